//! What can assemble: the kinds of backend and the floating-point types they
//! compute in. A floor-level module (the errors name them too); re-exported
//! from [`crate::assembly`].

use serde::Serialize;

/// Which kind of backend assembles.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum BackendKind {
    /// [`crate::assembly::CpuBackend`]: rayon, f64.
    Cpu,
    /// The WGSL backend of `radcol-gpu`.
    Gpu,
}

impl std::fmt::Display for BackendKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            BackendKind::Cpu => "cpu",
            BackendKind::Gpu => "gpu",
        })
    }
}

/// The floating-point type an assembly computes in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Scalar {
    /// Double precision.
    F64,
    /// Single precision (GPUs without `SHADER_F64`, or when asked).
    F32,
}

impl std::fmt::Display for Scalar {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Scalar::F64 => "f64",
            Scalar::F32 => "f32",
        })
    }
}
