//! Query points on an edge where faces meet at an angle (a room's floor
//! against its wall, a cube's edges and corners).
//!
//! A point P of face A that lies in the plane of another face B sees B
//! edge-on: G(P, Q) = 0 for every Q of B, since (P - Q)·n_B = 0. Yet points
//! of A approaching P see B under a finite, non-zero weight. The value
//! asked for at P is the limit from A (the face whose normal the point
//! takes, approached from P towards its element's centre along the unit d
//! of A), and that limit concentrates at P: with P_δ = P + δ d and
//! Q = P + δ q, q in the plane of B (t along the edge line L, e_B across it
//! in B),
//!
//! ```text
//!   G(P_δ, Q) dQ = (q·n_A)(d·n_B) / |q - d|⁴ dq,
//! ```
//!
//! the same for every δ. So as δ → 0 the elements of B that touch P add
//! u_n(P) (from each element) times (1/π) ∫ of that over the angular wedge
//! they occupy at P; the rest of B adds nothing. On an edge at a right
//! angle the half-plane's weight is 1/2: a closed room's row sums are 1 at
//! its edges and corners too (`tests/tests/query.rs`).

use crate::mesh::{Located, Mesh};
use crate::quadrature::gauss::gauss_legendre01;
use glam::DVec3;
use std::f64::consts::PI;

/// ∫_0^∞ r² / (r² - 2 b r + 1)² dr for |b| < 1, in closed form: with
/// a² = 1 - b² and Θ = π/2 + atan(b / a), it is Θ / a + b + (2b² - 1)
/// (Θ / (2a³) + b / (2a²)) (π/4 at b = 0).
fn radial(b: f64) -> f64 {
    let a2 = (1.0 - b * b).max(1e-300);
    let a = a2.sqrt();
    let theta = PI / 2.0 + (b / a).atan();
    theta / a + b + (2.0 * b * b - 1.0) * (theta / (2.0 * a2 * a) + b / (2.0 * a2))
}

/// (1/π) ∫ over the directions φ ∈ [lo, hi] ⊂ [0, π] of the plane of B
/// (φ from t towards e_B) of κ r² sin φ / (r² - 2 b(φ) r + 1)² dr dφ, with
/// b(φ) = b_t cos φ + b_e sin φ (|b| < 1): the limit weight of that wedge.
pub(super) fn wedge_weight(b_t: f64, b_e: f64, kappa: f64, lo: f64, hi: f64) -> f64 {
    if hi <= lo || kappa <= 0.0 {
        return 0.0;
    }
    let (x, w) = gauss_legendre01(64);
    let angular: f64 = (x.iter().zip(&w))
        .map(|(&v, &wv)| {
            let phi = lo + (hi - lo) * v;
            wv * phi.sin() * radial(b_t * phi.cos() + b_e * phi.sin())
        })
        .sum();
    kappa / PI * (hi - lo) * angular
}

/// The element `k`'s share of the row at `at` when `at` lies on an edge
/// where `k`'s plane meets the face of `at.element` at an angle: its wedge
/// weight times its basis functions at P (`basis(st, out)`), added to
/// `out`. False (nothing added) when P is not in `k`'s plane or closure
/// within `tol`, or `k` is parallel to the point's face.
pub(super) fn add_edge_limit(
    mesh: &Mesh,
    at: &Located,
    k: usize,
    tol: f64,
    basis: &dyn Fn([f64; 2], &mut [f64]),
    out: &mut [f64],
) -> bool {
    let v = mesh.vertices(k);
    let n_b = mesh.point(k, 1.0 / 3.0, 1.0 / 3.0).normal;
    let (p, n_a) = (at.position, at.normal);
    if (p - v[0]).dot(n_b).abs() > tol {
        return false;
    }
    let t = n_a.cross(n_b);
    if t.length() < 1e-9 {
        return false;
    }
    let t = t.normalize();
    let Some(lambda) = barycentric(&v, p, tol) else {
        return false;
    };
    // e_B: across L in B, towards A's front; e_A: across L in A, into the
    // element the point was found on.
    let mut e_b = n_b.cross(t);
    if e_b.dot(n_a) < 0.0 {
        e_b = -e_b;
    }
    // The approach: from P towards the centre of its element, in A.
    let own = mesh.vertices(at.element);
    let centre = (own[0] + own[1] + own[2]) / 3.0;
    let d = centre - p;
    let d = (d - d.dot(n_a) * n_a).normalize();
    let kappa = e_b.dot(n_a) * d.dot(n_b);
    if kappa.is_nan() || kappa <= 0.0 {
        return false;
    }
    let (b_t, b_e) = (d.dot(t), d.dot(e_b));
    let angle = |d: DVec3| d.dot(e_b).atan2(d.dot(t));
    let (lo, span) = wedge(&v, lambda, p, tol, angle);
    let mut weight = 0.0;
    // The wedge [lo, lo + span] (span ≤ 2π) against [0, π], one turn either way.
    for shift in [-2.0 * PI, 0.0, 2.0 * PI] {
        let (a, b) = (lo + shift, lo + shift + span);
        weight += wedge_weight(b_t, b_e, kappa, a.max(0.0), b.min(PI));
    }
    if weight <= 0.0 {
        return false;
    }
    let mut values = vec![0.0; out.len()];
    basis([lambda[1], lambda[2]], &mut values);
    for (o, b) in out.iter_mut().zip(values) {
        *o += weight * b;
    }
    true
}

