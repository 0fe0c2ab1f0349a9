//! `radcol study --degrees A..B [--adaptive TOL]`: one study per degree (and
//! its adaptive run), then the fastest setting for each decade of error.

use super::{sci, AdaptReport, StudyReport};
use radcol_core::study::{speed::DecadeBest, speed::Setting};
use serde::Serialize;
use std::fmt;

/// One degree's part of a comparison.
#[derive(Clone, Debug, Serialize)]
pub struct DegreePart {
    /// Its uniform study.
    #[serde(flatten)]
    pub study: StudyReport,
    /// Its adaptive run, when asked for.
    pub adaptive: Option<AdaptReport>,
}

/// The decades and who reaches them first (printed after the degrees' tables).
#[derive(Clone, Debug, Serialize)]
pub struct Fastest {
    /// Every setting compared.
    pub settings: Vec<Setting>,
    /// Per decade, the fastest setting and the one with the fewest unknowns.
    pub fastest: Vec<DecadeBest>,
}

/// Everything the comparison reports (JSON).
#[derive(Clone, Debug, Serialize)]
pub struct ComparisonReport {
    /// `"study"`.
    pub command: &'static str,
    /// Each degree's study and adaptive run.
    pub degrees: Vec<DegreePart>,
    /// The ranking.
    #[serde(flatten)]
    pub fastest: Fastest,
    /// The SVG written with `--plot`.
    pub plot: Option<String>,
}

impl fmt::Display for ComparisonReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for part in &self.degrees {
            write!(f, "{}", part.study)?;
            if let Some(a) = &part.adaptive {
                write!(f, "{a}")?;
            }
            writeln!(f)?;
        }
        write!(f, "{}", self.fastest)
    }
}

fn describe(s: &Setting) -> String {
    format!(
        "r = {}, {} ({} unknowns): {:.2} s, error {}{}",
        s.degree,
        s.refinement,
        s.unknowns,
        s.seconds,
        sci(s.error),
        if s.estimated { " (estimated)" } else { "" }
    )
}

impl fmt::Display for Fastest {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "fastest setting per decade of error (global max / max |u_n|; wall seconds of the level, or of every adaptive step up to that one):"
        )?;
        if self.fastest.is_empty() {
            return writeln!(f, "  (no setting has a finite error)");
        }
        for d in &self.fastest {
            writeln!(f, "  <= 1e{:<4} {}", d.exponent, describe(&d.fastest))?;
            if d.fewest_unknowns.unknowns < d.fastest.unknowns {
                writeln!(
                    f,
                    "  {:8} fewest unknowns: {}",
                    "",
                    describe(&d.fewest_unknowns)
                )?;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use radcol_core::study::{speed::fastest_per_decade, speed::Refinement};

    /// The table names the fastest setting of each decade, and the one with
    /// the fewest unknowns only where it has fewer.
    #[test]
    fn table_names_the_fastest_per_decade() {
        let s = |degree, refinement, unknowns, seconds, error| Setting {
            degree,
            refinement,
            unknowns,
            seconds,
            error,
            estimated: false,
        };
        let settings = vec![
            s(1, Refinement::Uniform { level: 2 }, 384, 0.5, 4e-3),
            s(2, Refinement::Adaptive { step: 3 }, 300, 0.9, 6e-3),
        ];
        let fastest = fastest_per_decade(&settings);
        let text = Fastest { settings, fastest }.to_string();
        assert!(
            text.contains("<= 1e-2   r = 1, uniform level 2 (384 unknowns): 0.50 s"),
            "{text}"
        );
        assert!(
            text.contains("fewest unknowns: r = 2, adaptive step 3 (300 unknowns)"),
            "{text}"
        );
        assert_eq!(text.lines().count(), 3, "{text}");
    }
}
