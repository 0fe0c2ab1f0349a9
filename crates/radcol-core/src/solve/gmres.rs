//! Restarted GMRES(m) for the dense, non-symmetric radiosity system.
//!
//! Why GMRES: `I - diag(rho) G` is non-symmetric (so no CG) but its spectrum
//! is clustered around 1 (`||diag(rho) G|| < 1`), so GMRES converges in a few
//! dozen mat-vecs, needs only `y = A x` (matrix-free or GPU operators work),
//! and costs `O(n^2)` per iteration against `O(n^3)` for LU.
//!
//! Design: the Krylov basis (`restart + 1` vectors of length `n`) and the
//! small Hessenberg workspace are allocated once per call; the iteration
//! itself allocates nothing. Orthogonalisation is modified Gram–Schmidt with
//! one reorthogonalisation pass (cheap next to the mat-vec, and it keeps the
//! basis orthogonal to working precision); the least-squares problem is kept
//! triangular by Givens rotations, which also give the residual estimate for
//! free. Only the operator apply is parallel: for `n <= ~30000` the `O(n^2)`
//! mat-vec dominates the `O(n m)` vector work.

use super::{all_finite, Reduce, SolveError};
#[cfg(any(test, feature = "internals"))]
use super::LinearOperator;
use std::ops::ControlFlow;

/// Options for `gmres`.
#[derive(Clone, Debug)]
pub struct GmresParams {
    /// Stop when the relative residual `||b - A x|| / ||b||` is at most this.
    pub rel_tol: f64,
    /// Krylov subspace dimension `m` before a restart (clamped to `1..=n`).
    pub restart: usize,
    /// Maximum total number of iterations (operator applications inside the
    /// Krylov loop, summed over all restart cycles).
    pub max_iters: usize,
}

impl Default for GmresParams {
    fn default() -> Self {
        Self {
            rel_tol: 1e-12,
            restart: 60,
            max_iters: 2000,
        }
    }
}

/// What a successful [`gmres`] call did.
#[derive(Clone, Debug)]
pub struct GmresInfo {
    /// Total iterations (Krylov-loop operator applications) over all cycles.
    pub iterations: usize,
    /// Number of restarts: restart cycles begun after the first one.
    #[cfg_attr(
        not(any(test, feature = "internals")),
        allow(dead_code, reason = "read by the solver tests and benches")
    )]
    pub restarts: usize,
    /// True relative residual `||b - A x|| / ||b||` of the returned `x`,
    /// recomputed with one extra operator apply (not the Arnoldi estimate).
    pub residual: f64,
    /// `||A|| ||x|| / ||b||`, with `||A||` the largest `||A v||` seen on the
    /// unit Krylov vectors: a lower bound of the condition number, and the
    /// factor by which rounding in `b - A x` exceeds `ε ||b||`.
    pub growth: f64,
    /// True when `rel_tol` was below what f64 can deliver for this system and
    /// the iteration stopped at the rounding floor instead
    /// (`ROUNDING_FLOOR` `ε (||A|| ||x|| + ||b||)`, a backward error of a
    /// few dozen ulps).
    pub at_rounding_floor: bool,
}

/// The residual `b - A x` cannot be computed more accurately than about
/// `ε ||A|| ||x||`: when `||x|| ≫ ||b||` (ρ → 1 in a closed room, where
/// `||x|| / ||b|| ≈ 1/(1 - ρ)`), a tolerance relative to `||b||` alone is out
/// of reach and restarted GMRES stagnates there (box room at ρ = 0.99999: true
/// residual 1.5e-11 against `--tol` 1e-12 after 2000 iterations). A residual
/// below this many ulps of `||A|| ||x|| + ||b||` counts as converged.
pub const ROUNDING_FLOOR: f64 = 64.0;

