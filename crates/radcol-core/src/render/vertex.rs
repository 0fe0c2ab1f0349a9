//! Per-vertex read-back: each element tessellated into its own sub-triangles,
//! with u_n evaluated at every vertex, for export to PLY and glTF.
//!
//! Vertices are not shared between elements: u_n is discontinuous across element
//! edges, and merging would average two different values into one colour.

use super::tessellation::{tessellation_points, tessellation_triangles};
use super::tonemap::{srgb_encode, ToneMap};
use super::{check_solutions, eval_rgb, RenderError};
use crate::mesh::Mesh;
use crate::solution::Solution;
use std::f64::consts::PI;

/// Triangles with the solution at their vertices. Two layouts:
///
/// * from [`vertex_mesh`] (the elements tessellated `n` times per edge):
///   element k owns vertices `k·V .. (k+1)·V` with V = (n + 1)(n + 2)/2
///   laid out like [`super::tessellation_points`]`(n)`, and triangles
///   `k·n² .. (k+1)·n²`;
/// * from [`super::input_vertex_mesh`] (the scene's own triangles): one
///   triangle per input triangle, patch by patch, its corners split
///   or shared as [`super::Corners`] says; `element` names an element
///   inside each.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct VertexMesh {
    /// Vertex positions m_k(s, t).
    pub positions: Vec<[f32; 3]>,
    /// Unit normals at the vertices, pointing to the side light leaves from.
    pub normals: Vec<[f32; 3]>,
    /// Radiosity u_n per channel at the vertices (grey replicated to three).
    pub values: Vec<[f32; 3]>,
    /// Three vertex indices per triangle, counter-clockwise seen from the front.
    pub indices: Vec<u32>,
    /// The element of each triangle.
    pub element: Vec<u32>,
}

impl VertexMesh {
    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Radiance u / π at the vertices (the quantity images show).
    pub fn radiance(&self) -> Vec<[f32; 3]> {
        self.values
            .iter()
            .map(|v| v.map(|x| (x as f64 / PI) as f32))
            .collect()
    }

    /// Display-referred linear colours in [0, 1]: the radiance tone-mapped like an
    /// image (auto exposure over all vertices), before the sRGB encoding.
    pub fn linear_colors(&self, tm: &ToneMap) -> Vec<[f32; 3]> {
        tm.apply_linear(&self.radiance(), None)
    }

    /// 8-bit sRGB colours: [`Self::linear_colors`] encoded.
    pub fn srgb8_colors(&self, tm: &ToneMap) -> Vec<[u8; 3]> {
        self.linear_colors(tm)
            .into_iter()
            .map(|c| c.map(|y| (255.0 * srgb_encode(y as f64)).round() as u8))
            .collect()
    }
}

/// Tessellates every element of `mesh` into `subdivisions`² triangles with its
/// own vertices and evaluates the solutions (1 grey or 3 RGB channels) there.
pub fn vertex_mesh(
    mesh: &Mesh,
    solutions: &[&Solution],
    subdivisions: u32,
) -> Result<VertexMesh, RenderError> {
    check_solutions(mesh, solutions)?;
    if subdivisions == 0 {
        return Err(RenderError::Subdivisions(subdivisions));
    }
    let pts = tessellation_points(subdivisions);
    let tris = tessellation_triangles(subdivisions);
    let per = pts.len();
    if mesh
        .len()
        .checked_mul(per)
        .is_none_or(|v| v > u32::MAX as usize)
    {
        return Err(RenderError::TooManyVertices {
            elements: mesh.len(),
            per_element: per,
        });
    }
    let nv = mesh.len() * per;
    let mut out = VertexMesh {
        positions: Vec::with_capacity(nv),
        normals: Vec::with_capacity(nv),
        values: Vec::with_capacity(nv),
        indices: Vec::with_capacity(mesh.len() * tris.len() * 3),
        element: Vec::with_capacity(mesh.len() * tris.len()),
    };
    let f32x3 = |v: glam::DVec3| [v.x as f32, v.y as f32, v.z as f32];
    for k in 0..mesh.len() {
        let base = (k * per) as u32;
        for &[s, t] in &pts {
            let p = mesh.point(k, s, t);
            out.positions.push(f32x3(p.position));
            out.normals.push(f32x3(p.normal));
            out.values
                .push(eval_rgb(solutions, k, s, t).map(|u| u as f32));
        }
        for tri in &tris {
            out.indices.extend(tri.map(|i| base + i));
            out.element.push(k as u32);
        }
    }
    Ok(out)
}
