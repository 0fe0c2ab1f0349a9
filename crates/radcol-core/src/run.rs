//! The solve pipeline: problem + configuration + backend → nodal solutions per
//! channel, with timings, pair statistics and (when u is known) errors.

use crate::assembly::{AssemblyBackend, AssemblyPlan, BackendInfo, PlanStats, QuadratureOptions};
use crate::discretization::Discretization;
use crate::error::{Error, InputError};
use crate::matrix::DenseMatrix;
use crate::mesh::Mesh;
use crate::nodes::NodeSet;
use crate::norms::{error_norms, ErrorNorms};
use crate::problem::{Field, Problem};
use crate::solution::{integrate_nodal, Solution};
use crate::solve::{gmres, DenseLu, GmresParams, LinearOperator, RadiosityOperator};
#[cfg(doc)]
use crate::visibility;
use crate::visibility::VisibilityAnalysis;
use rayon::prelude::*;
use serde::Serialize;
use std::sync::Arc;
use std::time::Instant;

/// Which linear solver.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SolverKind {
    /// Restarted GMRES on the dense operator.
    Gmres,
    /// Dense LU (faer), one factorisation per distinct ρ.
    Lu,
}

/// Observer of a solve's progress, for progress bars. Called from worker
/// threads; must be cheap.
pub trait Progress: Send + Sync {
    /// A stage starts ("assembly": row blocks, "solve": channels); `total`
    /// units of work follow.
    fn start(&self, stage: &str, total: u64);
    /// `n` more units of the current stage are done.
    fn advance(&self, n: u64);
}

/// A shared [`Progress`] observer.
#[derive(Clone)]
pub struct ProgressHandle(pub Arc<dyn Progress>);

impl std::fmt::Debug for ProgressHandle {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("ProgressHandle")
    }
}

impl ProgressHandle {
    /// Starts a stage of `total` units.
    pub fn start(&self, stage: &str, total: u64) {
        self.0.start(stage, total)
    }
    /// Reports `n` more units done.
    pub fn advance(&self, n: u64) {
        self.0.advance(n)
    }
}

/// Everything that sets up one discretization and solve.
#[derive(Clone, Debug)]
pub struct SolveConfig {
    /// Polynomial degree r (0..=6).
    pub degree: usize,
    /// Node parameter α in (0, 1/3).
    pub alpha: f64,
    /// Refinement level of the base triangulation.
    pub level: u32,
    /// Linear solver.
    pub solver: SolverKind,
    /// GMRES settings (tolerance also used to report LU's residual).
    pub gmres: GmresParams,
    /// Quadrature accuracy.
    pub quad: QuadratureOptions,
    /// Refuse problems whose dense matrix would not fit in memory.
    pub check_memory: bool,
    /// After the uniform `level`, refine elements 4:1 until every mapped edge
    /// is at most this long (scene units); None: uniform refinement only.
    pub max_edge: Option<f64>,
    /// Progress observer (assembly row blocks, channels solved), if any.
    pub progress: Option<ProgressHandle>,
}

impl Default for SolveConfig {
    fn default() -> Self {
        Self {
            degree: 1,
            alpha: 1.0 / 6.0,
            level: 2,
            solver: SolverKind::Gmres,
            gmres: GmresParams::default(),
            quad: QuadratureOptions::default(),
            check_memory: true,
            max_edge: None,
            progress: None,
        }
    }
}

/// Wall-clock seconds per stage.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Timings {
    /// Mesh, nodes and discretization.
    pub mesh_s: f64,
    /// Evaluating ρ and E at the nodes (includes manufacturing E).
    pub rhs_s: f64,
    /// Plan and matrix fill.
    pub assembly_s: f64,
    /// Linear solves, all channels.
    pub solve_s: f64,
    /// Error norms against the exact solution.
    pub errors_s: f64,
    /// Everything.
    pub total_s: f64,
}

/// How a channel's linear system was solved.
#[derive(Clone, Debug, Serialize)]
pub struct SolverReport {
    /// "gmres" or "lu".
    pub kind: SolverKind,
    /// GMRES iterations (0 for LU).
    pub iterations: usize,
    /// True relative residual ‖b - A x‖ / ‖b‖.
    pub residual: f64,
}

