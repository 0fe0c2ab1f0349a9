//! Building a hierarchical matrix in two passes, so that its size is
//! known before most of it is computed: the block tree's dense and zero
//! leaves are counted exactly, a systematic sample of its admissible
//! blocks is built first, and the rest of the admissible blocks are sized
//! from the sample, by block size. What a low-rank block stores (its rank,
//! or all of it when its cross does not pay) is known only once it is
//! computed, which is why counts over the block tree alone
//! ([`HMatrix::predict`]) fall short of what is built. The dense leaves are
//! counted with the rows and columns their structure proves zero left out,
//! as they are stored.

use super::cluster::Aabb;
use super::reuse::{Reuse, Trees};
use super::{
    dense_leaf_numbers, index_bytes, leaf, visit_blocks, Entries, HMatrix, HOptions, HStats, Leaf,
    Structure,
};
use rayon::prelude::*;
use serde::Serialize;
use std::cell::RefCell;
use std::collections::BTreeMap;
use std::ops::ControlFlow;

/// The admissible blocks of each size class sampled first: one in
/// `SAMPLE_STRIDE`, and at least [`MIN_PER_CLASS`] (all of them, in a class
/// with fewer).
pub const SAMPLE_STRIDE: usize = 32;

/// The fewest blocks sampled in a size class that has that many.
pub const MIN_PER_CLASS: usize = 4;

/// The size of a build, predicted from its sample before the rest is built.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SampledSize {
    /// Predicted bytes: dense leaves, orders and leaf records exactly, the
    /// admissible blocks from the sample.
    pub bytes: f64,
    /// Admissible blocks built in the sample.
    pub sampled_blocks: usize,
    /// Admissible blocks to compute (those the structure proves zero, and
    /// those taken from a previous matrix, left out).
    pub admissible_blocks: usize,
    /// The sample's share of those blocks' entries.
    pub sampled_entries: f64,
}

impl HMatrix {
    /// As [`HMatrix::build`], but first builds a sample of the admissible
    /// blocks and predicts the whole matrix's size from it
    /// ([`SampledSize`]); `check` sees that prediction before the other
    /// blocks are computed and can stop the build with its error. With
    /// `reuse`, the blocks a local change of the rows and columns did not
    /// touch are taken from the previous matrix ([`super::reuse`]) and
    /// counted exactly.
    ///
    /// # Errors
    /// What `check` returns.
    pub fn build_checked<E>(
        row_boxes: &[Aabb],
        col_boxes: &[Aabb],
        entries: &dyn Entries,
        opts: &HOptions,
        reuse: Option<&Reuse<'_>>,
        check: impl FnOnce(&SampledSize) -> Result<(), E>,
    ) -> Result<(Self, SampledSize), E> {
        Self::build_part(row_boxes, col_boxes, entries, opts, reuse, None, check)
    }

    /// [`HMatrix::build_checked`] of the whole matrix (`share` None), or of
    /// a share of its rows: the leaves whose rows meet `share`, a range of
    /// the row order (the block tree walked only where its rows meet it),
    /// the prediction and `check` of those alone. A share takes nothing
    /// from a previous matrix.
    ///
    /// # Errors
    /// What `check` returns.
    pub(super) fn build_part<E>(
        row_boxes: &[Aabb],
        col_boxes: &[Aabb],
        entries: &dyn Entries,
        opts: &HOptions,
        reuse: Option<&Reuse<'_>>,
        share: Option<std::ops::Range<usize>>,
        check: impl FnOnce(&SampledSize) -> Result<(), E>,
    ) -> Result<(Self, SampledSize), E> {
        let reuse = reuse.filter(|_| share.is_none());
        let t = Blocks::new(row_boxes, col_boxes, entries, opts, reuse, share);
        let classes = t.classes();
        let sample: Vec<usize> = classes.values().flat_map(|c| systematic(c)).collect();
        let make = |b: usize| {
            let (r, c, a) = t.blocks[b];
            match (reuse, t.reused[b]) {
                (Some(p), Some(k)) => p.leaf(k, &t.trees, r, c),
                _ => leaf(
                    &t.trees.rt,
                    &t.trees.ct,
                    r,
                    c,
                    a,
                    t.zero[b],
                    entries,
                    opts.tol,
                ),
            }
        };
        let built: Vec<Leaf> = sample.par_iter().map(|&b| make(b)).collect();
        let size = t.predict(&classes, &built, entries, reuse);
        check(&size)?;
        let mut leaves: Vec<Option<Leaf>> = vec![None; t.blocks.len()];
        for (&b, l) in sample.iter().zip(built) {
            leaves[b] = Some(l);
        }
        let rest: Vec<usize> = (0..t.blocks.len())
            .filter(|&b| leaves[b].is_none())
            .collect();
        let rest_built: Vec<Leaf> = rest.par_iter().map(|&b| make(b)).collect();
        for (b, l) in rest.into_iter().zip(rest_built) {
            leaves[b] = Some(l);
        }
        let leaves: Vec<Leaf> = leaves
            .into_iter()
            .map(|l| l.expect("every block built"))
            .collect();
        let admissible: Vec<bool> = t.blocks.iter().map(|b| b.2).collect();
        let shape = (row_boxes.len(), col_boxes.len());
        let trees = (&t.trees.rt, &t.trees.ct);
        let mut stats = HStats::of(&leaves, &admissible, shape, trees, opts.eta);
        stats.reused_blocks = t.reused.iter().flatten().count();
        let h = Self {
            rt: t.trees.rt,
            ct: t.trees.ct,
            leaves,
            stats,
            held: t.held,
        };
        Ok((h, size))
    }
}

