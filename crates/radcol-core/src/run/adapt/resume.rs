//! Refining a solved mesh further: the loop picks up where a solve left
//! off, with the elements' estimate history and degrees it had, so that a
//! smaller target costs the steps from the last mesh on, not a new start.
//! The first split is decided on the solve's own estimate; the plans of
//! the last step are not kept (they are the largest thing a step holds),
//! so the first new step assembles in full and the later ones reuse as
//! usual.

use super::history::History;
use super::hp::Degrees;
use super::next::carry;
use super::{assess, checked, diagonal, run, AdaptOptions, AdaptOutcome, AdaptStep};
use super::{Assessment, SingularPoint, Start, StopReason};
use crate::assembly::AssemblyBackend;
use crate::error::Error;
use crate::problem::Problem;
use crate::run::{ChannelResult, SolveConfig, SolveOutcome};

/// Where an adaptive loop stands after its last step: the elements'
/// estimate history (which splits stalled) and, with hp or a graded
/// start, every element's degree.
#[derive(Clone, Debug)]
pub struct Resume {
    pub(super) history: History,
    pub(super) degrees: Option<Degrees>,
}

impl Resume {
    /// A loop that starts on `outcome`'s mesh with no history: for a solve
    /// that did not come from the loop (one degree everywhere, `cfg`'s).
    pub fn fresh(
        outcome: &SolveOutcome,
        cfg: &SolveConfig,
        opts: &AdaptOptions,
        backend: &dyn AssemblyBackend,
    ) -> Result<Self, Error> {
        let mesh = outcome.discretization.mesh();
        let opts = AdaptOptions {
            graded_start: false,
            ..opts.clone()
        };
        Ok(Self {
            history: History::new(mesh.len(), opts.stall_generations as usize),
            degrees: Degrees::start(cfg, mesh, &opts, backend)?,
        })
    }
}

/// How a resumed loop ended.
#[derive(Debug)]
pub enum Resumed {
    /// The solve it started from stands: its estimate already meets the
    /// target, or no element may be split, or the next step would not fit.
    Stands {
        /// Why no step was solved.
        stop: StopReason,
        /// Where the estimate stays above the target on elements that are
        /// no longer split.
        singular: Vec<SingularPoint>,
    },
    /// New steps were solved; the steps listed are the new ones.
    Refined(Box<AdaptOutcome>),
}

/// Refines `from`, a solve of `problem` with `cfg` whose loop stands at
/// `resume`, until `opts.target` or a budget, as [`super::solve_adaptive`]
/// would have gone on; `on_step` sees each new step as it ends.
///
/// `channels` are the values held now. When each carries an estimate
/// (`from`'s own), that estimate decides the first split and `from` is not
/// solved again. Otherwise (relit channels, a solve without an estimate)
/// `from`'s mesh is solved again first, starting from those values, with
/// no history: the old estimates describe other lights.
#[allow(clippy::too_many_arguments)]
pub fn resume_adaptive(
    problem: &Problem,
    cfg: &SolveConfig,
    opts: &AdaptOptions,
    backend: &dyn AssemblyBackend,
    from: &SolveOutcome,
    channels: &[ChannelResult],
    resume: &Resume,
    mut on_step: impl FnMut(&AdaptStep),
) -> Result<Resumed, Error> {
    let cfg = checked(problem, cfg, opts, backend)?;
    let mesh = from.discretization.mesh();
    let assessed = channels.iter().all(|c| c.estimate.is_some());
    let mut stands = Vec::new();
    let start = if assessed {
        let floor = opts.min_size * diagonal(mesh);
        let Assessment {
            stop,
            marked,
            indicator,
            negative,
            singular,
            ..
        } = assess(from, &resume.history, (&cfg, opts, floor), 0);
        if let Some(stop) = stop {
            return Ok(Resumed::Stands { stop, singular });
        }
        let degrees = resume.degrees.as_ref();
        let next = carry(
            from,
            &marked,
            (&indicator, &negative),
            degrees,
            &resume.history,
        );
        stands = singular;
        Start {
            mesh: next.mesh,
            degrees: next.degrees,
            history: next.history,
            guess: Some(next.guess),
        }
    } else {
        Start {
            mesh: mesh.clone(),
            degrees: resume.degrees.clone(),
            history: History::new(mesh.len(), opts.stall_generations as usize),
            guess: Some(
                channels
                    .iter()
                    .map(|c| c.solution.nodal().to_vec())
                    .collect(),
            ),
        }
    };
    match run(problem, &cfg, opts, backend, start, &mut on_step) {
        // The first new step's peak would not fit: `from` stands, as after
        // any step the loop refuses.
        Err(Error::Input(e)) if assessed && e.is_peak_refusal() => Ok(Resumed::Stands {
            stop: StopReason::Memory,
            singular: stands,
        }),
        r => r.map(|out| Resumed::Refined(Box::new(out))),
    }
}
