//! Linear solvers for the collocation system `(I - diag(rho) G) u = e`.
//!
//! Two solvers, because the two regimes need different tools: the system
//! matrix is dense and well conditioned (`rho < 1`, `G` has row sums `<= 1`),
//! so restarted GMRES (`gmres`) converges in a handful of mat-vecs and never
//! needs the matrix explicitly (it can be matrix-free or GPU-backed), while a
//! dense LU ([`DenseLu`]) is the robust reference and pays off when many
//! right-hand sides (colour channels) share one factorisation.
//!
//! Every solver follows the pattern "options in, info or error out":
//! [`GmresParams`] in, [`GmresInfo`] or [`SolveError`] out.

mod gmres;
mod lockstep;
mod lu;
mod residual;

pub use gmres::{GmresInfo, GmresParams};
#[cfg(any(test, feature = "internals"))]
pub use gmres::{gmres, gmres_observed};
#[cfg(feature = "internals")]
pub use lockstep::gmres_radiosity;
pub use lockstep::{gmres_radiosity_reduced, RadiositySystem};
pub use lu::DenseLu;
pub use residual::true_residual;

use crate::matrix::{dot, dots, DenseMatrix};
use rayon::prelude::*;

/// Sums and maxima over the processes that each hold some of the rows of
/// GMRES's vectors (the ranks of a distributed solve: `crate::ranks`).
/// [`Alone`] is one process holding them all. Every process must call the
/// same reductions in the same order; GMRES does, since each of its
/// decisions is taken on reduced values.
pub trait Reduce: Sync {
    /// Each `v[i]` replaced by its sum over the processes.
    fn sum(&self, v: &mut [f64]);
    /// Each `v[i]` replaced by its maximum over the processes.
    fn max(&self, v: &mut [f64]);
}

/// One process, holding every row: reductions leave values as they are.
#[derive(Clone, Copy, Debug, Default)]
pub struct Alone;

impl Reduce for Alone {
    fn sum(&self, _: &mut [f64]) {}
    fn max(&self, _: &mut [f64]) {}
}

impl dyn Reduce + '_ {
    /// The dot product of two distributed vectors (local parts `a`, `b`).
    fn dot(&self, a: &[f64], b: &[f64]) -> f64 {
        let mut d = [dot(a, b)];
        self.sum(&mut d);
        d[0]
    }

    /// True on every process when `local` is true on any.
    fn any(&self, local: bool) -> bool {
        let mut v = [f64::from(u8::from(local))];
        self.max(&mut v);
        v[0] > 0.0
    }

    /// The largest |v_i| over every process's part of `v`.
    fn max_abs(&self, v: &[f64]) -> f64 {
        let mut m = [max_abs(v)];
        self.max(&mut m);
        m[0]
    }

    /// The total of a count held per process.
    fn total(&self, n: usize) -> usize {
        let mut t = [n as f64];
        self.sum(&mut t);
        t[0] as usize
    }
}

/// A square linear operator `y = A x` (dense, matrix-free or GPU-backed).
pub trait LinearOperator: Sync {
    /// Dimension `n` (the operator is `n × n`).
    fn dim(&self) -> usize;
    /// `y = A x`; `x.len() == y.len() == dim()`.
    fn apply(&self, x: &[f64], y: &mut [f64]);

    /// `ys[c] = A xs[c]` for every c, each product exactly as
    /// [`LinearOperator::apply`] would give it. Operators that keep their
    /// entries in memory override it to read them once for all the
    /// vectors (the products are memory-bound: three colour channels then
    /// cost about one); the default applies them one by one.
    fn apply_many(&self, xs: &[&[f64]], ys: &mut [&mut [f64]]) {
        assert_eq!(xs.len(), ys.len(), "as many products as vectors");
        for (x, y) in xs.iter().zip(ys.iter_mut()) {
            self.apply(x, y);
        }
    }
}

/// A dense matrix as an operator. Only square matrices are operators:
/// `dim()` is `nrows()` and [`LinearOperator::apply`] panics on a
/// non-square matrix.
impl LinearOperator for DenseMatrix {
    fn dim(&self) -> usize {
        self.nrows()
    }

