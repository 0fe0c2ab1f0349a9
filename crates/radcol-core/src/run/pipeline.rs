//! The stages of one solve (see the module overview in [`super`]).

use super::inputs::{check_quadrature, discretize, fields, visibility_of};
use super::operator::{
    build_compressed, decide_now, lighter_than_dense, predict_compressed, GeometricOperator,
    OperatorDecision, OperatorKind,
};
use super::relight::Relighter;
use super::size::{available_for, MemoryUse};
use super::{ChannelResult, SolveConfig, SolveOutcome, Timings};
use crate::assembly::{AssemblyBackend, AssemblyPlan, BackendInfo, CpuBackend, Unchanged};
use crate::discretization::Discretization;
use crate::error::Error;
use crate::mesh::Mesh;
use crate::nodes::{nodes_per_element, NodeSet};
use crate::norms::error_norms;
use crate::problem::Problem;
use crate::visibility::VisibilityAnalysis;
use std::sync::Arc;
use std::time::Instant;

/// The plans of one solve, kept by the adaptive loop so that the next
/// solve, on a mesh refined from this one, reuses their unchanged pairs.
pub(crate) struct Plans {
    solve: AssemblyPlan,
    check: Option<AssemblyPlan>,
}

/// What a solve on a refined mesh takes from the solve of the mesh it was
/// refined from: plans and geometric matrix, for the pairs of `unchanged`
/// elements.
pub(crate) struct Previous<'a> {
    pub(crate) outcome: &'a SolveOutcome,
    pub(crate) plans: &'a Plans,
    pub(crate) unchanged: Arc<Unchanged>,
    /// How far (relative to max |u_n|) an estimate updated from the
    /// previous one may be from the computed one
    /// ([`crate::estimate::estimate_updated`]); 0: computed always.
    pub(crate) estimate_within: f64,
}

/// What the assembly stage built.
struct Built {
    plan: AssemblyPlan,
    /// This rank's share, in a solve spread over ranks.
    layout: Option<crate::hmatrix::share::Layout>,
    operator: GeometricOperator,
    decision: OperatorDecision,
    kernel_evals: u64,
    device_seconds: Option<f64>,
    backend: BackendInfo,
    memory: MemoryUse,
}

/// Plans the assembly (with `visibility`, decided by the caller) and builds
/// the geometric operator: the dense matrix on `backend`, reusing
/// `previous`'s unchanged pairs, or the compressed one from the plan's
/// integrators ([`super::operator::decide`]).
fn assemble(
    disc: &Arc<Discretization>,
    cfg: &SolveConfig,
    visibility: &VisibilityAnalysis,
    backend: &dyn AssemblyBackend,
    previous: Option<&Previous<'_>>,
    channels: usize,
) -> Result<Built, Error> {
    let mut decision = decide_now(cfg, disc.len() as u64, disc.mesh().len() as u64)?;
    let compressed = decision.kind == OperatorKind::Compressed;
    // The compressed operator is sized from the geometry before the plan
    // (n² pairs classified) and the hours of entries a size that cannot
    // fit would take.
    if compressed {
        decision.predicted_bytes = Some(predict_compressed(disc, cfg)?.bytes());
    }
    if previous.is_none() && cfg.check_memory {
        let (available, above) = (available_for(cfg), super::PREDICT_PLAN_ABOVE);
        super::cost::check_plan_memory(disc, &cfg.quad, visibility, available, above)?;
    }
    let before = super::size::process_memory().map(|(rss, _)| rss);
    // Spread over ranks: each plans the row blocks of its share alone.
    let layout = cfg
        .distributed()
        .filter(|_| compressed)
        .map(|r| super::share::share_layout(disc, cfg, visibility, &**r));
    let plan = plan_of(disc, cfg, visibility, previous, layout.as_ref());
    // What building the plan cost the process (its heap with the
    // allocator's overhead: 25 % more on Cornell), where that is measured.
    let plan_cost = match (before, super::size::process_memory()) {
        (Some(b), Some((after, _))) => plan.heap_bytes().max(after.saturating_sub(b)),
        _ => plan.heap_bytes(),
    };
    // The estimate keeps the entries of its partly visible pairs: check
    // points (degree r + 1) times the column element's unknowns, per pair.
    let store = 8.0
        * plan.partial_entries(|kp| {
            nodes_per_element((disc.degree(kp) + 1).min(crate::nodes::MAX_DEGREE))
        }) as f64;
    let predict = |matrix_bytes: Option<f64>| {
        MemoryUse::predict(
            disc.len(),
            plan_cost,
            cfg.solver,
            channels * (cfg.gmres.restart + 4),
            cfg.estimate,
        )
        .with_estimate_store(store)
        .with_matrix(matrix_bytes)
    };
    Error::if_cancelled(cfg.progress.as_ref(), "plan")?;
    let mut memory = settle(&mut decision, disc, cfg, &predict)?;
    let compressed = decision.kind == OperatorKind::Compressed;
    if let Some(p) = &cfg.progress {
        p.start("assembly", disc.mesh().len() as u64);
    }
    let dense_previous = previous.and_then(|p| p.outcome.operator.dense());
    let (operator, kernel_evals, device_seconds, info) = if compressed {
        let reuse = previous.and_then(|p| Some((p.outcome.operator.compressed()?, &*p.unchanged)));
        let share = cfg.distributed().zip(layout.as_ref());
        let (operator, evals) = match share {
            Some((ranks, l)) => {
                let entries = crate::hmatrix::radiosity::PlanEntries::new(&plan);
                let share = (ranks.clone(), l.held.clone());
                super::share::build_share(&entries, cfg, share, &mut decision, &mut memory)?
            }
            None => build_compressed(&plan, cfg, reuse, &mut decision, &mut memory)?,
        };
        (operator, evals, None, CpuBackend.info())
    } else {
        let assembled = match dense_previous {
            Some(m) => backend.assemble_reusing(&plan, m)?,
            None => backend.assemble(&plan)?,
        };
        let a = assembled;
        (
            GeometricOperator::Dense(a.matrix),
            a.kernel_evals,
            a.device_seconds,
            backend.info(),
        )
    };
    Ok(Built {
        plan,
        layout,
        operator,
        decision,
        kernel_evals,
        device_seconds,
        backend: info,
        memory,
    })
}

