//! Contact lines imprinted on the faces they lie on.
//!
//! Where one object rests on another (a block on a floor), the edges of the
//! upper object's faces lie in the plane of the lower one's triangles. On
//! one side of such a line the lower face is hidden (u = 0 under the block),
//! on the other it is lit: u jumps there. A triangle that straddles the line
//! keeps straddling it under any 4:1 refinement, so its polynomial rings and
//! the max error does not fall (measured on the Cornell box floor: the
//! estimate stayed at 6e-3 over four adaptive steps). Splitting the lower
//! triangle along the line, by a constrained Delaunay triangulation of the
//! triangle with the segments as constraints (spade), makes the line an
//! element edge at every level.

use super::raw::RawTriangle;
use glam::DVec3;
use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation};

/// How many triangles were split, along how many segments.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Imprinted {
    /// Triangles replaced by their constrained triangulation.
    pub triangles: usize,
    /// Contact segments imprinted (after clipping to the triangles).
    pub segments: usize,
}

/// Plane of a triangle: a point, the unit normal, and an in-plane frame.
struct Frame {
    origin: DVec3,
    normal: DVec3,
    e1: DVec3,
    e2: DVec3,
}

impl Frame {
    fn of(t: &[DVec3; 3]) -> Self {
        let normal = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
        let e1 = (t[1] - t[0]).normalize();
        Self {
            origin: t[0],
            normal,
            e1,
            e2: normal.cross(e1),
        }
    }

    fn to_2d(&self, x: DVec3) -> [f64; 2] {
        let d = x - self.origin;
        [d.dot(self.e1), d.dot(self.e2)]
    }

    fn to_3d(&self, p: [f64; 2]) -> DVec3 {
        self.origin + self.e1 * p[0] + self.e2 * p[1]
    }
}

/// The part of segment `a`–`b` (2-D) inside the counter-clockwise triangle
/// `t`, when it is longer than `tol` and not along one of its edges.
fn clip(t: &[[f64; 2]; 3], a: [f64; 2], b: [f64; 2], tol: f64) -> Option<([f64; 2], [f64; 2])> {
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    let d = [b[0] - a[0], b[1] - a[1]];
    for i in 0..3 {
        let (p, q) = (t[i], t[(i + 1) % 3]);
        let edge = [q[0] - p[0], q[1] - p[1]];
        let len = edge[0].hypot(edge[1]);
        // Signed distance from the edge's line, positive inside.
        let dist = |x: [f64; 2]| (edge[0] * (x[1] - p[1]) - edge[1] * (x[0] - p[0])) / len;
        let (da, db) = (dist(a), dist(b));
        if da <= tol && db <= tol {
            // Outside, or lying along this edge: nothing to imprint.
            return None;
        }
        if da < 0.0 && db > 0.0 {
            lo = lo.max(da / (da - db));
        } else if da > 0.0 && db < 0.0 {
            hi = hi.min(da / (da - db));
        }
    }
    let at = |s: f64| [a[0] + s * d[0], a[1] + s * d[1]];
    let (p, q) = (at(lo), at(hi));
    ((q[0] - p[0]).hypot(q[1] - p[1]) > tol).then_some((p, q))
}

