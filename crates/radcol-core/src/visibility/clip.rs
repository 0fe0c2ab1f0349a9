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

/// Four points of the triangle `v` that rays are sent to: its centroid and
/// the midpoints between it and each vertex.
pub(crate) fn ray_targets(v: &[DVec3; 3]) -> [DVec3; 4] {
    let c = (v[0] + v[1] + v[2]) / 3.0;
    [c, 0.5 * (c + v[0]), 0.5 * (c + v[1]), 0.5 * (c + v[2])]
}

/// True when the point `p` (unit normal `n_p`) sees one of the
/// [`ray_targets`] of `v` in front of its tangent plane past every occluder
/// of `cands` (none blocks the segment: [`blocks`]). Then what `p` sees of
/// `v` is not empty, short of a ray grazing an occluder's edge (a set of
/// measure zero, where it may be). A cheap test before [`visible_region`]
/// when only emptiness is asked: a ray costs a few products per occluder,
/// a clip a polygon overlay.
pub(crate) fn sees_a_point(
    p: DVec3,
    n_p: DVec3,
    v: &[DVec3; 3],
    occ: &Occluders,
    cands: &[u32],
) -> bool {
    let tol = 1e-9 * occ.scale();
    ray_targets(v)
        .iter()
        .any(|&q| (q - p).dot(n_p) > tol && !cands.iter().any(|&i| blocks(p, q, occ.get(i))))
}

/// Above this many candidate occluders, their shadows are merged into one
/// region before it is taken from the element (`merged`); up to it they
/// are subtracted one by one (`subtracted`), which is exact to rounding
/// and cheapest for a few occluders but fragments the visible part with
/// every occluder that overlaps it: behind a closed mesh of m triangles the
/// pieces, and the work, grow like a power of m above 2 (measured on a room
/// with a decimated bunny), although the shadow's outline is only the mesh's
/// silhouette. 24 rather than 8: the Cornell box's pairs with 9 to 24
/// candidates assembled 3-5 % slower merged, and the bunny room with 1 000
/// triangles 7 % faster with 24 than with 8 (one run each, alternating).
pub const MERGE_ABOVE: usize = 24;

/// The part of the flat element `v` in front of the tangent plane of the
/// point `p` (unit normal `n_p`), in (s, t); None when it is negligible.
fn front_part(p: DVec3, n_p: DVec3, v: &[DVec3; 3]) -> Option<Polygon> {
    let sigma: Polygon = vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
    let front = clip(&sigma, Linear::along(v, p, n_p));
    (area(&front) > MIN_AREA).then_some(front)
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
    let Some(front) = front_part(p, n_p, v) else {
        return Vec::new();
    };
    let tol = 1e-12 * occ.scale();
    if cands.len() <= MERGE_ABOVE {
        let shadows: Vec<[Linear; 4]> = cands
            .iter()
            .filter_map(|&i| shadow_of(p, v, occ.get(i), tol))
            .filter(|shadow| !misses(&front, shadow))
            .collect();
        subtracted(front, shadows.into_iter())
    } else {
        merged(front, p, v, occ, cands, tol)
    }
}

/// The shadows that the occluders `cands` cast from the point `p` (unit
/// normal `n_p`) on the part of the flat element `v` in front of it: one
/// convex piece per occluder that casts one, in (s, t). Every point of a
/// piece is hidden from `p`; the pieces of neighbouring occluders overlap
/// or abut.
pub fn shadow_pieces(
    p: DVec3,
    n_p: DVec3,
    v: &[DVec3; 3],
    occ: &Occluders,
    cands: &[u32],
) -> Vec<Polygon> {
    let Some(front) = front_part(p, n_p, v) else {
        return Vec::new();
    };
    let tol = 1e-12 * occ.scale();
    cands
        .iter()
        .filter_map(|&i| shadow_of(p, v, occ.get(i), tol))
        .map(|shadow| shadow.iter().fold(front.clone(), |s, &h| clip(&s, h)))
        .filter(|piece| area(piece) > MIN_AREA)
        .collect()
}

