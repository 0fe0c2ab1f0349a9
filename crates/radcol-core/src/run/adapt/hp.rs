//! A degree per element (hp, [`super::AdaptOptions::hp`]): each element the
//! loop marks is split 4:1 at its degree, split with its children one degree
//! lower, or raised one degree, by how its estimate behaved when it was last
//! changed.
//!
//! * After a split at the same degree r, the child's estimate over its
//!   parent's, q, tells what u is like on it: where u is smooth a split
//!   divides the max error by about 2^{r+1}; along a kink (a shadow line)
//!   or next to a concave edge (u ~ x log x), by about 2, whatever the
//!   degree. With q ≤ 2^{−r/2} ([`split_smooth`]) the element is raised;
//!   otherwise it is split with its children one degree lower (at least 1):
//!   the line's error is then carried by 4 f_{r−1} unknowns instead of
//!   4 f_r.
//! * After a raise, q = the estimate over the estimate before: at most
//!   [`RAISE_AGAIN`], the raise paid and the element is raised again;
//!   otherwise it is split and lowered back.
//! * After a split that lowered the degree, the element is split once at
//!   its new degree, so that its next choice has a like-for-like q.
//! * On the starting mesh there is no history, and the choice is by the
//!   shape of u_n on the element: θ = the estimate over max |u_n − I_{r−1}
//!   u_n| (the part of u_n degree r adds to degree r − 1). Where u is
//!   smooth, the estimate is about C h^{r+1} and that part about C' h^r, so
//!   θ is about the element's size relative to the scale on which u varies;
//!   a line through the element makes the top-degree part no larger than
//!   the error (θ ≈ 1). θ ≤ [`START_SMOOTH`] raises, more splits and lowers.
//!
//! Elements where u_n < 0 are never raised (a higher degree rings more at
//! a contact line), nor beyond [`HP_MAX_DEGREE`].
//!
//! Measured (docs/accuracy.md, "`--hp`"): the thresholds were swept on the shadowed
//! floor and the Cornell box to 1e-3 (2^{−r/2} and 0.6 lie in the flat
//! part of both). The loop reaches the targets with 1.06–1.5× fewer
//! unknowns than at one degree, but in less wall time only with LU (whose
//! cost grows like N³) and, with GMRES, on the shadowed floor at 1e-4: its
//! steps are more, and cost more per unknown (more elements of degree 1).
//! So it is an option, not the default.

use super::AdaptOptions;
use crate::alpha0::auto_alpha;
use crate::assembly::AssemblyBackend;
use crate::error::Error;
use crate::mesh::Mesh;
use crate::nodes::{NodeSet, MAX_DEGREE};
use crate::norms::LATTICE;
use crate::run::{start_degree, SolveConfig, SolveOutcome};
use crate::solution::Solution;

/// The highest degree hp raises an element to: the study in
/// `tests/tests/hp.rs` found no gain from degrees beyond 4 on the shadow
/// family (the cheapest single degree there is 3 or 4).
pub const HP_MAX_DEGREE: usize = 4;

/// θ at or below which an element of the starting mesh is raised (see the
/// module's text; splitting gains about 2^{−(r+1)} for 3 f_r more
/// unknowns, raising about θ for r + 2).
pub const START_SMOOTH: f64 = 0.6;

/// A raised element whose estimate fell to at most this fraction of its
/// value before the raise is raised again.
pub const RAISE_AGAIN: f64 = 0.6;

/// The q at or below which an element split at degree `r` is raised:
/// 2^{−r/2}, between a smooth split's 2^{−(r+1)} and a kink's 1/2 (for
/// r ≤ 2 at 1/2 and above: the split must at least halve the estimate).
pub fn split_smooth(r: usize) -> f64 {
    2f64.powf(-(r as f64) / 2.0)
}

/// How an element came to be: what its estimate can be compared with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Lineage {
    /// An element of the starting mesh.
    Start,
    /// Split from a parent of the same degree whose estimate was this.
    Split(f64),
    /// Raised one degree from an element whose estimate was this.
    Raised(f64),
    /// Split from a parent one degree higher.
    Lowered,
}

/// What becomes of a marked element.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Change {
    /// Four children of its degree.
    Split,
    /// Four children one degree lower.
    SplitLower,
    /// The same element one degree higher.
    Raise,
}

