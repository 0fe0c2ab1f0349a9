//! A hierarchical matrix spread over ranks by block rows: every rank
//! builds the same cluster and block trees, cuts the row order into one
//! contiguous range per rank, balanced by predicted cost, and computes and
//! stores only the leaves whose rows meet its range ([`RowShare`]). A
//! product gathers x from every rank's rows and multiplies the leaves held:
//! the assembly needs no communication, a product one gather of x.

use super::cluster::{Aabb, ClusterTree};
use super::{visit_blocks, Entries, HMatrix, HOptions, SampledSize, Structure};
use crate::ranks::Ranks;
use crate::solve::LinearOperator;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};
use std::ops::{ControlFlow, Range};
use std::sync::Arc;
use std::time::Instant;

/// The rank counted for a low-rank block before it is computed, in the
/// cost of its rows: about what radiosity's far blocks keep at the
/// default tolerance (ranks 2–12 on the Cornell box at 1e-8).
const NOMINAL_RANK: f64 = 8.0;

/// Where one rank's share lies, decided from the geometry before any
/// assembly plan: the rows of the row order it holds, and the elements
/// whose pairs its plan must classify (`AssemblyPlan` rows: those of its
/// own rows, and those of every row cluster that straddles its range
/// where the block tree asks whether a block is smooth, so that its block
/// tree is the one-process tree restricted to its rows).
#[derive(Clone, Debug)]
pub(crate) struct Layout {
    /// Rows (positions of the row order) held.
    pub(crate) held: Range<usize>,
    /// Per element: whether the plan classifies its pairs.
    pub(crate) elements: Vec<bool>,
    /// Per element: the rank that holds its first row, which estimates
    /// its error (the same on every rank).
    pub(crate) owner: Vec<u32>,
}

/// A map between indices (a row to its element, an element to its first
/// row).
type Index<'a> = &'a dyn Fn(usize) -> usize;

/// The [`Layout`] of rank `rank` among `size`, from `geometry`'s block
/// tree (row and column boxes, and the structure of the geometry alone:
/// `super::radiosity::predict`'s). The cuts balance that tree's predicted
/// cost plus `extra` per row ([`cuts`]); the classified elements are those of the rows held,
/// and of the row cluster of every block the geometry finds admissible
/// that meets the rows held without lying inside them: the block tree
/// asks there, or below, whether the occlusion lets it stay low rank,
/// which needs all its rows' pairs. `element_of` maps a row to its
/// element, `first_row` an element to its first row, of `elements` in all.
pub(crate) fn layout(
    (row_boxes, col_boxes): (&[Aabb], &[Aabb]),
    geometry: &dyn Structure,
    opts: &HOptions,
    extra: &[f64],
    (rank, size): (usize, usize),
    (element_of, first_row, elements): (Index<'_>, Index<'_>, usize),
) -> Layout {
    let rt = ClusterTree::new(row_boxes, opts.leaf_size);
    let ct = ClusterTree::new(col_boxes, opts.leaf_size);
    let mut blocks = Vec::new();
    let _ = visit_blocks(&rt, &ct, geometry, opts, &mut |_, _| false, &mut |_, _, r, c, a| {
        blocks.push((r, c, a));
        ControlFlow::Continue(())
    });
    let zero: Vec<bool> = blocks
        .par_iter()
        .map(|&(r, c, _)| {
            let (rc, cc) = (&rt.clusters[r], &ct.clusters[c]);
            geometry.is_zero(
                &rt.order[rc.start..rc.end],
                &rc.bbox,
                &ct.order[cc.start..cc.end],
                &cc.bbox,
            )
        })
        .collect();
    let cut = cuts(&rt, &ct, (&blocks, &zero), extra, size);
    let held = cut[rank]..cut[rank + 1];
    let mut classified = vec![false; elements];
    let mut mark = |rows: Range<usize>| {
        for &i in &rt.order[rows] {
            classified[element_of(i)] = true;
        }
    };
    mark(held.clone());
    for &(r, _, admissible) in &blocks {
        let rc = &rt.clusters[r];
        let meets = rc.start < held.end && held.start < rc.end;
        let inside = held.start <= rc.start && rc.end <= held.end;
        if admissible && meets && !inside {
            mark(rc.start..rc.end);
        }
    }
    let mut position = vec![0; rt.order.len()];
    for (p, &i) in rt.order.iter().enumerate() {
        position[i] = p;
    }
    let owner = (0..elements)
        .map(|k| {
            let p = position[first_row(k)];
            (cut.partition_point(|&c| c <= p) - 1) as u32
        })
        .collect();
    Layout {
        held,
        elements: classified,
        owner,
    }
}

