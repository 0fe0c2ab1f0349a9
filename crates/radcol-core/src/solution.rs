//! The collocation solution u_n (eq. 18): nodal values, evaluation anywhere on
//! S, the iterated solution û_n = E + K u_n (eq. 21), ∫_S u_n, and its
//! nonnegative version for display ([`Solution::limited_nonnegative`]).

use crate::assembly::{ElementIntegrator, FieldPoint};
use crate::discretization::Discretization;
use crate::mesh::Locator;
use crate::nodes::MAX_DEGREE;
use crate::quadrature::RuleLadder;
use glam::DVec3;
use rayon::prelude::*;
use serde::Serialize;
use std::sync::{Arc, OnceLock};

/// Samples per element edge of the limiter's check for negative values: a
/// multiple of the norms' lattice (`norms::LATTICE`, 8; checked there), so
/// that every point the report counts, and the points between them, are
/// checked.
pub const LIMITER_LATTICE: usize = 16;

/// What [`Solution::limited_nonnegative`] changed.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Limited {
    /// Elements scaled towards their mean.
    pub elements: usize,
    /// Of those, elements whose mean was itself negative (set to 0: their
    /// integral is not kept).
    pub zeroed: usize,
    /// max |ũ_n − u_n| over S (absolute; on the limiter's lattice).
    pub max_change: f64,
    /// Per element, max |ũ_n − u_n| (0 where unchanged); length n.
    #[serde(skip)]
    pub change: Vec<f64>,
}

/// Nodal values of u_n on a discretization.
#[derive(Clone, Debug)]
pub struct Solution {
    disc: Arc<Discretization>,
    values: Vec<f64>,
    /// The BVH of [`Solution::eval_at`], built on its first call.
    locator: OnceLock<Arc<Locator>>,
}

impl Solution {
    /// Wraps nodal values (length N, ordered like the collocation points).
    pub fn new(disc: Arc<Discretization>, values: Vec<f64>) -> Self {
        assert_eq!(values.len(), disc.len(), "one value per collocation point");
        Self {
            disc,
            values,
            locator: OnceLock::new(),
        }
    }

    /// The discretization.
    pub fn discretization(&self) -> &Arc<Discretization> {
        &self.disc
    }

    /// u_n(v_i), length N.
    pub fn nodal(&self) -> &[f64] {
        &self.values
    }

    /// u_n at (s, t) of element `k`.
    pub fn eval(&self, k: usize, s: f64, t: f64) -> f64 {
        let nodes = self.disc.nodes_of(k);
        let f = nodes.len();
        let mut l = [0.0; (MAX_DEGREE + 1) * (MAX_DEGREE + 2) / 2];
        nodes.eval_basis(s, t, &mut l[..f]);
        l[..f]
            .iter()
            .zip(&self.values[self.disc.range(k)])
            .map(|(a, b)| a * b)
            .sum()
    }

