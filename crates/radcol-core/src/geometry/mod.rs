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
    /// The surface points of a batch of parameter points at once (the rule
    /// points of a near or self pair): one call per batch, in a loop over
    /// structure-of-arrays the compiler can vectorize. `u` and `v` are the
    /// element's edge vectors; the normal is along DF(x)u × DF(x)v and the
    /// Jacobian is that cross product's length. Maps override it with a
    /// closed form.
    fn frame_batch(&self, b: &mut FrameBatch, u: DVec3, v: DVec3) {
        for i in 0..b.len.min(FRAME_BATCH) {
            let x = DVec3::new(b.x[0][i], b.x[1][i], b.x[2][i]);
            let [position, du, dv] = self.frame(x, u, v);
            b.set(i, position, du.cross(dv));
        }
    }
}

/// Points per [`FrameBatch`].
pub const FRAME_BATCH: usize = 32;

/// Parameter points in, surface points out, each coordinate in its own
/// array ([`SurfaceMap::frame_batch`]).
#[derive(Clone, Debug)]
pub struct FrameBatch {
    /// How many of the `FRAME_BATCH` slots are in use.
    pub len: usize,
    /// The parameter points x (input).
    pub x: [[f64; FRAME_BATCH]; 3],
    /// F(x).
    pub position: [[f64; FRAME_BATCH]; 3],
    /// The unit normal along DF(x)u × DF(x)v.
    pub normal: [[f64; FRAME_BATCH]; 3],
    /// |DF(x)u × DF(x)v|.
    pub jacobian: [f64; FRAME_BATCH],
}

impl Default for FrameBatch {
    fn default() -> Self {
        Self {
            len: 0,
            x: [[0.0; FRAME_BATCH]; 3],
            position: [[0.0; FRAME_BATCH]; 3],
            normal: [[0.0; FRAME_BATCH]; 3],
            jacobian: [0.0; FRAME_BATCH],
        }
    }
}

impl FrameBatch {
    /// Slot `i`: position and the (unnormalized) cross product.
    #[inline]
    fn set(&mut self, i: usize, position: DVec3, cross: DVec3) {
        let jacobian = cross.length();
        let normal = cross / jacobian;
        for (c, (p, n)) in position
            .to_array()
            .into_iter()
            .zip(normal.to_array())
            .enumerate()
        {
            (self.position[c][i], self.normal[c][i]) = (p, n);
        }
        self.jacobian[i] = jacobian;
    }

    /// Slot `i`'s position, unit normal and Jacobian.
    #[inline]
    pub fn get(&self, i: usize) -> (DVec3, DVec3, f64) {
        let v = |a: &[[f64; FRAME_BATCH]; 3]| DVec3::new(a[0][i], a[1][i], a[2][i]);
        (v(&self.position), v(&self.normal), self.jacobian[i])
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
    /// With D = diag(a) and P = I - x̂x̂ᵀ, DF(x) = D P / |x|. P u and P v lie
    /// in the plane normal to x̂, so P u × P v = (x̂ · (u × v)) x̂, and
    /// D w₁ × D w₂ = det(D) D⁻¹ (w₁ × w₂): the cross product is
    /// abc (x · (u × v)) (x ⊘ a) / |x|⁴, with no tangent formed.
    fn frame_batch(&self, b: &mut FrameBatch, u: DVec3, v: DVec3) {
        let (a, c) = (self.semi_axes.to_array(), self.center.to_array());
        let inv_a = self.semi_axes.recip().to_array();
        let abc = a[0] * a[1] * a[2];
        let n = u.cross(v).to_array();
        let len = b.len.min(FRAME_BATCH);
        for i in 0..len {
            // The cross product is s y with y = x ⊘ a, s = abc (x · n) / |x|⁴:
            // the normal is ±y / |y| and the Jacobian |s| |y|. One division
            // gives both 1 / |x| and 1 / |y|.
            let x = [b.x[0][i], b.x[1][i], b.x[2][i]];
            let y = [0, 1, 2].map(|j| x[j] * inv_a[j]);
            let (len_x, len_y) = (
                (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt(),
                (y[0] * y[0] + y[1] * y[1] + y[2] * y[2]).sqrt(),
            );
            let inv_xy = 1.0 / (len_x * len_y);
            let (inv_x, inv_y) = (inv_xy * len_y, inv_xy * len_x);
            let inv2 = inv_x * inv_x;
            let scale = abc * (x[0] * n[0] + x[1] * n[1] + x[2] * n[2]) * (inv2 * inv2);
            let unit = scale.signum() * inv_y;
            for j in 0..3 {
                b.position[j][i] = c[j] + a[j] * (x[j] * inv_x);
                b.normal[j][i] = y[j] * unit;
            }
            b.jacobian[i] = scale.abs() * len_y;
        }
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

/// (s, t) with a + s (b - a) + t (c - a) the point of the triangle's plane
/// nearest x (x projected onto it), inside the triangle or not.
pub fn plane_st(a: DVec3, b: DVec3, c: DVec3, x: DVec3) -> [f64; 2] {
    let (e1, e2, d) = (b - a, c - a, x - a);
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d1, d2) = (d.dot(e1), d.dot(e2));
    let det = d11 * d22 - d12 * d12;
    [(d22 * d1 - d12 * d2) / det, (d11 * d2 - d12 * d1) / det]
}

/// (s, t) with a + s (b - a) + t (c - a) = x, if x lies in the triangle (within 1e-12).
pub fn barycentric_st(a: DVec3, b: DVec3, c: DVec3, x: DVec3) -> Option<[f64; 2]> {
    let (e1, e2, d) = (b - a, c - a, x - a);
    let (d11, d22) = (e1.dot(e1), e2.dot(e2));
    let [s, t] = plane_st(a, b, c, x);
    let eps = 1e-12;
    let off_plane = (d - e1 * s - e2 * t).length();
    (s >= -eps && t >= -eps && s + t <= 1.0 + eps && off_plane <= 1e-9 * (d11 + d22).sqrt())
        .then_some([s.clamp(0.0, 1.0), t.clamp(0.0, 1.0 - s.clamp(0.0, 1.0))])
}