/// The block tree of a build: its cluster trees, its leaves (row cluster,
/// column cluster, admissible), which the structure proves zero, and which
/// are taken from a previous matrix (its leaf's index); of a share, only
/// the blocks whose rows meet `held`, the positions of the row order held.
struct Blocks {
    trees: Trees,
    blocks: Vec<(usize, usize, bool)>,
    zero: Vec<bool>,
    reused: Vec<Option<usize>>,
    held: std::ops::Range<usize>,
}

impl Blocks {
    fn new(
        row_boxes: &[Aabb],
        col_boxes: &[Aabb],
        entries: &dyn Entries,
        opts: &HOptions,
        reuse: Option<&Reuse<'_>>,
        share: Option<std::ops::Range<usize>>,
    ) -> Self {
        let trees = reuse
            .and_then(|p| p.trees(row_boxes, col_boxes, opts.leaf_size))
            .unwrap_or_else(|| Trees::new(row_boxes, col_boxes, opts.leaf_size));
        // Leaves in block-tree order, each with the previous leaf it is.
        let found = RefCell::new(Vec::new());
        let taken = reuse.map(|p| p.taken(&trees));
        let held = share.unwrap_or(0..trees.rt.order.len());
        let mut take = |r: usize, c| {
            // Rows of another rank's share: not walked.
            let rc = &trees.rt.clusters[r];
            if rc.end <= held.start || held.end <= rc.start {
                return true;
            }
            match &taken {
                Some(t) => t.subtree(&trees, r, c, &mut found.borrow_mut()),
                None => false,
            }
        };
        let mut visit = |_: &_, _: &_, r, c, a| {
            found.borrow_mut().push(((r, c, a), None));
            ControlFlow::Continue(())
        };
        let _ = visit_blocks(&trees.rt, &trees.ct, entries, opts, &mut take, &mut visit);
        let (blocks, reused): (Vec<_>, Vec<_>) = found.into_inner().into_iter().unzip();
        let (rt, ct) = (&trees.rt, &trees.ct);
        let zero: Vec<bool> = blocks
            .par_iter()
            .zip(&reused)
            .map(|(&(r, c, _), old)| {
                let (rc, cc) = (&rt.clusters[r], &ct.clusters[c]);
                old.is_none()
                    && entries.is_zero(
                        &rt.order[rc.start..rc.end],
                        &rc.bbox,
                        &ct.order[cc.start..cc.end],
                        &cc.bbox,
                    )
            })
            .collect();
        Self {
            trees,
            blocks,
            zero,
            reused,
            held,
        }
    }

    /// Entries of block `b`.
    fn entries(&self, b: usize) -> f64 {
        let (r, c, _) = self.blocks[b];
        (self.trees.rt.clusters[r].len() * self.trees.ct.clusters[c].len()) as f64
    }

    /// The admissible blocks to be computed (not zero, not reused), by
    /// size class (log2 of their entries), in block-tree order.
    fn classes(&self) -> BTreeMap<u32, Vec<usize>> {
        let mut classes: BTreeMap<u32, Vec<usize>> = BTreeMap::new();
        for (b, blk) in self.blocks.iter().enumerate() {
            if blk.2 && !self.zero[b] && self.reused[b].is_none() {
                let class = (self.entries(b) as u64).max(1).ilog2();
                classes.entry(class).or_default().push(b);
            }
        }
        classes
    }

