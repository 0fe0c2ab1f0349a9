//! The run step's builders: the scene loaded, α resolved, the problem (with a
//! reference operator when E is manufactured), the solve configuration and
//! the backend, each built when a command needs it.

use crate::backend::select_backend;
use crate::error::bad_input;
use crate::scene::{Loaded, SceneSpec};
use crate::validate::{AlphaSpec, LookSpec, OutputFile, ProblemSpec};
use anyhow::Result;
use radcol_core::prelude::AssemblyBackend;
use radcol_core::render::{Camera, RenderOptions, ToneMap};
use radcol_core::run::{
    Field, Problem, ReferenceOperator, SolveConfig, StartMesh, REFERENCE_LEVEL,
};
use radcol_core::study::{find_alpha0, Alpha0Report};

/// The node parameter and how it was chosen.
#[derive(Clone, Debug)]
pub struct Alpha {
    /// α.
    pub value: f64,
    /// True for `--alpha auto`.
    pub auto: bool,
    /// The α0 search of the degree (done once per run).
    pub a0: Alpha0Report,
}

/// α for degree `r`: the α0 search runs once, here.
pub fn resolve_alpha(spec: AlphaSpec, r: usize) -> Alpha {
    let a0 = find_alpha0(r);
    match spec {
        AlphaSpec::Auto => Alpha {
            value: a0.auto_alpha(),
            auto: true,
            a0,
        },
        AlphaSpec::Value(value) => Alpha {
            value,
            auto: false,
            a0,
        },
    }
}

/// A problem, its discretization settings and a backend: what `solve` and
/// `study` run.
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
    pub backend: Box<dyn AssemblyBackend>,
    /// ρ as given, or where it comes from.
    pub rho: String,
    /// E as given, or how it is obtained.
    pub emission: String,
    /// u as given.
    pub exact: Option<String>,
    /// JSON instead of text.
    pub json: bool,
    /// The factor from the materials' Ke to E (`--ke`).
    pub ke_scale: f64,
}

impl std::fmt::Debug for Setup {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Setup")
            .field("scene", &self.scene)
            .field("cfg", &self.cfg)
            .field("backend", &self.backend.info())
            .finish_non_exhaustive()
    }
}

/// Loads `spec` and prints its repair and input warnings on stderr (the
/// report on stdout stays machine-readable).
pub fn load(spec: &SceneSpec) -> Result<Loaded> {
    let loaded = spec.load()?;
    // Under mpirun every rank loads the scene; rank 0 warns.
    if let Some(scene) = loaded.scene().filter(|_| crate::ranks::lead()) {
        for w in &scene.warnings {
            eprintln!("warning: {}: {w}", scene.name);
        }
    }
    Ok(loaded)
}

/// The level and maximum edge to use: the library's
/// [`StartMesh::resolve`], with the scene's diagonal when it has materials.
pub fn default_refinement(
    loaded: &Loaded,
    level: Option<u32>,
    max_edge: Option<f64>,
    adaptive: bool,
) -> (u32, Option<f64>) {
    let diagonal = loaded.scene().map(|s| s.diagonal());
    let m = StartMesh::resolve(diagonal, level, max_edge, adaptive);
    (m.level, m.max_edge)
}

