//! The far-field work function: far pairs of an [`AssemblyPlan`] on a device,
//! tile by tile, streamed back into the host matrix.
//!
//! Device data (all read-only except the tile):
//!
//! * `rules`: 256 [`RuleInfo`](crate::layout::RuleInfo), one per class code;
//! * `basis_t`: the basis tables of the used far rules, concatenated, each
//!   `nq × f` with row q contiguous (the plan's `FarTable::basis_t`);
//! * `colloc`: the N collocation points;
//! * `far_points`: the far-rule points of the column tile's `nk` elements,
//!   point-major: slot s = (offset of a used rule) + q holds rule point q of
//!   every element, `far_points[s · nk + e]`, the used rules concatenated in
//!   degree order (`stride` = Σ nq slots). Neighbouring invocations (elements
//!   e, e + 1) of the same rule read neighbouring records: coalesced loads;
//! * `classes`: the tile's class codes, four per u32;
//! * `tile`: the output, `rows × nk·f`, row-major.
//!
//! Two slots of (params, classes, tile, staging) buffers alternate so that the
//! host copies tile t while the device fills tile t + 1.

//!
//! By phase: [`kernels`] (shader and pipelines), `pack` (the plan laid out
//! for the device: pure, tested without a GPU), `stream` (buffers and the
//! tile loop) and `readback` (waiting, mapping, widening, timestamps).

pub mod kernels;
mod pack;
mod readback;
mod slot;
mod stream;

pub use kernels::FarFieldKernels;

use crate::error::GpuError;
use crate::layout::MAX_NODES_PER_ELEMENT;
use crate::scope::ErrorScopes;
use crate::tiling::TileLimits;
use radcol_core::backend::{AssemblyPlan, Scalar};

/// What [`fill_far_field`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FarFieldReport {
    /// Far kernel evaluations (the plan's count: f · nq per far pair of elements).
    pub kernel_evals: u64,
    /// Summed duration of the compute passes from timestamp queries, seconds,
    /// when the device has [`wgpu::Features::TIMESTAMP_QUERY`].
    pub device_seconds: Option<f64>,
    /// Tiles dispatched.
    pub tiles: usize,
}

/// Fills the far pairs of `plan` into `matrix` (N × N, row-major, length N²)
/// on `device`: every entry of a far pair gets its value, every other entry
/// (culled, near, self) is overwritten with 0, so near and self pairs must be
/// merged afterwards. Tiles respect `limits`.
pub fn fill_far_field(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    kernels: &FarFieldKernels,
    plan: &AssemblyPlan,
    limits: &TileLimits,
    matrix: &mut [f64],
) -> Result<FarFieldReport, GpuError> {
    let n_dim = plan.dim();
    assert_eq!(matrix.len(), n_dim * n_dim, "matrix must be N × N");
    let Some(nodes) = plan.discretization().uniform_nodes() else {
        return Err(GpuError::Unsupported(
            "a degree per element: the far-field shader takes one node set per assembly".into(),
        ));
    };
    let f = nodes.len();
    if f > MAX_NODES_PER_ELEMENT {
        return Err(GpuError::Unsupported(format!(
            "{f} nodes per element: the far-field shader holds at most {MAX_NODES_PER_ELEMENT} (r = 6)"
        )));
    }
    let scopes = ErrorScopes::push(device);
    let out = match kernels.precision() {
        Scalar::F32 => stream::run::<f32>(device, queue, kernels, plan, limits, matrix),
        Scalar::F64 => stream::run::<f64>(device, queue, kernels, plan, limits, matrix),
    };
    // A validation error explains any later failure (a failed map, say): report it first.
    scopes.pop("filling far pairs")?;
    out
}
