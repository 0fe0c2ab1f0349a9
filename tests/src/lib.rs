//! Shared helpers for radcol's cross-crate tests.

use radcol_core::assembly::CpuBackend;
use radcol_core::problem::Problem;
use radcol_core::run::SolveConfig;
use radcol_core::study::{fitted_order, study, StudyRow};

/// Asserts |got - want| ≤ tol, printing the label, index, both values, the
/// difference and the tolerance when it fails.
#[track_caller]
pub fn assert_close(label: &str, index: usize, got: f64, want: f64, tol: f64) {
    let diff = (got - want).abs();
    assert!(
        diff <= tol,
        "{label}[{index}]: got {got:.17e}, want {want:.17e}, |diff| = {diff:.3e} > tol {tol:.3e}"
    );
}

/// Fitted orders (nodes, global, L2) of a study over `levels`, printing the table.
pub fn orders(
    problem: &Problem,
    cfg: &SolveConfig,
    levels: std::ops::RangeInclusive<u32>,
) -> (Vec<StudyRow>, [f64; 3]) {
    let rows = study(problem, cfg, levels, &CpuBackend, |r| {
        println!(
            "  level {} N={:6} h={:.4} nodes={:.3e} global={:.3e} l2={:.3e}",
            r.level, r.unknowns, r.h, r.nodes_max, r.global_max, r.l2
        )
    })
    .expect("study runs");
    let h: Vec<f64> = rows.iter().map(|r| r.h).collect();
    let fit = |f: fn(&StudyRow) -> f64| fitted_order(&h, &rows.iter().map(f).collect::<Vec<_>>());
    let o = [fit(|r| r.nodes_max), fit(|r| r.global_max), fit(|r| r.l2)];
    println!(
        "  fitted orders: nodes {:.2}, global {:.2}, l2 {:.2}",
        o[0], o[1], o[2]
    );
    (rows, o)
}