/// The choice for one marked element of degree `r` with estimate
/// `estimate`, its `lineage`, whether u_n is `negative` on it, and its
/// `theta` (asked for only on the starting mesh).
pub fn choose(
    r: usize,
    estimate: f64,
    lineage: Lineage,
    negative: bool,
    theta: &dyn Fn() -> f64,
) -> Change {
    let smooth = match lineage {
        Lineage::Start => theta() <= START_SMOOTH,
        Lineage::Split(parent) => estimate <= split_smooth(r) * parent,
        Lineage::Raised(before) => estimate <= RAISE_AGAIN * before,
        Lineage::Lowered => return Change::Split,
    };
    if smooth && r < HP_MAX_DEGREE && !negative {
        Change::Raise
    } else if !smooth && r > 1 {
        Change::SplitLower
    } else {
        Change::Split
    }
}

/// Refuses hp (`hp` true) with a backend other than the CPU's.
pub fn check_backend(hp: bool, backend: &dyn AssemblyBackend) -> Result<(), Error> {
    let kind = backend.info().kind;
    if hp && kind != crate::backend_kind::BackendKind::Cpu {
        let backend = kind.to_string();
        return Err(crate::error::InputError::HpBackend { backend }.into());
    }
    Ok(())
}

/// The loop's degrees: per element, its degree and lineage, and the node
/// sets of every degree an element may take.
#[derive(Clone, Debug)]
pub struct Degrees {
    /// Node set of degree r at index r (the starting degree's with the
    /// configured α, the others with the automatic one).
    sets: Vec<NodeSet>,
    /// Per element.
    degree: Vec<usize>,
    /// Per element.
    lineage: Vec<Lineage>,
    /// Whether a marked element may be raised or lowered (else it is split
    /// at its degree).
    hp: bool,
}

impl Degrees {
    /// The degrees of the loop's starting `mesh`, or None when every element
    /// has `cfg`'s degree and the loop keeps it (no hp): with `opts.hp`, or
    /// a graded start ([`start_degree`]) on the CPU backend that lowers
    /// some element's degree.
    pub fn start(
        cfg: &SolveConfig,
        mesh: &Mesh,
        opts: &AdaptOptions,
        backend: &dyn AssemblyBackend,
    ) -> Result<Option<Self>, Error> {
        let mut d = Self::new(cfg, mesh.len())?;
        d.hp = opts.hp;
        if opts.graded_start && backend.info().kind == crate::backend_kind::BackendKind::Cpu {
            let diagonal = super::diagonal(mesh);
            for (k, r) in d.degree.iter_mut().enumerate() {
                let h = super::longest_edge(mesh, k);
                *r = start_degree(h, diagonal, opts.target, cfg.degree);
            }
        }
        let graded = d.degree.iter().any(|&r| r != cfg.degree);
        Ok((opts.hp || graded).then_some(d))
    }

