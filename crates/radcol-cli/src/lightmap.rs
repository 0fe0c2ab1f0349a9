//! `--lightmap`, `--lightmap-size` and `--lightmap-density`: the solution baked into a UV atlas of
//! the scene's triangles ([`radcol_core::render::lightmap`]), written as EXR
//! (linear radiance) or PNG (tone-mapped), and the lightmapped glTF.

use crate::files::create;
use crate::objects::layout;
use crate::progress::Bar;
use crate::setup::Look;
use crate::validate::{Output, OutputKind};
use anyhow::{Context, Result};
use radcol_core::export;
use radcol_core::render::{lightmap::bake, lightmap::Atlas, lightmap::Resolution, tone_map, Image};
use radcol_core::run::{Mesh, Solution};
use std::io::Write;

/// A baked lightmap: the atlas, its radiance and its tone-mapped PNG.
#[derive(Debug)]
pub struct Baked {
    atlas: Atlas,
    image: Image,
    png: Vec<u8>,
}

/// Bakes `solutions` into the layout made before the solve (or, for a
/// caller that made none, `mesh`'s surface laid out at `resolution`).
fn bake_all(
    mesh: &Mesh,
    solutions: &[&Solution],
    look: &Look,
    resolution: Resolution,
) -> Result<Baked> {
    let atlas = match &look.lightmap_atlas {
        Some(atlas) => atlas.clone(),
        None => look
            .atlas(mesh.surface(), resolution)
            .context("--lightmap")?,
    };
    let image = bake(mesh, solutions, &atlas).context("--lightmap")?;
    let pixels = tone_map(&image, &look.tone);
    let mut png = Vec::new();
    export::png::write(&mut png, atlas.size, atlas.size, &pixels)?;
    Ok(Baked { atlas, image, png })
}

/// Writes `o` when it uses the lightmap (a --lightmap file, or glTF while
/// a lightmap is baked), baking it on first use into `baked`; returns what
/// it holds, or None for outputs that do not use it.
pub fn output(
    o: &Output,
    look: &Look,
    mesh: &Mesh,
    solutions: &[&Solution],
    baked: &mut Option<Baked>,
    bar: Option<&Bar>,
) -> Result<Option<String>> {
    let uses = matches!(
        o.kind,
        OutputKind::LightmapExr | OutputKind::LightmapPng | OutputKind::Glb | OutputKind::Gltf
    );
    let Some(resolution) = look.lightmap.filter(|_| uses) else {
        return Ok(None);
    };
    if baked.is_none() {
        if let Some(b) = bar {
            b.spin("baking the lightmap".to_string());
        }
        *baked = Some(bake_all(mesh, solutions, look, resolution)?);
    }
    let lm = baked.as_ref().expect("baked above");
    write(o, lm, mesh, look).map(Some)
}

/// Writes one output that uses the lightmap; returns what it holds.
fn write(o: &Output, lm: &Baked, mesh: &Mesh, look: &Look) -> Result<String> {
    let shown = o.file.path.display().to_string();
    let size = lm.atlas.size;
    let charts = match lm.atlas.generated_charts {
        None => "the scene's texture coordinates".to_string(),
        Some(n) => format!("{n} charts"),
    };
    let charts = format!("{charts}, {:.4} texels per unit", lm.atlas.density);
    let mut f = create(&o.file)?;
    let what = match o.kind {
        OutputKind::LightmapExr => {
            export::exr::write(&mut f, &lm.image).with_context(|| format!("writing {shown}"))?;
            format!("{size}×{size} linear lightmap, {charts}")
        }
        OutputKind::LightmapPng => {
            f.write_all(&lm.png)?;
            format!("{size}×{size} lightmap, {charts}")
        }
        OutputKind::Glb | OutputKind::Gltf => {
            let layout = layout(mesh, look);
            let l = export::lightmapped::Lightmapped {
                surface: mesh.surface(),
                atlas: &lm.atlas,
                png: &lm.png,
                layout: &layout,
                object_of_patch: &layout.object_of_patch,
            };
            if o.kind == OutputKind::Glb {
                export::lightmapped::write_glb(&mut f, &l)
            } else {
                export::lightmapped::write_gltf(&mut f, &l)
            }
            .with_context(|| format!("writing {shown}"))?;
            format!(
                "{} objects with a {size}×{size} lightmap ({charts})",
                layout.objects.len()
            )
        }
        _ => unreachable!("only lightmap outputs come here"),
    };
    f.commit()?;
    Ok(what)
}
