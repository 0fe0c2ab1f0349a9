//! Layer 2: arguments -> a validated configuration of core types. Everything
//! that can be rejected without solving is rejected here, before any work.

use crate::args::{
    BackendArg, Cli, Command, InfoArgs, NodesArgs, PrecisionArg, ProblemArgs, SolveArgs, SolverArg,
    StudyArgs, TonemapArg, VisibilityArg,
};
use crate::error::{bad_input, BadInput};
use crate::scene::{Loaded, SceneSpec};
use anyhow::{Context, Result};
use radcol_core::alpha0::auto_alpha;
use radcol_core::assembly::{AssemblyBackend, CpuBackend, QuadratureOptions, VisibilityMode};
use radcol_core::camera::Camera;
use radcol_core::geometry::Surface;
use radcol_core::mesh::Mesh;
use radcol_core::nodes::MAX_DEGREE;
use radcol_core::problem::{Field, Problem, ReferenceOperator};
use radcol_core::render::{RenderOptions, ToneMap, ToneOperator};
use radcol_core::run::{check_memory, SolveConfig, SolverKind};
use radcol_core::solve::GmresParams;
use std::fmt;
use std::ops::RangeInclusive;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Refinement level of the reference mesh that manufactures E = u - K u.
const REFERENCE_LEVEL: u32 = 2;

/// Beyond this many unknowns 8 N² bytes overflows 64 bits: the CLI states the
/// size itself instead of asking the core's memory check.
const HUGE_UNKNOWNS: f64 = 1e9;

/// A validated command.
#[derive(Debug)]
pub enum Config {
    /// `radcol solve`.
    Solve(SolveJob),
    /// `radcol study`.
    Study(StudyJob),
    /// `radcol nodes`.
    Nodes(NodesJob),
    /// `radcol info`.
    Info(InfoJob),
}

/// The node parameter and how it was chosen.
#[derive(Clone, Copy, Debug)]
pub struct Alpha {
    /// α.
    pub value: f64,
    /// True for `--alpha auto`.
    pub auto: bool,
}

/// A problem, its discretization settings and a backend: what `solve` and `study` share.
#[derive(Debug)]
pub struct Setup {
    /// Scene name for reports.
    pub scene: String,
    /// The surface, or the scene with its materials and camera.
    pub loaded: Loaded,
    /// The problem (surface, ρ, E, exact u).
    pub problem: Problem,
    /// Degree, α, level, solver and quadrature settings.
    pub cfg: SolveConfig,
    /// α and whether it was `auto`.
    pub alpha: Alpha,
    /// The assembly backend.
    pub backend: Backend,
    /// ρ as given.
    pub rho: String,
    /// E as given, or how it is obtained.
    pub emission: String,
    /// u as given.
    pub exact: Option<String>,
    /// JSON instead of text.
    pub json: bool,
}

/// `radcol solve`.
#[derive(Debug)]
pub struct SolveJob {
    /// Problem and settings (the level is `setup.cfg.level`).
    pub setup: Setup,
    /// Files to write, in the order given.
    pub outputs: Vec<Output>,
    /// How images and vertex meshes are made.
    pub look: Look,
}

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

/// Camera, image and tone-mapping settings for the outputs people look at.
#[derive(Clone, Debug)]
pub struct Look {
    /// The camera of the images: --camera, else the scene's, else chosen from
    /// the solved mesh ([`radcol_core::render::auto_camera`]).
    pub camera: Option<Camera>,
    /// Image size and sampling.
    pub render: RenderOptions,
    /// Exposure and tone curve of 8-bit outputs.
    pub tone: ToneMap,
    /// Triangles per element edge of vertex meshes.
    pub tessellation: u32,
}

/// `radcol study`.
#[derive(Debug)]
pub struct StudyJob {
    /// Problem and settings (the level is replaced by each of `levels`).
    pub setup: Setup,
    /// Levels A..=B.
    pub levels: RangeInclusive<u32>,
    /// SVG plot file.
    pub plot: Option<OutputFile>,
}

