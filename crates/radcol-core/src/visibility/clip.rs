//! The part of a flat element that a point P sees, as convex polygons in the
//! element's (s, t) coordinates.
//!
//! Everything here is an intersection of half-planes, because every condition
//! is linear in the point Y = v0 + s (v1 - v0) + t (v2 - v0) of the element:
//! * the horizon: Y in front of P's tangent plane, (Y - P)·n_P > 0 (behind it
//!   G = 0; clipping removes the kink of the clamped cosine from the rules);
//! * the shadow of an occluder T = [a, b, c] is where the segment PY crosses
//!   T: Y beyond T's plane (on the side away from P) and inside the three
//!   planes through P and T's edges. Subtracting a convex shadow from a convex
//!   piece leaves at most four convex pieces (one outside each half-plane).
//!
//! The visible region is therefore exact (up to rounding): quadrature then
//! sees only smooth integrands, and V needs no per-point rays.

use super::occluders::Occluders;
use glam::DVec3;

/// A convex polygon in (s, t), counter-clockwise or clockwise.
pub type Polygon = Vec<[f64; 2]>;

/// A linear function c + g_s s + g_t t on the element's (s, t) plane.
#[derive(Clone, Copy, Debug)]
struct Linear {
    c: f64,
    gs: f64,
    gt: f64,
}

impl Linear {
    /// (Y - origin)·dir as a function of (s, t) on the element [v0, v1, v2].
    fn along(v: &[DVec3; 3], origin: DVec3, dir: DVec3) -> Self {
        Self {
            c: (v[0] - origin).dot(dir),
            gs: (v[1] - v[0]).dot(dir),
            gt: (v[2] - v[0]).dot(dir),
        }
    }

    #[inline]
    fn at(&self, p: [f64; 2]) -> f64 {
        self.c + self.gs * p[0] + self.gt * p[1]
    }

    fn neg(self) -> Self {
        Self {
            c: -self.c,
            gs: -self.gs,
            gt: -self.gt,
        }
    }
}

/// The part of `poly` where `h ≥ 0` (Sutherland–Hodgman against one line).
fn clip(poly: &[[f64; 2]], h: Linear) -> Polygon {
    let mut out = Vec::with_capacity(poly.len() + 1);
    let n = poly.len();
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        let (ha, hb) = (h.at(a), h.at(b));
        if ha >= 0.0 {
            out.push(a);
        }
        if (ha >= 0.0) != (hb >= 0.0) {
            let t = ha / (ha - hb);
            out.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
        }
    }
    out
}

/// Area of a polygon in (s, t).
pub fn area(poly: &[[f64; 2]]) -> f64 {
    let n = poly.len();
    let mut twice = 0.0;
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        twice += a[0] * b[1] - a[1] * b[0];
    }
    0.5 * twice.abs()
}

/// Pieces smaller than this fraction of σ's area carry no weight worth a rule.
const MIN_AREA: f64 = 1e-13;

/// True when the open segment p q crosses the occluder's triangle (for
/// [`crate::assembly::VisibilityMode::Rays`]): the ends strictly on either
/// side of its plane and the crossing point strictly inside it.
pub fn blocks(p: DVec3, q: DVec3, t: &super::occluders::Occluder) -> bool {
    super::occluders::crosses(p, q, t, 0.0)
}

/// The convex pieces of the flat element `v` that the point `p` (unit normal
/// `n_p`) sees past the occluders `cands` of `occ`, in (s, t) coordinates.
pub fn visible_region(
    p: DVec3,
    n_p: DVec3,
    v: &[DVec3; 3],
    occ: &Occluders,
    cands: &[u32],
) -> Vec<Polygon> {
    let sigma: Polygon = vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
    let front = clip(&sigma, Linear::along(v, p, n_p));
    if area(&front) <= MIN_AREA {
        return Vec::new();
    }
    let mut pieces = vec![front];
    let tol = 1e-12 * occ.scale();
    for &i in cands {
        let t = occ.get(i);
        let side = (p - t.v[0]).dot(t.normal);
        if side.abs() <= tol {
            continue; // P in T's plane: T is seen edge-on and hides nothing
        }
        // Inside the shadow: all four ≥ 0.
        let mut shadow = [Linear::along(v, t.v[0], t.normal * (-side.signum())); 4];
        for e in 0..3 {
            let (a, b, c) = (t.v[e], t.v[(e + 1) % 3], t.v[(e + 2) % 3]);
            let mut m = (a - p).cross(b - p);
            if (c - p).dot(m) < 0.0 {
                m = -m;
            }
            shadow[e + 1] = Linear::along(v, p, m);
        }
        let mut next = Vec::with_capacity(pieces.len() + 3);
        for piece in pieces {
            let mut rest = piece;
            for h in shadow {
                let outside = clip(&rest, h.neg());
                if area(&outside) > MIN_AREA {
                    next.push(outside);
                }
                rest = clip(&rest, h);
                if area(&rest) <= MIN_AREA {
                    break;
                }
            }
            // What is left of `rest` lies in T's shadow.
        }
        pieces = next;
        if pieces.is_empty() {
            break;
        }
    }
    pieces
}

