//! A posteriori error estimate of a collocation solution, from what the
//! method already has: the residual of the equation at points that are not
//! collocation nodes,
//!
//! ```text
//! η(P) = û_n(P) - u_n(P) = E(P) + ρ(P)/π ∫_S G(P, Q) V(P, Q) u_n(Q) dS_Q - u_n(P),
//! ```
//!
//! the iterated solution (21) minus u_n. u - u_n = (u - û_n) + η, and u - û_n
//! = K(u - u_n) is of higher order than u - u_n wherever K smooths (on smooth
//! surfaces û_n superconverges, Theorems 7 and 9), so η tracks the error; at
//! the nodes η vanishes by construction, hence the check points.
//!
//! **Check points.** Per element, the nodes q_ij(α_c) of degree r + 1 with a
//! small α_c ([`check_nodes`]). Through them η is interpolated on each
//! element, which holds the leading (degree r + 1) term of u - u_n, and that
//! interpolant is sampled everywhere on the element, vertices and edges
//! included, where u - u_n is largest. K u_n at the check points is one row
//! block of an [`AssemblyPlan::at_points`] plan per element, rows at the
//! check points and columns u_n's own basis, with the solve's visibility
//! (partly visible pairs clipped exactly) and quadrature: η is the
//! collocation residual on the check points. The blocks are filled and
//! contracted one at a time (memory O(f·N), not N²). (A first version wrote
//! u_n in the degree-(r + 1) basis of the check points: a square plan with
//! (r + 3)/(r + 1) times the columns, the same estimates in the same time,
//! since the cost is the kernel evaluations per check point.)
//!
//! **Negative light.** With E ≥ 0 and ρ ≥ 0 the exact u is ≥ 0, so a
//! negative u_n at a node or check point is an error at least |u_n| there:
//! it is counted and, on such problems, taken into the element's estimate.

use crate::assembly::AssemblyPlan;
use crate::discretization::Discretization;
use crate::nodes::{NodeSet, MAX_DEGREE};
use crate::norms::LATTICE;
use crate::quadrature::RuleLadder;
use crate::solution::Solution;
use rayon::prelude::*;
use serde::Serialize;

mod shared;
mod update;
pub use shared::estimate_shared;
pub use update::estimate_updated;

/// The element-integral tolerance of the check rows (the solve's own when
/// looser): η is wanted to a few digits, and an integral error of 1e-9
/// relative to a row whose entries sum to at most 1 moves η by at most
/// 1e-9 max |u_n|, far below any error worth estimating.
pub const ESTIMATE_QUAD_TOL: f64 = 1e-9;

/// α of the check points, in order of preference: the first whose points
/// keep away from the nodes ([`CHECK_SEPARATION`]). A small α_c keeps the
/// interpolation through them well conditioned over the whole element,
/// vertices included: at degree 4 (r = 3) the Lebesgue constant is 3.5 at
/// α_c = 0.02, 9.6 at 0.05 and 68 at 0.12, and where η has a kink (a
/// shadow line through the element) the interpolant's overshoot is the
/// estimate's. On the shadowed family's floor, where η is u − u_n exactly,
/// the element estimates over the true element errors (meshes whose
/// elements straddle the shadow lines) are within 0.86–1.79 at r = 1..3
/// (`hp::element_estimates_follow_the_error_across_shadow_lines`; above
/// 1.2 only at r = 1); with α_c = 0.12, which
/// r = 3 took before (auto α(3) = 0.078 lies near 0.05), they ranged over
/// 0.18–13 on the elements of the cheapest r = 3 meshes to 1e-3.
const CHECK_ALPHA: [f64; 3] = [0.01, 0.03, 0.05];

/// Check points nearer a node than this (reference coordinates) add little
/// to it: η vanishes at the nodes.
const CHECK_SEPARATION: f64 = 0.005;

