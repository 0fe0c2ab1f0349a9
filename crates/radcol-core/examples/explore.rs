use radcol_core::assembly::CpuBackend;
use radcol_core::geometry::shapes::sphere;
use radcol_core::problem::{Field, Problem};
use radcol_core::run::{solve, SolveConfig};
use radcol_core::study::study;
use std::sync::Arc;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let r: usize = args.get(1).map(|s| s.parse().unwrap()).unwrap_or(1);
    let l0: u32 = args.get(2).map(|s| s.parse().unwrap()).unwrap_or(0);
    let l1: u32 = args.get(3).map(|s| s.parse().unwrap()).unwrap_or(3);
    let alpha = radcol_core::alpha0::auto_alpha(r);
    let s = Arc::new(sphere(1.0));
    let mut p = Problem::new(
        s,
        Field::parse("0.5+0.2*x").unwrap(),
        Field::parse("exp(0.3*x+0.5*y+0.8*z)").unwrap(),
    );
    p.exact = Some(
        Field::parse("exp(0.3*x+0.5*y+0.8*z)+(0.5+0.2*x)*2*sinh(sqrt(0.98))/sqrt(0.98)").unwrap(),
    );
    let cfg = SolveConfig {
        degree: r,
        alpha,
        ..Default::default()
    };
    println!("r={r} alpha={alpha}");
    let _ = solve;
    study(&p, &cfg, l0..=l1, &CpuBackend, |row| println!("L{} n={} N={} nodes={:.3e} glob={:.3e} l2={:.3e} eoc n/g/l {:.2?} {:.2?} {:.2?} asm={:.2}s", row.level, row.elements, row.unknowns, row.nodes_max, row.global_max, row.l2, row.eoc_nodes, row.eoc_global, row.eoc_l2, row.assembly_s)).unwrap();
}
