//! The far and the special (near and self) pairs of one assembly on a
//! curved surface, timed apart on one thread: where the whole assembly's
//! rate (the `assembly` bench) stands against the far field's.
//!
//! Run: `cargo run --release -p radcol-benches --example special_pairs --
//! [sphere|ellipsoid] R LEVEL` (default: ellipsoid 2 3; the ellipsoid is
//! 1, 0.8, 0.6, as in the bench).

use radcol_core::assembly::{AssemblyPlan, FillMode, QuadratureOptions};
use radcol_core::discretization::Discretization;
use radcol_core::geometry::shapes::{ellipsoid, sphere};
use radcol_core::mesh::Mesh;
use radcol_core::nodes::NodeSet;
use std::sync::Arc;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let name = args.first().map_or("ellipsoid", String::as_str);
    let r: usize = args.get(1).map_or(2, |a| a.parse().expect("R: a degree"));
    let level: u32 = args
        .get(2)
        .map_or(3, |a| a.parse().expect("LEVEL: a number"));
    let surface = match name {
        "sphere" => sphere(1.0),
        "ellipsoid" => ellipsoid(1.0, 0.8, 0.6),
        other => panic!("{other}: sphere or ellipsoid"),
    };
    let mesh = Arc::new(Mesh::new(Arc::new(surface), level));
    let disc = Arc::new(Discretization::new(mesh, NodeSet::new(r, 0.1).unwrap()));
    let visibility = radcol_core::visibility::analyze(disc.mesh().surface());
    let plan = AssemblyPlan::new(disc, QuadratureOptions::default(), &visibility);
    let n = plan.dim();
    let f = plan.discretization().max_nodes_per_element();
    let mut matrix = vec![0.0; n * n];
    // Each part twice, the second timed (the first faults the pages in).
    let mut time = |mode: FillMode| {
        let mut last = (0, 0.0);
        for _ in 0..2 {
            let start = Instant::now();
            let evals: u64 = matrix
                .chunks_exact_mut(f * n)
                .enumerate()
                .map(|(kp, block)| plan.fill_block(kp, block, mode))
                .sum();
            last = (evals, start.elapsed().as_secs_f64());
        }
        last
    };
    let (far, far_s) = time(FillMode::FarOnly);
    let (special, special_s) = time(FillMode::SpecialOnly);
    println!("{name} r = {r}, level {level}: {n} unknowns, one thread");
    println!(
        "far      {far:>11} kernel evaluations  {far_s:.3} s  {:.3e}/s",
        far as f64 / far_s
    );
    println!(
        "special  {special:>11} kernel evaluations  {special_s:.3} s  {:.3e}/s",
        special as f64 / special_s
    );
    let whole = (far + special) as f64 / (far_s + special_s);
    println!(
        "together {:.3e}/s: {:.0} % of the far rate",
        whole,
        100.0 * whole * far_s / far as f64
    );
}
