//! Self pairs: the integral over the element that contains P.
//!
//! σ is split at P's coordinates into three triangles with P as apex, each
//! integrated in Duffy coordinates (u, v) ↦ P + u (A - P) + u v (B - A), where
//! the bounded, direction-dependent kernel of a curved surface becomes smooth.
//!
//! Smooth is not enough on strongly curved elements: on the flat ellipsoid
//! (c = 0.1) the normal turns by 90° within a parameter distance of about c of
//! the rim, so the normal and the Jacobian have complex singularities that
//! close to the element, and a fixed tensor Gauss rule on the whole Duffy
//! square erred by 6 % of the element's integral (row sums off by 2.9e-3 at
//! level 2 for every quadrature tolerance). Each Duffy window is therefore
//! integrated up a ladder of tensor Gauss rules (0.3, 0.5, 0.7 and 1 times
//! `self_order` points a direction) until two successive rungs agree to the
//! tolerance, the higher taken; where the last two disagree, its quadrants
//! are integrated the same way, recursively. Smooth windows stop early: on
//! the sphere 1 300–1 800 kernel evaluations a self pair, against 4 000–4 700
//! when every window took the full rule and was checked against half-order
//! ones (and on the ellipsoid 15 % fewer, closer to a reference: 4e-15
//! against 4e-13 of the integral at level 2).

use super::{ElementIntegrator, FieldPoint, Integrand};
use crate::kernel::g;
use crate::quadrature::gauss::gauss_legendre01;
use std::f64::consts::FRAC_1_PI;

/// Deepest quadrant split of a Duffy window: 4^-10 of the window, far below
/// any feature a mesh element can carry in f64 (and a bound on the work when
/// the integrand is not smooth at all).
pub const MAX_SELF_DEPTH: u32 = 10;

/// Nodes and weights of a Gauss–Legendre rule on [0, 1].
type Rule = (Vec<f64>, Vec<f64>);

/// Gauss–Legendre rules on [0, 1] for self pairs, each a ladder of
/// increasing orders: `plain` (radial, and angular on an interval of its
/// own) up to `self_order` points, `graded` with about half as many for
/// each piece of a geometrically graded angular interval.
#[derive(Clone, Debug)]
pub struct SelfRules {
    plain: Vec<Rule>,
    graded: Vec<Rule>,
}

impl SelfRules {
    /// Rules for up to `order` points per direction (at least 4: a ladder
    /// needs two rungs to compare, or every window would be split to
    /// [`MAX_SELF_DEPTH`]).
    pub fn new(order: usize) -> Self {
        let ladder = |n: usize| {
            let mut orders: Vec<usize> = [0.3, 0.5, 0.7]
                .iter()
                .map(|&x| (x * n as f64).round() as usize)
                .chain([n])
                .map(|m| m.max(1))
                .collect();
            orders.dedup();
            orders.into_iter().map(gauss_legendre01).collect::<Vec<_>>()
        };
        let order = order.max(4);
        Self {
            plain: ladder(order),
            graded: ladder(order.div_ceil(2) + 2),
        }
    }

    /// The angular ladder of a window, and the radial one with as many steps.
    fn ladders(&self, graded: bool) -> (&[Rule], &[Rule]) {
        let angular = if graded { &self.graded } else { &self.plain };
        let steps = angular.len().min(self.plain.len());
        (&angular[..steps], &self.plain[..steps])
    }
}

/// One Duffy triangle (P, A, B) of a self pair, in σ coordinates.
#[derive(Clone, Copy)]
struct Duffy<'a> {
    p: &'a FieldPoint,
    k: usize,
    st0: [f64; 2],
    pa: [f64; 2],
    ab: [f64; 2],
    det: f64,
    phi: &'a Integrand<'a>,
    m: usize,
    /// Whether its angular interval is graded (the shorter angular rules).
    graded: bool,
}

/// A rectangle [u0, u1] × [v0, v1] of Duffy coordinates.
type Window = [f64; 4];

fn quadrants([u0, u1, v0, v1]: Window) -> [Window; 4] {
    let (um, vm) = (0.5 * (u0 + u1), 0.5 * (v0 + v1));
    [
        [u0, um, v0, vm],
        [um, u1, v0, vm],
        [u0, um, vm, v1],
        [um, u1, vm, v1],
    ]
}

