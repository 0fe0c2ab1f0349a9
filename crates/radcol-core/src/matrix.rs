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
