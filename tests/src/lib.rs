//! Shared helpers for radcol's cross-crate tests.

use radcol_core::alpha0::auto_alpha;
use radcol_core::assembly::CpuBackend;
use radcol_core::geometry::shapes::{box_room, ellipsoid, sphere};
use radcol_core::problem::{Field, Problem};
use radcol_core::run::SolveConfig;
use radcol_core::study::{fitted_order, study, StudyRow};
use std::sync::Arc;

/// The one tolerance check (core's), re-exported for these tests.
pub use radcol_core::testing::assert_close;

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
        // Orders only: the estimate has tests of its own (estimate.rs).
        estimate: false,
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

/// The closed-form problem on the unit sphere: ρ = 0.5 + 0.2x, E = exp(a·P) with
/// a = (0.3, 0.5, 0.8). G ≡ 1/4 gives ∫_S E = 4π sinh|a|/|a|, ∫_S ρ = 2π, so
/// ∫_S u = 2∫E and u = E + 2ρ sinh|a|/|a| exactly.
pub fn sphere_closed_form() -> Problem {
    let mut p = Problem::new(
        Arc::new(sphere(1.0)),
        Field::parse("0.5 + 0.2*x").unwrap(),
        Field::parse("exp(0.3*x + 0.5*y + 0.8*z)").unwrap(),
    );
    let a = (0.3f64 * 0.3 + 0.5 * 0.5 + 0.8 * 0.8).sqrt();
    let c = 2.0 * a.sinh() / a;
    p.exact = Some(
        Field::parse(&format!(
            "exp(0.3*x + 0.5*y + 0.8*z) + (0.5 + 0.2*x)*{c:.17e}"
        ))
        .unwrap(),
    );
    p
}

/// The manufactured problem on the ellipsoid (1, 1.3, 0.8): ρ = 0.4 +
/// 0.1x − 0.1z, u = exp(0.3x + 0.5y + 0.8z), E = u − K u with K u from the
/// reference operator (tolerance 1e-14 on a fixed mesh of level 2).
pub fn ellipsoid_manufactured() -> Problem {
    let surface = Arc::new(ellipsoid(1.0, 1.3, 0.8));
    Problem::manufactured(
        surface.clone(),
        Field::parse("0.4 + 0.1*x - 0.1*z").unwrap(),
        Field::parse("exp(0.3*x + 0.5*y + 0.8*z)").unwrap(),
        radcol_core::problem::ReferenceOperator::new(surface, 2),
    )
}

/// One small problem per built-in shape for solver and backend agreement:
/// (name, problem, degree r, level), with ρ = 0.7 - 0.1z², E = 1 + xy.
pub fn mixed_problems() -> Vec<(String, Problem, usize, u32)> {
    [
        (Arc::new(sphere(1.0)), 2usize, 1u32),
        (Arc::new(ellipsoid(1.0, 1.5, 0.8)), 1, 2),
        (Arc::new(box_room(1.0, 2.0, 1.5)), 3, 1),
    ]
    .into_iter()
    .map(|(surface, r, level)| {
        let name = surface.name.clone();
        let problem = Problem::new(
            surface,
            Field::parse("0.7 - 0.1*z^2").unwrap(),
            Field::parse("1 + x*y").unwrap(),
        );
        (name, problem, r, level)
    })
    .collect()
}

/// ‖a - b‖ / ‖b‖.
pub fn rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let num: f64 = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt();
    let den: f64 = b.iter().map(|y| y * y).sum::<f64>().sqrt();
    num / den
}

/// Index of the collocation node at `x` (to 1e-12 of the scene size).
pub fn node_at(out: &radcol_core::run::SolveOutcome, x: glam::DVec3, scale: f64) -> usize {
    let pts = out.discretization.points();
    let (i, d) = pts
        .iter()
        .enumerate()
        .map(|(i, p)| (i, (p.position - x).length()))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap();
    assert!(d <= 1e-12 * scale, "no node at {x} (nearest {d:.3e} away)");
    i
}

/// Checks u(m(P)) = u(P) for every node P and every channel, where `m` maps
/// the node set onto itself.
#[track_caller]
pub fn assert_symmetric(
    out: &radcol_core::run::SolveOutcome,
    m: impl Fn(glam::DVec3) -> glam::DVec3,
    what: &str,
    tol: f64,
) {
    let mut worst = 0.0f64;
    for (i, p) in out.discretization.points().iter().enumerate() {
        let j = node_at(out, m(p.position), 1.0);
        for ch in &out.channels {
            let (a, b) = (ch.solution.nodal()[i], ch.solution.nodal()[j]);
            worst = worst.max((a - b).abs() / a.abs().max(1e-300));
            assert!(
                (a - b).abs() <= tol * a.abs(),
                "{what}, channel {}: u = {a} at {} but {b} at its image {}",
                ch.name,
                p.position,
                out.discretization.points()[j].position
            );
        }
    }
    println!("{what}: max relative asymmetry {worst:.2e}");
}

/// Degree `degree` on level `level`, dense LU, element integrals to 1e-13:
/// the configuration of the scene and visibility identities.
pub fn lu_config(degree: usize, level: u32) -> SolveConfig {
    SolveConfig {
        degree,
        level,
        solver: radcol_core::run::SolverKind::Lu,
        quad: radcol_core::assembly::QuadratureOptions {
            tol: 1e-13,
            ..Default::default()
        },
        ..Default::default()
    }
}

/// Max over nodes and channels of |a − b| relative to max |b| (per
/// channel's largest value): how far two solves of one discretization
/// differ.
pub fn max_rel_nodal(
    a: &radcol_core::run::SolveOutcome,
    b: &radcol_core::run::SolveOutcome,
) -> f64 {
    let mut worst = 0.0f64;
    for (ca, cb) in a.channels.iter().zip(&b.channels) {
        let (ua, ub) = (ca.solution.nodal(), cb.solution.nodal());
        let scale = ub.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (x, y) in ua.iter().zip(ub) {
            worst = worst.max((x - y).abs() / scale);
        }
    }
    worst
}
