//! Numbers and ranges from their text: the degree (and its default with a
//! target), α, `A..B` ranges, values in (0, 1).

use super::AlphaSpec;
use crate::error::{bad_input, BadInput};
use radcol_core::run::{check_alpha, check_degree};
use std::ops::RangeInclusive;

/// `--degree R` in 0..=6 (the range is core's).
pub(super) fn degree(r: usize) -> Result<usize, BadInput> {
    check_degree(r).map_err(|e| bad_input(format!("--degree {r}: {e}")))
}

/// `auto` or a number in (0, 1/3).
pub fn parse_alpha(text: &str) -> Result<AlphaSpec, BadInput> {
    let text = text.trim();
    if text.eq_ignore_ascii_case("auto") {
        return Ok(AlphaSpec::Auto);
    }
    let value: f64 = text
        .parse()
        .map_err(|_| bad_input(format!("--alpha '{text}' is neither a number nor 'auto'")))?;
    check_alpha(value).map_err(|e| bad_input(format!("--alpha {text}: {e}")))?;
    Ok(AlphaSpec::Value(value))
}

pub(super) fn open_unit(name: &str, v: f64) -> Result<f64, BadInput> {
    if !(v > 0.0 && v < 1.0) {
        return Err(bad_input(format!(
            "{name} {v}: must lie strictly between 0 and 1"
        )));
    }
    Ok(v)
}

/// `A..B` or `A..=B`, both inclusive, A <= B.
pub fn parse_levels(text: &str) -> Result<RangeInclusive<u32>, BadInput> {
    parse_range("--levels", text, "a level")
}

/// `A..B` or `A..=B` (inclusive) of whole numbers for `flag`; `what` names
/// one of them in messages.
pub(super) fn parse_range(
    flag: &str,
    text: &str,
    what: &str,
) -> Result<RangeInclusive<u32>, BadInput> {
    let t = text.trim();
    let (a, b) = t
        .split_once("..=")
        .or_else(|| t.split_once(".."))
        .ok_or_else(|| {
            bad_input(format!(
                "{flag} '{t}': expected A..B (inclusive), e.g. 0..3"
            ))
        })?;
    let number = |s: &str| {
        s.trim().parse::<u32>().map_err(|_| {
            bad_input(format!(
                "{flag} '{t}': '{}' is not {what} (a whole number >= 0); expected A..B, e.g. 0..3",
                s.trim()
            ))
        })
    };
    let (a, b) = (number(a)?, number(b)?);
    if a > b {
        return Err(bad_input(format!(
            "{flag} '{t}': the first {} {a} is greater than the last {b}",
            what.trim_start_matches("a ")
        )));
    }
    Ok(a..=b)
}
