//! Refusals for size that say what would fit: the refinement the run used
//! (flags given or defaulted), and the nearest values whose matrices fit in the memory
//! available (the user was told "use a coarser mesh" and had to find
//! out by trial how much coarser).

use crate::error::{bad_input, with_flags};
use crate::setup::Setup;
use radcol_core::run::{mesh_size, usable, Error as CoreError, InputError, MemoryBudget};

/// The t in (0, 1] where an operator of `operator` bytes growing like N and
/// a pair table of `pair_table` bytes on `elements` elements growing as
/// [`radcol_core::run::pair_table_bytes`], both at t times the size,
/// fill `bytes` (by bisection: both grow with t).
fn shrink_to_fit(operator: f64, pair_table: f64, elements: f64, bytes: f64) -> f64 {
    let b = radcol_core::run::pair_table_bytes;
    let table = |t: f64| pair_table * b(t * elements) / b(elements).max(f64::MIN_POSITIVE);
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..200 {
        let t = 0.5 * (lo + hi);
        if operator * t + table(t) > bytes {
            hi = t;
        } else {
            lo = t;
        }
    }
    lo
}

/// `err` with the CLI's flags named; for a refusal for size, with the
/// refinement that fits.
pub fn sized(err: CoreError, s: &Setup) -> anyhow::Error {
    // Memory grows like N², so the unknowns that fit follow from the ratio.
    let fit = match &err {
        CoreError::Input(InputError::TooLarge {
            bytes_lu,
            bytes_available,
            ..
        }) => {
            let copies = if *bytes_lu > 0.0 { 2.0 } else { 1.0 };
            let budget = MemoryBudget {
                available: Some(*bytes_available),
            };
            budget.largest_dense(copies).unwrap_or(u64::MAX) as f64
        }
        CoreError::Input(InputError::PeakTooLarge {
            to_come,
            matrix,
            available,
            ..
        }) => (matrix / 8.0).sqrt() * (usable(*available) / to_come).sqrt(),
        // The compressed operator's a priori limit: its table of pair classes.
        CoreError::Input(InputError::PairTableTooLarge { available, .. }) => {
            let per_element = radcol_core::run::nodes_per_element(s.cfg.degree) as f64;
            radcol_core::run::pair_table_elements(usable(*available)) * per_element
        }
        // The operator grows like N (its dense blocks near the diagonal),
        // the pair table as pair_table_bytes: the t = N'/N where the two
        // fill what is usable of what is available (by bisection: both grow with t).
        CoreError::Input(InputError::CompressedWontFit {
            unknowns,
            operator,
            pair_table,
            available,
            ..
        }) => {
            let per_element = radcol_core::run::nodes_per_element(s.cfg.degree) as f64;
            let elements = *unknowns as f64 / per_element;
            let t = shrink_to_fit(*operator, *pair_table, elements, usable(*available));
            *unknowns as f64 * t
        }
        _ => return with_flags(err),
    };
    let fit = fit.floor() as u64;
    let cfg = &s.cfg;
    let gave = match cfg.max_edge {
        Some(h) => format!(
            "--level {} --max-edge {h} --degree {}",
            cfg.level, cfg.degree
        ),
        None => format!("--level {} --degree {}", cfg.level, cfg.degree),
    };
    let mut fits = Vec::new();
    if let Some(h) = cfg.max_edge {
        if let Some((h2, n)) = coarsest_edge_that_fits(s, h, fit) {
            fits.push(format!("--max-edge {} ({n} unknowns)", round_up(h2)));
        }
    }
    let unknowns = |level: u32, degree: usize| {
        mesh_size(
            &s.problem.surface,
            level,
            cfg.max_edge,
            cfg.grade.as_ref(),
            degree,
        )
        .unknowns
    };
    if let Some(l) = (0..cfg.level)
        .rev()
        .find(|&l| unknowns(l, cfg.degree) <= fit)
    {
        fits.push(format!(
            "--level {l} ({} unknowns)",
            unknowns(l, cfg.degree)
        ));
    }
    if let Some(r) = (0..cfg.degree)
        .rev()
        .find(|&r| unknowns(cfg.level, r) <= fit)
    {
        fits.push(format!(
            "--degree {r} ({} unknowns)",
            unknowns(cfg.level, r)
        ));
    }
    let advice = if fits.is_empty() {
        format!("no coarser setting of these flags fits {fit} unknowns")
    } else {
        format!("about {fit} unknowns fit: {}", fits.join(", or "))
    };
    bad_input(format!("{err} (this run: {gave}; {advice})")).into()
}

/// The smallest maximum edge length, at least `h`, whose mesh has at most
/// `fit` unknowns (bisection on a log scale: the count falls as the length
/// grows), with its unknowns.
fn coarsest_edge_that_fits(s: &Setup, h: f64, fit: u64) -> Option<(f64, u64)> {
    let cfg = &s.cfg;
    let count = |edge: f64| {
        mesh_size(
            &s.problem.surface,
            cfg.level,
            Some(edge),
            cfg.grade.as_ref(),
            cfg.degree,
        )
        .unknowns
    };
    let (lo_box, hi_box) = s.problem.surface.bounding_box();
    let mut hi = (hi_box - lo_box).length().max(h);
    if count(hi) > fit {
        return None; // the level alone is too fine
    }
    let mut lo = h;
    for _ in 0..40 {
        let mid = (lo * hi).sqrt();
        if count(mid) <= fit {
            hi = mid;
        } else {
            lo = mid;
        }
        if hi / lo < 1.01 {
            break;
        }
    }
    Some((hi, count(hi)))
}

/// `v` rounded up to three significant digits, as typed (a length that
/// still fits).
fn round_up(v: f64) -> String {
    let decimals = (2 - v.log10().floor() as i32).max(0);
    let scale = 10f64.powi(decimals);
    format!("{:.*}", decimals as usize, (v * scale).ceil() / scale)
}

#[cfg(test)]
mod tests {
    use super::round_up;

    #[test]
    fn lengths_round_up_to_three_digits() {
        assert_eq!(round_up(95.04), "95.1");
        assert_eq!(round_up(0.012341), "0.0124");
        assert_eq!(round_up(1200.0), "1200");
        assert_eq!(round_up(1234.5), "1235");
    }
}
