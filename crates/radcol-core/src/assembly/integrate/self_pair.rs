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
//! checked: its n × n rule is compared with n/2 × n/2 rules on its four
//! quadrants, and where the two disagree by more than the tolerance the
//! quadrants are integrated the same way, recursively. Where the rule is
//! already accurate (the sphere, every flat-ish element) the result is the
//! n × n value as before, at twice the kernel evaluations of a self pair.

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

/// Gauss–Legendre rules on [0, 1] for self pairs: `radial` and `angular` with
/// `self_order` points, `graded` with about half as many for each piece of a
/// geometrically graded angular interval; each with a half-order companion
/// used on the quadrants to check it.
#[derive(Clone, Debug)]
pub struct SelfRules {
    radial: [Rule; 2],
    angular: [Rule; 2],
    graded: [Rule; 2],
}

impl SelfRules {
    /// Rules for `order` points per direction.
    pub fn new(order: usize) -> Self {
        let order = order.max(2);
        let pair = |n: usize| [gauss_legendre01(n), gauss_legendre01(n.div_ceil(2))];
        Self {
            radial: pair(order),
            angular: pair(order),
            graded: pair(order.div_ceil(2) + 2),
        }
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
        // First pass: every window with its n × n rule (the values to check).
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
            let rules = if breaks.len() > 2 {
                &self.self_rule.graded
            } else {
                &self.self_rule.angular
            };
            let duffy = Duffy {
                p,
                k,
                st0,
                pa,
                ab,
                det,
                phi,
                m,
            };
            for w in breaks.windows(2) {
                let window = [0.0, 1.0, w[0], w[1]];
                let mut coarse = [0.0f64; 64];
                evals += self.tensor(&duffy, window, 0, &rules[0], &mut coarse);
                windows.push((duffy, window, rules, coarse));
            }
        }
        // The size of the integral, as the sum of its windows' magnitudes:
        // a φ that changes sign (a Lagrange basis function, u_n) can make
        // the total cancel to rounding, and a tolerance relative to that
        // would split every window to the depth limit.
        let scale = (0..m)
            .map(|j| windows.iter().map(|w| w.3[j].abs()).sum::<f64>())
            .fold(0.0, f64::max);
        let tol = self.opts.tol * scale;
        for (duffy, window, rules, coarse) in &windows {
            evals += self.check_window(duffy, *window, rules, coarse, tol, 0, out);
        }
        evals
    }

    /// Adds the window's integral to `out`: `coarse` (its n × n value) when
    /// the half-order rules on its quadrants agree with it to `tol`, else the
    /// quadrants' own checked values.
    #[allow(clippy::too_many_arguments)]
    fn check_window(
        &self,
        d: &Duffy<'_>,
        window: Window,
        rules: &[Rule; 2],
        coarse: &[f64; 64],
        tol: f64,
        depth: u32,
        out: &mut [f64],
    ) -> u64 {
        let m = d.m;
        let mut fine = [0.0f64; 64];
        let mut evals = self.tensor(d, window, 1, &rules[1], &mut fine);
        if (0..m).all(|j| (coarse[j] - fine[j]).abs() <= tol) {
            for (o, v) in out.iter_mut().zip(&coarse[..m]) {
                *o += v;
            }
            return evals;
        }
        fine = [0.0f64; 64];
        for q in quadrants(window) {
            evals += self.tensor(d, q, 1, &rules[1], &mut fine);
        }
        let agree = (0..m).all(|j| (coarse[j] - fine[j]).abs() <= tol);
        if !agree && depth >= MAX_SELF_DEPTH {
            self.note_shortfall(d.p, d.k, 0.0);
        }
        if agree || depth >= MAX_SELF_DEPTH {
            let best = if agree { coarse } else { &fine };
            for (o, v) in out.iter_mut().zip(&best[..m]) {
                *o += v;
            }
            return evals;
        }
        for q in quadrants(window) {
            let mut part = [0.0f64; 64];
            evals += self.tensor(d, q, 0, &rules[0], &mut part);
            evals += self.check_window(d, q, rules, &part, 0.25 * tol, depth + 1, out);
        }
        evals
    }

    /// Adds the tensor rule `angular` × (radial rule `which`) on `window` to `acc`.
    fn tensor(
        &self,
        d: &Duffy<'_>,
        [u0, u1, v0, v1]: Window,
        which: usize,
        angular: &Rule,
        acc: &mut [f64; 64],
    ) -> u64 {
        let (ux, uw) = &self.self_rule.radial[which];
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