/// The centroid of a polygon of nonzero area.
pub fn centroid(poly: &[[f64; 2]]) -> [f64; 2] {
    let (mut cx, mut cy, mut twice) = (0.0, 0.0, 0.0);
    for i in 0..poly.len() {
        let (p, q) = (poly[i], poly[(i + 1) % poly.len()]);
        let w = p[0] * q[1] - q[0] * p[1];
        cx += (p[0] + q[0]) * w;
        cy += (p[1] + q[1]) * w;
        twice += w;
    }
    [cx / (3.0 * twice), cy / (3.0 * twice)]
}

/// Whether the convex polygon `poly` (either orientation) holds `q`
/// (its boundary included).
pub fn contains(poly: &[[f64; 2]], q: [f64; 2]) -> bool {
    let side = |i: usize| {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        (b[0] - a[0]) * (q[1] - a[1]) - (b[1] - a[1]) * (q[0] - a[0])
    };
    let n = poly.len();
    (0..n).all(|i| side(i) >= 0.0) || (0..n).all(|i| side(i) <= 0.0)
}

/// Central projection from a point P onto the plane of an element, in the
/// element's (s, t), of the points strictly between that plane and the
/// plane through P parallel to it.
struct Projector {
    p: DVec3,
    v0: DVec3,
    /// Unit normal of the element's plane.
    n: DVec3,
    /// P's height above that plane (either sign).
    height: f64,
    /// The dual basis of the element's edges: s = (Y - v0)·gs, t = (Y - v0)·gt.
    gs: DVec3,
    gt: DVec3,
}

/// How far from σ a projected vertex may land (in (s, t)) for its triangle
/// to take the projected path: farther ones come from near P's parallel
/// plane and would stretch the overlay's integer grid.
const PROJECTED_REACH: f64 = 16.0;

impl Projector {
    fn new(p: DVec3, v: &[DVec3; 3]) -> Self {
        let (e1, e2) = (v[1] - v[0], v[2] - v[0]);
        let m = e1.cross(e2);
        let n = m.normalize();
        // Y - v0 = s e1 + t e2 ⇒ s = (Y - v0)·(e2 × m)/|m|², t = (Y - v0)·(m × e1)/|m|².
        let m2 = m.length_squared();
        Self {
            p,
            v0: v[0],
            n,
            height: (p - v[0]).dot(n),
            gs: e2.cross(m) / m2,
            gt: m.cross(e1) / m2,
        }
    }

    /// Where the segment from P through `x` meets the plane, when `x` lies
    /// strictly inside the slab (by more than `tol`) and lands within reach.
    fn project(&self, x: DVec3, tol: f64) -> Option<[f64; 2]> {
        let hx = (x - self.v0).dot(self.n);
        let inside = if self.height > 0.0 {
            hx > tol && hx < self.height - tol
        } else {
            hx < -tol && hx > self.height + tol
        };
        if !inside {
            return None;
        }
        let y = self.p + (x - self.p) * (self.height / (self.height - hx));
        let d = y - self.v0;
        let st = [d.dot(self.gs), d.dot(self.gt)];
        (st[0].abs() <= PROJECTED_REACH && st[1].abs() <= PROJECTED_REACH).then_some(st)
    }

    /// The shadow of a triangle wholly inside the slab: its projection,
    /// counter-clockwise. Each vertex is projected on its own, so triangles
    /// that share an edge cast shadows that share it to the bit, and the
    /// overlay merges them without computing crossings.
    fn triangle(&self, t: &[DVec3; 3], tol: f64) -> Option<Polygon> {
        let a = self.project(t[0], tol)?;
        let b = self.project(t[1], tol)?;
        let c = self.project(t[2], tol)?;
        let twice = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        Some(if twice >= 0.0 {
            vec![a, b, c]
        } else {
            vec![a, c, b]
        })
    }
}

