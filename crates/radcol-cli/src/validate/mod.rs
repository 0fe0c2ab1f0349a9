//! Layer 2: arguments -> validated values. Parsing only: no file is read, no
//! device opened, no number computed beyond parsing. Every value that can be
//! rejected from its text alone is rejected here, with the flag's name.

mod mesh;
mod numbers;
mod outputs;
mod points;

pub use numbers::{parse_alpha, parse_levels};
pub use outputs::{LookSpec, Output, OutputFile, OutputKind};
pub use points::PointsSpec;
use radcol_core::run::{
    adapt::AdaptOptions, adapt::MIN_TARGET, check_degree, Field, GmresParams, Grade, HOptions,
    OperatorChoice, QuadratureOptions, RelativeTo, SolveConfig, SolverKind, VisibilityMode,
    ADAPTIVE_DEGREE, DEFAULT_DEGREE, MIN_QUAD_TOL,
};

use crate::args::{
    BackendArg, Cli, Command, InfoArgs, NodesArgs, OperatorArg, PrecisionArg, ProblemArgs,
    RelativeToArg, SolveArgs, SolverArg, StudyArgs, VisibilityArg,
};
use crate::error::{bad_input, BadInput};
use crate::scene::SceneSpec;
use anyhow::{Context, Result};
use numbers::{degree, open_unit, parse_range};
use outputs::{error_map, look, output, svg_file};
use std::ops::RangeInclusive;

/// A validated command. There is one per run, so its variants' sizes do
/// not matter.
#[derive(Debug)]
#[allow(clippy::large_enum_variant)]
pub enum Config {
    /// `radcol solve`.
    Solve(SolveJob),
    /// `radcol study`.
    Study(StudyJob),
    /// `radcol nodes`.
    Nodes(NodesJob),
    /// `radcol info`.
    Info(InfoJob),
    /// `radcol completions`: the script for this shell.
    Completions(clap_complete::Shell),
}

/// The node parameter as asked for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AlphaSpec {
    /// `--alpha auto`: the best conditioned α that lifts the rule's precision, else the defect minimiser.
    Auto,
    /// A number in (0, 1/3).
    Value(f64),
}

/// The problem and discretization settings `solve` and `study` share.
#[derive(Clone, Debug)]
pub struct ProblemSpec {
    /// The scene as given (not loaded yet).
    pub scene: SceneSpec,
    /// Degree r (0..=6).
    pub degree: usize,
    /// True when `--degree` was not given.
    pub degree_by_default: bool,
    /// α.
    pub alpha: AlphaSpec,
    /// ρ as given (default "0.5") and parsed.
    pub rho: (String, Field),
    /// E as given and parsed.
    pub emission: Option<(String, Field)>,
    /// u as given and parsed.
    pub exact: Option<(String, Field)>,
    /// Linear solver.
    pub solver: SolverKind,
    /// GMRES settings.
    pub gmres: GmresParams,
    /// Dense or compressed operator, and the compression's settings.
    pub operator: (OperatorChoice, HOptions),
    /// Quadrature accuracy and visibility mode.
    pub quad: QuadratureOptions,
    /// Which backend.
    pub backend: BackendArg,
    /// Device precision.
    pub precision: PrecisionArg,
    /// Estimate the error after the solve.
    pub estimate: bool,
    /// Limit negative u_n for display.
    pub limit_negative: bool,
    /// Grading towards concave lines, when asked for.
    pub grade: Option<Grade>,
    /// The factor from the materials' Ke to E (1, or π with `--ke radiance`).
    pub ke_scale: f64,
    /// JSON instead of text.
    pub json: bool,
}

/// `radcol solve`.
#[derive(Debug)]
pub struct SolveJob {
    /// Problem and settings.
    pub problem: ProblemSpec,
    /// Refinement level; None: the default refinement.
    pub level: Option<u32>,
    /// Maximum edge length after the uniform level.
    pub max_edge: Option<f64>,
    /// Files to write, in the order given.
    pub outputs: Vec<Output>,
    /// How images and vertex meshes are made.
    pub look: LookSpec,
    /// Adaptive refinement to a target, when asked for.
    pub adapt: Option<AdaptOptions>,
    /// Fail when the target is not reached.
    pub strict: bool,
    /// `--relight` sets, solved after the first on its matrix.
    pub relight: Vec<String>,
    /// `--at`: points to evaluate u_n and û_n at.
    pub at: Option<PointsSpec>,
}

