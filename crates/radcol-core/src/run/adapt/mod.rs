//! Adaptive refinement to a tolerance: solve, estimate (`crate::estimate`),
//! split the elements whose estimate is large 4:1, solve again, until the
//! estimated max error of what is shown (u_n, or u_n limited to nonnegative
//! values with the limiter's change added) relative to max |u_n| is below
//! the target or a budget stops it.
//!
//! The collocation space is discontinuous, so an element is split without
//! its neighbours (hanging vertices are harmless to the method); children
//! replace their parent in place, which keeps the elements of a base
//! triangle consecutive and in refinement order (what the occlusion walk
//! reads). Each new solve starts GMRES from the previous solution evaluated
//! at the new nodes, and takes the classes, occluder candidates and matrix
//! entries of pairs of unchanged elements from the previous solve
//! ([`AssemblyPlan::updating`](crate::assembly::AssemblyPlan::updating)):
//! only the rows and columns of new elements are integrated. The estimate
//! is updated from the previous step's where u_n changed little away from
//! the new elements (`crate::estimate::estimate_updated`). Elements whose
//! estimate stops falling under refinement are no longer split
//! (`history.rs`); the loop then names where they are. With
//! [`AdaptOptions::hp`] a marked element may instead be raised one degree,
//! or split with its children one degree lower (`hp.rs`).

mod assess;
mod budget;
mod history;
pub mod hp;
mod next;
mod options;
mod resume;

pub use history::{singular_points, SingularPoint, STALL_RATIO};
pub use options::{
    AdaptOptions, ESTIMATE_WITHIN, MARK_FRACTION, MAX_FRACTION, MIN_SIZE, MIN_TARGET,
    STALL_GENERATIONS,
};
pub use resume::{resume_adaptive, Resume, Resumed};

use super::pipeline::{solve_step, PerElement, Plans, Previous};
use super::{discretize, visibility_budget_for, OperatorKind, SolveConfig, SolveOutcome, Timings};
use crate::assembly::{AssemblyBackend, Unchanged};
use crate::error::{Error, InputError};
use crate::estimate::RelativeTo;
use crate::mesh::Mesh;
use crate::problem::Problem;
use assess::{assess, Assessment};
use history::History;
use hp::Degrees;
use next::carry;
pub use next::{on_refined, on_refined_at, refine};
use serde::Serialize;
use std::sync::Arc;
use std::time::Instant;
#[cfg(test)]
use {
    assess::{decide, mark, Marking},
    budget::budget,
};

/// Why the loop stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// The estimate of what is shown (the limited solution where u_n < 0
    /// was limited) is below the target.
    Reached,
    /// The next step would exceed the unknowns budget.
    MaxUnknowns,
    /// The next step's operator (dense, or a compressed one's pair table) would not fit in memory.
    Memory,
    /// The step limit was reached.
    MaxSteps,
    /// The estimate is below the target except at elements that are no
    /// longer split (their estimate stalled, or they reached the size
    /// floor): the error is concentrated at points where refinement does not
    /// reduce it (or not above the floor), named in
    /// [`AdaptOutcome::singular`].
    Singular,
}

impl std::fmt::Display for StopReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            StopReason::Reached => "the estimate is below the target",
            StopReason::MaxUnknowns => "the next step would exceed the unknowns budget",
            StopReason::Memory => "the next step's operator would not fit in memory",
            StopReason::MaxSteps => "the step limit was reached",
            StopReason::Singular => "the estimate is below the target except next to the points listed, where it stopped falling under refinement (typically a point where u has a direction-dependent limit, such as the foot of a block's corner on a floor) or the elements reached the smallest size split",
        })
    }
}

