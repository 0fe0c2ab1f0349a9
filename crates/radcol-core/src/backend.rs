//! What an assembly backend implements and uses, in one place: the
//! [`AssemblyBackend`] trait that a device backend (radcol-gpu's) implements,
//! the [`AssemblyPlan`] it executes (pairs classified, with their tables of
//! rules and far pairs), the matrix it fills, what it reports, and the
//! errors it returns. [`CpuBackend`] is the reference that every other
//! backend is tested against, and the fallback when a device is missing.

pub use crate::assembly::{
    Assembled, AssemblyBackend, AssemblyPlan, BackendInfo, ClassTable, CpuBackend, FarTable,
    FillMode, PairClass,
};
pub use crate::backend_kind::{BackendKind, Scalar};
pub use crate::error::{Error, InputError};
pub use crate::matrix::DenseMatrix;
pub use crate::quadrature::MAX_RULE_DEGREE;