/// Where the row order is cut among `size` ranks: `size + 1` positions,
/// from 0 to the number of rows, rank p holding `cuts[p]..cuts[p + 1]`.
/// Each block's predicted cost (a dense leaf its entries, a low-rank block
/// [`NOMINAL_RANK`] (m + n), a zero block nothing) is spread evenly over
/// its rows, `extra[i]` is added to row i's (original index: work the
/// geometry does not see, such as visibility), and the cuts fall on the starts of the row tree's leaves
/// nearest to equal shares of the total, so that a dense leaf is never
/// split and only low-rank blocks of large clusters straddle a cut (their
/// rank on each side computes them whole and keeps them); with fewer
/// leaves than ranks, on any row.
pub(super) fn cuts(
    rt: &ClusterTree,
    ct: &ClusterTree,
    (blocks, zero): (&[(usize, usize, bool)], &[bool]),
    extra: &[f64],
    size: usize,
) -> Vec<usize> {
    let before = cumulative_cost(rt, ct, (blocks, zero), extra);
    let m = rt.order.len();
    let total = before[m];
    let mut starts: Vec<usize> = rt
        .clusters
        .iter()
        .filter(|c| c.children.is_none() && c.end > c.start)
        .map(|c| c.start)
        .chain([m])
        .collect();
    starts.sort_unstable();
    starts.dedup();
    // Fewer leaves than ranks (a mesh of a few dozen unknowns): any row.
    if starts.len() <= size {
        starts = (0..=m).collect();
    }
    let mut cuts = vec![0];
    for p in 1..size {
        let target = total * p as f64 / size as f64;
        let last = *cuts.last().expect("starts at 0");
        let best = starts
            .iter()
            .copied()
            .filter(|&s| s >= last)
            .min_by(|&a, &b| {
                (before[a] - target)
                    .abs()
                    .total_cmp(&(before[b] - target).abs())
            })
            .unwrap_or(m);
        cuts.push(best);
    }
    cuts.push(m);
    cuts
}

/// The predicted cost of the rows before each position of the row order
/// (`m + 1` sums): [`cuts`]'s model.
fn cumulative_cost(
    rt: &ClusterTree,
    ct: &ClusterTree,
    (blocks, zero): (&[(usize, usize, bool)], &[bool]),
    extra: &[f64],
) -> Vec<f64> {
    let m = rt.order.len();
    // Cost per row as a difference array of densities.
    let mut density = vec![0.0; m + 1];
    for (&(r, c, admissible), &z) in blocks.iter().zip(zero) {
        let (rc, cc) = (&rt.clusters[r], &ct.clusters[c]);
        let (rows, cols) = (rc.len() as f64, cc.len() as f64);
        let cost = match (z, admissible) {
            (true, _) => 0.0,
            (false, true) => NOMINAL_RANK * (rows + cols),
            (false, false) => rows * cols,
        };
        density[rc.start] += cost / rows;
        density[rc.end] -= cost / rows;
    }
    // Cumulative cost before each row.
    let mut before = vec![0.0; m + 1];
    let mut d = 0.0;
    for i in 0..m {
        d += density[i];
        before[i + 1] = before[i] + d + extra.get(rt.order[i]).copied().unwrap_or(0.0);
    }
    before
}

/// One rank's share of a hierarchical matrix's rows, as an operator on
/// that rank's rows: `LinearOperator::apply` takes this rank's rows of x
/// (every rank calling it together), gathers the others', and returns
/// this rank's rows of A x.
#[derive(Debug)]
pub struct RowShare {
    h: HMatrix,
    /// Original indices of the rows held, in row-tree order.
    rows: Vec<usize>,
    /// Rows held by each rank.
    counts: Vec<usize>,
    ranks: Arc<dyn Ranks>,
    /// Time in this rank's leaf products.
    product_nanos: AtomicU64,
    /// Time gathering x for them.
    gather_nanos: AtomicU64,
    /// When this rank's own part of the build ended (before it first
    /// waited for the others), and the process's CPU seconds then.
    built: (Instant, Option<f64>),
}

