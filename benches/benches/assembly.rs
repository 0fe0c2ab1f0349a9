//! Assembly throughput: far-field kernel evaluations per second by degree, and
//! whole assemblies by size. Plans are built outside the timed closures.
//!
//! Run: `cargo bench -p radcol-benches --bench assembly`.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use radcol_core::assembly::{
    AssemblyBackend, AssemblyPlan, CpuBackend, FillMode, QuadratureOptions,
};
use radcol_core::discretization::Discretization;
use radcol_core::geometry::shapes::{box_room, ellipsoid, sphere};
use radcol_core::geometry::Surface;
use radcol_core::matrix::DenseMatrix;
use radcol_core::mesh::Mesh;
use radcol_core::nodes::NodeSet;
use rayon::prelude::*;
use std::sync::Arc;

fn plan(surface: Surface, r: usize, level: u32) -> AssemblyPlan {
    let mesh = Arc::new(Mesh::new(Arc::new(surface), level));
    let disc = Arc::new(Discretization::new(mesh, NodeSet::new(r, 0.1).unwrap()));
    let visibility = radcol_core::visibility::analyze(disc.mesh().surface());
    AssemblyPlan::new(disc, QuadratureOptions::default(), &visibility)
}

/// Far-field kernel throughput on the box room (flat walls, 1/r² near edges)
/// and the ellipsoid (curved: tabulated points), CPU backend, f64: elements/s
/// in the report = kernel evaluations per second.
fn far_field(c: &mut Criterion) {
    let mut group = c.benchmark_group("far_field_cpu_f64");
    group.sample_size(10);
    let curved = (1..=3).map(|r| ("ellipsoid", r, 3));
    for (name, r, level) in [("box", 0, 4), ("box", 1, 3), ("box", 2, 3), ("box", 3, 2)]
        .into_iter()
        .chain(curved)
    {
        let p = if name == "box" {
            plan(box_room(1.0, 1.0, 1.0), r, level)
        } else {
            plan(ellipsoid(1.0, 0.8, 0.6), r, level)
        };
        let n = p.dim();
        let f = p.discretization().max_nodes_per_element();
        let mut m = DenseMatrix::zeros(n, n);
        group.throughput(Throughput::Elements(p.stats().far_kernel_evals));
        group.bench_function(BenchmarkId::new(format!("{name}_r{r}"), n), |b| {
            b.iter(|| {
                m.as_mut_slice()
                    .par_chunks_exact_mut(f * n)
                    .enumerate()
                    .for_each(|(kp, block)| {
                        p.fill_block(kp, block, FillMode::FarOnly);
                    })
            })
        });
    }
    group.finish();
}

/// Whole assemblies (far, near and self pairs) by size and degree; elements/s
/// in the report = kernel evaluations per second over the whole assembly,
/// to set beside the far-field rate above (issue 10: curved near and self
/// pairs should not dominate). The ellipsoid at level 4 and r = 2 is the
/// 12 288 unknowns the issue measured.
fn assembly_by_size(c: &mut Criterion) {
    let mut group = c.benchmark_group("assembly_cpu");
    group.sample_size(10);
    for (name, r, level) in [
        ("sphere", 1, 3),
        ("sphere", 2, 3),
        ("sphere", 3, 3),
        ("ellipsoid", 1, 3),
        ("ellipsoid", 2, 3),
        ("ellipsoid", 3, 3),
        ("ellipsoid", 2, 4),
        ("box", 1, 3),
        ("box", 3, 2),
    ] {
        let surface = match name {
            "sphere" => sphere(1.0),
            "ellipsoid" => ellipsoid(1.0, 0.8, 0.6),
            _ => box_room(1.0, 1.0, 1.0),
        };
        let p = plan(surface, r, level);
        let evals = CpuBackend.assemble(&p).unwrap().kernel_evals;
        group.throughput(Throughput::Elements(evals));
        group.bench_function(
            BenchmarkId::new(format!("{name}_r{r}_level{level}"), p.dim()),
            |b| b.iter(|| CpuBackend.assemble(&p).unwrap()),
        );
    }
    group.finish();
}

criterion_group!(benches, far_field, assembly_by_size);
criterion_main!(benches);
