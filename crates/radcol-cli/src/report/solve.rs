//! `radcol solve`: mesh, problem, visibility, backend, assembly, timings and
//! per-channel results.

use super::channel::{fmt_estimate, fmt_limited, RelativeFigures};
use super::operator::{self, OperatorReport};
use super::{alpha_text, precise, sci, secs, AdaptReport, ProblemText};
use crate::setup::Setup;
use radcol_core::prelude::BackendInfo;
use radcol_core::run::{
    ErrorEstimate, ErrorNorms, Limited, SolveOutcome, SolverKind, SolverReport, Timings,
    VisibilityAnalysis, VisibilityMode,
};
use serde::Serialize;
use std::fmt;

/// A file `radcol solve` wrote.
#[derive(Clone, Debug, Serialize)]
pub struct Written {
    /// Where.
    pub path: String,
    /// What it holds, one phrase ("38 node rows", "640×480 image").
    pub what: String,
    /// Which value of the solution it carries ([`crate::output::value_of`]).
    pub value: String,
    /// Seconds spent making and writing it.
    pub seconds: f64,
}

/// Smallest and largest of a quantity.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Range {
    /// Smallest.
    pub min: f64,
    /// Largest.
    pub max: f64,
}

/// Solver settings as used.
#[derive(Clone, Debug, Serialize)]
pub struct Settings {
    gmres_rel_tol: f64,
    gmres_restart: usize,
    gmres_max_iters: usize,
    quad_tol: f64,
    visibility: VisibilityMode,
}

/// Work of the assembly.
#[derive(Clone, Debug, Serialize)]
pub struct AssemblyWork {
    kernel_evals: u64,
    kernel_evals_per_s: Option<f64>,
    pairs_far: u64,
    pairs_near: u64,
    pairs_self: u64,
    pairs_culled: u64,
    pairs_partial: u64,
    /// Of the partly visible pairs, those whose visibility is approximated.
    pairs_approximate: u64,
    /// The largest bounded share of a row point's view approximated.
    visibility_bound: f64,
    far_kernel_evals: u64,
    device_s: Option<f64>,
}

/// One material of a scene.
#[derive(Clone, Debug, Serialize)]
pub struct MaterialShort {
    name: String,
    rho: [f64; 3],
    emission: [f64; 3],
}

/// One channel's result.
#[derive(Clone, Debug, Serialize)]
pub struct ChannelReport {
    name: String,
    solver: SolverReport,
    integral_u: f64,
    integral_e: f64,
    errors: Option<ErrorNorms>,
    estimate: Option<ErrorEstimate>,
    /// [`ErrorEstimate::shown_max_rel`]: the limiter's change included.
    estimate_shown: Option<f64>,
    /// The estimate's figures as the report leads with them: relative to
    /// the reflected light, or to max |u| where nothing is reflected.
    estimate_relative: Option<RelativeFigures>,
    /// Estimated over true global max error, when both are known.
    effectivity: Option<f64>,
    /// What the positivity limiter changed for display, when u_n < 0
    /// somewhere although E, ρ ≥ 0.
    limited: Option<Limited>,
}

/// What a scene with materials holds, for the text report.
#[derive(Clone, Debug)]
struct SceneSummary {
    triangles: usize,
    materials: usize,
    emitters: Vec<String>,
    imprinted: radcol_core::scene::Imprinted,
}

