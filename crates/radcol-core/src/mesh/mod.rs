//! Triangulations T_n = {Δ_1, …, Δ_n} of a surface (eq. 11–12), refined uniformly
//! 4:1 in parameter space.
//!
//! Midpoint refinement of every base triangle keeps the triangulation
//! *symmetric* (pairs of triangles form parallelograms) and conforming (T1–T3)
//! across patches whose maps agree on shared edges, as the superconvergence
//! theorems 7 and 9 require.

mod base;
mod frames;
pub mod grading;
mod locate;

pub use locate::{Located, Locator};

use crate::geometry::{Surface, SurfaceMap};
use glam::DVec3;
use grading::Grading;
use std::sync::Arc;

/// One element Δ_k = F_j(Δ̂_k), with the parameter triangle Δ̂_k = [a, b, c].
///
/// The element map is m_k(s, t) = F_j(a + s (b - a) + t (c - a)) for (s, t) in σ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Element {
    /// Index of the patch j in [`Surface::patches`].
    pub patch: u32,
    /// Vertices of the parameter triangle Δ̂_k.
    pub param: [DVec3; 3],
}

/// A point on an element with everything the kernel needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// Position m_k(s, t).
    pub position: DVec3,
    /// Inner unit normal.
    pub normal: DVec3,
    /// Area element |D_s m_k × D_t m_k| (area of Δ_k per unit area of σ).
    pub jacobian: f64,
}

/// Where a field is evaluated: a point of S with its normal and its place in
/// the parametrisation (patch and parameter point).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Site {
    /// Position on S.
    pub position: DVec3,
    /// Inner unit normal.
    pub normal: DVec3,
    /// Patch index j.
    pub patch: usize,
    /// The parameter point x with F_j(x) = position.
    pub param: DVec3,
}

/// A triangulated surface.
#[derive(Clone, Debug)]
pub struct Mesh {
    surface: Arc<Surface>,
    level: u32,
    elements: Vec<Element>,
}

impl Mesh {
    /// The base triangulation of `surface` refined `level` times (4^level children each).
    pub fn new(surface: Arc<Surface>, level: u32) -> Self {
        let mut elements: Vec<Element> = surface
            .patches
            .iter()
            .enumerate()
            .flat_map(|(j, p)| {
                p.triangles.iter().map(move |&param| Element {
                    patch: j as u32,
                    param,
                })
            })
            .collect();
        for _ in 0..level {
            elements = elements.iter().flat_map(|e| e.children()).collect();
        }
        Self {
            surface,
            level,
            elements,
        }
    }

    /// The base triangulation refined `level` times, then each element refined
    /// 4:1 again, recursively, until the longest edge of its mapped triangle
    /// (the straight chords between its mapped vertices) is at most `max_edge`.
    ///
    /// Refinement is depth-first per element, so the descendants of every
    /// element stay consecutive in the element order (the assembly relies on
    /// neighbours being close in the numbering). A `max_edge` that is not a
    /// positive finite number sets no bound (the mesh of [`Mesh::new`]);
    /// callers that take it from users should refuse such values first.
    pub fn with_max_edge(surface: Arc<Surface>, level: u32, max_edge: f64) -> Self {
        let uniform = Self::new(surface.clone(), level);
        if !is_edge_bound(max_edge) {
            return uniform;
        }
        let elements = collect_refined(&uniform.elements, |e, visit| {
            refine_to_max_edge(&surface, e, max_edge, visit)
        });
        Self {
            surface,
            level,
            elements,
        }
    }

