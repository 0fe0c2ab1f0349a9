//! Output files and the look of images, as given: kinds by extension,
//! camera, image size, exposure, tone curve and tessellation.

use crate::args::{SolveArgs, TonemapArg, VerticesArg};
use crate::error::{bad_input, BadInput};
use radcol_core::render::{lightmap::Resolution, Camera, RenderOptions, ToneMap, ToneOperator};
use std::path::{Path, PathBuf};

/// The kinds of file `--out` writes, by extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutputKind {
    /// Nodal values, one row per collocation node.
    Csv,
    /// Binary PLY vertex mesh.
    Ply,
    /// Binary glTF.
    Glb,
    /// glTF JSON with the buffer embedded.
    Gltf,
    /// Tone-mapped 8-bit image.
    Png,
    /// Linear radiance image.
    Exr,
    /// Map of the element error estimates (`--error-map`, PNG).
    ErrorMap,
    /// The lightmap atlas, linear (`--lightmap`, EXR).
    LightmapExr,
    /// The lightmap atlas, tone-mapped (`--lightmap`, PNG).
    LightmapPng,
}

impl OutputKind {
    /// Every kind with its extension.
    pub const ALL: [(OutputKind, &'static str); 6] = [
        (OutputKind::Csv, "csv"),
        (OutputKind::Ply, "ply"),
        (OutputKind::Glb, "glb"),
        (OutputKind::Gltf, "gltf"),
        (OutputKind::Png, "png"),
        (OutputKind::Exr, "exr"),
    ];

    /// True for the rendered images.
    pub fn is_image(self) -> bool {
        matches!(self, OutputKind::Png | OutputKind::Exr)
    }
}

/// One `--out` file.
#[derive(Clone, Debug)]
pub struct Output {
    /// What to write.
    pub kind: OutputKind,
    /// Where.
    pub file: OutputFile,
}

/// An output file with an accepted extension; whether it may be written
/// (parent exists, not in the way) is checked by the run step before work.
#[derive(Clone, Debug)]
pub struct OutputFile {
    /// Where.
    pub path: PathBuf,
    /// Overwrite if it exists.
    pub force: bool,
    /// The flag that named it, for messages.
    pub flag: &'static str,
}

/// Camera, image and tone-mapping settings as given.
#[derive(Clone, Debug)]
pub struct LookSpec {
    /// --camera, when given.
    pub camera: Option<Camera>,
    /// Image size and sampling.
    pub render: RenderOptions,
    /// Exposure and tone curve of 8-bit outputs.
    pub tone: ToneMap,
    /// Triangles per element edge of vertex meshes; None: max(r, 1).
    pub tessellation: Option<u32>,
    /// --units: metres per scene unit, when given.
    pub metres_per_unit: Option<f64>,
    /// The lightmap's size or texel density, when one is baked
    /// (--lightmap, --lightmap-size or --lightmap-density).
    pub lightmap: Option<Resolution>,
    /// --lightmap-unwrap: a generated layout even when the scene has texture
    /// coordinates.
    pub lightmap_unwrap: bool,
    /// --vertices: the vertex meshes on the scene's triangles, and with
    /// which corners shared, instead of on the elements.
    pub input_vertices: Option<radcol_core::render::Corners>,
}

/// The lightmap's size or density when one is asked for
/// ([`Resolution::default`] when neither is given).
fn lightmap_size(a: &SolveArgs) -> Result<Option<Resolution>, BadInput> {
    if let Some(n) = a.lightmap_size.filter(|n| !(16..=16384).contains(n)) {
        return Err(bad_input(format!(
            "--lightmap-size {n}: must lie in 16..=16384 texels"
        )));
    }
    if let Some(d) = a.lightmap_density.filter(|d| !(d.is_finite() && *d > 0.0)) {
        return Err(bad_input(format!(
            "--lightmap-density {d}: must be a positive number of texels per scene unit"
        )));
    }
    let asked = !a.lightmap.is_empty() || a.lightmap_size.is_some() || a.lightmap_density.is_some();
    Ok(asked.then(|| match (a.lightmap_size, a.lightmap_density) {
        (_, Some(d)) => Resolution::Density(d),
        (n, None) => n.map_or_else(Resolution::default, Resolution::Size),
    }))
}

/// A `--lightmap` file: EXR or PNG by its extension.
pub(super) fn lightmap(path: &Path, force: bool) -> Result<Output, BadInput> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let kind = match ext.as_deref() {
        Some("exr") => OutputKind::LightmapExr,
        Some("png") => OutputKind::LightmapPng,
        _ => {
            return Err(bad_input(format!(
                "--lightmap {}: the name must end in .exr (linear) or .png (tone-mapped)",
                path.display()
            )))
        }
    };
    Ok(Output {
        kind,
        file: OutputFile {
            path: path.to_path_buf(),
            force,
            flag: "--lightmap",
        },
    })
}

/// `--units`: a unit's name or metres per scene unit.
fn units(text: &str) -> Result<f64, BadInput> {
    let named = [
        ("mm", 1e-3),
        ("cm", 1e-2),
        ("m", 1.0),
        ("km", 1e3),
        ("in", 0.0254),
        ("ft", 0.3048),
    ];
    if let Some(&(_, v)) = named
        .iter()
        .find(|(n, _)| n.eq_ignore_ascii_case(text.trim()))
    {
        return Ok(v);
    }
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(bad_input(format!(
            "--units {text}: give mm, cm, m, km, in, ft or metres per scene unit (a positive number)"
        ))),
    }
}

