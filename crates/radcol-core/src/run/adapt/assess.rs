//! What a solve tells the adaptive loop: each element's indicator (the
//! worst channel's estimate relative to its max |u_n|), the step as
//! reported, whether to stop, which elements to split (worst first, within
//! the budget) and where the error stays on elements no longer split.

use super::budget::budget;
use super::history::{singular_points, History, SingularPoint};
use super::{longest_edge, AdaptOptions, AdaptStep, StopReason};
use crate::estimate::RelativeTo;
use crate::run::{SolveConfig, SolveOutcome};

/// What a solve tells the loop: the step as reported, whether to stop,
/// the elements to split (worst first), every element's indicator and
/// negative flag, and where the error stays.
pub(super) struct Assessment {
    pub(super) step: AdaptStep,
    pub(super) stop: Option<StopReason>,
    pub(super) marked: Vec<usize>,
    pub(super) indicator: Vec<f64>,
    pub(super) negative: Vec<bool>,
    pub(super) singular: Vec<SingularPoint>,
}

/// The assessment of `out`, the `step_no`-th step, given the elements'
/// estimate `history`; `floor`: the smallest size split. `seconds` is
/// left at 0.
pub(super) fn assess(
    out: &SolveOutcome,
    history: &History,
    (cfg, opts, floor): (&SolveConfig, &AdaptOptions, f64),
    step_no: usize,
) -> Assessment {
    let (indicator, negative) = indicators(out, opts.relative_to);
    let stalls = history.stalls(&indicator);
    let smallest = |k: usize| longest_edge(out.discretization.mesh(), k) < floor;
    let frozen = |k: usize| smallest(k) || History::stalled(k, &stalls, opts.stall_generations);
    let mut step = describe(out, &indicator, &negative, &frozen, opts);
    let marking = Marking {
        indicator: &indicator,
        frozen: &frozen,
        // One more stalled split freezes these.
        stalling: &|k| stalls[k] > 0 && stalls[k] + 1 >= opts.stall_generations,
    };
    let shown = step.estimate_shown;
    let disc = &out.discretization;
    // Splitting element k adds at most 3 f_{r_k} unknowns (a raise or a
    // lowering adds fewer).
    let grows = |k: usize| 3 * disc.nodes_per(k);
    let size: (_, _, &dyn Fn(usize) -> usize) = (disc.mesh().len(), disc.len(), &grows);
    let (stop, mut marked, split) = decide(opts, cfg, (shown, step_no), &marking, size);
    step.split = split;
    marked.truncate(split);
    let left: Vec<usize> = (0..indicator.len())
        .filter(|&k| frozen(k) && indicator[k] > opts.target)
        .collect();
    let singular = singular_points(disc.mesh(), &left, &indicator, &smallest);
    Assessment {
        step,
        stop,
        marked,
        indicator,
        negative,
        singular,
    }
}

/// What marking knows of each element: its `indicator`, whether it is
/// `frozen` (not split any more), and whether it is `stalling`: one more
/// split that does not lower its estimate below [`super::STALL_RATIO`] of its
/// parent's would freeze it.
pub(super) struct Marking<'a> {
    pub(super) indicator: &'a [f64],
    pub(super) frozen: &'a dyn Fn(usize) -> bool,
    pub(super) stalling: &'a dyn Fn(usize) -> bool,
}

/// Whether the loop stops after its `step`-th step (estimate `estimate`),
/// the elements marked for splitting (worst first) and how many of them the
/// budget lets split. Marked: the splittable elements above both
/// `mark_fraction · target` and `max_fraction` of the worst splittable
/// element that is not stalling. Stalling elements above that are split in
/// the same step: measured against the worst of them, steps split only the
/// few on their way to being frozen (on the Cornell box to 1e-4, steps of
/// 2, 50 and 71 of 12 600 elements, two minutes each; to 1e-3, 12 steps
/// against 11 now, to the same mesh). Setting aside every element whose
/// last split stalled went too far: the shadow family's square occluder
/// took 18 117 unknowns to 1e-3 instead of 12 339.
/// `size`: the mesh's elements and unknowns, and how many unknowns
/// splitting element k adds at most.
pub(super) fn decide(
    opts: &AdaptOptions,
    cfg: &SolveConfig,
    (estimate, step): (f64, usize),
    m: &Marking<'_>,
    size: (usize, usize, &dyn Fn(usize) -> usize),
) -> (Option<StopReason>, Vec<usize>, usize) {
    let stop = if estimate <= opts.target {
        Some(StopReason::Reached)
    } else if step >= opts.max_steps {
        Some(StopReason::MaxSteps)
    } else {
        None
    };
    let marked = match stop {
        Some(_) => Vec::new(),
        None => {
            let set_aside = |k: usize| (m.frozen)(k) || (m.stalling)(k);
            let worst = match splittable_max(m.indicator, &set_aside) {
                w if w > 0.0 => w,
                _ => splittable_max(m.indicator, m.frozen),
            };
            let threshold = (opts.mark_fraction * opts.target).max(opts.max_fraction * worst);
            mark(m.indicator, threshold, m.frozen)
        }
    };
    let stop = stop.or((marked.is_empty()).then_some(StopReason::Singular));
    let (elements, unknowns, grows) = size;
    let growth: Vec<usize> = marked.iter().map(|&k| grows(k)).collect();
    let budget = budget(opts, cfg, (elements, unknowns), &growth);
    let stop = stop.or(budget.err());
    let split = budget.map_or(0, |n| n.min(marked.len()));
    (stop, marked, split)
}