/// Splits every triangle along the edges of other, non-coplanar triangles
/// that lie in its plane (within `1e-9 · scale`), keeping group, material
/// and orientation.
pub(crate) fn contact_lines(tris: Vec<RawTriangle>, scale: f64) -> (Vec<RawTriangle>, Imprinted) {
    let tol = 1e-9 * scale;
    let boxes: Vec<(DVec3, DVec3)> = tris
        .iter()
        .map(|t| {
            let v = t.vertices;
            (v[0].min(v[1]).min(v[2]), v[0].max(v[1]).max(v[2]))
        })
        .collect();
    let frames: Vec<Frame> = tris.iter().map(|t| Frame::of(&t.vertices)).collect();
    let mut segments: Vec<Vec<([f64; 2], [f64; 2])>> = vec![Vec::new(); tris.len()];
    // The edges of `j` that lie in the plane of `i`, clipped to `i`.
    let mut test = |i: usize, j: usize| {
        let f = &frames[i];
        if frames[j].normal.dot(f.normal).abs() > 1.0 - 1e-9 {
            return; // coplanar or parallel: not a contact
        }
        let on_plane = |x: DVec3| (x - f.origin).dot(f.normal).abs() <= tol;
        let t2 = tris[i].vertices.map(|v| f.to_2d(v));
        let v = tris[j].vertices;
        for e in 0..3 {
            let (a, b) = (v[e], v[(e + 1) % 3]);
            if on_plane(a) && on_plane(b) {
                if let Some(seg) = clip(&t2, f.to_2d(a), f.to_2d(b), tol) {
                    segments[i].push(seg);
                }
            }
        }
    };
    // Sweep along x with an active list: only pairs whose boxes overlap are
    // tested.
    let mut order: Vec<usize> = (0..tris.len()).collect();
    order.sort_by(|&a, &b| boxes[a].0.x.total_cmp(&boxes[b].0.x));
    let mut active: Vec<usize> = Vec::new();
    for &i in &order {
        let (lo, hi) = boxes[i];
        active.retain(|&j| boxes[j].1.x + tol >= lo.x);
        for &j in &active {
            let (ljo, ljh) = boxes[j];
            if (ljo - tol).cmpgt(hi).any() || (ljh + tol).cmplt(lo).any() {
                continue;
            }
            test(i, j);
            test(j, i);
        }
        active.push(i);
    }
    let mut out = Vec::with_capacity(tris.len());
    let mut count = Imprinted::default();
    for (i, t) in tris.into_iter().enumerate() {
        if segments[i].is_empty() {
            out.push(t);
            continue;
        }
        match triangulate(&frames[i], &t, &segments[i], tol) {
            Some(pieces) => {
                count.triangles += 1;
                count.segments += segments[i].len();
                out.extend(pieces);
            }
            None => out.push(t),
        }
    }
    (out, count)
}

/// [`triangulate_with_spade`], with a panic inside spade taken as a failed
/// triangulation: spade 2.15 can panic ("Failed to locate position. This
/// is a bug in spade.") on nearly degenerate constraints, which a mutated
/// Cornell box reached (found by fuzzing; `crates/radcol-cli/tests/fuzz.rs`).
fn triangulate(
    f: &Frame,
    t: &RawTriangle,
    segments: &[([f64; 2], [f64; 2])],
    tol: f64,
) -> Option<Vec<RawTriangle>> {
    let attempt = || triangulate_with_spade(f, t, segments, tol);
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(attempt))
        .ok()
        .flatten()
}

