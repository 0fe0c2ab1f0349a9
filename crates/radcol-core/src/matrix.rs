//! Dense row-major matrices: the collocation matrix is filled one row per
//! collocation point, so rows are contiguous (`par_chunks_exact_mut(ncols)`).

use rayon::prelude::*;

/// A dense `nrows × ncols` matrix of `f64`, stored row-major:
/// entry `(i, j)` is `data[i * ncols + j]`.
#[derive(Clone, Debug, PartialEq)]
pub struct DenseMatrix {
    nrows: usize,
    ncols: usize,
    data: Vec<f64>,
}

impl DenseMatrix {
    /// An all-zero matrix.
    pub fn zeros(nrows: usize, ncols: usize) -> Self {
        Self {
            nrows,
            ncols,
            data: vec![0.0; nrows * ncols],
        }
    }

    /// Wraps row-major `data` (length `nrows * ncols`).
    ///
    /// # Panics
    /// If `data.len() != nrows * ncols` (a programming error, not bad input).
    pub fn from_row_major(nrows: usize, ncols: usize, data: Vec<f64>) -> Self {
        assert_eq!(
            data.len(),
            nrows * ncols,
            "row-major data has the wrong length"
        );
        Self { nrows, ncols, data }
    }

    /// Number of rows.
    pub fn nrows(&self) -> usize {
        self.nrows
    }

    /// Number of columns.
    pub fn ncols(&self) -> usize {
        self.ncols
    }

    /// Entry `(i, j)`.
    #[inline]
    pub fn get(&self, i: usize, j: usize) -> f64 {
        self.data[i * self.ncols + j]
    }

    /// Row `i` as a slice of length `ncols`.
    #[inline]
    pub fn row(&self, i: usize) -> &[f64] {
        &self.data[i * self.ncols..(i + 1) * self.ncols]
    }

    /// All entries, row-major, length `nrows * ncols`.
    pub fn as_slice(&self) -> &[f64] {
        &self.data
    }

    /// All entries, row-major, mutable.
    pub fn as_mut_slice(&mut self) -> &mut [f64] {
        &mut self.data
    }

    /// `y = self · x` in parallel over rows. `x.len() == ncols`, `y.len() == nrows`.
    pub fn matvec(&self, x: &[f64], y: &mut [f64]) {
        assert_eq!(x.len(), self.ncols);
        assert_eq!(y.len(), self.nrows);
        if self.ncols == 0 {
            y.fill(0.0);
            return;
        }
        y.par_iter_mut()
            .zip(self.data.par_chunks_exact(self.ncols))
            .for_each(|(yi, row)| *yi = dot(row, x));
    }
}

/// Dot product with four independent accumulators so the compiler can vectorise it.
/// (No `mul_add`: without a target FMA feature it becomes a slow library call.)
#[inline]
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut acc = [0.0f64; 4];
    let mut ca = a.chunks_exact(4);
    let mut cb = b.chunks_exact(4);
    for (x, y) in (&mut ca).zip(&mut cb) {
        for k in 0..4 {
            acc[k] += x[k] * y[k];
        }
    }
    let mut s = (acc[0] + acc[1]) + (acc[2] + acc[3]);
    for (x, y) in ca.remainder().iter().zip(cb.remainder()) {
        s += x * y;
    }
    s
}

/// `[dot(a, bs[0]), …, dot(a, bs[K-1])]`, each bit for bit as [`dot`]
/// computes it (the same four accumulators in the same order), with every
/// element of `a` loaded once for all K products: a matrix row multiplied
/// by the Krylov vectors of K colour channels is read from memory once.
#[inline]
pub fn dots<const K: usize>(a: &[f64], bs: [&[f64]; K]) -> [f64; K] {
    let n = bs.iter().fold(a.len(), |n, b| n.min(b.len()));
    let (a, bs) = (&a[..n], bs.map(|b| &b[..n]));
    let mut acc = [[0.0f64; 4]; K];
    let ca = a.chunks_exact(4);
    let rest = ca.remainder();
    let mut cbs = bs.map(|b| b.chunks_exact(4));
    for x in ca {
        for (acc, cb) in acc.iter_mut().zip(cbs.iter_mut()) {
            let y = cb.next().expect("as long as a");
            for k in 0..4 {
                acc[k] += x[k] * y[k];
            }
        }
    }
    let mut out = [0.0; K];
    for ((o, acc), cb) in out.iter_mut().zip(&acc).zip(&cbs) {
        let mut s = (acc[0] + acc[1]) + (acc[2] + acc[3]);
        for (x, y) in rest.iter().zip(cb.remainder()) {
            s += x * y;
        }
        *o = s;
    }
    out
}

/// `data` (row-major, `ncols` columns) cut into the row blocks
/// `offsets[k]..offsets[k + 1]`, one per element.
pub fn row_blocks<'a>(data: &'a mut [f64], offsets: &[usize], ncols: usize) -> Vec<&'a mut [f64]> {
    let mut blocks = Vec::with_capacity(offsets.len().saturating_sub(1));
    let mut rest = data;
    for w in offsets.windows(2) {
        let (block, tail) = std::mem::take(&mut rest).split_at_mut((w[1] - w[0]) * ncols);
        blocks.push(block);
        rest = tail;
    }
    blocks
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `dots` gives `dot`'s every bit, whatever the length's remainder
    /// modulo 4 and the number of vectors.
    #[test]
    fn dots_are_dot_to_the_bit() {
        let v = |n: usize, s: f64| -> Vec<f64> {
            (0..n)
                .map(|i| ((i as f64 + s) * 0.618_033_988_749_895).fract() - 0.3)
                .collect()
        };
        for n in [0, 1, 3, 4, 7, 8, 1001] {
            let a = v(n, 0.5);
            let bs: Vec<Vec<f64>> = (1..=4).map(|k| v(n, k as f64 * 1.7)).collect();
            let want: Vec<f64> = bs.iter().map(|b| dot(&a, b)).collect();
            assert_eq!(dots(&a, [&bs[0]]), [want[0]]);
            assert_eq!(dots(&a, [&bs[0], &bs[1]]), [want[0], want[1]]);
            assert_eq!(
                dots(&a, [&bs[0], &bs[1], &bs[2]]),
                [want[0], want[1], want[2]]
            );
            assert_eq!(
                dots(&a, [&bs[0], &bs[1], &bs[2], &bs[3]]),
                [want[0], want[1], want[2], want[3]]
            );
        }
    }
}