/// The step of `out` (its element `indicator`s, where u_n is `negative`,
/// which elements are `frozen`); `seconds` is left at 0.
fn describe(
    out: &SolveOutcome,
    indicator: &[f64],
    negative: &[bool],
    frozen: &dyn Fn(usize) -> bool,
    opts: &AdaptOptions,
) -> AdaptStep {
    let to = opts.relative_to;
    let (estimate, estimate_rms, estimate_shown) = worst(out, to);
    let threshold = opts.mark_fraction * opts.target;
    AdaptStep {
        elements: indicator.len(),
        unknowns: out.discretization.len(),
        estimate,
        estimate_shown,
        estimate_rms,
        true_error: out.channels.first().and_then(|c| {
            let scale = c.estimate.as_ref().map_or(1.0, |x| x.scale_of(to));
            c.errors.map(|e| e.global_max / scale)
        }),
        split: 0,
        negative_elements: negative.iter().filter(|&&b| b).count(),
        singular_elements: (0..indicator.len())
            .filter(|&k| frozen(k) && indicator[k] > threshold)
            .count(),
        // Approximate visibility's bound holds at every point, the
        // splittable elements' included.
        estimate_elsewhere: splittable_max(indicator, frozen) + visibility_bound(out, to),
        seconds: 0.0,
        estimate_updated_within: out
            .channels
            .iter()
            .filter_map(|c| c.estimate.as_ref())
            .filter_map(|e| {
                e.updated_within
                    .map(|b| b / e.scale_of(to).max(f64::MIN_POSITIVE))
            })
            .reduce(f64::max),
        timings: out.timings,
        operator: out.operator.kind(),
        degrees: out.discretization.elements_per_degree(),
    }
}

/// Per element, the worst channel's estimate relative `to` its max |u_n|
/// or its reflected light, and whether some channel has unphysical
/// negative values on it.
fn indicators(out: &SolveOutcome, to: RelativeTo) -> (Vec<f64>, Vec<bool>) {
    let n = out.discretization.mesh().len();
    let mut ind = vec![0.0f64; n];
    let mut negative = vec![false; n];
    for e in out.channels.iter().filter_map(|c| c.estimate.as_ref()) {
        let f = e.rescale(to);
        for (i, v) in ind.iter_mut().zip(e.elements_rel()) {
            *i = i.max(v * f);
        }
        for (a, &b) in negative.iter_mut().zip(&e.negative) {
            *a |= b;
        }
    }
    (ind, negative)
}

/// The worst channel's max and rms estimates of u_n, and its max estimate
/// of what is shown, relative `to`.
fn worst(out: &SolveOutcome, to: RelativeTo) -> (f64, f64, f64) {
    out.channels
        .iter()
        .filter_map(|c| c.estimate.as_ref())
        .fold((0.0f64, 0.0f64, 0.0f64), |(m, r, s), e| {
            let f = e.rescale(to);
            let (max, rms, shown) = (e.max_rel * f, e.rms_rel * f, e.shown_max_rel() * f);
            (m.max(max), r.max(rms), s.max(shown))
        })
}

/// The worst channel's bound of approximate visibility, relative `to` (0
/// when every pair is exact).
fn visibility_bound(out: &SolveOutcome, to: RelativeTo) -> f64 {
    let channels = out.channels.iter().filter_map(|c| c.estimate.as_ref());
    channels.fold(0.0, |m, e| {
        m.max(e.visibility_bound / e.scale_of(to).max(f64::MIN_POSITIVE))
    })
}

/// The largest `indicator` of an element that is not `frozen` (0 if none).
fn splittable_max(indicator: &[f64], frozen: &dyn Fn(usize) -> bool) -> f64 {
    (0..indicator.len())
        .filter(|&k| !frozen(k))
        .fold(0.0f64, |m, k| m.max(indicator[k]))
}

/// The elements above `threshold` that may still be split (not `frozen`), worst first.
/// (Negative u_n is part of the indicator, as |u_n|; splitting an element
/// only because it has some does not remove them: on the Cornell box the
/// elements with u_n < 0 sit at the feet of the blocks, where 10 splits of
/// each left 32 of 37 negative.)
pub(super) fn mark(
    indicator: &[f64],
    threshold: f64,
    frozen: &dyn Fn(usize) -> bool,
) -> Vec<usize> {
    let mut marked: Vec<usize> = (0..indicator.len())
        .filter(|&k| indicator[k] > threshold && !frozen(k))
        .collect();
    marked.sort_by(|&a, &b| indicator[b].total_cmp(&indicator[a]));
    marked
}