/// The check-point node set for a solution of degree `r` with node
/// parameter `alpha`: degree r + 1 (capped at [`MAX_DEGREE`]), so that the
/// interpolant of η through them holds the leading, degree-(r+1) term of
/// u - u_n, and an α that keeps their interpolation well conditioned and
/// the points away from the nodes (`CHECK_ALPHA`; only the centroid may
/// be a node of both).
pub fn check_nodes(r: usize, alpha: f64) -> NodeSet {
    let rc = (r + 1).min(MAX_DEGREE);
    let sets = CHECK_ALPHA.map(|a| NodeSet::new(rc, a).expect("check α inside (0, 1/3)"));
    let Ok(nodes) = NodeSet::new(r, alpha) else {
        return sets[0].clone();
    };
    let apart = |check: &&NodeSet| {
        let near = check.points().iter().filter(|c| {
            nodes
                .points()
                .iter()
                .any(|q| (q[0] - c[0]).hypot(q[1] - c[1]) < CHECK_SEPARATION)
        });
        near.count() <= 1
    };
    let last = &sets[CHECK_ALPHA.len() - 1];
    sets.iter().find(apart).unwrap_or(last).clone()
}

/// The check points of every element of `disc`: [`check_nodes`] of the
/// element's node set (degree r + 1, at most [`MAX_DEGREE`]; where two of
/// `disc`'s sets give check sets of one degree, the first one's serves
/// both).
pub fn check_discretization(disc: &Discretization) -> Discretization {
    let mut sets: Vec<NodeSet> = Vec::new();
    for s in disc.node_sets() {
        let c = check_nodes(s.degree(), s.alpha());
        if !sets.iter().any(|o| o.degree() == c.degree()) {
            sets.push(c);
        }
    }
    let degrees: Vec<usize> = (0..disc.mesh().len())
        .map(|k| (disc.degree(k) + 1).min(MAX_DEGREE))
        .collect();
    Discretization::with_degrees(disc.mesh().clone(), sets, &degrees)
        .expect("a check set of every degree used")
}

/// What the relative figures of an estimate, and an adaptive target, are
/// relative to.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RelativeTo {
    /// max |u_n|: in a lit scene, the emitters' own radiosity.
    MaxU,
    /// The reflected light, max over the nodes of u_n − E
    /// ([`ErrorEstimate::reflected_scale`]): what a viewer sees on lit
    /// surfaces, and the default. Where nothing is reflected, max |u_n|.
    #[default]
    Reflected,
}

