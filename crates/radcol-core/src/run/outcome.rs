//! What one solve produced: nodal solutions per channel, with timings, pair
//! statistics, the visibility decision and (when u is known) errors.

use super::SolverKind;
use crate::assembly::{BackendInfo, PlanStats};
use crate::discretization::Discretization;
use crate::estimate::ErrorEstimate;
use crate::norms::ErrorNorms;
use crate::solution::{Limited, Solution};
use crate::visibility::VisibilityAnalysis;
use serde::Serialize;
use std::sync::Arc;

/// Wall-clock seconds per stage.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Timings {
    /// Mesh, nodes and discretization.
    pub mesh_s: f64,
    /// Evaluating ρ and E at the nodes (includes manufacturing E).
    pub rhs_s: f64,
    /// Plan and matrix fill.
    pub assembly_s: f64,
    /// Linear solves, all channels.
    pub solve_s: f64,
    /// Error norms against the exact solution.
    pub errors_s: f64,
    /// The error estimate (check plan, fill and contraction).
    pub estimate_s: f64,
    /// Everything.
    pub total_s: f64,
}

/// How a channel's linear system was solved.
#[derive(Clone, Debug, Serialize)]
pub struct SolverReport {
    /// "gmres" or "lu".
    pub kind: SolverKind,
    /// GMRES iterations (0 for LU).
    pub iterations: usize,
    /// True relative residual ‖b - A x‖ / ‖b‖.
    pub residual: f64,
    /// GMRES's ‖A‖ ‖x‖ / ‖b‖, a lower bound of the condition number
    /// (`crate::solve::GmresInfo::growth`); None for LU.
    pub growth: Option<f64>,
    /// LU's estimate of the condition number κ₁(A)
    /// (`crate::solve::DenseLu::condition_estimate`); None for GMRES.
    pub condition: Option<f64>,
    /// GMRES stopped at the rounding floor of the system, above `--tol`
    /// (`ROUNDING_FLOOR`).
    pub at_rounding_floor: bool,
}

impl SolverReport {
    /// What is known of the condition number: LU's estimate of κ₁, else
    /// GMRES's lower bound.
    pub fn conditioning(&self) -> Option<f64> {
        self.condition.or(self.growth)
    }
}

/// One channel's result.
#[derive(Clone, Debug)]
pub struct ChannelResult {
    /// Channel name.
    pub name: String,
    /// u_n.
    pub solution: Solution,
    /// ρ at the nodes.
    pub rho: Vec<f64>,
    /// E at the nodes.
    pub emission: Vec<f64>,
    /// Solver report.
    pub solver: SolverReport,
    /// ∫_S u_n.
    pub integral_u: f64,
    /// ∫_S of the interpolated emission.
    pub integral_e: f64,
    /// Errors, when the exact solution is known.
    pub errors: Option<ErrorNorms>,
    /// The a posteriori error estimate, when asked for.
    pub estimate: Option<ErrorEstimate>,
    /// u_n made nonnegative and what that changed, when u_n has negative
    /// values although E, ρ ≥ 0 (and [`super::SolveConfig::limit_negative`]).
    /// Its changes are added to the element estimates.
    pub limited: Option<(Solution, Limited)>,
}

impl ChannelResult {
    /// Limits u_n to nonnegative values when E ≥ 0 (ρ ≥ 0 always) and
    /// u_n has negative ones; the element estimates grow by the change.
    pub(crate) fn limit_negative(&mut self) {
        if self.emission.iter().any(|&e| e < 0.0) {
            return;
        }
        self.limited = self.solution.limited_nonnegative();
        if let (Some((_, lim)), Some(e)) = (&self.limited, &mut self.estimate) {
            for (x, c) in e.elements.iter_mut().zip(&lim.change) {
                *x += c;
            }
        }
    }

    /// The solution to show (images, vertex meshes): the limited one when
    /// there is one, else u_n.
    pub fn shown(&self) -> &Solution {
        self.limited.as_ref().map_or(&self.solution, |(s, _)| s)
    }
}

