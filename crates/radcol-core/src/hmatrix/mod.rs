//! Hierarchical matrices: the geometric matrix stored in O(N log N) instead of
//! N², within a requested relative tolerance.
//!
//! Rows and columns are ordered by cluster trees ([`cluster`]) so that every
//! cluster is a contiguous range. The block tree pairs a row cluster τ with a
//! column cluster σ and stops at
//! * **zero blocks**, proved zero before any entry is computed
//!   ([`Structure::is_zero`]: for radiosity, clusters wholly behind each other's
//!   planes);
//! * **admissible blocks**, min(diam τ, diam σ) ≤ η dist(τ, σ), where the
//!   kernel is smooth: approximated by ACA+ and recompressed to the tolerance
//!   ([`aca`]); a block whose cross grows too large is stored dense;
//! * **dense leaves**, where both clusters are leaves.
//!
//! Each low-rank block is within `tol` of its own Frobenius norm, so the
//! whole matrix is within `tol` of ‖A‖_F and a product with it within about
//! `tol` relative. The entries come from an [`Entries`] oracle: the dense
//! matrix in tests, the assembly's integrators in production.

pub mod aca;
mod classes;
pub mod cluster;
mod leaf;
mod predict;
pub mod radiosity;
pub mod reuse;
mod sample;
pub mod share;

use cluster::{Aabb, ClusterTree};
use leaf::{dense_leaf_numbers, leaf, Leaf, LeafData};
use rayon::prelude::*;
use serde::Serialize;
use std::ops::ControlFlow;

pub use predict::HPrediction;
pub use sample::SampledSize;
pub use share::RowShare;

/// What is known of a matrix's blocks without computing an entry: which
/// are zero, and which are smooth enough to compress. The block tree is
/// made from this alone ([`HMatrix::predict`] sizes a matrix from it).
pub trait Structure: Sync {
    /// True when the block is known to be zero without computing it. The
    /// default knows nothing.
    fn is_zero(&self, _rows: &[usize], _row_box: &Aabb, _cols: &[usize], _col_box: &Aabb) -> bool {
        false
    }

    /// False when a geometrically admissible block is not smooth and must be
    /// subdivided instead of compressed (for radiosity: pairs partly hidden
    /// by an occluder, whose entries jump across shadow lines). The default:
    /// every admissible block is smooth.
    fn smooth(&self, _rows: &[usize], _row_box: &Aabb, _cols: &[usize], _col_box: &Aabb) -> bool {
        true
    }

    /// Of a smooth block, the rows and the columns known to be zero (for
    /// radiosity: points and elements facing away from, coplanar with or
    /// hidden from the whole other side), which compression leaves out:
    /// adaptive cross approximation started in a zero part stops before it
    /// has seen the rest (the box room: a product error of 5e-5 at a
    /// tolerance of 1e-8 with blocks mixing a floor's columns and a wall's).
    /// The default: none.
    fn zero_lines(&self, rows: &[usize], cols: &[usize]) -> (Vec<bool>, Vec<bool>) {
        (vec![false; rows.len()], vec![false; cols.len()])
    }
}

/// Where a hierarchical matrix's entries come from.
pub trait Entries: Structure {
    /// `out[a * cols.len() + b] = A[rows[a], cols[b]]` (original indices).
    fn block(&self, rows: &[usize], cols: &[usize], out: &mut [f64]);

    /// The columns computed together with column `j` (original indices, `j`
    /// among them): asking [`Entries::block`] for any of them costs as much
    /// as asking for all. A cross approximation keeps the others for when
    /// it asks for them.
    fn column_group(&self, j: usize) -> std::ops::Range<usize> {
        j..j + 1
    }
}

/// How a hierarchical matrix is built.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct HOptions {
    /// Relative tolerance of each low-rank block (Frobenius).
    pub tol: f64,
    /// Admissibility η: a block is low rank when min(diam τ, diam σ) ≤ η
    /// dist(τ, σ). Larger η admits nearer blocks, with higher ranks.
    pub eta: f64,
    /// Clusters of at most this many indices are not split.
    pub leaf_size: usize,
}

impl Default for HOptions {
    fn default() -> Self {
        Self {
            tol: 1e-6,
            eta: 1.0,
            leaf_size: 32,
        }
    }
}