/// Restarted GMRES(m) with modified Gram–Schmidt (plus one
/// reorthogonalisation pass) and Givens rotations.
///
/// `x` holds the initial guess on entry and the solution on exit (also on
/// [`SolveError::NotConverged`], where it is the best iterate found).
/// `b = 0` gives `x = 0` with 0 iterations.
///
/// The iteration runs on `b / s` and `x / s`, `s = max |b_i|`, so that any
/// representable `b` (1e-300 or 1e300) gives the same relative answer; the
/// solution is multiplied back at the end.
///
/// Convergence is declared only on the *true* residual `||b - A x||`,
/// recomputed at the start of every cycle: `Ok(info)` guarantees
/// `info.residual <= params.rel_tol`, or `info.at_rounding_floor` (see
/// `ROUNDING_FLOOR`).
///
/// # Errors
/// * [`SolveError::DimensionMismatch`] if `b` or `x` is not of length `op.dim()`;
/// * [`SolveError::NonFinite`] if `b`, the initial `x` or an operator output
///   contains NaN or infinity;
/// * [`SolveError::NotConverged`] if `params.max_iters` iterations did not
///   reach `params.rel_tol` (with the true relative residual of `x`);
/// * [`SolveError::Overflow`] if the solution is beyond the largest f64.
#[cfg(any(test, feature = "internals"))]
pub fn gmres(
    op: &dyn LinearOperator,
    b: &[f64],
    x: &mut [f64],
    params: &GmresParams,
) -> Result<GmresInfo, SolveError> {
    gmres_observed(op, b, x, params, &mut |_, _| ControlFlow::Continue(()))
}

/// [`gmres`], calling `observe(iterations, residual)` after every iteration
/// with the Arnoldi estimate of the relative residual (the true one is
/// checked at each restart, as in [`gmres`]); `ControlFlow::Break` stops the
/// iteration with [`SolveError::Stopped`], `x` holding the start of the
/// cycle (progress bars, cancellation).
#[cfg(any(test, feature = "internals"))]
pub fn gmres_observed(
    op: &dyn LinearOperator,
    b: &[f64],
    x: &mut [f64],
    params: &GmresParams,
    observe: &mut dyn FnMut(usize, f64) -> ControlFlow<()>,
) -> Result<GmresInfo, SolveError> {
    let mut krylov = match Krylov::start(op.dim(), b, x, params, &super::Alone)? {
        Started::Running(k) => k,
        Started::Solved(info) => {
            x.fill(0.0);
            return Ok(info);
        }
    };
    let info = loop {
        let (v, w) = krylov.product();
        op.apply(v, w);
        if let Some(done) = krylov.advance(observe) {
            break done;
        }
    };
    krylov.finish(x)?;
    info
}

/// What [`Krylov::start`] found: an iteration to run, or b = 0 (x = 0).
pub(super) enum Started<'p> {
    Running(Box<Krylov<'p>>),
    Solved(GmresInfo),
}

/// One system's restarted GMRES(m), advanced one operator product at a
/// time so that a driver can compute the products of several systems
/// together ([`super::gmres_radiosity_reduced`]) or one by one ([`gmres_observed`]):
/// [`Krylov::product`] lends the vector to multiply and the place for its
/// product, [`Krylov::advance`] takes the product and says whether the
/// iteration is over.
///
/// The iteration runs on a right-hand side of order 1 (`b / s`, `x / s`,
/// `s = max |b_i|`); [`Krylov::finish`] scales the solution back.
///
/// Workspace, allocated once: basis V (m+1 vectors, contiguous), the
/// Hessenberg matrix H ((m+1) × m, column j at h[j*(m+1)..]), the Givens
/// rotations, the rotated right-hand side g and the residual scratch r.
pub(super) struct Krylov<'p> {
    params: &'p GmresParams,
    /// Sums and maxima over the processes holding the other rows.
    reduce: &'p dyn Reduce,
    scale: f64,
    b: Vec<f64>,
    x: Vec<f64>,
    b_norm: f64,
    tol: f64,
    m: usize,
    basis: Vec<f64>,
    h: Vec<f64>,
    cs: Vec<f64>,
    sn: Vec<f64>,
    g: Vec<f64>,
    r: Vec<f64>,
    iterations: usize,
    cycles: usize,
    /// The largest ||A v|| over unit Krylov vectors v: a lower bound of ||A||.
    a_norm: f64,
    /// The rounding floor of this cycle (see `ROUNDING_FLOOR`).
    floor: f64,
    /// The Arnoldi step awaiting A v_j, or None while the cycle's true
    /// residual awaits A x.
    step: Option<usize>,
    /// Columns of H in the least-squares problem.
    k: usize,
}