/// Everything `radcol solve` reports.
#[derive(Clone, Debug, Serialize)]
pub struct SolveReport {
    command: &'static str,
    scene: String,
    degree: usize,
    alpha: f64,
    alpha_auto: bool,
    level: u32,
    max_edge: Option<f64>,
    /// --grade: exponent, zone and the lines graded towards.
    grading: Option<GradeReport>,
    elements: usize,
    /// With a degree per element (`--hp`): how many elements have each
    /// degree (index: the degree).
    #[serde(skip_serializing_if = "Option::is_none")]
    degrees: Option<Vec<usize>>,
    unknowns: usize,
    h: f64,
    shape_ratio: Range,
    problem: ProblemText,
    settings: Settings,
    backend: BackendInfo,
    solver: Option<SolverReport>,
    timings: Timings,
    /// Predicted and measured memory (the peak measured when the report is
    /// made, outputs written).
    memory: radcol_core::run::MemoryUse,
    operator: OperatorReport,
    assembly: AssemblyWork,
    visibility: VisibilityAnalysis,
    materials: Option<Vec<MaterialShort>>,
    channels: Vec<ChannelReport>,
    out: Vec<Written>,
    /// The adaptive loop's steps, with --target-error.
    pub adaptive: Option<AdaptReport>,
    /// The --relight sets, solved on the same matrix.
    pub relit: Vec<crate::run::RelitSet>,
    /// The values at the `--at` points.
    pub points: Option<super::PointsReport>,
    /// What makes this answer doubtful, and what to change.
    warnings: Vec<String>,
    #[serde(skip)]
    contents: Option<SceneSummary>,
}

impl AssemblyWork {
    /// The assembly's work in `out`, which took `seconds`.
    fn new(out: &SolveOutcome, seconds: f64) -> Self {
        let p = &out.plan;
        AssemblyWork {
            kernel_evals: out.kernel_evals,
            kernel_evals_per_s: (seconds > 0.0).then(|| out.kernel_evals as f64 / seconds),
            pairs_far: p.pairs_far,
            pairs_near: p.pairs_near,
            pairs_self: p.pairs_self,
            pairs_culled: p.pairs_culled,
            pairs_partial: p.pairs_partial,
            pairs_approximate: p.pairs_approximate,
            visibility_bound: p.visibility_bound,
            far_kernel_evals: p.far_kernel_evals,
            device_s: out.device_seconds,
        }
    }
}

impl SolveReport {
    /// The report of `out`, solved for `s`, with the files `written`.
    pub fn new(s: &Setup, out: &SolveOutcome, written: &[Written]) -> Self {
        let disc = &out.discretization;
        let (sr_lo, sr_hi) = disc.mesh().shape_ratio_range();
        let t = &out.timings;
        let scene = s.loaded.scene();
        let grading = s
            .cfg
            .grade
            .as_ref()
            .map(|g| GradeReport::new(g, &s.problem.surface));
        Self {
            command: "solve",
            scene: s.scene.clone(),
            degree: s.cfg.degree,
            alpha: s.alpha.value,
            alpha_auto: s.alpha.auto,
            level: s.cfg.level,
            max_edge: s.cfg.max_edge,
            warnings: warnings(s, out, grading.as_ref()),
            grading,
            elements: disc.mesh().len(),
            degrees: degrees_by_element(disc),
            unknowns: disc.len(),
            h: out.h,
            shape_ratio: Range {
                min: sr_lo,
                max: sr_hi,
            },
            problem: ProblemText::of(s),
            settings: Settings {
                gmres_rel_tol: s.cfg.gmres.rel_tol,
                gmres_restart: s.cfg.gmres.restart,
                gmres_max_iters: s.cfg.gmres.max_iters,
                quad_tol: s.cfg.quad.tol,
                visibility: s.cfg.quad.visibility,
            },
            backend: out.backend.clone(),
            solver: out.channels.first().map(|c| c.solver.clone()),
            timings: *t,
            assembly: AssemblyWork::new(out, t.assembly_s),
            visibility: out.visibility.clone(),
            materials: scene.map(|sc| {
                sc.materials
                    .iter()
                    .map(|m| MaterialShort {
                        name: m.name.clone(),
                        rho: m.rho,
                        emission: m.emission,
                    })
                    .collect()
            }),
            channels: out
                .channels
                .iter()
                .map(|c| ChannelReport {
                    name: c.name.clone(),
                    solver: c.solver.clone(),
                    integral_u: c.integral_u,
                    integral_e: c.integral_e,
                    errors: c.errors,
                    estimate: c.estimate.clone(),
                    estimate_shown: c.estimate.as_ref().map(ErrorEstimate::shown_max_rel),
                    estimate_relative: c.estimate.as_ref().map(RelativeFigures::new),
                    effectivity: match (&c.errors, &c.estimate) {
                        (Some(e), Some(est)) if e.global_max > 0.0 => Some(est.max / e.global_max),
                        _ => None,
                    },
                    limited: c.limited.as_ref().map(|(_, l)| l.clone()),
                })
                .collect(),
            memory: out.memory.measured(),
            operator: OperatorReport::new(out),
            out: written.to_vec(),
            adaptive: None,
            relit: Vec::new(),
            points: None,
            contents: scene.map(|sc| SceneSummary {
                triangles: sc.triangle_count(),
                materials: sc.materials.len(),
                emitters: sc
                    .materials
                    .iter()
                    .filter(|m| m.is_emitter())
                    .map(|m| m.name.clone())
                    .collect(),
                imprinted: sc.imprinted,
            }),
        }
    }