/// What the matrix holds, for reports and tests.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct HStats {
    /// Rows × columns.
    pub shape: (usize, usize),
    /// Leaves proved zero, and the entries they cover.
    pub zero_blocks: usize,
    /// Entries in zero blocks.
    pub zero_entries: u64,
    /// Dense leaves (including admissible blocks left dense).
    pub dense_blocks: usize,
    /// Low-rank leaves.
    pub low_rank_blocks: usize,
    /// Admissible blocks whose cross grew too large and were stored dense.
    pub low_rank_failed: usize,
    /// The largest rank kept.
    pub max_rank: usize,
    /// Numbers stored (dense entries plus (m + n) k per low-rank block).
    pub stored: u64,
    /// Where the stored numbers are: low-rank blocks, admissible blocks
    /// left dense (their cross did not pay), dense leaves of blocks that
    /// are admissible by distance but were subdivided because the
    /// structure found them not smooth (`Structure::smooth`: for
    /// radiosity, shadow boundaries and tangent planes), and dense leaves of
    /// the near field. They add up to `stored`.
    pub stored_by_kind: StoredByKind,
    /// Leaves taken from a previous matrix (`reuse`) instead of computed.
    pub reused_blocks: usize,
}

/// The numbers of a hierarchical matrix by the kind of leaf that stores
/// them ([`HStats::stored_by_kind`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct StoredByKind {
    /// In low-rank blocks.
    pub low_rank: u64,
    /// In admissible blocks left dense.
    pub left_dense: u64,
    /// In dense leaves of blocks admissible by distance that the structure
    /// split (not smooth).
    pub split: u64,
    /// In dense leaves of the near field (not admissible by distance).
    pub near: u64,
}

impl HStats {
    /// What `leaves` hold (`admissible`: which were admissible blocks) in a
    /// matrix of `shape` whose row and column trees are `rt` and `ct`, its
    /// admissibility `eta`.
    fn of(
        leaves: &[Leaf],
        admissible: &[bool],
        shape: (usize, usize),
        (rt, ct): (&ClusterTree, &ClusterTree),
        eta: f64,
    ) -> Self {
        let mut stats = HStats {
            shape,
            ..Default::default()
        };
        let by = &mut stats.stored_by_kind;
        for (l, &admissible) in leaves.iter().zip(admissible) {
            let (m, n) = (l.rows.len() as u64, l.cols.len() as u64);
            let stored = l.data.stored(l.rows.len(), l.cols.len());
            stats.stored += stored;
            match &l.data {
                LeafData::Zero => {
                    stats.zero_blocks += 1;
                    stats.zero_entries += m * n;
                }
                LeafData::Dense(_) | LeafData::Compact(_) => {
                    stats.dense_blocks += 1;
                    stats.low_rank_failed += admissible as usize;
                    let (rc, cc) = (
                        &rt.clusters[l.block.0 as usize],
                        &ct.clusters[l.block.1 as usize],
                    );
                    if admissible {
                        by.left_dense += stored;
                    } else if by_distance(rc, cc, eta) {
                        by.split += stored;
                    } else {
                        by.near += stored;
                    }
                }
                LeafData::LowRank(lr) => {
                    stats.low_rank_blocks += 1;
                    stats.max_rank = stats.max_rank.max(lr.rank());
                    by.low_rank += stored;
                }
            }
        }
        stats
    }

    /// Stored numbers over the dense matrix's.
    pub fn compression(&self) -> f64 {
        self.stored as f64 / (self.shape.0 as f64 * self.shape.1 as f64).max(1.0)
    }
}

/// A hierarchical matrix.
#[derive(Clone, Debug)]
pub struct HMatrix {
    rt: ClusterTree,
    ct: ClusterTree,
    leaves: Vec<Leaf>,
    stats: HStats,
    /// The positions of the row order whose rows it holds: all of them,
    /// or one rank's share ([`RowShare`]), whose leaves are those that
    /// meet these rows.
    held: std::ops::Range<usize>,
}

impl HMatrix {
    /// Builds the matrix whose rows and columns have these boxes (a point's
    /// box is the point; a basis function's, its support), sampling
    /// `entries` (leaves in parallel; a sample of the admissible blocks
    /// first, see [`HMatrix::build_checked`]).
    pub fn build(
        row_boxes: &[Aabb],
        col_boxes: &[Aabb],
        entries: &dyn Entries,
        opts: &HOptions,
    ) -> Self {
        let built = Self::build_checked(row_boxes, col_boxes, entries, opts, None, |_| {
            Ok::<(), std::convert::Infallible>(())
        });
        match built {
            Ok((h, _)) => h,
            Err(never) => match never {},
        }
    }

    /// What it holds.
    pub fn stats(&self) -> HStats {
        self.stats
    }

    /// Heap bytes of the stored numbers, the cluster trees and the leaves'
    /// records.
    pub fn heap_bytes(&self) -> u64 {
        8 * self.stats.stored + index_bytes(&self.rt, &self.ct, self.leaves.len()) as u64
    }

