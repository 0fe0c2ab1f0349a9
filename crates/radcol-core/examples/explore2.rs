use radcol_core::assembly::{AssemblyPlan, FillMode, QuadratureOptions};
use radcol_core::discretization::Discretization;
use radcol_core::geometry::shapes::{box_room, sphere};
use radcol_core::matrix::DenseMatrix;
use radcol_core::mesh::Mesh;
use radcol_core::nodes::NodeSet;
use rayon::prelude::*;
use std::sync::Arc;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let r: usize = args[1].parse().unwrap();
    let l: u32 = args[2].parse().unwrap();
    let shape = args.get(3).cloned().unwrap_or("sphere".into());
    let tol: f64 = args.get(4).map(|s| s.parse().unwrap()).unwrap_or(1e-12);
    let s = Arc::new(if shape == "box" {
        box_room(1.0, 1.0, 1.0)
    } else {
        sphere(1.0)
    });
    let disc = Arc::new(Discretization::new(
        Arc::new(Mesh::new(s, l)),
        NodeSet::new(r, 0.1).unwrap(),
    ));
    let t = Instant::now();
    let plan = AssemblyPlan::new(
        disc.clone(),
        QuadratureOptions {
            tol,
            ..Default::default()
        },
    );
    println!("plan {:.3}s {:?}", t.elapsed().as_secs_f64(), plan.stats());
    println!("avg run {:.2}", runs(plan.classes(), disc.mesh().len()));
    let n = disc.len();
    let f = disc.nodes_per_element();
    for mode in [FillMode::SpecialOnly, FillMode::All] {
        let mut m = DenseMatrix::zeros(n, n);
        let t = Instant::now();
        let ev: u64 = m
            .as_mut_slice()
            .par_chunks_exact_mut(f * n)
            .enumerate()
            .map(|(k, b)| plan.fill_block(k, b, mode))
            .sum();
        let dt = t.elapsed().as_secs_f64();
        println!("{mode:?}: {dt:.3}s evals {ev} -> {:.3e}/s", ev as f64 / dt);
        if mode == FillMode::All {
            let rs: Vec<f64> = (0..n).map(|i| m.row(i).iter().sum::<f64>()).collect();
            let dev = rs.iter().map(|v| (v - 1.0).abs()).fold(0.0, f64::max);
            println!("max |rowsum - 1| = {dev:.3e}");
        }
    }
}
#[allow(dead_code)]
fn runs(c: &[u8], n: usize) -> f64 {
    let mut runs = 0usize;
    for row in c.chunks(n) {
        runs += 1 + row.windows(2).filter(|w| w[0] != w[1]).count();
    }
    c.len() as f64 / runs as f64
}
