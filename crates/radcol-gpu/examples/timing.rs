//! One assembly of the unit sphere (r = 2, level 3) on the GPU, both
//! precisions, against the CPU backend: wall time, device time from timestamp
//! queries, and far-field kernel evaluations per second.
//!
//! Run: `cargo run --release -p radcol-gpu --example timing`.

use radcol_core::assembly::{
    AssemblyBackend, AssemblyPlan, CpuBackend, FillMode, QuadratureOptions,
};
use radcol_core::discretization::Discretization;
use radcol_core::geometry::shapes::sphere;
use radcol_core::mesh::Mesh;
use radcol_core::nodes::NodeSet;
use radcol_gpu::far_field::fill_far_field;
use radcol_gpu::{AdapterFilter, GpuBackend, GpuContext, Precision};
use rayon::prelude::*;
use std::sync::Arc;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let ctx = match GpuContext::new(AdapterFilter::Any) {
        Ok(c) => Arc::new(c),
        Err(e) => {
            println!("no GPU: {e}");
            return Ok(());
        }
    };
    println!("device: {}", ctx.description());
    let mesh = Arc::new(Mesh::new(Arc::new(sphere(1.0)), 3));
    let disc = Arc::new(Discretization::new(mesh, NodeSet::new(2, 0.1)?));
    let visibility = radcol_core::visibility::analyze(disc.mesh().surface());
    let plan = AssemblyPlan::new(disc, QuadratureOptions::default(), &visibility);
    let n = plan.dim();
    let f = plan.discretization().max_nodes_per_element();
    let evals = plan.stats().far_kernel_evals as f64;
    println!("N = {n}, far kernel evaluations = {evals:.3e}");

    let mut m = vec![0.0; n * n];
    let t = Instant::now();
    m.par_chunks_exact_mut(f * n)
        .enumerate()
        .for_each(|(kp, block)| {
            plan.fill_block(kp, block, FillMode::FarOnly);
        });
    let s = t.elapsed().as_secs_f64();
    println!("cpu f64 far pairs: {s:.3} s, {:.3e} evals/s", evals / s);
    let t = Instant::now();
    CpuBackend.assemble(&plan)?;
    println!("cpu f64 assembly:  {:.3} s", t.elapsed().as_secs_f64());

    for p in [Precision::F64, Precision::F32] {
        let Ok(b) = GpuBackend::new(ctx.clone(), p) else {
            continue;
        };
        let t = Instant::now();
        let r = fill_far_field(
            ctx.device(),
            ctx.queue(),
            ctx.kernels(b.precision())?,
            &plan,
            &b.tile_limits(),
            &mut m,
        )?;
        let s = t.elapsed().as_secs_f64();
        println!(
            "gpu {p} far pairs: {s:.3} s, {:.3e} evals/s, device {:?} s, {} tiles",
            evals / s,
            r.device_seconds,
            r.tiles
        );
        let t = Instant::now();
        let out = b.assemble(&plan)?;
        println!(
            "gpu {p} assembly:  {:.3} s (device {:?} s)",
            t.elapsed().as_secs_f64(),
            out.device_seconds
        );
    }
    Ok(())
}