    fn apply(&self, x: &[f64], y: &mut [f64]) {
        assert_eq!(
            self.nrows(),
            self.ncols(),
            "a DenseMatrix used as a LinearOperator must be square"
        );
        self.matvec(x, y);
    }

    /// One pass over the rows: each row, read once from memory, is
    /// multiplied by every vector while it is in cache.
    fn apply_many(&self, xs: &[&[f64]], ys: &mut [&mut [f64]]) {
        assert_eq!(self.nrows(), self.ncols(), "a square DenseMatrix");
        assert_eq!(xs.len(), ys.len(), "as many products as vectors");
        let n = self.nrows();
        if n == 0 || xs.is_empty() {
            return;
        }
        assert!(xs.iter().all(|x| x.len() == n) && ys.iter().all(|y| y.len() == n));
        let k = xs.len();
        let mut rows = vec![0.0; n * k];
        rows.par_chunks_exact_mut(k)
            .zip(self.as_slice().par_chunks_exact(n))
            .for_each(|(out, row)| {
                // Up to four vectors per pass over the row (registers).
                for (o, x) in out.chunks_mut(4).zip(xs.chunks(4)) {
                    match *x {
                        [a] => o.copy_from_slice(&dots(row, [a])),
                        [a, b] => o.copy_from_slice(&dots(row, [a, b])),
                        [a, b, c] => o.copy_from_slice(&dots(row, [a, b, c])),
                        [a, b, c, d] => o.copy_from_slice(&dots(row, [a, b, c, d])),
                        _ => unreachable!("chunks of one to four"),
                    }
                }
            });
        for (c, y) in ys.iter_mut().enumerate() {
            for (yi, r) in y.iter_mut().zip(rows.chunks_exact(k)) {
                *yi = r[c];
            }
        }
    }
}

/// The radiosity system operator `A = I - diag(rho) * gm`, where `gm` is the
/// geometric collocation matrix (shared by all colour channels) and `rho` the
/// reflectivity at each collocation point.
///
/// Invariants (checked by [`RadiosityOperator::new`], asserted by `apply`):
/// `gm` is square and `rho.len() == gm.nrows()`.
#[derive(Clone, Copy, Debug)]
pub struct RadiosityOperator<'a> {
    /// Geometric collocation matrix `G` (`n × n`).
    pub gm: &'a DenseMatrix,
    /// Reflectivity at each collocation point (length `n`).
    pub rho: &'a [f64],
}

impl<'a> RadiosityOperator<'a> {
    /// Checks the dimensions: `gm` square and `rho.len() == gm.nrows()`.
    pub fn new(gm: &'a DenseMatrix, rho: &'a [f64]) -> Result<Self, SolveError> {
        if gm.ncols() != gm.nrows() {
            return Err(SolveError::DimensionMismatch {
                expected: gm.nrows(),
                found: gm.ncols(),
            });
        }
        if rho.len() != gm.nrows() {
            return Err(SolveError::DimensionMismatch {
                expected: gm.nrows(),
                found: rho.len(),
            });
        }
        Ok(Self { gm, rho })
    }

    fn assert_shape(&self) {
        assert_eq!(self.gm.nrows(), self.gm.ncols(), "gm must be square");
        assert_eq!(self.rho.len(), self.gm.nrows(), "rho.len() != gm.nrows()");
    }

    /// The explicit matrix `I - diag(rho) gm` (for [`DenseLu`]).
    #[cfg(any(test, feature = "internals"))]
    pub fn to_dense(self) -> DenseMatrix {
        self.assert_shape();
        let n = self.gm.nrows();
        let mut a = DenseMatrix::zeros(n, n);
        if n == 0 {
            return a;
        }
        a.as_mut_slice()
            .par_chunks_exact_mut(n)
            .zip(self.gm.as_slice().par_chunks_exact(n))
            .zip(self.rho.par_iter())
            .enumerate()
            .for_each(|(i, ((arow, grow), &r))| {
                for (aij, &gij) in arow.iter_mut().zip(grow) {
                    *aij = -r * gij;
                }
                arow[i] += 1.0;
            });
        a
    }
}

