//! Backend selection by name, for the CLI: `cpu`, `gpu` or `auto`.

use crate::backend::GpuBackend;
use crate::context::{AdapterFilter, GpuContext};
use crate::Precision;
use radcol_core::assembly::{AssemblyBackend, CpuBackend};
use radcol_core::error::{Error, InputError};
use std::sync::Arc;

/// The assembly backend called `name`:
///
/// * `"cpu"`: [`CpuBackend`] (f64); never touches wgpu. Asking it for f32 is an error.
/// * `"gpu"`: a [`GpuBackend`] on the best adapter, software ones (lavapipe)
///   included; no adapter is an error that says so. `precision` defaults to
///   `Auto` (f64 when the adapter offers `SHADER_F64`).
/// * `"auto"`: a [`GpuBackend`] on a hardware adapter that can compute in the
///   precision asked for; otherwise (no adapter, only a software rasteriser,
///   or no f64 when f64 was asked for) the [`CpuBackend`]. The returned
///   backend's [`info`](AssemblyBackend::info) says which was chosen.
pub fn backend_from_name(
    name: &str,
    precision: Option<Precision>,
) -> Result<Box<dyn AssemblyBackend>, Error> {
    match name.trim().to_ascii_lowercase().as_str() {
        "cpu" => {
            if precision == Some(Precision::F32) {
                return Err(InputError::Other(
                    "the CPU backend computes in f64 only; --precision f32 needs --backend gpu"
                        .into(),
                )
                .into());
            }
            Ok(Box::new(CpuBackend))
        }
        "gpu" => {
            let ctx = GpuContext::new(AdapterFilter::Any)?;
            Ok(Box::new(GpuBackend::new(
                Arc::new(ctx),
                precision.unwrap_or_default(),
            )?))
        }
        "auto" => {
            let gpu = GpuContext::new(AdapterFilter::Hardware)
                .and_then(|ctx| GpuBackend::new(Arc::new(ctx), precision.unwrap_or_default()));
            match gpu {
                Ok(b) => Ok(Box::new(b)),
                Err(_) => Ok(Box::new(CpuBackend)),
            }
        }
        other => Err(InputError::Other(format!(
            "unknown backend '{other}': expected cpu, gpu or auto"
        ))
        .into()),
    }
}
