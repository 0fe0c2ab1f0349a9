//! A solved scene baked into a lightmap (a texture atlas of its
//! triangles) and written as an image or as a glTF scene that carries it,
//! and its values at the collocation nodes written as CSV.

use super::{Error, Radiosity};
use crate::export::{self, gltf::Layout, lightmapped::Lightmapped, ExportError};
use crate::render::lightmap::{bake, Atlas, Resolution};
use crate::render::{tone_map, Image, ToneMap};
use std::io::Write;

/// The solved scene's light in a texture atlas of its triangles.
#[derive(Clone, Debug)]
pub struct Lightmap {
    /// Where each triangle lies in the atlas.
    pub atlas: Atlas,
    /// Linear radiance per texel, per colour channel (RGB).
    pub image: Image,
}

/// The files [`Radiosity::write_lightmap`] writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightmapFormat {
    /// The atlas as linear radiance (OpenEXR, 32-bit float RGB).
    Exr,
    /// The atlas tone-mapped to 8-bit sRGB (PNG).
    Png,
    /// The scene's triangles textured with the tone-mapped atlas, one node
    /// per object, as one self-contained `.gltf`.
    Gltf,
    /// The same as binary glTF (`.glb`).
    Glb,
}

impl Radiosity {
    /// Bakes the shown values into a lightmap at `resolution` (a size in
    /// texels, or texels per scene unit). Laid out on the scene's own
    /// texture coordinates ([`crate::scene::Scene::uvs`]) when it has them
    /// and `unwrap` is false, else on a generated layout.
    ///
    /// # Errors
    /// A layout that cannot be made at that resolution, or the scene's
    /// own coordinates overlapping ([`crate::render::RenderError`]).
    pub fn bake_lightmap(&self, resolution: Resolution, unwrap: bool) -> Result<Lightmap, Error> {
        let mesh = self.outcome.discretization.mesh();
        let uvs = self.scene.uvs.as_deref().filter(|_| !unwrap);
        let atlas = Atlas::layout(mesh.surface(), uvs, resolution)?;
        let image = bake(mesh, &self.shown(), &atlas)?;
        Ok(Lightmap { atlas, image })
    }

    /// Writes `lightmap` to `w` as `format`, colours tone-mapped by `tone`
    /// (for all but EXR). A glTF's positions keep the scene's units; its
    /// root node scales them to metres when the scene says how.
    pub fn write_lightmap<W: Write>(
        &self,
        lightmap: &Lightmap,
        mut w: W,
        format: LightmapFormat,
        tone: &ToneMap,
    ) -> Result<(), Error> {
        let size = lightmap.atlas.size;
        let png = || -> Result<Vec<u8>, ExportError> {
            let mut png = Vec::new();
            let pixels = tone_map(&lightmap.image, tone);
            export::png::write(&mut png, size, size, &pixels)?;
            Ok(png)
        };
        let written = |r: std::io::Result<()>| {
            r.map_err(|e| ExportError::Write {
                what: "lightmap: writing the file".into(),
                source: Box::new(e),
            })
        };
        match format {
            LightmapFormat::Exr => {
                // EXR needs to seek: encoded in memory, then written.
                let mut exr = std::io::Cursor::new(Vec::new());
                export::exr::write(&mut exr, &lightmap.image)?;
                written(w.write_all(exr.get_ref()))?;
            }
            LightmapFormat::Png => written(w.write_all(&png()?))?,
            LightmapFormat::Gltf | LightmapFormat::Glb => {
                let mesh = self.outcome.discretization.mesh();
                let metres = self.scene.metres_per_unit.unwrap_or(1.0);
                let layout = Layout::of_mesh(mesh, &self.scene.name, metres, true);
                let png = png()?;
                let l = Lightmapped {
                    surface: mesh.surface(),
                    atlas: &lightmap.atlas,
                    png: &png,
                    layout: &layout,
                    object_of_patch: &layout.object_of_patch,
                };
                if format == LightmapFormat::Glb {
                    export::lightmapped::write_glb(w, &l)?;
                } else {
                    export::lightmapped::write_gltf(w, &l)?;
                }
            }
        }
        Ok(())
    }

    /// Writes one CSV row per collocation node: its element, node and
    /// position, each channel's u_n under the current lights and, until the
    /// first relight, each one's estimated error on the node's element
    /// ([`export::csv::write_nodes`]). Returns the number of rows.
    pub fn write_nodes_csv<W: Write>(&self, w: W) -> Result<usize, Error> {
        let disc = &self.outcome.discretization;
        Ok(export::csv::write_nodes(w, disc, self.channels())?)
    }
}
