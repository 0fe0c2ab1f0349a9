//! The CPU backend: row blocks filled in parallel with rayon, no unsafe.

use super::{Assembled, AssemblyBackend, BackendInfo, BackendKind, FillMode, Scalar};
use crate::assembly::AssemblyPlan;
use crate::error::Error;
use crate::matrix::DenseMatrix;
use rayon::prelude::*;
use std::time::Instant;

/// Fills the whole geometric matrix on the CPU (f64), one rayon task per row block.
#[derive(Clone, Copy, Debug, Default)]
pub struct CpuBackend;

impl AssemblyBackend for CpuBackend {
    fn info(&self) -> BackendInfo {
        BackendInfo {
            kind: BackendKind::Cpu,
            device: match rayon::current_num_threads() {
                1 => "1 rayon thread".into(),
                n => format!("{n} rayon threads"),
            },
            precision: Scalar::F64,
        }
    }

    fn assemble(&self, plan: &AssemblyPlan) -> Result<Assembled, Error> {
        Ok(fill(plan, None))
    }

    fn assemble_reusing(
        &self,
        plan: &AssemblyPlan,
        previous: &DenseMatrix,
    ) -> Result<Assembled, Error> {
        Ok(fill(plan, Some(previous)))
    }
}

/// The matrix of `plan`, with the pairs of unchanged elements copied from
/// `previous` when given and the plan was updated.
fn fill(plan: &AssemblyPlan, previous: Option<&DenseMatrix>) -> Assembled {
    let start = Instant::now();
    let n_dim = plan.dim();
    assert!(
        std::sync::Arc::ptr_eq(plan.rows(), plan.discretization()),
        "backends assemble square plans (AssemblyPlan::at_points plans are filled block by block)"
    );
    let disc = plan.discretization();
    let mut matrix = DenseMatrix::zeros(n_dim, n_dim);
    let mode = match (previous, plan.unchanged(), plan.previous_offsets()) {
        (Some(prev), Some(u), Some(old)) => {
            u.copy_blocks(prev, &mut matrix, old, disc.offsets());
            FillMode::NotReused
        }
        _ => FillMode::All,
    };
    let kernel_evals = if n_dim == 0 {
        0
    } else {
        crate::matrix::row_blocks(matrix.as_mut_slice(), disc.offsets(), n_dim)
            .into_par_iter()
            .enumerate()
            .map(|(kp, block)| plan.fill_block(kp, block, mode))
            .sum()
    };
    Assembled {
        matrix,
        kernel_evals,
        device_seconds: None,
        wall_seconds: start.elapsed().as_secs_f64(),
    }
}
