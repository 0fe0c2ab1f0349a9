//! Choosing a backend: `cpu`, `gpu` or `auto`, as an enum end to end.

use crate::backend::GpuBackend;
use crate::context::{AdapterFilter, GpuContext};
use crate::error::GpuError;
use crate::Precision;
use radcol_core::backend::{AssemblyBackend, BackendKind, CpuBackend, Error, InputError, Scalar};
use std::fmt;
use std::str::FromStr;
use std::sync::Arc;

/// Which backend to assemble on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum BackendChoice {
    /// [`CpuBackend`] (f64); never touches wgpu.
    Cpu,
    /// A [`GpuBackend`] on the best adapter, software ones (lavapipe) included.
    Gpu,
    /// A [`GpuBackend`] on a hardware adapter that can compute in the
    /// precision asked for, else the [`CpuBackend`].
    #[default]
    Auto,
}

impl fmt::Display for BackendChoice {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            BackendChoice::Cpu => "cpu",
            BackendChoice::Gpu => "gpu",
            BackendChoice::Auto => "auto",
        })
    }
}

impl FromStr for BackendChoice {
    type Err = GpuError;

    fn from_str(s: &str) -> Result<Self, GpuError> {
        match s.trim().to_ascii_lowercase().as_str() {
            "cpu" => Ok(BackendChoice::Cpu),
            "gpu" => Ok(BackendChoice::Gpu),
            "auto" => Ok(BackendChoice::Auto),
            other => Err(GpuError::BadName(format!(
                "unknown backend '{other}': expected cpu, gpu or auto"
            ))),
        }
    }
}

/// The assembly backend for `choice` in `precision`:
///
/// * [`BackendChoice::Cpu`]: [`CpuBackend`] (f64); never touches wgpu.
///   Asking it for f32 is an error.
/// * [`BackendChoice::Gpu`]: a [`GpuBackend`] on the best adapter, software
///   ones (lavapipe) included; no adapter is an error that says so.
///   [`Precision::Auto`] is f64 when the adapter offers `SHADER_F64`.
/// * [`BackendChoice::Auto`]: a [`GpuBackend`] on a hardware adapter that
///   can compute in the precision asked for; otherwise (no adapter, only a
///   software rasteriser, or no f64 when f64 was asked for) the
///   [`CpuBackend`]. The returned backend's
///   [`info`](AssemblyBackend::info) says which was chosen.
pub fn select_backend(
    choice: BackendChoice,
    precision: Precision,
) -> Result<Box<dyn AssemblyBackend>, Error> {
    match choice {
        BackendChoice::Cpu if precision == Precision::F32 => Err(InputError::Precision {
            backend: BackendKind::Cpu,
            supported: Scalar::F64,
            asked: Scalar::F32,
        }
        .into()),
        BackendChoice::Cpu => Ok(Box::new(CpuBackend)),
        BackendChoice::Gpu => {
            let ctx = GpuContext::new(AdapterFilter::Any)?;
            Ok(Box::new(GpuBackend::new(Arc::new(ctx), precision)?))
        }
        BackendChoice::Auto => {
            let gpu = GpuContext::new(AdapterFilter::Hardware)
                .and_then(|ctx| GpuBackend::new(Arc::new(ctx), precision));
            match gpu {
                Ok(b) => Ok(Box::new(b)),
                Err(_) => Ok(Box::new(CpuBackend)),
            }
        }
    }
}