    /// u_n made nonnegative element by element, for problems whose exact u is
    /// (E, ρ ≥ 0), with Zhang and Shu's scaling limiter (J. Comput. Phys. 229,
    /// 2010): on an element where u_n < 0 somewhere on the limiter's lattice,
    /// ũ_n = ū + θ (u_n − ū), ū the element's mean of u_n and θ ∈ [0, 1) the
    /// largest that keeps ũ_n ≥ 0 there (up to a floor of a few ulps against
    /// rounding). The element integral is kept, and the change is
    /// |m| max(M − ū, ū − m)/(ū − m) (M, m: max and min of u_n on the element):
    /// where the exact u ≥ 0, at most the element's error (|m| ≤ max |u − u_n|)
    /// times max(M − ū, ū − m)/(ū − m), a factor between 1 and 2 at r = 1 (the
    /// mean of a linear function on a triangle is the mean of its vertex
    /// values). None when u_n has no negative value there.
    pub fn limited_nonnegative(&self) -> Option<(Solution, Limited)> {
        let disc = &self.disc;
        let mesh = disc.mesh();
        let m = LIMITER_LATTICE;
        let lattice: Vec<[f64; 2]> = (0..=m)
            .flat_map(|a| (0..=m - a).map(move |b| [a as f64 / m as f64, b as f64 / m as f64]))
            .collect();
        let ladder = RuleLadder::new();
        let l = [0.0; (MAX_DEGREE + 1) * (MAX_DEGREE + 2) / 2];
        let eval = |k: usize, c: &[f64], st: &[f64; 2], l: &mut [f64]| -> f64 {
            let nodes = disc.nodes_of(k);
            let f = nodes.len();
            nodes.eval_basis(st[0], st[1], &mut l[..f]);
            l[..f].iter().zip(c).map(|(a, b)| a * b).sum()
        };
        // Per element that must be limited: its new coefficients, ū and the change.
        let limits: Vec<Option<(Vec<f64>, f64, f64)>> = (0..mesh.len())
            .into_par_iter()
            .map_init(
                || l,
                |l, k| {
                    let c = &self.values[disc.range(k)];
                    let (lo, hi) = lattice
                        .iter()
                        .map(|st| eval(k, c, st, l))
                        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), u| {
                            (a.min(u), b.max(u))
                        });
                    if lo >= 0.0 {
                        return None;
                    }
                    let r = disc.degree(k);
                    let rule = ladder.rule(if mesh.is_flat(k) { r } else { r + 6 });
                    let (mut num, mut den) = (0.0, 0.0);
                    for (&[s, t], &w) in rule.points.iter().zip(&rule.weights) {
                        let j = w * mesh.point(k, s, t).jacobian;
                        num += j * self.eval(k, s, t);
                        den += j;
                    }
                    let mean = (num / den).max(0.0);
                    // θ brings the minimum to a floor δ of a few ulps of the
                    // element's values rather than to 0, so that rounding in
                    // the new coefficients cannot leave it below zero; the
                    // lattice check guards the rest (θ = 0 is the constant ū).
                    let delta = 16.0 * f64::EPSILON * hi.max(-lo).max(mean);
                    let theta = ((mean - delta) / (mean - lo)).clamp(0.0, 1.0);
                    let scaled = |theta: f64| -> Vec<f64> {
                        c.iter().map(|&v| mean + theta * (v - mean)).collect()
                    };
                    let cand = scaled(theta);
                    let (new, theta) = if lattice.iter().all(|st| eval(k, &cand, st, l) >= 0.0) {
                        (cand, theta)
                    } else {
                        (scaled(0.0), 0.0)
                    };
                    let change = (1.0 - theta) * (hi - mean).max(mean - lo);
                    Some((new, mean, change))
                },
            )
            .collect();
        if limits.iter().all(Option::is_none) {
            return None;
        }
        let mut values = self.values.clone();
        let mut report = Limited {
            change: vec![0.0; mesh.len()],
            ..Limited::default()
        };
        for (k, lim) in limits.into_iter().enumerate() {
            let Some((new, mean, change)) = lim else {
                continue;
            };
            values[disc.range(k)].copy_from_slice(&new);
            report.elements += 1;
            report.zeroed += usize::from(mean == 0.0);
            report.change[k] = change;
            report.max_change = report.max_change.max(change);
        }
        Some((Solution::new(disc.clone(), values), report))
    }

    /// u_n at a point of S (None when the point is not on the mesh, within
    /// 1e-9 of the element's size: [`Mesh::locate`]'s test), found through a
    /// BVH over the elements built on the first call ([`Locator`]), so each
    /// call costs O(log n).
    ///
    /// [`Mesh::locate`]: crate::mesh::Mesh::locate
    pub fn eval_at(&self, x: DVec3) -> Option<f64> {
        let mesh = self.disc.mesh();
        let locator = self.locator.get_or_init(|| Arc::new(Locator::new(mesh)));
        let (k, [s, t]) = locator.locate(mesh, x)?;
        Some(self.eval(k, s, t))
    }

    /// ∫_S u_n dS (a rule exact for the polynomial on flat elements, r + 6 on curved ones).
    pub fn integral(&self) -> f64 {
        integrate_nodal(&self.disc, &self.values)
    }

    /// û_n(P) = E(P) + ρ(P) (1/π) ∫_S G(P, Q) u_n(Q) dS_Q at a point P of S, with
    /// `integrator` over this solution's mesh; `rho` and `emission` are ρ(P), E(P).
    pub fn iterated(
        &self,
        integrator: &ElementIntegrator<'_>,
        p: &FieldPoint,
        rho: f64,
        emission: f64,
    ) -> f64 {
        let phi = |k: usize, st: [f64; 2], _q: DVec3, out: &mut [f64]| {
            out[0] = self.eval(k, st[0], st[1]);
        };
        let mut acc = [0.0];
        for k in 0..self.disc.mesh().len() {
            integrator.integrate(p, k, self.disc.degree(k), &phi, &mut acc);
        }
        emission + rho * acc[0]
    }
}