    fn fmt_assembly(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let a = &self.assembly;
        let rate = match a.kernel_evals_per_s {
            Some(r) => format!("{}/s", sci(r)),
            None => "-".into(),
        };
        let partial = if self.visibility.needed {
            let how = match self.settings.visibility {
                VisibilityMode::Clip => "clipped".to_string(),
                VisibilityMode::Rays => "rays per quadrature point".to_string(),
            };
            let how = match a.pairs_approximate {
                0 => how,
                n => format!(
                    "{how}; {n} of them approximated by rays, a row's bounded share of the view at most {}",
                    sci(a.visibility_bound)
                ),
            };
            format!(", {} partly visible ({how})", a.pairs_partial)
        } else {
            String::new()
        };
        writeln!(
            f,
            "  assembly    pairs: {} far, {} near, {} self, {} culled{partial}; {} kernel evaluations ({rate}){}",
            a.pairs_far,
            a.pairs_near,
            a.pairs_self,
            a.pairs_culled,
            a.kernel_evals,
            a.device_s
                .map(|d| format!(", device {}", secs(d)))
                .unwrap_or_default()
        )
    }

    fn fmt_channels(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for ch in &self.channels {
            writeln!(
                f,
                "  channel {:<4}{}: {} iteration{}, relative residual {}{}",
                ch.name,
                match ch.solver.kind {
                    SolverKind::Gmres => "gmres",
                    SolverKind::Lu => "lu",
                },
                ch.solver.iterations,
                if ch.solver.iterations == 1 { "" } else { "s" },
                sci(ch.solver.residual),
                match ch.solver.growth {
                    Some(g) if ch.solver.at_rounding_floor => format!(
                        " (the rounding floor: ‖A‖‖u‖/‖E‖ = {}, condition at least that)",
                        sci(g)
                    ),
                    Some(g) => format!(", ‖A‖‖u‖/‖E‖ = {}", sci(g)),
                    None => ch
                        .solver
                        .condition
                        .map_or(String::new(), |k| format!(", condition κ₁ ≈ {}", sci(k))),
                }
            )?;
            writeln!(
                f,
                "              ∫u = {}, ∫E = {}",
                precise(ch.integral_u),
                precise(ch.integral_e)
            )?;
            match &ch.errors {
                Some(e) => writeln!(
                    f,
                    "              errors: nodes max {}, global max {}, L2 {}",
                    sci(e.nodes_max),
                    sci(e.global_max),
                    sci(e.l2)
                )?,
                None => writeln!(
                    f,
                    "              errors: - (give --exact EXPR to measure them)"
                )?,
            }
            if let Some(e) = &ch.estimate {
                fmt_estimate(f, e, ch.effectivity)?;
            }
            if let Some(l) = &ch.limited {
                fmt_limited(f, l, ch.estimate.as_ref(), ch.estimate_shown)?;
            }
        }
        Ok(())
    }
}

/// The trust warnings of `out`, and --grade's when it found nothing to grade
/// towards.
fn warnings(s: &Setup, out: &SolveOutcome, grading: Option<&GradeReport>) -> Vec<String> {
    let mut w = super::trust::solve_warnings(s, out);
    w.extend(grading.and_then(GradeReport::warning));
    w
}