impl ElementIntegrator<'_> {
    /// Adds ∫_{Δ_k} G(P, Q) φ(Q) dS_Q / π for P on element `k` at `st0`; returns
    /// the number of kernel evaluations.
    ///
    /// When P is close to the edge AB the triangle is a sliver and the integrand
    /// has a complex near-singularity in v at distance δ = dist(P, AB) / |AB| from
    /// the foot of the perpendicular; the v-interval is therefore split at
    /// geometrically graded points around the foot (δ, 2δ, 4δ, …), so that each
    /// piece sees the singularity at a distance comparable to its length.
    pub(super) fn integrate_self(
        &self,
        p: &FieldPoint,
        k: usize,
        st0: [f64; 2],
        phi: &Integrand<'_>,
        out: &mut [f64],
    ) -> u64 {
        let corners = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        let m = out.len();
        let mut evals = 0;
        // First pass: every window with the ladder's first rules (the
        // integral's size, and the first value to compare).
        let mut windows = Vec::with_capacity(24);
        for e in 0..3 {
            let (a, b) = (corners[e], corners[(e + 1) % 3]);
            let pa = [a[0] - st0[0], a[1] - st0[1]];
            let ab = [b[0] - a[0], b[1] - a[1]];
            let det = (pa[0] * ab[1] - pa[1] * ab[0]).abs();
            if det < 1e-300 {
                continue; // P on this edge of σ: the piece has no area
            }
            let ab2 = ab[0] * ab[0] + ab[1] * ab[1];
            let foot = (-(pa[0] * ab[0] + pa[1] * ab[1]) / ab2).clamp(0.0, 1.0);
            let breaks = graded_breaks(foot, det / ab2);
            let duffy = Duffy {
                p,
                k,
                st0,
                pa,
                ab,
                det,
                phi,
                m,
                graded: breaks.len() > 2,
            };
            let (angular, radial) = self.self_rule.ladders(duffy.graded);
            for w in breaks.windows(2) {
                let window = [0.0, 1.0, w[0], w[1]];
                let mut first = [0.0f64; 64];
                evals += self.tensor(&duffy, window, &radial[0], &angular[0], &mut first);
                windows.push((duffy, window, first));
            }
        }
        // The size of the integral, as the sum of its windows' magnitudes:
        // a φ that changes sign (a Lagrange basis function, u_n) can make
        // the total cancel to rounding, and a tolerance relative to that
        // would split every window to the depth limit.
        let scale = (0..m)
            .map(|j| windows.iter().map(|w| w.2[j].abs()).sum::<f64>())
            .fold(0.0, f64::max);
        let tol = self.opts.tol * scale;
        for (duffy, window, first) in &windows {
            evals += self.converge(duffy, *window, first, tol, 0, out);
        }
        evals
    }

    /// Adds the window's integral to `out`: up the ladder of rules from
    /// `first` (the first rung's value) until two successive rungs agree to
    /// `tol`, taking the higher; where even the last two disagree, the
    /// quadrants' own values (to a quarter of the tolerance each), down to
    /// [`MAX_SELF_DEPTH`].
    fn converge(
        &self,
        d: &Duffy<'_>,
        window: Window,
        first: &[f64; 64],
        tol: f64,
        depth: u32,
        out: &mut [f64],
    ) -> u64 {
        let m = d.m;
        let (angular, radial) = self.self_rule.ladders(d.graded);
        let mut prev = *first;
        let mut evals = 0;
        for (ur, vr) in radial.iter().zip(angular).skip(1) {
            let mut next = [0.0f64; 64];
            evals += self.tensor(d, window, ur, vr, &mut next);
            let agree = (0..m).all(|j| (next[j] - prev[j]).abs() <= tol);
            prev = next;
            if agree {
                for (o, v) in out.iter_mut().zip(&prev[..m]) {
                    *o += v;
                }
                return evals;
            }
        }
        if depth >= MAX_SELF_DEPTH {
            self.note_shortfall(d.p, d.k, 0.0);
            for (o, v) in out.iter_mut().zip(&prev[..m]) {
                *o += v;
            }
            return evals;
        }
        for q in quadrants(window) {
            let mut part = [0.0f64; 64];
            evals += self.tensor(d, q, &radial[0], &angular[0], &mut part);
            evals += self.converge(d, q, &part, 0.25 * tol, depth + 1, out);
        }
        evals
    }

    /// Adds the tensor rule `radial` × `angular` on `window` to `acc`.
    fn tensor(
        &self,
        d: &Duffy<'_>,
        [u0, u1, v0, v1]: Window,
        radial: &Rule,
        angular: &Rule,
        acc: &mut [f64; 64],
    ) -> u64 {
        let (ux, uw) = radial;
        let (vx, vw) = angular;
        let mut buf = [0.0f64; 64];
        let mut evals = 0;
        for (&x, &wv) in vx.iter().zip(vw) {
            let v = v0 + (v1 - v0) * x;
            for (&y, &wu) in ux.iter().zip(uw) {
                let u = u0 + (u1 - u0) * y;
                let st = [
                    d.st0[0] + u * d.pa[0] + u * v * d.ab[0],
                    d.st0[1] + u * d.pa[1] + u * v * d.ab[1],
                ];
                let q = self.mesh.point(d.k, st[0], st[1]);
                let wt = wu * wv * (u1 - u0) * (v1 - v0);
                let gw = g(d.p.position, d.p.normal, q.position, q.normal)
                    * q.jacobian
                    * wt
                    * u
                    * d.det
                    * FRAC_1_PI;
                evals += 1;
                if gw == 0.0 {
                    continue;
                }
                (d.phi)(d.k, st, q.position, &mut buf[..d.m]);
                for (o, val) in acc.iter_mut().zip(&buf[..d.m]) {
                    *o += gw * val;
                }
            }
        }
        evals
    }
}