/// One channel's result.
#[derive(Clone, Debug)]
pub struct ChannelResult {
    /// Channel name.
    pub name: String,
    /// u_n.
    pub solution: Solution,
    /// ρ at the nodes.
    pub rho: Vec<f64>,
    /// E at the nodes.
    pub emission: Vec<f64>,
    /// Solver report.
    pub solver: SolverReport,
    /// ∫_S u_n.
    pub integral_u: f64,
    /// ∫_S of the interpolated emission.
    pub integral_e: f64,
    /// Errors, when the exact solution is known.
    pub errors: Option<ErrorNorms>,
}

/// Everything a solve produced.
#[derive(Debug)]
pub struct SolveOutcome {
    /// The discretization solved on.
    pub discretization: Arc<Discretization>,
    /// The geometric matrix (kept for exports and checks).
    pub matrix: DenseMatrix,
    /// Mesh size h (eq. 11).
    pub h: f64,
    /// Backend that assembled.
    pub backend: BackendInfo,
    /// Pair statistics of the plan.
    pub plan: PlanStats,
    /// Whether visibility was modelled, and why.
    pub visibility: VisibilityAnalysis,
    /// Kernel evaluations of the assembly.
    pub kernel_evals: u64,
    /// Device seconds of the assembly, when measured.
    pub device_seconds: Option<f64>,
    /// Per-channel results.
    pub channels: Vec<ChannelResult>,
    /// Timings.
    pub timings: Timings,
}

/// Bytes of memory available, from /proc/meminfo on Linux.
pub fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    text.lines()
        .find(|l| l.starts_with("MemAvailable:"))
        .and_then(|l| l.split_whitespace().nth(1))
        .and_then(|kb| kb.parse::<u64>().ok())
        .map(|kb| kb * 1024)
}

/// Checks that the dense matrices for `unknowns` fit in memory.
pub fn check_memory(unknowns: usize, solver: SolverKind) -> Result<(), InputError> {
    let n = unknowns as u64;
    let bytes_matrix = n.saturating_mul(n).saturating_mul(8);
    let bytes_lu = if solver == SolverKind::Lu {
        bytes_matrix
    } else {
        0
    };
    if let Some(avail) = available_memory() {
        if bytes_matrix.saturating_add(bytes_lu) > avail / 10 * 9 {
            return Err(InputError::TooLarge {
                unknowns,
                bytes_matrix,
                bytes_lu,
                bytes_available: avail,
            });
        }
    }
    Ok(())
}

/// Evaluates `field` at every collocation point, rejecting non-finite values.
fn eval_at_nodes(disc: &Discretization, field: &Field, what: &str) -> Result<Vec<f64>, InputError> {
    let mesh = disc.mesh();
    let values: Vec<f64> = disc
        .points()
        .par_iter()
        .map(|p| field.eval(&mesh.site(p.element, p.st[0], p.st[1])))
        .collect();
    if let Some((i, &v)) = values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        let p = disc.points()[i];
        return Err(InputError::InvalidValue {
            what: what.into(),
            value: v,
            element: p.element,
            node: p.node,
            position: p.position,
        });
    }
    Ok(values)
}

/// Refuses surfaces whose occlusion radcol cannot model: visibility is
/// computed exactly for flat elements only, so a curved patch in a surface that
/// is not known to bound a convex set is an error, not a silently wrong answer.
/// (Such a surface is exactly one that [`visibility::analyze`] marks as needing
/// visibility because of a curved patch; no geometric test is run here.)
pub fn check_visibility_supported(surface: &crate::geometry::Surface) -> Result<(), InputError> {
    if surface.convex_enclosure {
        return Ok(());
    }
    match surface.patches.iter().find(|p| !p.map.is_affine()) {
        Some(p) => Err(InputError::Other(format!(
            "surface '{}': patch '{}' is curved and the surface is not known to bound a convex set; \
             radcol models occlusion between flat triangles only (set Surface::convex_enclosure \
             when the surface does bound a convex set)",
            surface.name, p.name
        ))),
        None => Ok(()),
    }
}

