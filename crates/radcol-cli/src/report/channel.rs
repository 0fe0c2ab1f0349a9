//! One channel's estimate and limiter lines of the `radcol solve` report.

use super::sci;
use radcol_core::run::{ErrorEstimate, Limited, RelativeTo};
use serde::Serialize;
use std::fmt;

/// The scale a channel's relative figures divide by, and its name: the
/// reflected light (max over the nodes of u_n − E), or max |u_n| where
/// nothing is reflected.
pub(super) fn norm(e: &ErrorEstimate) -> (f64, &'static str) {
    match norm_of(e) {
        RelativeTo::Reflected => (e.reflected_scale, "of the reflected light"),
        RelativeTo::MaxU => (e.scale.max(f64::MIN_POSITIVE), "of max|u|"),
    }
}

/// Which norm a channel's figures read in: the reflected light, or max
/// |u_n| where nothing is reflected.
fn norm_of(e: &ErrorEstimate) -> RelativeTo {
    if e.reflected_scale > 0.0 {
        RelativeTo::Reflected
    } else {
        RelativeTo::MaxU
    }
}

/// One channel's estimate relative to the norm the report reads in.
#[derive(Clone, Debug, Serialize)]
pub struct RelativeFigures {
    /// `reflected` (max over the nodes of u_n − E) or `max_u` (where
    /// nothing is reflected).
    relative_to: RelativeTo,
    /// The scale divided by.
    scale: f64,
    /// Estimated max error of u_n.
    max: f64,
    /// Root mean square of the estimate.
    rms: f64,
    /// Estimated max error of what is shown (the limiter's change included).
    shown: f64,
}

impl RelativeFigures {
    pub(super) fn new(e: &ErrorEstimate) -> Self {
        let to = norm_of(e);
        let factor = e.rescale(to);
        Self {
            relative_to: to,
            scale: e.scale_of(to),
            max: e.max_rel * factor,
            rms: e.rms_rel * factor,
            shown: e.shown_max_rel() * factor,
        }
    }
}

/// The estimate's line(s) of one channel: relative to the reflected light
/// (max |u| where nothing is reflected), with the absolute figure and the
/// one relative to max |u| beside it.
pub(super) fn fmt_estimate(
    f: &mut fmt::Formatter<'_>,
    e: &ErrorEstimate,
    eff: Option<f64>,
) -> fmt::Result {
    let (scale, of) = norm(e);
    let updated = |b: f64| {
        let rel = sci(b / scale);
        format!("; updated from the previous step's, within {rel} {of} of the computed one")
    };
    let rms = e.rms_rel * e.rescale(RelativeTo::Reflected);
    writeln!(
        f,
        "              estimated error: max {} {of}, rms {}{}{}",
        sci(e.max / scale),
        sci(rms),
        eff.map(|x| format!(" (estimate / true global max = {x:.2})"))
            .unwrap_or_default(),
        e.updated_within.map(updated).unwrap_or_default()
    )?;
    let reflected = match e.max_rel_reflected() {
        Some(_) => format!(
            "reflected light max(u_n - E) = {} at the nodes; ",
            sci(e.reflected_scale)
        ),
        None => String::new(),
    };
    writeln!(
        f,
        "              {reflected}absolute max {}, or {} of max|u| = {}",
        sci(e.max),
        sci(e.max_rel),
        sci(e.scale)
    )?;
    if e.visibility_bound > 0.0 {
        writeln!(
            f,
            "              of which approximate visibility: at most {} {of} (bound, included)",
            sci(e.visibility_bound / scale)
        )?;
    }
    let negative = e.negative_nodes + e.negative_points;
    if negative > 0 {
        writeln!(
            f,
            "              negative u_n at {} nodes and {} lattice points (min {}){}",
            e.negative_nodes,
            e.negative_points,
            sci(e.min_value),
            if e.nonnegative_problem {
                ": unphysical (E, ρ ≥ 0), counted as error"
            } else {
                ""
            }
        )?;
    }
    Ok(())
}

/// The limiter's line of one channel: what it changed, and the estimated
/// error of what is shown (`shown`, [`ErrorEstimate::shown_max_rel`]).
pub(super) fn fmt_limited(
    f: &mut fmt::Formatter<'_>,
    l: &Limited,
    estimate: Option<&ErrorEstimate>,
    shown: Option<f64>,
) -> fmt::Result {
    // `shown` is relative to max |u|, as `ErrorEstimate::shown_max_rel`.
    let shown = shown
        .zip(estimate)
        .map(|(m, e)| {
            let of = norm(e).1;
            let m = m * e.rescale(RelativeTo::Reflected);
            format!("; estimated error of what is shown: max {} {of}", sci(m))
        })
        .unwrap_or_default();
    let relative = estimate
        .filter(|e| e.scale > 0.0)
        .map(|e| {
            let (s, of) = norm(e);
            format!(" = {} {of}", sci(l.max_change / s))
        })
        .unwrap_or_default();
    let (s, its) = if l.elements == 1 {
        ("", "its")
    } else {
        ("s", "their")
    };
    writeln!(
        f,
        "              limited: {} element{s} scaled towards {its} mean{s} to show no u < 0 ({} set to 0); largest change {}{relative}{shown} (--keep-negative shows u_n as computed)",
        l.elements,
        l.zeroed,
        sci(l.max_change),
    )
}