impl RowShare {
    /// This rank's share (of `ranks`), the rows `held` of the row order
    /// ([`Layout`]), of the matrix `HMatrix::build_checked` builds from
    /// the same arguments, with `check` seeing the share's predicted size
    /// (its own memory). Every rank calls it together, with its own
    /// layout's rows.
    ///
    /// # Errors
    /// What `check` returns.
    pub(crate) fn build<E>(
        row_boxes: &[super::cluster::Aabb],
        col_boxes: &[super::cluster::Aabb],
        entries: &dyn Entries,
        opts: &HOptions,
        (ranks, held): (Arc<dyn Ranks>, Range<usize>),
        check: impl FnOnce(&SampledSize) -> Result<(), E>,
    ) -> Result<(Self, SampledSize), E> {
        let share = Some(held);
        let (h, size) =
            HMatrix::build_part(row_boxes, col_boxes, entries, opts, None, share, check)?;
        let built = (Instant::now(), crate::ranks::cpu_seconds());
        let rows = h.rt.order[h.held.clone()].to_vec();
        let counts = ranks
            .gather_each(rows.len() as f64)
            .into_iter()
            .map(|c| c as usize)
            .collect();
        Ok((
            Self {
                h,
                rows,
                counts,
                ranks,
                product_nanos: AtomicU64::new(0),
                gather_nanos: AtomicU64::new(0),
                built,
            },
            size,
        ))
    }

    /// The leaves this rank holds.
    pub(crate) fn local(&self) -> &HMatrix {
        &self.h
    }

    /// What this rank's leaves hold (its share of the numbers; the shape
    /// is the whole matrix's).
    pub fn stats(&self) -> super::HStats {
        self.h.stats()
    }

    /// Heap bytes of this rank's share.
    pub fn heap_bytes(&self) -> u64 {
        self.h.heap_bytes()
    }

    /// Original indices of this rank's rows, in the order of its vectors.
    pub fn rows(&self) -> &[usize] {
        &self.rows
    }

    /// Rows held by each rank.
    pub fn counts(&self) -> &[usize] {
        &self.counts
    }

    /// The ranks it is spread over.
    pub fn ranks(&self) -> &dyn Ranks {
        &*self.ranks
    }

    /// When this rank's own part of the build ended, before it first
    /// waited for another rank, and the process's CPU seconds then
    /// (`crate::ranks::cpu_seconds`).
    pub(crate) fn built(&self) -> (Instant, Option<f64>) {
        self.built
    }

    /// Seconds this rank has spent multiplying its leaves.
    pub fn product_seconds(&self) -> f64 {
        self.product_nanos.load(Ordering::Relaxed) as f64 * 1e-9
    }

    /// Seconds this rank has spent gathering x for its products (waiting
    /// for the other ranks included).
    pub fn gather_seconds(&self) -> f64 {
        self.gather_nanos.load(Ordering::Relaxed) as f64 * 1e-9
    }

    /// This rank's rows of a vector every rank holds whole.
    pub fn restrict(&self, full: &[f64]) -> Vec<f64> {
        self.rows.iter().map(|&i| full[i]).collect()
    }

    /// The whole vector from every rank's rows (`local`: this rank's), on
    /// every rank; every rank calls it together.
    pub fn gather(&self, local: &[f64], full: &mut [f64]) {
        let m = self.h.stats.shape.0;
        let mut tree = vec![0.0; m];
        self.ranks.gather_all(local, &self.counts, &mut tree);
        for (p, &i) in self.h.rt.order.iter().enumerate() {
            full[i] = tree[p];
        }
    }

    /// The relative error of a product over `rows` sample rows of the
    /// whole matrix, as `HMatrix::sampled_error` measures it: each rank
    /// checks the sample rows it holds, the sums are taken over the ranks
    /// (every rank calls it together).
    pub(crate) fn sampled_error(&self, entries: &dyn Entries, rows: usize) -> f64 {
        let (m, n) = self.h.stats.shape;
        let golden = |k: usize| ((k as f64 + 1.0) * 0.618_033_988_749_895).fract();
        let x: Vec<f64> = (0..n).map(golden).collect();
        let yp = self.h.products(&[&x]);
        let held = self.h.held.clone();
        let mut picked: Vec<usize> = (0..rows.min(m))
            .map(|k| ((golden(k) * m as f64) as usize).min(m - 1))
            .collect();
        picked.sort_unstable();
        picked.dedup();
        let cols: Vec<usize> = (0..n).collect();
        let (num, den) = picked
            .par_iter()
            .map(|&i| {
                // Row i of the original order, at its position in the tree.
                let Some(p) = held.clone().find(|&p| self.h.rt.order[p] == i) else {
                    return (0.0, 0.0);
                };
                let mut row = vec![0.0; n];
                entries.block(&[i], &cols, &mut row);
                let exact: f64 = row.iter().zip(&x).map(|(a, b)| a * b).sum();
                ((yp[p] - exact).powi(2), exact * exact)
            })
            .reduce(|| (0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1));
        let mut sums = [num, den];
        self.ranks.sum(&mut sums);
        if sums[1] > 0.0 {
            (sums[0] / sums[1]).sqrt()
        } else {
            sums[0].sqrt()
        }
    }
}

