//! Solving on an assembled operator: the channels of a solve, and then, as
//! often as wanted, new emission or new reflectance on the same surface
//! without reassembly (the operator holds the geometric matrix Gm only, so
//! every channel, every light set and every set of materials reuses it;
//! LU factors are kept while ρ stays the same).

use super::inputs::{fields, NodalFields};
use super::pipeline::{limit_negative, true_residual};
use super::GeometricOperator;
use super::{ChannelResult, SolveConfig, SolveOutcome, SolverKind, SolverReport};
use crate::discretization::Discretization;
use crate::error::{Error, InputError};
use crate::norms::error_norms;
use crate::problem::Problem;
use crate::progress::solve_decades;
use crate::solution::{integrate_nodal, Solution};
use crate::solve::{gmres_observed, DenseLu, ImplicitRadiosity, LinearOperator, RadiosityOperator};
use std::ops::ControlFlow;
use std::sync::Arc;

/// An assembled operator kept to solve again: (I - diag ρ Gm) u = E for any
/// ρ and E given at the nodes of its discretization.
///
/// ```no_run
/// # use radcol_core::{assembly::CpuBackend, geometry::shapes::sphere, problem::{Field, Problem}};
/// # use radcol_core::run::{solve, Relighter, SolveConfig};
/// # use std::sync::Arc;
/// let surface = Arc::new(sphere(1.0));
/// let cfg = SolveConfig::default();
/// let first = Problem::new(surface.clone(), Field::Constant(0.5), Field::Constant(1.0));
/// let outcome = solve(&first, &cfg, &CpuBackend)?;
/// let mut relight = Relighter::new(&outcome, &cfg);
/// let dimmer = Problem::new(surface, Field::Constant(0.5), Field::Constant(0.2));
/// let channels = relight.solve(&dimmer)?; // no assembly
/// # Ok::<(), radcol_core::error::Error>(())
/// ```
#[derive(Debug)]
pub struct Relighter<'a> {
    disc: Arc<Discretization>,
    operator: &'a GeometricOperator,
    cfg: SolveConfig,
    /// ρ at the nodes and its factors with their condition estimate (LU).
    lu: Option<(Vec<f64>, DenseLu, f64)>,
}

impl<'a> Relighter<'a> {
    /// Over the discretization and geometric matrix of `outcome`, with the
    /// solver settings of `cfg` (solver, GMRES tolerances, limiter).
    pub fn new(outcome: &'a SolveOutcome, cfg: &SolveConfig) -> Self {
        let quiet = SolveConfig {
            progress: None,
            ..cfg.clone()
        };
        Self::over(outcome.discretization.clone(), &outcome.operator, &quiet)
    }

    pub(crate) fn over(
        disc: Arc<Discretization>,
        operator: &'a GeometricOperator,
        cfg: &SolveConfig,
    ) -> Self {
        Self {
            disc,
            operator,
            cfg: cfg.clone(),
            lu: None,
        }
    }

    /// Solves every channel of `problem`, whose surface must be the one the
    /// operator was assembled on (the same `Arc`): u_n, ∫u, ∫E, the solver's
    /// report, the errors against `problem.exact` (first channel) and the
    /// positivity limiter as in a full solve. There is no error estimate:
    /// it needs the check points' plan, as much work as the assembly.
    ///
    /// # Errors
    /// [`InputError::OtherSurface`] for another surface; a field that is
    /// not finite at a node; a failed linear solve.
    pub fn solve(&mut self, problem: &Problem) -> Result<Vec<ChannelResult>, Error> {
        if !Arc::ptr_eq(self.disc.mesh().surface(), &problem.surface) {
            return Err(InputError::OtherSurface {
                assembled: self.disc.mesh().surface().name.clone(),
                given: problem.surface.name.clone(),
            }
            .into());
        }
        let nodal = fields(&self.disc, problem)?;
        let mut channels = self.solve_fields(problem, nodal, None)?;
        if let (Some(exact), Some(first)) = (&problem.exact, channels.first_mut()) {
            first.errors = Some(error_norms(&first.solution, exact));
        }
        if self.cfg.limit_negative {
            channels.iter_mut().for_each(limit_negative);
        }
        Ok(channels)
    }