impl LinearOperator for RadiosityOperator<'_> {
    fn dim(&self) -> usize {
        self.gm.nrows()
    }

    /// `y = x - rho .* (gm x)`, parallel over rows.
    fn apply(&self, x: &[f64], y: &mut [f64]) {
        self.assert_shape();
        let n = self.gm.nrows();
        assert_eq!(x.len(), n, "x.len() != dim()");
        assert_eq!(y.len(), n, "y.len() != dim()");
        if n == 0 {
            return;
        }
        y.par_iter_mut()
            .zip(self.gm.as_slice().par_chunks_exact(n))
            .zip(self.rho.par_iter())
            .zip(x.par_iter())
            .for_each(|(((yi, row), &r), &xi)| *yi = xi - r * dot(row, x));
    }
}

/// `A = I - diag(rho) g` for any geometric operator `g` (a compressed one,
/// for example): only products, for GMRES.
#[derive(Clone, Copy)]
#[cfg(any(test, feature = "internals"))]
pub struct ImplicitRadiosity<'a> {
    /// The geometric operator.
    pub g: &'a dyn LinearOperator,
    /// Reflectivity at each collocation point (length `g.dim()`).
    pub rho: &'a [f64],
}

#[cfg(any(test, feature = "internals"))]
impl<'a> ImplicitRadiosity<'a> {
    /// Checks that `rho` has `g`'s dimension.
    pub fn new(g: &'a dyn LinearOperator, rho: &'a [f64]) -> Result<Self, SolveError> {
        if rho.len() != g.dim() {
            return Err(SolveError::DimensionMismatch {
                expected: g.dim(),
                found: rho.len(),
            });
        }
        Ok(Self { g, rho })
    }
}

#[cfg(any(test, feature = "internals"))]
impl std::fmt::Debug for ImplicitRadiosity<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ImplicitRadiosity")
            .field("dim", &self.g.dim())
            .finish_non_exhaustive()
    }
}

#[cfg(any(test, feature = "internals"))]
impl LinearOperator for ImplicitRadiosity<'_> {
    fn dim(&self) -> usize {
        self.g.dim()
    }

    /// `y = x - rho .* (g x)`.
    fn apply(&self, x: &[f64], y: &mut [f64]) {
        self.g.apply(x, y);
        y.par_iter_mut()
            .zip(self.rho.par_iter())
            .zip(x.par_iter())
            .for_each(|((yi, &r), &xi)| *yi = xi - r * *yi);
    }
}

/// Why a solve failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SolveError {
    /// A vector or matrix does not have the dimension the operator needs.
    #[error("dimension mismatch: expected {expected}, found {found}")]
    DimensionMismatch {
        /// The dimension required (the operator's `n`).
        expected: usize,
        /// The dimension supplied.
        found: usize,
    },
    /// The iteration limit was reached before the relative residual
    /// tolerance `rel_tol` was met.
    #[error(
        "not converged: relative residual {residual:e} still above rel_tol after {iterations} iterations"
    )]
    NotConverged {
        /// Iterations (operator applications in the Krylov loop) performed.
        iterations: usize,
        /// True relative residual `||b - A x|| / ||b||` of the returned `x`.
        residual: f64,
    },
    /// The LU factorisation found a zero or non-finite pivot, or the solve
    /// produced non-finite values (the matrix is singular to working precision).
    #[error("matrix is singular: zero or non-finite pivot at index {pivot}")]
    Singular {
        /// Index of the offending pivot (the smallest one when the solution
        /// overflowed).
        pivot: usize,
    },
    /// The right-hand side, the initial guess, the matrix or an operator
    /// output contained NaN or infinity.
    #[error("input or operator output contains NaN or infinity")]
    NonFinite,
    /// The observer of [`gmres_observed`] stopped the iteration.
    #[error("stopped by the caller after {iterations} iterations")]
    Stopped {
        /// Iterations performed.
        iterations: usize,
    },
    /// The solution is larger than the largest f64, although the system
    /// was solved (on a right-hand side scaled to 1).
    #[error(
        "the solution overflows double precision: its largest value is {largest:e} times the largest right-hand side value {scale:e}; scale the right-hand side (emission) down, the solution scales with it"
    )]
    Overflow {
        /// Largest |x_i| of the solution for the scaled right-hand side.
        largest: f64,
        /// The scale, max |b_i|.
        scale: f64,
    },
}