/// Builds the mesh and collocation points for `cfg` (refusing sizes that do
/// not fit in memory and occluding curved surfaces).
pub fn discretize(problem: &Problem, cfg: &SolveConfig) -> Result<Arc<Discretization>, Error> {
    let nodes = NodeSet::new(cfg.degree, cfg.alpha)?;
    let surface = &problem.surface;
    check_visibility_supported(surface)?;
    let elements = match cfg.max_edge {
        None => {
            (surface.base_triangle_count() as u64).saturating_mul(4u64.saturating_pow(cfg.level))
        }
        Some(h) if h.is_finite() && h > 0.0 => {
            Mesh::count_with_max_edge(surface.clone(), cfg.level, h)
        }
        Some(h) => {
            return Err(InputError::Other(format!(
                "max edge length {h} must be a positive finite number"
            ))
            .into())
        }
    };
    let unknowns = elements.saturating_mul(nodes.len() as u64);
    if cfg.check_memory {
        check_memory(unknowns.min(usize::MAX as u64) as usize, cfg.solver)?;
    }
    let mesh = Arc::new(match cfg.max_edge {
        Some(h) => Mesh::with_max_edge(surface.clone(), cfg.level, h),
        None => Mesh::new(surface.clone(), cfg.level),
    });
    Ok(Arc::new(Discretization::new(mesh, nodes)))
}

/// Solves `problem` with `cfg`, assembling on `backend`.
pub fn solve(
    problem: &Problem,
    cfg: &SolveConfig,
    backend: &dyn AssemblyBackend,
) -> Result<SolveOutcome, Error> {
    let t0 = Instant::now();
    let disc = discretize(problem, cfg)?;
    let h = disc.mesh().h();
    let mesh_s = t0.elapsed().as_secs_f64();

    let t = Instant::now();
    let mut fields = Vec::new();
    let single = problem.channels.len() == 1;
    for ch in &problem.channels {
        // "reflectivity" alone for a scalar problem, "reflectivity R" for a colour channel.
        let label = |what: &str| {
            if single {
                what.to_string()
            } else {
                format!("{what} {}", ch.name)
            }
        };
        let rho = eval_at_nodes(&disc, &ch.rho, &label("reflectivity"))?;
        if let Some((i, &v)) = rho
            .iter()
            .enumerate()
            .find(|(_, v)| !(0.0..1.0).contains(*v))
        {
            let p = disc.points()[i];
            return Err(InputError::Reflectivity {
                name: label("reflectivity"),
                value: v,
                element: p.element,
                node: p.node,
                position: p.position,
            }
            .into());
        }
        let emission = eval_at_nodes(&disc, &ch.emission, &label("emission"))?;
        fields.push((rho, emission));
    }
    let rhs_s = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let plan = AssemblyPlan::with_progress(disc.clone(), cfg.quad.clone(), cfg.progress.clone());
    if let Some(p) = &cfg.progress {
        p.start("assembly", disc.mesh().len() as u64);
    }
    let assembled = backend.assemble(&plan)?;
    let assembly_s = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let mut channels = Vec::new();
    let mut lu_cache: Option<(Vec<f64>, DenseLu)> = None;
    if let Some(p) = &cfg.progress {
        p.start("solve", problem.channels.len() as u64);
    }
    for (ch, (rho, emission)) in problem.channels.iter().zip(fields) {
        let op = RadiosityOperator::new(&assembled.matrix, &rho)?;
        let mut x = emission.clone();
        let iterations = match cfg.solver {
            SolverKind::Gmres => gmres(&op, &emission, &mut x, &cfg.gmres)?.iterations,
            SolverKind::Lu => {
                if lu_cache.as_ref().is_none_or(|(r, _)| *r != rho) {
                    lu_cache = Some((rho.clone(), DenseLu::factor(&op.to_dense())?));
                }
                let (_, lu) = lu_cache.as_ref().expect("just built");
                lu.solve_in_place(&mut x)?;
                0
            }
        };
        let residual = true_residual(&op, &x, &emission);
        let integral_e = integrate_nodal(&disc, &emission);
        let solution = Solution::new(disc.clone(), x);
        channels.push(ChannelResult {
            name: ch.name.clone(),
            integral_u: solution.integral(),
            integral_e,
            solution,
            rho,
            emission,
            solver: SolverReport {
                kind: cfg.solver,
                iterations,
                residual,
            },
            errors: None,
        });
        if let Some(p) = &cfg.progress {
            p.advance(1);
        }
    }
    let solve_s = t.elapsed().as_secs_f64();

    let t = Instant::now();
    if let (Some(exact), Some(first)) = (&problem.exact, channels.first_mut()) {
        first.errors = Some(error_norms(&first.solution, exact));
    }
    let errors_s = t.elapsed().as_secs_f64();

    Ok(SolveOutcome {
        h,
        backend: backend.info(),
        plan: plan.stats(),
        visibility: plan.visibility().clone(),
        kernel_evals: assembled.kernel_evals,
        device_seconds: assembled.device_seconds,
        matrix: assembled.matrix,
        discretization: disc,
        channels,
        timings: Timings {
            mesh_s,
            rhs_s,
            assembly_s,
            solve_s,
            errors_s,
            total_s: t0.elapsed().as_secs_f64(),
        },
    })
}