impl<'p> Krylov<'p> {
    /// Checks `b` and the initial `x` against the dimension `n` (of this
    /// process's rows: all of them with [`Alone`]) and for finite values;
    /// the first product asked for is A x. Dot products and maxima are
    /// taken over every process's rows through `reduce`.
    pub(super) fn start(
        n: usize,
        b: &[f64],
        x: &[f64],
        params: &'p GmresParams,
        reduce: &'p dyn Reduce,
    ) -> Result<Started<'p>, SolveError> {
        for len in [b.len(), x.len()] {
            if len != n {
                return Err(SolveError::DimensionMismatch {
                    expected: n,
                    found: len,
                });
            }
        }
        if reduce.any(!all_finite(b) || !all_finite(x)) {
            return Err(SolveError::NonFinite);
        }
        let scale = reduce.max_abs(b);
        if scale == 0.0 {
            return Ok(Started::Solved(GmresInfo {
                iterations: 0,
                restarts: 0,
                residual: 0.0,
                growth: 0.0,
                at_rounding_floor: false,
            }));
        }
        let b: Vec<f64> = b.iter().map(|v| v / scale).collect();
        let b_norm = reduce.dot(&b, &b).sqrt();
        let m = params.restart.clamp(1, reduce.total(n));
        Ok(Started::Running(Box::new(Self {
            params,
            reduce,
            scale,
            x: x.iter().map(|v| v / scale).collect(),
            b,
            b_norm,
            tol: params.rel_tol * b_norm,
            m,
            basis: vec![0.0; (m + 1) * n],
            h: vec![0.0; (m + 1) * m],
            cs: vec![0.0; m],
            sn: vec![0.0; m],
            g: vec![0.0; m + 1],
            r: vec![0.0; n],
            iterations: 0,
            cycles: 0,
            a_norm: 0.0,
            floor: 0.0,
            step: None,
            k: 0,
        })))
    }

    /// The vector to multiply by A and the place for its product.
    pub(super) fn product(&mut self) -> (&[f64], &mut [f64]) {
        let n = self.r.len();
        match self.step {
            None => (&self.x, &mut self.r),
            Some(j) => {
                let (done, rest) = self.basis.split_at_mut((j + 1) * n);
                (&done[j * n..], &mut rest[..n])
            }
        }
    }

    /// Takes the product [`Krylov::product`] asked for; `Some` with the
    /// outcome when the iteration is over, `None` when it needs another.
    /// `observe(iterations, estimate)` is called after every Arnoldi step.
    pub(super) fn advance(
        &mut self,
        observe: &mut dyn FnMut(usize, f64) -> ControlFlow<()>,
    ) -> Option<Result<GmresInfo, SolveError>> {
        match self.step {
            None => self.begin_cycle(),
            Some(j) => self.arnoldi(j, observe),
        }
    }

    /// Writes the solution, scaled back, into `x` (the best iterate, or the
    /// start of the cycle, when the iteration failed or was stopped).
    ///
    /// # Errors
    /// [`SolveError::Overflow`] when the solution is beyond the largest f64.
    pub(super) fn finish(&self, x: &mut [f64]) -> Result<(), SolveError> {
        x.copy_from_slice(&self.x);
        let largest = self.reduce.max_abs(x);
        x.iter_mut().for_each(|v| *v *= self.scale);
        if self.reduce.any(!all_finite(x)) {
            return Err(SolveError::Overflow {
                largest,
                scale: self.scale,
            });
        }
        Ok(())
    }

    /// r holds A x: the cycle's true residual decides convergence, or a
    /// new cycle starts from v_0 = r / β.
    fn begin_cycle(&mut self) -> Option<Result<GmresInfo, SolveError>> {
        if self.reduce.any(!all_finite(&self.r)) {
            return Some(Err(SolveError::NonFinite));
        }
        for (ri, &bi) in self.r.iter_mut().zip(&self.b) {
            *ri = bi - *ri;
        }
        let beta = self.reduce.dot(&self.r, &self.r).sqrt();
        let x_norm = self.reduce.dot(&self.x, &self.x).sqrt();
        self.floor = ROUNDING_FLOOR * f64::EPSILON * (self.a_norm * x_norm + self.b_norm);
        if beta <= self.tol || beta <= self.floor {
            return Some(Ok(GmresInfo {
                iterations: self.iterations,
                restarts: self.cycles.saturating_sub(1),
                residual: beta / self.b_norm,
                growth: self.a_norm * x_norm / self.b_norm,
                at_rounding_floor: beta > self.tol,
            }));
        }
        if self.iterations >= self.params.max_iters {
            return Some(Err(SolveError::NotConverged {
                iterations: self.iterations,
                residual: beta / self.b_norm,
            }));
        }
        self.cycles += 1;
        // v_0 = r / beta, g = beta e_1.
        for (v, &ri) in self.basis.iter_mut().zip(&self.r) {
            *v = ri / beta;
        }
        self.g.fill(0.0);
        self.g[0] = beta;
        self.k = 0;
        self.iterations += 1;
        self.step = Some(0);
        None
    }

    /// basis[j+1] holds A v_j: Arnoldi step j, then the next step's product,
    /// or the cycle's update of x and the next cycle's A x.
    fn arnoldi(
        &mut self,
        j: usize,
        observe: &mut dyn FnMut(usize, f64) -> ControlFlow<()>,
    ) -> Option<Result<GmresInfo, SolveError>> {
        let (n, ld) = (self.r.len(), self.m + 1);
        let (done, rest) = self.basis.split_at_mut((j + 1) * n);
        let w = &mut rest[..n];
        if self.reduce.any(!all_finite(w)) {
            return Some(Err(SolveError::NonFinite));
        }
        self.a_norm = self.a_norm.max(self.reduce.dot(w, w).sqrt());
        let col = &mut self.h[j * ld..(j + 1) * ld];
        let h_next = orthogonalise(done, w, col, j, self.reduce);
        // A v_j in span(v_0..v_{j-1}) adds nothing: the triangular system
        // would be singular, so column j is dropped and the cycle ends.
        let mut more = rotate(col, &mut self.cs, &mut self.sn, &mut self.g, j);
        if more {
            self.k = j + 1;
            let stop = observe(self.iterations, self.g[j + 1].abs() / self.b_norm).is_break();
            if self.reduce.any(stop) {
                return Some(Err(SolveError::Stopped {
                    iterations: self.iterations,
                }));
            }
            more = self.g[j + 1].abs() > self.tol.max(self.floor)
                && h_next != 0.0
                && j + 1 < self.m
                && self.iterations < self.params.max_iters;
        }
        if more {
            self.iterations += 1;
            self.step = Some(j + 1);
        } else {
            update(&self.h, ld, &mut self.g, self.k, &self.basis, &mut self.x);
            self.step = None;
        }
        None
    }
}

