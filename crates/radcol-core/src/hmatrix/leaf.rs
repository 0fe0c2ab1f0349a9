//! The leaves of a hierarchical matrix: zero, dense (whole, or compact
//! where the structure proves rows and columns zero) and low rank; how each
//! is built from an [`Entries`] oracle, how many numbers it stores, and its
//! product.

use super::aca::{aca_plus, recompress, Cross, LowRank};
use super::cluster::{self, ClusterTree};
use super::{Entries, Structure};

/// One leaf of the block tree: ranges of the row and column orders.
#[derive(Clone, Debug)]
pub(super) struct Leaf {
    pub(super) rows: std::ops::Range<usize>,
    pub(super) cols: std::ops::Range<usize>,
    /// Its row and column clusters.
    pub(super) block: (u32, u32),
    /// Whether it is an admissible block (low rank, or left dense when its
    /// cross did not pay).
    pub(super) admissible: bool,
    pub(super) data: LeafData,
}

#[derive(Clone, Debug)]
pub(super) enum LeafData {
    Zero,
    /// Row-major.
    Dense(Vec<f64>),
    /// A dense block of which the structure proves whole rows and columns
    /// zero: the others only.
    Compact(Compact),
    LowRank(LowRank),
}

/// The non-zero rows and columns of a dense block (local indices, sorted)
/// and their entries, row-major.
#[derive(Clone, Debug)]
pub(super) struct Compact {
    rows: Vec<u32>,
    cols: Vec<u32>,
    a: Vec<f64>,
}

impl LeafData {
    /// Numbers stored, in f64s (two u32 indices count as one).
    pub(super) fn stored(&self, m: usize, n: usize) -> u64 {
        match self {
            LeafData::Zero => 0,
            LeafData::Dense(_) => (m * n) as u64,
            LeafData::Compact(c) => compact_numbers(c.rows.len(), c.cols.len()),
            LeafData::LowRank(lr) => ((m + n) * lr.rank()) as u64,
        }
    }
}

/// Numbers a compact block of `live_rows` × `live_cols` stores: its
/// entries and its indices.
fn compact_numbers(live_rows: usize, live_cols: usize) -> u64 {
    (live_rows * live_cols + (live_rows + live_cols).div_ceil(2)) as u64
}

/// Numbers a dense leaf of m × n with `live_rows` and `live_cols` not
/// proved zero stores: none when either is empty, the compact block when
/// that is smaller, else all m n.
fn dense_numbers(m: usize, n: usize, live_rows: usize, live_cols: usize) -> u64 {
    if live_rows == 0 || live_cols == 0 {
        0
    } else {
        compact_numbers(live_rows, live_cols).min((m * n) as u64)
    }
}

impl Leaf {
    pub(super) fn apply_add(&self, xp: &[f64], yp: &mut [f64]) {
        let x = &xp[self.cols.clone()];
        let y = &mut yp[self.rows.clone()];
        match &self.data {
            LeafData::Zero => {}
            LeafData::Dense(a) => {
                let n = x.len();
                for (yi, row) in y.iter_mut().zip(a.chunks_exact(n)) {
                    *yi += row.iter().zip(x).map(|(a, b)| a * b).sum::<f64>();
                }
            }
            LeafData::Compact(c) => {
                let n = c.cols.len();
                for (&i, row) in c.rows.iter().zip(c.a.chunks_exact(n)) {
                    y[i as usize] += row
                        .iter()
                        .zip(&c.cols)
                        .map(|(a, &j)| a * x[j as usize])
                        .sum::<f64>();
                }
            }
            LeafData::LowRank(lr) => lr.apply_add(x, y),
        }
    }
}

/// The leaf of row cluster `r` and column cluster `c` (`zero`: proved zero
/// by the structure).
#[allow(clippy::too_many_arguments)]
pub(super) fn leaf(
    rt: &ClusterTree,
    ct: &ClusterTree,
    r: usize,
    c: usize,
    admissible: bool,
    zero: bool,
    entries: &dyn Entries,
    tol: f64,
) -> Leaf {
    let (rc, cc) = (&rt.clusters[r], &ct.clusters[c]);
    let rows = &rt.order[rc.start..rc.end];
    let cols = &ct.order[cc.start..cc.end];
    let data = if zero {
        LeafData::Zero
    } else {
        let (zero_rows, zero_cols) = entries.zero_lines(rows, cols);
        let (lr, lc) = (live(&zero_rows), live(&zero_cols));
        let cross = admissible.then(|| {
            let (sub_rows, sub_cols) = (pick(rows, &lr), pick(cols, &lc));
            aca_plus(
                sub_rows.len(),
                sub_cols.len(),
                tol,
                &mut |i, out| entries.block(&sub_rows[i..i + 1], &sub_cols, out),
                &mut |j, out| entries.block(&sub_rows, &sub_cols[j..j + 1], out),
            )
        });
        match cross {
            Some(Cross::LowRank(l)) => {
                LeafData::LowRank(recompress(&l, tol).padded(rows.len(), &lr, cols.len(), &lc))
            }
            Some(Cross::Dense) | None => dense(rows, cols, &lr, &lc, entries),
        }
    };
    Leaf {
        rows: rc.start..rc.end,
        cols: cc.start..cc.end,
        block: (r as u32, c as u32),
        admissible,
        data,
    }
}

/// Numbers the dense leaf of row cluster `rc` and column cluster `cc`
/// (orders `row_order`, `col_order`) stores, known from `structure`'s zero
/// lines without an entry.
pub(super) fn dense_leaf_numbers(
    row_order: &[usize],
    rc: &cluster::Cluster,
    col_order: &[usize],
    cc: &cluster::Cluster,
    structure: &dyn Structure,
) -> u64 {
    let (rows, cols) = (&row_order[rc.start..rc.end], &col_order[cc.start..cc.end]);
    let (zr, zc) = structure.zero_lines(rows, cols);
    dense_numbers(rows.len(), cols.len(), live(&zr).len(), live(&zc).len())
}

/// The positions of the lines not proved zero.
fn live(zero: &[bool]) -> Vec<usize> {
    (0..zero.len()).filter(|&a| !zero[a]).collect()
}

/// `idx` at `positions`.
fn pick(idx: &[usize], positions: &[usize]) -> Vec<usize> {
    positions.iter().map(|&a| idx[a]).collect()
}

/// The dense leaf of `rows` × `cols`, of which only the rows at positions
/// `lr` and the columns at `lc` can be non-zero: zero, compact or whole,
/// whichever stores least ([`dense_numbers`]).
fn dense(
    rows: &[usize],
    cols: &[usize],
    lr: &[usize],
    lc: &[usize],
    entries: &dyn Entries,
) -> LeafData {
    let (m, n) = (rows.len(), cols.len());
    let numbers = dense_numbers(m, n, lr.len(), lc.len());
    if numbers == 0 {
        LeafData::Zero
    } else if numbers < (m * n) as u64 {
        let mut a = vec![0.0; lr.len() * lc.len()];
        entries.block(&pick(rows, lr), &pick(cols, lc), &mut a);
        let index = |v: &[usize]| v.iter().map(|&a| a as u32).collect();
        LeafData::Compact(Compact {
            rows: index(lr),
            cols: index(lc),
            a,
        })
    } else {
        let mut a = vec![0.0; m * n];
        entries.block(rows, cols, &mut a);
        LeafData::Dense(a)
    }
}
