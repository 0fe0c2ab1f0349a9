//! Vertex colours on the scene's own triangles (not radcol's refinement of
//! them), for engines that light a user's mesh per vertex: u_n at every
//! corner of every input triangle, from the element of that triangle that
//! holds the corner. Split (every triangle its own three vertices: u_n is
//! discontinuous between elements, and the values are the triangle's own)
//! or shared (the corners of one patch at one position and with one normal
//! averaged into one vertex, as a smooth-shaded mesh has them).

use super::{check_solutions, eval_rgb, RenderError, VertexMesh};
use crate::geometry::barycentric_st;
use crate::mesh::Mesh;
use crate::solution::Solution;
use std::collections::HashMap;

/// How corners of neighbouring triangles become vertices.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Corners {
    /// Three vertices per triangle, each with its triangle's value.
    Split,
    /// One vertex per patch, position and normal: the mean of its corners.
    Shared,
}

/// The scene's triangles with u_n (1 grey or 3 RGB channels on `mesh`) at
/// their corners. `VertexMesh::element` names, per triangle, an element
/// inside it (so that its patch, and object, are known).
pub fn input_vertex_mesh(
    mesh: &Mesh,
    solutions: &[&Solution],
    corners: Corners,
) -> Result<VertexMesh, RenderError> {
    check_solutions(mesh, solutions)?;
    let surface = mesh.surface();
    // The elements of each base triangle (patch, triangle).
    let mut inside: HashMap<(u32, usize), Vec<usize>> = HashMap::new();
    for (k, base) in mesh.base_triangles().into_iter().enumerate() {
        if let Some((j, t)) = base {
            inside.entry((j, t as usize)).or_default().push(k);
        }
    }
    let mut out = VertexMesh::default();
    let mut shared: HashMap<([u32; 3], [u32; 3], u32), u32> = HashMap::new();
    let mut sums: Vec<[f64; 3]> = Vec::new();
    let mut count: Vec<u32> = Vec::new();
    let f32x3 = |v: glam::DVec3| [v.x as f32, v.y as f32, v.z as f32];
    for (j, patch) in surface.patches.iter().enumerate() {
        for (t, tri) in patch.triangles.iter().enumerate() {
            let Some(ks) = inside.get(&(j as u32, t)) else {
                continue;
            };
            let normal = mesh.point(ks[0], 1.0 / 3.0, 1.0 / 3.0).normal;
            for corner in tri {
                let (k, st) = ks
                    .iter()
                    .find_map(|&k| {
                        let p = mesh.elements()[k].param;
                        barycentric_st(p[0], p[1], p[2], *corner).map(|st| (k, st))
                    })
                    .ok_or_else(|| {
                        RenderError::InputMesh(format!(
                            "corner of triangle {t} of patch '{}' lies in none of its elements",
                            patch.name
                        ))
                    })?;
                let value = eval_rgb(solutions, k, st[0], st[1]);
                let position = f32x3(patch.map.map(*corner));
                let n = f32x3(normal);
                let index = match corners {
                    Corners::Split => None,
                    Corners::Shared => {
                        let key = (position.map(f32::to_bits), n.map(f32::to_bits), j as u32);
                        let next = out.positions.len() as u32;
                        let i = *shared.entry(key).or_insert(next);
                        (i != next).then_some(i)
                    }
                };
                match index {
                    Some(i) => {
                        let s = &mut sums[i as usize];
                        for c in 0..3 {
                            s[c] += value[c];
                        }
                        out.indices.push(i);
                        count[i as usize] += 1;
                    }
                    None => {
                        out.indices.push(out.positions.len() as u32);
                        out.positions.push(position);
                        out.normals.push(n);
                        sums.push(value);
                        count.push(1);
                    }
                }
            }
            out.element.push(ks[0] as u32);
        }
    }
    // Means over the corners that share each vertex (1 when split).
    out.values = sums
        .iter()
        .zip(&count)
        .map(|(s, &c)| s.map(|v| (v / c as f64) as f32))
        .collect();
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::discretization::Discretization;
    use crate::nodes::NodeSet;
    use std::sync::Arc;

    /// On the Cornell box refined twice, with u_n linear in position (its
    /// nodal values a linear function): every corner holds the function
    /// (split and shared alike: it is continuous), the triangles are the
    /// scene's, and sharing merges the corners of a face.
    #[test]
    fn corners_hold_u_n_on_the_scene_triangles() {
        let scene = crate::scene::builtin("cornell").unwrap().unwrap();
        let mesh = Arc::new(Mesh::new(scene.surface.clone(), 2));
        let disc = Arc::new(Discretization::new(
            mesh.clone(),
            NodeSet::new(1, 0.2).unwrap(),
        ));
        let f = |x: glam::DVec3| 1.0 + 0.001 * x.x + 0.002 * x.y + 0.003 * x.z;
        let u = Solution::new(
            disc.clone(),
            disc.points().iter().map(|p| f(p.position)).collect(),
        );
        let triangles: usize = scene
            .surface
            .patches
            .iter()
            .map(|p| p.triangles.len())
            .sum();
        let split = input_vertex_mesh(&mesh, &[&u], Corners::Split).unwrap();
        let shared = input_vertex_mesh(&mesh, &[&u], Corners::Shared).unwrap();
        for vm in [&split, &shared] {
            assert_eq!(vm.triangle_count(), triangles);
            for (p, v) in vm.positions.iter().zip(&vm.values) {
                let x = glam::DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64);
                crate::assert_close!(v[0] as f64, f(x), 1e-5 * f(x));
            }
        }
        assert_eq!(split.vertex_count(), 3 * triangles);
        assert!(
            shared.vertex_count() < 2 * triangles,
            "{}",
            shared.vertex_count()
        );
    }
}