/// One solve of the loop.
#[derive(Clone, Debug, Serialize)]
pub struct AdaptStep {
    /// Elements.
    pub elements: usize,
    /// Unknowns N.
    pub unknowns: usize,
    /// Estimated max error of u_n relative to max |u_n| (worst channel).
    pub estimate: f64,
    /// Estimated max error of what is shown (worst channel,
    /// [`crate::estimate::ErrorEstimate::shown_max_rel`]): at least
    /// `estimate`, more where u_n < 0 was limited or is counted as error.
    /// The loop stops on this figure, so that the outputs, which show the
    /// limited solution, meet the target.
    pub estimate_shown: f64,
    /// Estimated rms error relative to max |u_n| (worst channel).
    pub estimate_rms: f64,
    /// True global max error, when the exact solution is known (first channel).
    pub true_error: Option<f64>,
    /// Elements split after this step (0 on the last).
    pub split: usize,
    /// Elements where u_n < 0 somewhere although E, ρ ≥ 0.
    pub negative_elements: usize,
    /// Elements above the marking threshold left whole because refinement
    /// stopped reducing their estimate (or they are at the size floor).
    pub singular_elements: usize,
    /// The estimate (relative max, worst channel) over the elements still
    /// refined: the error away from the singular points.
    pub estimate_elsewhere: f64,
    /// Wall seconds of the solve, estimate included.
    pub seconds: f64,
    /// When the estimate was updated from the previous step's instead of
    /// computed: at most how far from the computed one (relative to max
    /// |u_n|, worst channel).
    pub estimate_updated_within: Option<f64>,
    /// The solve's seconds per stage (assembly, linear solves, estimate).
    pub timings: Timings,
    /// Dense or compressed geometric operator.
    pub operator: OperatorKind,
    /// How many elements have each degree (index: the degree).
    pub degrees: Vec<usize>,
}

/// The last solve and how the loop got there.
#[derive(Debug)]
pub struct AdaptOutcome {
    /// The final solve (its outputs are what to write).
    pub outcome: SolveOutcome,
    /// Every step, in order.
    pub steps: Vec<AdaptStep>,
    /// Why it stopped.
    pub stop: StopReason,
    /// Where the last step's estimate is above the target on elements that
    /// are no longer split, largest first (empty when none is).
    pub singular: Vec<SingularPoint>,
    /// Where the loop stands, to refine the final mesh further
    /// ([`resume_adaptive`]).
    pub resume: Resume,
}

/// Solves `problem` from the mesh `cfg` describes, refining where the
/// estimate is large until `opts.target` or a budget; `on_step` sees each
/// step as it ends.
pub fn solve_adaptive(
    problem: &Problem,
    cfg: &SolveConfig,
    opts: &AdaptOptions,
    backend: &dyn AssemblyBackend,
    mut on_step: impl FnMut(&AdaptStep),
) -> Result<AdaptOutcome, Error> {
    let cfg = checked(problem, cfg, opts, backend)?;
    let mesh = discretize(problem, &cfg)?.mesh().clone();
    // With hp or a graded start, every element's degree and how it came to be.
    let degrees = Degrees::start(&cfg, &mesh, opts, backend)?;
    let history = History::new(mesh.len(), opts.stall_generations as usize);
    let start = Start {
        mesh,
        degrees,
        history,
        guess: None,
    };
    run(problem, &cfg, opts, backend, start, &mut on_step)
}

/// `cfg` as every step solves with it, once `opts`, `problem` and
/// `backend` are checked.
fn checked(
    problem: &Problem,
    cfg: &SolveConfig,
    opts: &AdaptOptions,
    backend: &dyn AssemblyBackend,
) -> Result<SolveConfig, Error> {
    opts.check()?;
    if !problem.emits() {
        return Err(InputError::NoEmission.into());
    }
    hp::check_backend(opts.hp, backend)?;
    Ok(step_config(problem, cfg, opts))
}

/// Where the loop starts: a mesh, its elements' degrees (with hp or a
/// graded start), their estimate history and GMRES's start.
struct Start {
    mesh: Arc<Mesh>,
    degrees: Option<Degrees>,
    history: History,
    guess: Option<Vec<Vec<f64>>>,
}

