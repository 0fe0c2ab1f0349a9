//! GMRES against dense LU on collocation systems of growing size (box room,
//! ρ = 0.7). Run: `cargo bench -p radcol-benches --bench solvers`.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use radcol_core::assembly::{AssemblyBackend, AssemblyPlan, CpuBackend, QuadratureOptions};
use radcol_core::discretization::Discretization;
use radcol_core::geometry::shapes::box_room;
use radcol_core::mesh::Mesh;
use radcol_core::nodes::NodeSet;
use radcol_core::solve::{gmres, DenseLu, GmresParams, RadiosityOperator};
use std::sync::Arc;

fn solvers(c: &mut Criterion) {
    let mut group = c.benchmark_group("solve");
    group.sample_size(10);
    for (r, level) in [(1, 2), (2, 2), (1, 3), (2, 3)] {
        let mesh = Arc::new(Mesh::new(Arc::new(box_room(1.0, 1.0, 1.0)), level));
        let disc = Arc::new(Discretization::new(mesh, NodeSet::new(r, 0.1).unwrap()));
        let visibility = radcol_core::visibility::analyze(disc.mesh().surface());
        let plan = AssemblyPlan::new(disc, QuadratureOptions::default(), &visibility);
        let gm = CpuBackend.assemble(&plan).unwrap().matrix;
        let n = gm.nrows();
        let rho = vec![0.7; n];
        let b: Vec<f64> = (0..n).map(|i| 1.0 + (i % 7) as f64 * 0.1).collect();
        let op = RadiosityOperator::new(&gm, &rho).unwrap();
        group.bench_function(BenchmarkId::new("gmres", n), |bench| {
            bench.iter(|| {
                let mut x = b.clone();
                gmres(&op, &b, &mut x, &GmresParams::default()).unwrap()
            })
        });
        let dense = op.to_dense();
        group.bench_function(BenchmarkId::new("lu", n), |bench| {
            bench.iter(|| {
                let lu = DenseLu::factor(&dense).unwrap();
                let mut x = b.clone();
                lu.solve_in_place(&mut x).unwrap();
                x
            })
        });
    }
    group.finish();
}

criterion_group!(benches, solvers);
criterion_main!(benches);