/// Builds what `solve` and `study` need from `p`: the scene, α, the problem,
/// the configuration at `level` (None: the default refinement, for an
/// `adaptive` solve when true) and the backend.
pub fn setup(
    p: &ProblemSpec,
    level: Option<u32>,
    max_edge: Option<f64>,
    adaptive: bool,
) -> Result<Setup> {
    let loaded = load(&p.scene)?;
    let surface = loaded.surface().clone();
    let (level, max_edge) = default_refinement(&loaded, level, max_edge, adaptive);
    let alpha = resolve_alpha(p.alpha, p.degree);
    let backend = select_backend(p.backend, p.precision).map_err(|e| {
        bad_input(format!(
            "--backend {}: {e} (--backend cpu needs no device)",
            crate::backend::name(p.backend)
        ))
    })?;
    let (rho_text, emission_text) = match (&loaded, &p.emission, &p.exact) {
        (Loaded::Scene(_), _, _) => (
            "Kd of the materials (R, G, B)".to_string(),
            if p.ke_scale == 1.0 {
                "Ke of the materials (R, G, B)".to_string()
            } else {
                "π Ke of the materials (R, G, B; Ke read as radiance)".to_string()
            },
        ),
        (_, Some((e, _)), _) => (p.rho.0.clone(), e.clone()),
        (_, None, Some(_)) => (p.rho.0.clone(), "manufactured: u - K u".to_string()),
        (_, None, None) => (p.rho.0.clone(), "1".to_string()),
    };
    let rho = p.rho.1.clone();
    let problem = match (&p.emission, &p.exact) {
        _ if loaded.scene().is_some() => {
            let mut problem = loaded.scene().expect("checked").problem();
            if p.ke_scale != 1.0 {
                problem.scale_emission(p.ke_scale);
            }
            problem
        }
        (None, Some((_, u))) => Problem::manufactured(
            surface.clone(),
            rho,
            u.clone(),
            ReferenceOperator::new(surface.clone(), REFERENCE_LEVEL),
        ),
        (e, u) => {
            let e = e.as_ref().map(|(_, f)| f.clone());
            let mut problem = Problem::new(surface.clone(), rho, e.unwrap_or(Field::Constant(1.0)));
            problem.exact = u.as_ref().map(|(_, f)| f.clone());
            problem
        }
    };
    if loaded.scene().is_none() && !problem.emits() && !adaptive && crate::ranks::lead() {
        // A scene says so in its own warnings; an adaptive solve refuses.
        eprintln!(
            "warning: {}: the emission is zero: the solution is zero everywhere",
            surface.name
        );
    }
    let cfg = SolveConfig {
        degree: p.degree,
        alpha: alpha.value,
        level,
        solver: p.solver,
        gmres: p.gmres.clone(),
        operator: p.operator.0,
        compression: p.operator.1,
        quad: p.quad.clone(),
        check_memory: true,
        max_edge,
        grade: p.grade,
        estimate: p.estimate,
        limit_negative: p.limit_negative,
        progress: None,
        ranks: None,
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
        exact: p.exact.as_ref().map(|(t, _)| t.clone()),
        json: p.json,
        ke_scale: p.ke_scale,
    })
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
    /// The scene's name (the glTF root node's).
    pub scene: String,
    /// Metres per scene unit (the glTF root node's scale): --units, else
    /// the scene's own, else 1.
    pub metres_per_unit: f64,
    /// Whether the surface is a scene whose objects (OBJ groups, glTF
    /// nodes) become glTF nodes of their own.
    pub objects: bool,
    /// The lightmap's size or texel density, when one is baked.
    pub lightmap: Option<radcol_core::render::lightmap::Resolution>,
    /// The scene's texture coordinates, the lightmap's layout when given
    /// (none with --lightmap-unwrap).
    pub lightmap_uvs: Option<Vec<Vec<[[f64; 2]; 3]>>>,
    /// The lightmap's layout, made once before the solve (a generated one
    /// costs an unwrap of the whole scene).
    pub lightmap_atlas: Option<radcol_core::render::lightmap::Atlas>,
    /// Vertex meshes on the scene's triangles (and how corners are shared).
    pub input_vertices: Option<radcol_core::render::Corners>,
}