/// ‖b - A x‖ / ‖b‖ (‖A x‖-free: 0 when b = 0 and x = 0).
pub fn true_residual(op: &dyn LinearOperator, x: &[f64], b: &[f64]) -> f64 {
    let mut ax = vec![0.0; b.len()];
    op.apply(x, &mut ax);
    let num: f64 = ax
        .iter()
        .zip(b)
        .map(|(a, b)| (b - a) * (b - a))
        .sum::<f64>()
        .sqrt();
    let den: f64 = b.iter().map(|v| v * v).sum::<f64>().sqrt();
    if den > 0.0 {
        num / den
    } else {
        num
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::shapes::box_room;

    /// `max_edge` reaches the mesh, bad values are refused, and the memory
    /// check sees the refined count before anything is built.
    #[test]
    fn discretize_honours_max_edge() {
        let problem = Problem::new(
            Arc::new(box_room(1.0, 2.0, 3.0)),
            Field::Constant(0.5),
            Field::Constant(1.0),
        );
        let cfg = |max_edge| SolveConfig {
            degree: 0,
            level: 0,
            max_edge,
            ..Default::default()
        };
        // Closed form (see mesh.rs): 12 triangles, each 16 children for H = 1.
        let d = discretize(&problem, &cfg(Some(1.0))).unwrap();
        assert_eq!(d.mesh().len(), 192);
        assert_eq!(d.len(), 192);
        assert_eq!(discretize(&problem, &cfg(None)).unwrap().len(), 12);
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let msg = discretize(&problem, &cfg(Some(bad)))
                .unwrap_err()
                .to_string();
            assert!(msg.contains("max edge length"), "{msg}");
        }
        if available_memory().is_some() {
            let err = discretize(&problem, &cfg(Some(1e-9))).unwrap_err();
            assert!(
                matches!(err, Error::Input(InputError::TooLarge { .. })),
                "{err}"
            );
        }
    }

    /// A curved surface not known to bound a convex set is refused (radcol
    /// cannot clip curved elements); flat ones that occlude are accepted.
    #[test]
    fn occluding_curved_surfaces_are_refused() {
        let mut open_sphere = crate::geometry::shapes::sphere(1.0);
        open_sphere.convex_enclosure = false;
        let problem = |s| Problem::new(Arc::new(s), Field::Constant(0.5), Field::Constant(1.0));
        let cfg = SolveConfig {
            level: 0,
            ..Default::default()
        };
        let msg = discretize(&problem(open_sphere), &cfg)
            .unwrap_err()
            .to_string();
        assert!(msg.contains("curved") && msg.contains("octant"), "{msg}");
        let flat = crate::assembly::conformance::room_with_cube();
        assert!(crate::visibility::analyze(&flat).needed);
        assert!(discretize(&problem(flat), &cfg).is_ok());
    }
}
