//! Reports: one `#[derive(Serialize)]` struct per command, JSON from serde
//! and text from `Display` of the same struct, so both list the same fields.
//! Pure formatting: every number comes from core.

mod adapt;
mod channel;
mod compare;
mod info;
mod nodes;
mod operator;
mod points;
mod solve;
mod study;
mod trust;

pub use adapt::{AdaptLine, AdaptReport};
pub use compare::{ComparisonReport, DegreePart, Fastest};
pub use info::{
    BoundingBox, CompressedInfo, ElementSize, Estimate, InfoReport, MaterialInfo, SceneInfo,
    ShapeRatio,
};
pub use nodes::NodesReport;
pub use points::{PointChannel, PointLine, PointsReport};
pub use solve::{SolveReport, Written};
pub use study::{StudyFooter, StudyHeader, StudyLine, StudyReport};
pub use trust::untrusted;

use serde::Serialize;
use std::fmt::Display;
use std::io::Write;

/// Writes `report` to `w`: pretty JSON when `json`, else its text.
pub fn emit<T: Serialize + Display>(
    w: &mut dyn Write,
    report: &T,
    json: bool,
) -> anyhow::Result<()> {
    if json {
        // Rendered first so that a closed stdout surfaces as a plain io::Error.
        let text = serde_json::to_string_pretty(&serde_json::to_value(report)?)?;
        writeln!(w, "{text}")?;
    } else {
        write!(w, "{report}")?;
    }
    Ok(())
}

/// `1.234e-5`: errors, residuals, counts per second.
fn sci(v: f64) -> String {
    format!("{v:.3e}")
}

/// Elements per degree (index: the degree) as `88 of r = 1, 40 of r = 2`,
/// the degrees no element has left out.
fn by_degree(counts: &[usize]) -> String {
    let used = counts.iter().enumerate().filter(|(_, &n)| n > 0);
    let text: Vec<String> = used.map(|(r, n)| format!("{n} of r = {r}")).collect();
    text.join(", ")
}

/// 13 significant digits: fixed-point for everyday magnitudes, scientific
/// beyond them (an integral of 1e300 is not 300 digits long).
fn precise(v: f64) -> String {
    if v == 0.0 || (1e-3..1e12).contains(&v.abs()) {
        format!("{v:.12}")
    } else {
        format!("{v:.12e}")
    }
}

/// Seconds with a sensible number of digits.
fn secs(v: f64) -> String {
    if v >= 100.0 {
        format!("{v:.1} s")
    } else if v >= 0.01 {
        format!("{v:.3} s")
    } else {
        format!("{:.3} ms", v * 1e3)
    }
}

/// "α = 0.1666 (auto)", or why α does not matter.
fn alpha_text(alpha: f64, auto: bool, degree: usize) -> String {
    match (auto, degree) {
        (_, 0) => "α unused (r = 0: the centroid node)".into(),
        (true, _) => format!("α = {alpha} (auto)"),
        (false, _) => format!("α = {alpha}"),
    }
}

/// The problem as given: ρ, E and u (texts).
#[derive(Clone, Debug, Serialize)]
pub struct ProblemText {
    /// ρ.
    pub rho: String,
    /// E.
    pub emission: String,
    /// u, when known.
    pub exact: Option<String>,
}

impl ProblemText {
    /// The texts of `s`.
    pub fn of(s: &crate::setup::Setup) -> Self {
        Self {
            rho: s.rho.clone(),
            emission: s.emission.clone(),
            exact: s.exact.clone(),
        }
    }
}
