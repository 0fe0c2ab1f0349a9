//! Typed errors of the GPU backend. They convert into
//! [`radcol_core::backend::Error::Backend`] at the [`AssemblyBackend`] boundary.
//!
//! [`AssemblyBackend`]: radcol_core::backend::AssemblyBackend

/// Everything that can go wrong on the GPU path.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum GpuError {
    /// No adapter (or none of the kind asked for).
    #[error("no GPU adapter found ({detail}); install a Vulkan driver (for a software one: apt-get install mesa-vulkan-drivers, i.e. lavapipe) or use the CPU backend")]
    NoAdapter {
        /// What was enumerated.
        detail: String,
    },
    /// f64 asked for on an adapter without `SHADER_F64`.
    #[error("adapter '{adapter}' does not offer SHADER_F64; use f32 precision (or auto)")]
    NoF64 {
        /// Adapter name.
        adapter: String,
    },
    /// The adapter refused the device request.
    #[error("requesting a device from '{adapter}': {message}")]
    RequestDevice {
        /// Adapter name.
        adapter: String,
        /// wgpu's message.
        message: String,
    },
    /// A wgpu validation error caught by an error scope.
    #[error("wgpu validation error while {stage}: {message}")]
    Validation {
        /// What the backend was doing.
        stage: &'static str,
        /// wgpu's message.
        message: String,
    },
    /// The device ran out of memory.
    #[error("GPU out of memory while {stage}: {message}")]
    OutOfMemory {
        /// What the backend was doing.
        stage: &'static str,
        /// wgpu's message.
        message: String,
    },
    /// Any other device error (internal, lost device, failed map, failed poll).
    #[error("GPU device error while {stage}: {message}")]
    Device {
        /// What the backend was doing.
        stage: &'static str,
        /// wgpu's message.
        message: String,
    },
    /// The problem cannot be cut into tiles this device can bind.
    #[error("problem too large for the device: {message}")]
    TooLarge {
        /// Which limit.
        message: String,
    },
    /// Something the shader does not support (too many nodes per element).
    #[error("{0}")]
    Unsupported(String),
    /// An unknown backend or precision name.
    #[error("{0}")]
    BadName(String),
}

impl GpuError {
    /// True when the error only says no adapter exists (so `auto` may fall back).
    pub fn is_no_adapter(&self) -> bool {
        matches!(self, GpuError::NoAdapter { .. })
    }

    /// Classifies a wgpu error caught in an error scope.
    pub(crate) fn from_wgpu(stage: &'static str, e: wgpu::Error) -> Self {
        match e {
            wgpu::Error::OutOfMemory { .. } => GpuError::OutOfMemory {
                stage,
                message: e.to_string(),
            },
            wgpu::Error::Validation { .. } => GpuError::Validation {
                stage,
                message: e.to_string(),
            },
            _ => GpuError::Device {
                stage,
                message: e.to_string(),
            },
        }
    }
}

impl From<GpuError> for radcol_core::backend::Error {
    fn from(e: GpuError) -> Self {
        radcol_core::backend::Error::Backend {
            backend: radcol_core::backend::BackendKind::Gpu,
            source: Box::new(e),
        }
    }
}
