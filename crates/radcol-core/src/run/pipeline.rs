//! The stages of one solve (see the module overview in [`super`]).

use super::inputs::{check_quadrature, discretize, fields, visibility_of};
use super::operator::{
    build_compressed, decide_now, lighter_than_dense, predict_compressed, GeometricOperator,
    OperatorDecision, OperatorKind,
};
use super::probes;
use super::relight::Relighter;
use super::size::{available_memory, MemoryUse};
use super::{ChannelResult, SolveConfig, SolveOutcome, Timings};
use crate::assembly::QuadratureOptions;
use crate::assembly::{AssemblyBackend, AssemblyPlan, BackendInfo, CpuBackend, Unchanged};
use crate::discretization::Discretization;
use crate::error::Error;
use crate::estimate::{
    check_discretization, estimate_shared, estimate_updated, ChannelFields, ErrorEstimate,
    ESTIMATE_QUAD_TOL,
};
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
        let (available, above) = (available_memory(), super::PREDICT_PLAN_ABOVE);
        super::cost::check_plan_memory(disc, &cfg.quad, visibility, available, above)?;
    }
    let progress = cfg.progress.clone();
    let before = super::size::process_memory().map(|(rss, _)| rss);
    // Spread over ranks: each plans the row blocks of its share alone.
    let layout = cfg
        .distributed()
        .filter(|_| compressed)
        .map(|r| super::operator::share_layout(disc, cfg, &**r));
    let plan = match (previous, &layout) {
        (_, Some(l)) => AssemblyPlan::of_rows(
            disc.clone(),
            (None, None),
            cfg.quad.clone(),
            visibility,
            progress,
            &l.elements,
        ),
        (Some(p), None) => AssemblyPlan::updating(
            disc.clone(),
            cfg.quad.clone(),
            visibility,
            progress,
            &p.plans.solve,
            p.unchanged.clone(),
        ),
        (None, None) => {
            AssemblyPlan::with_progress(disc.clone(), cfg.quad.clone(), visibility, progress)
        }
    };
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
        let held = layout.as_ref().map(|l| l.held.clone());
        let (operator, evals) =
            build_compressed(&plan, cfg, reuse, held, &mut decision, &mut memory)?;
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
        let available = available_memory();
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
    if let Some(d) = lighter_than_dense(decision, disc, cfg, to_come, available_memory()) {
        *decision = d;
        memory = predict(decision.predicted_bytes);
    }
    Ok(memory)
}

