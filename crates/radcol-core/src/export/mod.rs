//! Writers for what people look at: 8-bit PNG images, linear EXR images,
//! per-vertex meshes as PLY and glTF 2.0, glTF scenes with their
//! lightmaps, and the nodal values as CSV.
//!
//! Every writer takes the data it writes ([`crate::render::Image`], tone-mapped
//! pixels, [`crate::render::VertexMesh`]) and any `Write`: the caller opens
//! the file (and decides whether an existing one may be replaced).

/// `return Err(ExportError::Invalid(format!(…)))`.
macro_rules! bail {
    ($($t:tt)*) => {
        return Err($crate::export::ExportError::Invalid(format!($($t)*)))
    };
}

pub mod csv;
pub mod exr;
pub mod gltf;
pub mod lightmapped;
pub mod ply;
pub mod png;

/// Why a file could not be written.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// The data cannot be written in the format (the message names the
    /// format and the item at fault).
    #[error("{0}")]
    Invalid(String),
    /// The writer or encoder failed (the reason is the error's source).
    #[error("{what}")]
    Write {
        /// What was being written ("PNG: writing the pixels").
        what: String,
        /// The underlying error.
        #[source]
        source: Box<dyn std::error::Error + Send + Sync>,
    },
}

/// The writers' result.
pub type Result<T> = std::result::Result<T, ExportError>;

/// Names what was being written when a writer or encoder failed.
pub(crate) trait Context<T> {
    /// The error as [`ExportError::Write`] of `what`.
    fn context(self, what: &str) -> Result<T>;
}

impl<T, E: std::error::Error + Send + Sync + 'static> Context<T> for std::result::Result<T, E> {
    fn context(self, what: &str) -> Result<T> {
        self.map_err(|e| ExportError::Write {
            what: what.to_string(),
            source: Box::new(e),
        })
    }
}

use crate::render::VertexMesh;

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
