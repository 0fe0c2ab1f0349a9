//! Which triangle of the surface (its patch's `triangles`, the scene's own
//! triangles for a scene) each element refines, found through a BVH over
//! each patch's triangles in parameter space: O(n log T), where trying
//! every triangle of the patch cost O(n T) (a 10^5-triangle OBJ).

use super::Mesh;
use crate::geometry::{barycentric_st, bounds};
use glam::Vec3A;
use obvhs::aabb::Aabb;
use obvhs::bvh2::builder::build_bvh2;
use obvhs::{Boundable, BvhBuildParams};
use std::time::Duration;

struct TriBox(Aabb);

impl Boundable for TriBox {
    fn aabb(&self) -> Aabb {
        self.0
    }
}

impl Mesh {
    /// Per element: (patch, index into the patch's `triangles`) of the
    /// surface triangle it lies in (its parameter centroid does), or None
    /// when none holds it.
    pub fn base_triangles(&self) -> Vec<Option<(u32, u32)>> {
        let patches = &self.surface().patches;
        let mut by_patch: Vec<Vec<usize>> = vec![Vec::new(); patches.len()];
        for (k, e) in self.elements().iter().enumerate() {
            by_patch[e.patch as usize].push(k);
        }
        let mut out = vec![None; self.len()];
        for (j, ks) in by_patch.iter().enumerate() {
            let tris = &patches[j].triangles;
            if ks.is_empty() || tris.is_empty() {
                continue;
            }
            let (lo, hi) = bounds(tris.iter().flatten().copied());
            let centre = 0.5 * (lo + hi);
            let pad = 1e-5 * (hi - lo).max_element().max(f64::MIN_POSITIVE);
            let f32x3 = |v: glam::DVec3| Vec3A::new(v.x as f32, v.y as f32, v.z as f32);
            let boxes: Vec<TriBox> = tris
                .iter()
                .map(|t| {
                    let (a, b) = bounds(t.iter().copied());
                    TriBox(Aabb::new(f32x3(a - centre - pad), f32x3(b - centre + pad)))
                })
                .collect();
            let bvh = build_bvh2(
                &boxes,
                BvhBuildParams::medium_build(),
                &mut Duration::default(),
            );
            for &k in ks {
                let p = self.elements()[k].param;
                let c = (p[0] + p[1] + p[2]) / 3.0;
                let query = Aabb::new(f32x3(c - centre - pad), f32x3(c - centre + pad));
                let mut found = None;
                bvh.aabb_traverse(query, |bvh, node_index| {
                    let node = &bvh.nodes[node_index as usize];
                    for slot in node.first_index..node.first_index + node.prim_count {
                        let t = bvh.primitive_indices[slot as usize] as usize;
                        let tri = &tris[t];
                        if found.is_none() && barycentric_st(tri[0], tri[1], tri[2], c).is_some() {
                            found = Some((j as u32, t as u32));
                        }
                    }
                    found.is_none()
                });
                out[k] = found;
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use crate::geometry::barycentric_st;
    use crate::geometry::shapes::{box_room, sphere};
    use crate::mesh::Mesh;
    use std::sync::Arc;

    /// Every element's triangle holds all three of its parameter vertices,
    /// on flat (box, refined with a max edge too) and curved (sphere) meshes.
    #[test]
    fn every_element_lies_in_its_base_triangle() {
        let box_ = Arc::new(box_room(1.0, 2.0, 1.5));
        for mesh in [
            Mesh::new(box_.clone(), 2),
            Mesh::with_max_edge(box_, 0, 0.3),
            Mesh::new(Arc::new(sphere(1.0)), 2),
        ] {
            let base = mesh.base_triangles();
            for (k, e) in mesh.elements().iter().enumerate() {
                let (j, t) = base[k].expect("every element has its triangle");
                assert_eq!(j, e.patch);
                let tri = mesh.surface().patches[j as usize].triangles[t as usize];
                for v in e.param {
                    assert!(barycentric_st(tri[0], tri[1], tri[2], v).is_some());
                }
            }
        }
    }
}
