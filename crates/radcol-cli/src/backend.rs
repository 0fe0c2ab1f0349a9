//! The assembly backends this build has: the CPU always, the GPU (wgpu,
//! `radcol-gpu`) with the `gpu` cargo feature, on by default. Without it
//! the command links no wgpu: `--backend auto` assembles on the CPU and
//! `--backend gpu` is refused with one line.

use crate::args::{BackendArg, PrecisionArg};
use clap::ValueEnum;
use radcol_core::prelude::AssemblyBackend;

/// The flag's value as written ("cpu", "gpu", "auto").
pub fn name(b: BackendArg) -> String {
    b.to_possible_value()
        .map_or_else(String::new, |v| v.get_name().to_string())
}

/// The backend `backend` asks for in `precision`, or why this build or
/// machine cannot give it.
#[cfg(feature = "gpu")]
pub fn select_backend(
    backend: BackendArg,
    precision: PrecisionArg,
) -> Result<Box<dyn AssemblyBackend>, String> {
    use radcol_gpu::{BackendChoice, Precision};
    let choice = match backend {
        BackendArg::Cpu => BackendChoice::Cpu,
        BackendArg::Gpu => BackendChoice::Gpu,
        BackendArg::Auto => BackendChoice::Auto,
    };
    let precision = match precision {
        PrecisionArg::Auto => Precision::Auto,
        PrecisionArg::F64 => Precision::F64,
        PrecisionArg::F32 => Precision::F32,
    };
    radcol_gpu::select_backend(choice, precision).map_err(|e| e.to_string())
}

/// The backend `backend` asks for in `precision`: the CPU (f64), or why
/// this build cannot give it.
#[cfg(not(feature = "gpu"))]
pub fn select_backend(
    backend: BackendArg,
    precision: PrecisionArg,
) -> Result<Box<dyn AssemblyBackend>, String> {
    use radcol_core::prelude::{BackendKind, CpuBackend, Scalar};
    if backend == BackendArg::Gpu {
        return Err(
            "this radcol was built without the `gpu` cargo feature (no wgpu); \
                    build it with default features for GPU assembly"
                .into(),
        );
    }
    if precision == PrecisionArg::F32 {
        return Err(radcol_core::run::InputError::Precision {
            backend: BackendKind::Cpu,
            supported: Scalar::F64,
            asked: Scalar::F32,
        }
        .to_string());
    }
    Ok(Box::new(CpuBackend))
}

#[cfg(all(test, not(feature = "gpu")))]
mod tests {
    use super::*;
    use radcol_core::prelude::BackendKind;

    /// Without the gpu feature: auto and cpu assemble on the CPU; gpu and
    /// f32 are refused, saying why.
    #[test]
    fn backend_without_the_gpu_feature() {
        for choice in [BackendArg::Auto, BackendArg::Cpu] {
            let b = select_backend(choice, PrecisionArg::Auto).unwrap();
            assert_eq!(b.info().kind, BackendKind::Cpu);
        }
        let e = select_backend(BackendArg::Gpu, PrecisionArg::Auto)
            .err()
            .unwrap();
        assert!(e.contains("without the `gpu` cargo feature"), "{e}");
        assert!(select_backend(BackendArg::Cpu, PrecisionArg::F32).is_err());
    }
}
