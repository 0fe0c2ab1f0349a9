//! The assembly backends this build has: the CPU always, the GPU (wgpu,
//! `radcol-gpu`) with the `gpu` cargo feature, on by default. Without it
//! the command links no wgpu: `--backend auto` assembles on the CPU and
//! `--backend gpu` is refused with one line.

#[cfg(feature = "gpu")]
pub use radcol_gpu::{select_backend, BackendChoice, Precision};

#[cfg(not(feature = "gpu"))]
pub use cpu_only::{select_backend, BackendChoice, Precision};

#[cfg(not(feature = "gpu"))]
mod cpu_only {
    use radcol_core::assembly::{AssemblyBackend, BackendKind, CpuBackend, Scalar};
    use radcol_core::error::InputError;
    use std::fmt;

    /// Which backend to assemble on (as `radcol_gpu::BackendChoice`).
    #[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
    pub enum BackendChoice {
        /// The CPU backend.
        Cpu,
        /// A GPU: not in this build.
        Gpu,
        /// The CPU backend (no GPU in this build).
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

    /// The device precision asked for (as `radcol_gpu::Precision`).
    #[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
    pub enum Precision {
        /// f64 on the CPU.
        #[default]
        Auto,
        /// f64.
        F64,
        /// f32: a GPU precision, refused.
        F32,
    }

    /// The CPU backend, or why the choice cannot be had in this build.
    pub fn select_backend(
        choice: BackendChoice,
        precision: Precision,
    ) -> Result<Box<dyn AssemblyBackend>, String> {
        if choice == BackendChoice::Gpu {
            return Err(
                "this radcol was built without the `gpu` cargo feature (no wgpu); \
                 build it with default features for GPU assembly"
                    .into(),
            );
        }
        if precision == Precision::F32 {
            return Err(InputError::Precision {
                backend: BackendKind::Cpu,
                supported: Scalar::F64,
                asked: Scalar::F32,
            }
            .to_string());
        }
        Ok(Box::new(CpuBackend))
    }
}

#[cfg(all(test, not(feature = "gpu")))]
mod tests {
    use super::*;
    use radcol_core::assembly::BackendKind;

    /// Without the gpu feature: auto and cpu assemble on the CPU; gpu and
    /// f32 are refused, saying why.
    #[test]
    fn backend_without_the_gpu_feature() {
        for choice in [BackendChoice::Auto, BackendChoice::Cpu] {
            let b = select_backend(choice, Precision::Auto).unwrap();
            assert_eq!(b.info().kind, BackendKind::Cpu);
        }
        let e = select_backend(BackendChoice::Gpu, Precision::Auto)
            .err()
            .unwrap();
        assert!(e.contains("without the `gpu` cargo feature"), "{e}");
        assert!(select_backend(BackendChoice::Cpu, Precision::F32).is_err());
    }
}