/// `radcol nodes`.
#[derive(Debug)]
pub struct NodesJob {
    /// Degree r.
    pub degree: usize,
    /// α.
    pub alpha: Alpha,
    /// JSON instead of text.
    pub json: bool,
}

/// `radcol info`.
#[derive(Debug)]
pub struct InfoJob {
    /// Scene name.
    pub scene: String,
    /// The surface, or the scene with its materials.
    pub loaded: Loaded,
    /// The surface.
    pub surface: Arc<Surface>,
    /// Maximum edge length after uniform refinement.
    pub max_edge: Option<f64>,
    /// Degree r (for unknowns and memory).
    pub degree: usize,
    /// Refinement level.
    pub level: u32,
    /// JSON instead of text.
    pub json: bool,
}

/// An output file that may be written: right extension, parent exists, and not
/// in the way of an existing file unless `force`.
#[derive(Clone, Debug)]
pub struct OutputFile {
    /// Where.
    pub path: PathBuf,
    /// Overwrite if it exists.
    pub force: bool,
}

/// The assembly backend chosen on the command line.
pub struct Backend {
    /// What was asked for.
    pub requested: BackendArg,
    /// What will assemble.
    pub imp: Box<dyn AssemblyBackend>,
}

impl fmt::Debug for Backend {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Backend")
            .field("requested", &self.requested)
            .field("info", &self.imp.info())
            .finish()
    }
}

/// The one place that turns `--backend` and `--precision` into an assembly
/// backend. `cpu` never touches wgpu.
pub fn make_backend(
    choice: BackendArg,
    precision: PrecisionArg,
) -> Result<Box<dyn AssemblyBackend>, BadInput> {
    let precision = match precision {
        PrecisionArg::Auto => radcol_gpu::Precision::Auto,
        PrecisionArg::F64 => radcol_gpu::Precision::F64,
        PrecisionArg::F32 => radcol_gpu::Precision::F32,
    };
    match choice {
        BackendArg::Cpu if precision == radcol_gpu::Precision::F32 => Err(bad_input(
            "the CPU backend computes in f64 only; --precision f32 needs --backend gpu",
        )),
        BackendArg::Cpu => Ok(Box::new(CpuBackend)),
        BackendArg::Gpu => radcol_gpu::backend_from_name("gpu", Some(precision))
            .map_err(|e| bad_input(format!("--backend gpu: {e}"))),
        BackendArg::Auto => radcol_gpu::backend_from_name("auto", Some(precision))
            .map_err(|e| bad_input(format!("--backend auto: {e}"))),
    }
}

impl Config {
    /// Validates `cli` into a configuration.
    pub fn from_cli(cli: Cli) -> Result<Self> {
        Ok(match cli.command {
            Command::Solve(a) => Config::Solve(solve_job(a)?),
            Command::Study(a) => Config::Study(study_job(a)?),
            Command::Nodes(a) => Config::Nodes(nodes_job(a)?),
            Command::Info(a) => Config::Info(info_job(a)?),
        })
    }
}

fn solve_job(a: SolveArgs) -> Result<SolveJob> {
    let mut outputs: Vec<Output> = Vec::new();
    for p in &a.out {
        let output = output(p, a.problem.force)?;
        if outputs.iter().any(|o| o.file.path == output.file.path) {
            return Err(bad_input(format!("--out {} is given twice", p.display())).into());
        }
        outputs.push(output);
    }
    let max_edge = a.max_edge.map(check_max_edge).transpose()?;
    let setup = setup(&a.problem, a.level, None, max_edge)?;
    let look = look(&a, &setup)?;
    Ok(SolveJob {
        setup,
        outputs,
        look,
    })
}

fn check_max_edge(h: f64) -> Result<f64, BadInput> {
    if !(h.is_finite() && h > 0.0) {
        return Err(bad_input(format!(
            "--max-edge {h}: the maximum edge length must be a positive finite number (scene units)"
        )));
    }
    Ok(h)
}

