//! What the adaptive loop aims for and may spend, and the defaults.

use crate::error::InputError;
use crate::estimate::RelativeTo;
use serde::Serialize;

/// What the adaptive loop aims for and may spend.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AdaptOptions {
    /// Target of the estimated max error relative to the reflected light
    /// (or, with [`AdaptOptions::relative_to`], to max |u_n|), per channel,
    /// in (0, 1).
    pub target: f64,
    /// No step with more unknowns than this (None: as many as the dense
    /// matrix's memory allows).
    pub max_unknowns: Option<u64>,
    /// At most this many solves.
    pub max_steps: usize,
    /// Elements whose estimate exceeds `mark_fraction · target` are split:
    /// below 1, elements about to cross the target are split in the same
    /// step (fewer solves for a few more unknowns).
    pub mark_fraction: f64,
    /// ...and exceeds `max_fraction` of the largest estimate of an element
    /// that may still be split: worst first, so that each step's mesh is
    /// the one its error needs, and a budget that stops the loop leaves the
    /// best mesh for its size (0: every element above the target's
    /// fraction, at once).
    pub max_fraction: f64,
    /// An element whose longest edge is shorter than this fraction of the
    /// diagonal of the scene's bounding box is not split. The stall test
    /// (`stall_generations`) is what stops refinement at a point where u
    /// has a direction-dependent limit; this floor is the backstop (with no
    /// limit at all, the loop graded towards such points until rounding
    /// broke it: `tests/tests/contact.rs`). It is relative to the scene, not
    /// counted in splits from the starting mesh, so that the mesh a run
    /// starts from does not decide how fine it may go: 10 splits from the
    /// built-in `shadow` scene's 6 triangles stopped the kinks through its
    /// point umbra at an estimated 1.6e-4 against a 1e-4 target.
    pub min_size: f64,
    /// An element whose estimate fell by less than [`super::STALL_RATIO`] per
    /// split on average over its last this many splits is not split again
    /// (0: only the size floor applies). At such points the depth limit alone costs
    /// a solve per wasted generation (the Cornell box from its 50 triangles
    /// to 1e-3: 12 steps and 14 973 unknowns with the depth limit alone, 9
    /// steps and 7 710 unknowns with 3 stalled generations).
    pub stall_generations: u32,
    /// A step's estimate may be updated from the previous step's instead of
    /// computed afresh (`crate::estimate::estimate_updated`) when it is
    /// then within this fraction of the marking threshold
    /// (`mark_fraction · target`) of the computed one (0: computed always).
    pub estimate_within: f64,
    /// A degree per element ([`super::hp`]): a marked element is split,
    /// split with its children one degree lower, or raised one degree, by
    /// how its estimate fell when it last changed. Off: every element keeps
    /// the configured degree. CPU backend only (the GPU far field takes one
    /// node set).
    pub hp: bool,
    /// Elements of the starting mesh that are small against the scene
    /// start at a lower degree than the configured one
    /// ([`crate::run::start_degree`]): a scanned mesh's thousands of small
    /// triangles are elements already, and at the configured degree their
    /// nodes would be most of the unknowns and most of the visibility work
    /// (the bunny room to 1e-2: 22 152 unknowns on its first step at r = 2,
    /// 22 044 of them on the bunny's 3 674 triangles). Marked elements are then split at their
    /// degree (or, with `hp`, as hp decides). Off: every element starts at
    /// the configured degree, as a study of one degree needs. CPU backend
    /// only; with another backend the start is not graded.
    pub graded_start: bool,
    /// What `target` (and every relative figure of the steps) is relative
    /// to: the reflected light, max over the nodes of u_n − E (the default;
    /// max |u_n| where nothing is reflected), or max |u_n| (in a lit scene,
    /// the light itself).
    pub relative_to: RelativeTo,
}

/// The smallest target accepted: the estimate's integrals are accurate to
/// `crate::estimate::ESTIMATE_QUAD_TOL` of a row (1e-9), so an error
/// below ten times that could not be told from quadrature error, and a
/// loop asked for it refined until memory ran out.
pub const MIN_TARGET: f64 = 1e-8;

/// The default [`AdaptOptions::mark_fraction`]. At 0.5, with an estimate
/// that follows the error closely (on the shadow family 0.86–1.79 per
/// element, 0.91–1.02 overall at r = 1), the last step split every element in (TOL/2, TOL] and
/// overshot: r = 1 ended at 18 162 unknowns and 8.3e-4 against 10 890 and
/// 9.1e-4 at 0.8; at 1 the true error ended just above TOL (1.03e-3).
pub const MARK_FRACTION: f64 = 0.8;

/// The default [`AdaptOptions::stall_generations`]: along a kink parallel
/// to the mesh's lines the estimate of the element on it can stay flat for
/// three splits and then fall 10× (the shadow family's square occluder at
/// r = 3: 4.3e-3, 3.6e-3, 2.5e-3, 3.3e-3, 3.9e-4), which three froze
/// (r = 3 stopped at 3.4e-3 against a 1e-3 target).
pub const STALL_GENERATIONS: u32 = 4;

/// The default [`AdaptOptions::estimate_within`].
pub const ESTIMATE_WITHIN: f64 = 0.05;

/// The default [`AdaptOptions::max_fraction`].
pub const MAX_FRACTION: f64 = 0.25;

/// The default [`AdaptOptions::min_size`].
pub const MIN_SIZE: f64 = 1e-5;

impl Default for AdaptOptions {
    fn default() -> Self {
        Self {
            target: 1e-2,
            max_unknowns: None,
            max_steps: 25,
            mark_fraction: MARK_FRACTION,
            max_fraction: MAX_FRACTION,
            min_size: MIN_SIZE,
            stall_generations: STALL_GENERATIONS,
            estimate_within: ESTIMATE_WITHIN,
            hp: false,
            graded_start: true,
            relative_to: RelativeTo::Reflected,
        }
    }
}

impl AdaptOptions {
    /// Refuses a target outside [[`MIN_TARGET`], 1) and a size floor outside [0, 1).
    pub fn check(&self) -> Result<(), InputError> {
        if !(self.target >= MIN_TARGET && self.target < 1.0) {
            return Err(InputError::TargetError { value: self.target });
        }
        if !(self.min_size >= 0.0 && self.min_size < 1.0) {
            return Err(InputError::MinSize {
                value: self.min_size,
            });
        }
        Ok(())
    }
}
