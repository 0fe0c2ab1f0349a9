//! What one solve is asked to do: degree, α, refinement, solver, quadrature.

use super::operator::OperatorChoice;
use crate::assembly::QuadratureOptions;
use crate::hmatrix::HOptions;
use crate::mesh::grading::Grade;
use crate::progress::ProgressHandle;
use crate::solve::GmresParams;
use serde::Serialize;

/// The compressed operator's default relative tolerance per block: below
/// the discretization errors radcol reaches in practice (1e-3 … 1e-6), so
/// that compression does not show in them.
pub const DEFAULT_COMPRESSION_TOL: f64 = 1e-8;

/// Which linear solver.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SolverKind {
    /// Restarted GMRES on the dense or compressed operator.
    Gmres,
    /// Dense LU (faer), one factorisation per distinct ρ.
    Lu,
}

/// Everything that sets up one discretization and solve. Its `Default`
/// is what `radcol solve` runs on a surface given no flag;
/// [`SolveConfig::recommended`] gives that for scenes and adaptive solves.
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
    /// Refuse problems whose operator (dense, or a compressed one's pair table) would not fit in memory.
    pub check_memory: bool,
    /// After the uniform `level`, refine elements 4:1 until every mapped edge
    /// is at most this long (scene units); None: uniform refinement only.
    pub max_edge: Option<f64>,
    /// Then grade the mesh towards concave edges and contact lines
    /// (`crate::mesh::grading`; exponent 2 suits r = 1); None: no grading.
    pub grade: Option<Grade>,
    /// Estimate the error of every channel after the solve
    /// (`crate::estimate`): about as much work again as the assembly.
    pub estimate: bool,
    /// Where u_n < 0 although E, ρ ≥ 0, also give the nonnegative ũ_n of
    /// [`crate::solution::Solution::limited_nonnegative`] for display
    /// ([`super::ChannelResult::shown`]).
    pub limit_negative: bool,
    /// Dense or compressed geometric operator ([`super::operator::decide`]).
    pub operator: OperatorChoice,
    /// How a compressed operator is built: its relative tolerance per
    /// block, admissibility and leaf size.
    pub compression: HOptions,
    /// Progress observer (assembly row blocks, channels solved), if any.
    pub progress: Option<ProgressHandle>,
    /// The ranks a distributed solve is spread over (`crate::ranks`), when
    /// more than one process runs it: each stores its share of the
    /// compressed operator's rows, and GMRES runs on all of them; the rest
    /// of the solve is the same on every rank. None: this process alone.
    pub ranks: Option<std::sync::Arc<dyn crate::ranks::Ranks>>,
}

impl SolveConfig {
    /// The ranks of a distributed solve, when there are more than one.
    pub fn distributed(&self) -> Option<&std::sync::Arc<dyn crate::ranks::Ranks>> {
        self.ranks.as_ref().filter(|r| r.size() > 1)
    }
}

impl Default for SolveConfig {
    fn default() -> Self {
        Self {
            degree: super::DEFAULT_DEGREE,
            // α0(1) = 1/6 as the search finds it (to 5e-16), so that the
            // command's `--alpha auto` and this agree to the last bit.
            alpha: crate::alpha0::auto_alpha(super::DEFAULT_DEGREE),
            level: super::DEFAULT_LEVEL,
            solver: SolverKind::Gmres,
            gmres: GmresParams::default(),
            quad: QuadratureOptions::default(),
            check_memory: true,
            max_edge: None,
            grade: None,
            estimate: true,
            limit_negative: true,
            operator: OperatorChoice::Auto,
            compression: HOptions {
                tol: DEFAULT_COMPRESSION_TOL,
                ..HOptions::default()
            },
            progress: None,
            ranks: None,
        }
    }
}
