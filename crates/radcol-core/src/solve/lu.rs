//! Dense LU with partial pivoting (faer, rayon-parallel).
//!
//! Why: a direct solver is the robust reference for the iterative one, and
//! its `O(n^3)` factorisation is reused by every right-hand side that shares
//! the matrix (e.g. colour channels with the same reflectivity), each of
//! which then costs only `O(n^2)`.
//!
//! Implementation notes: faer's low-level
//! `linalg::lu::partial_pivoting::{factor, solve}` routines are used instead
//! of `Mat::partial_piv_lu()` because (a) they take an explicit [`Par`], so
//! the factorisation is rayon-parallel regardless of faer's global
//! parallelism setting, and (b) they keep L and U packed in one matrix
//! (the high-level type stores separate L and U copies: 2× the memory, which
//! matters at n ≈ 30000, 7.2 GB per matrix).

use super::{all_finite, max_abs, unscale, SolveError};
use crate::matrix::DenseMatrix;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::lu::partial_pivoting::{factor, solve};
use faer::perm::Perm;
use faer::{Mat, MatMut, Par};
use rayon::prelude::*;

/// Columns per parallel task when transposing row-major input into faer's
/// column-major storage: each task reads one contiguous row segment of this
/// width per row (cache-line friendly) and writes as many column streams.
const TRANSPOSE_BLOCK: usize = 16;

/// Dense LU factorisation `P A = L U` with partial (row) pivoting; factor
/// once, solve many right-hand sides (colour channels).
pub struct DenseLu {
    /// L (unit lower, strictly below the diagonal) and U (upper, with the
    /// diagonal) packed together, column-major.
    lu: Mat<f64>,
    /// Row permutation `P`.
    perm: Perm<usize>,
    /// Index of the smallest `|U_ii|`: reported if a solve overflows.
    min_pivot: usize,
    par: Par,
}

impl std::fmt::Debug for DenseLu {
    // Manual: faer's Debug would print all n² entries.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DenseLu")
            .field("dim", &self.dim())
            .field("min_pivot", &self.min_pivot)
            .finish_non_exhaustive()
    }
}

impl DenseLu {
    /// Factors the square matrix `a` (rayon-parallel, all threads of the
    /// current rayon pool).
    ///
    /// # Errors
    /// * [`SolveError::DimensionMismatch`] if `a` is not square
    ///   (`expected` = rows, `found` = columns);
    /// * [`SolveError::NonFinite`] if `a` contains NaN or infinity;
    /// * [`SolveError::Singular`] if a pivot (diagonal of U) is zero or not
    ///   finite.
    pub fn factor(a: &DenseMatrix) -> Result<Self, SolveError> {
        let n = a.nrows();
        if a.ncols() != n {
            return Err(SolveError::DimensionMismatch {
                expected: n,
                found: a.ncols(),
            });
        }
        if !a.as_slice().par_iter().all(|v| v.is_finite()) {
            return Err(SolveError::NonFinite);
        }
        let par = Par::rayon(0);

        // Row-major -> column-major, in parallel over column blocks.
        let mut lu = Mat::<f64>::zeros(n, n);
        lu.par_col_chunks_mut(TRANSPOSE_BLOCK)
            .enumerate()
            .for_each(|(blk, mut cols)| {
                let j0 = blk * TRANSPOSE_BLOCK;
                let w = cols.ncols();
                for i in 0..n {
                    let src = &a.row(i)[j0..j0 + w];
                    for (jj, &v) in src.iter().enumerate() {
                        cols[(i, jj)] = v;
                    }
                }
            });

        let mut fwd = vec![0usize; n];
        let mut bwd = vec![0usize; n];
        factor::lu_in_place(
            lu.as_mut(),
            &mut fwd,
            &mut bwd,
            par,
            MemStack::new(&mut MemBuffer::new(
                factor::lu_in_place_scratch::<usize, f64>(n, n, par, Default::default()),
            )),
            Default::default(),
        );
        // Checked construction (no `unsafe`): O(n), negligible next to O(n^3).
        let perm = Perm::new_checked(fwd.into_boxed_slice(), bwd.into_boxed_slice(), n);

        let mut min_pivot = 0;
        let mut min_abs = f64::INFINITY;
        for i in 0..n {
            let u = lu[(i, i)];
            if u == 0.0 || !u.is_finite() {
                return Err(SolveError::Singular { pivot: i });
            }
            if u.abs() < min_abs {
                min_abs = u.abs();
                min_pivot = i;
            }
        }
        Ok(Self {
            lu,
            perm,
            min_pivot,
            par,
        })
    }