/// The constrained triangulation of `t` with `segments` as constraints, in
/// `t`'s orientation; None when the triangulation fails (the triangle is
/// then kept whole). Endpoints within `tol` of a corner become the corner;
/// within `tol` of an edge, a point of that edge, which joins the boundary
/// polygon (so no sliver forms between a nearly collinear point and the
/// edge); faces of area below tol² (rounding slivers) are dropped.
fn triangulate_with_spade(
    f: &Frame,
    t: &RawTriangle,
    segments: &[([f64; 2], [f64; 2])],
    tol: f64,
) -> Option<Vec<RawTriangle>> {
    let c = t.vertices.map(|v| f.to_2d(v));
    // Boundary points per edge, as (parameter along the edge, point).
    let mut on_edge: [Vec<(f64, [f64; 2])>; 3] = Default::default();
    let mut snap = |x: [f64; 2]| -> [f64; 2] {
        for k in 0..3 {
            if (x[0] - c[k][0]).hypot(x[1] - c[k][1]) <= tol {
                return c[k];
            }
        }
        for k in 0..3 {
            let (p, q) = (c[k], c[(k + 1) % 3]);
            let e = [q[0] - p[0], q[1] - p[1]];
            let len2 = e[0] * e[0] + e[1] * e[1];
            let s = ((x[0] - p[0]) * e[0] + (x[1] - p[1]) * e[1]) / len2;
            let on = [p[0] + s * e[0], p[1] + s * e[1]];
            if (0.0..=1.0).contains(&s) && (x[0] - on[0]).hypot(x[1] - on[1]) <= tol {
                on_edge[k].push((s, on));
                return on;
            }
        }
        x
    };
    let snapped: Vec<([f64; 2], [f64; 2])> =
        segments.iter().map(|&(a, b)| (snap(a), snap(b))).collect();
    let mut cdt = ConstrainedDelaunayTriangulation::<Point2<f64>>::new();
    let p = |x: [f64; 2]| Point2::new(x[0], x[1]);
    let mut boundary = Vec::new();
    for k in 0..3 {
        boundary.push(c[k]);
        on_edge[k].sort_by(|a, b| a.0.total_cmp(&b.0));
        boundary.extend(on_edge[k].iter().map(|&(_, x)| x));
    }
    let handles: Vec<_> = boundary
        .iter()
        .map(|&x| cdt.insert(p(x)).ok())
        .collect::<Option<_>>()?;
    for k in 0..handles.len() {
        let (a, b) = (handles[k], handles[(k + 1) % handles.len()]);
        if a != b {
            cdt.add_constraint(a, b);
        }
    }
    for &(a, b) in &snapped {
        let (va, vb) = (cdt.insert(p(a)).ok()?, cdt.insert(p(b)).ok()?);
        if va != vb {
            cdt.add_constraint_and_split(va, vb, |x| x);
        }
    }
    let pieces: Vec<RawTriangle> = cdt
        .inner_faces()
        .filter_map(|face| {
            let q = face.vertices().map(|v| {
                let q = v.position();
                [q.x, q.y]
            });
            let area = 0.5
                * ((q[1][0] - q[0][0]) * (q[2][1] - q[0][1])
                    - (q[2][0] - q[0][0]) * (q[1][1] - q[0][1]));
            // spade's faces are counter-clockwise in (e1, e2), the original
            // orientation (e2 = n × e1).
            (area > tol * tol).then(|| RawTriangle {
                vertices: q.map(|x| f.to_3d(x)),
                uv: t.uv.map(|uv| q.map(|x| interpolate(&c, &uv, x))),
                ..t.clone()
            })
        })
        .collect();
    (pieces.len() >= 2).then_some(pieces)
}

/// The value at `x` of the affine function taking the triangle `c`'s
/// corners to `uv`.
fn interpolate(c: &[[f64; 2]; 3], uv: &[[f64; 2]; 3], x: [f64; 2]) -> [f64; 2] {
    let (e1, e2) = (
        [c[1][0] - c[0][0], c[1][1] - c[0][1]],
        [c[2][0] - c[0][0], c[2][1] - c[0][1]],
    );
    let d = [x[0] - c[0][0], x[1] - c[0][1]];
    let det = e1[0] * e2[1] - e1[1] * e2[0];
    let s = (d[0] * e2[1] - d[1] * e2[0]) / det;
    let t = (e1[0] * d[1] - e1[1] * d[0]) / det;
    [0, 1].map(|a| uv[0][a] + s * (uv[1][a] - uv[0][a]) + t * (uv[2][a] - uv[0][a]))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn raw(group: &str, v: [DVec3; 3]) -> RawTriangle {
        RawTriangle {
            uv: None,
            origin: crate::scene::TriangleOrigin {
                input: 0,
                vertices: [0, 1, 2],
                corners: v,
                at: String::new(),
            },
            group: group.into(),
            material: 0,
            vertices: v,
            at: group.into(),
        }
    }

    /// A unit-square floor (two triangles) under a box's side face whose
    /// bottom edge runs across it: the floor is split along that edge, area
    /// and orientation kept, and no piece crosses the line.
    #[test]
    fn a_face_resting_on_the_floor_is_imprinted() {
        let d = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
        let floor = vec![
            raw("floor", [d(0., 0., 0.), d(1., 0., 0.), d(1., 1., 0.)]),
            raw("floor", [d(0., 0., 0.), d(1., 1., 0.), d(0., 1., 0.)]),
        ];
        // A wall standing on the line x = 0.3, from y = 0.2 to y = 0.8.
        let wall = raw("wall", [d(0.3, 0.2, 0.), d(0.3, 0.8, 0.), d(0.3, 0.5, 0.4)]);
        let mut all = floor.clone();
        all.push(wall);
        let (out, n) = contact_lines(all, 2.0);
        assert_eq!(n.triangles, 2, "{n:?}");
        let pieces: Vec<_> = out.iter().filter(|t| t.group == "floor").collect();
        assert!(pieces.len() > 2);
        let area: f64 = pieces
            .iter()
            .map(|t| {
                let v = t.vertices;
                let c = (v[1] - v[0]).cross(v[2] - v[0]);
                assert!(c.z > 0.0, "orientation kept: {v:?}");
                0.5 * c.length()
            })
            .sum();
        crate::assert_close!(area, 1.0, 1e-12);
        for t in &pieces {
            let xs = t.vertices.map(|v| v.x - 0.3);
            let c = (t.vertices[0] + t.vertices[1] + t.vertices[2]) / 3.0;
            if (0.2..0.8).contains(&c.y) {
                assert!(
                    xs.iter().all(|&x| x >= -1e-12) || xs.iter().all(|&x| x <= 1e-12),
                    "a piece crosses the contact line: {:?}",
                    t.vertices
                );
            }
        }
        // The wall itself is untouched; a floor with nothing on it too.
        assert_eq!(out.iter().filter(|t| t.group == "wall").count(), 1);
        let (same, none) = contact_lines(floor.clone(), 2.0);
        assert_eq!(none, Imprinted::default());
        assert_eq!(same.len(), 2);
    }
}

