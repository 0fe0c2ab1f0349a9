//! The leaves of a hierarchical matrix: zero, dense (whole, or compact
//! where the structure proves rows and columns zero) and low rank; how each
//! is built from an [`Entries`] oracle, how many numbers it stores, and its
//! product.

use super::aca::{aca_plus, recompress, Cross, LowRank};
use super::cluster::{self, ClusterTree};
use super::{Entries, Structure};
use std::cell::RefCell;

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
        let (sub_rows, sub_cols) = (pick(rows, &lr), pick(cols, &lc));
        let sampled = RefCell::new(Sampled::new(entries, &sub_rows, &sub_cols));
        let cross = admissible.then(|| {
            aca_plus(
                sub_rows.len(),
                sub_cols.len(),
                tol,
                &mut |i, out| sampled.borrow_mut().row(i, out),
                &mut |j, out| sampled.borrow_mut().column(j, out),
            )
        });
        match cross {
            Some(Cross::LowRank(l)) => {
                LeafData::LowRank(recompress(&l, tol).padded(rows.len(), &lr, cols.len(), &lc))
            }
            Some(Cross::Dense) | None => {
                dense(rows.len(), cols.len(), &lr, &lc, sampled.into_inner())
            }
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

/// The live lines of one block (`rows` × `cols`, original indices) as a
/// cross approximation asks for them, kept: a column is computed with its
/// group ([`Entries::column_group`]: on the radiosity matrix the f_r basis
/// functions of one element, whose integrals come together), so a later
/// pivot in the group costs no kernel evaluation; and when the cross does
/// not pay, the dense block is filled from the lines it already computed
/// and only the rest is asked of `entries`.
struct Sampled<'a> {
    entries: &'a dyn Entries,
    rows: &'a [usize],
    cols: &'a [usize],
    kept_rows: Vec<Option<Vec<f64>>>,
    kept_cols: Vec<Option<Vec<f64>>>,
}

impl<'a> Sampled<'a> {
    fn new(entries: &'a dyn Entries, rows: &'a [usize], cols: &'a [usize]) -> Self {
        Self {
            entries,
            rows,
            cols,
            kept_rows: vec![None; rows.len()],
            kept_cols: vec![None; cols.len()],
        }
    }

    /// Local row `i` into `out`.
    fn row(&mut self, i: usize, out: &mut [f64]) {
        if let Some(r) = &self.kept_rows[i] {
            out.copy_from_slice(r);
            return;
        }
        self.entries.block(&self.rows[i..i + 1], self.cols, out);
        self.kept_rows[i] = Some(out.to_vec());
    }

    /// Local column `j` into `out`.
    fn column(&mut self, j: usize, out: &mut [f64]) {
        if let Some(c) = &self.kept_cols[j] {
            out.copy_from_slice(c);
            return;
        }
        let group = self.entries.column_group(self.cols[j]);
        let members: Vec<usize> = (0..self.cols.len())
            .filter(|&b| group.contains(&self.cols[b]))
            .collect();
        let cols: Vec<usize> = members.iter().map(|&b| self.cols[b]).collect();
        let (m, g) = (self.rows.len(), cols.len());
        let mut buf = vec![0.0; m * g];
        self.entries.block(self.rows, &cols, &mut buf);
        for (at, &b) in members.iter().enumerate() {
            self.kept_cols[b] = Some((0..m).map(|i| buf[i * g + at]).collect());
        }
        out.copy_from_slice(self.kept_cols[j].as_deref().expect("j is in its group"));
    }