/// The loop from `start`: solve, assess, split, until a stop.
fn run(
    problem: &Problem,
    cfg: &SolveConfig,
    opts: &AdaptOptions,
    backend: &dyn AssemblyBackend,
    start: Start,
    on_step: &mut dyn FnMut(&AdaptStep),
) -> Result<AdaptOutcome, Error> {
    let Start {
        mut mesh,
        mut degrees,
        mut history,
        mut guess,
    } = start;
    let floor = opts.min_size * diagonal(&mesh);
    let mut steps = Vec::new();
    // The previous solve, its plans and which elements it shares with this
    // mesh: pairs of unchanged elements are neither classified nor
    // integrated again.
    let mut previous: Option<Held> = None;
    // The previous step's singular points, for a stop before this step ends.
    let mut pending_singular = Vec::new();
    loop {
        let t = Instant::now();
        let per_element = degrees.as_ref().map(|d| (d.sets(), d.degrees()));
        let step = (mesh.clone(), per_element, guess.as_deref());
        let Some((out, plans)) = solve_or_stand(problem, cfg, opts, backend, step, &previous)?
        else {
            // The step's peak (matrix, check rows, solver) would not fit,
            // although the budget let its matrices in: the previous step's
            // answer stands, as at any other budget stop.
            let (outcome, _, _, resume) = previous.take().expect("refused after a step");
            return Ok(AdaptOutcome {
                outcome,
                steps,
                stop: StopReason::Memory,
                singular: pending_singular,
                resume,
            });
        };
        // The previous solve has served: its matrix goes before the next one.
        drop(previous.take());
        let Assessment {
            mut step,
            stop,
            marked,
            indicator,
            negative,
            singular,
        } = assess(&out, &history, (cfg, opts, floor), steps.len() + 1);
        step.seconds = t.elapsed().as_secs_f64();
        on_step(&step);
        steps.push(step);
        if let Some(stop) = stop {
            return Ok(AdaptOutcome {
                outcome: out,
                steps,
                stop,
                singular,
                resume: Resume { history, degrees },
            });
        }
        let next = carry(
            &out,
            &marked,
            (&indicator, &negative),
            degrees.as_ref(),
            &history,
        );
        let resume = Resume {
            history: std::mem::replace(&mut history, next.history),
            degrees: std::mem::replace(&mut degrees, next.degrees),
        };
        (mesh, guess) = (next.mesh, Some(next.guess));
        previous = Some((out, plans, next.unchanged, resume));
        pending_singular = singular;
    }
}

/// A step's mesh, its degrees (with hp) and GMRES's start.
type StepInput<'a> = (Arc<Mesh>, Option<PerElement<'a>>, Option<&'a [Vec<f64>]>);

/// The previous solve, its plans, which elements the next mesh shares
/// with it, and where the loop stood after it.
type Held = (SolveOutcome, Plans, Arc<Unchanged>, Resume);

/// The step on `mesh` (with a degree per element when given, from `guess`),
/// reusing what `previous` has; None when its peak would not fit after a
/// previous step (whose answer then stands).
fn solve_or_stand(
    problem: &Problem,
    cfg: &SolveConfig,
    opts: &AdaptOptions,
    backend: &dyn AssemblyBackend,
    (mesh, per_element, guess): StepInput<'_>,
    previous: &Option<Held>,
) -> Result<Option<(SolveOutcome, Plans)>, Error> {
    let prev = previous
        .as_ref()
        .map(|(outcome, plans, unchanged, _)| Previous {
            outcome,
            plans,
            unchanged: unchanged.clone(),
            // The update's tolerance is relative to max |u_n|: a target
            // relative to the reflected light is the smaller, by the
            // smallest ratio of the channels' scales.
            estimate_within: opts.estimate_within
                * opts.mark_fraction
                * opts.target
                * to_max_u(outcome, opts.relative_to),
        });
    // After a first step, GMRES stops where the algebraic error is far
    // below the target.
    let tuned;
    let cfg = match previous {
        Some((outcome, ..)) => {
            let most = per_element.map_or(cfg.degree, |(sets, _)| {
                sets.iter().map(|s| s.degree()).max().unwrap_or(cfg.degree)
            });
            let n = mesh.len() * (most + 1) * (most + 2) / 2;
            tuned = SolveConfig {
                gmres: crate::solve::GmresParams {
                    rel_tol: step_tolerance(cfg.gmres.rel_tol, opts, outcome, n),
                    ..cfg.gmres.clone()
                },
                ..cfg.clone()
            };
            &tuned
        }
        None => cfg,
    };
    let step = (mesh, per_element);
    match solve_step(problem, cfg, step, backend, guess, prev.as_ref()) {
        Ok(step) => Ok(Some(step)),
        Err(Error::Input(e)) if e.is_peak_refusal() && previous.is_some() => Ok(None),
        Err(e) => Err(e),
    }
}