/// The estimate of one channel's solution.
#[derive(Clone, Debug, Serialize)]
pub struct ErrorEstimate {
    /// max |η| over S (η interpolated through each element's check
    /// points, sampled on the lattice, and at the shadow probes),
    /// absolute.
    pub max: f64,
    /// (∫_S η²)^½ of the same interpolant (absolute).
    pub l2: f64,
    /// max |u_n| over the nodes, check points and lattice points: the scale
    /// of the relative figures.
    pub scale: f64,
    /// `max / scale`.
    pub max_rel: f64,
    /// max over the nodes of u_n − E: the light that the surfaces reflect,
    /// the part the method computes (the emission is known exactly). On a
    /// lit scene it is what a viewer sees on the walls, where `scale` is
    /// the emitters' radiosity. 0 when nothing is reflected.
    pub reflected_scale: f64,
    /// Root mean square of η over S relative to `scale`:
    /// l2 / (scale · |S|^½).
    pub rms_rel: f64,
    /// Nodes where u_n < 0.
    pub negative_nodes: usize,
    /// Lattice points (vertices, edges, interiors of every element; see
    /// `crate::norms::LATTICE`) where u_n < 0.
    pub negative_points: usize,
    /// min u_n over the nodes, check points and lattice points.
    pub min_value: f64,
    /// Whether negative u_n is unphysical here (E ≥ 0 at every node and
    /// check point; ρ ≥ 0 always): then it is part of the element estimates.
    pub nonnegative_problem: bool,
    /// Per element: max of |η| over its lattice and its shadow probes (and
    /// of -u_n where negative light is unphysical), absolute; length n.
    #[serde(skip)]
    pub elements: Vec<f64>,
    /// Per element: whether u_n < 0 somewhere on its lattice while negative
    /// light is unphysical; length n.
    #[serde(skip)]
    pub negative: Vec<bool>,
    /// When the estimate was updated from the previous adaptive step's
    /// (`estimate_updated`) instead of computed afresh: at most how far
    /// (absolute) η, each element's figure and `max` can be from the
    /// computed ones.
    pub updated_within: Option<f64>,
    /// With approximate visibility of bounce pairs: at most how far
    /// (absolute) the approximation can have moved the solution,
    /// ρ_max B max|u_n| / (1 − ρ_max) with B the largest sum of the
    /// approximated pairs' mass bounds at a node or check point
    /// (`visibility::bounce`); already added to `max` and
    /// `max_rel`, not to the element figures (they rank the elements for
    /// refinement, which does not lower it; a point's estimate is its
    /// element's plus this). 0 when every pair is exact.
    pub visibility_bound: f64,
    /// Shadow probes evaluated: points inside a shadow that an emitting
    /// element casts on an element between its check points, where |η|
    /// raised that element's figure and `max` when larger
    /// ([`ErrorEstimate::add_probe`]; `l2` and `rms_rel` leave them out).
    pub probes: usize,
    /// ∫_S G V u_n / π at every check point (ordered like the check rows):
    /// û_n = E + ρ · this. What the next step's update starts from.
    #[serde(skip)]
    pub check_ku: Vec<f64>,
    /// At most how far `check_ku` can be from the computed values (0 when
    /// computed; updates accumulate it).
    #[serde(skip)]
    pub check_ku_drift: f64,
}

impl ErrorEstimate {
    /// Adds what approximate visibility can have moved the solution: with
    /// `mass` the largest sum of approximated mass bounds at a row point
    /// (the residual there moved by at most ρ · mass · max|u|) and
    /// `rho_max` the largest reflectance (the error's amplification is at
    /// most 1 / (1 − ρ_max)), [`ErrorEstimate::visibility_bound`] is
    /// ρ_max · mass · scale / (1 − ρ_max), added to `max` (not to the
    /// element figures, which rank elements for refinement).
    pub fn add_visibility_bound(&mut self, rho_max: f64, mass: f64) {
        if mass <= 0.0 {
            return;
        }
        let bound = rho_max * mass * self.scale / (1.0 - rho_max);
        self.visibility_bound += bound;
        self.max += bound;
        let s = if self.scale > 0.0 { self.scale } else { 1.0 };
        self.max_rel = self.max / s;
    }

    /// Adds |η| = `eta` at a probe point of element `k` (absolute): the
    /// element's figure and `max` become at least `eta` (before
    /// [`ErrorEstimate::add_visibility_bound`], which adds to `max`).
    pub fn add_probe(&mut self, k: usize, eta: f64) {
        self.probes += 1;
        self.elements[k] = self.elements[k].max(eta);
        if eta > self.max {
            self.max = eta;
            let s = if self.scale > 0.0 { self.scale } else { 1.0 };
            self.max_rel = self.max / s;
        }
    }

    /// The scale that figures relative `to` divide by.
    pub fn scale_of(&self, to: RelativeTo) -> f64 {
        match to {
            RelativeTo::Reflected if self.reflected_scale > 0.0 => self.reflected_scale,
            _ => self.scale,
        }
    }

    /// The factor that turns a figure relative to `scale` into one
    /// relative `to` (1 when either scale is 0).
    pub fn rescale(&self, to: RelativeTo) -> f64 {
        match self.scale_of(to) {
            s if s > 0.0 && self.scale > 0.0 => self.scale / s,
            _ => 1.0,
        }
    }

    /// `max` relative to the reflected light (`reflected_scale`); None when
    /// nothing is reflected.
    pub fn max_rel_reflected(&self) -> Option<f64> {
        (self.reflected_scale > 0.0).then(|| self.max / self.reflected_scale)
    }