/// The solve's plan: of this rank's rows (`layout`) in a solve spread over
/// ranks, else updating `previous`'s where there is one, else fresh.
fn plan_of(
    disc: &Arc<Discretization>,
    cfg: &SolveConfig,
    visibility: &VisibilityAnalysis,
    previous: Option<&Previous<'_>>,
    layout: Option<&crate::hmatrix::share::Layout>,
) -> AssemblyPlan {
    let (quad, progress) = (cfg.quad.clone(), cfg.progress.clone());
    match (previous, layout) {
        (_, Some(l)) => AssemblyPlan::of_rows(
            disc.clone(),
            (None, None),
            quad,
            visibility,
            progress,
            &l.elements,
        ),
        (Some(p), None) => AssemblyPlan::updating(
            disc.clone(),
            quad,
            visibility,
            progress,
            &p.plans.solve,
            p.unchanged.clone(),
        ),
        (None, None) => AssemblyPlan::with_progress(disc.clone(), quad, visibility, progress),
    }
}

/// The memory a solve will use with the operator `decision` finally
/// stores (`predict`: the prediction for a matrix of so many bytes, None
/// dense). The compressed operator counts at its predicted size (checked
/// again once built). Where auto chose dense but the dense solve's whole
/// peak does not fit, it compresses instead; where it fits but would take
/// much of the memory and the compressed operator is predicted far
/// smaller, too ([`lighter_than_dense`]).
fn settle(
    decision: &mut OperatorDecision,
    disc: &Discretization,
    cfg: &SolveConfig,
    predict: &dyn Fn(Option<f64>) -> MemoryUse,
) -> Result<MemoryUse, Error> {
    let mut memory = predict(decision.predicted_bytes);
    let compressed = decision.kind == OperatorKind::Compressed;
    if cfg.check_memory {
        let available = available_for(cfg);
        match memory.check(available) {
            Err(e) if !compressed && decision.switchable => {
                *decision = decision.compress_instead(&e);
                decision.predicted_bytes = Some(predict_compressed(disc, cfg)?.bytes());
                memory = predict(decision.predicted_bytes);
                memory.check(available)?;
            }
            r => r?,
        }
    }
    let to_come = memory.predicted_peak_bytes - memory.after_plan_bytes;
    if let Some(d) = lighter_than_dense(decision, disc, cfg, to_come, available_for(cfg)) {
        *decision = d;
        memory = predict(decision.predicted_bytes);
    }
    Ok(memory)
}

/// Solves `problem` with `cfg`, assembling on `backend`.
pub fn solve(
    problem: &Problem,
    cfg: &SolveConfig,
    backend: &dyn AssemblyBackend,
) -> Result<SolveOutcome, Error> {
    let t0 = Instant::now();
    let visibility = visibility_of(problem, cfg)?;
    let disc = discretize(problem, cfg)?;
    let stages = Stages {
        problem,
        cfg,
        backend,
        visibility: &visibility,
        guess: None,
        previous: None,
    };
    Ok(stages.run(disc, t0)?.0)
}

