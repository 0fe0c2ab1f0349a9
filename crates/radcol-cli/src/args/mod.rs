//! Layer 1: the command line as clap sees it. Plain strings and numbers only;
//! turning them into core types (and rejecting bad values) is `config.rs`'s job.

use clap::{Args, Parser, Subcommand};
use radcol_core::run::{
    GmresParams, QuadratureOptions, ADAPTIVE_DEGREE, DEFAULT_COMPRESSION_TOL, DEFAULT_DEGREE,
};

#[cfg(test)]
mod doc_commands;
#[cfg(test)]
mod docs_shown;
mod solve;
mod values;
pub use solve::SolveArgs;
use std::path::PathBuf;
pub use values::*;

const SCENES: &str = "sphere (unit sphere), sphere:R, ellipsoid:A,B,C, box:LX,LY,LZ \
(the room [0,LX]x[0,LY]x[0,LZ]); the built-in triangle scenes cornell (the Cornell box), \
room (an empty lit room), lroom (an L-shaped room lit in one leg), shadow (a floor under a light and a floating occluder) and plates (two facing squares); FILE.obj with its MTL materials \
(Kd = reflectance ρ, Ke = emission E, per colour channel R, G, B); or FILE.gltf / FILE.glb \
(glTF 2.0: baseColorFactor = ρ, emissiveFactor × KHR_materials_emissive_strength = E, node \
transforms applied, metres kept, the first perspective camera used)";

const EXPRESSIONS: &str =
    "Expressions (--rho, --emission, --exact): numbers (2, 0.5, 1e-3), x, y, z, \
pi, + - * / and ^ (or **), parentheses, and sin cos tan asin acos atan sinh cosh tanh exp \
log (natural; also ln) log10 sqrt abs. Precedence is the one on paper: ^ binds tighter than a \
sign and groups to the right, so -z^2 = -(z^2), 2^3^2 = 2^9 and 2^-1 = 0.5; * and / bind \
tighter than + and -, and both group to the left (8/4/2 = 1). Write 2*x, not 2x.";

/// A library default as the help shows it: `1e-12`, not `0.000000000001`.
fn sci(x: f64) -> String {
    format!("{x:e}")
}

/// Collocation for the radiosity equation u - (ρ/π) ∫ G u = E on curved and
/// polyhedral surfaces (Atkinson-Chien collocation with Micula's α0 nodes).
#[derive(Debug, Parser)]
#[command(name = "radcol", version, propagate_version = true)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,

    /// Worker threads for assembly, solve and rendering [default: RAYON_NUM_THREADS if set,
    /// else one per logical CPU].
    #[arg(long, global = true, value_name = "N", value_parser = clap::value_parser!(u16).range(1..))]
    pub threads: Option<u16>,

    /// No progress bar and no adaptive step lines on stderr (warnings and errors still
    /// print there; the report on stdout is unchanged).
    #[arg(long, short = 'q', global = true)]
    pub quiet: bool,

    /// Log each stage of a solve on stderr as it starts, with the seconds
    /// since the start and the stage before's duration (also where stderr is
    /// no terminal).
    #[arg(long, short = 'v', global = true, conflicts_with = "quiet")]
    pub verbose: bool,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
// One per run: the variants' sizes do not matter.
#[allow(clippy::large_enum_variant)]
pub enum Command {
    /// Solve on one refinement level and report mesh, assembly, timings, solution integrals and errors.
    #[command(after_help = EXPRESSIONS)]
    Solve(SolveArgs),
    /// Solve on levels A..=B against an exact u and report errors with their convergence orders.
    #[command(after_help = EXPRESSIONS)]
    Study(StudyArgs),
    /// Print the collocation nodes and weights of degree r on the unit triangle, and α0.
    Nodes(NodesArgs),
    /// Describe a scene's mesh at a level: elements, h, shape ratios, area, unknowns, memory.
    Info(InfoArgs),
    /// Print a completion script for a shell (for example `radcol completions bash >
    /// ~/.local/share/bash-completion/completions/radcol`).
    Completions(CompletionsArgs),
}

/// `radcol completions`.
#[derive(Debug, clap::Args)]
pub struct CompletionsArgs {
    /// The shell.
    #[arg(value_enum)]
    pub shell: clap_complete::Shell,
}

/// The problem and discretization options shared by `solve` and `study`.
#[derive(Debug, Args)]
pub struct ProblemArgs {
    /// The surface.
    #[arg(value_name = "SCENE", long_help = format!("The surface: {SCENES}."))]
    pub scene: String,