    /// The relative error of y = A x over `rows` sample rows, for a fixed
    /// pseudo-random x in [0, 1): ‖ŷ − y‖ / ‖y‖ over those rows, with y
    /// from the exact rows of `entries`. An a posteriori check of the
    /// compression, at the cost of `rows` rows of the dense matrix.
    pub fn sampled_error(&self, entries: &dyn Entries, rows: usize) -> f64 {
        let (m, n) = self.stats.shape;
        let golden = |k: usize| ((k as f64 + 1.0) * 0.618_033_988_749_895).fract();
        let x: Vec<f64> = (0..n).map(golden).collect();
        let mut y = vec![0.0; m];
        self.matvec(&x, &mut y);
        let cols: Vec<usize> = (0..n).collect();
        let mut picked: Vec<usize> = (0..rows.min(m))
            .map(|k| ((golden(k) * m as f64) as usize).min(m - 1))
            .collect();
        picked.sort_unstable();
        picked.dedup();
        let (num, den) = picked
            .par_iter()
            .map(|&i| {
                let mut row = vec![0.0; n];
                entries.block(&[i], &cols, &mut row);
                let exact: f64 = row.iter().zip(&x).map(|(a, b)| a * b).sum();
                ((y[i] - exact).powi(2), exact * exact)
            })
            .reduce(|| (0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1));
        if den > 0.0 {
            (num / den).sqrt()
        } else {
            num.sqrt()
        }
    }

    /// y = A x (original indices), leaves in parallel.
    pub fn matvec(&self, x: &[f64], y: &mut [f64]) {
        self.matvec_many(&[x], &mut [y]);
    }

    /// `ys[c] = A xs[c]` for every c, in one pass over the leaves: each leaf
    /// is read from memory once and applied to every vector.
    pub fn matvec_many(&self, xs: &[&[f64]], ys: &mut [&mut [f64]]) {
        let m = self.stats.shape.0;
        assert_eq!(self.held, 0..m, "the whole matrix: a share multiplies its rows");
        assert!(ys.iter().all(|y| y.len() == m), "matvec shapes");
        let yp = self.products(xs);
        for (y, yp) in ys.iter_mut().zip(yp.chunks_exact(m.max(1))) {
            for (p, &i) in self.rt.order.iter().enumerate() {
                y[i] = yp[p];
            }
        }
    }

    /// The products of the leaves held with every `xs[c]` (original
    /// column indices), in row-tree order: m numbers per vector, of which
    /// the `held` positions are complete (leaves that straddle the edge of
    /// a share add to rows beyond it, which are not read).
    fn products(&self, xs: &[&[f64]]) -> Vec<f64> {
        let (m, n) = self.stats.shape;
        assert!(xs.iter().all(|x| x.len() == n), "matvec shapes");
        let k = xs.len();
        if m == 0 || k == 0 {
            return Vec::new();
        }
        let xp: Vec<Vec<f64>> = xs
            .iter()
            .map(|x| self.ct.order.iter().map(|&j| x[j]).collect())
            .collect();
        self.leaves
            .par_iter()
            .fold(
                || vec![0.0; m * k],
                |mut acc, l| {
                    for (x, y) in xp.iter().zip(acc.chunks_exact_mut(m)) {
                        l.apply_add(x, y);
                    }
                    acc
                },
            )
            .reduce(
                || vec![0.0; m * k],
                |mut a, b| {
                    a.iter_mut().zip(&b).for_each(|(x, y)| *x += y);
                    a
                },
            )
    }
}

/// A visitor of block-tree leaves: (row tree, column tree, row cluster,
/// column cluster, admissible).
type Visit<'a> = dyn FnMut(&ClusterTree, &ClusterTree, usize, usize, bool) -> ControlFlow<()> + 'a;

/// The cluster trees of `row_boxes` and `col_boxes` (leaves of
/// `opts.leaf_size`), with the leaves of their block tree visited until
/// `visit` breaks (none when either side is empty), and whether it did.
fn partition(
    row_boxes: &[Aabb],
    col_boxes: &[Aabb],
    structure: &dyn Structure,
    opts: &HOptions,
    visit: &mut Visit<'_>,
) -> (ClusterTree, ClusterTree, ControlFlow<()>) {
    let rt = ClusterTree::new(row_boxes, opts.leaf_size);
    let ct = ClusterTree::new(col_boxes, opts.leaf_size);
    let flow = visit_blocks(&rt, &ct, structure, opts, &mut |_, _| false, visit);
    (rt, ct, flow)
}

