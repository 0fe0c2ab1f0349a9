//! `radcol solve --target-error`: the adaptive loop's steps and why it stopped.

use super::{sci, secs};
use radcol_core::run::{
    adapt::AdaptOptions, adapt::AdaptOutcome, adapt::AdaptStep, adapt::SingularPoint,
    adapt::StopReason, OperatorKind, RelativeTo,
};
use serde::Serialize;
use std::fmt;

/// The loop as run.
#[derive(Clone, Debug, Serialize)]
pub struct AdaptReport {
    /// Target of the estimated max error relative to the reflected light,
    /// or to max |u| (`relative_to`).
    target: f64,
    /// What the target and the steps' figures are relative to.
    relative_to: RelativeTo,
    /// The unknowns budget, when given.
    max_unknowns: Option<u64>,
    /// The degree, when the target chose it (`--degree` not given).
    default_degree: Option<usize>,
    /// The estimate reached of what is shown (worst channel, relative
    /// max; the figure the loop stops on, [`AdaptStep::estimate_shown`]).
    reached_estimate: f64,
    /// Why it stopped.
    stop: StopReason,
    /// Every step.
    steps: Vec<AdaptStep>,
    /// Where the estimate stayed above the target because refinement
    /// stopped reducing it or the elements reached the size floor (largest
    /// first).
    singular_points: Vec<SingularPoint>,
}

impl AdaptReport {
    /// The report of `res`, run with `opts`; `default_degree`: the degree
    /// when the target chose it.
    pub fn new(opts: &AdaptOptions, res: &AdaptOutcome, default_degree: Option<usize>) -> Self {
        Self {
            target: opts.target,
            relative_to: opts.relative_to,
            max_unknowns: opts.max_unknowns,
            default_degree,
            reached_estimate: res.steps.last().map_or(f64::NAN, |s| s.estimate_shown),
            stop: res.stop,
            steps: res.steps.clone(),
            singular_points: res.singular.clone(),
        }
    }

    /// Whether the target was reached: everywhere, or everywhere but the
    /// neighbourhoods of the singular points the report names (refinement
    /// does not lower the error there, so no budget would reach it).
    pub fn reached(&self) -> bool {
        matches!(self.stop, StopReason::Reached | StopReason::Singular)
    }

    /// One sentence: what was reached and why the loop stopped.
    pub fn summary(&self) -> String {
        let elsewhere = match self.steps.last() {
            Some(s) if !self.singular_points.is_empty() => format!(
                " ({} away from the {} point{} below)",
                sci(s.estimate_elsewhere),
                self.singular_points.len(),
                if self.singular_points.len() == 1 {
                    ""
                } else {
                    "s"
                }
            ),
            _ => String::new(),
        };
        let flag = match self.stop {
            StopReason::MaxSteps => " (--max-steps)",
            StopReason::MaxUnknowns => " (--max-unknowns)",
            _ => "",
        };
        let of = match self.relative_to {
            RelativeTo::MaxU => " of max|u|",
            RelativeTo::Reflected => " of the reflected light",
        };
        format!(
            "estimated error {}{elsewhere} against the target {}{of} after {} steps: {}{flag}",
            sci(self.reached_estimate),
            sci(self.target),
            self.steps.len(),
            self.stop
        )
    }
}

/// One step as a line of text.
pub struct AdaptLine<'a>(pub &'a AdaptStep);

impl fmt::Display for AdaptLine<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = self.0;
        write!(
            f,
            "  step        {:7} elements {:8} unknowns  estimate max {} rms {}{}{}  {}{}",
            s.elements,
            s.unknowns,
            sci(s.estimate),
            sci(s.estimate_rms),
            if s.estimate_shown > s.estimate {
                format!(", shown max {}", sci(s.estimate_shown))
            } else {
                String::new()
            },
            s.true_error
                .map(|e| format!("  true {}", sci(e)))
                .unwrap_or_default(),
            secs(s.seconds),
            if s.split > 0 {
                format!(", split {}", s.split)
            } else {
                String::new()
            }
        )?;
        if s.negative_elements > 0 {
            write!(f, ", {} with u < 0", s.negative_elements)?;
        }
        if s.singular_elements > 0 {
            write!(
                f,
                ", {} no longer split (elsewhere {})",
                s.singular_elements,
                sci(s.estimate_elsewhere)
            )?;
        }
        if let Some(b) = s.estimate_updated_within {
            write!(f, ", estimate updated (within {})", sci(b))?;
        }
        if s.degrees.iter().filter(|&&n| n > 0).count() > 1 {
            write!(f, ", elements {}", super::by_degree(&s.degrees))?;
        }
        let t = &s.timings;
        write!(
            f,
            " [{} operator {}, solve {}, estimate {}]",
            match s.operator {
                OperatorKind::Dense => "dense",
                OperatorKind::Compressed => "compressed",
            },
            secs(t.assembly_s),
            secs(t.solve_s),
            secs(t.estimate_s)
        )?;
        Ok(())
    }
}

impl fmt::Display for AdaptReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "  adaptive    target {} (max error {}, estimated){}{}",
            sci(self.target),
            match self.relative_to {
                RelativeTo::MaxU => "/ max |u|",
                RelativeTo::Reflected => "relative to the reflected light",
            },
            self.max_unknowns
                .map(|m| format!(", at most {m} unknowns"))
                .unwrap_or_default(),
            self.default_degree
                .map(|r| format!(", r = {r}: the default with a target (--degree R sets it)"))
                .unwrap_or_default()
        )?;
        for s in &self.steps {
            writeln!(f, "{}", AdaptLine(s))?;
        }
        writeln!(f, "  stopped     {}", self.summary())?;
        for p in &self.singular_points {
            let [x, y, z] = p.position;
            writeln!(
                f,
                "  singular    ({x:.6}, {y:.6}, {z:.6}) within {:.3e}: {} element{}{}, estimate up to {}",
                p.radius,
                p.elements,
                if p.elements == 1 { "" } else { "s" },
                match p.smallest {
                    0 => String::new(),
                    n if n == p.elements => " (all at the smallest size split)".into(),
                    n => format!(" ({n} at the smallest size split)"),
                },
                sci(p.estimate)
            )?;
        }
        Ok(())
    }
}
