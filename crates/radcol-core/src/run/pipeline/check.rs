//! The estimate stage of a solve: the check points, their plan, the
//! residual there (computed, or updated from the previous adaptive step's),
//! the shadow probes, and the approximate-visibility bound; over ranks each
//! rank estimates its own elements.

use super::super::inputs::fields;
use super::super::probes;
use super::super::{ChannelResult, SolveConfig};
use super::Previous;
use crate::assembly::{AssemblyPlan, QuadratureOptions};
use crate::discretization::Discretization;
use crate::error::Error;
use crate::estimate::{
    check_discretization, estimate_shared, estimate_updated, ChannelFields, ErrorEstimate,
    ESTIMATE_QUAD_TOL,
};
use crate::problem::Problem;
use crate::visibility::VisibilityAnalysis;
use std::sync::Arc;

/// Estimates every channel's error at the check points of its mesh
/// ([`crate::estimate`]), with the solve's quadrature and visibility, or
/// updates `previous`'s estimate where it allows and that pays ([`update`]);
/// returns the check points' plan.
pub(super) fn estimate_channels(
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
    let owned = share.as_ref().map(|(_, _, o)| o.as_slice());
    let plan = check_plan(disc, &check, (&quad, visibility, square), previous, owned);
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
    // Over ranks, each finds and evaluates its own elements' probes.
    let ranks = share.as_ref().map(|(r, _, _)| *r);
    let mut found = probes::find(square, &check, &probes::emitting(disc, channels), owned);
    let mut etas = probes::etas(&found, (disc, &quad, visibility), problem, channels);
    if let Some(ranks) = ranks {
        (found, etas) = probes::gather(ranks, (&found, &etas), channels.len());
    }
    probes::add(&found, &etas, &mut estimates);
    // Approximate visibility: the most the residual at a node or check
    // point can have moved, per unit of ρ max|u| (0 when exact).
    let mut mass = [(square.stats().visibility_bound).max(plan.stats().visibility_bound)];
    if let Some(ranks) = ranks {
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

/// The plan of the check points `check` against `disc`'s basis: of the
/// elements `owned` alone in a solve spread over ranks, else taking what
/// `previous`'s check plan has for unchanged elements; both take the
/// pairs `square` (the solve's plan) searched.
fn check_plan(
    disc: &Arc<Discretization>,
    check: &Arc<Discretization>,
    (quad, visibility, square): (&QuadratureOptions, &VisibilityAnalysis, &AssemblyPlan),
    previous: Option<&Previous<'_>>,
    owned: Option<&[bool]>,
) -> AssemblyPlan {
    match owned {
        Some(owned) => AssemblyPlan::of_rows(
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
    }
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
