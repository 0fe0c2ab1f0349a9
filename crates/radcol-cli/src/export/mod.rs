//! Writers for what people look at: 8-bit PNG images, linear EXR images, and
//! per-vertex meshes as PLY and glTF 2.0.
//!
//! Every writer takes plain data ([`radcol_core::render::Image`], tone-mapped
//! pixels, [`radcol_core::render::VertexMesh`]) and any `Write`, so the caller
//! opens files through `output::create` (which honours --force).

pub mod exr;
pub mod gltf;
pub mod ply;
pub mod png;