    /// The whole block, row-major: the kept lines, and the entries of the
    /// other rows in the other columns from `entries` (one call).
    fn block(self) -> Vec<f64> {
        let (m, n) = (self.rows.len(), self.cols.len());
        let mut a = vec![0.0; m * n];
        let rest_rows: Vec<usize> = (0..m).filter(|&i| self.kept_rows[i].is_none()).collect();
        let rest_cols: Vec<usize> = (0..n).filter(|&j| self.kept_cols[j].is_none()).collect();
        if !rest_rows.is_empty() && !rest_cols.is_empty() {
            let mut rest = vec![0.0; rest_rows.len() * rest_cols.len()];
            self.entries.block(
                &pick(self.rows, &rest_rows),
                &pick(self.cols, &rest_cols),
                &mut rest,
            );
            for (row, &i) in rest.chunks_exact(rest_cols.len()).zip(&rest_rows) {
                for (v, &j) in row.iter().zip(&rest_cols) {
                    a[i * n + j] = *v;
                }
            }
        }
        for (j, c) in self.kept_cols.iter().enumerate() {
            if let Some(c) = c {
                for (i, v) in c.iter().enumerate() {
                    a[i * n + j] = *v;
                }
            }
        }
        for (i, r) in self.kept_rows.iter().enumerate() {
            if let Some(r) = r {
                a[i * n..(i + 1) * n].copy_from_slice(r);
            }
        }
        a
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

/// The dense leaf of an m × n block of which only the rows at positions
/// `lr` and the columns at `lc` can be non-zero (`live`: those lines):
/// zero, compact or whole, whichever stores least ([`dense_numbers`]).
fn dense(m: usize, n: usize, lr: &[usize], lc: &[usize], live: Sampled<'_>) -> LeafData {
    let numbers = dense_numbers(m, n, lr.len(), lc.len());
    if numbers == 0 {
        LeafData::Zero
    } else if numbers < (m * n) as u64 {
        let index = |v: &[usize]| v.iter().map(|&a| a as u32).collect();
        LeafData::Compact(Compact {
            rows: index(lr),
            cols: index(lc),
            a: live.block(),
        })
    } else {
        let mut a = vec![0.0; m * n];
        for (row, &i) in live.block().chunks_exact(lc.len()).zip(lr) {
            for (v, &j) in row.iter().zip(lc) {
                a[i * n + j] = *v;
            }
        }
        LeafData::Dense(a)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::matrix::DenseMatrix;
    use std::sync::atomic::{AtomicU64, Ordering};

    /// A dense matrix whose columns come in groups of three (as an
    /// element's basis functions do), counting the entries asked of it.
    struct Grouped {
        m: DenseMatrix,
        asked: AtomicU64,
    }

    impl Structure for Grouped {}

    impl Entries for Grouped {
        fn block(&self, rows: &[usize], cols: &[usize], out: &mut [f64]) {
            self.asked
                .fetch_add((rows.len() * cols.len()) as u64, Ordering::Relaxed);
            self.m.block(rows, cols, out);
        }

        fn column_group(&self, j: usize) -> std::ops::Range<usize> {
            j / 3 * 3..(j / 3 + 1) * 3
        }
    }

    /// A block whose cross does not pay (full rank) is filled from the
    /// rows and columns the cross computed plus the rest: every entry the
    /// matrix's, and fewer asked than the cross and a fresh fill together
    /// (what the build asked before); a low-rank block's columns are asked
    /// a group at a time and never twice.
    #[test]
    fn a_dense_leaf_reuses_what_its_cross_computed() {
        let (m, n) = (30, 24);
        let mut x = 0x9e37_79b9_u64;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x % 1000) as f64 / 1000.0 - 0.5
        };
        let data: Vec<f64> = (0..m * n).map(|_| next()).collect();
        let entries = Grouped {
            m: DenseMatrix::from_row_major(m, n, data.clone()),
            asked: AtomicU64::new(0),
        };
        let (rows, cols): (Vec<usize>, Vec<usize>) = ((0..m).collect(), (0..n).collect());
        let sampled = RefCell::new(Sampled::new(&entries, &rows, &cols));
        let cross = aca_plus(
            m,
            n,
            1e-8,
            &mut |i, out| sampled.borrow_mut().row(i, out),
            &mut |j, out| sampled.borrow_mut().column(j, out),
        );
        assert!(matches!(cross, Cross::Dense));
        let by_cross = entries.asked.load(Ordering::Relaxed);
        assert!(by_cross > (m * n) as u64 / 2, "{by_cross}");
        let LeafData::Dense(a) = dense(m, n, &rows, &cols, sampled.into_inner()) else {
            panic!("a full block is stored whole");
        };
        assert_eq!(a, data);
        let asked = entries.asked.load(Ordering::Relaxed);
        assert!(
            asked < by_cross + (m * n) as u64 / 2,
            "{asked} after {by_cross}"
        );

        // Rank 2, columns in groups of three: each group asked once.
        let data: Vec<f64> = (0..m * n)
            .map(|k| {
                let (i, j) = ((k / n) as f64, (k % n) as f64);
                1.0 + i * j + (0.1 * i).sin() * (0.2 * j).cos()
            })
            .collect();
        let entries = Grouped {
            m: DenseMatrix::from_row_major(m, n, data),
            asked: AtomicU64::new(0),
        };
        let sampled = RefCell::new(Sampled::new(&entries, &rows, &cols));
        let cross = aca_plus(
            m,
            n,
            1e-10,
            &mut |i, out| sampled.borrow_mut().row(i, out),
            &mut |j, out| sampled.borrow_mut().column(j, out),
        );
        let Cross::LowRank(lr) = cross else {
            panic!("rank 2 compresses");
        };
        let s = sampled.into_inner();
        let (rows_kept, cols_kept) = (
            s.kept_rows.iter().flatten().count(),
            s.kept_cols.iter().flatten().count(),
        );
        assert_eq!(cols_kept % 3, 0, "whole groups");
        let asked = entries.asked.load(Ordering::Relaxed) as usize;
        assert_eq!(asked, rows_kept * n + cols_kept * m, "no line asked twice");
        assert!(lr.rank() <= 4, "rank {}", lr.rank());
    }
}