#[cfg(test)]
mod scene_tests {
    /// The Cornell box's floor is already cut around the blocks' footprints
    /// (its triangles use the blocks' bottom vertices): nothing to imprint.
    #[test]
    fn cornell_floor_already_conforms() {
        let scene = crate::scene::builtin("cornell").unwrap().unwrap();
        assert_eq!(scene.imprinted, super::Imprinted::default());
    }
}

#[cfg(test)]
mod cube_tests {
    use crate::scene::{Material, SceneBuilder};
    use glam::DVec3;

    /// A cube's footprint on a two-triangle floor: every floor piece lies
    /// wholly inside or wholly outside the footprint, and the pieces tile
    /// the floor.
    #[test]
    fn floor_pieces_do_not_cross_the_footprint() {
        let (lo, hi) = (1.37, 2.41);
        let v = DVec3::new;
        let mut b = SceneBuilder::new("cube");
        let m = b.add_material(Material::diffuse("grey", [0.5; 3])).unwrap();
        let floor = [v(0., 0., 0.), v(4., 0., 0.), v(4., 4., 0.), v(0., 4., 0.)];
        b.add_mesh_f64("floor", &floor, &[[0, 1, 2], [0, 2, 3]], m)
            .unwrap();
        let c = [(lo, lo), (hi, lo), (hi, hi), (lo, hi)];
        for k in 0..4 {
            let ((x0, y0), (x1, y1)) = (c[k], c[(k + 1) % 4]);
            let wall = [v(x0, y0, 0.), v(x1, y1, 0.), v(x1, y1, 1.), v(x0, y0, 1.)];
            b.add_mesh_f64("cube", &wall, &[[0, 1, 2], [0, 2, 3]], m)
                .unwrap();
        }
        let scene = b.build().unwrap();
        let floor_patch = &scene.surface.patches[0];
        let inside =
            |p: DVec3, e: f64| p.x > lo + e && p.x < hi - e && p.y > lo + e && p.y < hi - e;
        let mut area = 0.0;
        for t in &floor_patch.triangles {
            let c = (t[0] + t[1] + t[2]) / 3.0;
            let a = 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).z;
            assert!(a > 0.0, "{t:?}");
            area += a;
            let centre_in = inside(c, 0.0);
            for p in t {
                // A vertex strictly on the other side of the line than the
                // centroid means the piece crosses it.
                if centre_in {
                    assert!(
                        p.x >= lo - 1e-12
                            && p.x <= hi + 1e-12
                            && p.y >= lo - 1e-12
                            && p.y <= hi + 1e-12,
                        "{t:?}"
                    );
                } else {
                    assert!(!inside(*p, 1e-12), "{t:?}");
                }
            }
        }
        crate::assert_close!(area, 16.0, 1e-12);
    }
}