/// Estimates every channel's error at the check points of its mesh
/// ([`crate::estimate`]), with the solve's quadrature and visibility, or
/// updates `previous`'s estimate where it allows and that pays ([`update`]);
/// returns the check points' plan.
fn estimate_channels(
    problem: &Problem,
    cfg: &SolveConfig,
    (visibility, square, layout): (
        &VisibilityAnalysis,
        &AssemblyPlan,
        Option<&crate::hmatrix::share::Layout>,
    ),
    channels: &mut [ChannelResult],
    previous: Option<&Previous<'_>>,
    guess: Option<&[Vec<f64>]>,
) -> Result<Option<AssemblyPlan>, Error> {
    let Some(first) = channels.first() else {
        return Ok(None);
    };
    Error::if_cancelled(cfg.progress.as_ref(), "solve")?;
    let disc = first.solution.discretization();
    // A stage of its own (about as long as the assembly), counted in the
    // row blocks it fills, reported when it ends.
    let blocks = disc.mesh().len() as u64;
    if let Some(p) = &cfg.progress {
        p.start("estimate", blocks);
    }
    let check = Arc::new(check_discretization(disc));
    let check_fields = fields(&check, problem)?;
    let quad = QuadratureOptions {
        tol: cfg.quad.tol.max(ESTIMATE_QUAD_TOL),
        ..cfg.quad.clone()
    };
    // Spread over ranks: each estimates the elements it owns, planning
    // their check rows alone.
    let share = cfg.distributed().zip(layout).map(|(r, l)| {
        let owned: Vec<bool> = l.owner.iter().map(|&p| p as usize == r.rank()).collect();
        (&**r, l, owned)
    });
    let plan = match &share {
        Some((_, _, owned)) => AssemblyPlan::of_rows(
            disc.clone(),
            (Some(check.clone()), Some(square)),
            quad.clone(),
            visibility,
            None,
            owned,
        ),
        None => {
            let reuse =
                previous.and_then(|p| p.plans.check.as_ref().map(|c| (c, p.unchanged.clone())));
            AssemblyPlan::at_points(
                disc.clone(),
                check.clone(),
                quad.clone(),
                visibility,
                (reuse, Some(square)),
            )
        }
    };
    let inputs: Vec<ChannelFields<'_>> = channels
        .iter()
        .zip(&check_fields)
        .map(|(ch, (rho, emission))| ChannelFields {
            solution: &ch.solution,
            rho,
            emission,
            emission_nodes: &ch.emission,
        })
        .collect();
    // An update reads check rows of every element: one process only.
    let updated = previous
        .zip(guess)
        .filter(|_| share.is_none())
        .and_then(|(p, g)| update(&plan, &inputs, p, g));
    let by_rank = share.as_ref().map(|(r, l, _)| (*r, l.owner.as_slice()));
    let mut estimates = updated.unwrap_or_else(|| estimate_shared(&plan, &inputs, by_rank));
    // Shadows of the direct light between an element's check points.
    let owned = share.as_ref().map(|(_, _, o)| o.as_slice());
    let mut found = probes::find(square, &check, &probes::emitting(disc, channels), owned);
    if let Some((ranks, _, _)) = &share {
        found = probes::gather(*ranks, &found);
    }
    probes::apply(
        &found,
        (disc, &quad, visibility),
        problem,
        channels,
        &mut estimates,
    );
    // Approximate visibility: the most the residual at a node or check
    // point can have moved, per unit of ρ max|u| (0 when exact).
    let mut mass = [(square.stats().visibility_bound).max(plan.stats().visibility_bound)];
    if let Some((ranks, _, _)) = &share {
        // Each rank's plans hold its rows' pairs.
        ranks.max(&mut mass);
    }
    let mass = mass[0];
    for ((ch, mut e), (rho, _)) in channels.iter_mut().zip(estimates).zip(&check_fields) {
        let rho_max = ch.rho.iter().chain(rho).copied().fold(0.0, f64::max);
        e.add_visibility_bound(rho_max, mass);
        ch.estimate = Some(e);
    }
    if let Some(p) = &cfg.progress {
        p.advance(blocks);
    }
    Ok(Some(plan))
}

/// The estimate of `inputs` updated from `previous`'s, with `guess` (the
/// previous solution at this mesh's nodes), where that is allowed and pays.
fn update(
    plan: &AssemblyPlan,
    inputs: &[ChannelFields<'_>],
    previous: &Previous<'_>,
    guess: &[Vec<f64>],
) -> Option<Vec<ErrorEstimate>> {
    if previous.estimate_within <= 0.0 {
        return None;
    }
    let prev: Option<Vec<_>> = previous
        .outcome
        .channels
        .iter()
        .map(|c| c.estimate.as_ref())
        .collect();
    let change: Vec<Vec<f64>> = inputs
        .iter()
        .zip(guess)
        .map(|(ch, g)| {
            ch.solution
                .nodal()
                .iter()
                .zip(g)
                .map(|(u, g)| u - g)
                .collect()
        })
        .collect();
    estimate_updated(plan, inputs, &prev?, &change, previous.estimate_within)
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
        let built = assemble(
            &disc,
            cfg,
            &visibility,
            self.backend,
            self.previous,
            problem.channels.len(),
        )?;
        let assembly_s = t.elapsed().as_secs_f64();
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
            estimate_channels(
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

        let ranks = built.operator.shared().map(|s| {
            let mine = super::RankFigures {
                rows: s.rows().len(),
                stored_bytes: s.local().heap_bytes(),
                assembly_s,
                products_s: s.product_seconds(),
                communication_s: s.ranks().seconds(),
            };
            super::RanksReport::gather(s.ranks(), mine)
        });
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

#[cfg(test)]
mod tests;
