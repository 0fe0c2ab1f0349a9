//! `radcol solve`'s own arguments (the problem's are [`super::ProblemArgs`]).

use super::{ProblemArgs, RelativeToArg, TonemapArg, VerticesArg};
use clap::Args;
use radcol_core::prelude::DEFAULT_SNAP;
use radcol_core::render::{lightmap::DEFAULT_LIGHTMAP_SIZE, RenderOptions};
use radcol_core::run::{adapt::AdaptOptions, DEFAULT_EDGE_FRACTION, DEFAULT_LEVEL};
use std::path::PathBuf;

/// `radcol solve`.
#[derive(Debug, Args)]
pub struct SolveArgs {
    #[command(flatten)]
    pub problem: ProblemArgs,

    /// Refinement level.
    #[arg(help_heading = "Mesh", long, short = 'l', value_name = "L", help = format!(
        "Refinement level: each level splits every triangle into 4 (8 elements at level 0 on \
a sphere or ellipsoid, 12 on a box, the file's triangles for a scene) [default: \
{DEFAULT_LEVEL}; 0 with --max-edge; for a scene with materials given neither --level nor \
--max-edge: level 0 and --max-edge {DEFAULT_EDGE_FRACTION} of its bounding box's diagonal, \
or with --target-error its own triangles]"))]
    pub level: Option<u32>,

    /// After the uniform --level (0 when --level is not given), keep splitting elements 4:1
    /// until no edge is longer than H (scene units) [default: uniform refinement only, but
    /// see --level].
    #[arg(
        help_heading = "Mesh",
        long,
        value_name = "H",
        allow_hyphen_values = true
    )]
    pub max_edge: Option<f64>,

    /// Refine adaptively until the estimated max error relative to the reflected light
    /// (--relative-to) is at most TOL,
    /// in (0, 1): the elements with the largest estimates are split 4:1 and the problem
    /// re-solved, from --level/--max-edge (a scene with materials given neither: its own
    /// triangles). Points where the error stops falling under refinement (the foot of a
    /// block on a floor) are named in the report and left out of the target
    /// (docs/accuracy.md) [default: uniform refinement only].
    #[arg(
        help_heading = "Accuracy",
        long,
        value_name = "TOL",
        allow_hyphen_values = true
    )]
    pub target_error: Option<f64>,

    /// With --target-error: what TOL is relative to: the light the surfaces reflect
    /// (max over the nodes of u − E; max |u| where nothing is reflected) or max |u| (in a
    /// lit scene, the light itself) (docs/accuracy.md).
    #[arg(
        help_heading = "Accuracy",
        long,
        value_enum,
        requires = "target_error",
        default_value_t = RelativeToArg::Reflected
    )]
    pub relative_to: RelativeToArg,

    /// With --target-error: never solve with more unknowns than N [default: what the
    /// dense matrix's memory allows].
    #[arg(
        help_heading = "Accuracy",
        long,
        value_name = "N",
        requires = "target_error"
    )]
    pub max_unknowns: Option<u64>,

    /// With --target-error: stop after N solves.
    #[arg(
        help_heading = "Accuracy",
        long,
        value_name = "N",
        requires = "target_error",
        help = format!("With --target-error: stop after N solves [default: {}]",
                       AdaptOptions::default().max_steps)
    )]
    pub max_steps: Option<usize>,

    /// With --target-error: a degree per element (hp). A marked element is raised one
    /// degree where its error fell as for a smooth u when it last changed, and split with
    /// its children one degree lower where it fell as at a shadow or contact line (degrees
    /// 1..=4). Fewer unknowns and less memory; faster with --solver lu, usually slower
    /// with GMRES (docs/accuracy.md, "--hp"). CPU backend.
    #[arg(help_heading = "Accuracy", long, requires = "target_error")]
    pub hp: bool,

    /// With --target-error: fail (exit 1, outputs still written) when the target is not
    /// reached within the budget (a stop where only the neighbourhoods of the singular
    /// points the report names are above it counts as reached).
    #[arg(help_heading = "Accuracy", long, requires = "target_error")]
    pub strict: bool,

    /// Write results; repeat for several files. By extension: .csv (one row per collocation
    /// node: element,node,x,y,z,u…), .ply and .glb/.gltf (per-vertex radiosity on a
    /// tessellation of every element), .png (tone-mapped image) or .exr (linear radiance u/π)
    /// seen by --camera. Refuses to overwrite without --force.
    #[arg(help_heading = "Output", long, short = 'o', value_name = "FILE")]
    pub out: Vec<PathBuf>,

    /// After the solve, solve again on the same matrix (no reassembly) for new lights or
    /// materials, and report each set's ∫u and solve time; repeat for several sets. For a
    /// scene: ';'-separated NAME=R,G,B or NAME.Ke=R,G,B (emission of material NAME) and
    /// NAME.Kd=R,G,B (its reflectance); for a surface: a new emission expression. The
    /// --out files show the first solve.
    #[arg(
        help_heading = "Problem",
        long,
        value_name = "SPEC",
        allow_hyphen_values = true
    )]
    pub relight: Vec<String>,

    /// Evaluate u_n and the iterated solution û_n at the points of FILE.csv.
    #[arg(help_heading = "Output", long, value_name = "FILE.csv", help = format!(
        "Evaluate u_n and the iterated solution û_n = E + K u_n (superconvergent on smooth \
surfaces, shadows clipped exactly) at the points of FILE.csv, with the estimated error of \
each at the point: rows x,y,z or x,y,z,nx,ny,nz (the normal picks the face at an edge), or a \
header row naming columns x, y, z [nx, ny, nz] [label]. Points are taken onto the surface \
from up to {DEFAULT_SNAP:e} of the scene's diagonal away. The values are in the report \
(text and JSON), or in --at-out."))]
    pub at: Option<PathBuf>,

    /// Write the --at values to FILE.csv (a row per point: label, x, y, z, element,
    /// distance, then u, uhat and estimate per channel) instead of listing them in the text
    /// report.
    #[arg(
        help_heading = "Output",
        long,
        value_name = "FILE.csv",
        requires = "at"
    )]
    pub at_out: Option<PathBuf>,

    /// Write a PNG map of the estimated error seen by --camera: each element coloured by its
    /// estimated max error relative to the reflected light (worst channel), log scale from
    /// 1e-5 (dark) to 1 (bright), a colour bar with a tick per decade along the bottom edge.
    #[arg(help_heading = "Output", long, value_name = "FILE.png")]
    pub error_map: Option<PathBuf>,

    /// Camera for .png/.exr as ex,ey,ez,tx,ty,tz,ux,uy,uz,fov: eye, target, up vector and
    /// vertical field of view in degrees [default: the scene's camera, else one looking at
    /// the whole scene along +z].
    #[arg(
        help_heading = "Image",
        long,
        value_name = "EYE,TARGET,UP,FOV",
        allow_hyphen_values = true
    )]
    pub camera: Option<String>,

    /// Image width in pixels.
    #[arg(help_heading = "Image", long, value_name = "PX",
          default_value_t = RenderOptions::default().width)]
    pub width: u32,

    /// Image height in pixels.
    #[arg(help_heading = "Image", long, value_name = "PX",
          default_value_t = RenderOptions::default().height)]
    pub height: u32,

    /// Rays (samples) per pixel.
    #[arg(
        help_heading = "Image",
        long,
        value_name = "N",
        conflicts_with = "samples",
        help = format!("Rays (samples) per pixel: a square count on a regular grid, any \
other on a low-discrepancy set [default: {}]", RenderOptions::default().samples_per_pixel)
    )]
    pub spp: Option<u32>,

    /// Rays per pixel axis, kept with its old meaning: N² rays per pixel on a
    /// regular grid, the same as --spp N²
    #[arg(help_heading = "Image", long, value_name = "N")]
    pub samples: Option<u32>,

    /// Exposure for 8-bit outputs: `auto` (the 99th luminance percentile maps to white; in
    /// images, of the pixels that show no emitter),
    /// `auto+S` / `auto-S` (auto, then S stops brighter/darker), or S stops applied to the
    /// radiance as is.
    #[arg(
        help_heading = "Image",
        long,
        value_name = "auto|S",
        default_value = "auto",
        allow_hyphen_values = true
    )]
    pub exposure: String,

    /// Tone curve for 8-bit outputs.
    #[arg(help_heading = "Image", long, value_enum, default_value_t = TonemapArg::Aces)]
    pub tonemap: TonemapArg,

    /// Bake u_n into a UV lightmap and write it to FILE: .exr (linear radiance u/pi) or
    /// .png (tone-mapped); repeatable. The layout is the scene's own texture coordinates
    /// when every triangle has them in [0, 1] (glTF TEXCOORD_1, else TEXCOORD_0; OBJ vt),
    /// else uvunwrap generates one (each material's triangles grown into charts, flattened
    /// and packed in one square atlas). With a lightmap, .glb/.gltf outputs hold the
    /// scene's own triangles with texture coordinates and the lightmap as their unlit
    /// texture, instead of vertex colours on radcol's mesh.
    #[arg(help_heading = "Output", long, value_name = "FILE.exr|.png")]
    pub lightmap: Vec<PathBuf>,

    /// Generate the lightmap's layout (uvunwrap) even when the scene has texture
    /// coordinates.
    #[arg(help_heading = "Output", long)]
    pub lightmap_unwrap: bool,

    /// Lightmap width and height in texels.
    #[arg(help_heading = "Output", long, value_name = "N", help = format!(
        "Lightmap width and height in texels (16..=16384); given alone, .glb/.gltf outputs \
are lightmapped without a separate file [default: {DEFAULT_LIGHTMAP_SIZE}]"))]
    pub lightmap_size: Option<u32>,

    /// Lightmap texel density in texels per scene unit of length, instead of a size: the
    /// square atlas is as large as the layout needs (a generated layout packs its charts at
    /// exactly this density; the scene's own coordinates get at least it on average); given
    /// alone, .glb/.gltf outputs are lightmapped without a separate file.
    #[arg(
        help_heading = "Output",
        long,
        value_name = "TEXELS_PER_UNIT",
        conflicts_with = "lightmap_size",
        allow_hyphen_values = true
    )]
    pub lightmap_density: Option<f64>,

    /// The scene's unit, for .glb/.gltf (whose unit is the metre): mm, cm, m, km, in, ft or
    /// metres per unit; the root node scales the positions, which stay in the input's units
    /// [default: the scene's own (glTF input: m; the built-in Cornell box: mm), else m].
    #[arg(
        help_heading = "Output",
        long,
        value_name = "UNIT",
        allow_hyphen_values = true
    )]
    pub units: Option<String>,

    /// Vertices of .ply/.glb/.gltf: a tessellation of radcol's elements (every detail of
    /// u_n), or the scene's own triangles with u_n at their corners, each triangle's own
    /// (input) or averaged where corners of one material meet (input-shared).
    #[arg(help_heading = "Output", long, value_enum, default_value_t = VerticesArg::Elements)]
    pub vertices: VerticesArg,

    /// Triangles per element edge in .ply/.glb/.gltf (N² per element), so that degree-r
    /// polynomials show inside elements [default: max(r, 1)].
    #[arg(help_heading = "Image", long, value_name = "N")]
    pub tessellation: Option<u32>,
}
