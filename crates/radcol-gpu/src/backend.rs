//! [`GpuBackend`]: the assembly backend. Far pairs on the device, near and self
//! pairs on the CPU at the same time, merged into one matrix.

use crate::context::GpuContext;
use crate::error::GpuError;
use crate::far_field::fill_far_field;
use crate::tiling::TileLimits;
use crate::Precision;
use radcol_core::backend::{
    Assembled, AssemblyBackend, AssemblyPlan, BackendInfo, BackendKind, DenseMatrix, Error,
    FillMode, PairClass, Scalar,
};
use rayon::prelude::*;
use std::sync::Arc;
use std::time::Instant;

/// Assembles on a [`GpuContext`] in one precision.
#[derive(Debug, Clone)]
pub struct GpuBackend {
    ctx: Arc<GpuContext>,
    precision: Scalar,
    limits: TileLimits,
}

impl GpuBackend {
    /// A backend on `ctx` computing in `precision` (`Auto`: f64 when the device
    /// has it, else f32). Asking for f64 on a device without it is an error.
    pub fn new(ctx: Arc<GpuContext>, precision: Precision) -> Result<Self, GpuError> {
        let precision = ctx.resolve(precision)?;
        let limits = ctx.tile_limits();
        Ok(Self {
            ctx,
            precision,
            limits,
        })
    }

    /// Caps tile sizes below the device limits (tests use this to force many
    /// row and column tiles on small problems). Each field is clamped to the
    /// device's own limit.
    pub fn with_tile_limits(mut self, limits: TileLimits) -> Self {
        let dev = self.ctx.tile_limits();
        self.limits = TileLimits {
            max_binding_bytes: limits.max_binding_bytes.min(dev.max_binding_bytes),
            max_buffer_bytes: limits.max_buffer_bytes.min(dev.max_buffer_bytes),
            max_workgroups: limits.max_workgroups.min(dev.max_workgroups),
            target_tile_bytes: limits.target_tile_bytes,
        };
        self
    }

    /// The precision the device computes in.
    pub fn precision(&self) -> Scalar {
        self.precision
    }

    /// The context.
    pub fn context(&self) -> &Arc<GpuContext> {
        &self.ctx
    }

    /// The tile limits in use.
    pub fn tile_limits(&self) -> TileLimits {
        self.limits
    }

    fn assemble_gpu(&self, plan: &AssemblyPlan) -> Result<Assembled, GpuError> {
        let start = Instant::now();
        let Some(nodes) = plan.discretization().uniform_nodes() else {
            return Err(GpuError::Unsupported(
                "a degree per element: the far-field shader takes one node set per assembly; use the CPU backend".into(),
            ));
        };
        let f = nodes.len();
        let n_dim = plan.dim();
        let mut matrix = DenseMatrix::zeros(n_dim, n_dim);
        if n_dim == 0 {
            return Ok(Assembled {
                matrix,
                kernel_evals: 0,
                device_seconds: None,
                wall_seconds: start.elapsed().as_secs_f64(),
            });
        }
        let kernels = self.ctx.kernels(self.precision)?;
        let (far, special) = std::thread::scope(|s| {
            let cpu = s.spawn(|| special_pairs(plan));
            let far = fill_far_field(
                self.ctx.device(),
                self.ctx.queue(),
                kernels,
                plan,
                &self.limits,
                matrix.as_mut_slice(),
            );
            (
                far,
                cpu.join().unwrap_or_else(|p| std::panic::resume_unwind(p)),
            )
        });
        let far = far?;
        let data = matrix.as_mut_slice();
        for block in &special.blocks {
            for (k, vals) in &block.pairs {
                for row in 0..f {
                    let at = (block.kp * f + row) * n_dim + k * f;
                    data[at..at + f].copy_from_slice(&vals[row * f..(row + 1) * f]);
                }
            }
        }
        Ok(Assembled {
            matrix,
            kernel_evals: far.kernel_evals + special.evals,
            device_seconds: far.device_seconds,
            wall_seconds: start.elapsed().as_secs_f64(),
        })
    }
}

impl AssemblyBackend for GpuBackend {
    fn info(&self) -> BackendInfo {
        BackendInfo {
            kind: BackendKind::Gpu,
            device: self.ctx.description(),
            precision: self.precision,
        }
    }

    fn assemble(&self, plan: &AssemblyPlan) -> Result<Assembled, Error> {
        Ok(self.assemble_gpu(plan)?)
    }
}

/// Near and self pairs of one row block: `(k, f × f values, row-major)`.
struct SpecialBlock {
    kp: usize,
    pairs: Vec<(usize, Vec<f64>)>,
}

struct Special {
    blocks: Vec<SpecialBlock>,
    evals: u64,
}

/// Integrates every partial, near and self pair on the CPU (rayon), with the plan's own
/// `fill_block(.., FillMode::SpecialOnly)` so the rules are the CPU backend's.
fn special_pairs(plan: &AssemblyPlan) -> Special {
    let n = plan.discretization().mesh().len();
    // One node set (checked by the caller).
    let f = plan.discretization().max_nodes_per_element();
    let n_dim = plan.dim();
    let classes = plan.classes();
    let kps: Vec<usize> = (0..n)
        .filter(|&kp| {
            classes
                .runs(kp, 0..n)
                .any(|(_, c)| PairClass::from_code(c).is_special())
        })
        .collect();
    let results: Vec<(SpecialBlock, u64)> = kps
        .par_iter()
        .map_init(
            || vec![0.0f64; f * n_dim],
            |scratch, &kp| {
                // SpecialOnly writes exactly the entries read back below.
                let evals = plan.fill_block(kp, scratch, FillMode::SpecialOnly);
                let pairs = (0..n)
                    .filter(|&k| PairClass::from_code(classes.get(kp, k)).is_special())
                    .map(|k| {
                        let mut vals = Vec::with_capacity(f * f);
                        for row in 0..f {
                            vals.extend_from_slice(
                                &scratch[row * n_dim + k * f..row * n_dim + (k + 1) * f],
                            );
                        }
                        (k, vals)
                    })
                    .collect();
                (SpecialBlock { kp, pairs }, evals)
            },
        )
        .collect();
    let evals = results.iter().map(|r| r.1).sum();
    Special {
        blocks: results.into_iter().map(|r| r.0).collect(),
        evals,
    }
}