/// The look of `spec` for the scene and degree of `s`.
pub fn look(spec: &LookSpec, s: &Setup) -> Look {
    Look {
        camera: spec
            .camera
            .or_else(|| s.loaded.scene().and_then(|sc| sc.camera)),
        render: spec.render,
        tone: spec.tone,
        tessellation: spec.tessellation.unwrap_or(s.cfg.degree.max(1) as u32),
        scene: s.scene.clone(),
        metres_per_unit: spec
            .metres_per_unit
            .or_else(|| s.loaded.scene().and_then(|sc| sc.metres_per_unit))
            .unwrap_or(1.0),
        objects: s.loaded.scene().is_some(),
        lightmap: spec.lightmap,
        lightmap_uvs: (spec.lightmap.is_some() && !spec.lightmap_unwrap)
            .then(|| s.loaded.scene().and_then(|sc| sc.uvs.clone()))
            .flatten(),
        lightmap_atlas: None,
        input_vertices: spec.input_vertices,
    }
}

impl Look {
    /// The lightmap's atlas of `surface` at `resolution`: the scene's
    /// texture coordinates when it has them, else a generated layout.
    pub fn atlas(
        &self,
        surface: &radcol_core::run::Surface,
        resolution: radcol_core::render::lightmap::Resolution,
    ) -> Result<radcol_core::render::lightmap::Atlas, radcol_core::render::RenderError> {
        use radcol_core::render::RenderError;
        radcol_core::render::lightmap::Atlas::layout(
            surface,
            self.lightmap_uvs.as_deref(),
            resolution,
        )
        .map_err(|e| match e {
            // The scene's own layout refused: the flag that generates one.
            RenderError::Lightmap(m) if self.lightmap_uvs.is_some() => {
                RenderError::Lightmap(format!("{m} (flag: --lightmap-unwrap)"))
            }
            e => e,
        })
    }
}

/// Checks, before any work, that `file` may be written: not a directory, an
/// existing parent directory, no existing file unless `--force`, and the
/// system lets us write it (a read-only directory or `/proc` used to be found
/// only after the solve, losing its report). The probe creates and removes
/// the file, or opens an existing one without truncating it.
pub fn check_writable(file: &OutputFile) -> Result<(), crate::error::BadInput> {
    let (flag, path) = (file.flag, &file.path);
    let shown = path.display();
    if path.is_dir() {
        return Err(bad_input(format!("{flag} {shown} is a directory")));
    }
    if let Ok(meta) = std::fs::metadata(path) {
        if !file.force {
            return Err(bad_input(format!(
                "{flag} {shown} already exists; pass --force to overwrite it"
            )));
        }
        // A pipe or a device would block or take the file's place.
        if !meta.is_file() {
            return Err(bad_input(format!(
                "{flag} {shown} is not a regular file; radcol replaces only files"
            )));
        }
    }
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        if !parent.is_dir() {
            return Err(bad_input(format!(
                "{flag} {shown}: directory {} does not exist",
                parent.display()
            )));
        }
    }
    // What the write will do: a file beside it, moved in place at the end.
    let probe = crate::files::create(file).map(drop);
    probe.map_err(|e| bad_input(format!("{flag} {shown} cannot be written: {e:#}")))
}

/// Where `path` leads: its canonical form, or its directory's with its
/// name when it does not exist yet (two spellings of one file compare
/// equal).
pub fn identity(path: &std::path::Path) -> std::path::PathBuf {
    if let Ok(p) = std::fs::canonicalize(path) {
        return p;
    }
    let parent = path.parent().filter(|p| !p.as_os_str().is_empty());
    let dir = std::fs::canonicalize(parent.unwrap_or(std::path::Path::new(".")));
    match (dir, path.file_name()) {
        (Ok(d), Some(name)) => d.join(name),
        _ => path.to_path_buf(),
    }
}

