//! Finding the element under a point: a BVH (obvhs) over the elements'
//! bounding balls, so that a query tests the few elements near the point
//! instead of all n ([`Mesh::locate`] is the linear scan it replaces, kept
//! as its reference).
//!
//! The BVH is f32. As in the render BVH, boxes live in coordinates relative
//! to the mesh's centre and are padded by 1e-5 of its extent, a hundred
//! times f32's rounding, so the broad phase never drops an element the f64
//! test would keep.

use super::Mesh;
use crate::geometry::bounds;
use glam::{DVec3, Vec3A};
use obvhs::aabb::Aabb;
use obvhs::bvh2::builder::build_bvh2;
use obvhs::bvh2::Bvh2;
use obvhs::{Boundable, BvhBuildParams};
use std::time::Duration;

/// Box padding relative to the mesh's extent.
const PAD: f64 = 1e-5;

/// A point found on a mesh: its element, (s, t) there, and how far the
/// point asked for was from it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Located {
    /// Element k.
    pub element: usize,
    /// (s, t) in σ.
    pub st: [f64; 2],
    /// The point of S: m_k(s, t).
    pub position: DVec3,
    /// The inner unit normal there (the side light leaves from).
    pub normal: DVec3,
    /// Distance from the point asked for to `position`.
    pub distance: f64,
}

struct BallBox(Aabb);

impl Boundable for BallBox {
    fn aabb(&self) -> Aabb {
        self.0
    }
}

/// A BVH over the elements of one mesh.
pub struct Locator {
    bvh: Bvh2,
    centre: DVec3,
    pad: f64,
}

impl std::fmt::Debug for Locator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Locator")
            .field("nodes", &self.bvh.nodes.len())
            .field("centre", &self.centre)
            .finish()
    }
}

impl Locator {
    /// The BVH over `mesh`'s elements: each in the box of its bounding ball
    /// widened as [`Mesh::locate`] widens it (1.1 × the radius).
    pub fn new(mesh: &Mesh) -> Self {
        let balls: Vec<(DVec3, f64)> = (0..mesh.len()).map(|k| mesh.bounding_ball(k)).collect();
        let (lo, hi) = if balls.is_empty() {
            (DVec3::ZERO, DVec3::ZERO)
        } else {
            bounds(balls.iter().flat_map(|&(c, r)| [c - r, c + r]))
        };
        let centre = 0.5 * (lo + hi);
        let pad = PAD * (hi - lo).max_element().max(f64::MIN_POSITIVE);
        let boxes: Vec<BallBox> = balls
            .iter()
            .map(|&(c, r)| {
                let w = DVec3::splat(1.1 * r + 1e-12 + pad);
                BallBox(Aabb::new(to_f32(c - w - centre), to_f32(c + w - centre)))
            })
            .collect();
        let bvh = build_bvh2(
            &boxes,
            BvhBuildParams::medium_build(),
            &mut Duration::default(),
        );
        Self { bvh, centre, pad }
    }

    /// The elements whose box meets the cube of half-side `reach` around `x`.
    fn near(&self, x: DVec3, reach: f64, out: &mut Vec<usize>) {
        out.clear();
        if self.bvh.nodes.is_empty() || !x.is_finite() {
            return;
        }
        let w = DVec3::splat(reach + self.pad);
        let query = Aabb::new(to_f32(x - w - self.centre), to_f32(x + w - self.centre));
        self.bvh.aabb_traverse(query, |bvh, node_index| {
            let node = &bvh.nodes[node_index as usize];
            for slot in node.first_index..node.first_index + node.prim_count {
                out.push(bvh.primitive_indices[slot as usize] as usize);
            }
            true
        });
        out.sort_unstable();
        out.dedup();
    }

    /// [`Mesh::locate`] through the BVH: the same element and (s, t).
    pub fn locate(&self, mesh: &Mesh, x: DVec3) -> Option<(usize, [f64; 2])> {
        let mut cands = Vec::new();
        self.near(x, 0.0, &mut cands);
        mesh.locate_among(cands, x)
    }