    /// The number of elements of [`Mesh::with_max_edge`] with the same
    /// arguments, without storing them (for memory checks). Counts above
    /// [`MAX_EDGE_COUNT_CAP`] stop early and return `u64::MAX`: no dense
    /// matrix of that many elements fits in any memory.
    pub fn count_with_max_edge(surface: Arc<Surface>, level: u32, max_edge: f64) -> u64 {
        let base = surface.base_triangle_count() as u64;
        if !is_edge_bound(max_edge) {
            return base.saturating_mul(4u64.saturating_pow(level));
        }
        let mut count = 0u64;
        let mut uniform = surface.patches.iter().enumerate().flat_map(|(j, p)| {
            p.triangles.iter().map(move |&param| Element {
                patch: j as u32,
                param,
            })
        });
        // Walks the uniform level depth-first too, so that a huge `level`
        // stops at the cap instead of materialising every element first.
        fn uniform_then_bound(
            surface: &Surface,
            e: Element,
            depth: u32,
            max_edge: f64,
            visit: &mut dyn FnMut(Element) -> bool,
        ) -> bool {
            if depth == 0 {
                return refine_to_max_edge(surface, e, max_edge, visit);
            }
            e.children()
                .into_iter()
                .all(|c| uniform_then_bound(surface, c, depth - 1, max_edge, visit))
        }
        let complete = uniform.all(|e| {
            uniform_then_bound(&surface, e, level, max_edge, &mut |_| {
                count += 1;
                count <= MAX_EDGE_COUNT_CAP
            })
        });
        if complete {
            count
        } else {
            u64::MAX
        }
    }

    /// The mesh of [`Mesh::with_max_edge`] (or [`Mesh::new`] when `max_edge`
    /// is None) with every element refined further by `grading`.
    pub fn graded(
        surface: Arc<Surface>,
        level: u32,
        max_edge: Option<f64>,
        grading: &Grading,
    ) -> Self {
        let ungraded = Self::with_max_edge(surface.clone(), level, max_edge.unwrap_or(f64::NAN));
        let elements = collect_refined(&ungraded.elements, |e, visit| {
            grading.refine(&surface, e, visit)
        });
        Self {
            surface,
            level,
            elements,
        }
    }

    /// The number of elements of [`Mesh::graded`] with the same arguments,
    /// or `u64::MAX` when it is above `cap` (counted up to there).
    pub fn count_graded(
        surface: Arc<Surface>,
        level: u32,
        max_edge: Option<f64>,
        grading: &Grading,
        cap: u64,
    ) -> u64 {
        let bound = max_edge.unwrap_or(f64::NAN);
        if Self::count_with_max_edge(surface.clone(), level, bound) > cap {
            return u64::MAX;
        }
        let ungraded = Self::with_max_edge(surface.clone(), level, bound);
        let mut count = 0u64;
        let complete = ungraded.elements.iter().all(|e| {
            grading.refine(&surface, *e, &mut |_| {
                count += 1;
                count <= cap
            })
        });
        if complete {
            count
        } else {
            u64::MAX
        }
    }

    /// Builds a mesh from explicit elements (for example an OBJ triangulation).
    pub fn from_elements(surface: Arc<Surface>, level: u32, elements: Vec<Element>) -> Self {
        Self {
            surface,
            level,
            elements,
        }
    }

    /// The surface meshed.
    pub fn surface(&self) -> &Arc<Surface> {
        &self.surface
    }

    /// Refinement level above the base triangulation.
    pub fn level(&self) -> u32 {
        self.level
    }

    /// The elements Δ_1 … Δ_n.
    pub fn elements(&self) -> &[Element] {
        &self.elements
    }

    /// Number of elements n.
    pub fn len(&self) -> usize {
        self.elements.len()
    }

    /// True when the mesh has no element.
    pub fn is_empty(&self) -> bool {
        self.elements.is_empty()
    }

    /// The map F_j of element `k`.
    #[inline]
    pub fn map_of(&self, k: usize) -> &dyn SurfaceMap {
        &*self.surface.patches[self.elements[k].patch as usize].map
    }

    /// True when element `k` is flat (affine map).
    pub fn is_flat(&self, k: usize) -> bool {
        self.map_of(k).is_affine()
    }

    /// m_k(s, t).
    #[inline]
    pub fn position(&self, k: usize, s: f64, t: f64) -> DVec3 {
        let e = &self.elements[k];
        self.map_of(k).map(e.param_point(s, t))
    }