/// The shadow that occluder `t` casts from `p` on the plane of element `v`:
/// the points Y with all four functions ≥ 0 (Y beyond T's plane, seen from
/// P, and inside the three planes through P and T's edges). None when P lies
/// in T's plane (within `tol`): T is seen edge-on and hides nothing.
#[inline]
fn shadow_of(
    p: DVec3,
    v: &[DVec3; 3],
    t: &super::occluders::Occluder,
    tol: f64,
) -> Option<[Linear; 4]> {
    let side = (p - t.v[0]).dot(t.normal);
    if side.abs() <= tol {
        return None;
    }
    let mut shadow = [Linear::along(v, t.v[0], t.normal * (-side.signum())); 4];
    for e in 0..3 {
        let (a, b, c) = (t.v[e], t.v[(e + 1) % 3], t.v[(e + 2) % 3]);
        let mut m = (a - p).cross(b - p);
        if (c - p).dot(m) < 0.0 {
            m = -m;
        }
        shadow[e + 1] = Linear::along(v, p, m);
    }
    Some(shadow)
}

/// True when one of the shadow's half-planes leaves every vertex of the
/// convex polygon `poly` clearly outside (by more than a rounding margin,
/// so that pieces clipped from `poly` lie outside too): the shadow misses
/// it, and subtracting it would only copy each piece.
fn misses(poly: &[[f64; 2]], shadow: &[Linear; 4]) -> bool {
    shadow.iter().any(|h| {
        let margin = 1e-9 * (h.gs.abs() + h.gt.abs());
        poly.iter().all(|&q| h.at(q) < -margin)
    })
}

