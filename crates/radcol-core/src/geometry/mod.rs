//! Surfaces as unions of patches S_j = F_j(R_j) (paper eq. 9–10).
//!
//! A patch's parameter domain R_j is a planar polygon embedded in R^3 (a face of
//! an octahedron, a wall of a box), triangulated into base triangles. The map F_j
//! carries exact first derivatives, so curved elements get their exact Jacobian
//! |D_s m_k × D_t m_k| and normal: the geometry adds no error of its own.

pub mod shapes;

use glam::DVec3;
use std::fmt::Debug;
use std::sync::Arc;

/// A smooth map F from a planar parameter polygon (embedded in R^3) onto a surface patch.
pub trait SurfaceMap: Send + Sync + Debug {
    /// F(x).
    fn map(&self, x: DVec3) -> DVec3;
    /// The derivative DF(x) applied to the direction `v`.
    fn push_forward(&self, x: DVec3, v: DVec3) -> DVec3;
    /// True when F is affine: elements are flat, with constant normal and Jacobian.
    fn is_affine(&self) -> bool {
        false
    }
    /// F(x) with DF(x) applied to `u` and to `v`: what a surface point needs
    /// (position, tangents). Maps override it to share work between the three.
    fn frame(&self, x: DVec3, u: DVec3, v: DVec3) -> [DVec3; 3] {
        [
            self.map(x),
            self.push_forward(x, u),
            self.push_forward(x, v),
        ]
    }
}

/// F(x) = x: flat patches (polyhedra, OBJ faces).
#[derive(Clone, Copy, Debug, Default)]
pub struct Identity;

impl SurfaceMap for Identity {
    fn map(&self, x: DVec3) -> DVec3 {
        x
    }
    fn push_forward(&self, _x: DVec3, v: DVec3) -> DVec3 {
        v
    }
    fn is_affine(&self) -> bool {
        true
    }
}

/// F(x) = center + semi_axes ⊙ x/|x|: the radial projection of a polyhedron around
/// the origin onto an ellipsoid (a sphere when all semi-axes are equal).
#[derive(Clone, Copy, Debug)]
pub struct RadialProjection {
    /// Centre of the ellipsoid.
    pub center: DVec3,
    /// Semi-axes (a, b, c), all positive.
    pub semi_axes: DVec3,
}

impl SurfaceMap for RadialProjection {
    fn map(&self, x: DVec3) -> DVec3 {
        self.center + self.semi_axes * (x / x.length())
    }
    fn push_forward(&self, x: DVec3, v: DVec3) -> DVec3 {
        // d(x/|x|)·v = (v - x̂ (x̂·v)) / |x|
        let len = x.length();
        let xh = x / len;
        self.semi_axes * ((v - xh * xh.dot(v)) / len)
    }
    fn frame(&self, x: DVec3, u: DVec3, v: DVec3) -> [DVec3; 3] {
        let inv = 1.0 / x.length();
        let xh = x * inv;
        let d = |w: DVec3| self.semi_axes * ((w - xh * xh.dot(w)) * inv);
        [self.center + self.semi_axes * xh, d(u), d(v)]
    }
}

/// One patch: a map and the base triangles of its parameter polygon.
///
/// Each base triangle `[a, b, c]` is ordered so that the mapped tangent cross
/// product D_s m × D_t m points to the *inside* of the enclosure (the side light
/// leaves from), with m(s, t) = F(a + s (b - a) + t (c - a)).
#[derive(Clone, Debug)]
pub struct Patch {
    /// A name for reports ("octant +x+y+z", "floor", an OBJ group).
    pub name: String,
    /// The map F_j.
    pub map: Arc<dyn SurfaceMap>,
    /// The triangulation of R_j, points in the parameter polygon.
    pub triangles: Vec<[DVec3; 3]>,
}

/// A surface S = S_1 ∪ … ∪ S_J (eq. 9).
#[derive(Clone, Debug)]
pub struct Surface {
    /// A short name for reports ("sphere", "box:1,1,1").
    pub name: String,
    /// The patches.
    pub patches: Vec<Patch>,
    /// True when S is known to lie on the boundary of a convex set, so that no
    /// pair of points can be occluded (the paper's "unoccluded" case).
    pub convex_enclosure: bool,
}

impl Surface {
    /// Number of base triangles over all patches.
    pub fn base_triangle_count(&self) -> usize {
        self.patches.iter().map(|p| p.triangles.len()).sum()
    }

    /// The axis-aligned box (min, max) of the mapped vertices of the base
    /// triangles (exact for flat surfaces; curved patches may bulge beyond it).
    pub fn bounding_box(&self) -> (DVec3, DVec3) {
        bounds(
            self.patches
                .iter()
                .flat_map(|p| p.triangles.iter().flat_map(|t| t.map(|x| p.map.map(x)))),
        )
    }
}

/// The axis-aligned box (min, max) of `points` (min = +∞, max = -∞ when empty).
pub fn bounds(points: impl IntoIterator<Item = DVec3>) -> (DVec3, DVec3) {
    points.into_iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(p), hi.max(p)),
    )
}

/// (s, t) with a + s (b - a) + t (c - a) = x, if x lies in the triangle (within 1e-12).
pub fn barycentric_st(a: DVec3, b: DVec3, c: DVec3, x: DVec3) -> Option<[f64; 2]> {
    let (e1, e2, d) = (b - a, c - a, x - a);
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d1, d2) = (d.dot(e1), d.dot(e2));
    let det = d11 * d22 - d12 * d12;
    let s = (d22 * d1 - d12 * d2) / det;
    let t = (d11 * d2 - d12 * d1) / det;
    let eps = 1e-12;
    let off_plane = (d - e1 * s - e2 * t).length();
    (s >= -eps && t >= -eps && s + t <= 1.0 + eps && off_plane <= 1e-9 * (d11 + d22).sqrt())
        .then_some([s.clamp(0.0, 1.0), t.clamp(0.0, 1.0 - s.clamp(0.0, 1.0))])
}