    /// Polynomial degree r of the collocation space.
    #[arg(help_heading = "Method", long, short = 'r', value_name = "R",
          help = format!("Polynomial degree r of the collocation space, 0..=6 [default: \
{DEFAULT_DEGREE}; for `solve --target-error`, {ADAPTIVE_DEGREE}, with the scene's small triangles \
starting lower (docs/accuracy.md); given, every element starts at R]"))]
    pub degree: Option<usize>,

    /// Node parameter α in (0, 1/3), or `auto`: of the α at which the node rule gains a
    /// degree of precision (α0 for odd r), the one with the smallest Lebesgue constant;
    /// else the α minimising the degree-(r+1) defect (see `radcol nodes`).
    #[arg(
        help_heading = "Method",
        long,
        value_name = "A|auto",
        default_value = "auto"
    )]
    pub alpha: String,

    /// Reflectivity ρ: a number or an expression in x, y, z; must lie in [0, 1) at every node.
    /// Scenes with materials take ρ from Kd and refuse this flag [default: 0.5].
    #[arg(
        help_heading = "Problem",
        long,
        value_name = "EXPR",
        allow_hyphen_values = true
    )]
    pub rho: Option<String>,

    /// Emission E: a number or an expression in x, y, z [default: 1 without --exact;
    /// with --exact, E is manufactured as u - K u with an accurate reference quadrature;
    /// scenes with materials take E from Ke and refuse this flag].
    #[arg(
        help_heading = "Problem",
        long,
        value_name = "EXPR",
        allow_hyphen_values = true
    )]
    pub emission: Option<String>,

    /// Exact solution u (an expression in x, y, z), to measure errors [default: none].
    #[arg(
        help_heading = "Problem",
        long,
        value_name = "EXPR",
        allow_hyphen_values = true
    )]
    pub exact: Option<String>,

    /// Grade the mesh towards concave edges (a floor meeting a wall) and contact lines (a
    /// block resting on a floor), found from the geometry: element sizes H (d/D)^(1 - 1/Q) at
    /// distance d from the nearest such line, within --grade-zone D, after
    /// --level/--max-edge (H: their size). Q in [1, 3]; 2 suits degree 1 (Atkinson, Chien
    /// and Seol 2000) [default: no grading].
    #[arg(
        help_heading = "Mesh",
        long,
        value_name = "Q",
        allow_hyphen_values = true
    )]
    pub grade: Option<f64>,

    /// With --grade: the width D of the graded zone on either side of each line (scene
    /// units) [default: a quarter of the scene's largest extent].
    #[arg(
        help_heading = "Mesh",
        long,
        value_name = "D",
        allow_hyphen_values = true,
        requires = "grade"
    )]
    pub grade_zone: Option<f64>,

    /// How a scene's MTL `Ke` is read: as the exitance E of the equation (radiosity units,
    /// radcol's convention), or as radiance (renderers' convention: E = π Ke). The reported u
    /// is radiosity either way; u/π is its radiance.
    #[arg(help_heading = "Problem", long, value_enum, default_value_t = KeArg::Exitance)]
    pub ke: KeArg,

    /// Linear solver.
    #[arg(help_heading = "Linear system", long, value_enum, default_value_t = SolverArg::Gmres)]
    pub solver: SolverArg,

    /// The geometric operator: the dense N×N matrix, or a hierarchical matrix whose
    /// well-separated blocks are low-rank (adaptive cross approximation to
    /// --compression-tol), fully shadowed blocks zero. `auto`: dense when it fits in memory
    /// (or with --solver lu), else compressed.
    #[arg(help_heading = "Linear system", long, value_enum, default_value_t = OperatorArg::Auto)]
    pub operator: OperatorArg,

    /// Relative tolerance of each compressed block (Frobenius), in (0, 1); the solution's
    /// error from compression is of this order.
    #[arg(
        help_heading = "Linear system",
        long,
        value_name = "T",
        default_value = sci(DEFAULT_COMPRESSION_TOL)
    )]
    pub compression_tol: f64,

    /// GMRES relative residual tolerance, in (0, 1).
    #[arg(
        help_heading = "Linear system",
        long,
        value_name = "T",
        default_value = sci(GmresParams::default().rel_tol)
    )]
    pub tol: f64,

    /// GMRES restart length (Krylov dimension), >= 1.
    #[arg(
        help_heading = "Linear system",
        long,
        value_name = "M",
        default_value_t = GmresParams::default().restart
    )]
    pub restart: usize,

    /// GMRES iteration limit, >= 1.
    #[arg(
        help_heading = "Linear system",
        long,
        value_name = "N",
        default_value_t = GmresParams::default().max_iters
    )]
    pub max_iters: usize,

    /// Target relative error of each element integral, in [1e-15, 1) (f64 cannot deliver
    /// less).
    #[arg(
        help_heading = "Assembly",
        long,
        value_name = "Q",
        default_value = sci(QuadratureOptions::default().tol)
    )]
    pub quad_tol: f64,

    /// Assembly backend.
    #[arg(help_heading = "Assembly", long, value_enum, default_value_t = BackendArg::Auto)]
    pub backend: BackendArg,

    /// Partly visible pairs in scenes that occlude: exact clipping, rays per quadrature
    /// point (for comparison), or approximate (bounded, added to the estimate).
    #[arg(help_heading = "Assembly", long, value_enum, default_value_t = VisibilityArg::Clip)]
    pub visibility: VisibilityArg,

    /// GPU arithmetic precision (the CPU backend is always f64).
    #[arg(help_heading = "Assembly", long, value_enum, default_value_t = PrecisionArg::Auto)]
    pub precision: PrecisionArg,

    /// Skip the a posteriori error estimate (the residual E + K u_n - u_n at check points
    /// of every element, about as much work again as the assembly) [default: estimate].
    #[arg(help_heading = "Accuracy", long)]
    pub no_estimate: bool,

    /// Show u_n as computed in images and vertex meshes, negative values included. By
    /// default, where u_n < 0 although E, rho >= 0 (ringing at contact lines and shadow
    /// edges), each such element is scaled towards its mean until it is nonnegative (Zhang
    /// and Shu's limiter: integrals kept, the change reported and added to the estimate).
    #[arg(help_heading = "Accuracy", long)]
    pub keep_negative: bool,

    /// Print one JSON object instead of the text report.
    #[arg(help_heading = "Output", long)]
    pub json: bool,

    /// Overwrite existing output files.
    #[arg(help_heading = "Output", long)]
    pub force: bool,
}