impl LinearOperator for RowShare {
    /// This rank's rows.
    fn dim(&self) -> usize {
        self.rows.len()
    }

    fn apply(&self, x: &[f64], y: &mut [f64]) {
        self.apply_many(&[x], &mut [y]);
    }

    /// One gather per vector, then one pass over the leaves held.
    fn apply_many(&self, xs: &[&[f64]], ys: &mut [&mut [f64]]) {
        let n = self.h.stats.shape.1;
        let gathering = Instant::now();
        let full: Vec<Vec<f64>> = xs
            .iter()
            .map(|x| {
                let mut f = vec![0.0; n];
                self.gather(x, &mut f);
                f
            })
            .collect();
        self.gather_nanos
            .fetch_add(gathering.elapsed().as_nanos() as u64, Ordering::Relaxed);
        let start = Instant::now();
        let refs: Vec<&[f64]> = full.iter().map(Vec::as_slice).collect();
        let yp = self.h.products(&refs);
        let m = self.h.stats.shape.0;
        for (y, yp) in ys.iter_mut().zip(yp.chunks_exact(m.max(1))) {
            y.copy_from_slice(&yp[self.h.held.clone()]);
        }
        self.product_nanos
            .fetch_add(start.elapsed().as_nanos() as u64, Ordering::Relaxed);
    }
}

impl Clone for RowShare {
    fn clone(&self) -> Self {
        Self {
            h: self.h.clone(),
            rows: self.rows.clone(),
            counts: self.counts.clone(),
            ranks: self.ranks.clone(),
            product_nanos: AtomicU64::new(self.product_nanos.load(Ordering::Relaxed)),
            gather_nanos: AtomicU64::new(self.gather_nanos.load(Ordering::Relaxed)),
            built: self.built,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    /// Points on a line, nothing zero: the cuts' cost from the geometry,
    /// with or without work per row that the geometry does not see.
    fn cuts_of(extra: &[f64], size: usize) -> Vec<usize> {
        let boxes: Vec<Aabb> = (0..extra.len())
            .map(|i| {
                let p = DVec3::new(i as f64, 0.0, 0.0);
                Aabb { lo: p, hi: p }
            })
            .collect();
        let opts = HOptions {
            leaf_size: 4,
            ..HOptions::default()
        };
        let (rt, ct) = (ClusterTree::new(&boxes, 4), ClusterTree::new(&boxes, 4));
        struct Nothing;
        impl Structure for Nothing {}
        let mut blocks = Vec::new();
        let _ = visit_blocks(&rt, &ct, &Nothing, &opts, &mut |_, _| false, &mut |_, _, r, c, a| {
            blocks.push((r, c, a));
            ControlFlow::Continue(())
        });
        let zero = vec![false; blocks.len()];
        cuts(&rt, &ct, (&blocks, &zero), extra, size)
    }

    #[test]
    fn work_the_geometry_does_not_see_moves_the_cuts() {
        let n = 256;
        let even = cuts_of(&vec![0.0; n], 2);
        // Rows of one half of the line cost far more: the cut moves into
        // that half, near its middle (a quarter of the rows on one side).
        let heavy: Vec<f64> = (0..n).map(|i| if i < n / 2 { 1e4 } else { 0.0 }).collect();
        let skewed = cuts_of(&heavy, 2);
        let off_middle = |c: &[usize]| (c[1] as f64 - n as f64 / 2.0).abs() / n as f64;
        assert!(off_middle(&even) <= 0.1, "{even:?}");
        assert!((off_middle(&skewed) - 0.25).abs() <= 0.1, "{skewed:?}");
        assert_eq!((skewed[0], skewed[2]), (0, n), "{skewed:?}");
    }
}