    /// Solves `A x = b` in place: `b` holds the right-hand side on entry and
    /// the solution on exit.
    ///
    /// # Errors
    /// * [`SolveError::DimensionMismatch`] if `b.len() != self.dim()`;
    /// * [`SolveError::NonFinite`] if `b` contains NaN or infinity;
    /// * [`SolveError::Singular`] if the solution is not finite (overflow on a
    ///   tiny pivot; `pivot` is the index of the smallest `|U_ii|`);
    /// * [`SolveError::Overflow`] if the solution is beyond the largest f64.
    pub fn solve_in_place(&self, b: &mut [f64]) -> Result<(), SolveError> {
        let n = self.dim();
        if b.len() != n {
            return Err(SolveError::DimensionMismatch {
                expected: n,
                found: b.len(),
            });
        }
        if !all_finite(b) {
            return Err(SolveError::NonFinite);
        }
        // Solved for b / max|b_i| and scaled back, so that tiny or huge
        // right-hand sides neither underflow into subnormals nor overflow
        // on the way.
        let scale = max_abs(b);
        if scale == 0.0 {
            return Ok(());
        }
        b.iter_mut().for_each(|v| *v /= scale);
        let rhs = MatMut::from_column_major_slice_mut(b, n, 1);
        solve::solve_in_place(
            self.lu.as_ref(),
            self.lu.as_ref(),
            self.perm.as_ref(),
            rhs,
            self.par,
            MemStack::new(&mut MemBuffer::new(solve::solve_in_place_scratch::<
                usize,
                f64,
            >(n, 1, self.par))),
        );
        if !all_finite(b) {
            return Err(SolveError::Singular {
                pivot: self.min_pivot,
            });
        }
        unscale(b, scale)
    }