/// Column j of the Hessenberg matrix: w (= A v_j) is orthogonalised against
/// v_0..v_j (`done`, contiguous) by modified Gram–Schmidt and one
/// reorthogonalisation pass, then normalised; `col` receives the
/// coefficients and h_{j+1,j}, which is returned. Each dot product is
/// reduced over the processes (one reduction of a number each: on the
/// 2-core machine about 0.3 µs, next to milliseconds of product).
fn orthogonalise(
    done: &[f64],
    w: &mut [f64],
    col: &mut [f64],
    j: usize,
    reduce: &dyn Reduce,
) -> f64 {
    let n = w.len();
    col.fill(0.0);
    for _pass in 0..2 {
        for (i, v) in done.chunks_exact(n).enumerate() {
            let hij = reduce.dot(w, v);
            for (wk, &vk) in w.iter_mut().zip(v) {
                *wk -= hij * vk;
            }
            col[i] += hij;
        }
    }
    let h_next = reduce.dot(w, w).sqrt();
    col[j + 1] = h_next;
    // A zero h_next is a "happy breakdown": the Krylov space is
    // invariant and the LS solution is exact. Do not divide.
    if h_next > 0.0 {
        for wk in w.iter_mut() {
            *wk /= h_next;
        }
    }
    h_next
}