/// `front` less each shadow in turn: subtracting a convex shadow from a
/// convex piece leaves at most four convex pieces (one outside each
/// half-plane).
fn subtracted(front: Polygon, shadows: impl Iterator<Item = [Linear; 4]>) -> Vec<Polygon> {
    let mut pieces = vec![front];
    for shadow in shadows {
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

/// `front` less the union of the shadows of the occluders `cands`, as
/// triangles. An occluder wholly between the element's plane and P's
/// parallel plane casts its central projection ([`Projector::triangle`]);
/// any other its shadow's half-planes clipped to `front` (a convex polygon).
/// Their union (non-zero rule) is subtracted in one overlay (i_overlay, in
/// 64-bit integer coordinates: a grid finer than f64's own step on σ), and
/// what remains is triangulated (i_triangle, Delaunay). Shadows of adjacent
/// triangles share their edges, so the outline that remains is the
/// occluders' silhouette, and the pieces grow with it, not with the number
/// of occluders.
fn merged(
    front: Polygon,
    p: DVec3,
    v: &[DVec3; 3],
    occ: &Occluders,
    cands: &[u32],
    tol: f64,
) -> Vec<Polygon> {
    use i_overlay::core::fill_rule::FillRule;
    use i_overlay::core::overlay_rule::OverlayRule;
    use i_overlay::float::overlay::FloatOverlay;
    use i_triangle::float::triangulatable::Triangulatable;

    let projector = Projector::new(p, v);
    let (lo, hi) = bounding_box(&front);
    let mut cast: Vec<Polygon> = Vec::with_capacity(cands.len());
    for &i in cands {
        let t = occ.get(i);
        if let Some(tri) = projector.triangle(&t.v, tol) {
            if meets_box(&tri, lo, hi) {
                cast.push(tri);
            }
            continue;
        }
        let Some(shadow) = shadow_of(p, v, t, tol) else {
            continue;
        };
        let mut s = front.clone();
        for h in shadow {
            s = clip(&s, h);
            if area(&s) <= MIN_AREA {
                break;
            }
        }
        if area(&s) > MIN_AREA {
            cast.push(s);
        }
    }
    if cast.is_empty() {
        return vec![front];
    }
    let rest = FloatOverlay::<[f64; 2], i64>::from_subj_and_clip(&front, &cast)
        .overlay(OverlayRule::Difference, FillRule::NonZero);
    if rest.is_empty() {
        return Vec::new();
    }
    let mesh = rest.triangulate_as::<i64>().into_delaunay();
    let points = mesh.points();
    mesh.triangle_indices::<usize>()
        .chunks_exact(3)
        .map(|t| vec![points[t[0]], points[t[1]], points[t[2]]])
        .filter(|t| area(t) > MIN_AREA)
        .collect()
}

/// The corners of the axis-aligned box around `poly`'s vertices.
fn bounding_box(poly: &[[f64; 2]]) -> ([f64; 2], [f64; 2]) {
    poly.iter().fold(
        ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
        |(lo, hi), q| {
            (
                [lo[0].min(q[0]), lo[1].min(q[1])],
                [hi[0].max(q[0]), hi[1].max(q[1])],
            )
        },
    )
}

/// False when the triangle `tri` lies wholly on one side of the box
/// [`lo`, `hi`] (a separating axis of the two): its shadow misses the
/// polygon in the box and changes nothing in the overlay but its size.
fn meets_box(tri: &[[f64; 2]], lo: [f64; 2], hi: [f64; 2]) -> bool {
    (0..2).all(|a| {
        tri.iter().any(|q| q[a] >= lo[a]) && tri.iter().any(|q| q[a] <= hi[a])
    })
}

/// Fan triangulation of a convex polygon, without the triangles whose
/// area is at rounding level (a thousandth of the smallest piece kept).
///
/// A polygon can repeat a vertex (where a shadow's edge meets the
/// element's corner), and the fan then holds triangles of no area. They
/// add nothing to an integral, but the adaptive quadrature splits a
/// segment into four segments that cover it twice, so next to a point it
/// doubled its work at every level down to its depth limit: a query a hair
/// from a block's foot corner on the Cornell box took 8 to 270 s.
pub fn triangles(poly: &[[f64; 2]]) -> impl Iterator<Item = [[f64; 2]; 3]> + '_ {
    (1..poly.len().saturating_sub(1))
        .map(move |i| [poly[0], poly[i], poly[i + 1]])
        .filter(|t| area(t) > FAN_AREA)
}

/// Fan triangles of at most this area (in the element's parameters, whose
/// triangle has area 1/2) are left out: a thousandth of the smallest piece
/// kept ([`MIN_AREA`]), below the rounding of any integral over the element.
const FAN_AREA: f64 = 1e-3 * MIN_AREA;

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

    /// The square [-h, h]² at height z as two triangles (split along the
    /// diagonal through (-h, -h)), facing up.
    fn square(h: f64, z: f64) -> [[DVec3; 3]; 2] {
        let c = [
            DVec3::new(-h, -h, z),
            DVec3::new(h, -h, z),
            DVec3::new(h, h, z),
            DVec3::new(-h, h, z),
        ];
        [[c[0], c[1], c[2]], [c[0], c[2], c[3]]]
    }

    /// A square occluder half way between P and the element hides a square of
    /// twice its side (central projection), in closed form.
    #[test]
    fn shadow_of_a_square_is_its_projection() {
        // Element: the square [-1,1]² at z = 0 as two triangles; P at z = 2
        // looking down; blocker [-0.25,0.25]² at z = 1 hides [-0.5,0.5]².
        let occ = Occluders::new(&square(0.25, 1.0));
        let p = DVec3::new(0.0, 0.0, 2.0);
        let mut hidden = 0.0;
        for el in square(1.0, 0.0) {
            let visible = total(&visible_region(p, -DVec3::Z, &el, &occ, &[0, 1]));
            // (s, t) area × 2 × element area (2 here) = physical area.
            hidden += (0.5 - visible) * 2.0 * 2.0;
        }
        crate::assert_close!(hidden, 1.0, 1e-13, "hidden area {hidden}");
    }

    /// ∫ 1, s, t, s², st, t² over the pieces (each triangle's exact moments
    /// from its vertices): the region seen through its first and second
    /// moments, whatever its split into pieces.
    fn moments(pieces: &[Polygon]) -> [f64; 6] {
        let mut m = [0.0; 6];
        for piece in pieces {
            for [a, b, c] in triangles(piece) {
                let ar = area(&[a, b, c]);
                let q = |i: usize, j: usize| {
                    (a[i] * a[j]
                        + b[i] * b[j]
                        + c[i] * c[j]
                        + (a[i] + b[i] + c[i]) * (a[j] + b[j] + c[j]))
                        / 12.0
                };
                m[0] += ar;
                m[1] += ar * (a[0] + b[0] + c[0]) / 3.0;
                m[2] += ar * (a[1] + b[1] + c[1]) / 3.0;
                m[3] += ar * q(0, 0);
                m[4] += ar * q(0, 1);
                m[5] += ar * q(1, 1);
            }
        }
        m
    }

    /// A closed, outward-facing polyhedral sphere of 8·4^level flat
    /// triangles (a subdivided octahedron), centre `c`, radius `r`.
    fn polysphere(level: u32, c: DVec3, r: f64) -> Vec<[DVec3; 3]> {
        let (x, y, z) = (DVec3::X, DVec3::Y, DVec3::Z);
        let mut tris = vec![
            [x, y, z],
            [y, -x, z],
            [-x, -y, z],
            [-y, x, z],
            [y, x, -z],
            [-x, y, -z],
            [-y, -x, -z],
            [x, -y, -z],
        ];
        for _ in 0..level {
            tris = tris
                .iter()
                .flat_map(|&[a, b, c]| {
                    let (ab, bc, ca) = (
                        ((a + b) / 2.0).normalize(),
                        ((b + c) / 2.0).normalize(),
                        ((c + a) / 2.0).normalize(),
                    );
                    [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
                })
                .collect();
        }
        tris.iter().map(|t| t.map(|v| c + v * r)).collect()
    }

    /// Area of the convex hull of points in the plane (monotone chain).
    fn hull_area(mut pts: Vec<[f64; 2]>) -> f64 {
        pts.sort_by(|a, b| a.partial_cmp(b).unwrap());
        let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
            (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
        };
        let mut hull: Vec<[f64; 2]> = Vec::new();
        for pass in 0..2 {
            let start = hull.len();
            let iter: Box<dyn Iterator<Item = &[f64; 2]>> = if pass == 0 {
                Box::new(pts.iter())
            } else {
                Box::new(pts.iter().rev())
            };
            for &p in iter {
                while hull.len() >= start + 2
                    && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
                {
                    hull.pop();
                }
                hull.push(p);
            }
            hull.pop();
        }
        area(&hull)
    }

    /// Behind a closed convex polyhedron of many triangles, the merged
    /// shadow is the convex hull of its vertices' central projections (an
    /// independent closed form), at every subdivision level, and the pieces
    /// left grow with the outline, not with the triangle count.
    #[test]
    fn merged_shadow_of_a_closed_polyhedron_is_its_projected_hull() {
        // Element: a large triangle at z = 0 (s, t = x / 4, y / 4 on it).
        let v = [
            DVec3::new(0., 0., 0.),
            DVec3::new(4., 0., 0.),
            DVec3::new(0., 4., 0.),
        ];
        let p = DVec3::new(1.1, 0.9, 3.0);
        let mut pieces_per_level = Vec::new();
        for level in 1..=4 {
            let tris = polysphere(level, DVec3::new(1.0, 1.0, 1.2), 0.3);
            let occ = Occluders::new(&tris);
            let cands: Vec<u32> = (0..tris.len() as u32).collect();
            assert!(cands.len() > MERGE_ABOVE);
            let pieces = visible_region(p, -DVec3::Z, &v, &occ, &cands);
            let projected: Vec<[f64; 2]> = tris
                .iter()
                .flatten()
                .map(|x| {
                    let y = p + (*x - p) * (p.z / (p.z - x.z));
                    [y.x / 4.0, y.y / 4.0]
                })
                .collect();
            let want = 0.5 - hull_area(projected);
            // Pieces under MIN_AREA are dropped by design (slivers of the
            // triangulation along the outline, here): the region is exact up
            // to a few of them, and closer than the one-by-one subtraction,
            // whose fragments are dropped by the same rule.
            crate::assert_close!(total(&pieces), want, 10.0 * MIN_AREA, "level {level}");
            if level <= 2 {
                // The one-by-one subtraction (too slow beyond: the reason
                // for merging) drops more.
                let sigma: Polygon = vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
                let front = clip(&sigma, Linear::along(&v, p, -DVec3::Z));
                let tol = 1e-12 * occ.scale();
                let shadows = cands
                    .iter()
                    .filter_map(|&i| shadow_of(p, &v, occ.get(i), tol));
                let sub = total(&subtracted(front, shadows));
                assert!(
                    (total(&pieces) - want).abs() <= (sub - want).abs() + 1e-15,
                    "level {level}"
                );
            }
            pieces_per_level.push(pieces.len());
        }
        // 4× the triangles per level, about 2× the outline.
        let growth = pieces_per_level[3] as f64 / pieces_per_level[2] as f64;
        assert!(growth < 3.0, "pieces per level {pieces_per_level:?}");
    }

    /// Merging and subtracting are two paths to one region: on random
    /// occluders (a closed polyhedron cut by the element's plane and by P's
    /// tangent plane, plus loose triangles straddling both), their areas and
    /// first and second moments agree to rounding.
    #[test]
    fn merged_and_subtracted_regions_agree() {
        let mut rnd = crate::testing::uniform(0x9e3779b97f4a7c15u64);
        let v = [
            DVec3::new(-1., -1., 0.),
            DVec3::new(2., -1., 0.2),
            DVec3::new(-1., 2., -0.1),
        ];
        let n_v = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
        let mut partial = 0;
        for case in 0..40 {
            let mut tris = polysphere(
                2,
                DVec3::new(rnd() - 0.5, rnd() - 0.5, 0.3 + rnd()),
                0.2 + 0.4 * rnd(),
            );
            for _ in 0..6 {
                let c = DVec3::new(2.0 * rnd() - 1.0, 2.0 * rnd() - 1.0, 1.5 * rnd());
                let mut d = || DVec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5);
                tris.push([c + d(), c + d(), c + d()]);
            }
            let occ = Occluders::new(&tris);
            let cands: Vec<u32> = (0..occ.len() as u32).collect();
            let p = DVec3::new(2.0 * rnd() - 1.0, 2.0 * rnd() - 1.0, 1.0 + rnd());
            let n_p = (-n_v + DVec3::new(rnd() - 0.5, rnd() - 0.5, 0.0)).normalize();
            let sigma: Polygon = vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
            let front = clip(&sigma, Linear::along(&v, p, n_p));
            let tol = 1e-12 * occ.scale();
            let shadows = || {
                cands
                    .iter()
                    .filter_map(|&i| shadow_of(p, &v, occ.get(i), tol))
            };
            let a = moments(&subtracted(front.clone(), shadows()));
            let b = moments(&merged(front, p, &v, &occ, &cands, tol));
            partial += usize::from(a[0] > 1e-3 && a[0] < 0.49);
            for k in 0..6 {
                crate::assert_close!(b[k], a[k], 1e-13, "case {case}, moment {k}");
            }
        }
        assert!(
            partial >= 20,
            "only {partial} of 40 cases are partly visible"
        );
    }

    /// A closed mesh's triangles that face away from P hide nothing more
    /// than the ones facing it ([`super::super::sealed`]): the visible
    /// region without them has the same area and moments, for P on the
    /// mesh itself and for P clear of it, with loose triangles mixed in.
    #[test]
    fn a_closed_mesh_hides_with_the_triangles_facing_p() {
        use super::super::sealed::facing_point;
        let mut rnd = crate::testing::uniform(0x5eed_5ea1_ed00_0001u64);
        let v = [
            DVec3::new(-1., -1., 0.),
            DVec3::new(2., -1., 0.2),
            DVec3::new(-1., 2., -0.1),
        ];
        let n_v = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
        let (mut filtered, mut partial) = (0, 0);
        for case in 0..40 {
            let centre = DVec3::new(rnd() - 0.5, rnd() - 0.5, 0.5 + rnd());
            let mut tris = polysphere(2, centre, 0.2 + 0.3 * rnd());
            let sphere = tris.len();
            for _ in 0..4 {
                let c = DVec3::new(2.0 * rnd() - 1.0, 2.0 * rnd() - 1.0, 1.5 * rnd());
                let mut d = || DVec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5);
                tris.push([c + d(), c + d(), c + d()]);
            }
            let occ = Occluders::new(&tris);
            let c = occ.sealed().component(0).expect("the sphere is closed");
            assert!((0..sphere as u32).all(|i| occ.sealed().component(i) == Some(c)));
            // P on a sphere triangle facing the element half the time, else
            // on a small element above the sphere.
            let (a, n_a, p) = if case % 2 == 0 {
                let t = (0..sphere)
                    .map(|i| occ.get(i as u32))
                    .find(|t| t.normal.dot(n_v) < -0.3 && rnd() < 0.2)
                    .unwrap_or(occ.get(0));
                let (x, y) = (0.1 + 0.4 * rnd(), 0.1 + 0.4 * rnd());
                (
                    t.v,
                    t.normal,
                    t.v[0] + x * (t.v[1] - t.v[0]) + y * (t.v[2] - t.v[0]),
                )
            } else {
                let p = DVec3::new(2.0 * rnd() - 1.0, 2.0 * rnd() - 1.0, 1.8 + rnd());
                let a = [p, p + DVec3::X * 0.01, p + DVec3::Y * 0.01];
                (a, -DVec3::Z, p + DVec3::new(0.003, 0.003, 0.0))
            };
            let tol = 1e-9 * occ.scale();
            if !occ.sealed().starts_in_front(c, occ.all(), &a, n_a, tol) {
                continue;
            }
            let all: Vec<u32> = (0..occ.len() as u32).collect();
            let fewer = facing_point(&occ, &[c], &all, p);
            assert!(fewer.len() < all.len(), "case {case}");
            filtered += 1;
            let want = moments(&visible_region(p, n_a, &v, &occ, &all));
            let got = moments(&visible_region(p, n_a, &v, &occ, &fewer));
            partial += usize::from(want[0] > 1e-3 && want[0] < 0.49);
            for k in 0..6 {
                crate::assert_close!(got[k], want[k], 1e-13, "case {case}, moment {k}");
            }
        }
        assert!(filtered >= 36, "only {filtered} of 40 cases filtered");
        assert!(partial >= 15, "only {partial} cases partly visible");
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

    /// A shadow that misses the element leaves it whole, in one piece: a
    /// triangle beside the element, whose shadow's first half-planes cut
    /// the element, used to split it into pieces that covered it (and
    /// dropped the slivers below [`MIN_AREA`]). Beside it, one that does
    /// meet the element still cuts it.
    #[test]
    fn a_shadow_that_misses_the_element_leaves_it_whole() {
        let v = [
            DVec3::new(0., 0., 0.),
            DVec3::new(1., 0., 0.),
            DVec3::new(0., 1., 0.),
        ];
        let p = DVec3::new(0.0, 0.0, 2.0);
        // In the plane x = 0.5 + 2z, about z = 1: its shadow lies near
        // x = 4.8, past the element, but its plane (the shadow's first
        // half-plane) crosses σ along x = 0.5.
        let beside = [
            DVec3::new(2.3, -0.5, 0.9),
            DVec3::new(2.7, -0.5, 1.1),
            DVec3::new(2.5, 0.5, 1.0),
        ];
        // Over the element's corner at the origin.
        let over = [
            DVec3::new(-0.2, -0.2, 1.0),
            DVec3::new(0.4, -0.2, 1.0),
            DVec3::new(-0.2, 0.4, 1.0),
        ];
        let occ = Occluders::new(&[beside, over]);
        let n = -DVec3::Z;
        let sh = shadow_of(p, &v, occ.get(0), 1e-12).unwrap();
        let sigma = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        let side = sigma.map(|q| sh[0].at(q) > 0.0);
        assert!(side.contains(&true) && side.contains(&false), "the case tests nothing");
        assert!(misses(&sigma, &sh));
        let whole = visible_region(p, n, &v, &occ, &[0]);
        assert_eq!(whole.len(), 1, "{whole:?}");
        crate::assert_close!(total(&whole), 0.5, 1e-15);
        assert!(!misses(&sigma, &shadow_of(p, &v, occ.get(1), 1e-12).unwrap()));
        let cut = total(&visible_region(p, n, &v, &occ, &[0, 1]));
        // The triangle at z = 1, half way down from P, casts one twice its
        // size, below x + y = 0.4: σ loses the triangle (0, 0), (0.4, 0),
        // (0, 0.4), of area 0.08 in (x, y), which are (s, t) here.
        crate::assert_close!(cut, 0.5 - 0.08, 1e-13, "{cut}");
    }

    /// The box test keeps every triangle that meets the box and drops those
    /// wholly to one side of it.
    #[test]
    fn the_box_test_separates_by_the_axes() {
        let (lo, hi) = ([0.0, 0.0], [1.0, 1.0]);
        assert!(meets_box(&[[0.5, 0.5], [2.0, 0.5], [0.5, 2.0]], lo, hi));
        assert!(meets_box(&[[-1.0, 0.5], [2.0, 0.4], [0.5, 0.6]], lo, hi));
        // Its box overlaps, the triangle does not: kept (the test is
        // conservative, the overlay decides).
        assert!(meets_box(&[[1.5, 0.9], [0.9, 1.5], [1.5, 1.5]], lo, hi));
        assert!(!meets_box(&[[-1.0, 0.5], [-0.1, 0.4], [-0.5, 0.6]], lo, hi));
        assert!(!meets_box(&[[0.2, 1.1], [0.4, 1.5], [0.9, 3.0]], lo, hi));
        assert!(!meets_box(&[[2.0, 0.1], [1.1, 0.5], [3.0, 0.2]], lo, hi));
        assert!(!meets_box(&[[0.2, -1.1], [0.4, -0.5], [0.9, -3.0]], lo, hi));
    }

    /// The shadow pieces of a square blocker half way between a point and
    /// a square element: one per blocker triangle and element triangle that
    /// overlap, abutting, their union the central projection (closed form: the
    /// square of twice the blocker's side, centred under the point), each
    /// holding its own centroid.
    #[test]
    fn shadow_pieces_tile_the_projection() {
        let occ = Occluders::new(&square(0.25, 1.0));
        let p = DVec3::new(0.0, 0.0, 2.0);
        let (mut area_sum, mut moment, mut count) = (0.0, DVec3::ZERO, 0);
        for el in square(1.0, 0.0) {
            for piece in shadow_pieces(p, -DVec3::Z, &el, &occ, &[0, 1]) {
                let c = centroid(&piece);
                assert!(contains(&piece, c), "{piece:?}");
                let at = el[0] + (el[1] - el[0]) * c[0] + (el[2] - el[0]) * c[1];
                // (s, t) area × 2 × element area (2 here) = physical area.
                let a = area(&piece) * 4.0;
                area_sum += a;
                moment += at * a;
                count += 1;
            }
        }
        // Both squares split along the same diagonal: each blocker
        // triangle shadows one element triangle (the other only along the
        // diagonal).
        assert_eq!(count, 2);
        crate::assert_close!(area_sum, 1.0, 1e-13, "{area_sum}");
        assert!(moment.length() < 1e-13, "{moment}");
        // Beside the element: no piece.
        let far = Occluders::new(&[[
            DVec3::new(3.0, 3.0, 1.0),
            DVec3::new(3.5, 3.0, 1.0),
            DVec3::new(3.0, 3.5, 1.0),
        ]]);
        assert!(shadow_pieces(p, -DVec3::Z, &square(1.0, 0.0)[0], &far, &[0]).is_empty());
        assert!(!contains(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], [0.6, 0.6]));
        assert!(contains(&[[0.0, 0.0], [0.0, 1.0], [1.0, 0.0]], [0.3, 0.3]));
    }
}