/// Everything a solve produced: the discretization, the operator, and per
/// colour channel the solution u_n, its integrals, the solver's report and
/// the error estimate; with timings and the assembly's pair counts.
///
/// ```
/// use radcol_core::backend::CpuBackend;
/// use radcol_core::run::{shapes::sphere, solve, Field, Problem, SolveConfig};
/// use std::sync::Arc;
///
/// let problem = Problem::new(Arc::new(sphere(1.0)), Field::Constant(0.5), Field::Constant(1.0));
/// let outcome = solve(&problem, &SolveConfig { level: 1, ..Default::default() }, &CpuBackend)?;
/// let u = &outcome.channels[0];
/// // u ≡ 2 = 2 E on the unit sphere, so ∫u = 2 ∫E; the estimate says how far u_n is.
/// assert!((u.integral_u / u.integral_e - 2.0).abs() < 1e-9);
/// assert!(u.estimate.as_ref().unwrap().max < 1e-8);
/// assert_eq!(outcome.discretization.len(), u.solution.nodal().len());
/// # Ok::<(), radcol_core::run::Error>(())
/// ```
#[derive(Debug)]
pub struct SolveOutcome {
    /// The discretization solved on.
    pub discretization: Arc<Discretization>,
    /// The geometric operator, dense or compressed (kept for relighting,
    /// exports and checks).
    pub operator: super::GeometricOperator,
    /// Why it is dense or compressed.
    pub operator_decision: super::OperatorDecision,
    /// Mesh size h (eq. 11).
    pub h: f64,
    /// Backend that assembled.
    pub backend: BackendInfo,
    /// Pair statistics of the plan.
    pub plan: PlanStats,
    /// Predicted and measured memory ([`super::MemoryUse`]).
    pub memory: super::MemoryUse,
    /// Whether visibility was modelled, and why.
    pub visibility: VisibilityAnalysis,
    /// Kernel evaluations of the assembly.
    pub kernel_evals: u64,
    /// Device seconds of the assembly, when measured.
    pub device_seconds: Option<f64>,
    /// Per-channel results.
    pub channels: Vec<ChannelResult>,
    /// Timings.
    pub timings: Timings,
    /// In a solve spread over ranks, what each held and spent (the same on
    /// every rank); None in one process.
    pub ranks: Option<RanksReport>,
}

/// What each rank of a distributed solve held and spent, gathered at the
/// end of the solve.
#[derive(Clone, Debug, Serialize)]
pub struct RanksReport {
    /// How many ranks ran the solve.
    pub size: usize,
    /// Per rank, in rank order.
    pub per_rank: Vec<RankFigures>,
}

/// One rank's share of a distributed solve.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct RankFigures {
    /// Rows of the operator (unknowns) it held.
    pub rows: usize,
    /// Bytes of the operator's numbers it stored.
    pub stored_bytes: u64,
    /// Seconds of its assembly (plan and its share of the blocks), up to
    /// the end of the slowest rank's.
    pub assembly_s: f64,
    /// Seconds of its own part of the assembly, before it first waits
    /// for another rank: its plan and its blocks (wall time).
    pub work_s: f64,
    /// CPU seconds of that work (all its threads), where the platform
    /// says and the rank is a process of its own: the measure of its share of the work when ranks outnumber
    /// cores and wall times include turns taken on a shared core.
    pub work_cpu_s: Option<f64>,
    /// Kernel evaluations of its blocks.
    pub kernel_evals: u64,
    /// Seconds multiplying its blocks in GMRES's products.
    pub products_s: f64,
    /// Seconds gathering x for those products (waiting for the other
    /// ranks included): the communication of a product.
    pub gathers_s: f64,
    /// Seconds in collective operations since the process began (gathers
    /// and reductions, waiting for the other ranks included).
    pub communication_s: f64,
}

impl RanksReport {
    /// Every rank's figures, gathered from each rank's own (every rank
    /// calls it together).
    pub(crate) fn gather(ranks: &dyn crate::ranks::Ranks, mine: RankFigures) -> Self {
        let each = |v: f64| ranks.gather_each(v);
        let (rows, stored) = (each(mine.rows as f64), each(mine.stored_bytes as f64));
        let (assembly, products) = (each(mine.assembly_s), each(mine.products_s));
        let (gathers, communication) = (each(mine.gathers_s), each(mine.communication_s));
        let (work, cpu) = (each(mine.work_s), each(mine.work_cpu_s.unwrap_or(f64::NAN)));
        let evals = each(mine.kernel_evals as f64);
        let per_rank = (0..ranks.size())
            .map(|p| RankFigures {
                rows: rows[p] as usize,
                stored_bytes: stored[p] as u64,
                assembly_s: assembly[p],
                work_s: work[p],
                work_cpu_s: Some(cpu[p]).filter(|c| c.is_finite()),
                kernel_evals: evals[p] as u64,
                products_s: products[p],
                gathers_s: gathers[p],
                communication_s: communication[p],
            })
            .collect();
        Self {
            size: ranks.size(),
            per_rank,
        }
    }
}

impl SolveOutcome {
    /// Per element of the mesh: whether it emits (E > 0 at one of its nodes
    /// in some channel). What [`crate::render::render_scene`] takes, so that
    /// an image is exposed for the light the surfaces reflect.
    pub fn emitting_elements(&self) -> Vec<bool> {
        let disc = &self.discretization;
        (0..disc.mesh().len())
            .map(|k| {
                let nodes = disc.range(k);
                (self.channels.iter()).any(|c| c.emission[nodes.clone()].iter().any(|&e| e > 0.0))
            })
            .collect()
    }
}
