//! The geometric kernel G(P, Q) of the radiosity equation (eq. 2).

use glam::DVec3;

/// G(P, Q) = [(Q-P)·n_P]⁺ [(P-Q)·n_Q]⁺ / |P-Q|⁴ with inner unit normals.
///
/// The cosines are clamped at zero: a point behind the tangent plane of the
/// other sends it no light. On the boundary of a convex set both cosines are
/// non-negative (Lemma 1b) and the clamp changes nothing. Only arithmetic is
/// used (no transcendental functions), so the GPU shader computes the same.
#[inline(always)]
pub fn g(p: DVec3, n_p: DVec3, q: DVec3, n_q: DVec3) -> f64 {
    let d = q - p;
    let a = d.dot(n_p).max(0.0);
    let b = (-d.dot(n_q)).max(0.0);
    let r2 = d.length_squared();
    a * b / (r2 * r2)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Lemma 1(d): G ≡ 1/4 on the unit sphere with inner normals.
    #[test]
    fn g_is_one_quarter_on_the_unit_sphere() {
        let pts = [
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 0.6, 0.8),
            DVec3::new(-0.48, 0.6, -0.64),
        ];
        for &p in &pts {
            for &q in &pts {
                if p != q {
                    crate::assert_close!(g(p, -p, q, -q), 0.25, 1e-15);
                }
            }
        }
    }

    #[test]
    fn back_facing_points_contribute_nothing() {
        let p = DVec3::ZERO;
        let q = DVec3::new(0.0, 0.0, 1.0);
        assert_eq!(g(p, DVec3::Z, q, DVec3::Z), 0.0); // Q faces away
        assert_eq!(g(p, -DVec3::Z, q, -DVec3::Z), 0.0); // P faces away
        crate::assert_close!(g(p, DVec3::Z, q, -DVec3::Z), 1.0, 1e-16);
    }
}
