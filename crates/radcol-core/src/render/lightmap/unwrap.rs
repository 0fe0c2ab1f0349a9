//! Lightmap layouts generated for scenes without texture coordinates, by
//! the `uvunwrap` crate: each patch's triangles (vertices merged where they
//! coincide, so charts grow across edges) are segmented into charts within
//! a normal cone, flattened (planar faces exactly) and shape-packed, with
//! `GUTTER` texels of padding around each chart, either at the largest
//! density that fits one `size`² page or at a chosen texel density in a
//! page as large as it needs. The coordinates are then checked and used as the
//! input's would be ([`Atlas::from_uvs`]).

use super::{plane_of, Atlas, RenderError, GUTTER};
use crate::geometry::Surface;
use std::collections::HashMap;

impl Atlas {
    /// A generated layout of `surface`'s triangles at `size`×`size`
    /// texels. Curved patches are refused (their elements are not planar).
    ///
    /// # Errors
    /// A size outside 16..=16384, a curved patch, a scene with no triangle
    /// of area, and charts that do not fit one page at any density.
    pub fn new(surface: &Surface, size: u32) -> Result<Self, RenderError> {
        if !(16..=16384).contains(&size) {
            return Err(RenderError::Lightmap(format!(
                "atlas size {size}: must lie in 16..=16384 texels"
            )));
        }
        generate(surface, Page::Size(size))
    }

    /// A generated layout of `surface`'s triangles at `texels_per_unit`
    /// texels per scene unit of length (how engines size lightmaps, so
    /// that texels are alike across scenes): the square atlas is as large
    /// as the packed charts need, at least 16 texels.
    ///
    /// # Errors
    /// A density that is not positive and finite, or that needs an atlas
    /// over 16384 texels a side (the error says the largest that fits),
    /// and the errors of [`Atlas::new`].
    pub fn with_density(surface: &Surface, texels_per_unit: f64) -> Result<Self, RenderError> {
        let d = texels_per_unit as f32;
        if !(d.is_finite() && d > 0.0) {
            return Err(RenderError::Lightmap(format!(
                "texel density {texels_per_unit}: must be positive and finite"
            )));
        }
        // No packing beats the whole surface in one square: refused before
        // unwrapping when even that would not fit.
        let area: f64 = surface
            .patches
            .iter()
            .flat_map(|p| p.triangles.iter().map(|t| t.map(|x| p.map.map(x))))
            .map(|v| 0.5 * (v[1] - v[0]).cross(v[2] - v[0]).length())
            .sum();
        let least = texels_per_unit * area.sqrt();
        if least > 16384.0 {
            return Err(RenderError::Lightmap(format!(
                "texel density {texels_per_unit}: the surface alone needs {least:.0}² texels, \
                 more than 16384 texels a side; a density below {:.3e} fits",
                16384.0 / area.sqrt()
            )));
        }
        generate(surface, Page::Density(d))
    }
}

/// How the page of a generated layout is sized.
#[derive(Clone, Copy)]
enum Page {
    /// A square of this many texels a side, the charts as large as fits.
    Size(u32),
    /// As large as the charts need at this many texels per unit.
    Density(f32),
}

/// The layout of `surface` that `uvunwrap` generates for `page`, checked
/// and used as input coordinates.
fn generate(surface: &Surface, page: Page) -> Result<Atlas, RenderError> {
    let bad = |m: String| Err(RenderError::Lightmap(m));
    let (lo, hi) = surface.bounding_box();
    let scale = (hi - lo).length().max(f64::MIN_POSITIVE);
    // Per patch: merged vertices (f32, relative to the scene's corner)
    // and the triangles' indices.
    let mut meshes: Vec<(Vec<[f32; 3]>, Vec<u32>)> = Vec::new();
    let mut areas = 0usize;
    for patch in &surface.patches {
        let (mut positions, mut indices) = (Vec::new(), Vec::new());
        let mut index_of: HashMap<[u64; 3], u32> = HashMap::new();
        for tri in &patch.triangles {
            areas += usize::from(plane_of(patch, tri, scale)?.is_some());
            for x in tri.map(|x| patch.map.map(x)) {
                let i = *index_of
                    .entry(x.to_array().map(f64::to_bits))
                    .or_insert_with(|| {
                        positions.push((x - lo).as_vec3().to_array());
                        positions.len() as u32 - 1
                    });
                indices.push(i);
            }
        }
        meshes.push((positions, indices));
    }
    if areas == 0 {
        return bad("the scene has no triangle to map".into());
    }
    let inputs: Vec<uvunwrap::MeshInput<'_>> = meshes
        .iter()
        .map(|(p, i)| uvunwrap::MeshInput::new(p, i))
        .collect();
    let density = match page {
        Page::Size(page_size) => uvunwrap::Density::Auto { page_size },
        Page::Density(texels_per_unit) => uvunwrap::Density::Fixed {
            texels_per_unit,
            page_size: None,
        },
    };
    let options = uvunwrap::Options {
        density,
        padding: GUTTER,
        ..Default::default()
    };
    let layout = uvunwrap::generate(&inputs, &options)
        .map_err(|e| RenderError::Lightmap(format!("unwrapping the scene: {e}")))?;
    let size = match page {
        Page::Size(size) => size,
        Page::Density(texels_per_unit) => {
            let side = layout.width.max(layout.height).max(16);
            if side > 16384 {
                let fits = texels_per_unit as f64 * 16384.0 / side as f64;
                return bad(format!(
                    "texel density {texels_per_unit}: the charts need a {side}×{side} atlas, \
                     more than 16384 texels a side; a density up to about {fits:.3e} fits"
                ));
            }
            side
        }
    };
    if layout.page_count != 1 || layout.width > size || layout.height > size {
        return bad(format!(
            "{} charts do not fit one {size}×{size} atlas with their padding: give a larger size",
            layout.chart_count
        ));
    }
    // Page coordinates (of the page cropped to its rows) to the square.
    let page = [layout.width, layout.height].map(|w| w as f64 / size as f64);
    let uvs: Vec<Vec<[[f64; 2]; 3]>> = layout
        .meshes
        .iter()
        .map(|out| {
            out.indices
                .chunks_exact(3)
                .map(|t| {
                    [0, 1, 2].map(|c| {
                        let uv = out.vertices[t[c] as usize].uv;
                        [0, 1].map(|a| (uv[a] as f64 * page[a]).clamp(0.0, 1.0))
                    })
                })
                .collect()
        })
        .collect();
    let mut atlas = Atlas::from_uvs(surface, &uvs, size)?;
    atlas.generated_charts = Some(layout.chart_count);
    Ok(atlas)
}
