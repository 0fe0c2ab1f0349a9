//! The hierarchical matrix against the dense one on the Cornell box refined
//! by --max-edge (r = 1, occluded: partly visible blocks are subdivided to
//! dense leaves, culled blocks are zero), or on the empty room by level:
//! unknowns, build seconds, numbers stored (and by the kind of leaf that
//! stores them), product seconds, and the product's error against the dense
//! matrix where that fits (`DENSE_CAP` unknowns); then the exponents of
//! storage (all, and by kind) and product time against N fitted over the
//! run. Wall-clock
//! figures of one run: compare them as ratios within it.
//!
//!     cargo run --release -p radcol-benches --example hmatrix [-- TOL [EDGE ...]]
//!     cargo run --release -p radcol-benches --example hmatrix -- room TOL [LEVEL ...]
//!
//! The entries come from the assembly plan, which classifies all n² element
//! pairs (its table keeps them as runs of equal classes).

use radcol_benches::fit_exponent as fit;
use radcol_core::assembly::{AssemblyBackend, AssemblyPlan, CpuBackend, QuadratureOptions};
use radcol_core::discretization::Discretization;
use radcol_core::hmatrix::radiosity::PlanEntries;
use radcol_core::hmatrix::HOptions;
use radcol_core::mesh::Mesh;
use radcol_core::nodes::NodeSet;
use radcol_core::scene::builtin;
use radcol_core::visibility;
use std::sync::Arc;
use std::time::Instant;

const DENSE_CAP: usize = 16_000;

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    // `room TOL LEVEL ...`: the empty room refined uniformly instead.
    let room = args.first().is_some_and(|a| a == "room");
    if room {
        args.remove(0);
    }
    let tol: f64 = args.first().map_or(1e-6, |a| a.parse().expect("TOL"));
    let sizes: Vec<f64> = if args.len() > 1 {
        args[1..]
            .iter()
            .map(|a| a.parse().expect("EDGE or LEVEL"))
            .collect()
    } else if room {
        vec![3.0, 4.0]
    } else {
        vec![120.0, 85.0, 60.0, 42.0]
    };
    let name = if room { "room" } else { "cornell" };
    let surface = builtin(name).unwrap().unwrap().surface.clone();
    let vis = visibility::analyze(&surface);
    println!("{name}, r = 1, tol {tol:e}, eta 1, leaf 32");
    println!(
        "     N   build s   stored   of dense   matvec s   dense asm s   dense matvec s   error"
    );
    let (mut storage, mut times) = (Vec::new(), Vec::new());
    let mut by_kind: [Vec<(f64, f64)>; 4] = Default::default();
    for h in sizes {
        let mesh = Arc::new(if room {
            Mesh::new(surface.clone(), h as u32)
        } else {
            Mesh::with_max_edge(surface.clone(), 0, h)
        });
        let disc = Arc::new(Discretization::new(
            mesh,
            NodeSet::new(1, 1.0 / 6.0).unwrap(),
        ));
        let plan = AssemblyPlan::new(disc, QuadratureOptions::default(), &vis);
        let n = plan.dim();
        let t = Instant::now();
        let hm = PlanEntries::new(&plan).build(&HOptions {
            tol,
            ..Default::default()
        });
        let build = t.elapsed().as_secs_f64();
        let x: Vec<f64> = (0..n)
            .map(|i| ((i as f64 + 1.0) * 0.618_034).fract())
            .collect();
        let mut y = vec![0.0; n];
        let t = Instant::now();
        for _ in 0..10 {
            hm.matvec(&x, &mut y);
        }
        let matvec = t.elapsed().as_secs_f64() / 10.0;
        let s = hm.stats();
        let dense = (n <= DENSE_CAP).then(|| {
            let t = Instant::now();
            let g = CpuBackend.assemble(&plan).unwrap().matrix;
            let asm = t.elapsed().as_secs_f64();
            let mut yd = vec![0.0; n];
            let t = Instant::now();
            for _ in 0..10 {
                g.matvec(&x, &mut yd);
            }
            let mv = t.elapsed().as_secs_f64() / 10.0;
            let d: f64 = y.iter().zip(&yd).map(|(a, b)| (a - b) * (a - b)).sum();
            let nd: f64 = yd.iter().map(|b| b * b).sum();
            (asm, mv, (d / nd).sqrt())
        });
        let (asm, mv, err) = dense.map_or(("-".into(), "-".into(), "-".into()), |(a, m, e)| {
            (format!("{a:.2}"), format!("{m:.4}"), format!("{e:.1e}"))
        });
        println!(
            "{n:>6}   {build:>7.2}   {:>6.1}M   {:>8.3}   {matvec:>8.4}   {asm:>11}   {mv:>14}   {err}",
            s.stored as f64 / 1e6,
            s.compression()
        );
        let by = s.stored_by_kind;
        let kinds = [by.low_rank, by.left_dense, by.split, by.near];
        println!(
            "        numbers by kind: low rank {:.1}M, admissible left dense {:.1}M, split at shadows or tangent planes {:.1}M, near the diagonal {:.1}M",
            kinds[0] as f64 / 1e6,
            kinds[1] as f64 / 1e6,
            kinds[2] as f64 / 1e6,
            kinds[3] as f64 / 1e6
        );
        for (fits, k) in by_kind.iter_mut().zip(kinds) {
            fits.push((n as f64, k.max(1) as f64));
        }
        storage.push((n as f64, s.stored as f64));
        times.push((n as f64, matvec));
    }
    if storage.len() >= 2 {
        println!(
            "fitted exponents against N: storage {:.2}, matvec time {:.2} (dense: 2)",
            fit(&storage),
            fit(&times)
        );
        println!(
            "  by kind: low rank {:.2}, admissible left dense {:.2}, split {:.2}, near {:.2}",
            fit(&by_kind[0]),
            fit(&by_kind[1]),
            fit(&by_kind[2]),
            fit(&by_kind[3])
        );
    }
}
