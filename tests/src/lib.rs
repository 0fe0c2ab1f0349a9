//! Shared helpers for radcol's cross-crate tests.

use radcol_core::alpha0::auto_alpha;
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

/// Runs a study of `problem` at degree `r` (α = auto) over `levels` and checks
/// the theory: fitted global order within 0.3 of r + 1 (eq. 23); fitted node
/// order at least r + 3 - 0.3 for odd r at α0 (36), r + 2 - 0.3 for even r (39)
/// (lower bounds: on closed surfaces the leading node term largely cancels).
pub fn assert_orders(
    label: &str,
    problem: &Problem,
    r: usize,
    levels: std::ops::RangeInclusive<u32>,
) {
    let cfg = SolveConfig {
        degree: r,
        alpha: auto_alpha(r),
        ..Default::default()
    };
    println!("{label} r = {r}, alpha = {}", cfg.alpha);
    let (rows, [nodes, global, _l2]) = orders(problem, &cfg, levels);
    let theory_global = (r + 1) as f64;
    assert!(
        (global - theory_global).abs() <= 0.3,
        "{label} r = {r}: fitted global order {global:.3}, theory {theory_global}"
    );
    let theory_nodes = if r % 2 == 1 { r + 3 } else { r + 2 } as f64;
    assert!(
        nodes >= theory_nodes - 0.3,
        "{label} r = {r}: fitted node order {nodes:.3} below theory {theory_nodes}"
    );
    // Superconvergence (24): the node error is far below the global error.
    let last = rows.last().expect("at least one level");
    assert!(last.nodes_max < 1e-2 * last.global_max);
}
