//! Building a hierarchical matrix in two passes, so that its size is
//! known before most of it is computed: the block tree's dense and zero
//! leaves are counted exactly, a systematic sample of its admissible
//! blocks is built first, and the rest of the admissible blocks are sized
//! from the sample, by block size. What a low-rank block stores (its rank,
//! or all of it when its cross does not pay) is known only once it is
//! computed, which is why counts over the block tree alone
//! ([`HMatrix::predict`]) fall short of what is built.

use super::cluster::Aabb;
use super::{leaf, partition, Entries, HMatrix, HOptions, HStats, Leaf, LeafData};
use rayon::prelude::*;
use serde::Serialize;
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
    /// Admissible blocks in all (those the structure proves zero left out).
    pub admissible_blocks: usize,
    /// The sample's share of the admissible blocks' entries.
    pub sampled_entries: f64,
}

impl HMatrix {
    /// As [`HMatrix::build`], but first builds a sample of the admissible
    /// blocks and predicts the whole matrix's size from it
    /// ([`SampledSize`]); `check` sees that prediction before the other
    /// blocks are computed and can stop the build with its error.
    ///
    /// # Errors
    /// What `check` returns.
    pub fn build_checked<E>(
        row_boxes: &[Aabb],
        col_boxes: &[Aabb],
        entries: &dyn Entries,
        opts: &HOptions,
        check: impl FnOnce(&SampledSize) -> Result<(), E>,
    ) -> Result<(Self, SampledSize), E> {
        let mut blocks = Vec::new();
        let (rt, ct, _) = partition(row_boxes, col_boxes, entries, opts, &mut |_, _, r, c, a| {
            blocks.push((r, c, a));
            ControlFlow::Continue(())
        });
        let shape = |&(r, c, _): &(usize, usize, bool)| {
            (rt.clusters[r].len() as u64, ct.clusters[c].len() as u64)
        };
        let zero: Vec<bool> = blocks
            .par_iter()
            .map(|&(r, c, _)| {
                let (rc, cc) = (&rt.clusters[r], &ct.clusters[c]);
                entries.is_zero(
                    &rt.order[rc.start..rc.end],
                    &rc.bbox,
                    &ct.order[cc.start..cc.end],
                    &cc.bbox,
                )
            })
            .collect();
        // Admissible, non-zero blocks by size class (log2 of m n), in block
        // order: neighbours in the order are neighbours in space.
        let mut classes: BTreeMap<u32, Vec<usize>> = BTreeMap::new();
        for (b, blk) in blocks.iter().enumerate() {
            if blk.2 && !zero[b] {
                let (m, n) = shape(blk);
                classes.entry((m * n).max(1).ilog2()).or_default().push(b);
            }
        }
        let sample: Vec<usize> = classes.values().flat_map(|c| systematic(c)).collect();
        let make = |b: usize| {
            let (r, c, a) = blocks[b];
            leaf(&rt, &ct, r, c, a, zero[b], entries, opts.tol)
        };
        let built: Vec<Leaf> = sample.par_iter().map(|&b| make(b)).collect();
        let mut fixed = 8.0 * (row_boxes.len() + col_boxes.len()) as f64
            + (blocks.len() * std::mem::size_of::<Leaf>()) as f64;
        for (b, blk) in blocks.iter().enumerate() {
            if !blk.2 && !zero[b] {
                let (m, n) = shape(blk);
                fixed += 8.0 * (m * n) as f64;
            }
        }
        let mut at = 0;
        let (mut predicted, mut sampled_entries, mut admissible_entries) = (fixed, 0.0, 0.0);
        for members in classes.values() {
            let k = systematic(members).len();
            let part = &built[at..at + k];
            at += k;
            let entries_of = |l: &Leaf| (l.rows.len() * l.cols.len()) as f64;
            let stored: f64 = part.iter().map(|l| l.stored() as f64).sum();
            let seen: f64 = part.iter().map(entries_of).sum();
            let all: f64 = members
                .iter()
                .map(|&b| {
                    let (m, n) = shape(&blocks[b]);
                    (m * n) as f64
                })
                .sum();
            predicted += 8.0 * stored / seen * all;
            sampled_entries += seen;
            admissible_entries += all;
        }
        let size = SampledSize {
            bytes: predicted,
            sampled_blocks: sample.len(),
            admissible_blocks: classes.values().map(Vec::len).sum(),
            sampled_entries: sampled_entries / admissible_entries.max(1.0),
        };
        check(&size)?;
        let mut in_sample = vec![false; blocks.len()];
        sample.iter().for_each(|&b| in_sample[b] = true);
        let rest: Vec<usize> = (0..blocks.len()).filter(|&b| !in_sample[b]).collect();
        let rest_built: Vec<Leaf> = rest.par_iter().map(|&b| make(b)).collect();
        let mut leaves: Vec<Option<Leaf>> = vec![None; blocks.len()];
        for (b, l) in sample
            .into_iter()
            .zip(built)
            .chain(rest.into_iter().zip(rest_built))
        {
            leaves[b] = Some(l);
        }
        let leaves: Vec<Leaf> = leaves
            .into_iter()
            .map(|l| l.expect("every block built"))
            .collect();
        let admissible: Vec<bool> = blocks.iter().map(|b| b.2).collect();
        let stats = HStats::of(&leaves, &admissible, (row_boxes.len(), col_boxes.len()));
        let h = Self {
            row_order: rt.order,
            col_order: ct.order,
            leaves,
            stats,
        };
        Ok((h, size))
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
        let (m, n) = (self.rows.len() as u64, self.cols.len() as u64);
        match &self.data {
            LeafData::Zero => 0,
            LeafData::Dense(_) => m * n,
            LeafData::LowRank(lr) => (m + n) * lr.rank() as u64,
        }
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
            HMatrix::build_checked(&boxes, &boxes, &entries, &opts, |_| Ok::<(), ()>(())).unwrap();
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
        let refused = HMatrix::build_checked(&boxes, &boxes, &entries, &opts, |z| Err(z.bytes));
        assert_eq!(refused.unwrap_err(), size.bytes);
        let asked = entries.asked.load(Ordering::Relaxed) as f64;
        assert!(asked > 0.0 && asked < 0.05 * (n * n) as f64, "{asked}");
    }
}
