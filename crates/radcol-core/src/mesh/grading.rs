//! Meshes graded towards the lines where u is rough by geometry alone:
//! concave edges, where two faces meet at an angle below 180° seen from the
//! free space (a room's floor and wall), and contact lines, where one object
//! rests on another (a block's bottom edge on the floor, imprinted there by
//! the scene builder).
//!
//! Near such a line u is continuous but its gradient is not bounded: at
//! distance d from a 90° edge the form factor to the other face varies like
//! d log d, so uniform refinement converges at the edge at order about 1
//! whatever the degree. Atkinson, Chien and Seol (2000) restore the order
//! with meshes graded towards polyhedral edges: element sizes following
//! h(d) ≈ H (d / D)^(1 − 1/q) within a zone of width D, with the smallest
//! elements H (H / D)^(q − 1) at the line. With 4:1 (isotropic) splitting a
//! line singularity costs about (D / H²) · ∫ (d / D)^(−2 (1 − 1/q)) dd per
//! unit length of line: finite for q < 2, a log factor at q = 2 and a power
//! of H beyond. For r = 1, q = 2 makes the interpolation error h² |u''| ≈
//! h² / d the same H² / D in every element; that is the default exponent.

use super::{mapped_longest_edge, Element};
use crate::geometry::Surface;
use glam::DVec3;

/// Grading exponents accepted: 1 is uniform, 3 already multiplies the
/// elements near a line by a power of 1/H.
pub const GRADE_RANGE: std::ops::RangeInclusive<f64> = 1.0..=3.0;

/// Splits below the uniform mesh's element that grading may add (a floor
/// 4^-12 of its area; reached only for q near 3 on fine meshes).
const MAX_EXTRA_DEPTH: u32 = 12;

/// What a user asks for: the exponent q and the zone's width D.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Grade {
    /// The exponent q in [`GRADE_RANGE`] (1: no grading).
    pub exponent: f64,
    /// The width D of the graded zone (scene units); None: a quarter of the
    /// scene's largest extent.
    pub zone: Option<f64>,
}

impl Grade {
    /// Exponent `q` in the default zone.
    pub fn exponent(q: f64) -> Self {
        Self {
            exponent: q,
            zone: None,
        }
    }
}

/// Where and how strongly a mesh is graded.
#[derive(Clone, Debug, PartialEq)]
pub struct Grading {
    /// The exponent q ≥ 1 (1: no grading).
    pub exponent: f64,
    /// Width D of the graded zone on either side of each line (scene units).
    pub zone: f64,
    /// The segments graded towards.
    pub lines: Vec<[DVec3; 2]>,
}

impl Grading {
    /// The grading `grade` asks for towards the concave edges and contact
    /// lines of `surface` (`concave_lines`).
    pub fn towards_concave_lines(surface: &Surface, grade: &Grade) -> Self {
        let (lo, hi) = surface.bounding_box();
        Self {
            exponent: grade.exponent,
            zone: grade.zone.unwrap_or(0.25 * (hi - lo).max_element()),
            lines: concave_lines(surface),
        }
    }

    /// The element size wanted at distance `d` from the nearest line, for an
    /// element of size `h` in the ungraded mesh.
    pub fn size_at(&self, h: f64, d: f64) -> f64 {
        let (q, z) = (self.exponent, self.zone);
        if h >= z || q <= 1.0 {
            return h;
        }
        let s = (d / z).min(1.0).max((h / z).powf(q));
        h * s.powf(1.0 - 1.0 / q)
    }

    /// A lower bound of the distance from the triangle `v` to the nearest
    /// line: the distance from its centroid less its circumscribing radius
    /// about the centroid (∞ without lines).
    fn distance_below(&self, v: [DVec3; 3]) -> f64 {
        let c = (v[0] + v[1] + v[2]) / 3.0;
        let r = v.iter().map(|x| (*x - c).length()).fold(0.0, f64::max);
        let d = self
            .lines
            .iter()
            .map(|&[a, b]| point_segment_distance(c, a, b))
            .fold(f64::INFINITY, f64::min);
        (d - r).max(0.0)
    }