/// `radcol study`.
#[derive(Debug)]
pub struct StudyJob {
    /// Problem and settings.
    pub problem: ProblemSpec,
    /// Levels A..=B.
    pub levels: RangeInclusive<u32>,
    /// SVG plot file.
    pub plot: Option<OutputFile>,
    /// Degrees to compare (each at its auto α), when asked for.
    pub degrees: Option<RangeInclusive<usize>>,
    /// Adaptive refinement to this target as well, for each degree.
    pub adaptive: Option<f64>,
}

/// `radcol nodes`.
#[derive(Debug)]
pub struct NodesJob {
    /// Degree r.
    pub degree: usize,
    /// α.
    pub alpha: AlphaSpec,
    /// JSON instead of text.
    pub json: bool,
}

/// `radcol info`.
#[derive(Debug)]
pub struct InfoJob {
    /// The scene as given.
    pub scene: SceneSpec,
    /// Maximum edge length after uniform refinement.
    pub max_edge: Option<f64>,
    /// Degree r (for unknowns and memory).
    pub degree: usize,
    /// Refinement level; None: the default refinement.
    pub level: Option<u32>,
    /// Predict the assembly's and the estimate's cost from this many
    /// sampled row blocks.
    pub plan: Option<usize>,
    /// JSON instead of text.
    pub json: bool,
}