/// Applies the previous Givens rotations to column j, then a new rotation
/// that annihilates col[j+1], updating the rotated right-hand side g.
/// False when the column is zero after the previous rotations.
fn rotate(col: &mut [f64], cs: &mut [f64], sn: &mut [f64], g: &mut [f64], j: usize) -> bool {
    for i in 0..j {
        let (a, c) = (col[i], col[i + 1]);
        col[i] = cs[i] * a + sn[i] * c;
        col[i + 1] = -sn[i] * a + cs[i] * c;
    }
    let (a, c) = (col[j], col[j + 1]);
    let rho = a.hypot(c);
    if rho == 0.0 {
        return false;
    }
    cs[j] = a / rho;
    sn[j] = c / rho;
    col[j] = rho;
    col[j + 1] = 0.0;
    g[j + 1] = -sn[j] * g[j];
    g[j] *= cs[j];
    true
}

/// Solves the k × k upper-triangular system H y = g (y stored in g), then
/// x += V_k y.
fn update(h: &[f64], ld: usize, g: &mut [f64], k: usize, basis: &[f64], x: &mut [f64]) {
    let n = x.len();
    for i in (0..k).rev() {
        let mut s = g[i];
        for l in i + 1..k {
            s -= h[l * ld + i] * g[l];
        }
        g[i] = s / h[i * ld + i];
    }
    for (i, v) in basis.chunks_exact(n).take(k).enumerate() {
        let yi = g[i];
        for (xk, &vk) in x.iter_mut().zip(v) {
            *xk += yi * vk;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_util::*;
    use super::*;
    use crate::matrix::DenseMatrix;

    /// Strongly non-normal and non-symmetric: `I + 0.6 S + 0.2 K / ||K||_inf`
    /// with `S` the upper shift. GMRES(5) needs many cycles.
    fn nonnormal(n: usize) -> DenseMatrix {
        let mut rng = Lcg(7);
        let k: Vec<f64> = (0..n * n).map(|_| rng.sym()).collect();
        let norm = (0..n)
            .map(|i| k[i * n..(i + 1) * n].iter().map(|v| v.abs()).sum::<f64>())
            .fold(0.0, f64::max);
        let mut a = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                a[i * n + j] = 0.2 * k[i * n + j] / norm;
            }
            a[i * n + i] += 1.0;
            if i + 1 < n {
                a[i * n + i + 1] += 0.6;
            }
        }
        DenseMatrix::from_row_major(n, n, a)
    }

    /// The observer sees every iteration with a non-increasing residual
    /// estimate (within a restart cycle), the same answer as `gmres`, and
    /// stops the iteration when it breaks.
    #[test]
    fn observer_sees_each_iteration_and_can_stop() {
        let n = 120;
        let a = nonnormal(n);
        let b = ref_matvec(&a, &x_true(n));
        let params = GmresParams {
            restart: 200,
            ..GmresParams::default()
        };
        let mut seen = Vec::new();
        let mut x = vec![0.0; n];
        let info = gmres_observed(&a, &b, &mut x, &params, &mut |i, r| {
            seen.push((i, r));
            ControlFlow::Continue(())
        })
        .unwrap();
        let mut y = vec![0.0; n];
        let plain = gmres(&a, &b, &mut y, &params).unwrap();
        assert_eq!((info.iterations, x), (plain.iterations, y));
        assert_eq!(seen.len(), info.iterations);
        assert!(seen
            .windows(2)
            .all(|w| w[1].0 == w[0].0 + 1 && w[1].1 <= w[0].1));
        let mut x = vec![0.0; n];
        let stopped = gmres_observed(&a, &b, &mut x, &params, &mut |i, _| {
            if i == 3 {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        });
        assert!(matches!(
            stopped,
            Err(SolveError::Stopped { iterations: 3 })
        ));
    }

    #[test]
    fn manufactured_solution_recovered() {
        let n = 300;
        let a = well_conditioned(n, 42);
        let xt = x_true(n);
        let b = ref_matvec(&a, &xt);
        let params = GmresParams::default();
        let mut x = vec![0.0; n];
        let info = gmres(&a, &b, &mut x, &params).unwrap();
        assert!(info.residual <= params.rel_tol, "{info:?}");
        // independent residual check (plain loops), small slack for rounding
        assert!(ref_rel_residual(&a, &x, &b) <= 1.05 * params.rel_tol);
        assert!(rel_diff(&x, &xt) < 1e-10, "{}", rel_diff(&x, &xt));
        assert!(info.iterations > 0 && info.iterations <= params.restart);
        assert_eq!(info.restarts, 0);
    }

    #[test]
    fn restarted_nonnormal_converges() {
        let n = 200;
        let a = nonnormal(n);
        let xt = x_true(n);
        let b = ref_matvec(&a, &xt);
        let params = GmresParams {
            rel_tol: 1e-12,
            restart: 5,
            max_iters: 2000,
        };
        let mut x = vec![0.0; n];
        let info = gmres(&a, &b, &mut x, &params).unwrap();
        assert!(info.iterations > params.restart, "{info:?}");
        assert!(info.restarts >= 1, "{info:?}");
        assert!(
            info.restarts >= (info.iterations - 1) / params.restart,
            "{info:?}"
        );
        assert!(info.residual <= params.rel_tol, "{info:?}");
        assert!(ref_rel_residual(&a, &x, &b) <= 1.05 * params.rel_tol);
        assert!(rel_diff(&x, &xt) < 1e-10, "{}", rel_diff(&x, &xt));
    }

    #[test]
    fn too_few_iterations_not_converged() {
        let n = 200;
        let a = nonnormal(n);
        let b = ref_matvec(&a, &x_true(n));
        let params = GmresParams {
            rel_tol: 1e-12,
            restart: 5,
            max_iters: 7,
        };
        let mut x = vec![0.0; n];
        match gmres(&a, &b, &mut x, &params) {
            Err(SolveError::NotConverged {
                iterations,
                residual,
            }) => {
                assert_eq!(iterations, 7);
                assert!(residual.is_finite() && residual > params.rel_tol);
                assert!(residual < 1.0, "7 iterations should reduce the residual");
                // the reported residual is the true one of the returned x
                let r = ref_rel_residual(&a, &x, &b);
                assert!(
                    (r - residual).abs() <= 1e-12 * r.max(1.0),
                    "{r} vs {residual}"
                );
            }
            other => panic!("expected NotConverged, got {other:?}"),
        }
        // max_iters = 0: no iteration, the residual of the initial guess
        let mut x = vec![0.0; n];
        let p0 = GmresParams {
            max_iters: 0,
            ..params
        };
        assert!(matches!(
            gmres(&a, &b, &mut x, &p0),
            Err(SolveError::NotConverged { iterations: 0, residual }) if residual == 1.0
        ));
    }

    #[test]
    fn zero_rhs_gives_zero_solution() {
        let a = well_conditioned(20, 1);
        let mut x = vec![3.0; 20];
        let info = gmres(&a, &[0.0; 20], &mut x, &GmresParams::default()).unwrap();
        assert_eq!(info.iterations, 0);
        assert_eq!(info.restarts, 0);
        assert_eq!(info.residual, 0.0);
        assert!(x.iter().all(|&v| v == 0.0));
    }

    #[test]
    fn exact_initial_guess_needs_no_iterations() {
        let a = DenseMatrix::from_row_major(2, 2, vec![2.0, 1.0, 0.0, 4.0]);
        let mut x = vec![1.0, 0.5];
        let info = gmres(&a, &[2.5, 2.0], &mut x, &GmresParams::default()).unwrap();
        assert_eq!(info.iterations, 0);
        assert_eq!(x, vec![1.0, 0.5]);
    }

    #[test]
    fn happy_breakdown_is_exact() {
        // diag with 3 distinct eigenvalues: the Krylov space has dimension 3.
        let n = 30;
        let mut d = vec![0.0; n * n];
        for i in 0..n {
            d[i * n + i] = [1.0, 2.0, 4.0][i % 3];
        }
        let a = DenseMatrix::from_row_major(n, n, d);
        let b = vec![1.0; n];
        let mut x = vec![0.0; n];
        let info = gmres(&a, &b, &mut x, &GmresParams::default()).unwrap();
        assert!(info.iterations <= 3, "{info:?}");
        for i in 0..n {
            let expect = 1.0 / [1.0, 2.0, 4.0][i % 3];
            crate::assert_close!(x[i], expect, 1e-13);
        }
        // identity: one iteration
        let mut id = vec![0.0; n * n];
        for i in 0..n {
            id[i * n + i] = 1.0;
        }
        let id = DenseMatrix::from_row_major(n, n, id);
        let mut x = vec![0.0; n];
        let info = gmres(&id, &b, &mut x, &GmresParams::default()).unwrap();
        assert_eq!(info.iterations, 1);
        assert!(x.iter().all(|&v| (v - 1.0).abs() < 1e-15));
    }

    #[test]
    fn restart_larger_than_n_and_tiny_systems() {
        let a = DenseMatrix::from_row_major(1, 1, vec![4.0]);
        let mut x = vec![0.0];
        let info = gmres(&a, &[2.0], &mut x, &GmresParams::default()).unwrap();
        assert_eq!(x, vec![0.5]);
        assert_eq!(info.iterations, 1);
        // restart = 0 is clamped to 1 (steepest-descent-like GMRES(1))
        let a = well_conditioned(10, 3);
        let xt = x_true(10);
        let b = ref_matvec(&a, &xt);
        let mut x = vec![0.0; 10];
        let p = GmresParams {
            restart: 0,
            ..GmresParams::default()
        };
        gmres(&a, &b, &mut x, &p).unwrap();
        assert!(rel_diff(&x, &xt) < 1e-10);
        // n = 0
        let e = DenseMatrix::zeros(0, 0);
        let info = gmres(&e, &[], &mut [], &GmresParams::default()).unwrap();
        assert_eq!(info.iterations, 0);
    }

    #[test]
    fn dimension_mismatch() {
        let a = well_conditioned(10, 1);
        let mut x = vec![0.0; 10];
        assert!(matches!(
            gmres(&a, &[1.0; 9], &mut x, &GmresParams::default()),
            Err(SolveError::DimensionMismatch {
                expected: 10,
                found: 9
            })
        ));
        let mut x = vec![0.0; 11];
        assert!(matches!(
            gmres(&a, &[1.0; 10], &mut x, &GmresParams::default()),
            Err(SolveError::DimensionMismatch {
                expected: 10,
                found: 11
            })
        ));
    }

    #[test]
    fn nan_in_b_is_non_finite() {
        let a = well_conditioned(10, 1);
        let mut b = vec![1.0; 10];
        b[3] = f64::NAN;
        let mut x = vec![0.0; 10];
        assert!(matches!(
            gmres(&a, &b, &mut x, &GmresParams::default()),
            Err(SolveError::NonFinite)
        ));
        b[3] = f64::INFINITY;
        assert!(matches!(
            gmres(&a, &b, &mut x, &GmresParams::default()),
            Err(SolveError::NonFinite)
        ));
    }

    #[test]
    fn nan_operator_output_is_non_finite() {
        struct Bad;
        impl LinearOperator for Bad {
            fn dim(&self) -> usize {
                4
            }
            fn apply(&self, x: &[f64], y: &mut [f64]) {
                y.copy_from_slice(x);
                // finite on the zero initial guess, NaN once x != 0
                if x.iter().any(|&v| v != 0.0) {
                    y[2] = f64::NAN;
                }
            }
        }
        let mut x = vec![0.0; 4];
        assert!(matches!(
            gmres(&Bad, &[1.0; 4], &mut x, &GmresParams::default()),
            Err(SolveError::NonFinite)
        ));
    }

    /// `I - ρ P` with P row-stochastic (a closed room's G): the constant
    /// vector is an eigenvector with eigenvalue 1 - ρ.
    fn closed_room(n: usize, rho: f64) -> DenseMatrix {
        let mut rng = Lcg(11);
        let mut a = vec![0.0; n * n];
        for i in 0..n {
            let row: Vec<f64> = (0..n).map(|_| rng.next_f64()).collect();
            let sum: f64 = row.iter().sum();
            for j in 0..n {
                a[i * n + j] = -rho * row[j] / sum;
            }
            a[i * n + i] += 1.0;
        }
        DenseMatrix::from_row_major(n, n, a)
    }

    #[test]
    fn tiny_and_huge_right_hand_sides_give_the_same_relative_answer() {
        let n = 50;
        let a = well_conditioned(n, 5);
        let b1 = ref_matvec(&a, &x_true(n));
        let mut x1 = vec![0.0; n];
        gmres(&a, &b1, &mut x1, &GmresParams::default()).unwrap();
        for scale in [1e-300, 1e-160, 1e160, 1e300] {
            let b: Vec<f64> = b1.iter().map(|v| v * scale).collect();
            let mut x = vec![0.0; n];
            let info = gmres(&a, &b, &mut x, &GmresParams::default()).unwrap();
            assert!(info.residual <= 1e-12, "{scale}: {info:?}");
            let back: Vec<f64> = x.iter().map(|v| v / scale).collect();
            assert!(
                rel_diff(&back, &x1) < 1e-13,
                "{scale}: {}",
                rel_diff(&back, &x1)
            );
        }
        // The solution of I - 0.5 P for b = 1e308 is 2e308: beyond f64.
        let a = closed_room(n, 0.5);
        let mut x = vec![0.0; n];
        let e = gmres(&a, &[1e308; 50], &mut x, &GmresParams::default()).unwrap_err();
        assert!(
            matches!(e, SolveError::Overflow { largest, scale } if (largest - 2.0).abs() < 1e-9 && scale == 1e308),
            "{e:?}"
        );
    }

    #[test]
    fn near_singular_closed_rooms_stop_at_the_rounding_floor() {
        // At ρ = 0.999999 the residual cannot be computed below about
        // ε ||A|| ||x|| = ε 1e6 ||b|| > 1e-12 ||b||: GMRES used to stagnate
        // there until max_iters and report "not converged".
        let n = 200;
        for rho in [0.9, 0.9999, 0.999999] {
            let a = closed_room(n, rho);
            let b: Vec<f64> = (0..n).map(|i| 1.0 + 0.5 * (i as f64).sin()).collect();
            let mut x = vec![0.0; n];
            let info = gmres(&a, &b, &mut x, &GmresParams::default()).unwrap();
            assert!(info.iterations < 100, "{rho}: {info:?}");
            assert!(rho < 0.9999 || info.at_rounding_floor, "{rho}: {info:?}");
            let kappa = 1.0 / (1.0 - rho);
            // ‖A‖‖x‖/‖b‖ is at least ~1/(1 - ρ) · (mean of b / rms of b).
            assert!(
                info.growth > 0.5 * kappa && info.growth < 4.0 * kappa,
                "{rho}: {info:?}"
            );
            assert_eq!(info.at_rounding_floor, info.residual > 1e-12, "{info:?}");
            // The tolerance met, or a backward error of a few dozen ulps;
            // the forward error within κ of it.
            let r = ref_rel_residual(&a, &x, &b);
            let floor = ROUNDING_FLOOR * f64::EPSILON * (info.growth + 1.0);
            assert!(r <= 1.01 * floor.max(1e-12), "{rho}: {r}");
            let lu = crate::solve::DenseLu::factor(&a).unwrap();
            let mut y = b.clone();
            lu.solve_in_place(&mut y).unwrap();
            assert!(
                rel_diff(&x, &y) < 1e-12 * kappa,
                "{rho}: {}",
                rel_diff(&x, &y)
            );
        }
    }
}