/// Fan triangulation of a convex polygon.
pub fn triangles(poly: &[[f64; 2]]) -> impl Iterator<Item = [[f64; 2]; 3]> + '_ {
    (1..poly.len().saturating_sub(1)).map(move |i| [poly[0], poly[i], poly[i + 1]])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn total(pieces: &[Polygon]) -> f64 {
        pieces.iter().map(|p| area(p)).sum()
    }

    /// The horizon cuts the element along a line: the area in front of P's
    /// tangent plane, in closed form.
    #[test]
    fn horizon_clip_keeps_the_front_part() {
        let v = [
            DVec3::new(0., 0., 0.),
            DVec3::new(1., 0., 0.),
            DVec3::new(0., 1., 0.),
        ];
        let occ = Occluders::new(&[]);
        // P on the plane x = 0.5 facing +x: the part x > 0.5 of the element,
        // a triangle with legs 0.5: area 0.125 in (s, t).
        let pieces = visible_region(DVec3::new(0.5, 0.0, 1.0), DVec3::X, &v, &occ, &[]);
        crate::assert_close!(total(&pieces), 0.125, 1e-15, "{}", total(&pieces));
        // Facing -x: the rest.
        let pieces = visible_region(DVec3::new(0.5, 0.0, 1.0), -DVec3::X, &v, &occ, &[]);
        crate::assert_close!(total(&pieces), 0.375, 1e-15);
    }

    /// A square occluder half way between P and the element hides a square of
    /// twice its side (central projection), in closed form.
    #[test]
    fn shadow_of_a_square_is_its_projection() {
        // Element: the square [-1,1]² at z = 0 as two triangles; P at z = 2
        // looking down; blocker [-0.25,0.25]² at z = 1 hides [-0.5,0.5]².
        let sq = |h: f64, z: f64| {
            let c = [
                DVec3::new(-h, -h, z),
                DVec3::new(h, -h, z),
                DVec3::new(h, h, z),
                DVec3::new(-h, h, z),
            ];
            [[c[0], c[1], c[2]], [c[0], c[2], c[3]]]
        };
        let occ = Occluders::new(&sq(0.25, 1.0));
        let p = DVec3::new(0.0, 0.0, 2.0);
        let mut hidden = 0.0;
        for el in sq(1.0, 0.0) {
            let visible = total(&visible_region(p, -DVec3::Z, &el, &occ, &[0, 1]));
            // (s, t) area × 2 × element area (2 here) = physical area.
            hidden += (0.5 - visible) * 2.0 * 2.0;
        }
        crate::assert_close!(hidden, 1.0, 1e-13, "hidden area {hidden}");
    }

    /// An occluder behind P or beyond the element hides nothing.
    #[test]
    fn occluders_outside_the_segment_hide_nothing() {
        let v = [
            DVec3::new(-1., -1., 0.),
            DVec3::new(1., -1., 0.),
            DVec3::new(0., 1., 0.),
        ];
        let behind_p = [
            DVec3::new(-5., -5., 3.),
            DVec3::new(5., -5., 3.),
            DVec3::new(0., 5., 3.),
        ];
        let below = [
            DVec3::new(-5., -5., -1.),
            DVec3::new(5., -5., -1.),
            DVec3::new(0., 5., -1.),
        ];
        let occ = Occluders::new(&[behind_p, below]);
        let p = DVec3::new(0.0, 0.0, 2.0);
        let pieces = visible_region(p, -DVec3::Z, &v, &occ, &[0, 1]);
        crate::assert_close!(total(&pieces), 0.5, 1e-15);
    }
}
