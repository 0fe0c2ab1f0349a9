//! GMRES and dense LU solve the same collocation systems to 1e-10 relative.

use radcol_core::assembly::CpuBackend;
use radcol_core::geometry::shapes::{box_room, ellipsoid, sphere};
use radcol_core::problem::{Field, Problem};
use radcol_core::run::{solve, SolveConfig, SolverKind};
use std::sync::Arc;

#[test]
fn gmres_and_lu_agree() {
    let cases = [
        (Arc::new(sphere(1.0)), 2usize, 1u32),
        (Arc::new(ellipsoid(1.0, 1.5, 0.8)), 1, 2),
        (Arc::new(box_room(1.0, 2.0, 1.5)), 3, 1),
    ];
    for (surface, r, level) in cases {
        let name = surface.name.clone();
        let problem = Problem::new(
            surface,
            Field::parse("0.7 - 0.1*z^2").unwrap(),
            Field::parse("1 + x*y").unwrap(),
        );
        let mut values = Vec::new();
        for solver in [SolverKind::Gmres, SolverKind::Lu] {
            let cfg = SolveConfig {
                degree: r,
                alpha: 0.12,
                level,
                solver,
                ..Default::default()
            };
            let out = solve(&problem, &cfg, &CpuBackend).unwrap();
            assert!(
                out.channels[0].solver.residual < 1e-11,
                "{name} {solver:?}: residual {}",
                out.channels[0].solver.residual
            );
            values.push(out.channels[0].solution.nodal().to_vec());
        }
        let num: f64 = values[0]
            .iter()
            .zip(&values[1])
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>()
            .sqrt();
        let den: f64 = values[1].iter().map(|b| b * b).sum::<f64>().sqrt();
        println!(
            "{name}: r = {r}, N = {}, |gmres - lu| / |lu| = {:.3e}",
            values[0].len(),
            num / den
        );
        assert!(
            num / den < 1e-10,
            "{name}: GMRES and LU differ by {:.3e}",
            num / den
        );
    }
}