/// The leaves of the block tree of `rt` and `ct` visited until `visit`
/// breaks (none when either is empty), and whether it did; the nodes for
/// which `take` returns true are left to it ([`block_tree`]).
fn visit_blocks(
    rt: &ClusterTree,
    ct: &ClusterTree,
    structure: &dyn Structure,
    opts: &HOptions,
    take: &mut dyn FnMut(usize, usize) -> bool,
    visit: &mut Visit<'_>,
) -> ControlFlow<()> {
    if rt.order.is_empty() || ct.order.is_empty() {
        ControlFlow::Continue(())
    } else {
        block_tree(rt, ct, 0, 0, opts.eta, structure, take, &mut |r, c, a| {
            visit(rt, ct, r, c, a)
        })
    }
}

/// The runs of consecutive numbers in `sorted`, as ranges.
fn consecutive_runs(sorted: &[usize]) -> Vec<std::ops::Range<usize>> {
    let mut runs: Vec<std::ops::Range<usize>> = Vec::new();
    for &k in sorted {
        match runs.last_mut() {
            Some(r) if r.end == k => r.end = k + 1,
            _ => runs.push(k..k + 1),
        }
    }
    runs
}

/// Bytes of the trees `rt` and `ct` and of `leaves` leaf records: what a
/// matrix holds besides its numbers.
fn index_bytes(rt: &ClusterTree, ct: &ClusterTree, leaves: usize) -> usize {
    let cluster = std::mem::size_of::<cluster::Cluster>();
    8 * (rt.order.len() + ct.order.len())
        + cluster * (rt.clusters.len() + ct.clusters.len())
        + std::mem::size_of::<Leaf>() * leaves
}

/// The admissibility by distance of the block of clusters `rc` and `cc`:
/// min(diam τ, diam σ) ≤ η dist(τ, σ), apart.
fn by_distance(rc: &cluster::Cluster, cc: &cluster::Cluster, eta: f64) -> bool {
    let dist = rc.bbox.distance(&cc.bbox);
    dist > 0.0 && rc.bbox.diameter().min(cc.bbox.diameter()) <= eta * dist
}

/// Visits the leaves of the block tree under (r, c): (row cluster, column
/// cluster, admissible), until `visit` breaks. An admissible pair that is
/// not [`Structure::smooth`] is subdivided like an inadmissible one. A node
/// for which `take` returns true is left to it, subtree and all.
#[allow(clippy::too_many_arguments)]
fn block_tree(
    rt: &ClusterTree,
    ct: &ClusterTree,
    r: usize,
    c: usize,
    eta: f64,
    structure: &dyn Structure,
    take: &mut dyn FnMut(usize, usize) -> bool,
    visit: &mut dyn FnMut(usize, usize, bool) -> ControlFlow<()>,
) -> ControlFlow<()> {
    if take(r, c) {
        return ControlFlow::Continue(());
    }
    let (rc, cc) = (&rt.clusters[r], &ct.clusters[c]);
    if by_distance(rc, cc, eta)
        && structure.smooth(
            &rt.order[rc.start..rc.end],
            &rc.bbox,
            &ct.order[cc.start..cc.end],
            &cc.bbox,
        )
    {
        return visit(r, c, true);
    }
    let mut recurse = |r, c| block_tree(rt, ct, r, c, eta, structure, take, visit);
    match (rc.children, cc.children) {
        (None, None) => visit(r, c, false),
        (Some(rs), None) => rs.iter().try_for_each(|&r| recurse(r, c)),
        (None, Some(cs)) => cs.iter().try_for_each(|&c| recurse(r, c)),
        (Some(rs), Some(cs)) => rs
            .iter()
            .try_for_each(|&r| cs.iter().try_for_each(|&c| recurse(r, c))),
    }
}

impl crate::solve::LinearOperator for HMatrix {
    fn dim(&self) -> usize {
        assert_eq!(self.stats.shape.0, self.stats.shape.1, "a square H-matrix");
        self.stats.shape.0
    }

    fn apply(&self, x: &[f64], y: &mut [f64]) {
        self.matvec(x, y);
    }

    fn apply_many(&self, xs: &[&[f64]], ys: &mut [&mut [f64]]) {
        self.matvec_many(xs, ys);
    }
}

impl Structure for crate::matrix::DenseMatrix {}

impl Entries for crate::matrix::DenseMatrix {
    fn block(&self, rows: &[usize], cols: &[usize], out: &mut [f64]) {
        for (a, &i) in rows.iter().enumerate() {
            let row = self.row(i);
            for (b, &j) in cols.iter().enumerate() {
                out[a * cols.len() + b] = row[j];
            }
        }
    }
}
