//! Writers for what people look at: 8-bit PNG images, linear EXR images, and
//! per-vertex meshes as PLY and glTF 2.0.
//!
//! Every writer takes plain data ([`radcol_core::render::Image`], tone-mapped
//! pixels, [`radcol_core::render::VertexMesh`]) and any `Write`, so the caller
//! opens files through `files::create` (which honours --force).

pub mod error_map;
pub mod exr;
pub mod gltf;
pub mod lightmapped;
pub mod ply;
pub mod png;

use anyhow::{bail, Result};
use radcol_core::render::VertexMesh;

/// Checks what every mesh writer relies on: one normal and one value per
/// position, whole triangles, and indices below the vertex count and at most
/// `max_index` (the format's largest index). `format` prefixes the message.
pub fn check_vertex_mesh(format: &str, mesh: &VertexMesh, max_index: u32) -> Result<()> {
    let nv = mesh.positions.len();
    if mesh.normals.len() != nv || mesh.values.len() != nv {
        bail!(
            "{format}: vertex mesh has {nv} positions, {} normals and {} values",
            mesh.normals.len(),
            mesh.values.len()
        );
    }
    if !mesh.indices.len().is_multiple_of(3) {
        bail!(
            "{format}: {} triangle indices is not a multiple of 3",
            mesh.indices.len()
        );
    }
    if let Some((i, &v)) = mesh
        .indices
        .iter()
        .enumerate()
        .find(|&(_, &v)| v as usize >= nv || v > max_index)
    {
        bail!(
            "{format}: index {i} (triangle {}) = {v} is out of range for {nv} vertices",
            i / 3
        );
    }
    Ok(())
}
