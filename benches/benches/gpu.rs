//! GPU assembly throughput against the CPU backend on the same machine.
//!
//! * `far_evals_*`: the far-field kernel alone (GPU `fill_far_field` vs the
//!   CPU's `fill_block(.., FarOnly)` on every row block): criterion's
//!   elements/s = far kernel evaluations per second.
//! * `assembly_entries_*`: whole assemblies (`AssemblyBackend::assemble`, the
//!   GPU backend with near and self pairs on the CPU at the same time):
//!   elements/s = matrix entries per second.
//!
//! The GPU context (device, queue, both pipelines) and every plan are built
//! once, outside the timed closures. Without an adapter only the CPU rows run
//! (the reason is printed).
//!
//! Run: `cargo bench -p radcol-benches --bench gpu` (lavapipe: install
//! mesa-vulkan-drivers first).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use radcol_core::assembly::{
    AssemblyBackend, AssemblyPlan, CpuBackend, FillMode, QuadratureOptions,
};
use radcol_core::discretization::Discretization;
use radcol_core::geometry::shapes::{box_room, sphere};
use radcol_core::geometry::Surface;
use radcol_core::mesh::Mesh;
use radcol_core::nodes::NodeSet;
use radcol_gpu::far_field::fill_far_field;
use radcol_gpu::{AdapterFilter, GpuBackend, GpuContext, Precision};
use rayon::prelude::*;
use std::sync::{Arc, OnceLock};

fn plan(surface: Surface, r: usize, level: u32) -> AssemblyPlan {
    let mesh = Arc::new(Mesh::new(Arc::new(surface), level));
    let disc = Arc::new(Discretization::new(mesh, NodeSet::new(r, 0.1).unwrap()));
    let visibility = radcol_core::visibility::analyze(disc.mesh().surface());
    AssemblyPlan::new(disc, QuadratureOptions::default(), &visibility)
}

/// The context, built once per bench binary.
fn context() -> Option<Arc<GpuContext>> {
    static CTX: OnceLock<Option<Arc<GpuContext>>> = OnceLock::new();
    CTX.get_or_init(|| match GpuContext::new(AdapterFilter::Any) {
        Ok(c) => {
            println!(
                "GPU: {} (f64: {}, timestamps: {})",
                c.description(),
                c.supports_f64(),
                c.has_timestamps()
            );
            Some(Arc::new(c))
        }
        Err(e) => {
            println!("GPU benches skipped: {e}");
            None
        }
    })
    .clone()
}

/// GPU backends to measure: f64 (when offered) and f32.
fn gpu_backends() -> Vec<GpuBackend> {
    let Some(ctx) = context() else {
        return Vec::new();
    };
    let mut out = Vec::new();
    if ctx.supports_f64() {
        out.push(GpuBackend::new(ctx.clone(), Precision::F64).unwrap());
    }
    out.push(GpuBackend::new(ctx, Precision::F32).unwrap());
    out
}

fn cases() -> Vec<(&'static str, AssemblyPlan)> {
    vec![
        ("box_r1", plan(box_room(1.0, 1.0, 1.0), 1, 3)),
        ("sphere_r2", plan(sphere(1.0), 2, 3)),
    ]
}

/// Far kernel evaluations per second.
fn far_evals(c: &mut Criterion) {
    let gpus = gpu_backends();
    for (name, p) in cases() {
        let n = p.dim();
        let f = p.discretization().max_nodes_per_element();
        let mut group = c.benchmark_group(format!("far_evals_{name}"));
        group.sample_size(10);
        group.throughput(Throughput::Elements(p.stats().far_kernel_evals));
        let mut m = vec![0.0f64; n * n];
        group.bench_function(BenchmarkId::new("cpu_f64", n), |b| {
            b.iter(|| {
                m.par_chunks_exact_mut(f * n)
                    .enumerate()
                    .for_each(|(kp, block)| {
                        p.fill_block(kp, block, FillMode::FarOnly);
                    })
            })
        });
        for g in &gpus {
            let ctx = g.context().clone();
            let kernels = ctx.kernels(g.precision()).unwrap();
            let limits = g.tile_limits();
            group.bench_function(BenchmarkId::new(format!("gpu_{}", g.precision()), n), |b| {
                b.iter(|| {
                    fill_far_field(ctx.device(), ctx.queue(), kernels, &p, &limits, &mut m).unwrap()
                })
            });
        }
        group.finish();
    }
}

/// Matrix entries per second, whole assemblies.
fn assembly_entries(c: &mut Criterion) {
    let gpus = gpu_backends();
    for (name, p) in cases() {
        let n = p.dim();
        let mut group = c.benchmark_group(format!("assembly_entries_{name}"));
        group.sample_size(10);
        group.throughput(Throughput::Elements((n * n) as u64));
        group.bench_function(BenchmarkId::new("cpu_f64", n), |b| {
            b.iter(|| CpuBackend.assemble(&p).unwrap())
        });
        for g in &gpus {
            group.bench_function(BenchmarkId::new(format!("gpu_{}", g.precision()), n), |b| {
                b.iter(|| g.assemble(&p).unwrap())
            });
        }
        group.finish();
    }
}

criterion_group!(benches, far_evals, assembly_entries);
criterion_main!(benches);
