//! Box room with constant ρ and E: by Lemma 1(c) every row of the geometric
//! matrix sums to 1 (∫_S G dS_Q = π on a closed surface bounding a convex set,
//! and Σ_j l_j ≡ 1), so the collocation solution is the exact constant
//! E / (1 - ρ) — to rounding only if the near-edge quadrature (G ~ 1/r² next to
//! the edges where walls meet) is accurate to rounding.

use radcol_core::assembly::{CpuBackend, QuadratureOptions};
use radcol_core::geometry::shapes::box_room;
use radcol_core::problem::{Field, Problem};
use radcol_core::run::{solve, SolveConfig, SolverKind};
use radcol_tests::assert_close;
use std::sync::Arc;

#[test]
fn box_room_reproduces_the_constant_solution() {
    let rho = 0.9;
    let e = 1.0;
    let exact = e / (1.0 - rho);
    for (r, level) in [(0, 2), (1, 1), (2, 1), (3, 0)] {
        let problem = Problem::new(
            Arc::new(box_room(1.0, 2.0, 1.5)),
            Field::Constant(rho),
            Field::Constant(e),
        );
        let cfg = SolveConfig {
            degree: r,
            alpha: 0.1,
            level,
            solver: SolverKind::Lu,
            quad: QuadratureOptions {
                tol: 1e-14,
                ..Default::default()
            },
            ..Default::default()
        };
        let out = solve(&problem, &cfg, &CpuBackend).unwrap();
        for i in 0..out.operator.dense().expect("dense").nrows() {
            let row_sum: f64 = out.operator.dense().expect("dense").row(i).iter().sum();
            assert_close(&format!("r={r} row sum"), i, row_sum, 1.0, 2e-13);
        }
        for (i, &u) in out.channels[0].solution.nodal().iter().enumerate() {
            assert_close(&format!("r={r} u"), i, u, exact, 1e-11 * exact);
        }
        println!(
            "r = {r}: {} unknowns, {:?}",
            out.operator.dense().expect("dense").nrows(),
            out.plan
        );
    }
}