    /// Position, inner normal and Jacobian at (s, t) of element `k`.
    pub fn point(&self, k: usize, s: f64, t: f64) -> SurfacePoint {
        let e = &self.elements[k];
        let f = self.map_of(k);
        let x = e.param_point(s, t);
        let [position, ds, dt] = f.frame(x, e.param[1] - e.param[0], e.param[2] - e.param[0]);
        let cross = ds.cross(dt);
        let jacobian = cross.length();
        SurfacePoint {
            position,
            normal: cross / jacobian,
            jacobian,
        }
    }

    /// The `Site` at (s, t) of element `k` (for evaluating fields).
    pub fn site(&self, k: usize, s: f64, t: f64) -> Site {
        let p = self.point(k, s, t);
        Site {
            position: p.position,
            normal: p.normal,
            patch: self.elements[k].patch as usize,
            param: self.elements[k].param_point(s, t),
        }
    }

    /// The tangents (D_s m_k, D_t m_k) at (s, t).
    pub fn tangents(&self, k: usize, s: f64, t: f64) -> (DVec3, DVec3) {
        let e = &self.elements[k];
        let f = self.map_of(k);
        let x = e.param_point(s, t);
        (
            f.push_forward(x, e.param[1] - e.param[0]),
            f.push_forward(x, e.param[2] - e.param[0]),
        )
    }

    /// Finds the element and (s, t) of a point on S (within `1e-9` of the surface
    /// relative to the element size), trying every element whose bounding ball
    /// contains x: the linear scan that [`Locator`] does through a BVH, kept as
    /// its reference.
    pub fn locate(&self, x: DVec3) -> Option<(usize, [f64; 2])> {
        self.locate_among(0..self.len(), x)
    }

    /// [`Mesh::locate`] over the elements `ks` (ascending): of those whose
    /// widened bounding ball contains x and that hold it, the nearest, the
    /// first of equals.
    pub(crate) fn locate_among(
        &self,
        ks: impl IntoIterator<Item = usize>,
        x: DVec3,
    ) -> Option<(usize, [f64; 2])> {
        let mut best: Option<(usize, [f64; 2], f64)> = None;
        for k in ks {
            let (c, rad) = self.bounding_ball(k);
            if (x - c).length() > rad * 1.1 + 1e-12 {
                continue;
            }
            let [s, t] = self.project_onto(k, x);
            let eps = 1e-9;
            if !(s >= -eps && t >= -eps && s + t <= 1.0 + eps) {
                continue;
            }
            let st = [s.clamp(0.0, 1.0), t.clamp(0.0, 1.0)];
            let miss = (self.position(k, st[0], st[1]) - x).length();
            if miss <= 1e-9 * rad.max(1e-300) && best.as_ref().is_none_or(|b| miss < b.2) {
                best = Some((k, st, miss));
            }
        }
        best.map(|(k, st, _)| (k, st))
    }

    /// (s, t) of the point of element `k`'s surface (its map extended beyond
    /// σ) nearest to `x`, by Gauss–Newton on m_k(s, t) = x from the centroid
    /// (exact in one step on a flat element); it may lie outside σ.
    pub fn project_onto(&self, k: usize, x: DVec3) -> [f64; 2] {
        let (mut s, mut t) = (1.0 / 3.0, 1.0 / 3.0);
        for _ in 0..30 {
            let r = self.position(k, s, t) - x;
            let (ds, dt) = self.tangents(k, s, t);
            let (a11, a12, a22) = (ds.dot(ds), ds.dot(dt), dt.dot(dt));
            let (b1, b2) = (-ds.dot(r), -dt.dot(r));
            let det = a11 * a22 - a12 * a12;
            if det <= 0.0 {
                break;
            }
            let (d1, d2) = ((a22 * b1 - a12 * b2) / det, (a11 * b2 - a12 * b1) / det);
            s += d1;
            t += d2;
            if d1.abs() + d2.abs() < 1e-15 {
                break;
            }
        }
        [s, t]
    }

