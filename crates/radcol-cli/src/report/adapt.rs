//! `radcol solve --target-error`: the adaptive loop's steps and why it stopped.

use super::{sci, secs};
use radcol_core::run::adapt::{AdaptOptions, AdaptOutcome, AdaptStep, StopReason};
use serde::Serialize;
use std::fmt;

/// The loop as run.
#[derive(Clone, Debug, Serialize)]
pub struct AdaptReport {
    /// Target of the estimated max error relative to max |u|.
    target: f64,
    /// The unknowns budget, when given.
    max_unknowns: Option<u64>,
    /// The estimate reached (worst channel, relative max).
    reached_estimate: f64,
    /// Why it stopped.
    stop: StopReason,
    /// Every step.
    steps: Vec<AdaptStep>,
}

impl AdaptReport {
    /// The report of `res`, run with `opts`.
    pub fn new(opts: &AdaptOptions, res: &AdaptOutcome) -> Self {
        Self {
            target: opts.target,
            max_unknowns: opts.max_unknowns,
            reached_estimate: res.steps.last().map_or(f64::NAN, |s| s.estimate),
            stop: res.stop,
            steps: res.steps.clone(),
        }
    }

    /// Whether the target was reached.
    pub fn reached(&self) -> bool {
        self.stop == StopReason::Reached
    }

    /// One sentence: what was reached and why the loop stopped.
    pub fn summary(&self) -> String {
        let elsewhere = match self.steps.last() {
            Some(s) if s.at_depth_limit > 0 => format!(
                " ({} away from the {} elements at the depth limit)",
                sci(s.estimate_elsewhere),
                s.at_depth_limit
            ),
            _ => String::new(),
        };
        format!(
            "estimated error {}{elsewhere} against the target {} after {} steps: {}",
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
            "  step        {:7} elements {:8} unknowns  estimate max {} rms {}{}  {}{}",
            s.elements,
            s.unknowns,
            sci(s.estimate),
            sci(s.estimate_rms),
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
        if s.at_depth_limit > 0 {
            write!(
                f,
                ", {} at the depth limit (elsewhere {})",
                s.at_depth_limit,
                sci(s.estimate_elsewhere)
            )?;
        }
        Ok(())
    }
}

impl fmt::Display for AdaptReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "  adaptive    target {} (max error / max |u|, estimated){}",
            sci(self.target),
            self.max_unknowns
                .map(|m| format!(", at most {m} unknowns"))
                .unwrap_or_default()
        )?;
        for s in &self.steps {
            writeln!(f, "{}", AdaptLine(s))?;
        }
        writeln!(f, "  stopped     {}", self.summary())
    }
}

/// Warnings about the trustworthiness of a solve: ill-conditioned
/// interpolation (the Lebesgue constant of the nodes), an inaccurate linear
/// solve (the true residual), and a large estimated error. Each says what to
/// change.
pub fn solve_warnings(
    s: &crate::setup::Setup,
    out: &radcol_core::run::SolveOutcome,
) -> Vec<String> {
    let mut w = Vec::new();
    let r = s.cfg.degree;
    if r > 0 {
        let lebesgue = |a: f64| {
            radcol_core::nodes::NodeSet::new(r, a).map_or(f64::INFINITY, |n| n.lebesgue_constant())
        };
        let here = lebesgue(s.cfg.alpha);
        let auto = s.alpha.a0.auto_alpha();
        let best = lebesgue(auto);
        if here > 10.0 && here > 2.0 * best {
            w.push(format!(
                "α = {}: its nodes have Lebesgue constant {here:.1} (interpolation amplifies errors up to that much; \
                 collocation near edges is stable roughly while ρ·Λ·cos²(θ/2) < 1); --alpha auto ({auto:.6}) has {best:.1}",
                s.cfg.alpha
            ));
        }
    }
    let tol = s.cfg.gmres.rel_tol;
    for ch in &out.channels {
        if ch.solver.residual > (1e3 * tol).max(1e-8) {
            w.push(format!(
                "channel {}: the linear solve's true relative residual is {} (asked {}): the system is badly \
                 conditioned; try a smaller α, a lower degree or --solver gmres with more --max-iters",
                ch.name,
                sci(ch.solver.residual),
                sci(tol)
            ));
        }
        if let Some(e) = &ch.estimate {
            if e.max_rel > 0.1 {
                w.push(format!(
                    "channel {}: estimated error {} of max |u|: refine (--level, --max-edge or --target-error)",
                    ch.name,
                    sci(e.max_rel)
                ));
            }
        }
    }
    w
}
