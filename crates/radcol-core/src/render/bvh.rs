//! Closest-hit ray queries on a mesh: an obvhs [`Bvh2`] over the elements, with
//! the exact ray–triangle test in f64.
//!
//! Flat elements are one triangle each. Curved elements are tessellated into
//! n² flat facets that remember the (s, t) of their corners, so a hit maps back
//! to (s, t) of the element (to within the facet's chord error).
//!
//! The BVH itself is f32. Three things keep f32 rounding from ever losing a hit
//! that the f64 test would find: boxes live in coordinates relative to the scene
//! centre (so their rounding is relative to the scene size, not to where the
//! scene sits in space), every box is padded by [`PAD`] times the scene extent,
//! and a query first moves the ray origin (in f64) to where the ray enters the
//! scene box, so the f32 origin is never far from the boxes it is tested against.

use crate::mesh::Mesh;
use crate::render::tessellation::{tessellation_points, tessellation_triangles};
use glam::{DVec3, Vec3A};
use obvhs::aabb::Aabb;
use obvhs::bvh2::Bvh2;
use obvhs::ploc::{PlocBuilder, PlocSearchDistance, SortPrecision};
use obvhs::ray::{Ray, RayHit};

/// Box padding relative to the scene extent: f32 rounding of box corners, of the
/// moved ray origin and of the direction is a few 1e-7 of the extent; this is
/// two orders of magnitude more.
const PAD: f64 = 1e-5;

/// Barycentric slack of the f64 triangle test, so that a ray through an edge
/// shared by two facets cannot slip between them by rounding.
const EDGE_SLACK: f64 = 1e-12;

/// The closest surface point along a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Element index k.
    pub element: usize,
    /// (s, t) of the hit point in the unit simplex of element k.
    pub st: [f64; 2],
    /// Ray parameter: the hit point is origin + t · dir (in units of `dir`).
    pub t: f64,
    /// True when the ray arrives on the side the element normal points to (the
    /// side light leaves from); false for back faces.
    pub front: bool,
}

/// One flat triangle of the BVH with the element and (s, t) of its corners.
#[derive(Clone, Copy, Debug)]
struct Facet {
    v: [DVec3; 3],
    st: [[f64; 2]; 3],
    element: u32,
}

/// A bounding volume hierarchy over the elements of a mesh.
pub struct ElementBvh {
    bvh: Bvh2,
    /// Facets in BVH primitive order (so no index indirection at query time).
    facets: Vec<Facet>,
    centre: DVec3,
    lo: DVec3,
    hi: DVec3,
}

impl std::fmt::Debug for ElementBvh {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ElementBvh")
            .field("facets", &self.facets.len())
            .field("nodes", &self.bvh.nodes.len())
            .field("lo", &self.lo)
            .field("hi", &self.hi)
            .finish()
    }
}

impl ElementBvh {
    /// Builds the hierarchy over the elements of `mesh`; curved elements are cut
    /// into `curved_subdivisions`² facets (values below 1 count as 1).
    pub fn new(mesh: &Mesh, curved_subdivisions: u32) -> Self {
        let n = curved_subdivisions.max(1);
        let pts = tessellation_points(n);
        let tris = tessellation_triangles(n);
        let mut facets = Vec::new();
        for k in 0..mesh.len() {
            if mesh.is_flat(k) {
                facets.push(Facet {
                    v: mesh.vertices(k),
                    st: [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
                    element: k as u32,
                });
            } else {
                let pos: Vec<DVec3> = pts.iter().map(|&[s, t]| mesh.position(k, s, t)).collect();
                for tri in &tris {
                    let c = tri.map(|i| i as usize);
                    facets.push(Facet {
                        v: c.map(|i| pos[i]),
                        st: c.map(|i| pts[i]),
                        element: k as u32,
                    });
                }
            }
        }
        let (mut lo, mut hi) = crate::geometry::bounds(facets.iter().flat_map(|f| f.v));
        if facets.is_empty() {
            lo = DVec3::ZERO;
            hi = DVec3::ZERO;
        }
        let centre = 0.5 * (lo + hi);
        let pad = PAD * (0.5 * (hi - lo).max_element()).max(f64::MIN_POSITIVE);
        let lo = lo - DVec3::splat(pad);
        let hi = hi + DVec3::splat(pad);
        let boxes: Vec<Aabb> = facets
            .iter()
            .map(|f| {
                let (mut a, mut b) = (f.v[0], f.v[0]);
                for v in &f.v[1..] {
                    a = a.min(*v);
                    b = b.max(*v);
                }
                Aabb::new(
                    to_f32(a - centre - DVec3::splat(pad)),
                    to_f32(b - centre + DVec3::splat(pad)),
                )
            })
            .collect();
        let bvh = PlocBuilder::with_capacity(boxes.len()).build(
            PlocSearchDistance::Medium,
            &boxes,
            (0..boxes.len() as u32).collect(),
            SortPrecision::U64,
            1,
        );
        let facets = bvh
            .primitive_indices
            .iter()
            .map(|&i| facets[i as usize])
            .collect();
        Self {
            bvh,
            facets,
            centre,
            lo,
            hi,
        }
    }

    /// The bounding box (min, max) of all facets.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        (self.lo, self.hi)
    }