    /// Mapped vertices of element `k`.
    pub fn vertices(&self, k: usize) -> [DVec3; 3] {
        let e = &self.elements[k];
        let f = self.map_of(k);
        e.param.map(|x| f.map(x))
    }

    /// A ball containing element `k`: (centre, radius). The centre is the image of
    /// the parameter centroid; the radius covers the mapped vertices and edge
    /// midpoints with a 5 % margin for curvature.
    pub fn bounding_ball(&self, k: usize) -> (DVec3, f64) {
        let c = self.position(k, 1.0 / 3.0, 1.0 / 3.0);
        let probes = [
            (0.0, 0.0),
            (1.0, 0.0),
            (0.0, 1.0),
            (0.5, 0.0),
            (0.5, 0.5),
            (0.0, 0.5),
        ];
        let r = probes
            .iter()
            .map(|&(s, t)| (self.position(k, s, t) - c).length())
            .fold(0.0, f64::max);
        (c, r * if self.is_flat(k) { 1.0 } else { 1.05 })
    }

    /// Mesh size h (eq. 11): the largest diameter of a parameter triangle.
    pub fn h(&self) -> f64 {
        self.elements
            .iter()
            .map(|e| e.param_diameter())
            .fold(0.0, f64::max)
    }

    /// Shape ratios r(Δ) = diameter / inradius (eq. 32) of the straight triangles
    /// through each element's mapped vertices: (min, max).
    pub fn shape_ratio_range(&self) -> (f64, f64) {
        (0..self.len())
            .map(|k| shape_ratio(self.vertices(k)))
            .fold((f64::INFINITY, 0.0f64), |(lo, hi), r| {
                (lo.min(r), hi.max(r))
            })
    }

    /// Total surface area ∫_S 1, with a rule exact to high degree on each element.
    pub fn area(&self) -> f64 {
        let rule = crate::quadrature::collapsed::collapsed_rule(12);
        (0..self.len())
            .map(|k| {
                if self.is_flat(k) {
                    0.5 * self.point(k, 0.0, 0.0).jacobian
                } else {
                    rule.points
                        .iter()
                        .zip(&rule.weights)
                        .map(|(&[s, t], w)| w * self.point(k, s, t).jacobian)
                        .sum()
                }
            })
            .sum()
    }
}

impl Element {
    /// The parameter point a + s (b - a) + t (c - a).
    #[inline]
    pub fn param_point(&self, s: f64, t: f64) -> DVec3 {
        let [a, b, c] = self.param;
        a + (b - a) * s + (c - a) * t
    }

    /// The four children of 4:1 midpoint refinement, in the parent's orientation.
    pub fn children(&self) -> [Element; 4] {
        let [a, b, c] = self.param;
        let (ab, bc, ca) = ((a + b) * 0.5, (b + c) * 0.5, (c + a) * 0.5);
        [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]].map(|param| Element {
            patch: self.patch,
            param,
        })
    }

    /// Diameter (longest edge) of the parameter triangle.
    pub fn param_diameter(&self) -> f64 {
        let [a, b, c] = self.param;
        (b - a).length().max((c - b).length()).max((a - c).length())
    }
}

/// [`Mesh::count_with_max_edge`] gives up (returns `u64::MAX`) above this many elements.
pub const MAX_EDGE_COUNT_CAP: u64 = 1 << 22;

/// The leaves of `refine` (a depth-first refinement calling its visitor on
/// each leaf) over every element of `elements`, in order.
fn collect_refined(
    elements: &[Element],
    refine: impl Fn(Element, &mut dyn FnMut(Element) -> bool) -> bool,
) -> Vec<Element> {
    let mut out = Vec::with_capacity(elements.len());
    for e in elements {
        refine(*e, &mut |child| {
            out.push(child);
            true
        });
    }
    out
}