/// `radcol study`.
#[derive(Debug, Args)]
pub struct StudyArgs {
    #[command(flatten)]
    pub problem: ProblemArgs,

    /// Refinement levels A..B (inclusive; A..=B also accepted), e.g. 0..3.
    #[arg(help_heading = "Mesh", long, value_name = "A..B", required = true)]
    pub levels: String,

    /// Draw error vs h and error vs time as an SVG log-log plot (with --degrees
    /// or --adaptive: error vs unknowns and vs wall time, a line per degree and
    /// refinement) [default: none]; refuses to overwrite without --force.
    #[arg(help_heading = "Output", long, value_name = "FILE.svg")]
    pub plot: Option<PathBuf>,

    /// Compare the degrees A..B, each at its auto α: a table per degree, then the fastest
    /// setting (degree, level or adaptive step) for each decade of error [default: --degree
    /// alone].
    #[arg(
        help_heading = "Method",
        long,
        value_name = "A..B",
        conflicts_with = "degree"
    )]
    pub degrees: Option<String>,

    /// For each degree, also refine adaptively to TOL (estimated max error relative to the
    /// reflected light, max |u| where nothing is reflected) from the first level: every step is a row of the comparison.
    #[arg(
        help_heading = "Accuracy",
        long,
        value_name = "TOL",
        allow_hyphen_values = true
    )]
    pub adaptive: Option<f64>,
}

/// `radcol nodes`.
#[derive(Debug, Args)]
pub struct NodesArgs {
    /// Polynomial degree r, 0..=6.
    #[arg(long, short = 'r', value_name = "R", default_value_t = DEFAULT_DEGREE)]
    pub degree: usize,

    /// Node parameter α in (0, 1/3), or `auto` (the best conditioned α that lifts the
    /// rule's precision, α0 for odd r; else the defect minimiser).
    #[arg(long, value_name = "A|auto", default_value = "auto")]
    pub alpha: String,

    /// Print one JSON object instead of the text report.
    #[arg(long)]
    pub json: bool,
}

/// `radcol info`.
#[derive(Debug, Args)]
pub struct InfoArgs {
    /// The surface.
    #[arg(value_name = "SCENE", long_help = format!("The surface: {SCENES}."))]
    pub scene: String,

    /// Polynomial degree r, 0..=6 (for the unknowns and memory estimate).
    #[arg(long, short = 'r', value_name = "R", default_value_t = DEFAULT_DEGREE)]
    pub degree: usize,

    /// Refinement level [default: as for solve].
    #[arg(long, short = 'l', value_name = "L")]
    pub level: Option<u32>,

    /// As for solve: split elements until no edge is longer than H.
    #[arg(long, value_name = "H", allow_hyphen_values = true)]
    pub max_edge: Option<f64>,

    /// Also predict what the assembly and the error estimate will cost:
    /// plan and fill a sample of row blocks (a few seconds), and extrapolate
    /// the pair counts, the occlusion work (candidate occluders and the
    /// memory they hold) and the seconds on this machine's threads, each
    /// with its standard error. ROWS: how many row blocks to measure
    /// [default: sizes from the geometry only; ROWS: radcol_core's
    /// COST_SAMPLE_ROWS, 64]
    #[arg(long, value_name = "ROWS", num_args = 0..=1,
          value_parser = clap::value_parser!(u32).range(1..))]
    pub plan: Option<Option<u32>>,

    /// Print one JSON object instead of the text report.
    #[arg(long)]
    pub json: bool,
}
