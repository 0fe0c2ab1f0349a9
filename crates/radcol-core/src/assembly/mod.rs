//! Assembly of the geometric collocation matrix
//!
//!   Gm[i, (k, j)] = (1/π) ∫_σ G(v_i, m_k(s, t)) l_j(s, t) |D_s m_k × D_t m_k| dσ   (eq. 19)
//!
//! without the reflectivity, so that every colour channel reuses it: the system
//! of channel c is (I - diag(ρ_c) Gm) u = E_c.
//!
//! [`AssemblyPlan`] decides once how every pair is integrated; an
//! [`AssemblyBackend`] executes the plan ([`CpuBackend`] here, the GPU backend in
//! `radcol-gpu`).

#[cfg(any(test, feature = "conformance"))]
pub mod conformance;
pub mod cpu;
pub mod integrate;
pub mod plan;
pub mod point;

pub use cpu::CpuBackend;
pub use integrate::{
    ElementIntegrator, FieldPoint, QuadratureOptions, VisibilityMode, MIN_QUAD_TOL,
};
pub use plan::{pair_table_bytes, pair_table_elements};
pub use plan::{
    AssemblyPlan, ClassTable, FarTable, FillMode, PairClass, PlanStats, Unchanged,
};

pub use crate::backend_kind::{BackendKind, Scalar};

use crate::error::Error;
use crate::matrix::DenseMatrix;
use serde::Serialize;

/// What executed an assembly: for reports and JSON.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct BackendInfo {
    /// CPU or GPU.
    pub kind: BackendKind,
    /// Device description (adapter name and driver, or thread count).
    pub device: String,
    /// The precision the matrix was computed in.
    pub precision: Scalar,
}

impl std::fmt::Display for BackendInfo {
    /// `cpu (2 rayon threads, f64)`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} ({}, {})", self.kind, self.device, self.precision)
    }
}

/// The result of one assembly.
#[derive(Debug)]
pub struct Assembled {
    /// The geometric matrix Gm, N × N.
    pub matrix: DenseMatrix,
    /// Kernel evaluations G(v_i, Q) performed.
    pub kernel_evals: u64,
    /// Device time (GPU timestamp queries), when measured.
    pub device_seconds: Option<f64>,
    /// Wall time of the assembly, seconds.
    pub wall_seconds: f64,
}

/// Executes an [`AssemblyPlan`].
pub trait AssemblyBackend: Send + Sync {
    /// Which backend, device and precision.
    fn info(&self) -> BackendInfo;
    /// Fills the geometric matrix of `plan`.
    fn assemble(&self, plan: &AssemblyPlan) -> Result<Assembled, Error>;

    /// Fills the geometric matrix of `plan`, a plan built by
    /// [`AssemblyPlan::updating`], whose pairs of unchanged elements may be
    /// copied from `previous` (the matrix of the plan it was updated from)
    /// instead of computed: the result is the same matrix. This default
    /// computes every entry; [`CpuBackend`] copies.
    fn assemble_reusing(
        &self,
        plan: &AssemblyPlan,
        previous: &DenseMatrix,
    ) -> Result<Assembled, Error> {
        let _ = previous;
        self.assemble(plan)
    }
}