impl Config {
    /// Validates `cli` into a configuration.
    pub fn from_cli(cli: Cli) -> Result<Self> {
        Ok(match cli.command {
            Command::Solve(a) => Config::Solve(solve_job(a)?),
            Command::Study(a) => Config::Study(study_job(a)?),
            Command::Nodes(a) => Config::Nodes(nodes_job(a)?),
            Command::Info(a) => Config::Info(info_job(a)?),
            Command::Completions(a) => Config::Completions(a.shell),
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
    let max_edge = a.max_edge.map(mesh::check_max_edge).transpose()?;
    let problem = problem(&a.problem, a.target_error.is_some())?;
    if let Some(p) = &a.error_map {
        if !problem.estimate {
            return Err(bad_input(
                "--error-map shows the error estimate: it cannot be used with --no-estimate",
            )
            .into());
        }
        let map = error_map(p, a.problem.force)?;
        if outputs.iter().any(|o| o.file.path == map.file.path) {
            return Err(
                bad_input(format!("--error-map {} is also an --out file", p.display())).into(),
            );
        }
        outputs.push(map);
    }
    for p in &a.lightmap {
        let map = outputs::lightmap(p, a.problem.force)?;
        if outputs.iter().any(|o| o.file.path == map.file.path) {
            return Err(bad_input(format!("--lightmap {} is given twice", p.display())).into());
        }
        outputs.push(map);
    }
    let look = look(&a)?;
    let mut problem = problem;
    if a.hp {
        problem.backend = hp_backend(problem.backend, problem.precision)?;
    }
    // An explicit --degree is every element's degree; by default small
    // elements start lower.
    let adapt = a
        .target_error
        .map(|t| adapt(t, (a.max_unknowns, a.max_steps, a.hp), &problem))
        .transpose()?
        .map(|o| AdaptOptions {
            graded_start: a.problem.degree.is_none(),
            relative_to: match a.relative_to {
                RelativeToArg::MaxU => RelativeTo::MaxU,
                RelativeToArg::Reflected => RelativeTo::Reflected,
            },
            ..o
        });
    if adapt.is_some() && !a.relight.is_empty() {
        return Err(bad_input(
            "--relight solves again on one assembled matrix: it cannot be used with --target-error, whose mesh follows the first lights",
        )
        .into());
    }
    Ok(SolveJob {
        problem,
        level: a.level,
        max_edge,
        outputs,
        look,
        adapt,
        strict: a.strict,
        relight: a.relight,
        at: a
            .at
            .as_deref()
            .map(|p| points::points(p, a.at_out.as_deref(), a.problem.force))
            .transpose()?,
    })
}

/// The backend of an hp run: the CPU (`--backend auto` picks it: the GPU
/// far field takes one node set per assembly); `--backend gpu` and
/// `--precision f32` are refused.
fn hp_backend(backend: BackendArg, precision: PrecisionArg) -> Result<BackendArg, BadInput> {
    match (backend, precision) {
        (_, PrecisionArg::F32) => Err(bad_input(
            "--hp assembles on the CPU, which computes in f64: leave out --precision f32 or --hp",
        )),
        (BackendArg::Gpu, _) => Err(bad_input(
            "--hp gives each element its own degree, and the GPU backend's far-field shader takes one node set per assembly: use --backend cpu (or auto), or leave out --hp",
        )),
        _ => Ok(BackendArg::Cpu),
    }
}

/// `--target-error` and its budget (`--max-unknowns`, `--max-steps`), and
/// `--hp`.
fn adapt(
    target: f64,
    (max_unknowns, max_steps, hp): (Option<u64>, Option<usize>, bool),
    p: &ProblemSpec,
) -> Result<AdaptOptions, BadInput> {
    if !(MIN_TARGET..1.0).contains(&target) {
        return Err(bad_input(format!(
            "--target-error {target:e}: the target (max error relative to the reflected light, or to max |u|) must lie in [{MIN_TARGET:e}, 1): the error estimate's integrals are accurate to 1e-9"
        )));
    }
    if max_unknowns == Some(0) {
        return Err(bad_input("--max-unknowns must be at least 1"));
    }
    if max_steps == Some(0) {
        return Err(bad_input("--max-steps must be at least 1"));
    }
    if !p.estimate {
        return Err(bad_input(
            "--target-error refines where the error estimate is large: it cannot be used with --no-estimate",
        ));
    }
    let default = AdaptOptions::default();
    Ok(AdaptOptions {
        target,
        max_unknowns,
        max_steps: max_steps.unwrap_or(default.max_steps),
        hp,
        ..default
    })
}

fn study_job(a: StudyArgs) -> Result<StudyJob> {
    let levels = parse_levels(&a.levels)?;
    let problem = problem(&a.problem, false)?;
    if problem.exact.is_none() && !problem.estimate {
        return Err(bad_input(
            "a study without --exact EXPR estimates its errors: it cannot be used with --no-estimate",
        )
        .into());
    }
    let plot = a
        .plot
        .as_deref()
        .map(|p| svg_file(p, a.problem.force))
        .transpose()?;
    let degrees = a
        .degrees
        .as_deref()
        .map(|t| {
            let d = parse_range("--degrees", t, "a degree")?;
            for r in [*d.start(), *d.end()] {
                check_degree(r as usize).map_err(|e| bad_input(format!("--degrees {t}: {e}")))?;
            }
            Ok::<_, BadInput>(*d.start() as usize..=*d.end() as usize)
        })
        .transpose()?;
    if degrees.is_some() && problem.alpha != AlphaSpec::Auto {
        return Err(bad_input(
            "--degrees compares each degree at its own auto α: it cannot be used with --alpha",
        )
        .into());
    }
    if let Some(t) = a.adaptive {
        if !(MIN_TARGET..1.0).contains(&t) {
            return Err(bad_input(format!(
                "--adaptive {t:e}: the target (max error relative to the reflected light, or to max |u|) must lie in [{MIN_TARGET:e}, 1): the error estimate's integrals are accurate to 1e-9"
            ))
            .into());
        }
        if !problem.estimate {
            return Err(bad_input(
                "--adaptive refines where the error estimate is large: it cannot be used with --no-estimate",
            )
            .into());
        }
    }
    Ok(StudyJob {
        problem,
        levels,
        plot,
        degrees,
        adaptive: a.adaptive,
    })
}

fn nodes_job(a: NodesArgs) -> Result<NodesJob> {
    let degree = degree(a.degree)?;
    let alpha = parse_alpha(&a.alpha)?;
    Ok(NodesJob {
        degree,
        alpha,
        json: a.json,
    })
}

fn info_job(a: InfoArgs) -> Result<InfoJob> {
    let scene = SceneSpec::parse(&a.scene)?;
    let degree = degree(a.degree)?;
    let max_edge = a.max_edge.map(mesh::check_max_edge).transpose()?;
    Ok(InfoJob {
        scene,
        max_edge,
        degree,
        level: a.level,
        plan: a
            .plan
            .map(|r| r.map_or(radcol_core::run::COST_SAMPLE_ROWS, |r| r as usize)),
        json: a.json,
    })
}

/// The shared options of `solve` and `study`; `adaptive`: `--target-error`
/// was given, which makes the default degree [`ADAPTIVE_DEGREE`].
fn problem(p: &ProblemArgs, adaptive: bool) -> Result<ProblemSpec> {
    let scene = SceneSpec::parse(&p.scene)?;
    mesh::scene_flags(p, &scene)?;
    let default_degree = match adaptive {
        true => ADAPTIVE_DEGREE,
        false => DEFAULT_DEGREE,
    };
    let degree = degree(p.degree.unwrap_or(default_degree))?;
    let alpha = parse_alpha(&p.alpha)?;
    let tol = open_unit("--tol", p.tol)?;
    let quad_tol = open_unit("--quad-tol", p.quad_tol)?;
    if quad_tol < MIN_QUAD_TOL {
        return Err(bad_input(format!(
            "--quad-tol {quad_tol:e}: below {MIN_QUAD_TOL:e} no f64 quadrature can deliver it (sums carry about 1e-16 of rounding) and the adaptive rules would subdivide every near pair to their depth limit; give a value in [{MIN_QUAD_TOL:e}, 1)"
        ))
        .into());
    }
    if p.restart == 0 {
        return Err(bad_input("--restart must be at least 1").into());
    }
    if p.max_iters == 0 {
        return Err(bad_input("--max-iters must be at least 1").into());
    }
    let field = |flag: &'static str, text: &str| -> Result<(String, Field)> {
        Ok((text.to_string(), Field::parse(text).context(flag)?))
    };
    let (backend, precision) = (p.backend, p.precision);
    if backend == BackendArg::Cpu && precision == PrecisionArg::F32 {
        return Err(bad_input(
            "the CPU backend computes in f64 only; --precision f32 needs --backend gpu",
        )
        .into());
    }
    Ok(ProblemSpec {
        scene,
        degree,
        degree_by_default: p.degree.is_none(),
        alpha,
        rho: field("--rho", p.rho.as_deref().unwrap_or("0.5"))?,
        emission: p
            .emission
            .as_deref()
            .map(|e| field("--emission", e))
            .transpose()?,
        exact: p
            .exact
            .as_deref()
            .map(|e| field("--exact", e))
            .transpose()?,
        solver: match p.solver {
            SolverArg::Gmres => SolverKind::Gmres,
            SolverArg::Lu => SolverKind::Lu,
        },
        operator: (
            match p.operator {
                OperatorArg::Auto => OperatorChoice::Auto,
                OperatorArg::Dense => OperatorChoice::Dense,
                OperatorArg::Compressed => OperatorChoice::Compressed,
            },
            HOptions {
                tol: p.compression_tol,
                ..SolveConfig::default().compression
            },
        ),
        gmres: GmresParams {
            rel_tol: tol,
            restart: p.restart,
            max_iters: p.max_iters,
        },
        quad: QuadratureOptions {
            tol: quad_tol,
            visibility: match p.visibility {
                VisibilityArg::Clip | VisibilityArg::Approximate => VisibilityMode::Clip,
                VisibilityArg::Rays => VisibilityMode::Rays,
            },
            visibility_budget: match p.visibility {
                VisibilityArg::Approximate => radcol_core::run::DEFAULT_VISIBILITY_BUDGET,
                VisibilityArg::Clip | VisibilityArg::Rays => 0.0,
            },
            ..QuadratureOptions::default()
        },
        backend,
        precision,
        estimate: !p.no_estimate,
        limit_negative: !p.keep_negative,
        grade: p
            .grade
            .map(|q| mesh::check_grade(q, p.grade_zone))
            .transpose()?,
        ke_scale: mesh::ke_scale(p.ke),
        json: p.json,
    })
}

#[cfg(test)]
mod tests;
