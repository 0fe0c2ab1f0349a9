//! Solving on an assembled operator: the channels of a solve, and then, as
//! often as wanted, new emission or new reflectance on the same surface
//! without reassembly (the operator holds the geometric matrix Gm only, so
//! every channel, every light set and every set of materials reuses it;
//! LU factors are kept while ρ stays the same).

use super::inputs::{fields, NodalFields};
use super::GeometricOperator;
use super::{ChannelResult, SolveConfig, SolveOutcome, SolverKind, SolverReport};
use crate::discretization::Discretization;
use crate::error::{Error, InputError};
use crate::norms::error_norms;
use crate::problem::Problem;
use crate::progress::solve_decades;
use crate::solution::{integrate_nodal, Solution};
use crate::solve::{
    gmres_radiosity_reduced, Alone, DenseLu, RadiosityOperator, RadiositySystem, Reduce,
};
use std::ops::ControlFlow;
use std::sync::Arc;

/// An assembled operator kept to solve again: (I - diag ρ Gm) u = E for any
/// ρ and E given at the nodes of its discretization.
///
/// ```no_run
/// # use radcol_core::{backend::CpuBackend, run::shapes::sphere, run::{Field, Problem}};
/// # use radcol_core::run::{solve, Relighter, SolveConfig};
/// # use std::sync::Arc;
/// let surface = Arc::new(sphere(1.0));
/// let cfg = SolveConfig::default();
/// let first = Problem::new(surface.clone(), Field::Constant(0.5), Field::Constant(1.0));
/// let outcome = solve(&first, &cfg, &CpuBackend)?;
/// let mut relight = Relighter::new(&outcome, &cfg);
/// let dimmer = Problem::new(surface, Field::Constant(0.5), Field::Constant(0.2));
/// let channels = relight.solve(&dimmer)?; // no assembly
/// # Ok::<(), radcol_core::run::Error>(())
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
            channels.iter_mut().for_each(ChannelResult::limit_negative);
        }
        Ok(channels)
    }

    /// Solves every channel's system for its nodal ρ and E, from `guess`
    /// (one vector per channel) where given: GMRES on all channels in
    /// lockstep (one pass over Gm per iteration for all of them), or LU
    /// with factors shared between channels, and calls, with equal ρ.
    pub(crate) fn solve_fields(
        &mut self,
        problem: &Problem,
        fields: Vec<NodalFields>,
        guess: Option<&[Vec<f64>]>,
    ) -> Result<Vec<ChannelResult>, Error> {
        let decades = solve_decades(self.cfg.gmres.rel_tol);
        if let Some(p) = &self.cfg.progress {
            p.start("solve", problem.channels.len() as u64 * decades);
        }
        let mut xs: Vec<Vec<f64>> = fields
            .iter()
            .enumerate()
            .map(|(c, (_, emission))| match guess.and_then(|g| g.get(c)) {
                Some(g) if g.len() == emission.len() => g.clone(),
                _ => emission.clone(),
            })
            .collect();
        let reports = match self.cfg.solver {
            SolverKind::Gmres => self.gmres_all(&fields, &mut xs, decades)?,
            SolverKind::Lu => fields
                .iter()
                .zip(&mut xs)
                .map(|((rho, emission), x)| self.lu(rho, emission, x, decades))
                .collect::<Result<_, _>>()?,
        };
        let mut channels = Vec::new();
        for (((ch, (rho, emission)), x), solver) in
            problem.channels.iter().zip(fields).zip(xs).zip(reports)
        {
            if !solver.residual.is_finite() {
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
                solver,
                errors: None,
                estimate: None,
                limited: None,
            });
        }
        Ok(channels)
    }

    /// GMRES on every channel at once ([`gmres_radiosity_reduced`]; in a
    /// distributed solve on this rank's rows, reduced over the ranks, the
    /// solutions gathered whole), each channel reporting the decades its
    /// residual falls to `cfg.progress` (`decades` per channel) and
    /// stopping when it asks.
    fn gmres_all(
        &self,
        fields: &[NodalFields],
        xs: &mut [Vec<f64>],
        decades: u64,
    ) -> Result<Vec<SolverReport>, Error> {
        let progress = self.cfg.progress.as_ref();
        let mut shown = vec![0u64; fields.len()];
        // Spread over ranks: every system restricted to this rank's rows,
        // solved together, and gathered whole again on every rank.
        let share = self.operator.shared();
        let local: Option<Vec<[Vec<f64>; 3]>> = share.map(|s| {
            fields
                .iter()
                .zip(xs.iter())
                .map(|((rho, b), x)| [s.restrict(rho), s.restrict(b), s.restrict(x)])
                .collect()
        });
        let mut local_x: Vec<Vec<f64>> = local
            .as_ref()
            .map(|l| l.iter().map(|[_, _, x]| x.clone()).collect())
            .unwrap_or_default();
        let mut systems: Vec<RadiositySystem> = match &local {
            Some(l) => l
                .iter()
                .zip(local_x.iter_mut())
                .map(|([rho, b, _], x)| RadiositySystem { rho, b, x })
                .collect(),
            None => fields
                .iter()
                .zip(xs.iter_mut())
                .map(|((rho, b), x)| RadiositySystem { rho, b, x })
                .collect(),
        };
        let reduce: &dyn Reduce = match share {
            Some(s) => s.ranks(),
            None => &Alone,
        };
        let results = gmres_radiosity_reduced(
            self.operator,
            &mut systems,
            &self.cfg.gmres,
            reduce,
            &mut |c, _, residual| {
                let Some(p) = progress else {
                    return ControlFlow::Continue(());
                };
                let reached = if residual > 0.0 {
                    ((-residual.log10()).floor().max(0.0) as u64).min(decades)
                } else {
                    decades
                };
                if reached > shown[c] {
                    p.advance(reached - shown[c]);
                    shown[c] = reached;
                }
                if p.cancelled() {
                    ControlFlow::Break(())
                } else {
                    ControlFlow::Continue(())
                }
            },
        );
        drop(systems);
        if let Some(s) = share {
            for (x, local) in xs.iter_mut().zip(&local_x) {
                s.gather(local, x);
            }
        }
        let mut reports = Vec::new();
        for (result, shown) in results.into_iter().zip(shown) {
            let info = match result {
                Err(crate::solve::SolveError::Stopped { .. }) => {
                    return Err(Error::Cancelled { stage: "solve" })
                }
                r => r?,
            };
            // A converged channel counts all its decades (GMRES may stop
            // short of the last one at the rounding floor, or pass several
            // in one step).
            if let Some(p) = progress {
                p.advance(decades - shown);
            }
            reports.push(SolverReport {
                kind: SolverKind::Gmres,
                iterations: info.iterations,
                // GMRES's own: the true residual of the returned x.
                residual: info.residual,
                growth: Some(info.growth),
                condition: None,
                at_rounding_floor: info.at_rounding_floor,
            });
        }
        Ok(reports)
    }

    /// One channel by LU on the dense matrix, refactored only when ρ
    /// changes (the old factors go first: a channel with other ρ, Cornell's
    /// green after red, held two copies at once).
    fn lu(
        &mut self,
        rho: &[f64],
        emission: &[f64],
        x: &mut [f64],
        decades: u64,
    ) -> Result<SolverReport, Error> {
        Error::if_cancelled(self.cfg.progress.as_ref(), "solve")?;
        let Some(gm) = self.operator.dense() else {
            return Err(InputError::CompressedLu.into());
        };
        let op = RadiosityOperator::new(gm, rho)?;
        if self.lu.as_ref().is_none_or(|(r, _, _)| r != rho) {
            drop(self.lu.take());
            let lu = DenseLu::factor_radiosity(&op)?;
            let kappa = lu.condition_estimate();
            self.lu = Some((rho.to_vec(), lu, kappa));
        }
        let (_, lu, kappa) = self.lu.as_ref().expect("just built");
        // x holds GMRES's starting guess (the previous adaptive step's
        // solution); LU solves for the emission itself.
        x.copy_from_slice(emission);
        lu.solve_in_place(x)?;
        if let Some(p) = &self.cfg.progress {
            p.advance(decades);
        }
        Ok(SolverReport {
            kind: SolverKind::Lu,
            iterations: 0,
            residual: crate::solve::true_residual(&op, x, emission),
            growth: None,
            condition: Some(*kappa),
            at_rounding_floor: false,
        })
    }
}
