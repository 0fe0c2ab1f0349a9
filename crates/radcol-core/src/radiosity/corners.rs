//! Values at the corners of the input's triangles: the join from elements
//! to the input (element → surface triangle → input triangle → its
//! vertices) done once, here, so that a program colours its own copy of
//! the mesh by the indices it already has.

use crate::mesh::Mesh;
use crate::render::{input_vertex_mesh, Corners, RenderError};
use crate::scene::Scene;
use crate::solution::Solution;

/// The shown values at the three corners of one input triangle.
#[derive(Clone, Debug, PartialEq)]
pub struct CornerValues {
    /// The input triangle's position among all the triangles read
    /// ([`crate::scene::TriangleOrigin::input`]).
    pub input: usize,
    /// Its corners' vertex indices in the input (0-based OBJ `v` indices,
    /// or indices into the glTF primitive's or builder mesh's positions).
    pub vertices: [u32; 3],
    /// Radiosity u per channel (R, G, B) at each corner, in the order of
    /// `vertices`. A vertex shared by triangles of different planes has a
    /// value per triangle: average them for smooth shading.
    pub values: [[f32; 3]; 3],
}

/// [`CornerValues`] of every input triangle of `scene` that `mesh` covers,
/// in input order, from `solutions` (one grey or three RGB channels).
pub(super) fn corner_values(
    scene: &Scene,
    mesh: &Mesh,
    solutions: &[&Solution],
) -> Result<Vec<CornerValues>, RenderError> {
    // Every surface triangle with its corners' values; an input triangle cut
    // into pieces (imprinted contact lines) has each of its corners at a
    // corner of one of its pieces.
    let split = input_vertex_mesh(mesh, solutions, Corners::Split)?;
    let origins = scene.element_origins(mesh);
    let tol = 1e-6 * scene.diagonal();
    let mut found: Vec<Option<CornerValues>> = Vec::new();
    let mut set = vec![[false; 3]; 0];
    for (t, tri) in split.indices.chunks_exact(3).enumerate() {
        let Some(origin) = origins[split.element[t] as usize] else {
            continue;
        };
        if found.len() <= origin.input {
            found.resize(origin.input + 1, None);
            set.resize(origin.input + 1, [false; 3]);
        }
        let entry = found[origin.input].get_or_insert(CornerValues {
            input: origin.input,
            vertices: origin.vertices,
            values: [[0.0; 3]; 3],
        });
        for &v in tri {
            let p = split.positions[v as usize].map(f64::from);
            let at = origin.corners.iter().position(|c| {
                (c.x - p[0]).abs() <= tol && (c.y - p[1]).abs() <= tol && (c.z - p[2]).abs() <= tol
            });
            if let Some(c) = at.filter(|&c| !set[origin.input][c]) {
                entry.values[c] = split.values[v as usize];
                set[origin.input][c] = true;
            }
        }
    }
    if let Some((input, _)) =
        (set.iter().enumerate()).find(|(i, s)| found[*i].is_some() && !s.iter().all(|&x| x))
    {
        return Err(RenderError::InputMesh(format!(
            "a corner of input triangle {input} lies at no corner of its surface triangles"
        )));
    }
    Ok(found.into_iter().flatten().collect())
}
