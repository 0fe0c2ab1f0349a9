//! Layer 2: arguments -> a validated configuration of core types. Everything
//! that can be rejected without solving is rejected here, before any work.

use crate::args::{
    BackendArg, Cli, Command, InfoArgs, NodesArgs, PrecisionArg, ProblemArgs, SolveArgs, SolverArg,
    StudyArgs,
};
use crate::error::{bad_input, BadInput};
use crate::scene::SceneSpec;
use anyhow::{Context, Result};
use radcol_core::alpha0::auto_alpha;
use radcol_core::assembly::{AssemblyBackend, CpuBackend, QuadratureOptions};
use radcol_core::geometry::Surface;
use radcol_core::nodes::MAX_DEGREE;
use radcol_core::problem::{Field, Problem, ReferenceOperator};
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
    /// CSV file for the nodal solution.
    pub out: Option<OutputFile>,
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
    /// The surface.
    pub surface: Arc<Surface>,
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
    let out = a
        .out
        .as_deref()
        .map(|p| {
            output_file(
                p,
                "csv",
                "--out",
                "only .csv output for now",
                a.problem.force,
            )
        })
        .transpose()?;
    let setup = setup(&a.problem, a.level, a.level)?;
    Ok(SolveJob { setup, out })
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
    let setup = setup(&a.problem, *levels.start(), *levels.end())?;
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
    let surface = SceneSpec::parse(&a.scene)?.surface()?;
    let degree = check_degree(a.degree)?;
    Ok(InfoJob {
        scene: surface.name.clone(),
        surface: Arc::new(surface),
        degree,
        level: a.level,
        json: a.json,
    })
}

/// Validates the shared options; `max_level` is the finest level that will be
/// solved (checked against memory before anything is built).
fn setup(p: &ProblemArgs, level: u32, max_level: u32) -> Result<Setup> {
    let surface = Arc::new(SceneSpec::parse(&p.scene)?.surface()?);
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
    let rho = Field::parse(&p.rho).context("--rho")?;
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
    check_size(&surface, degree, max_level, solver)?;

    let emission_text = match (&p.emission, &p.exact) {
        (Some(e), _) => e.clone(),
        (None, Some(_)) => "manufactured: u - K u".to_string(),
        (None, None) => "1".to_string(),
    };
    let problem = match (emission, exact) {
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
            ..QuadratureOptions::default()
        },
        check_memory: true,
        max_edge: None,
    };
    Ok(Setup {
        scene: surface.name.clone(),
        problem,
        cfg,
        alpha,
        backend,
        rho: p.rho.clone(),
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

/// Unknowns N = (base triangles · 4^level) · f_r, as f64 (no overflow).
pub fn unknowns_f64(surface: &Surface, degree: usize, level: u32) -> f64 {
    let f = ((degree + 1) * (degree + 2) / 2) as f64;
    surface.base_triangle_count() as f64 * 4f64.powf(level as f64) * f
}

/// Refuses, before anything is built, a level whose dense matrix cannot fit.
fn check_size(surface: &Surface, degree: usize, level: u32, solver: SolverKind) -> Result<()> {
    let n = unknowns_f64(surface, degree, level);
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
