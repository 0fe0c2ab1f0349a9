//! One channel's estimate and limiter lines of the `radcol solve` report.

use super::sci;
use radcol_core::run::{ErrorEstimate, Limited};
use std::fmt;

/// The estimate's line(s) of one channel.
pub(super) fn fmt_estimate(
    f: &mut fmt::Formatter<'_>,
    e: &ErrorEstimate,
    eff: Option<f64>,
) -> fmt::Result {
    let updated = |b: f64| {
        let rel = sci(b / e.scale.max(f64::MIN_POSITIVE));
        format!("; updated from the previous step's, within {rel} of max|u| of the computed one")
    };
    writeln!(
        f,
        "              estimated error: max {} of max|u| = {}, rms {}{}{}",
        sci(e.max_rel),
        sci(e.scale),
        sci(e.rms_rel),
        eff.map(|x| format!(" (estimate / true global max = {x:.2})"))
            .unwrap_or_default(),
        e.updated_within.map(updated).unwrap_or_default()
    )?;
    if let Some(rel) = e.max_rel_reflected() {
        writeln!(
            f,
            "              relative to the reflected light: max {} of max(u_n - E) = {} at the nodes",
            sci(rel),
            sci(e.reflected_scale)
        )?;
    }
    if e.visibility_bound > 0.0 {
        writeln!(
            f,
            "              of which approximate visibility: at most {} of max|u| (bound, included)",
            sci(e.visibility_bound / e.scale.max(f64::MIN_POSITIVE))
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
    let shown = shown
        .map(|m| format!("; estimated error of what is shown: max {}", sci(m)))
        .unwrap_or_default();
    let relative = estimate
        .map(|e| e.scale)
        .filter(|&s| s > 0.0)
        .map(|s| format!(" = {} of max|u|", sci(l.max_change / s)))
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
