//! GMRES against dense LU on collocation systems of growing size (box room,
//! ρ = 0.7), and three colour channels by GMRES one after another against
//! in lockstep (one pass over the matrix per iteration for all three).
//! Run: `cargo bench -p radcol-benches --bench solvers`.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use radcol_core::assembly::{AssemblyBackend, AssemblyPlan, CpuBackend, QuadratureOptions};
use radcol_core::discretization::Discretization;
use radcol_core::geometry::shapes::box_room;
use radcol_core::matrix::DenseMatrix;
use radcol_core::mesh::Mesh;
use radcol_core::nodes::NodeSet;
use radcol_core::solve::{
    gmres, gmres_radiosity, DenseLu, GmresParams, RadiosityOperator, RadiositySystem,
};
use std::ops::ControlFlow;
use std::sync::Arc;

/// The geometric matrix of the unit box room at degree `r`, `level`.
fn box_matrix(r: usize, level: u32) -> DenseMatrix {
    let mesh = Arc::new(Mesh::new(Arc::new(box_room(1.0, 1.0, 1.0)), level));
    let disc = Arc::new(Discretization::new(mesh, NodeSet::new(r, 0.1).unwrap()));
    let visibility = radcol_core::visibility::analyze(disc.mesh().surface());
    let plan = AssemblyPlan::new(disc, QuadratureOptions::default(), &visibility);
    CpuBackend.assemble(&plan).unwrap().matrix
}

fn solvers(c: &mut Criterion) {
    let mut group = c.benchmark_group("solve");
    group.sample_size(10);
    for (r, level) in [(1, 2), (2, 2), (1, 3), (2, 3)] {
        let gm = box_matrix(r, level);
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

/// Red, green and blue of the Cornell box's white and red walls (ρ per
/// channel) on the box room: separately, then in lockstep.
fn channels(c: &mut Criterion) {
    let mut group = c.benchmark_group("channels");
    group.sample_size(10);
    for (r, level) in [(1, 3), (2, 3), (1, 4)] {
        let gm = box_matrix(r, level);
        let n = gm.nrows();
        let rhos: Vec<Vec<f64>> = [0.63, 0.45, 0.4]
            .iter()
            .map(|&r| (0..n).map(|i| if i % 5 == 0 { 0.06 } else { r }).collect())
            .collect();
        let b: Vec<f64> = (0..n)
            .map(|i| if i % 11 == 0 { 1.0 } else { 0.0 })
            .collect();
        group.bench_function(BenchmarkId::new("separate", n), |bench| {
            bench.iter(|| {
                rhos.iter()
                    .map(|rho| {
                        let op = RadiosityOperator::new(&gm, rho).unwrap();
                        let mut x = b.clone();
                        gmres(&op, &b, &mut x, &GmresParams::default()).unwrap();
                        x
                    })
                    .collect::<Vec<_>>()
            })
        });
        group.bench_function(BenchmarkId::new("lockstep", n), |bench| {
            bench.iter(|| {
                let mut xs = vec![b.clone(); 3];
                let mut systems: Vec<RadiositySystem> = xs
                    .iter_mut()
                    .zip(&rhos)
                    .map(|(x, rho)| RadiositySystem { rho, b: &b, x })
                    .collect();
                let params = GmresParams::default();
                gmres_radiosity(&gm, &mut systems, &params, &mut |_, _, _| {
                    ControlFlow::Continue(())
                })
            })
        });
    }
    group.finish();
}

criterion_group!(benches, solvers, channels);
criterion_main!(benches);
