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
mod probes;
mod relight;
mod share;
mod size;

pub use crate::solve::true_residual;

// The types a solve is configured with and reports, gathered here so that
// a program that goes below the front door ([`crate::prelude`]) needs this
// module and not the stages behind it.
pub use crate::alpha0::auto_alpha;
pub use crate::assembly::{
    pair_table_bytes, pair_table_elements, QuadratureOptions, VisibilityMode, MIN_QUAD_TOL,
};
pub use crate::discretization::Discretization;
pub use crate::error::{Error, FieldKind, FieldName, InputError};
pub use crate::estimate::{ErrorEstimate, RelativeTo};
pub use crate::geometry::{shapes, Surface};
pub use crate::hmatrix::radiosity::predict as predict_compressed_from_geometry;
pub use crate::hmatrix::{HOptions, HPrediction, HStats, RowShare, SampledSize};
pub use crate::mesh::grading::{Grade, Grading, GRADE_RANGE};
pub use crate::mesh::{Locator, Mesh, MAX_EDGE_COUNT_CAP};
pub use crate::nodes::{check_alpha, check_degree, nodes_per_element, NodeSet};
pub use crate::norms::ErrorNorms;
pub use crate::problem::{Field, Problem, ReferenceOperator};
pub use crate::progress::{Cancel, Progress, ProgressHandle};
#[cfg(feature = "mpi")]
pub use crate::ranks::{Mpi, MpiSession};
pub use crate::ranks::{Ranks, Threads};
pub use crate::solution::{Limited, Solution};
pub use crate::solve::GmresParams;
pub use crate::visibility::{analyze as analyze_visibility, VisibilityAnalysis};
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
pub use operator::SAMPLED_ROWS;
pub use operator::{GeometricOperator, OperatorChoice, OperatorDecision, OperatorKind};
pub use outcome::{ChannelResult, RankFigures, RanksReport, SolveOutcome, SolverReport, Timings};
pub use pipeline::{solve, solve_on_mesh};
pub use relight::Relighter;
pub use size::{
    available_memory, dense_bytes, elements, mesh_size, process_memory, usable, MemoryBudget,
    MemoryEstimate, MemoryUse, MeshSize,
};
