//! GMRES and dense LU solve the same collocation systems to 1e-10 relative.

use radcol_core::assembly::CpuBackend;
use radcol_core::run::{solve, SolveConfig, SolverKind};
use radcol_tests::{mixed_problems, rel_diff};

#[test]
fn gmres_and_lu_agree() {
    for (name, problem, r, level) in mixed_problems() {
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
        let d = rel_diff(&values[0], &values[1]);
        println!(
            "{name}: r = {r}, N = {}, |gmres - lu| / |lu| = {:.3e}",
            values[0].len(),
            d
        );
        assert!(d < 1e-10, "{name}: GMRES and LU differ by {:.3e}", d);
    }
}