    /// Dimension `n` of the factored `n × n` matrix.
    pub fn dim(&self) -> usize {
        self.lu.nrows()
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_util::*;
    use super::*;

    #[test]
    fn manufactured_solution_recovered() {
        let n = 300;
        let a = well_conditioned(n, 42);
        let xt = x_true(n);
        let b = ref_matvec(&a, &xt);
        let lu = DenseLu::factor(&a).unwrap();
        assert_eq!(lu.dim(), n);
        let mut x = b.clone();
        lu.solve_in_place(&mut x).unwrap();
        assert!(rel_diff(&x, &xt) < 1e-10, "{}", rel_diff(&x, &xt));
        assert!(ref_rel_residual(&a, &x, &b) < 1e-13);
    }

    #[test]
    fn factor_once_solve_many() {
        // Large enough (> faer's 128² parallel threshold, not a multiple of
        // the transpose block) to exercise the blocked, parallel paths.
        let n = 517;
        let a = well_conditioned(n, 9);
        let lu = DenseLu::factor(&a).unwrap();
        for c in 0..3 {
            let xt: Vec<f64> = x_true(n)
                .iter()
                .map(|v| v * (c as f64 + 1.0) - 0.5)
                .collect();
            let mut x = ref_matvec(&a, &xt);
            lu.solve_in_place(&mut x).unwrap();
            assert!(rel_diff(&x, &xt) < 1e-10, "channel {c}");
        }
    }

    #[test]
    fn tiny_and_huge_right_hand_sides_give_the_same_relative_answer() {
        let n = 40;
        let a = well_conditioned(n, 4);
        let lu = DenseLu::factor(&a).unwrap();
        let xt = x_true(n);
        let b = ref_matvec(&a, &xt);
        // 1e-320 is subnormal: without scaling its digits are lost.
        for scale in [1e-320, 1e-300, 1e300] {
            let mut x: Vec<f64> = b.iter().map(|v| v * scale).collect();
            lu.solve_in_place(&mut x).unwrap();
            let back: Vec<f64> = x.iter().map(|v| v / scale).collect();
            let tol = if scale < 1e-310 { 1e-3 } else { 1e-13 };
            assert!(
                rel_diff(&back, &xt) < tol,
                "{scale}: {}",
                rel_diff(&back, &xt)
            );
        }
        let half = DenseMatrix::from_row_major(1, 1, vec![0.5]);
        let mut x = vec![1e308];
        assert!(matches!(
            DenseLu::factor(&half).unwrap().solve_in_place(&mut x),
            Err(SolveError::Overflow { .. })
        ));
    }

    #[test]
    fn pivoting_is_needed_and_done() {
        // zero leading entry: unpivoted LU would fail
        let a =
            DenseMatrix::from_row_major(3, 3, vec![0.0, 2.0, 1.0, 1.0, 1.0, 1.0, 2.0, 0.0, 3.0]);
        let lu = DenseLu::factor(&a).unwrap();
        // x = (1, 2, 3): b = (0+4+3, 1+2+3, 2+0+9)
        let mut b = vec![7.0, 6.0, 11.0];
        lu.solve_in_place(&mut b).unwrap();
        for (got, want) in b.iter().zip([1.0, 2.0, 3.0]) {
            crate::assert_close!(got, want, 1e-14, "{b:?}");
        }
    }

    #[test]
    fn singular_matrix_is_singular() {
        // duplicated row
        let a =
            DenseMatrix::from_row_major(3, 3, vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 1.0, 2.0, 3.0]);
        assert!(matches!(
            DenseLu::factor(&a),
            Err(SolveError::Singular { .. })
        ));
        // zero column
        let mut z = well_conditioned(20, 4);
        for i in 0..20 {
            z.as_mut_slice()[i * 20 + 7] = 0.0;
        }
        assert!(matches!(
            DenseLu::factor(&z),
            Err(SolveError::Singular { pivot: 7 })
        ));
        // all zero
        assert!(matches!(
            DenseLu::factor(&DenseMatrix::zeros(4, 4)),
            Err(SolveError::Singular { pivot: 0 })
        ));
    }

    #[test]
    fn dimension_mismatch() {
        assert!(matches!(
            DenseLu::factor(&DenseMatrix::zeros(3, 4)),
            Err(SolveError::DimensionMismatch {
                expected: 3,
                found: 4
            })
        ));
        let lu = DenseLu::factor(&well_conditioned(5, 2)).unwrap();
        let mut b = vec![1.0; 6];
        assert!(matches!(
            lu.solve_in_place(&mut b),
            Err(SolveError::DimensionMismatch {
                expected: 5,
                found: 6
            })
        ));
    }

    #[test]
    fn non_finite_inputs() {
        let lu = DenseLu::factor(&well_conditioned(5, 2)).unwrap();
        let mut b = vec![1.0, f64::NAN, 0.0, 0.0, 0.0];
        assert!(matches!(
            lu.solve_in_place(&mut b),
            Err(SolveError::NonFinite)
        ));
        let mut a = well_conditioned(5, 2);
        a.as_mut_slice()[12] = f64::INFINITY;
        assert!(matches!(DenseLu::factor(&a), Err(SolveError::NonFinite)));
    }

    #[test]
    fn empty_and_debug() {
        let lu = DenseLu::factor(&DenseMatrix::zeros(0, 0)).unwrap();
        assert_eq!(lu.dim(), 0);
        lu.solve_in_place(&mut []).unwrap();
        let s = format!("{:?}", DenseLu::factor(&well_conditioned(4, 1)).unwrap());
        assert!(s.contains("dim: 4"), "{s}");
    }
}