    /// `n` elements of `cfg`'s degree, on the starting mesh, with hp.
    pub fn new(cfg: &SolveConfig, n: usize) -> Result<Self, Error> {
        let top = cfg.degree.clamp(HP_MAX_DEGREE, MAX_DEGREE);
        let sets = (0..=top)
            .map(|r| {
                let alpha = if r == cfg.degree {
                    cfg.alpha
                } else {
                    auto_alpha(r)
                };
                NodeSet::new(r, alpha)
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self {
            sets,
            degree: vec![cfg.degree; n],
            lineage: vec![Lineage::Start; n],
            hp: true,
        })
    }

    /// Every element's degree.
    pub fn degrees(&self) -> &[usize] {
        &self.degree
    }

    /// The node sets, index = degree.
    pub fn sets(&self) -> &[NodeSet] {
        &self.sets
    }

    /// The node set of degree `r`.
    pub fn set(&self, r: usize) -> &NodeSet {
        &self.sets[r]
    }

    /// The change for each of the `marked` elements of `out`'s mesh, given
    /// their `indicator` and where u_n is `negative`.
    pub fn choose(
        &self,
        out: &SolveOutcome,
        marked: &[usize],
        indicator: &[f64],
        negative: &[bool],
    ) -> Vec<Change> {
        marked
            .iter()
            .map(|&k| {
                let r = self.degree[k];
                if !self.hp {
                    return Change::Split;
                }
                let theta = || self.theta(out, k);
                choose(r, indicator[k], self.lineage[k], negative[k], &theta)
            })
            .collect()
    }

    /// The degrees and lineages after the elements `marked` took `changes`
    /// (estimates `indicator`), each new element coming from `parents`.
    pub fn follow(
        &self,
        marked: &[usize],
        changes: &[Change],
        indicator: &[f64],
        parents: &[usize],
    ) -> Self {
        let mut change: Vec<Option<Change>> = vec![None; self.degree.len()];
        for (&k, &c) in marked.iter().zip(changes) {
            change[k] = Some(c);
        }
        let (degree, lineage) = parents
            .iter()
            .map(|&p| {
                let r = self.degree[p];
                match change[p] {
                    None => (r, self.lineage[p]),
                    Some(Change::Split) => (r, Lineage::Split(indicator[p])),
                    Some(Change::SplitLower) => (r - 1, Lineage::Lowered),
                    Some(Change::Raise) => (r + 1, Lineage::Raised(indicator[p])),
                }
            })
            .unzip();
        Self {
            sets: self.sets.clone(),
            degree,
            lineage,
            hp: self.hp,
        }
    }

    /// θ of element `k` (the worst channel's estimate over its top-degree
    /// part), ∞ at degree 0 or where u_n has no top-degree part.
    fn theta(&self, out: &SolveOutcome, k: usize) -> f64 {
        let r = self.degree[k];
        if r == 0 {
            return f64::INFINITY;
        }
        let low = &self.sets[r - 1];
        let mut theta = 0.0f64;
        for ch in &out.channels {
            let Some(e) = &ch.estimate else { continue };
            let delta = top_part(&ch.solution, k, low);
            let eta = e.elements[k];
            theta = theta.max(match (delta > 0.0, eta > 0.0) {
                (true, _) => eta / delta,
                (false, true) => f64::INFINITY,
                (false, false) => 0.0,
            });
        }
        theta
    }
}

/// max |u_n − I u_n| on element `k` over the lattice of `LATTICE`
/// subdivisions (vertices, edges, interior), I the interpolation at the
/// nodes of `low`.
fn top_part(u: &Solution, k: usize, low: &NodeSet) -> f64 {
    let c: Vec<f64> = low.points().iter().map(|&[s, t]| u.eval(k, s, t)).collect();
    let mut l = vec![0.0; low.len()];
    let step = 1.0 / LATTICE as f64;
    let mut worst = 0.0f64;
    for a in 0..=LATTICE {
        for b in 0..=LATTICE - a {
            let (s, t) = (a as f64 * step, b as f64 * step);
            low.eval_basis(s, t, &mut l);
            let i: f64 = l.iter().zip(&c).map(|(x, y)| x * y).sum();
            worst = worst.max((u.eval(k, s, t) - i).abs());
        }
    }
    worst
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The choice by lineage: a split that divided the estimate by more
    /// than 2^{r/2} raises, a smaller fall lowers (not below 1); a raise
    /// that paid raises again, one that did not lowers back; a lowered
    /// element is split first; never raised with u_n < 0 or beyond the cap.
    #[test]
    fn the_choice_follows_the_measured_fall() {
        use Change::*;
        use Lineage as L;
        // (degree, estimate, lineage, u_n < 0, θ (NaN: must not be asked
        // for), the choice).
        let nan = f64::NAN;
        let cases = [
            // r = 2: a split must divide the estimate by 2^{2/2} = 2.
            (2, 0.12, L::Split(1.0), false, nan, Raise),
            (2, 0.55, L::Split(1.0), false, nan, SplitLower),
            (2, 0.12, L::Split(1.0), true, nan, Split),
            (1, 0.9, L::Split(1.0), false, nan, Split),
            // r = 3: by 2^{3/2} = 2.83 (q ≤ 0.354).
            (3, 0.3, L::Split(1.0), false, nan, Raise),
            (3, 0.4, L::Split(1.0), false, nan, SplitLower),
            (HP_MAX_DEGREE, 0.01, L::Split(1.0), false, nan, Split),
            (2, 0.5, L::Raised(1.0), false, nan, Raise),
            (3, 0.7, L::Raised(1.0), false, nan, SplitLower),
            (2, 0.01, L::Lowered, false, nan, Split),
            (2, 1.0, L::Start, false, 0.5, Raise),
            (2, 1.0, L::Start, false, 0.7, SplitLower),
            (0, 1.0, L::Start, false, f64::INFINITY, Split),
        ];
        for (r, estimate, lineage, negative, theta, want) in cases {
            let theta = || {
                assert!(!theta.is_nan(), "θ asked for after {lineage:?}");
                theta
            };
            let got = choose(r, estimate, lineage, negative, &theta);
            assert_eq!(got, want, "r = {r}, {estimate}, {lineage:?}, {negative}");
        }
    }
}