/// Solves `problem` on a mesh built by the caller (a locally refined one, for
/// example: see [`super::adapt`]), with `guess` (one vector of N values per
/// channel) as GMRES's starting point when given. `cfg`'s degree and α set
/// the nodes; its level and max edge are not used.
pub fn solve_on_mesh(
    problem: &Problem,
    cfg: &SolveConfig,
    mesh: Arc<Mesh>,
    backend: &dyn AssemblyBackend,
    guess: Option<&[Vec<f64>]>,
) -> Result<SolveOutcome, Error> {
    Ok(solve_step(problem, cfg, (mesh, None), backend, guess, None)?.0)
}

/// A degree per element: the node sets to choose from, and each element's
/// degree (a set of that degree must be among them).
pub(crate) type PerElement<'a> = (&'a [NodeSet], &'a [usize]);

/// [`solve_on_mesh`], reusing what `previous` has for the pairs of unchanged
/// elements, and returning the plans for the next step.
pub(crate) fn solve_step(
    problem: &Problem,
    cfg: &SolveConfig,
    (mesh, degrees): (Arc<Mesh>, Option<PerElement<'_>>),
    backend: &dyn AssemblyBackend,
    guess: Option<&[Vec<f64>]>,
    previous: Option<&Previous<'_>>,
) -> Result<(SolveOutcome, Plans), Error> {
    let t0 = Instant::now();
    check_quadrature(cfg)?;
    let visibility = visibility_of(problem, cfg)?;
    let disc = match degrees {
        None => Discretization::new(mesh, NodeSet::new(cfg.degree, cfg.alpha)?),
        Some((sets, degrees)) => Discretization::with_degrees(mesh, sets.to_vec(), degrees)?,
    };
    decide_now(cfg, disc.len() as u64, disc.mesh().len() as u64)?;
    let disc = Arc::new(disc);
    let stages = Stages {
        problem,
        cfg,
        backend,
        visibility: &visibility,
        guess,
        previous,
    };
    stages.run(disc, t0)
}

/// The stages after the discretization, and what they share.
struct Stages<'a> {
    problem: &'a Problem,
    cfg: &'a SolveConfig,
    backend: &'a dyn AssemblyBackend,
    visibility: &'a VisibilityAnalysis,
    guess: Option<&'a [Vec<f64>]>,
    previous: Option<&'a Previous<'a>>,
}

impl Stages<'_> {
    fn run(&self, disc: Arc<Discretization>, t0: Instant) -> Result<(SolveOutcome, Plans), Error> {
        let (problem, cfg) = (self.problem, self.cfg);
        let visibility = self.visibility.clone();
        let h = disc.mesh().h();
        let mesh_s = t0.elapsed().as_secs_f64();

        let t = Instant::now();
        let fields = fields(&disc, problem)?;
        let rhs_s = t.elapsed().as_secs_f64();

        let t = Instant::now();
        let cpu = super::share::own_cpu_seconds(cfg);
        let built = assemble(
            &disc,
            cfg,
            &visibility,
            self.backend,
            self.previous,
            problem.channels.len(),
        )?;
        let (assembly_s, t_assembly) = (t.elapsed().as_secs_f64(), t);
        Error::if_cancelled(cfg.progress.as_ref(), "assembly")?;

        let t = Instant::now();
        let mut channels = Relighter::over(disc.clone(), &built.operator, cfg)
            .solve_fields(problem, fields, self.guess)?;
        let solve_s = t.elapsed().as_secs_f64();

        let t = Instant::now();
        if let (Some(exact), Some(first)) = (&problem.exact, channels.first_mut()) {
            first.errors = Some(error_norms(&first.solution, exact));
        }
        let errors_s = t.elapsed().as_secs_f64();

        let t = Instant::now();
        let check = if cfg.estimate {
            check::estimate_channels(
                problem,
                cfg,
                (&visibility, &built.plan, built.layout.as_ref()),
                &mut channels,
                self.previous,
                self.guess,
            )?
        } else {
            None
        };
        let estimate_s = t.elapsed().as_secs_f64();
        Error::if_cancelled(cfg.progress.as_ref(), "estimate")?;
        if cfg.limit_negative {
            channels.iter_mut().for_each(ChannelResult::limit_negative);
        }

        let ranks = (built.operator.shared())
            .map(|s| super::share::figures(s, (t_assembly, cpu), (assembly_s, built.kernel_evals)));
        let outcome = SolveOutcome {
            ranks,
            h,
            backend: built.backend,
            plan: built.plan.stats(),
            memory: built.memory.measured(),
            visibility,
            kernel_evals: built.kernel_evals,
            device_seconds: built.device_seconds,
            operator: built.operator,
            operator_decision: built.decision,
            discretization: disc,
            channels,
            timings: Timings {
                mesh_s,
                rhs_s,
                assembly_s,
                solve_s,
                errors_s,
                estimate_s,
                total_s: t0.elapsed().as_secs_f64(),
            },
        };
        Ok((
            outcome,
            Plans {
                solve: built.plan,
                check,
            },
        ))
    }
}

mod check;
#[cfg(test)]
mod tests;