/// An `--out` path: its kind from the extension, checked like every output file.
fn output(path: &Path, force: bool) -> Result<Output, BadInput> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    let Some(&(kind, ext)) = OutputKind::ALL.iter().find(|(_, e)| *e == ext) else {
        return Err(bad_input(format!(
            "--out {}: unknown file type; the name must end in .csv, .ply, .glb, .gltf, .png or .exr",
            path.display()
        )));
    };
    let file = output_file(path, ext, "--out", "", force)?;
    Ok(Output { kind, file })
}

/// Camera, image size, exposure and tessellation; checked even when no image
/// is asked for, so that a typo never waits for a solve.
fn look(a: &SolveArgs, s: &Setup) -> Result<Look, BadInput> {
    let camera = match &a.camera {
        Some(text) => Some(Camera::parse(text).map_err(|e| bad_input(format!("--camera: {e}")))?),
        None => s.loaded.scene().and_then(|sc| sc.camera),
    };
    for (flag, v) in [
        ("--width", a.width),
        ("--height", a.height),
        ("--samples", a.samples),
    ] {
        if v == 0 {
            return Err(bad_input(format!("{flag} must be at least 1")));
        }
    }
    let pixels = a.width as u64 * a.height as u64 * (a.samples as u64).pow(2);
    if pixels > 1 << 30 {
        return Err(bad_input(format!(
            "--width {} --height {} --samples {}: {pixels} rays is more than radcol renders (2^30)",
            a.width, a.height, a.samples
        )));
    }
    let tessellation = a.tessellation.unwrap_or(s.cfg.degree.max(1) as u32);
    if !(1..=64).contains(&tessellation) {
        return Err(bad_input(format!(
            "--tessellation {tessellation}: must lie in 1..=64"
        )));
    }
    Ok(Look {
        camera,
        render: RenderOptions {
            width: a.width,
            height: a.height,
            samples: a.samples,
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
        tessellation,
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

fn study_job(a: StudyArgs) -> Result<StudyJob> {
    let levels = parse_levels(&a.levels)?;
    if a.problem.exact.is_none() {
        return Err(bad_input(
            "a study measures errors against the exact solution: give --exact EXPR \
             (E is then manufactured as u - K u unless --emission is given)",
        )
        .into());
    }
    let plot = a
        .plot
        .as_deref()
        .map(|p| {
            output_file(
                p,
                "svg",
                "--plot",
                "only .svg plots for now",
                a.problem.force,
            )
        })
        .transpose()?;
    let setup = setup(&a.problem, Some(*levels.start()), Some(*levels.end()), None)?;
    Ok(StudyJob {
        setup,
        levels,
        plot,
    })
}

fn nodes_job(a: NodesArgs) -> Result<NodesJob> {
    let degree = check_degree(a.degree)?;
    let alpha = parse_alpha(&a.alpha, degree)?;
    Ok(NodesJob {
        degree,
        alpha,
        json: a.json,
    })
}

fn info_job(a: InfoArgs) -> Result<InfoJob> {
    let loaded = SceneSpec::parse(&a.scene)?.load()?;
    warn_scene(&loaded);
    let degree = check_degree(a.degree)?;
    let max_edge = a.max_edge.map(check_max_edge).transpose()?;
    let (level, max_edge) = default_refinement(&loaded, a.level, max_edge);
    Ok(InfoJob {
        scene: loaded.surface().name.clone(),
        surface: loaded.surface().clone(),
        loaded,
        max_edge,
        degree,
        level,
        json: a.json,
    })
}

/// Prints a scene's repair and input warnings on stderr (the report on stdout
/// stays machine-readable).
fn warn_scene(loaded: &Loaded) {
    if let Some(scene) = loaded.scene() {
        for w in &scene.warnings {
            eprintln!("warning: {}: {w}", scene.name);
        }
    }
}

/// Level of `radcol solve` when none is given.
const DEFAULT_LEVEL: u32 = 2;

/// Scenes with materials given neither --level nor --max-edge are refined to
/// edges of at most this fraction of their bounding box's diagonal.
const DEFAULT_EDGE_FRACTION: f64 = 0.1;

/// The level and maximum edge to use: as given, else [`DEFAULT_LEVEL`], or for
/// a scene with materials given neither, level 0 with edges of at most
/// [`DEFAULT_EDGE_FRACTION`] of its bounding box's diagonal.
fn default_refinement(
    loaded: &Loaded,
    level: Option<u32>,
    max_edge: Option<f64>,
) -> (u32, Option<f64>) {
    match (level, max_edge, loaded.scene()) {
        (None, None, Some(scene)) => {
            let (lo, hi) = scene.bounding_box();
            (0, Some(DEFAULT_EDGE_FRACTION * (hi - lo).length()))
        }
        (level, max_edge, _) => (level.unwrap_or(DEFAULT_LEVEL), max_edge),
    }
}

/// Validates the shared options; `level` None means the default refinement
/// ([`DEFAULT_LEVEL`], or for scenes with materials and no `max_edge`, level 0
/// with edges of at most [`DEFAULT_EDGE_FRACTION`] of the diagonal);
/// `max_level` is the finest level that will be solved (checked against memory
/// before anything is built), `level` when None.
fn setup(
    p: &ProblemArgs,
    level: Option<u32>,
    max_level: Option<u32>,
    max_edge: Option<f64>,
) -> Result<Setup> {
    let spec = SceneSpec::parse(&p.scene)?;
    if spec.has_materials() {
        for (flag, given) in [
            ("--rho", p.rho.is_some()),
            ("--emission", p.emission.is_some()),
            ("--exact", p.exact.is_some()),
        ] {
            if given {
                return Err(bad_input(format!(
                    "{flag}: scene '{}' takes ρ and E from its materials (Kd, Ke) and has no known \
                     exact solution; {flag} applies to the analytic surfaces (sphere, ellipsoid, box)",
                    p.scene.trim()
                ))
                .into());
            }
        }
    }
    let loaded = spec.load()?;
    warn_scene(&loaded);
    let surface = loaded.surface().clone();
    let (level, max_edge) = default_refinement(&loaded, level, max_edge);
    let max_level = max_level.unwrap_or(level);
    radcol_core::run::check_visibility_supported(&surface).map_err(|e| bad_input(e.to_string()))?;
    let degree = check_degree(p.degree)?;
    let alpha = parse_alpha(&p.alpha, degree)?;
    let solver = match p.solver {
        SolverArg::Gmres => SolverKind::Gmres,
        SolverArg::Lu => SolverKind::Lu,
    };
    let tol = open_unit("--tol", p.tol)?;
    let quad_tol = open_unit("--quad-tol", p.quad_tol)?;
    if p.restart == 0 {
        return Err(bad_input("--restart must be at least 1").into());
    }
    if p.max_iters == 0 {
        return Err(bad_input("--max-iters must be at least 1").into());
    }
    let rho_text = p.rho.clone().unwrap_or_else(|| "0.5".into());
    let rho = Field::parse(&rho_text).context("--rho")?;
    let emission = p
        .emission
        .as_deref()
        .map(|e| Field::parse(e).context("--emission"))
        .transpose()?;
    let exact = p
        .exact
        .as_deref()
        .map(|e| Field::parse(e).context("--exact"))
        .transpose()?;
    let backend = Backend {
        requested: p.backend,
        imp: make_backend(p.backend, p.precision)?,
    };
    check_size(&surface, degree, max_level, max_edge, solver)?;

    let (rho_text, emission_text) = match (&loaded, &p.emission, &p.exact) {
        (Loaded::Scene(_), _, _) => (
            "Kd of the materials (R, G, B)".to_string(),
            "Ke of the materials (R, G, B)".to_string(),
        ),
        (_, Some(e), _) => (rho_text, e.clone()),
        (_, None, Some(_)) => (rho_text, "manufactured: u - K u".to_string()),
        (_, None, None) => (rho_text, "1".to_string()),
    };
    let problem = match (emission, exact) {
        _ if loaded.scene().is_some() => loaded.scene().expect("checked").problem(),
        (None, Some(u)) => Problem::manufactured(
            surface.clone(),
            rho,
            u,
            ReferenceOperator::new(surface.clone(), REFERENCE_LEVEL),
        ),
        (e, u) => {
            let mut problem = Problem::new(surface.clone(), rho, e.unwrap_or(Field::Constant(1.0)));
            problem.exact = u;
            problem
        }
    };
    let cfg = SolveConfig {
        degree,
        alpha: alpha.value,
        level,
        solver,
        gmres: GmresParams {
            rel_tol: tol,
            restart: p.restart,
            max_iters: p.max_iters,
        },
        quad: QuadratureOptions {
            tol: quad_tol,
            visibility: match p.visibility {
                VisibilityArg::Clip => VisibilityMode::Clip,
                VisibilityArg::Rays => VisibilityMode::Rays,
            },
            ..QuadratureOptions::default()
        },
        check_memory: true,
        max_edge,
        progress: None,
    };
    Ok(Setup {
        scene: surface.name.clone(),
        loaded,
        problem,
        cfg,
        alpha,
        backend,
        rho: rho_text,
        emission: emission_text,
        exact: p.exact.clone(),
        json: p.json,
    })
}

fn check_degree(r: usize) -> Result<usize, BadInput> {
    if r > MAX_DEGREE {
        return Err(bad_input(format!(
            "--degree {r}: radcol supports r = 0..={MAX_DEGREE}"
        )));
    }
    Ok(r)
}

/// `auto` or a number in (0, 1/3).
pub fn parse_alpha(text: &str, degree: usize) -> Result<Alpha, BadInput> {
    let text = text.trim();
    if text.eq_ignore_ascii_case("auto") {
        return Ok(Alpha {
            value: auto_alpha(degree),
            auto: true,
        });
    }
    let value: f64 = text
        .parse()
        .map_err(|_| bad_input(format!("--alpha '{text}' is neither a number nor 'auto'")))?;
    if !(value > 0.0 && value < 1.0 / 3.0) {
        return Err(bad_input(format!(
            "--alpha {text}: α must lie strictly between 0 and 1/3 so that all nodes are interior"
        )));
    }
    Ok(Alpha { value, auto: false })
}

fn open_unit(name: &str, v: f64) -> Result<f64, BadInput> {
    if !(v > 0.0 && v < 1.0) {
        return Err(bad_input(format!(
            "{name} {v}: must lie strictly between 0 and 1"
        )));
    }
    Ok(v)
}

/// `A..B` or `A..=B`, both inclusive, A <= B.
pub fn parse_levels(text: &str) -> Result<RangeInclusive<u32>, BadInput> {
    let t = text.trim();
    let (a, b) = t
        .split_once("..=")
        .or_else(|| t.split_once(".."))
        .ok_or_else(|| {
            bad_input(format!(
                "--levels '{t}': expected A..B (inclusive), e.g. 0..3"
            ))
        })?;
    let level = |s: &str| {
        s.trim().parse::<u32>().map_err(|_| {
            bad_input(format!(
                "--levels '{t}': '{}' is not a level (a whole number >= 0); expected A..B, e.g. 0..3",
                s.trim()
            ))
        })
    };
    let (a, b) = (level(a)?, level(b)?);
    if a > b {
        return Err(bad_input(format!(
            "--levels '{t}': the first level {a} is greater than the last {b}"
        )));
    }
    Ok(a..=b)
}

/// Elements at `level` (then split to `max_edge`, when given).
pub fn elements_f64(surface: &Arc<Surface>, level: u32, max_edge: Option<f64>) -> f64 {
    match max_edge {
        Some(h) => Mesh::count_with_max_edge(surface.clone(), level, h) as f64,
        None => surface.base_triangle_count() as f64 * 4f64.powf(level as f64),
    }
}

/// Unknowns N = elements · f_r, as f64 (no overflow).
pub fn unknowns_f64(
    surface: &Arc<Surface>,
    degree: usize,
    level: u32,
    max_edge: Option<f64>,
) -> f64 {
    let f = ((degree + 1) * (degree + 2) / 2) as f64;
    elements_f64(surface, level, max_edge) * f
}

/// Refuses, before anything is built, a level whose dense matrix cannot fit.
fn check_size(
    surface: &Arc<Surface>,
    degree: usize,
    level: u32,
    max_edge: Option<f64>,
    solver: SolverKind,
) -> Result<()> {
    let n = unknowns_f64(surface, degree, level, max_edge);
    if n >= HUGE_UNKNOWNS {
        let gib = 8.0 * n * n / 1073741824.0;
        return Err(bad_input(format!(
            "level {level} at degree {degree} gives {n:.3e} unknowns: the dense matrix alone would need {gib:.3e} GiB; lower --level or --degree"
        ))
        .into());
    }
    check_memory(n as usize, solver)?;
    Ok(())
}

/// Validates an output path: extension `ext`, existing parent directory, and
/// no existing file unless `force`.
fn output_file(
    path: &Path,
    ext: &str,
    flag: &str,
    wrong_ext: &str,
    force: bool,
) -> Result<OutputFile, BadInput> {
    let shown = path.display();
    let ext_ok = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case(ext));
    if !ext_ok {
        return Err(bad_input(format!(
            "{flag} {shown}: {wrong_ext} (the file name must end in .{ext})"
        )));
    }
    if path.is_dir() {
        return Err(bad_input(format!("{flag} {shown} is a directory")));
    }
    if path.exists() && !force {
        return Err(bad_input(format!(
            "{flag} {shown} already exists; pass --force to overwrite it"
        )));
    }
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        if !parent.is_dir() {
            return Err(bad_input(format!(
                "{flag} {shown}: directory {} does not exist",
                parent.display()
            )));
        }
    }
    Ok(OutputFile {
        path: path.to_path_buf(),
        force,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_accept_both_range_forms() {
        assert_eq!(parse_levels("0..3").unwrap(), 0..=3);
        assert_eq!(parse_levels(" 1..=2 ").unwrap(), 1..=2);
        assert_eq!(parse_levels("2..2").unwrap(), 2..=2);
    }

    #[test]
    fn levels_reject_bad_ranges() {
        assert!(parse_levels("3..1").unwrap_err().0.contains("greater"));
        assert!(parse_levels("a..2")
            .unwrap_err()
            .0
            .contains("'a' is not a level"));
        assert!(parse_levels("2").unwrap_err().0.contains("expected A..B"));
        assert!(parse_levels("-1..2").is_err());
    }

    #[test]
    fn alpha_is_auto_or_inside_the_open_interval() {
        assert!((parse_alpha("auto", 1).unwrap().value - 1.0 / 6.0).abs() < 1e-15);
        assert_eq!(parse_alpha("0.1", 2).unwrap().value, 0.1);
        assert!(parse_alpha("0.4", 1).is_err());
        assert!(parse_alpha("0", 1).is_err());
        assert!(parse_alpha("nan", 1).is_err());
        assert!(parse_alpha("x", 1).is_err());
    }

    #[test]
    fn cpu_backend_is_f64_only() {
        assert_eq!(
            make_backend(BackendArg::Cpu, PrecisionArg::Auto)
                .unwrap()
                .info()
                .precision,
            "f64"
        );
        assert!(make_backend(BackendArg::Cpu, PrecisionArg::F32).is_err());
    }
}