fn is_edge_bound(max_edge: f64) -> bool {
    max_edge.is_finite() && max_edge > 0.0
}

/// Longest straight edge between the mapped vertices of `e`.
fn mapped_longest_edge(surface: &Surface, e: &Element) -> f64 {
    let f = &surface.patches[e.patch as usize].map;
    let [a, b, c] = e.param.map(|x| f.map(x));
    (b - a).length().max((c - b).length()).max((a - c).length())
}

/// Calls `visit` on the leaves of the 4:1 refinement of `e` whose longest
/// mapped edge is ≤ `max_edge`, depth-first in children order; stops (and
/// returns false) as soon as `visit` returns false.
fn refine_to_max_edge(
    surface: &Surface,
    e: Element,
    max_edge: f64,
    visit: &mut dyn FnMut(Element) -> bool,
) -> bool {
    // The longest edge halves at each step, so the depth is bounded by
    // log2(edge / max_edge); NaN edges (bad geometry) are leaves.
    let longest = mapped_longest_edge(surface, &e);
    if longest.is_nan() || longest <= max_edge {
        return visit(e);
    }
    e.children()
        .into_iter()
        .all(|c| refine_to_max_edge(surface, c, max_edge, visit))
}

/// Diameter over inradius of a triangle (eq. 32); 2√3 ≈ 3.46 for an equilateral one.
pub fn shape_ratio([a, b, c]: [DVec3; 3]) -> f64 {
    let (la, lb, lc) = ((b - c).length(), (c - a).length(), (a - b).length());
    let area = 0.5 * (b - a).cross(c - a).length();
    let inradius = 2.0 * area / (la + lb + lc);
    la.max(lb).max(lc) / inradius
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::shapes::{box_room, ellipsoid, sphere};
    use std::f64::consts::PI;

    #[test]
    fn refinement_quadruples_and_halves_h() {
        let s = Arc::new(sphere(1.0));
        let m0 = Mesh::new(s.clone(), 0);
        let m2 = Mesh::new(s, 2);
        assert_eq!(m0.len(), 8);
        assert_eq!(m2.len(), 128);
        crate::assert_close!(m0.h() / m2.h(), 4.0, 1e-14);
    }

    /// Areas against closed forms: the exact maps carry exact Jacobians.
    #[test]
    fn areas_match_closed_forms() {
        let m = Mesh::new(Arc::new(sphere(2.0)), 3);
        assert!(
            (m.area() - 16.0 * PI).abs() < 1e-9 * 16.0 * PI,
            "{}",
            m.area()
        );
        let b = Mesh::new(Arc::new(box_room(1.0, 2.0, 3.0)), 1);
        crate::assert_close!(b.area(), 22.0, 1e-13);
        // Spheroid a = b = 1, c = 2: 2π(1 + c² asin(e)/(c e)), e = √(1 - 1/c²).
        let e = (1.0f64 - 0.25).sqrt();
        let exact = 2.0 * PI * (1.0 + 2.0 * e.asin() / e);
        let m = Mesh::new(Arc::new(ellipsoid(1.0, 1.0, 2.0)), 3);
        assert!(
            (m.area() - exact).abs() < 1e-8 * exact,
            "{} vs {exact}",
            m.area()
        );
    }

    /// Normals are unit and inner: on the sphere n = -P/R.
    #[test]
    fn sphere_normals_are_inner() {
        let m = Mesh::new(Arc::new(sphere(2.0)), 1);
        for k in 0..m.len() {
            let p = m.point(k, 0.2, 0.3);
            assert!((p.normal + p.position / 2.0).length() < 1e-14);
        }
    }

    /// Conformity (T3): every edge of the refined sphere is shared by exactly two elements.
    #[test]
    fn refined_sphere_is_conforming() {
        use std::collections::HashMap;
        let m = Mesh::new(Arc::new(sphere(1.0)), 2);
        let key = |p: DVec3| [p.x, p.y, p.z].map(|v| (v * 1e9).round() as i64);
        let mut edges: HashMap<_, usize> = HashMap::new();
        for k in 0..m.len() {
            let v = m.vertices(k);
            for i in 0..3 {
                let (a, b) = (key(v[i]), key(v[(i + 1) % 3]));
                *edges
                    .entry(if a < b { (a, b) } else { (b, a) })
                    .or_default() += 1;
            }
        }
        assert!(edges.values().all(|&c| c == 2));
    }

    /// Every edge ends ≤ H, the counter agrees with the builder, children stay
    /// consecutive (each element lies inside its uniform-level ancestor, in order).
    #[test]
    fn max_edge_refinement_bounds_edges_and_matches_the_counter() {
        for (surface, level, h) in [
            (Arc::new(box_room(1.0, 2.0, 3.0)), 0, 0.7),
            (Arc::new(box_room(1.0, 2.0, 3.0)), 1, 0.3),
            (Arc::new(sphere(1.0)), 1, 0.25),
            (Arc::new(box_room(1.0, 2.0, 3.0)), 1, 10.0),
        ] {
            let m = Mesh::with_max_edge(surface.clone(), level, h);
            assert_eq!(
                m.len() as u64,
                Mesh::count_with_max_edge(surface.clone(), level, h)
            );
            for k in 0..m.len() {
                let [a, b, c] = m.vertices(k);
                let longest = (b - a).length().max((c - b).length()).max((a - c).length());
                assert!(longest <= h, "element {k}: edge {longest} > {h}");
            }
            // Order: walk the uniform mesh; the refined elements must come in
            // runs lying inside each uniform element in turn, and areas add up.
            let uniform = Mesh::new(surface.clone(), level);
            let mut k = 0;
            for u in 0..uniform.len() {
                let mut area = 0.0;
                let parent = uniform.elements()[u];
                while k < m.len() && m.elements()[k].patch == parent.patch && {
                    let e = m.elements()[k];
                    let c = (e.param[0] + e.param[1] + e.param[2]) / 3.0;
                    crate::geometry::barycentric_st(
                        parent.param[0],
                        parent.param[1],
                        parent.param[2],
                        c,
                    )
                    .is_some_and(|[s, t]| s > 0.0 && t > 0.0 && s + t < 1.0)
                } {
                    let [a, b, c] = m.elements()[k].param;
                    area += 0.5 * (b - a).cross(c - a).length();
                    k += 1;
                }
                let [a, b, c] = parent.param;
                let want = 0.5 * (b - a).cross(c - a).length();
                crate::assert_close!(area, want, 1e-12 * want, "uniform element {u}");
            }
            assert_eq!(k, m.len());
        }
        // Box 1 × 2 × 3, two triangles per wall, 4:1 children similar with
        // halved edges: a wall a × b needs the least d with √(a² + b²)/2^d ≤ H.
        // H = 1: √5, √10, √13 all need d = 2 → 12 · 16. H = 0.7: the 1 × 2
        // walls d = 2 (0.56), the others d = 3 (0.79, 0.90 > 0.7) → 4·16 + 8·64.
        let b = Arc::new(box_room(1.0, 2.0, 3.0));
        assert_eq!(Mesh::count_with_max_edge(b.clone(), 0, 1.0), 192);
        assert_eq!(Mesh::with_max_edge(b.clone(), 0, 0.7).len(), 576);
        assert_eq!(Mesh::with_max_edge(b.clone(), 0, f64::NAN).len(), 12);
        assert_eq!(Mesh::count_with_max_edge(b.clone(), 0, 1e-9), u64::MAX);
    }

    #[test]
    fn shape_ratio_of_equilateral_triangle() {
        let r = shape_ratio([
            DVec3::ZERO,
            DVec3::X,
            DVec3::new(0.5, 3f64.sqrt() / 2.0, 0.0),
        ]);
        crate::assert_close!(r, 2.0 * 3f64.sqrt(), 1e-12);
    }
}
