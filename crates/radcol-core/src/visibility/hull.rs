//! The convex hull of a few points (the six vertices of a pair of
//! elements): its facet planes, to place a BVH box against it, and a
//! superset of its separating axes, for the exact test of one triangle.

use super::occluder::Occluder;
use crate::geometry::bounds;
use glam::DVec3;

/// Where a box lies against a convex hull.
pub(crate) enum Place {
    /// Beyond one of its planes by more than the tolerance: no point of
    /// the box meets the hull's interior.
    Outside,
    /// Strictly inside every facet by more than the tolerance.
    Inside,
    /// Neither decided.
    Across,
}

/// The facet planes of the convex hull of a few points (n·x ≤ d inside,
/// n unit), found among the planes through every triple of them; with
/// fewer than four the hull is flat, and no box is said to be inside it.
pub(crate) struct Facets {
    planes: Vec<(DVec3, f64)>,
    lo: DVec3,
    hi: DVec3,
    tol: f64,
}

impl Facets {
    pub(crate) fn new(pts: &[DVec3], tol: f64) -> Self {
        let m = pts.len();
        let mut planes = Vec::new();
        for i in 0..m {
            for j in i + 1..m {
                for k in j + 1..m {
                    let n = (pts[j] - pts[i]).cross(pts[k] - pts[i]);
                    let len = n.length();
                    if len.is_nan() || len <= 0.0 {
                        continue;
                    }
                    let n = n / len;
                    let d = pts[i].dot(n);
                    let side = |q: &DVec3| q.dot(n) - d;
                    let (below, above) = pts.iter().fold((false, false), |(b, a), q| {
                        (b || side(q) < -tol, a || side(q) > tol)
                    });
                    match (below, above) {
                        (true, false) => planes.push((n, d)),
                        (false, true) => planes.push((-n, -d)),
                        _ => {}
                    }
                }
            }
        }
        Self {
            planes,
            ..Self::box_only(pts, tol)
        }
    }

    /// Every box inside: below a node strictly inside the hull.
    pub(crate) fn everything() -> Self {
        Self {
            planes: Vec::new(),
            lo: DVec3::NEG_INFINITY,
            hi: DVec3::INFINITY,
            tol: 0.0,
        }
    }

    /// The hull's bounding box alone (no facet: nothing is inside).
    pub(crate) fn box_only(pts: &[DVec3], tol: f64) -> Self {
        let (lo, hi) = bounds(pts.iter().copied());
        Self {
            planes: Vec::new(),
            lo,
            hi,
            tol,
        }
    }

    /// Where triangle `v` lies: `Inside` when a corner is strictly inside
    /// every facet (so the triangle meets the hull's interior), `Outside`
    /// when every corner is beyond one facet, else `Across`. A flat hull
    /// (fewer than four facets) decides nothing.
    pub(crate) fn place_triangle(&self, v: &[DVec3; 3]) -> Place {
        if self.planes.len() < 4 {
            return Place::Across;
        }
        let t = self.tol;
        let mut inside = [true; 3];
        for &(n, d) in &self.planes {
            let side = v.map(|x| x.dot(n) - d);
            if side.iter().all(|&s| s > t) {
                return Place::Outside;
            }
            for (i, s) in inside.iter_mut().zip(side) {
                *i &= s < -t;
            }
        }
        if inside.iter().any(|&i| i) {
            Place::Inside
        } else {
            Place::Across
        }
    }

    pub(crate) fn classify(&self, lo: DVec3, hi: DVec3) -> Place {
        let t = self.tol;
        if lo.cmpgt(self.hi + t).any() || hi.cmplt(self.lo - t).any() {
            return Place::Outside;
        }
        if self.lo == DVec3::NEG_INFINITY {
            return Place::Inside;
        }
        let (c, e) = ((lo + hi) / 2.0, (hi - lo) / 2.0);
        let mut inside = self.planes.len() >= 4;
        for &(n, d) in &self.planes {
            let (mid, half) = (c.dot(n) - d, e.dot(n.abs()));
            if mid - half > t {
                return Place::Outside;
            }
            inside &= mid + half < -t;
        }
        if inside {
            Place::Inside
        } else {
            Place::Across
        }
    }
}

/// Candidate separating directions of a small point set's hull: the normals
/// of all its point triples and its point-to-point edges (a superset of the
/// hull's face normals and edges, so the separating-axis theorem stays exact).
pub(crate) struct HullAxes {
    /// The triple normals, each with the hull's extent along it (the same
    /// for every triangle tested, so found once).
    normals: Vec<(DVec3, f64, f64)>,
    edges: Vec<DVec3>,
}

/// The least and the greatest of `pts` along `axis`.
fn extent(pts: &[DVec3], axis: DVec3) -> (f64, f64) {
    let (mut h0, mut h1) = (f64::INFINITY, f64::NEG_INFINITY);
    for p in pts {
        let d = p.dot(axis);
        h0 = h0.min(d);
        h1 = h1.max(d);
    }
    (h0, h1)
}

impl HullAxes {
    pub(crate) fn new(pts: &[DVec3]) -> Self {
        let m = pts.len();
        let mut normals = Vec::with_capacity(m * m * m / 6);
        let mut edges = Vec::with_capacity(m * m / 2);
        for i in 0..m {
            for j in i + 1..m {
                let e = pts[j] - pts[i];
                if e.length_squared() > 0.0 {
                    edges.push(e);
                }
                for k in j + 1..m {
                    let n = e.cross(pts[k] - pts[i]);
                    if n.length_squared() > 0.0 {
                        let (h0, h1) = extent(pts, n);
                        normals.push((n, h0, h1));
                    }
                }
            }
        }
        Self { normals, edges }
    }

    /// True when triangle `t` and conv(`pts`) overlap by more than `tol`
    /// along every candidate axis (the separating-axis theorem for convex
    /// polytopes, with touching counted as separated).
    pub(crate) fn meets(&self, pts: &[DVec3], t: &Occluder, tol: f64) -> bool {
        // Separated along `axis` (the hull's extent along it `hull`, or
        // found here).
        let separated_given = |axis: DVec3, hull: Option<(f64, f64)>| -> bool {
            let len2 = axis.length_squared();
            if len2.is_nan() || len2 <= 0.0 {
                return false;
            }
            let (h0, h1) = hull.unwrap_or_else(|| extent(pts, axis));
            let (t0, t1) = extent(&t.v, axis);
            // Overlap (h1 - t0 or t1 - h0, whichever is smaller) of at most
            // tol · |axis|, decided without a square root when it is clear.
            let overlap = (h1 - t0).min(t1 - h0);
            overlap <= 0.0 || overlap * overlap <= tol * tol * len2
        };
        let separated = |axis: DVec3| separated_given(axis, None);
        if separated(t.normal) {
            return false;
        }
        if (self.normals.iter()).any(|&(n, h0, h1)| separated_given(n, Some((h0, h1)))) {
            return false;
        }
        let te = [t.v[1] - t.v[0], t.v[2] - t.v[1], t.v[0] - t.v[2]];
        for &e in &self.edges {
            if separated(e.cross(t.normal)) {
                return false;
            }
            for &f in &te {
                if separated(e.cross(f)) {
                    return false;
                }
            }
        }
        // Axes in the triangle's plane across its own edges (needed when the
        // hull is flat in a plane near the triangle's).
        for &f in &te {
            if separated(f.cross(t.normal)) {
                return false;
            }
        }
        true
    }
}