    /// Number of flat facets in the hierarchy.
    pub fn facet_count(&self) -> usize {
        self.facets.len()
    }

    /// The closest hit with t > 0 along origin + t · dir (`dir` need not be unit).
    pub fn closest_hit(&self, origin: DVec3, dir: DVec3) -> Option<Hit> {
        self.closest_hit_in(origin, dir, 0.0, f64::INFINITY)
    }

    /// The closest hit with `t_min` < t < `t_max` along origin + t · dir.
    /// Returns None for a zero or non-finite direction or origin.
    pub fn closest_hit_in(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> Option<Hit> {
        if self.facets.is_empty() || !origin.is_finite() || !dir.is_finite() {
            return None;
        }
        let len = dir.length();
        if !len.is_finite() || len <= 0.0 {
            return None;
        }
        let (enter, exit) = slab(origin, dir, self.lo, self.hi)?;
        let t0 = enter.max(t_min);
        if exit < t0 || t0 >= t_max {
            return None;
        }
        // The f32 ray starts where the f64 ray enters the scene box (or at t_min),
        // and measures distance (unit direction).
        let start = origin + t0 * dir - self.centre;
        let ray = Ray::new_inf(to_f32(start), to_f32(dir / len));
        let mut best: Option<Hit> = None;
        let mut best_t = t_max;
        let mut rayhit = RayHit::none();
        self.bvh.ray_traverse(ray, &mut rayhit, |_ray, prim| {
            let f = &self.facets[prim];
            match intersect(f, origin, dir, t_min, best_t) {
                Some(hit) => {
                    best_t = hit.t;
                    best = Some(hit);
                    // Round the f32 culling distance up, so that boxes reaching
                    // just beyond the hit are still visited.
                    (((hit.t - t0) * len).max(0.0) * (1.0 + 1e-6)) as f32
                }
                None => f32::INFINITY,
            }
        });
        best
    }
}

/// Möller–Trumbore in f64, barycentrics clamped into the facet after a slack test.
fn intersect(f: &Facet, o: DVec3, d: DVec3, t_min: f64, t_max: f64) -> Option<Hit> {
    let e1 = f.v[1] - f.v[0];
    let e2 = f.v[2] - f.v[0];
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - f.v[0];
    let u = s.dot(p) * inv;
    if !(-EDGE_SLACK..=1.0 + EDGE_SLACK).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = d.dot(q) * inv;
    if v < -EDGE_SLACK || u + v > 1.0 + EDGE_SLACK {
        return None;
    }
    let t = e2.dot(q) * inv;
    if !(t > t_min && t < t_max) {
        return None;
    }
    let u = u.clamp(0.0, 1.0);
    let v = v.clamp(0.0, 1.0 - u);
    let [a, b, c] = f.st;
    let st = [
        a[0] + u * (b[0] - a[0]) + v * (c[0] - a[0]),
        a[1] + u * (b[1] - a[1]) + v * (c[1] - a[1]),
    ];
    Some(Hit {
        element: f.element as usize,
        st,
        t,
        // e1 × e2 is the light side; a ray arriving there runs against it,
        // and det = e1 · (d × e2) = -d · (e1 × e2).
        front: det > 0.0,
    })
}

/// Entry and exit parameters of the ray in the box [lo, hi], or None on a miss.
fn slab(o: DVec3, d: DVec3, lo: DVec3, hi: DVec3) -> Option<(f64, f64)> {
    let (mut enter, mut exit) = (f64::NEG_INFINITY, f64::INFINITY);
    for i in 0..3 {
        if d[i] == 0.0 {
            if o[i] < lo[i] || o[i] > hi[i] {
                return None;
            }
        } else {
            let (a, b) = ((lo[i] - o[i]) / d[i], (hi[i] - o[i]) / d[i]);
            enter = enter.max(a.min(b));
            exit = exit.min(a.max(b));
        }
    }
    (enter <= exit).then_some((enter, exit))
}

fn to_f32(v: DVec3) -> Vec3A {
    Vec3A::new(v.x as f32, v.y as f32, v.z as f32)
}