fn all_finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// Largest |v_i| (0 for an empty vector).
fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}

/// Multiplies a solution found for a right-hand side divided by `scale`
/// back by `scale`.
///
/// # Errors
/// [`SolveError::Overflow`] when the product is beyond the largest f64.
fn unscale(x: &mut [f64], scale: f64) -> Result<(), SolveError> {
    let largest = max_abs(x);
    x.iter_mut().for_each(|v| *v *= scale);
    if all_finite(x) {
        Ok(())
    } else {
        Err(SolveError::Overflow { largest, scale })
    }
}

#[cfg(test)]
pub(crate) mod test_util {
    //! Deterministic test matrices and independent (plain-loop) reference
    //! arithmetic, shared by the solver tests.
    use crate::matrix::DenseMatrix;

    /// A 64-bit LCG (Knuth's MMIX constants): deterministic, dependency-free.
    pub struct Lcg(pub u64);

    impl Lcg {
        /// Uniform in `[0, 1)`.
        pub fn next_f64(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }

        /// Uniform in `[-1, 1)`.
        pub fn sym(&mut self) -> f64 {
            2.0 * self.next_f64() - 1.0
        }
    }

    /// `A = I - 0.9 K / ||K||_inf` with `K` uniform in `[-1, 1)`: non-symmetric,
    /// `||A - I||_inf = 0.9`, so `||A^{-1}||_inf <= 10`.
    pub fn well_conditioned(n: usize, seed: u64) -> DenseMatrix {
        let mut rng = Lcg(seed);
        let k: Vec<f64> = (0..n * n).map(|_| rng.sym()).collect();
        let norm = (0..n)
            .map(|i| k[i * n..(i + 1) * n].iter().map(|v| v.abs()).sum::<f64>())
            .fold(0.0, f64::max);
        let mut a = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                a[i * n + j] = -0.9 * k[i * n + j] / norm;
            }
            a[i * n + i] += 1.0;
        }
        DenseMatrix::from_row_major(n, n, a)
    }

    /// `y = A x` by a plain double loop (independent of `DenseMatrix::matvec`).
    pub fn ref_matvec(a: &DenseMatrix, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; a.nrows()];
        for i in 0..a.nrows() {
            let mut s = 0.0;
            for j in 0..a.ncols() {
                s += a.get(i, j) * x[j];
            }
            y[i] = s;
        }
        y
    }

    pub fn norm(v: &[f64]) -> f64 {
        v.iter().map(|x| x * x).sum::<f64>().sqrt()
    }

    /// `||a - b|| / ||b||`.
    pub fn rel_diff(a: &[f64], b: &[f64]) -> f64 {
        let d: Vec<f64> = a.iter().zip(b).map(|(x, y)| x - y).collect();
        norm(&d) / norm(b)
    }

    /// `||b - A x|| / ||b||` by plain loops.
    pub fn ref_rel_residual(a: &DenseMatrix, x: &[f64], b: &[f64]) -> f64 {
        rel_diff(&ref_matvec(a, x), b)
    }

    /// A smooth, sign-changing "true" solution.
    pub fn x_true(n: usize) -> Vec<f64> {
        (0..n)
            .map(|i| 1.0 + (0.37 * i as f64).sin() + 0.01 * i as f64)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::test_util::*;
    use super::*;

    /// A radiosity-like pair: `G >= 0` with row sums `0.95`, `rho` in `[0.2, 0.9]`.
    fn radiosity_data(n: usize, seed: u64) -> (DenseMatrix, Vec<f64>) {
        let mut rng = Lcg(seed);
        let mut g = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                if i != j {
                    g[i * n + j] = rng.next_f64();
                }
            }
            let s: f64 = g[i * n..(i + 1) * n].iter().sum();
            for j in 0..n {
                g[i * n + j] *= 0.95 / s;
            }
        }
        let rho = (0..n).map(|_| 0.2 + 0.7 * rng.next_f64()).collect();
        (DenseMatrix::from_row_major(n, n, g), rho)
    }

    #[test]
    fn radiosity_to_dense_matches_definition() {
        let (g, rho) = radiosity_data(37, 5);
        let a = RadiosityOperator::new(&g, &rho).unwrap().to_dense();
        for i in 0..37 {
            for j in 0..37 {
                let delta = if i == j { 1.0 } else { 0.0 };
                assert_eq!(a.get(i, j), delta - rho[i] * g.get(i, j));
            }
        }
    }

    #[test]
    fn radiosity_apply_equals_to_dense_matvec() {
        let n = 123;
        let (g, rho) = radiosity_data(n, 11);
        let op = RadiosityOperator { gm: &g, rho: &rho };
        let x = x_true(n);
        let mut y_op = vec![0.0; n];
        op.apply(&x, &mut y_op);
        let mut y_dense = vec![0.0; n];
        op.to_dense().matvec(&x, &mut y_dense);
        assert!(rel_diff(&y_op, &y_dense) < 1e-14);
        // and both agree with the plain-loop definition x - rho .* (G x)
        let gx = ref_matvec(&g, &x);
        let y_ref: Vec<f64> = (0..n).map(|i| x[i] - rho[i] * gx[i]).collect();
        assert!(rel_diff(&y_op, &y_ref) < 1e-14);
    }

    #[test]
    fn radiosity_new_checks_dimensions() {
        let (g, rho) = radiosity_data(10, 1);
        assert!(matches!(
            RadiosityOperator::new(&g, &rho[..9]),
            Err(SolveError::DimensionMismatch {
                expected: 10,
                found: 9
            })
        ));
        let rect = DenseMatrix::zeros(3, 4);
        assert!(matches!(
            RadiosityOperator::new(&rect, &[0.5; 3]),
            Err(SolveError::DimensionMismatch {
                expected: 3,
                found: 4
            })
        ));
    }

    #[test]
    fn gmres_and_lu_agree_on_radiosity_system() {
        let n = 400;
        let (g, rho) = radiosity_data(n, 23);
        let op = RadiosityOperator::new(&g, &rho).unwrap();
        let a = op.to_dense();
        let xt = x_true(n);
        // b = x - rho .* (G x) by plain loops
        let gx = ref_matvec(&g, &xt);
        let b: Vec<f64> = (0..n).map(|i| xt[i] - rho[i] * gx[i]).collect();

        let mut x_gm = vec![0.0; n];
        let info = gmres(&op, &b, &mut x_gm, &GmresParams::default()).unwrap();
        assert!(info.residual <= 1e-12, "{info:?}");

        let lu = DenseLu::factor(&a).unwrap();
        let mut x_lu = b.clone();
        lu.solve_in_place(&mut x_lu).unwrap();

        assert!(rel_diff(&x_gm, &xt) < 1e-10);
        assert!(rel_diff(&x_lu, &xt) < 1e-10);
        assert!(rel_diff(&x_gm, &x_lu) < 1e-10);
    }

    #[test]
    fn gmres_and_lu_agree_on_manufactured_system() {
        let n = 300;
        let a = well_conditioned(n, 42);
        let xt = x_true(n);
        let b = ref_matvec(&a, &xt);
        let mut x_gm = vec![0.0; n];
        gmres(&a, &b, &mut x_gm, &GmresParams::default()).unwrap();
        let mut x_lu = b.clone();
        DenseLu::factor(&a)
            .unwrap()
            .solve_in_place(&mut x_lu)
            .unwrap();
        assert!(rel_diff(&x_gm, &x_lu) < 1e-10);
    }

    #[test]
    fn error_messages_are_informative() {
        let e = SolveError::NotConverged {
            iterations: 7,
            residual: 1e-3,
        };
        let s = e.to_string();
        assert!(s.contains("rel_tol") && s.contains('7'), "{s}");
    }
}