    /// Calls `visit` on the leaves of the graded refinement of `e` (an
    /// element of the ungraded mesh), depth-first in children order; stops
    /// (and returns false) as soon as `visit` returns false.
    pub(super) fn refine(
        &self,
        surface: &Surface,
        e: Element,
        visit: &mut dyn FnMut(Element) -> bool,
    ) -> bool {
        let h = mapped_longest_edge(surface, &e);
        self.refine_below(surface, e, h, MAX_EXTRA_DEPTH, visit)
    }

    fn refine_below(
        &self,
        surface: &Surface,
        e: Element,
        h: f64,
        depth: u32,
        visit: &mut dyn FnMut(Element) -> bool,
    ) -> bool {
        let f = &surface.patches[e.patch as usize].map;
        let v = e.param.map(|x| f.map(x));
        let size = mapped_longest_edge(surface, &e);
        // NaN sizes (bad geometry) are leaves, as in the max-edge refinement.
        if depth == 0 || size.is_nan() || size <= self.size_at(h, self.distance_below(v)) {
            return visit(e);
        }
        e.children()
            .into_iter()
            .all(|c| self.refine_below(surface, c, h, depth - 1, visit))
    }
}

fn point_segment_distance(x: DVec3, a: DVec3, b: DVec3) -> f64 {
    let ab = b - a;
    let len2 = ab.length_squared();
    let t = if len2 > 0.0 {
        ((x - a).dot(ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (x - (a + ab * t)).length()
}

/// A flat base triangle with its plane.
struct Face {
    v: [DVec3; 3],
    normal: DVec3,
    lo: DVec3,
    hi: DVec3,
}

/// The edges of flat base triangles that are concave edges or contact
/// lines: the edge lies in another, non-coplanar flat triangle (its
/// midpoint inside it, both ends in its plane), the first triangle rises in
/// front of the second, and the second has a vertex in front of the first
/// (so the two faces see each other across the edge: a convex block edge
/// fails the first test, a face behind another the second). Curved patches
/// are not searched. Each line may be listed once from each side.
pub fn concave_lines(surface: &Surface) -> Vec<[DVec3; 2]> {
    let faces: Vec<Face> = surface
        .patches
        .iter()
        .filter(|p| p.map.is_affine())
        .flat_map(|p| p.triangles.iter().map(move |t| t.map(|x| p.map.map(x))))
        .filter_map(|v| {
            let n = (v[1] - v[0]).cross(v[2] - v[0]);
            (n.length() > 0.0).then(|| Face {
                v,
                normal: n.normalize(),
                lo: v[0].min(v[1]).min(v[2]),
                hi: v[0].max(v[1]).max(v[2]),
            })
        })
        .collect();
    let (lo, hi) = surface.bounding_box();
    let eps = 1e-9 * (hi - lo).max_element();
    let grid = FaceGrid::new(&faces, lo, hi, eps);
    let mut lines = Vec::new();
    for a in &faces {
        let centroid = (a.v[0] + a.v[1] + a.v[2]) / 3.0;
        for i in 0..3 {
            let (p, q) = (a.v[i], a.v[(i + 1) % 3]);
            let m = 0.5 * (p + q);
            let concave = grid.near(m).iter().any(|&b| {
                let b = &faces[b];
                let inside_box = m.cmpge(b.lo - eps).all() && m.cmple(b.hi + eps).all();
                inside_box
                    && b.normal.dot(a.normal) < 1.0 - 1e-9
                    && b.normal.dot(p - b.v[0]).abs() <= eps
                    && b.normal.dot(q - b.v[0]).abs() <= eps
                    && b.normal.dot(centroid - m) > eps
                    && b.v.iter().any(|&w| a.normal.dot(w - m) > eps)
                    && contains(b, m, eps)
            });
            if concave {
                lines.push([p, q]);
            }
        }
    }
    lines
}

/// The faces by the cells of a uniform grid that their boxes (grown by
/// `eps`) overlap, about one cell per face: a point's candidates are the
/// faces of its cell, so the search is about linear in the faces instead
/// of quadratic (40 000 triangles: 36 s before).
struct FaceGrid {
    lo: DVec3,
    cell: f64,
    dims: [usize; 3],
    cells: Vec<Vec<usize>>,
}

impl FaceGrid {
    fn new(faces: &[Face], lo: DVec3, hi: DVec3, eps: f64) -> Self {
        let extent = (hi - lo).max_element().max(f64::MIN_POSITIVE);
        let per_side = (faces.len() as f64).cbrt().ceil().clamp(1.0, 128.0);
        let cell = extent / per_side;
        let dim = |d: f64| ((d / cell).floor() as usize + 1).min(per_side as usize + 1);
        let span = hi - lo;
        let dims = [dim(span.x), dim(span.y), dim(span.z)];
        let mut grid = Self {
            lo,
            cell,
            dims,
            cells: vec![Vec::new(); dims[0] * dims[1] * dims[2]],
        };
        for (f, face) in faces.iter().enumerate() {
            let (a, b) = (grid.index(face.lo - eps), grid.index(face.hi + eps));
            for x in a[0]..=b[0] {
                for y in a[1]..=b[1] {
                    for z in a[2]..=b[2] {
                        let c = grid.flat([x, y, z]);
                        grid.cells[c].push(f);
                    }
                }
            }
        }
        grid
    }

    /// The cell of `p`, clamped to the grid.
    fn index(&self, p: DVec3) -> [usize; 3] {
        let r = (p - self.lo) / self.cell;
        let c = |v: f64, n: usize| (v.floor().max(0.0) as usize).min(n - 1);
        [
            c(r.x, self.dims[0]),
            c(r.y, self.dims[1]),
            c(r.z, self.dims[2]),
        ]
    }

    fn flat(&self, [x, y, z]: [usize; 3]) -> usize {
        (x * self.dims[1] + y) * self.dims[2] + z
    }

    /// The faces whose grown boxes overlap the cell of `p`.
    fn near(&self, p: DVec3) -> &[usize] {
        &self.cells[self.flat(self.index(p))]
    }
}

/// True when `x` (in the plane of `f`) lies in the closed triangle, within
/// `eps` of its edges.
fn contains(f: &Face, x: DVec3, eps: f64) -> bool {
    (0..3).all(|i| {
        let (a, b) = (f.v[i], f.v[(i + 1) % 3]);
        let inward = f.normal.cross(b - a);
        let len = inward.length();
        len == 0.0 || inward.dot(x - a) / len >= -eps
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::shapes::{box_room, sphere};
    use crate::mesh::Mesh;
    use std::sync::Arc;

    /// The box room's 12 edges are all concave, each split in two base
    /// edges at most, and every line found lies on one of them.
    #[test]
    fn box_room_edges_are_concave() {
        let (lx, ly, lz) = (4.0, 3.0, 5.0);
        let room = box_room(lx, ly, lz);
        let lines = concave_lines(&room);
        assert!(!lines.is_empty());
        let on_box_edge = |x: DVec3| {
            let at = |c: f64, l: f64| c.abs() < 1e-9 || (c - l).abs() < 1e-9;
            [at(x.x, lx), at(x.y, ly), at(x.z, lz)]
                .iter()
                .filter(|&&b| b)
                .count()
                >= 2
        };
        for [a, b] in &lines {
            assert!(on_box_edge(*a) && on_box_edge(*b) && on_box_edge(0.5 * (*a + *b)));
        }
        // Every box edge is covered: its midpoint lies on a found line.
        let mids = [
            DVec3::new(lx / 2.0, 0.0, 0.0),
            DVec3::new(0.0, ly / 2.0, 0.0),
            DVec3::new(0.0, 0.0, lz / 2.0),
            DVec3::new(lx / 2.0, ly, lz),
            DVec3::new(lx, ly / 2.0, lz),
            DVec3::new(lx, ly, lz / 2.0),
        ];
        for m in mids {
            let d = lines
                .iter()
                .map(|&[a, b]| point_segment_distance(m, a, b))
                .fold(f64::INFINITY, f64::min);
            assert!(d < 1e-9, "box edge through {m} not found");
        }
    }

    /// The grid finds every face whose grown box holds the point: over
    /// scattered faces of mixed sizes and points on, inside and outside them.
    #[test]
    fn face_grid_finds_every_face_holding_a_point() {
        let mut seed = 7u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let faces: Vec<Face> = (0..500)
            .map(|k| {
                let size = if k % 50 == 0 { 3.0 } else { 0.1 };
                let o = DVec3::new(rnd(), rnd(), rnd()) * 4.0;
                let v = [
                    o,
                    o + DVec3::new(size, 0.0, 0.0),
                    o + DVec3::new(0.0, size * rnd(), size),
                ];
                Face {
                    v,
                    normal: (v[1] - v[0]).cross(v[2] - v[0]).normalize(),
                    lo: v[0].min(v[1]).min(v[2]),
                    hi: v[0].max(v[1]).max(v[2]),
                }
            })
            .collect();
        let (lo, hi) = faces
            .iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(a, b), f| {
                (a.min(f.lo), b.max(f.hi))
            });
        let eps = 1e-9 * (hi - lo).max_element();
        let grid = FaceGrid::new(&faces, lo, hi, eps);
        for f in &faces {
            for p in [
                f.v[0],
                0.5 * (f.v[0] + f.v[1]),
                f.hi,
                DVec3::new(rnd(), rnd(), rnd()) * 7.0,
            ] {
                let near = grid.near(p);
                for (k, g) in faces.iter().enumerate() {
                    if p.cmpge(g.lo - eps).all() && p.cmple(g.hi + eps).all() {
                        assert!(near.contains(&k), "face {k} holds {p} but is not listed");
                    }
                }
            }
        }
    }

    /// Curved and convex surfaces have none.
    #[test]
    fn sphere_has_no_concave_lines() {
        assert!(concave_lines(&sphere(1.0)).is_empty());
    }

    /// Sizes follow H (d / D)^(1 − 1/q) between the floor at the line and H
    /// at the zone's edge.
    #[test]
    fn sizes_follow_the_grading_function() {
        let g = Grading {
            exponent: 2.0,
            zone: 1.0,
            lines: vec![],
        };
        let h = 0.1;
        assert!((g.size_at(h, 0.0) - h * h).abs() < 1e-15);
        assert!((g.size_at(h, 0.25) - h * 0.5).abs() < 1e-15);
        assert_eq!(g.size_at(h, 3.0), h);
        assert_eq!(g.size_at(2.0, 0.0), 2.0, "no grading when h ≥ D");
    }

    /// A graded room: elements at a concave edge are about H² / D, elements
    /// beyond the zone keep H, and the mesh still covers the room's area.
    #[test]
    fn graded_room_is_fine_at_edges_and_covers_the_room() {
        let room = Arc::new(box_room(4.0, 3.0, 5.0));
        let uniform = Mesh::new(room.clone(), 3);
        let g = Grading::towards_concave_lines(&room, &Grade::exponent(2.0));
        let graded = Mesh::graded(room.clone(), 3, None, &g);
        assert!(graded.len() > uniform.len());
        assert!((graded.area() - uniform.area()).abs() < 1e-9 * uniform.area());
        let smallest = (0..graded.len())
            .map(|k| shape_edge(&graded, k))
            .fold(f64::INFINITY, f64::min);
        let largest_uniform = (0..uniform.len())
            .map(|k| shape_edge(&uniform, k))
            .fold(0.0, f64::max);
        assert!(
            smallest < 2.0 * largest_uniform * largest_uniform / g.zone,
            "smallest {smallest}, H {largest_uniform}, D {}",
            g.zone
        );
        assert_eq!(
            Mesh::count_graded(room, 3, None, &g, u64::MAX),
            graded.len() as u64
        );
    }

    fn shape_edge(mesh: &Mesh, k: usize) -> f64 {
        let [a, b, c] = mesh.vertices(k);
        (b - a).length().max((c - b).length()).max((a - c).length())
    }
}
