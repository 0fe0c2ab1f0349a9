//! Triangle scenes: what occlusion costs (planning with the occluder tests,
//! then the assembly with clipped partly visible pairs), against the same
//! mesh sizes of a scene that needs no visibility; and rendering.
//!
//! Run: `cargo bench -p radcol-benches --bench scenes`.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use radcol_core::assembly::{
    AssemblyBackend, AssemblyPlan, CpuBackend, QuadratureOptions, VisibilityMode,
};
use radcol_core::discretization::Discretization;
use radcol_core::mesh::Mesh;
use radcol_core::nodes::NodeSet;
use radcol_core::render::{render, RenderOptions};
use radcol_core::run::{solve, SolveConfig};
use radcol_core::scene::builtin;
use radcol_core::visibility::analyze;
use std::sync::Arc;

fn disc(name: &str, max_edge: f64) -> Arc<Discretization> {
    let scene = builtin(name).unwrap().unwrap();
    let mesh = Arc::new(Mesh::with_max_edge(scene.surface.clone(), 0, max_edge));
    Arc::new(Discretization::new(
        mesh,
        NodeSet::new(1, 1.0 / 6.0).unwrap(),
    ))
}

/// The Cornell box (occludes) and the empty room (does not) at about the same
/// number of elements: plan, then assembly, CPU backend, r = 1.
fn occlusion(c: &mut Criterion) {
    let mut group = c.benchmark_group("scenes_cpu");
    group.sample_size(10);
    // Cornell: millimetres; room: metres (4 x 3 x 5).
    for (name, max_edge) in [("cornell", 120.0), ("room", 0.62)] {
        let d = disc(name, max_edge);
        let elements = d.mesh().len();
        group.bench_function(BenchmarkId::new(format!("{name}_plan"), elements), |b| {
            // The visibility analysis is part of planning, as in every solve.
            b.iter(|| {
                let visibility = analyze(d.mesh().surface());
                AssemblyPlan::new(d.clone(), QuadratureOptions::default(), &visibility)
            })
        });
        let visibility = analyze(d.mesh().surface());
        let plan = AssemblyPlan::new(d.clone(), QuadratureOptions::default(), &visibility);
        println!("{name}: {elements} elements, {:?}", plan.stats());
        group.bench_function(BenchmarkId::new(format!("{name}_fill"), elements), |b| {
            b.iter(|| CpuBackend.assemble(&plan).unwrap())
        });
        if plan.stats().pairs_partial > 0 {
            // The same pairs with V cast as rays at every quadrature point.
            let rays = AssemblyPlan::new(
                d.clone(),
                QuadratureOptions {
                    visibility: VisibilityMode::Rays,
                    ..Default::default()
                },
                &visibility,
            );
            group.bench_function(
                BenchmarkId::new(format!("{name}_fill_rays"), elements),
                |b| b.iter(|| CpuBackend.assemble(&rays).unwrap()),
            );
        }
    }
    group.finish();
}

/// A 640 × 480 image, 2 × 2 rays per pixel, of the solved Cornell box.
fn rendering(c: &mut Criterion) {
    let scene = builtin("cornell").unwrap().unwrap();
    let cfg = SolveConfig {
        level: 1,
        ..Default::default()
    };
    let out = solve(&scene.problem(), &cfg, &CpuBackend).unwrap();
    let rgb: Vec<_> = out.channels.iter().map(|c| &c.solution).collect();
    let camera = scene.camera.unwrap();
    let mut group = c.benchmark_group("render");
    group.sample_size(10);
    group.bench_function(
        BenchmarkId::new("cornell_640x480_2x2", out.discretization.mesh().len()),
        |b| {
            b.iter(|| {
                render(
                    out.discretization.mesh(),
                    &rgb,
                    &camera,
                    &RenderOptions::default(),
                )
                .unwrap()
            })
        },
    );
    group.finish();
}

criterion_group!(benches, occlusion, rendering);
criterion_main!(benches);
