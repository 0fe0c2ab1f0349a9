//! The solve pipeline, one stage a step, each stage's result the next one's
//! input:
//!
//! ```text
//! Problem ─ visibility::analyze ─> VisibilityAnalysis (decided once, refused if unsupported)
//!         ─ discretize ──────────> Discretization (sizes checked before anything is built)
//!         ─ fields ──────────────> ρ and E at the nodes, per channel
//!         ─ AssemblyPlan + backend > geometric matrix Gm
//!         ─ channels ────────────> u_n per channel (GMRES or LU)
//!         ─ errors ──────────────> norms against an exact u, when known
//! ```
//!
//! [`solve`] runs them all; [`crate::study::study`] repeats it over levels.

pub mod adapt;
mod config;
mod cost;
mod defaults;
mod inputs;
pub mod operator;
mod outcome;
mod pipeline;
mod relight;
mod size;

pub use crate::solve::true_residual;
pub use config::{SolveConfig, SolverKind, DEFAULT_COMPRESSION_TOL};
pub use cost::{
    check_plan_memory, predict_plan, AssemblyCost, Extrapolated, MatrixCost, COST_SAMPLE_ROWS,
    PREDICT_PLAN_ABOVE,
};
pub use defaults::{
    start_degree, visibility_budget_for, StartMesh, ADAPTIVE_DEGREE, DEFAULT_DEGREE,
    DEFAULT_EDGE_FRACTION, DEFAULT_LEVEL, DEFAULT_VISIBILITY_BUDGET, REFERENCE_LEVEL,
};
pub use inputs::{check_size, discretize, MAX_EXTENT, MIN_EXTENT};
pub use operator::{GeometricOperator, OperatorChoice, OperatorDecision, OperatorKind};
pub use outcome::{ChannelResult, SolveOutcome, SolverReport, Timings};
pub use pipeline::{solve, solve_on_mesh};
pub use relight::Relighter;
pub use size::{
    available_memory, dense_bytes, elements, mesh_size, process_memory, usable, MemoryBudget,
    MemoryEstimate, MemoryUse, MeshSize,
};
