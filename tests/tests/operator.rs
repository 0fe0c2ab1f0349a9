//! The pipeline's compressed operator ([`OperatorChoice`]): a solve on the
//! hierarchical matrix gives the dense solve's answer to the compression
//! tolerance, measured at every node against two independent references:
//! the closed form u = E / (1 − ρ) of closed surfaces (the sphere, the box
//! room: G's rows sum to 1), and the dense solve of the Cornell box
//! (occluded: zero and clipped blocks). GMRES needs at most one more
//! iteration; LU and bad tolerances are refused; `auto` stays dense where
//! the matrix fits; relighting on the compressed operator equals a fresh
//! compressed solve.

use radcol_core::assembly::CpuBackend;
use radcol_core::error::{Error, InputError};
use radcol_core::geometry::Surface;
use radcol_core::hmatrix::HOptions;
use radcol_core::problem::{Field, Problem};
use radcol_core::run::{
    solve, OperatorChoice, OperatorKind, Relighter, SolveConfig, SolveOutcome, SolverKind,
};
use radcol_core::scene::builtin;
use radcol_tests::max_rel_nodal as max_rel;
use std::sync::Arc;

fn config(operator: OperatorChoice, tol: f64, level: u32, max_edge: Option<f64>) -> SolveConfig {
    SolveConfig {
        level,
        max_edge,
        operator,
        compression: HOptions {
            tol,
            ..SolveConfig::default().compression
        },
        estimate: false,
        ..Default::default()
    }
}

fn scene(name: &str) -> Arc<Surface> {
    builtin(name).unwrap().unwrap().surface.clone()
}

fn compressed(p: &Problem, tol: f64, level: u32, max_edge: Option<f64>) -> SolveOutcome {
    let out = solve(
        p,
        &config(OperatorChoice::Compressed, tol, level, max_edge),
        &CpuBackend,
    )
    .unwrap();
    assert_eq!(out.operator.kind(), OperatorKind::Compressed);
    // Predicted from the geometry before the plan: far blocks at rank 1,
    // so no more than what was built on these unoccluded or lightly
    // occluded scenes.
    let predicted = out.operator_decision.predicted_bytes.expect("predicted");
    let built = out.operator.heap_bytes() as f64;
    assert!(
        predicted > 0.0 && predicted <= built,
        "{predicted} against {built}"
    );
    // Predicted again from the plan before a block was computed: dense
    // leaves exactly, low-rank ones at rank 1, so no more than was built.
    let planned = out.operator_decision.planned_bytes.expect("planned");
    assert!(
        planned > 0.0 && planned <= built,
        "{planned} against {built}"
    );
    // Predicted a third time from a sample of the admissible blocks, built
    // first: ranks and blocks left dense included, so within a tenth of
    // what was built (issue 10: the memory prediction within 10 %).
    let sampled = out.operator_decision.sampled_bytes.expect("sampled");
    assert!(
        sampled.sampled_blocks <= sampled.admissible_blocks
            && (sampled.bytes - built).abs() <= 0.1 * built,
        "{sampled:?} against {built}"
    );
    out
}

/// Closed surfaces, ρ = 1/2, E = 1: u = 2 at every node, whatever the
/// compression, to its tolerance.
#[test]
fn closed_surfaces_keep_their_closed_form() {
    for (name, surface, level) in [
        (
            "sphere",
            Arc::new(radcol_core::geometry::shapes::sphere(1.0)),
            2,
        ),
        ("room", scene("room"), 2),
    ] {
        let p = Problem::new(surface, Field::Constant(0.5), Field::Constant(1.0));
        for tol in [1e-4, 1e-7] {
            let out = compressed(&p, tol, level, None);
            let u = out.channels[0].solution.nodal();
            let worst = u.iter().map(|x| (x - 2.0).abs() / 2.0).fold(0.0, f64::max);
            let s = out.operator.stats().unwrap();
            println!(
                "{name}: N = {}, tol {tol:e}: max |u - 2|/2 = {worst:.2e}, stored {:.3} of dense, {} zero blocks",
                u.len(),
                s.compression(),
                s.zero_blocks
            );
            // The dense solve's own quadrature error is 1e-12.
            assert!(
                worst <= 10.0 * tol + 1e-10,
                "{name}, tol {tol:e}: {worst:e}"
            );
        }
    }
}