/// The share of the target that the algebraic error (GMRES stopping short
/// of the exact discrete solution) may take at any node of a step after
/// the first.
const ALGEBRAIC_SHARE: f64 = 1e-3;

/// GMRES's relative tolerance for a step on about `n` unknowns after the
/// step that gave `out`: the algebraic error at a node is at most
/// ‖(I − ρK)⁻¹‖∞ ‖r‖∞ ≤ rel_tol ‖E‖₂ / (1 − ρ_max), with ‖E‖₂ at most
/// max |E| √n, so that a tolerance of [`ALGEBRAIC_SHARE`] × target ×
/// scale × (1 − ρ_max) / (max |E| √n) keeps it below that share of the
/// target (the scale of `out`'s channels in the target's norm; the
/// smallest over channels). Never tighter than `asked`, never looser than
/// 1e-6; `asked` where a channel has no estimate, no emission or ρ ≥ 1.
/// (η at the check points counts the algebraic error in any case: it is
/// computed from u_n as solved.) On the Cornell box to 1e-2 of the
/// reflected light about 1e-9 instead of 1e-12.
fn step_tolerance(asked: f64, opts: &AdaptOptions, out: &SolveOutcome, n: usize) -> f64 {
    let mut tol = f64::INFINITY;
    for c in &out.channels {
        let Some(e) = &c.estimate else {
            return asked;
        };
        let rho = c.rho.iter().fold(0.0f64, |m, r| m.max(r.abs()));
        let emission = c.emission.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        if rho >= 1.0 || emission <= 0.0 || !emission.is_finite() {
            return asked;
        }
        let allowed = ALGEBRAIC_SHARE * opts.target * e.scale_of(opts.relative_to);
        tol = tol.min(allowed * (1.0 - rho) / (emission * (n.max(1) as f64).sqrt()));
    }
    if tol.is_finite() {
        tol.min(1e-6).max(asked)
    } else {
        asked
    }
}

/// What a figure relative `to` is relative to max |u_n| in `out`: the
/// smallest ratio of the channels' scales (1 for max |u_n| itself).
fn to_max_u(out: &SolveOutcome, to: RelativeTo) -> f64 {
    let channels = out.channels.iter().filter_map(|c| c.estimate.as_ref());
    channels.fold(1.0, |m, e| m.min(1.0 / e.rescale(to)))
}

/// The diagonal of the bounding box of `mesh`'s surface.
fn diagonal(mesh: &Mesh) -> f64 {
    let (lo, hi) = mesh.surface().bounding_box();
    (hi - lo).length()
}

/// The longest straight edge of element `k` of `mesh`.
fn longest_edge(mesh: &Mesh, k: usize) -> f64 {
    let [a, b, c] = mesh.vertices(k);
    (b - a).length().max((c - b).length()).max((a - c).length())
}

/// What every step solves with: `cfg` with the estimate on, and a
/// visibility budget whose bound is at most a quarter of the target.
fn step_config(problem: &Problem, cfg: &SolveConfig, opts: &AdaptOptions) -> SolveConfig {
    let mut cfg = SolveConfig {
        estimate: true,
        ..cfg.clone()
    };
    let budget = cfg.quad.visibility_budget;
    cfg.quad.visibility_budget = visibility_budget_for(budget, opts.target, problem.rho_bound());
    cfg
}

#[cfg(test)]
mod tests;
