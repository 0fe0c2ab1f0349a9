//! GMRES on several radiosity systems that share one geometric operator:
//! the colour channels of a scene, (I - diag(ρ_c) G) x_c = b_c. Each
//! iteration multiplies G once by the Krylov vectors of every system still
//! running ([`LinearOperator::apply_many`]), so the dense matrix, or the
//! compressed operator's blocks, are read from memory once per iteration
//! instead of once per channel: the solve stage of an RGB scene and every
//! relight cost about one channel's memory traffic.

use super::gmres::{Krylov, Started};
use super::{GmresInfo, GmresParams, LinearOperator, Reduce, SolveError};
use rayon::prelude::*;
use std::ops::ControlFlow;

/// One system (I - diag(ρ) G) x = b of [`gmres_radiosity`]: its
/// reflectance at the nodes, right-hand side, and the initial guess on entry
/// and solution on exit.
#[derive(Debug)]
pub struct RadiositySystem<'a> {
    /// ρ at each collocation point (length `G.dim()`).
    pub rho: &'a [f64],
    /// The right-hand side (emission at the nodes).
    pub b: &'a [f64],
    /// Initial guess on entry; solution on exit, as in `gmres`.
    pub x: &'a mut [f64],
}

/// Restarted GMRES on every system (I - diag(ρ_c) g) x_c = b_c at once.
///
/// Each system runs exactly the iteration [`super::gmres_observed`] runs on
/// [`super::ImplicitRadiosity`]`(g, ρ_c)` (same iterates, same
/// [`GmresInfo`]) when `g.apply_many` gives the products `g.apply` would;
/// only the products are shared. A system leaves the batch when it
/// converges or fails; `observe(system, iterations, estimate)` is called
/// after each of its Arnoldi steps, and `ControlFlow::Break` stops that
/// system with [`SolveError::Stopped`].
///
/// One result per system, in order. A system's `rho` of the wrong length is
/// its own [`SolveError::DimensionMismatch`].
#[cfg(any(test, feature = "internals"))]
pub fn gmres_radiosity(
    g: &dyn LinearOperator,
    systems: &mut [RadiositySystem<'_>],
    params: &GmresParams,
    observe: &mut dyn FnMut(usize, usize, f64) -> ControlFlow<()>,
) -> Vec<Result<GmresInfo, SolveError>> {
    gmres_radiosity_reduced(g, systems, params, &super::Alone, observe)
}

/// [`gmres_radiosity`] on systems whose rows are spread over processes:
/// `g` maps this process's rows of x to its rows of G x (gathering the
/// rest itself), each system holds this process's rows of ρ, b and x, and
/// `reduce` sums and maximises over the processes, which all call this
/// together. Every process then runs the same iteration and reaches the
/// same decisions.
pub fn gmres_radiosity_reduced(
    g: &dyn LinearOperator,
    systems: &mut [RadiositySystem<'_>],
    params: &GmresParams,
    reduce: &dyn Reduce,
    observe: &mut dyn FnMut(usize, usize, f64) -> ControlFlow<()>,
) -> Vec<Result<GmresInfo, SolveError>> {
    let n = g.dim();
    let mut results: Vec<Option<Result<GmresInfo, SolveError>>> = Vec::new();
    let mut running: Vec<(usize, Box<Krylov<'_>>)> = Vec::new();
    for (c, s) in systems.iter_mut().enumerate() {
        let started = if s.rho.len() == n {
            Krylov::start(n, s.b, s.x, params, reduce)
        } else {
            Err(SolveError::DimensionMismatch {
                expected: n,
                found: s.rho.len(),
            })
        };
        results.push(match started {
            Ok(Started::Running(k)) => {
                running.push((c, k));
                None
            }
            Ok(Started::Solved(info)) => {
                s.x.fill(0.0);
                Some(Ok(info))
            }
            Err(e) => Some(Err(e)),
        });
    }
    while !running.is_empty() {
        multiply(g, systems, &mut running);
        running.retain_mut(|(c, k)| {
            let Some(outcome) = k.advance(&mut |i, r| observe(*c, i, r)) else {
                return true;
            };
            results[*c] = Some(k.finish(systems[*c].x).and(outcome));
            false
        });
    }
    results
        .into_iter()
        .map(|r| r.expect("every system ends"))
        .collect()
}

/// The products every running system asks for: w = v - ρ .* (g v), the
/// g v of all of them in one [`LinearOperator::apply_many`].
fn multiply(
    g: &dyn LinearOperator,
    systems: &[RadiositySystem<'_>],
    running: &mut [(usize, Box<Krylov<'_>>)],
) {
    let (mut vs, mut ws, mut rhos) = (Vec::new(), Vec::new(), Vec::new());
    for (c, k) in running.iter_mut() {
        let (v, w) = k.product();
        vs.push(v);
        ws.push(w);
        rhos.push(systems[*c].rho);
    }
    g.apply_many(&vs, &mut ws);
    for ((v, w), rho) in vs.iter().zip(ws.iter_mut()).zip(rhos) {
        w.par_iter_mut()
            .zip(rho.par_iter())
            .zip(v.par_iter())
            .for_each(|((wi, &r), &vi)| *wi = vi - r * *wi);
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_util::*;
    use super::super::{gmres_observed, ImplicitRadiosity};
    use super::*;
    use crate::matrix::DenseMatrix;

    /// A radiosity-like G: non-negative, row sums below 1, non-symmetric.
    fn geometric(n: usize, seed: u64) -> DenseMatrix {
        let mut rng = Lcg(seed);
        let mut a: Vec<f64> = (0..n * n).map(|_| rng.sym().abs()).collect();
        for row in a.chunks_exact_mut(n) {
            let s: f64 = row.iter().sum();
            row.iter_mut().for_each(|v| *v *= 0.9 / s);
        }
        DenseMatrix::from_row_major(n, n, a)
    }

    /// Counts the calls of apply and apply_many of the operator it wraps.
    struct Counting<'a>(&'a DenseMatrix, std::sync::atomic::AtomicUsize);

    impl LinearOperator for Counting<'_> {
        fn dim(&self) -> usize {
            self.0.nrows()
        }
        fn apply(&self, x: &[f64], y: &mut [f64]) {
            self.1.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            self.0.apply(x, y);
        }
        fn apply_many(&self, xs: &[&[f64]], ys: &mut [&mut [f64]]) {
            self.1.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            self.0.apply_many(xs, ys);
        }
    }

    /// Three channels in lockstep give, to the bit, what three separate
    /// GMRES runs on I - diag(ρ_c) G give (solutions, iterations, residual
    /// estimates seen), with one pass over G per lockstep iteration: as many
    /// passes as the slowest channel needs, not the sum.
    #[test]
    fn lockstep_channels_equal_separate_solves() {
        let n = 150;
        let gm = geometric(n, 3);
        let mut rng = Lcg(11);
        let rhos: Vec<Vec<f64>> = [0.3, 0.6, 0.95]
            .iter()
            .map(|&r| (0..n).map(|_| r * (0.5 + 0.5 * rng.sym().abs())).collect())
            .collect();
        let bs: Vec<Vec<f64>> = (0..3)
            .map(|c| {
                (0..n)
                    .map(|i| if i % (c + 2) == 0 { 1.0 } else { 0.0 })
                    .collect()
            })
            .collect();
        let params = GmresParams {
            restart: 3,
            ..GmresParams::default()
        };
        let mut separate = Vec::new();
        for (rho, b) in rhos.iter().zip(&bs) {
            let op = ImplicitRadiosity::new(&gm, rho).unwrap();
            let mut x = b.clone();
            let mut seen = Vec::new();
            let info = gmres_observed(&op, b, &mut x, &params, &mut |i, r| {
                seen.push((i, r));
                ControlFlow::Continue(())
            })
            .unwrap();
            separate.push((x, info, seen));
        }
        let counting = Counting(&gm, 0.into());
        let mut xs: Vec<Vec<f64>> = bs.clone();
        let mut seen = vec![Vec::new(); 3];
        let mut systems: Vec<RadiositySystem> = xs
            .iter_mut()
            .zip(&rhos)
            .zip(&bs)
            .map(|((x, rho), b)| RadiositySystem { rho, b, x })
            .collect();
        let results = gmres_radiosity(&counting, &mut systems, &params, &mut |c, i, r| {
            seen[c].push((i, r));
            ControlFlow::Continue(())
        });
        let mut passes = 0;
        for (c, result) in results.into_iter().enumerate() {
            let info = result.unwrap();
            let (x, alone, seen_alone) = &separate[c];
            assert_eq!(&xs[c], x, "channel {c}");
            assert_eq!(info.iterations, alone.iterations);
            assert_eq!(info.residual, alone.residual);
            assert_eq!(&seen[c], seen_alone);
            assert!(info.restarts > 0 && info.residual <= params.rel_tol);
            // the Arnoldi steps, a true residual at the start of each
            // cycle (restarts + 1) and the final one
            passes = passes.max(info.iterations + info.restarts + 2);
        }
        let calls = counting.1.load(std::sync::atomic::Ordering::Relaxed);
        assert_eq!(calls, passes);
        let total: usize = separate.iter().map(|s| s.1.iterations).sum();
        assert!(calls < total, "{calls} passes against {total} iterations");
    }

    /// A zero right-hand side, a ρ of the wrong length and a stopped
    /// channel end on their own; the others still converge.
    #[test]
    fn each_system_ends_on_its_own() {
        let n = 40;
        let gm = geometric(n, 5);
        let rho = vec![0.8; n];
        let short = vec![0.8; n - 1];
        let (b, zero) = (vec![1.0; n], vec![0.0; n]);
        let mut xs = [vec![0.0; n], vec![3.0; n], vec![0.0; n], vec![0.0; n]];
        let [x0, x1, x2, x3] = &mut xs;
        let mut systems = [
            RadiositySystem {
                rho: &rho,
                b: &b,
                x: x0,
            },
            RadiositySystem {
                rho: &rho,
                b: &zero,
                x: x1,
            },
            RadiositySystem {
                rho: &short,
                b: &b,
                x: x2,
            },
            RadiositySystem {
                rho: &rho,
                b: &b,
                x: x3,
            },
        ];
        let params = GmresParams::default();
        let results = gmres_radiosity(&gm, &mut systems, &params, &mut |c, i, _| {
            if c == 3 && i == 1 {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        });
        assert!(results[0].as_ref().unwrap().residual <= params.rel_tol);
        assert_eq!(results[1].as_ref().unwrap().iterations, 0);
        assert!(matches!(
            results[2],
            Err(SolveError::DimensionMismatch {
                expected: 40,
                found: 39
            })
        ));
        assert!(matches!(
            results[3],
            Err(SolveError::Stopped { iterations: 1 })
        ));
        assert_eq!(xs[1], vec![0.0; n]);
        // the independent residual of the converged channel
        let a = DenseMatrix::from_row_major(
            n,
            n,
            (0..n * n)
                .map(|k| f64::from(u8::from(k / n == k % n)) - 0.8 * gm.as_slice()[k])
                .collect(),
        );
        assert!(ref_rel_residual(&a, &xs[0], &b) <= 1.05 * params.rel_tol);
    }
}