/// Break points of [0, 1] graded geometrically towards `foot`: foot ± δ 2^j.
fn graded_breaks(foot: f64, delta: f64) -> Vec<f64> {
    let mut pts = vec![0.0, 1.0];
    if delta < 0.25 {
        pts.push(foot);
        let mut h = delta;
        while h < 1.0 {
            for c in [foot - h, foot + h] {
                if c > 0.0 && c < 1.0 {
                    pts.push(c);
                }
            }
            h *= 2.0;
        }
    }
    pts.sort_by(f64::total_cmp);
    pts.dedup_by(|a, b| (*a - *b).abs() < 1e-15);
    pts
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::assembly::QuadratureOptions;
    use crate::geometry::shapes::sphere;
    use crate::mesh::Mesh;
    use crate::nodes::NodeSet;
    use crate::quadrature::RuleLadder;
    use glam::DVec3;
    use std::sync::Arc;

    /// Every order a caller may give yields ladders of at least two rungs,
    /// rising; and the smallest still integrates a self pair (it used to be
    /// a single rung, which split every window to the depth limit).
    #[test]
    fn every_self_order_gives_a_ladder() {
        for order in 0..=40 {
            let rules = SelfRules::new(order);
            for graded in [false, true] {
                let (angular, radial) = rules.ladders(graded);
                assert!(
                    angular.len() >= 2 && radial.len() == angular.len(),
                    "{order}"
                );
                for l in [angular, radial] {
                    assert!(l.windows(2).all(|w| w[0].0.len() < w[1].0.len()), "{order}");
                }
            }
        }
        let mesh = Mesh::new(Arc::new(sphere(1.0)), 2);
        let ladder = RuleLadder::new();
        let opts = QuadratureOptions {
            self_order: 2,
            ..QuadratureOptions::default()
        };
        let integrator = ElementIntegrator::new(&mesh, &ladder, opts);
        let nodes = NodeSet::new(1, 0.1).unwrap();
        let phi = |_k: usize, st: [f64; 2], _q: DVec3, out: &mut [f64]| {
            nodes.eval_basis(st[0], st[1], out)
        };
        let exact = super::super::tests::unit_sphere_row(&mesh, 5, &nodes, &ladder);
        let [s, t] = nodes.points()[0];
        let q = mesh.point(5, s, t);
        let p = FieldPoint {
            position: q.position,
            normal: q.normal,
            on_element: Some((5, [s, t])),
        };
        let mut out = vec![0.0; 3];
        let evals = integrator.integrate(&p, 5, 1, &phi, &mut out);
        assert!(evals < 100_000, "{evals} kernel evaluations");
        for (a, b) in out.iter().zip(&exact) {
            assert!(
                (a - b).abs() <= 1e-12 * exact.iter().sum::<f64>(),
                "{a} against {b}"
            );
        }
    }

    /// On the unit sphere G ≡ 1/4, so the self integral at every node is
    /// ∫_Δ φ dS / 4π, here from one plain rule of degree 30 (no kernel, no
    /// Duffy windows), for r = 1..3 on elements of three sizes.
    #[test]
    fn self_pairs_on_the_sphere_are_the_closed_form() {
        let ladder = RuleLadder::new();
        for level in [0, 2, 4] {
            let mesh = Mesh::new(Arc::new(sphere(1.0)), level);
            let integrator = ElementIntegrator::new(&mesh, &ladder, QuadratureOptions::default());
            for r in 1..=3 {
                let nodes = NodeSet::new(r, 0.1).unwrap();
                let phi = |_k: usize, st: [f64; 2], _q: DVec3, out: &mut [f64]| {
                    nodes.eval_basis(st[0], st[1], out)
                };
                let f = nodes.len();
                let k = mesh.len() / 3;
                let exact = super::super::tests::unit_sphere_row(&mesh, k, &nodes, &ladder);
                let scale: f64 = exact.iter().map(|x| x.abs()).sum();
                for &[s, t] in nodes.points() {
                    let q = mesh.point(k, s, t);
                    let p = FieldPoint {
                        position: q.position,
                        normal: q.normal,
                        on_element: Some((k, [s, t])),
                    };
                    let mut out = vec![0.0; f];
                    integrator.integrate(&p, k, r, &phi, &mut out);
                    for (a, b) in out.iter().zip(&exact) {
                        assert!(
                            (a - b).abs() <= 1e-12 * scale,
                            "level {level} r {r}: {a} against {b}"
                        );
                    }
                }
            }
        }
    }
}