    /// Solves every channel's system for its nodal ρ and E, from `guess`
    /// (one vector per channel) where given; LU factors are shared between
    /// channels, and calls, with equal ρ.
    pub(crate) fn solve_fields(
        &mut self,
        problem: &Problem,
        fields: Vec<NodalFields>,
        guess: Option<&[Vec<f64>]>,
    ) -> Result<Vec<ChannelResult>, Error> {
        let mut channels = Vec::new();
        let cfg = &self.cfg;
        let lu_cache = &mut self.lu;
        let decades = solve_decades(cfg.gmres.rel_tol);
        if let Some(p) = &cfg.progress {
            p.start("solve", problem.channels.len() as u64 * decades);
        }
        for (c, (ch, (rho, emission))) in problem.channels.iter().zip(fields).enumerate() {
            let mut x = match guess.and_then(|g| g.get(c)) {
                Some(g) if g.len() == emission.len() => g.clone(),
                _ => emission.clone(),
            };
            // The dense matrix's fused row products, or products through
            // the compressed operator.
            let (dense_op, implicit_op);
            let op: &dyn LinearOperator = match self.operator.dense() {
                Some(gm) => {
                    dense_op = RadiosityOperator::new(gm, &rho)?;
                    &dense_op
                }
                None => {
                    implicit_op = ImplicitRadiosity::new(self.operator, &rho)?;
                    &implicit_op
                }
            };
            let (iterations, growth, condition, at_rounding_floor) = match cfg.solver {
                SolverKind::Gmres => {
                    let info = gmres_watched(op, &emission, &mut x, cfg, decades)?;
                    (
                        info.iterations,
                        Some(info.growth),
                        None,
                        info.at_rounding_floor,
                    )
                }
                SolverKind::Lu => {
                    Error::if_cancelled(cfg.progress.as_ref(), "solve")?;
                    let Some(gm) = self.operator.dense() else {
                        return Err(InputError::CompressedLu.into());
                    };
                    if lu_cache.as_ref().is_none_or(|(r, _, _)| *r != rho) {
                        // The old factors go first: a channel with other ρ
                        // (Cornell's green after red) held two copies at once.
                        drop(lu_cache.take());
                        let lu = DenseLu::factor_radiosity(&RadiosityOperator::new(gm, &rho)?)?;
                        let kappa = lu.condition_estimate();
                        *lu_cache = Some((rho.clone(), lu, kappa));
                    }
                    let (_, lu, kappa) = lu_cache.as_ref().expect("just built");
                    lu.solve_in_place(&mut x)?;
                    if let Some(p) = &cfg.progress {
                        p.advance(decades);
                    }
                    (0, None, Some(*kappa), false)
                }
            };
            let residual = true_residual(op, &x, &emission);
            if !residual.is_finite() {
                return Err(crate::solve::SolveError::NonFinite.into());
            }
            let integral_e = integrate_nodal(&self.disc, &emission);
            let solution = Solution::new(self.disc.clone(), x);
            channels.push(ChannelResult {
                name: ch.name.clone(),
                integral_u: solution.integral(),
                integral_e,
                solution,
                rho,
                emission,
                solver: SolverReport {
                    kind: cfg.solver,
                    iterations,
                    residual,
                    growth,
                    condition,
                    at_rounding_floor,
                },
                errors: None,
                estimate: None,
                limited: None,
            });
        }
        Ok(channels)
    }
}

/// GMRES on one channel, reporting each decade its residual falls to
/// `cfg.progress` (`decades` per channel in all) and stopping when it asks.
fn gmres_watched(
    op: &dyn LinearOperator,
    b: &[f64],
    x: &mut [f64],
    cfg: &SolveConfig,
    decades: u64,
) -> Result<crate::solve::GmresInfo, Error> {
    let progress = cfg.progress.as_ref();
    let mut shown = 0u64;
    let result = gmres_observed(op, b, x, &cfg.gmres, &mut |_, residual| {
        let Some(p) = progress else {
            return ControlFlow::Continue(());
        };
        let reached = if residual > 0.0 {
            ((-residual.log10()).floor().max(0.0) as u64).min(decades)
        } else {
            decades
        };
        if reached > shown {
            p.advance(reached - shown);
            shown = reached;
        }
        if p.cancelled() {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    });
    // A converged channel counts all its decades (GMRES may stop short of
    // the last one at the rounding floor, or pass several in one step).
    if let (Some(p), Ok(_)) = (progress, &result) {
        p.advance(decades - shown);
    }
    match result {
        Err(crate::solve::SolveError::Stopped { .. }) => Err(Error::Cancelled { stage: "solve" }),
        r => Ok(r?),
    }
}