/// The occluded Cornell box, every channel: compressed against dense.
#[test]
fn cornell_compressed_solve_matches_dense() {
    let p = builtin("cornell").unwrap().unwrap().problem();
    let dense = solve(
        &p,
        &config(OperatorChoice::Dense, 1e-8, 0, Some(150.0)),
        &CpuBackend,
    )
    .unwrap();
    assert_eq!(dense.operator.kind(), OperatorKind::Dense);
    let mut last = f64::INFINITY;
    for tol in [1e-4, 1e-6, 1e-9] {
        let out = compressed(&p, tol, 0, Some(150.0));
        let d = max_rel(&out, &dense);
        let (ih, id) = (
            out.channels[0].solver.iterations,
            dense.channels[0].solver.iterations,
        );
        println!(
            "cornell: N = {}, tol {tol:e}: max nodal difference {d:.2e} of max u, stored {:.3} of dense, GMRES {ih} iterations (dense {id})",
            out.discretization.len(),
            out.operator.stats().unwrap().compression()
        );
        assert!(d <= 10.0 * tol, "tol {tol:e}: {d:e}");
        assert!(ih <= id + 1, "{ih} iterations against {id}");
        assert!(d < last || d < 1e-12, "the difference does not fall: {d:e}");
        last = d;
    }
}

#[test]
fn lu_and_bad_tolerances_are_refused() {
    let p = Problem::new(
        Arc::new(radcol_core::geometry::shapes::sphere(1.0)),
        Field::Constant(0.5),
        Field::Constant(1.0),
    );
    let lu = SolveConfig {
        solver: SolverKind::Lu,
        ..config(OperatorChoice::Compressed, 1e-8, 0, None)
    };
    let err = solve(&p, &lu, &CpuBackend).unwrap_err();
    assert!(
        matches!(err, Error::Input(InputError::CompressedLu)),
        "{err}"
    );
    for bad in [0.0, -1e-3, 1.0, f64::NAN, f64::INFINITY] {
        let err = solve(
            &p,
            &config(OperatorChoice::Compressed, bad, 0, None),
            &CpuBackend,
        )
        .unwrap_err();
        assert!(
            matches!(err, Error::Input(InputError::CompressionTolerance { .. })),
            "{bad}: {err}"
        );
    }
    // Auto with LU is dense, and says why.
    let out = solve(
        &p,
        &SolveConfig {
            solver: SolverKind::Lu,
            ..config(OperatorChoice::Auto, 1e-8, 0, None)
        },
        &CpuBackend,
    )
    .unwrap();
    assert_eq!(out.operator.kind(), OperatorKind::Dense);
    assert!(
        out.operator_decision.reason.contains("LU"),
        "{}",
        out.operator_decision.reason
    );
}

/// Where the dense matrix fits, auto is dense (it assembles faster).
#[test]
fn auto_is_dense_when_it_fits() {
    let p = Problem::new(
        Arc::new(radcol_core::geometry::shapes::sphere(1.0)),
        Field::Constant(0.5),
        Field::Constant(1.0),
    );
    let out = solve(
        &p,
        &config(OperatorChoice::Auto, 1e-8, 1, None),
        &CpuBackend,
    )
    .unwrap();
    assert_eq!(out.operator.kind(), OperatorKind::Dense);
    assert!(out.operator.dense().is_some());
    assert!(out.operator_decision.reason.contains("fits"));
}

/// New lights on the compressed operator: the answer of a fresh
/// compressed solve of the new problem, to rounding.
#[test]
fn relighting_a_compressed_solve() {
    let scene = builtin("shadow").unwrap().unwrap();
    let cfg = config(OperatorChoice::Compressed, 1e-8, 1, None);
    let first = solve(&scene.problem(), &cfg, &CpuBackend).unwrap();
    let mut relight = Relighter::new(&first, &cfg);
    let mut p = scene.problem();
    p.scale_emission(0.25);
    let relit = relight.solve(&p).unwrap();
    let fresh = solve(&p, &cfg, &CpuBackend).unwrap();
    for (a, b) in relit.iter().zip(&fresh.channels) {
        let (ua, ub) = (a.solution.nodal(), b.solution.nodal());
        let scale = ub.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (x, y) in ua.iter().zip(ub) {
            assert!((x - y).abs() <= 1e-10 * scale, "{x} against {y}");
        }
    }
}