/// How the mesh was graded (--grade).
#[derive(Clone, Debug, Serialize)]
pub struct GradeReport {
    exponent: f64,
    /// The zone's width D (scene units), the default resolved.
    zone: f64,
    /// Segments graded towards (a line found from both of its faces counts twice).
    lines: usize,
}

impl GradeReport {
    fn new(g: &radcol_core::run::Grade, surface: &radcol_core::run::Surface) -> Self {
        let grading = radcol_core::run::Grading::towards_concave_lines(surface, g);
        Self {
            exponent: grading.exponent,
            zone: grading.zone,
            lines: grading.lines.len(),
        }
    }

    fn warning(&self) -> Option<String> {
        (self.lines == 0).then(|| {
            "--grade: the scene has no concave edge or contact line between flat faces, so the mesh is not graded".into()
        })
    }
}

/// With a degree per element (`--hp`), how many elements have each degree.
fn degrees_by_element(disc: &radcol_core::run::Discretization) -> Option<Vec<usize>> {
    disc.uniform_nodes()
        .is_none()
        .then(|| disc.elements_per_degree())
}

impl fmt::Display for SolveReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "radcol solve: {}, r = {}, {}, level {}{}",
            self.scene,
            self.degree,
            alpha_text(self.alpha, self.alpha_auto, self.degree),
            self.level,
            self.max_edge
                .map(|h| format!(", max edge {h:.6}"))
                .unwrap_or_default()
        )?;
        let by_degree = (self.degrees.as_deref())
            .map_or_else(String::new, |n| format!(" ({})", super::by_degree(n)));
        writeln!(
            f,
            "  mesh        {} elements{by_degree}, {} unknowns, h = {:.6}, shape ratio {:.4} .. {:.4}",
            self.elements, self.unknowns, self.h, self.shape_ratio.min, self.shape_ratio.max
        )?;
        if let Some(g) = &self.grading {
            writeln!(
                f,
                "  grading     q = {} within {:.6} of {} concave edges and contact lines",
                g.exponent, g.zone, g.lines
            )?;
        }
        writeln!(
            f,
            "  problem     ρ = {}, E = {}, exact u = {}",
            self.problem.rho,
            self.problem.emission,
            self.problem.exact.as_deref().unwrap_or("unknown")
        )?;
        if let Some(sc) = &self.contents {
            writeln!(
                f,
                "  scene       {} triangles, {} materials, emitting: {}",
                sc.triangles,
                sc.materials,
                if sc.emitters.is_empty() {
                    "none (the solution is 0)".to_string()
                } else {
                    sc.emitters.join(", ")
                }
            )?;
            if sc.imprinted.triangles > 0 {
                writeln!(
                    f,
                    "              contact lines imprinted: {} segments split {} triangles",
                    sc.imprinted.segments, sc.imprinted.triangles
                )?;
            }
        }
        writeln!(f, "  visibility  {}", self.visibility.reason)?;
        writeln!(f, "  backend     {}", self.backend)?;
        self.fmt_assembly(f)?;
        write!(f, "{}", self.operator)?;
        let t = &self.timings;
        writeln!(
            f,
            "  timings     mesh {}, rhs {}, assembly {}, solve {}, errors {}, estimate {}, total {}",
            secs(t.mesh_s),
            secs(t.rhs_s),
            secs(t.assembly_s),
            secs(t.solve_s),
            secs(t.errors_s),
            secs(t.estimate_s),
            secs(t.total_s)
        )?;
        operator::fmt_memory(f, &self.memory)?;
        if let Some(a) = &self.adaptive {
            write!(f, "{a}")?;
        }
        self.fmt_channels(f)?;
        for set in &self.relit {
            write!(f, "{set}")?;
        }
        if let Some(p) = &self.points {
            write!(f, "{p}")?;
        }
        for w in &self.out {
            writeln!(
                f,
                "  wrote {} to {} ({}; {})",
                w.what,
                w.path,
                w.value,
                secs(w.seconds)
            )?;
        }
        for w in &self.warnings {
            writeln!(f, "  warning: {w}")?;
        }
        Ok(())
    }
}
