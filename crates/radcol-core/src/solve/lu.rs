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
#[cfg(any(test, feature = "internals"))]
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
    /// ‖A‖₁, the largest column sum of |a_ij|: for the condition estimate.
    norm1: f64,
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
    #[cfg(any(test, feature = "internals"))]
    pub fn factor(a: &DenseMatrix) -> Result<Self, SolveError> {
        let n = a.nrows();
        if a.ncols() != n {
            return Err(SolveError::DimensionMismatch {
                expected: n,
                found: a.ncols(),
            });
        }
        Self::factor_rows(n, |i, j0, out| {
            out.copy_from_slice(&a.row(i)[j0..j0 + out.len()])
        })
    }

    /// Factors `I - diag(ρ) Gm` of `op` without forming it first: the
    /// factors are the only n × n copy besides Gm (LU used to peak at three).
    ///
    /// # Errors
    /// As [`factor`](Self::factor).
    pub fn factor_radiosity(op: &super::RadiosityOperator<'_>) -> Result<Self, SolveError> {
        let (gm, rho) = (op.gm, op.rho);
        Self::factor_rows(gm.nrows(), |i, j0, out| {
            for (o, &g) in out.iter_mut().zip(&gm.row(i)[j0..]) {
                *o = -rho[i] * g;
            }
            if (j0..j0 + out.len()).contains(&i) {
                out[i - j0] += 1.0;
            }
        })
    }

    /// Factors the n × n matrix whose row i, columns j0.., `block(i, j0,
    /// out)` writes into `out`.
    fn factor_rows(
        n: usize,
        block: impl Fn(usize, usize, &mut [f64]) + Sync,
    ) -> Result<Self, SolveError> {
        let par = Par::rayon(0);
        // Row-major -> column-major, in parallel over column blocks, with
        // the column sums of |a_ij| for ‖A‖₁.
        let mut lu = Mat::<f64>::zeros(n, n);
        let col_sums: Vec<f64> = lu
            .par_col_chunks_mut(TRANSPOSE_BLOCK)
            .enumerate()
            .flat_map_iter(|(blk, mut cols)| {
                let j0 = blk * TRANSPOSE_BLOCK;
                let w = cols.ncols();
                let mut src = [0.0f64; TRANSPOSE_BLOCK];
                let mut sums = vec![0.0f64; w];
                for i in 0..n {
                    block(i, j0, &mut src[..w]);
                    for (jj, &v) in src[..w].iter().enumerate() {
                        cols[(i, jj)] = v;
                        sums[jj] += v.abs();
                    }
                }
                sums
            })
            .collect();
        if !col_sums.iter().all(|v| v.is_finite()) {
            return Err(SolveError::NonFinite);
        }
        let norm1 = col_sums.into_iter().fold(0.0, f64::max);

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
            norm1,
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

    /// An estimate of the condition number κ₁(A) = ‖A‖₁ ‖A⁻¹‖₁, from a few
    /// solves with the factors (Hager's method with Higham's refinements, as
    /// in LAPACK's `dlacon`: at most 5 steps of a power-like iteration on
    /// ‖A⁻¹ x‖₁ over the unit ball's vertices, and an alternating test
    /// vector that guards against its rare failures). It is a lower bound of
    /// κ₁ that is almost always within a factor 3 of it, at the cost of
    /// about 12 triangular solve pairs, O(n²) against the O(n³) factoring.
    /// A relative perturbation δ of A (quadrature error) can change the
    /// solution by up to about κ δ.
    pub fn condition_estimate(&self) -> f64 {
        let n = self.dim();
        if n == 0 {
            return 1.0;
        }
        let norm1 = |v: &[f64]| v.iter().map(|x| x.abs()).sum::<f64>();
        let sign = |v: &[f64]| -> Vec<f64> {
            v.iter()
                .map(|&x| if x >= 0.0 { 1.0 } else { -1.0 })
                .collect()
        };
        let mut x = vec![1.0 / n as f64; n];
        self.raw_solve(&mut x, false);
        let mut est = norm1(&x);
        let mut xi = sign(&x);
        let mut z = xi.clone();
        self.raw_solve(&mut z, true);
        let mut last = usize::MAX;
        for _ in 0..5 {
            let j = (0..n).fold(0, |b, i| if z[i].abs() > z[b].abs() { i } else { b });
            if j == last {
                break; // the same vertex again: converged
            }
            last = j;
            let mut y = vec![0.0; n];
            y[j] = 1.0;
            self.raw_solve(&mut y, false);
            let new = norm1(&y);
            let s = sign(&y);
            if new <= est || s == xi {
                est = est.max(new);
                break;
            }
            est = new;
            xi = s;
            z.clone_from(&xi);
            self.raw_solve(&mut z, true);
        }
        // Higham's alternating vector with growing entries.
        let mut alt: Vec<f64> = (0..n)
            .map(|i| {
                let t = 1.0 + i as f64 / (n.max(2) - 1) as f64;
                if i % 2 == 0 {
                    t
                } else {
                    -t
                }
            })
            .collect();
        self.raw_solve(&mut alt, false);
        est = est.max(2.0 * norm1(&alt) / (3.0 * n as f64));
        self.norm1 * est
    }

    /// Solves A x = b (or Aᵀ x = b) in place with the factors, unchecked.
    fn raw_solve(&self, b: &mut [f64], transpose: bool) {
        let n = self.dim();
        let rhs = MatMut::from_column_major_slice_mut(b, n, 1);
        let scratch = if transpose {
            solve::solve_transpose_in_place_scratch::<usize, f64>(n, 1, self.par)
        } else {
            solve::solve_in_place_scratch::<usize, f64>(n, 1, self.par)
        };
        let mut buffer = MemBuffer::new(scratch);
        let stack = MemStack::new(&mut buffer);
        let (l, u) = (self.lu.as_ref(), self.lu.as_ref());
        if transpose {
            solve::solve_transpose_in_place(l, u, self.perm.as_ref(), rhs, self.par, stack);
        } else {
            solve::solve_in_place(l, u, self.perm.as_ref(), rhs, self.par, stack);
        }
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
    fn condition_estimate_matches_closed_forms() {
        // Diagonal: κ₁ = max |d| / min |d| exactly.
        let d = DenseMatrix::from_row_major(3, 3, vec![1.0, 0., 0., 0., 1e-3, 0., 0., 0., -10.0]);
        let k = DenseLu::factor(&d).unwrap().condition_estimate();
        crate::assert_close!(k, 1e4, 1e-12 * 1e4, "diagonal");
        // Hilbert matrices, whose inverses have integer entries in closed
        // form: (H⁻¹)_ij = (-1)^(i+j) (i+j-1) C(n+i-1, n-j) C(n+j-1, n-i)
        // C(i+j-2, i-1)² (1-based). The estimate is a lower bound, and
        // within a factor 3 in practice.
        let binom = |n: u64, k: u64| (1..=k).fold(1.0f64, |c, i| c * (n + 1 - i) as f64 / i as f64);
        for n in [4usize, 6, 8] {
            let h: Vec<f64> = (0..n * n)
                .map(|e| 1.0 / ((e / n + e % n) as f64 + 1.0))
                .collect();
            let norm1 = |m: &dyn Fn(usize, usize) -> f64| {
                (0..n)
                    .map(|j| (0..n).map(|i| m(i, j).abs()).sum::<f64>())
                    .fold(0.0, f64::max)
            };
            let inv = |i: usize, j: usize| {
                let (i, j, n) = ((i + 1) as u64, (j + 1) as u64, n as u64);
                (i + j - 1) as f64
                    * binom(n + i - 1, n - j)
                    * binom(n + j - 1, n - i)
                    * binom(i + j - 2, i - 1).powi(2)
            };
            let exact = norm1(&|i, j| h[i * n + j]) * norm1(&inv);
            let lu = DenseLu::factor(&DenseMatrix::from_row_major(n, n, h.clone())).unwrap();
            let k = lu.condition_estimate();
            assert!(
                k <= exact * (1.0 + 1e-6) && k >= exact / 3.0,
                "n = {n}: {k:e} against {exact:e}"
            );
        }
    }

    #[test]
    fn radiosity_factors_equal_those_of_the_formed_matrix() {
        let n = 37; // not a multiple of the transpose block
        let g: Vec<f64> = (0..n * n)
            .map(|e| ((e * 7919 % 101) as f64 / 101.0) / n as f64)
            .collect();
        let g = DenseMatrix::from_row_major(n, n, g);
        let rho: Vec<f64> = (0..n).map(|i| 0.3 + 0.6 * (i as f64 / n as f64)).collect();
        let op = crate::solve::RadiosityOperator::new(&g, &rho).unwrap();
        let (direct, formed) = (
            DenseLu::factor_radiosity(&op).unwrap(),
            DenseLu::factor(&op.to_dense()).unwrap(),
        );
        let b: Vec<f64> = (0..n).map(|i| (i as f64).sin()).collect();
        let (mut x, mut y) = (b.clone(), b);
        direct.solve_in_place(&mut x).unwrap();
        formed.solve_in_place(&mut y).unwrap();
        assert_eq!(x, y);
        assert_eq!(direct.condition_estimate(), formed.condition_estimate());
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