/// An `--out` path: its kind from the extension.
pub(super) fn output(path: &Path, force: bool) -> Result<Output, BadInput> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    let Some(&(kind, _)) = OutputKind::ALL.iter().find(|(_, e)| *e == ext) else {
        return Err(bad_input(format!(
            "--out {}: unknown file type; the name must end in .csv, .ply, .glb, .gltf, .png or .exr",
            path.display()
        )));
    };
    let file = OutputFile {
        path: path.to_path_buf(),
        force,
        flag: "--out",
    };
    Ok(Output { kind, file })
}

/// An `--error-map` path: only PNG.
pub(super) fn error_map(path: &Path, force: bool) -> Result<Output, BadInput> {
    let file = only(
        "--error-map",
        "png",
        path,
        force,
        "the error map is a PNG image",
    )?;
    Ok(Output {
        kind: OutputKind::ErrorMap,
        file,
    })
}

/// `path` for `flag`, which writes only files ending in `.ext` (`why` says
/// so in the refusal).
pub(super) fn only(
    flag: &'static str,
    ext: &str,
    path: &Path,
    force: bool,
    why: &str,
) -> Result<OutputFile, BadInput> {
    let ok = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case(ext));
    if !ok {
        return Err(bad_input(format!(
            "{flag} {}: {why} (the file name must end in .{ext})",
            path.display()
        )));
    }
    Ok(OutputFile {
        path: path.to_path_buf(),
        force,
        flag,
    })
}

/// Camera, image size, exposure and tessellation; checked even when no image
/// is asked for, so that a typo never waits for a solve.
pub(super) fn look(a: &SolveArgs) -> Result<LookSpec, BadInput> {
    let camera = a
        .camera
        .as_deref()
        .map(|text| {
            // The library's messages start "camera: "; the flag says it here.
            Camera::parse(text).map_err(|e| {
                bad_input(format!(
                    "--camera: {}",
                    e.strip_prefix("camera: ").unwrap_or(&e)
                ))
            })
        })
        .transpose()?;
    // --samples N keeps its meaning: N² rays on the grid, as --spp N².
    let (rays, rays_flag) = match (a.spp, a.samples) {
        (Some(s), _) => (s as u64, "--spp"),
        (None, Some(n)) => ((n as u64).saturating_mul(n as u64), "--samples"),
        (None, None) => (RenderOptions::default().samples_per_pixel as u64, "--spp"),
    };
    for (flag, v) in [
        ("--width", a.width as u64),
        ("--height", a.height as u64),
        (rays_flag, rays),
    ] {
        if v == 0 {
            return Err(bad_input(format!("{flag} must be at least 1")));
        }
    }
    let pixels = (a.width as u64 * a.height as u64).saturating_mul(rays);
    if pixels > 1 << 30 {
        return Err(bad_input(format!(
            "--width {} --height {} with {rays} rays per pixel: {pixels} rays is more than radcol renders (2^30)",
            a.width, a.height
        )));
    }
    // Per pixel: linear RGB, coverage and emitters (f32 each), the 8-bit
    // image and the encoder's row: about 32 bytes. Refused before the solve,
    // not after it.
    let image_bytes = 32.0 * a.width as f64 * a.height as f64;
    let budget = radcol_core::run::MemoryBudget::now();
    if !budget.fits(image_bytes) {
        return Err(bad_input(format!(
            "--width {} --height {}: the image would take {:.1} GB, more than the {:.1} GB of memory available",
            a.width,
            a.height,
            image_bytes / 1e9,
            budget.usable() / 1e9
        )));
    }
    if let Some(t) = a.tessellation.filter(|t| !(1..=64).contains(t)) {
        return Err(bad_input(format!("--tessellation {t}: must lie in 1..=64")));
    }
    Ok(LookSpec {
        camera,
        render: RenderOptions {
            width: a.width,
            height: a.height,
            samples_per_pixel: rays as u32,
            ..RenderOptions::default()
        },
        tone: ToneMap {
            operator: match a.tonemap {
                TonemapArg::Aces => ToneOperator::Aces,
                TonemapArg::Reinhard => ToneOperator::Reinhard,
                TonemapArg::Linear => ToneOperator::Linear,
            },
            ..parse_exposure(&a.exposure)?
        },
        tessellation: a.tessellation,
        metres_per_unit: a.units.as_deref().map(units).transpose()?,
        lightmap: lightmap_size(a)?,
        lightmap_unwrap: a.lightmap_unwrap,
        input_vertices: match a.vertices {
            VerticesArg::Elements => None,
            VerticesArg::Input => Some(radcol_core::render::Corners::Split),
            VerticesArg::InputShared => Some(radcol_core::render::Corners::Shared),
        },
    })
}

/// `auto`, `auto+S`, `auto-S` or a number of stops S.
pub fn parse_exposure(text: &str) -> Result<ToneMap, BadInput> {
    let t = text.trim();
    let lower = t.to_ascii_lowercase();
    let (auto, stops) = match lower.strip_prefix("auto") {
        Some("") => (true, "0"),
        Some(rest) => (true, rest.strip_prefix('+').unwrap_or(rest)),
        None => (false, t),
    };
    let exposure: f64 = stops
        .trim()
        .parse()
        .ok()
        .filter(|v: &f64| v.is_finite())
        .ok_or_else(|| {
            bad_input(format!(
                "--exposure '{t}': expected auto, auto+S, auto-S or a number of stops S"
            ))
        })?;
    Ok(ToneMap {
        exposure,
        auto,
        ..ToneMap::default()
    })
}

/// A `--plot` path: only SVG.
pub(super) fn svg_file(path: &Path, force: bool) -> Result<OutputFile, BadInput> {
    only("--plot", "svg", path, force, "only .svg plots for now")
}