    /// The whole build's size: dense leaves and index exactly, reused
    /// leaves as stored, each class of admissible blocks from its
    /// `built` sample (in the order of `classes`).
    fn predict(
        &self,
        classes: &BTreeMap<u32, Vec<usize>>,
        built: &[Leaf],
        structure: &dyn Structure,
        reuse: Option<&Reuse<'_>>,
    ) -> SampledSize {
        let (rt, ct) = (&self.trees.rt, &self.trees.ct);
        let dense: u64 = (0..self.blocks.len())
            .into_par_iter()
            .filter(|&b| !self.blocks[b].2 && !self.zero[b] && self.reused[b].is_none())
            .map(|b| {
                let (r, c, _) = self.blocks[b];
                let (rc, cc) = (&rt.clusters[r], &ct.clusters[c]);
                dense_leaf_numbers(&rt.order, rc, &ct.order, cc, structure)
            })
            .sum();
        let kept: u64 = match reuse {
            Some(p) => self
                .reused
                .iter()
                .flatten()
                .map(|&k| p.previous.leaves[k].stored())
                .sum(),
            None => 0,
        };
        let mut bytes = 8.0 * (dense + kept) as f64 + index_bytes(rt, ct, self.blocks.len()) as f64;
        let (mut at, mut seen_all, mut all) = (0, 0.0, 0.0);
        for members in classes.values() {
            let part = &built[at..at + systematic(members).len()];
            at += part.len();
            let stored: f64 = part.iter().map(|l| l.stored() as f64).sum();
            let seen: f64 = part
                .iter()
                .map(|l| (l.rows.len() * l.cols.len()) as f64)
                .sum();
            let class: f64 = members.iter().map(|&b| self.entries(b)).sum();
            bytes += 8.0 * stored / seen * class;
            seen_all += seen;
            all += class;
        }
        SampledSize {
            bytes,
            sampled_blocks: at,
            admissible_blocks: classes.values().map(Vec::len).sum(),
            sampled_entries: seen_all / all.max(1.0),
        }
    }
}

/// `members.len()` spread evenly: one in [`SAMPLE_STRIDE`], at least
/// [`MIN_PER_CLASS`] (or all).
fn systematic(members: &[usize]) -> Vec<usize> {
    let n = members.len();
    let k = n.div_ceil(SAMPLE_STRIDE).max(MIN_PER_CLASS.min(n));
    (0..k).map(|j| members[(2 * j + 1) * n / (2 * k)]).collect()
}

impl Leaf {
    /// Numbers stored.
    fn stored(&self) -> u64 {
        self.data.stored(self.rows.len(), self.cols.len())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hmatrix::Structure;
    use crate::matrix::DenseMatrix;
    use glam::DVec3;
    use std::sync::atomic::{AtomicU64, Ordering};

    /// A dense matrix that counts the entries asked of it.
    struct Counted {
        m: DenseMatrix,
        asked: AtomicU64,
    }

    impl Structure for Counted {}

    impl Entries for Counted {
        fn block(&self, rows: &[usize], cols: &[usize], out: &mut [f64]) {
            self.asked
                .fetch_add((rows.len() * cols.len()) as u64, Ordering::Relaxed);
            self.m.block(rows, cols, out);
        }
    }

    /// Points on a surface-like sheet and a kernel 1 / (ε + r²): ranks
    /// grow as blocks come closer, so low-rank blocks differ in size and
    /// some crosses do not pay. The sample's prediction is within a tenth
    /// of what is built (every block computed, counted after); a check
    /// that refuses stops the build with only the sample computed.
    #[test]
    fn a_sample_predicts_the_built_size_and_a_refusal_stops_the_rest() {
        let side = 48;
        let n = side * side;
        let pts: Vec<DVec3> = (0..n)
            .map(|k| {
                let (x, y) = (
                    (k % side) as f64 / side as f64,
                    (k / side) as f64 / side as f64,
                );
                DVec3::new(x, y, 0.3 * (3.0 * x).sin() * y)
            })
            .collect();
        let boxes: Vec<Aabb> = pts.iter().map(|&p| Aabb { lo: p, hi: p }).collect();
        let data = (0..n * n)
            .map(|k| 1.0 / (1e-3 + pts[k / n].distance_squared(pts[k % n])))
            .collect();
        let entries = Counted {
            m: DenseMatrix::from_row_major(n, n, data),
            asked: AtomicU64::new(0),
        };
        let opts = HOptions {
            tol: 1e-8,
            ..Default::default()
        };
        let (h, size) =
            HMatrix::build_checked(&boxes, &boxes, &entries, &opts, None, |_| Ok::<(), ()>(()))
                .unwrap();
        let built = h.heap_bytes() as f64;
        let s = h.stats();
        assert!(s.low_rank_blocks > 100 && s.low_rank_failed > 0, "{s:?}");
        assert!(
            size.sampled_blocks * 10 < size.admissible_blocks,
            "{size:?}"
        );
        assert!(
            (size.bytes - built).abs() <= 0.1 * built,
            "{size:?} against {built}"
        );
        // Not the count over the block tree (ranks at 1): that falls short.
        let tree = HMatrix::predict(&boxes, &boxes, &entries, &opts, f64::INFINITY);
        assert!(tree.bytes() < 0.9 * built, "{tree:?} against {built}");

        entries.asked.store(0, Ordering::Relaxed);
        let refused =
            HMatrix::build_checked(&boxes, &boxes, &entries, &opts, None, |z| Err(z.bytes));
        assert_eq!(refused.unwrap_err(), size.bytes);
        let asked = entries.asked.load(Ordering::Relaxed) as f64;
        assert!(asked > 0.0 && asked < 0.05 * (n * n) as f64, "{asked}");
    }
}