/// Refuses outputs that are one of the run's `inputs` (flag and path) or
/// that name one file twice, under any spelling: `--force` is permission
/// to replace an earlier output, not what the run reads.
pub fn check_distinct(
    outputs: &[&OutputFile],
    inputs: &[(&str, &std::path::Path)],
) -> Result<(), crate::error::BadInput> {
    let mut seen: Vec<(std::path::PathBuf, &OutputFile)> = Vec::new();
    for o in outputs {
        let id = identity(&o.path);
        for (what, input) in inputs {
            if identity(input) == id {
                return Err(bad_input(format!(
                    "{} {} is {what} ({}), which this run reads; write the output elsewhere",
                    o.flag,
                    o.path.display(),
                    input.display()
                )));
            }
        }
        if let Some((_, first)) = seen.iter().find(|(p, _)| *p == id) {
            return Err(bad_input(format!(
                "{} {} and {} {} are one file",
                first.flag,
                first.path.display(),
                o.flag,
                o.path.display()
            )));
        }
        seen.push((id, o));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::args::{BackendArg, PrecisionArg};
    use radcol_core::prelude::Scalar;

    #[test]
    fn auto_alpha_is_alpha0_for_odd_degree() {
        radcol_core::assert_close!(resolve_alpha(AlphaSpec::Auto, 1).value, 1.0 / 6.0, 1e-15);
        assert_eq!(resolve_alpha(AlphaSpec::Value(0.1), 2).value, 0.1);
    }

    /// The solve configuration the command builds from `args` (CPU
    /// backend, which no configuration field depends on).
    fn configured(args: &[&str]) -> (SolveConfig, Option<radcol_core::run::adapt::AdaptOptions>) {
        use clap::Parser;
        let argv = ["radcol", "solve", "--backend", "cpu"].iter().chain(args);
        let cli = crate::args::Cli::try_parse_from(argv).expect("arguments parse");
        let crate::validate::Config::Solve(job) =
            crate::validate::Config::from_cli(cli).expect("arguments are valid")
        else {
            panic!("a solve job");
        };
        let s = setup(&job.problem, job.level, job.max_edge, job.adapt.is_some()).unwrap();
        (s.cfg, job.adapt)
    }

    /// The command given no flag builds the library's default
    /// configuration: `SolveConfig::default()` on a surface, the scene's
    /// `solve_config` on a scene, adaptive or not, and
    /// `AdaptOptions::default()` with the target.
    #[test]
    fn no_flags_build_the_library_defaults() {
        use radcol_core::run::adapt::AdaptOptions;
        let same =
            |a: &SolveConfig, b: &SolveConfig| assert_eq!(format!("{a:?}"), format!("{b:?}"));
        same(&configured(&["sphere"]).0, &SolveConfig::default());
        let cornell = radcol_core::scene::builtin("cornell").unwrap().unwrap();
        same(&configured(&["cornell"]).0, &cornell.solve_config(false));
        let (cfg, adapt) = configured(&["cornell", "--target-error", "1e-2"]);
        same(&cfg, &cornell.solve_config(true));
        let target = AdaptOptions {
            target: 1e-2,
            ..AdaptOptions::default()
        };
        assert_eq!(adapt, Some(target));
        // The library's front door configures the same.
        use radcol_core::prelude::Settings;
        for (args, settings) in [
            (&["cornell"][..], Settings::default()),
            (
                &["cornell", "--target-error", "1e-2"],
                Settings::target(1e-2),
            ),
            (
                &["cornell", "--target-error", "1e-2", "--degree", "3"],
                Settings {
                    degree: Some(3),
                    ..Settings::target(1e-2)
                },
            ),
        ] {
            let (cfg, adapt) = configured(args);
            let (want, want_adapt) = settings.configure(&cornell);
            same(&cfg, &want);
            assert_eq!(adapt, want_adapt, "{args:?}");
        }
    }

    #[test]
    fn cpu_backend_is_f64_only() {
        let cpu = select_backend(BackendArg::Cpu, PrecisionArg::Auto).unwrap();
        assert_eq!(cpu.info().precision, Scalar::F64);
        assert!(select_backend(BackendArg::Cpu, PrecisionArg::F32).is_err());
    }
}