    /// The point of S nearest to `x` within distance `reach`, on an element
    /// whose normal there points into the half-space of `facing` when it is
    /// given (so that a point on a room's edge is found on the face it was
    /// meant for). Elements are projected onto by [`Mesh::project_onto`] and
    /// the result clamped into σ; of equally near ones, the lowest index.
    pub fn nearest(
        &self,
        mesh: &Mesh,
        x: DVec3,
        facing: Option<DVec3>,
        reach: f64,
    ) -> Option<Located> {
        let mut cands = Vec::new();
        self.near(x, reach, &mut cands);
        let mut best: Option<Located> = None;
        for k in cands {
            let [s, t] = mesh.project_onto(k, x);
            if !(s.is_finite() && t.is_finite()) {
                continue;
            }
            let st = clamp_to_simplex(s, t);
            let p = mesh.point(k, st[0], st[1]);
            let distance = (p.position - x).length();
            let faces = facing.is_none_or(|n| p.normal.dot(n) > 0.0);
            if distance > reach || !faces {
                continue;
            }
            if best.as_ref().is_none_or(|b| distance < b.distance) {
                best = Some(Located {
                    element: k,
                    st,
                    position: p.position,
                    normal: p.normal,
                    distance,
                });
            }
        }
        best
    }
}

/// (s, t) moved into σ: negative coordinates to 0, then a sum above 1
/// scaled down to 1.
fn clamp_to_simplex(s: f64, t: f64) -> [f64; 2] {
    let (s, t) = (s.max(0.0), t.max(0.0));
    let sum = s + t;
    if sum > 1.0 {
        [s / sum, t / sum]
    } else {
        [s, t]
    }
}

fn to_f32(v: DVec3) -> Vec3A {
    Vec3A::new(v.x as f32, v.y as f32, v.z as f32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::shapes::{box_room, sphere};
    use std::sync::Arc;

    /// The BVH finds what the linear scan finds, element and (s, t), at
    /// points inside elements, on their edges and vertices, and off the
    /// surface (nothing); on flat (box) and curved (sphere) meshes.
    #[test]
    fn bvh_agrees_with_the_linear_scan() {
        for surface in [box_room(1.0, 2.0, 1.5), sphere(1.0)] {
            let mesh = Mesh::new(Arc::new(surface), 2);
            let loc = Locator::new(&mesh);
            for k in (0..mesh.len()).step_by(3) {
                for st in [[0.2, 0.3], [0.5, 0.0], [0.0, 0.0], [0.25, 0.75]] {
                    let x = mesh.position(k, st[0], st[1]);
                    let want = mesh.locate(x).expect("on the mesh");
                    let got = loc.locate(&mesh, x).expect("on the mesh");
                    assert_eq!(got.0, want.0, "element at {x}");
                    assert_eq!(got.1, want.1);
                    // Off the surface by 1e-3 along the normal: nothing,
                    // unless that lands on another face (a box corner).
                    let off = x + mesh.point(k, st[0], st[1]).normal * 1e-3;
                    assert_eq!(loc.locate(&mesh, off), mesh.locate(off));
                    if st == [0.2, 0.3] {
                        assert!(loc.locate(&mesh, off).is_none());
                    }
                }
            }
        }
    }

    /// `nearest` snaps a point off the surface back onto it, within reach
    /// only, and the facing normal picks the face at an edge of the room.
    #[test]
    fn nearest_snaps_and_picks_the_face() {
        let mesh = Mesh::new(Arc::new(box_room(1.0, 2.0, 1.5)), 1);
        let loc = Locator::new(&mesh);
        let k = 5;
        let p = mesh.point(k, 0.3, 0.3);
        let off = p.position - p.normal * 1e-4;
        let hit = loc.nearest(&mesh, off, None, 1e-3).expect("within reach");
        assert!((hit.position - p.position).length() < 1e-12);
        assert!((hit.distance - 1e-4).abs() < 1e-12);
        assert!(loc.nearest(&mesh, off, None, 5e-5).is_none());
        // A corner of the box: every face meets it; the normal picks one.
        let corner = DVec3::ZERO;
        for n in [DVec3::X, DVec3::Y, DVec3::Z] {
            let hit = loc.nearest(&mesh, corner, Some(n), 1e-9).expect("a corner");
            assert!(hit.normal.dot(n) > 0.99, "{n}: {}", hit.normal);
            assert!(hit.distance < 1e-12);
        }
    }
}