    /// Per element, `elements / scale`.
    pub fn elements_rel(&self) -> impl Iterator<Item = f64> + '_ {
        let s = if self.scale > 0.0 { self.scale } else { 1.0 };
        self.elements.iter().map(move |e| e / s)
    }

    /// The estimated max error of what is shown, relative to `scale`: the
    /// largest element figure, and at least `max_rel`. It exceeds
    /// `max_rel` where negative u_n is counted as error (the element
    /// figures include −u_n there) and, once u_n is limited to
    /// nonnegative values (`SolveConfig::limit_negative`), by the
    /// limiter's change on the limited elements, which is added to their
    /// figures.
    pub fn shown_max_rel(&self) -> f64 {
        // Every point's figure carries the approximate visibility's bound.
        let s = if self.scale > 0.0 { self.scale } else { 1.0 };
        let bound = self.visibility_bound / s;
        self.elements_rel()
            .map(|e| e + bound)
            .fold(self.max_rel, f64::max)
    }
}

/// What the estimate of one channel needs: u_n, and ρ and E at the check
/// points (ordered like `check.rows().points()`).
#[derive(Debug)]
pub struct ChannelFields<'a> {
    /// The solution.
    pub solution: &'a Solution,
    /// ρ at the check points.
    pub rho: &'a [f64],
    /// E at the check points.
    pub emission: &'a [f64],
    /// E at the solution's nodes (for the sign of the problem).
    pub emission_nodes: &'a [f64],
}