/// ∫_S of the interpolant with nodal values `values` (length N).
pub fn integrate_nodal(disc: &Discretization, values: &[f64]) -> f64 {
    let mesh = disc.mesh();
    let ladder = RuleLadder::new();
    let mut l = vec![0.0; disc.max_nodes_per_element()];
    let mut total = 0.0;
    for k in 0..mesh.len() {
        let (nodes, r) = (disc.nodes_of(k), disc.degree(k));
        let l = &mut l[..nodes.len()];
        let rule = ladder.rule(if mesh.is_flat(k) { r } else { r + 6 });
        for (&[s, t], &w) in rule.points.iter().zip(&rule.weights) {
            nodes.eval_basis(s, t, l);
            let u: f64 = l
                .iter()
                .zip(&values[disc.range(k)])
                .map(|(a, b)| a * b)
                .sum();
            total += w * mesh.point(k, s, t).jacobian * u;
        }
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::shapes::{box_room, sphere};
    use crate::mesh::Mesh;
    use crate::nodes::NodeSet;

    /// With a degree per element, u_n evaluates each element's own
    /// polynomial (a quadratic in x, y, z is reproduced on flat elements
    /// of degree ≥ 2, a linear one on degree 1), its integral is the
    /// closed form, and the limiter works element by element.
    #[test]
    fn a_degree_per_element() {
        let mesh = Arc::new(Mesh::new(Arc::new(box_room(1.0, 2.0, 1.5)), 1));
        let sets = (1..=3).map(|r| NodeSet::new(r, 0.1).unwrap()).collect();
        let degrees: Vec<usize> = (0..mesh.len()).map(|k| 1 + k % 3).collect();
        let disc = Arc::new(Discretization::with_degrees(mesh.clone(), sets, &degrees).unwrap());
        let lin = |p: DVec3| 1.0 + p.x + 2.0 * p.y - p.z;
        let values = disc.points().iter().map(|p| lin(p.position)).collect();
        let u = Solution::new(disc.clone(), values);
        for k in 0..mesh.len() {
            for (s, t) in [(0.0, 0.0), (1.0, 0.0), (0.2, 0.7), (0.5, 0.5)] {
                let p = mesh.point(k, s, t).position;
                crate::assert_close!(u.eval(k, s, t), lin(p), 1e-13);
            }
        }
        // ∫ over the box's walls of 1 + x + 2y − z: the area plus each
        // wall's area times its centroid's x + 2y − z, from the walls' own
        // centroids (box [0, 1] × [0, 2] × [0, 1.5]).
        let walls = [
            (2.0 * 1.5, DVec3::new(0.0, 1.0, 0.75)),
            (2.0 * 1.5, DVec3::new(1.0, 1.0, 0.75)),
            (1.0 * 1.5, DVec3::new(0.5, 0.0, 0.75)),
            (1.0 * 1.5, DVec3::new(0.5, 2.0, 0.75)),
            (1.0 * 2.0, DVec3::new(0.5, 1.0, 0.0)),
            (1.0 * 2.0, DVec3::new(0.5, 1.0, 1.5)),
        ];
        let exact: f64 = walls.iter().map(|(a, c)| a * lin(*c)).sum();
        crate::assert_close!(u.integral(), exact, 1e-12 * exact);
        let mut values = vec![1.0; disc.len()];
        let k3 = (0..mesh.len()).find(|&k| degrees[k] == 3).unwrap();
        values[disc.range(k3).start + 4] = -3.0;
        let u = Solution::new(disc.clone(), values);
        let (v, report) = u.limited_nonnegative().expect("u_n < 0 on one element");
        assert_eq!(report.elements, 1);
        assert!(report.change[k3] > 0.0);
        assert!(lattice_min(&v, k3) >= 0.0);
        crate::assert_close!(v.integral(), u.integral(), 1e-13 * u.integral());
    }

    fn lattice_min(s: &Solution, k: usize) -> f64 {
        let m = LIMITER_LATTICE;
        (0..=m)
            .flat_map(|a| (0..=m - a).map(move |b| (a, b)))
            .map(|(a, b)| s.eval(k, a as f64 / m as f64, b as f64 / m as f64))
            .fold(f64::INFINITY, f64::min)
    }

    /// The limiter changes only the elements with negative values, keeps their
    /// integrals, leaves them nonnegative with a minimum at 0 (the largest θ),
    /// and does nothing to a nonnegative u_n; flat (box) and curved (sphere)
    /// elements, r = 1 and 3.
    #[test]
    fn limiter_keeps_integrals_and_removes_negative_values() {
        for (surface, r) in [(box_room(1.0, 2.0, 1.5), 1), (sphere(1.0), 3)] {
            let mesh = Arc::new(Mesh::new(Arc::new(surface), 1));
            let disc = Arc::new(Discretization::new(mesh, NodeSet::new(r, 0.1).unwrap()));
            let f = disc.nodes_per(0);
            let positive = Solution::new(disc.clone(), vec![1.0; disc.len()]);
            assert!(positive.limited_nonnegative().is_none());
            let mut values = vec![1.0; disc.len()];
            values[0] = -0.5;
            values[3 * f + 1] = -2.0;
            let u = Solution::new(disc.clone(), values);
            let (v, report) = u.limited_nonnegative().expect("u_n < 0 on two elements");
            assert_eq!(report.elements, 2);
            crate::assert_close!(v.integral(), u.integral(), 1e-13 * u.integral());
            for k in 0..disc.mesh().len() {
                let min = lattice_min(&v, k);
                assert!(min >= 0.0, "r={r} element {k}: {min}");
                if k == 0 || k == 3 {
                    assert!(min < 1e-12, "r={r} element {k}: θ not the largest ({min})");
                    assert!(report.change[k] > 0.0);
                } else {
                    assert_eq!(
                        &v.nodal()[k * f..(k + 1) * f],
                        &u.nodal()[k * f..(k + 1) * f]
                    );
                    assert_eq!(report.change[k], 0.0);
                }
            }
        }
    }
}
