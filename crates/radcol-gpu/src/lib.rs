//! radcol-gpu: the GPU assembly backend of radcol.
//!
//! It executes the same [`AssemblyPlan`](radcol_core::backend::AssemblyPlan)
//! as the CPU backend: the far pairs (almost all of them) run as a WGSL compute
//! shader (`shaders/far_field.wgsl`) through wgpu, in f64 when the adapter
//! offers `SHADER_F64` (lavapipe does) and in f32 otherwise or when asked; the
//! few near and self pairs run at the same time on the CPU with the plan's own
//! adaptive rules, and both land in one matrix. With the same rules and the
//! same order of operations, f64 matrices agree with the CPU's to rounding.
//!
//! * [`GpuContext`]: instance, adapter, device, queue and pipelines, built once.
//! * [`far_field::fill_far_field`]: the work function, taking `&Device, &Queue`.
//! * [`GpuBackend`]: implements core's
//!   [`AssemblyBackend`](radcol_core::backend::AssemblyBackend).
//! * [`select_backend`]: [`BackendChoice`] `Cpu` / `Gpu` / `Auto` and a [`Precision`].
//!
//! The CPU/GPU split, tiling and precision rules are described in this
//! crate's `README.md`.
//!
//! # Example
//!
//! ```
//! use radcol_core::assembly::{AssemblyPlan, QuadratureOptions};
//! use radcol_core::discretization::Discretization;
//! use radcol_core::geometry::shapes::sphere;
//! use radcol_core::mesh::Mesh;
//! use radcol_core::nodes::NodeSet;
//! use std::sync::Arc;
//!
//! // `auto` is a hardware GPU when there is one, else the CPU backend.
//! use radcol_gpu::{select_backend, BackendChoice, Precision};
//! let backend = select_backend(BackendChoice::Auto, Precision::Auto)?;
//! let mesh = Arc::new(Mesh::new(Arc::new(sphere(1.0)), 0));
//! let disc = Arc::new(Discretization::new(mesh, NodeSet::new(0, 0.1)?));
//! let visibility = radcol_core::visibility::analyze(disc.mesh().surface());
//! let plan = AssemblyPlan::new(disc, QuadratureOptions::default(), &visibility);
//! let out = backend.assemble(&plan)?;
//! let info = backend.info();
//! println!("{} on {} in {}", info.kind, info.device, info.precision);
//! // Lemma 1(c): every row of the geometric matrix of a sphere sums to 1.
//! let row: f64 = out.matrix.row(0).iter().sum();
//! assert!((row - 1.0).abs() < 1e-6);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![deny(missing_docs)]

pub mod backend;
pub mod context;
pub mod error;
pub mod far_field;
pub mod layout;
mod scope;
pub mod select;
pub mod shader;
pub mod testing;
pub mod tiling;

pub use backend::GpuBackend;
pub use context::{AdapterFilter, GpuContext};
pub use error::GpuError;
pub use select::{select_backend, BackendChoice};
pub use tiling::TileLimits;

use std::fmt;
use std::str::FromStr;

/// Device arithmetic precision.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Precision {
    /// f64 when the device has `SHADER_F64`, else f32.
    #[default]
    Auto,
    /// f64 on the device (geometry, kernel and sums).
    F64,
    /// f32 on the device; the host widens the results to f64.
    F32,
}

impl Precision {
    /// "auto", "f64" or "f32".
    pub const fn name(self) -> &'static str {
        match self {
            Precision::Auto => "auto",
            Precision::F64 => "f64",
            Precision::F32 => "f32",
        }
    }
}

impl fmt::Display for Precision {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Precision {
    type Err = GpuError;

    fn from_str(s: &str) -> Result<Self, GpuError> {
        match s.trim().to_ascii_lowercase().as_str() {
            "auto" => Ok(Precision::Auto),
            "f64" | "double" => Ok(Precision::F64),
            "f32" | "single" | "float" => Ok(Precision::F32),
            other => Err(GpuError::BadName(format!(
                "unknown precision '{other}': expected auto, f64 or f32"
            ))),
        }
    }
}
