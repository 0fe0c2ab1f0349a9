//! A solved scene written as a mesh with its light (the input's triangles
//! with the shown values at their corners, as PLY or glTF) or as an image
//! (PNG, EXR).

use super::{Error, Radiosity};
use crate::camera::Camera;
use crate::export::{self, gltf, ply, ExportError};
use crate::render::{tone_map, Corners, RenderOptions, ToneMap};
use std::io::Write;

/// The image files [`Radiosity::write_image`] writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// 8-bit sRGB, tone-mapped.
    Png,
    /// Linear radiance, 32-bit float RGB (OpenEXR).
    Exr,
}

/// The mesh formats [`Radiosity::write_mesh`] writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshFormat {
    /// Binary PLY: positions, normals, sRGB colours and the raw radiosity
    /// of each channel per vertex.
    Ply,
    /// One self-contained `.gltf` (its buffer embedded): one node per
    /// object of the input, vertex colours (linear, tone-mapped), an unlit
    /// material.
    Gltf,
    /// The same as binary glTF (`.glb`).
    Glb,
}

impl Radiosity {
    /// Writes the input's triangles with the shown values at their corners
    /// (corners shared where position and normal agree) to `w` as `format`,
    /// colours tone-mapped by `tone`. Positions keep the scene's units; a
    /// glTF's root node scales them to metres when the scene says how.
    pub fn write_mesh<W: Write>(
        &self,
        w: W,
        format: MeshFormat,
        tone: &ToneMap,
    ) -> Result<(), Error> {
        let mesh = self.outcome.discretization.mesh();
        let vertices = self.input_vertex_mesh(Corners::Shared)?;
        let layout = || {
            let metres = self.scene.metres_per_unit.unwrap_or(1.0);
            gltf::Layout::of_mesh(mesh, &self.scene.name, metres, true)
        };
        match format {
            MeshFormat::Ply => ply::write(w, &vertices, &["R", "G", "B"], tone, None)?,
            MeshFormat::Gltf => gltf::write_gltf(w, &vertices, tone, &layout())?,
            MeshFormat::Glb => gltf::write_glb(w, &vertices, tone, &layout())?,
        }
        Ok(())
    }

    /// Renders the shown values from `camera` (None: the scene's own, or
    /// one chosen to show its lit sides; as [`Radiosity::render`]) and
    /// writes the image to `w` as `format`, tone-mapped by `tone` for PNG.
    pub fn write_image<W: Write>(
        &self,
        mut w: W,
        camera: Option<&Camera>,
        options: &RenderOptions,
        format: ImageFormat,
        tone: &ToneMap,
    ) -> Result<(), Error> {
        let image = self.render(camera, options)?;
        match format {
            ImageFormat::Png => {
                let pixels = tone_map(&image, tone);
                export::png::write(w, image.width, image.height, &pixels)?;
            }
            ImageFormat::Exr => {
                // EXR needs to seek: encoded in memory, then written.
                let mut exr = std::io::Cursor::new(Vec::new());
                export::exr::write(&mut exr, &image)?;
                w.write_all(exr.get_ref()).map_err(|e| ExportError::Write {
                    what: "EXR: writing the file".into(),
                    source: Box::new(e),
                })?;
            }
        }
        Ok(())
    }
}