/// The angular wedge the triangle `v` occupies at its point P (barycentric
/// `lambda`): (start angle, span), angles from `angle`. A vertex: its
/// corner; an edge: the half-plane on the triangle's side; inside: all.
fn wedge(
    v: &[DVec3; 3],
    lambda: [f64; 3],
    p: DVec3,
    tol: f64,
    angle: impl Fn(DVec3) -> f64,
) -> (f64, f64) {
    let scale = (v[1] - v[0]).length().max((v[2] - v[0]).length());
    let at_vertex = (0..3).find(|&i| (v[i] - p).length() <= tol.max(1e-9 * scale));
    let ccw = |a: f64, b: f64| (b - a).rem_euclid(2.0 * PI);
    if let Some(i) = at_vertex {
        let (a, b) = (angle(v[(i + 1) % 3] - v[i]), angle(v[(i + 2) % 3] - v[i]));
        let span = ccw(a, b);
        return if span <= PI {
            (a, span)
        } else {
            (b, ccw(b, a))
        };
    }
    let on_edge = (0..3).find(|&i| lambda[i] <= 1e-9);
    if let Some(i) = on_edge {
        // The edge opposite vertex i; the triangle lies on vertex i's side.
        let (a, b) = (v[(i + 1) % 3], v[(i + 2) % 3]);
        let (d, inner) = (angle(b - a), angle(v[i] - p));
        let start = if ccw(d, inner) <= PI { d } else { d + PI };
        return (start, PI);
    }
    (-PI, 2.0 * PI)
}

/// Barycentric coordinates of `p` in the triangle `v`, when it lies in
/// its closure within `tol` (a length).
fn barycentric(v: &[DVec3; 3], p: DVec3, tol: f64) -> Option<[f64; 3]> {
    let [s, t] = crate::geometry::plane_st(v[0], v[1], v[2], p);
    let longest = (v[1] - v[0]).length().max((v[2] - v[0]).length());
    let slack = tol / longest;
    let inside = s >= -slack && t >= -slack && s + t <= 1.0 + slack;
    inside.then(|| {
        let (s, t) = (s.clamp(0.0, 1.0), t.clamp(0.0, 1.0));
        let excess = (s + t - 1.0).max(0.0) / 2.0;
        let (s, t) = (s - excess, t - excess);
        [1.0 - s - t, s, t]
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The weight of B's whole half-plane, with the integral along the edge
    /// done by hand (∫ dy / (a + y²)² = π / (2 a^{3/2})), is (κ/2) ∫_0^∞ x
    /// (x² - 2cx + 1)^{-3/2} dx: 1/2 at a right angle, and a 1-D quadrature
    /// of it at other angles (d across the edge, b = c sin φ); a quadrant of
    /// a right angle is half of that.
    #[test]
    fn wedge_weights_are_the_limits_of_the_view() {
        // The radial integral's closed form against a quadrature.
        let (x, w) = gauss_legendre01(400);
        for b in [-0.9, -0.4, 0.0, 0.5, 0.9] {
            let q: f64 = (x.iter().zip(&w))
                .map(|(&u, &wu)| {
                    let r = u / (1.0 - u);
                    let d = r * r - 2.0 * b * r + 1.0;
                    wu * r * r / (d * d) / ((1.0 - u) * (1.0 - u))
                })
                .sum();
            crate::assert_close!(radial(b), q, 1e-9, "b = {b}");
        }
        crate::assert_close!(wedge_weight(0.0, 0.0, 1.0, 0.0, PI), 0.5, 1e-10);
        crate::assert_close!(wedge_weight(0.0, 0.0, 1.0, 0.0, PI / 2.0), 0.25, 1e-10);
        crate::assert_close!(wedge_weight(0.0, 0.0, 1.0, PI / 2.0, PI), 0.25, 1e-10);
        for c in [-0.7, -0.3, 0.2, 0.6] {
            let kappa = 1.0 - c * c;
            // x = u / (1 - u) on [0, 1).
            let line: f64 = (x.iter().zip(&w))
                .map(|(&u, &wu)| {
                    let r = u / (1.0 - u);
                    wu * r / (r * r - 2.0 * c * r + 1.0).powf(1.5) / ((1.0 - u) * (1.0 - u))
                })
                .sum();
            let want = kappa / 2.0 * line;
            crate::assert_close!(wedge_weight(0.0, c, kappa, 0.0, PI), want, 1e-8, "c = {c}");
        }
    }
}