/// The estimate of every channel, with `check` the plan from u_n's basis
/// to the check points ([`AssemblyPlan::at_points`] with the
/// [`check_nodes`] on the solutions' mesh), filled and contracted one row
/// block at a time (memory O(f·N)).
#[cfg(any(test, feature = "internals"))]
pub fn estimate(check: &AssemblyPlan, channels: &[ChannelFields<'_>]) -> Vec<ErrorEstimate> {
    estimate_shared(check, channels, None)
}

/// Per channel, the values of every element's `blocks` (channel-major
/// within each block, the same number per channel), in check-row order.
pub(super) fn by_channel(blocks: Vec<Vec<f64>>, channels: usize) -> Vec<Vec<f64>> {
    (0..channels)
        .map(|c| {
            blocks
                .iter()
                .flat_map(|b| {
                    let fc = b.len() / channels;
                    b[c * fc..(c + 1) * fc].iter().copied()
                })
                .collect()
        })
        .collect()
}

/// The estimate of every channel from `ku`, K u_n at its check points
/// (computed, drift 0): u_n there, η = E + ρ K u_n - u_n, and the summaries.
pub(super) fn summaries(
    check: &AssemblyPlan,
    channels: &[ChannelFields<'_>],
    ku: Vec<Vec<f64>>,
) -> Vec<ErrorEstimate> {
    let disc = check.rows();
    channels
        .iter()
        .zip(ku)
        .map(|(ch, ku)| {
            let coeffs: Vec<f64> = disc
                .points()
                .par_iter()
                .map(|p| ch.solution.eval(p.element, p.st[0], p.st[1]))
                .collect();
            let eta = |k: usize, a: usize| {
                let i = disc.offset(k) + a;
                ch.emission[i] + ch.rho[i] * ku[i] - coeffs[i]
            };
            let mut e = summarise(disc, ch, &coeffs, eta);
            e.check_ku = ku;
            e
        })
        .collect()
}

/// K u_n at the `fc` check points of one element for every channel
/// (channel-major), from its rows `block` (fc × ncols).
pub(super) fn contract(block: &[f64], fc: usize, ncols: usize, channels: &[ChannelFields<'_>]) -> Vec<f64> {
    let mut out = Vec::with_capacity(channels.len() * fc);
    for ch in channels {
        let u = ch.solution.nodal();
        for a in 0..fc {
            let row = &block[a * ncols..(a + 1) * ncols];
            out.push(row.iter().zip(u).map(|(g, u)| g * u).sum());
        }
    }
    out
}

/// Norms, signs and per-element figures of one channel's η. On each
/// element η is interpolated through its check points (degree r + 1) and
/// the interpolant's maximum taken over the lattice of [`norms`]
/// (vertices, edges and interior: u - u_n peaks at the vertices mostly,
/// where there are no check points) and its square integrated.
///
/// [`norms`]: crate::norms
fn summarise(
    disc: &Discretization,
    ch: &ChannelFields<'_>,
    coeffs: &[f64],
    eta: impl Fn(usize, usize) -> f64,
) -> ErrorEstimate {
    let mesh = disc.mesh();
    let nodal = ch.solution.nodal();
    let nonneg = ch
        .emission
        .iter()
        .chain(ch.emission_nodes)
        .all(|&e| e >= 0.0);
    let lattice: Vec<[f64; 2]> = (0..=LATTICE)
        .flat_map(|a| (0..=LATTICE - a).map(move |b| [a, b]))
        .map(|[a, b]| [a as f64 / LATTICE as f64, b as f64 / LATTICE as f64])
        .collect();
    let ladder = RuleLadder::new();
    let mut l = vec![0.0; disc.max_nodes_per_element()];
    let mut interp = |k: usize, st: [f64; 2]| {
        let check = disc.nodes_of(k);
        let fc = check.len();
        check.eval_basis(st[0], st[1], &mut l[..fc]);
        let e: f64 = (0..fc).map(|a| l[a] * eta(k, a)).sum();
        (e, ch.solution.eval(k, st[0], st[1]))
    };
    let mut elements = vec![0.0f64; mesh.len()];
    let mut negative = vec![false; mesh.len()];
    let (mut max, mut l2sq, mut scale) = (0.0f64, 0.0, 0.0f64);
    let (mut min_value, mut negative_points) = (f64::INFINITY, 0);
    // Squares are summed in units of max |u_n| so that they neither
    // overflow (u ~ 1e160) nor underflow (u ~ 1e-160).
    let unit = match nodal.iter().fold(0.0f64, |m, u| m.max(u.abs())) {
        m if m > 0.0 => m,
        _ => 1.0,
    };
    for (k, (elem, neg)) in elements.iter_mut().zip(&mut negative).enumerate() {
        let mut e_max = 0.0f64;
        let mut most_negative = 0.0f64;
        for &st in &lattice {
            let (e, u) = interp(k, st);
            e_max = e_max.max(e.abs());
            scale = scale.max(u.abs());
            min_value = min_value.min(u);
            if u < 0.0 {
                negative_points += 1;
                most_negative = most_negative.max(-u);
            }
        }
        let rule = ladder.rule(2 * disc.degree(k));
        for (&st, &w) in rule.points.iter().zip(&rule.weights) {
            let (e, _) = interp(k, st);
            l2sq += w * mesh.point(k, st[0], st[1]).jacobian * (e / unit) * (e / unit);
        }
        max = max.max(e_max);
        *neg = nonneg && most_negative > 0.0;
        *elem = if nonneg {
            e_max.max(most_negative)
        } else {
            e_max
        };
    }
    for &u in nodal.iter().chain(coeffs) {
        scale = scale.max(u.abs());
        min_value = min_value.min(u);
    }
    let area = mesh.area();
    let s = if scale > 0.0 { scale } else { 1.0 };
    let reflected = nodal.iter().zip(ch.emission_nodes).map(|(u, e)| u - e);
    ErrorEstimate {
        max,
        l2: l2sq.sqrt() * unit,
        scale,
        max_rel: max / s,
        reflected_scale: reflected.fold(0.0, f64::max),
        rms_rel: (l2sq / area).sqrt() * unit / s,
        negative_nodes: nodal.iter().filter(|&&u| u < 0.0).count(),
        negative_points,
        min_value,
        nonnegative_problem: nonneg,
        elements,
        negative,
        updated_within: None,
        visibility_bound: 0.0,
        probes: 0,
        check_ku: Vec::new(),
        check_ku_drift: 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::assembly::QuadratureOptions;
    use crate::geometry::shapes::sphere;
    use crate::mesh::Mesh;
    use std::sync::Arc;

    /// With a degree per element (1..=3), the check points follow each
    /// element's degree, and the estimate of u_n = the interpolant of
    /// exp(z) on the sphere with ρ = 0 (so η = E − u_n, the interpolation
    /// error) tracks each element's true error, sampled on its lattice,
    /// whatever its degree.
    #[test]
    fn a_degree_per_element_is_estimated_element_by_element() {
        let mesh = Arc::new(Mesh::new(Arc::new(sphere(1.0)), 1));
        let sets = (1..=3).map(|r| NodeSet::new(r, 0.1).unwrap()).collect();
        let degrees: Vec<usize> = (0..mesh.len()).map(|k| 1 + k % 3).collect();
        let disc = Arc::new(Discretization::with_degrees(mesh.clone(), sets, &degrees).unwrap());
        let check = Arc::new(check_discretization(&disc));
        for k in 0..mesh.len() {
            assert_eq!(check.degree(k), degrees[k] + 1);
        }
        let u = |i: usize, d: &Discretization| d.points()[i].position.z.exp();
        let nodal: Vec<f64> = (0..disc.len()).map(|i| u(i, &disc)).collect();
        let solution = Solution::new(disc.clone(), nodal.clone());
        let at_check: Vec<f64> = (0..check.len()).map(|i| u(i, &check)).collect();
        let rho = vec![0.0; check.len()];
        let visibility = crate::visibility::analyze(mesh.surface());
        let quad = QuadratureOptions::default();
        let plan = AssemblyPlan::at_points(disc.clone(), check, quad, &visibility, (None, None));
        let fields = ChannelFields {
            solution: &solution,
            rho: &rho,
            emission: &at_check,
            emission_nodes: &nodal,
        };
        let e = estimate(&plan, &[fields]).remove(0);
        // With ρ = 0 nothing is reflected: u_n = E at the nodes.
        assert_eq!((e.reflected_scale, e.max_rel_reflected()), (0.0, None));
        let mut by_degree = [0usize; 4];
        for k in 0..mesh.len() {
            let truth = (0..=LATTICE)
                .flat_map(|a| (0..=LATTICE - a).map(move |b| (a, b)))
                .map(|(a, b)| {
                    let (s, t) = (a as f64 / LATTICE as f64, b as f64 / LATTICE as f64);
                    (mesh.point(k, s, t).position.z.exp() - solution.eval(k, s, t)).abs()
                })
                .fold(0.0, f64::max);
            let eff = e.elements[k] / truth;
            assert!(
                (0.3..=3.0).contains(&eff),
                "element {k}, r = {}: effectivity {eff}",
                degrees[k]
            );
            by_degree[degrees[k]] += 1;
        }
        assert!(by_degree[1..].iter().all(|&c| c > 0), "{by_degree:?}");
    }

    /// The check points are never the nodes, for any degree and α.
    #[test]
    fn check_points_differ_from_the_nodes() {
        for r in 0..=crate::nodes::MAX_DEGREE {
            for alpha in [0.01, 0.05, 0.06, 0.1, 0.1666, 0.25, 0.33] {
                let nodes = NodeSet::new(r, alpha).unwrap();
                let check = check_nodes(r, alpha);
                let close = check
                    .points()
                    .iter()
                    .filter(|c| {
                        nodes
                            .points()
                            .iter()
                            .any(|q| (q[0] - c[0]).hypot(q[1] - c[1]) < 1e-3)
                    })
                    .count();
                // Only the centroid may coincide (it is a node of every
                // degree divisible by 3).
                assert!(check.degree() == (r + 1).min(MAX_DEGREE));
                assert!(
                    close <= 1,
                    "r = {r}, α = {alpha}: {close} check points on nodes"
                );
            }
        }
    }
}
