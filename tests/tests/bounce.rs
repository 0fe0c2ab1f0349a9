//! Approximate visibility of the bounce pairs against exact visibility: on
//! the Cornell box, the shadow scene (its occluder grey) and a room with a 200-triangle bunny,
//! the solution with the partly visible pairs of small unoccluded mass
//! approximated by rays differs from the exactly clipped one, at the nodes
//! and on every element's lattice (vertices, edges, interiors), by no more
//! than the bound the approximate run adds to its estimate; exact runs add
//! nothing. The independent reference is the exact solve (clipping, its own
//! tests in `visibility.rs`).

use radcol_core::assembly::CpuBackend;
use radcol_core::norms::LATTICE;
use radcol_core::run::{solve, SolveConfig, SolveOutcome};
use radcol_core::scene::{builtin, load_obj, Scene};

/// The largest difference of two solutions on one mesh, at the nodes and
/// on each element's lattice.
fn largest_difference(a: &SolveOutcome, b: &SolveOutcome, c: usize) -> f64 {
    let (a, b) = (&a.channels[c].solution, &b.channels[c].solution);
    let nodal = a
        .nodal()
        .iter()
        .zip(b.nodal())
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    let n = a.discretization().mesh().len();
    let step = 1.0 / LATTICE as f64;
    let mut most = nodal;
    for k in 0..n {
        for i in 0..=LATTICE {
            for j in 0..=LATTICE - i {
                let (s, t) = (i as f64 * step, j as f64 * step);
                most = most.max((a.eval(k, s, t) - b.eval(k, s, t)).abs());
            }
        }
    }
    most
}

/// Solves `scene` exactly and with `budget`, and checks the difference
/// against the approximate run's bound in every channel.
fn within_bound(name: &str, scene: &Scene, cfg: SolveConfig, budget: f64) {
    let problem = scene.problem();
    let exact = solve(&problem, &cfg, &CpuBackend).expect("exact solve");
    let mut loose = cfg.clone();
    loose.quad.visibility_budget = budget;
    let approx = solve(&problem, &loose, &CpuBackend).expect("approximate solve");
    assert_eq!(exact.plan.pairs_approximate, 0, "{name}");
    assert!(
        approx.plan.pairs_approximate > 0,
        "{name}: nothing approximated"
    );
    // The recorded bound exceeds the budget only by its rounding up (f32
    // storage, the integral's tolerance: a few 1e-6).
    let b = approx.plan.visibility_bound;
    assert!(b <= budget * (1.0 + 1e-5), "{name}: {b} > {budget}");
    for c in 0..problem.channels.len() {
        let e = exact.channels[c].estimate.as_ref().expect("estimated");
        let a = approx.channels[c].estimate.as_ref().expect("estimated");
        assert_eq!(e.visibility_bound, 0.0, "{name}");
        let diff = largest_difference(&exact, &approx, c);
        println!(
            "{name} channel {c}: {} of {} partly visible pairs approximated, difference {diff:.3e}, bound {:.3e} ({:.1e} of max|u|)",
            approx.plan.pairs_approximate,
            approx.plan.pairs_partial,
            a.visibility_bound,
            a.visibility_bound / a.scale
        );
        assert!(a.visibility_bound > 0.0, "{name}");
        assert!(
            diff <= a.visibility_bound,
            "{name} channel {c}: {diff} > {}",
            a.visibility_bound
        );
        // The bound is part of what is reported.
        assert!(a.max >= a.visibility_bound, "{name}");
    }
}

#[test]
fn the_cornell_box_approximated_stays_within_its_bound() {
    let scene = builtin("cornell").unwrap().unwrap();
    let cfg = SolveConfig {
        level: 0,
        max_edge: Some(100.0),
        ..SolveConfig::default()
    };
    within_bound("cornell", &scene, cfg, 1e-2);
}

/// The shadow scene with a grey occluder instead of its black one (black,
/// its bounce pairs carry u = 0 and no approximation can change anything).
/// Its approximated pairs (the occluder's points against far floor
/// elements) are fully visible: the rays find that, and the difference is
/// nil; the big pairs under the occluder hold too much of the view and stay
/// exact.
#[test]
fn the_shadow_scene_approximated_stays_within_its_bound() {
    let mut scene = builtin("shadow").unwrap().unwrap();
    for m in scene.materials.iter_mut().filter(|m| m.name == "occluder") {
        m.rho = [0.5; 3];
    }
    let cfg = SolveConfig {
        level: 0,
        max_edge: Some(0.25 * scene.diagonal()),
        ..SolveConfig::default()
    };
    within_bound("shadow", &scene, cfg, 3e-2);
}

#[test]
fn a_bunny_room_approximated_stays_within_its_bound() {
    let path = format!(
        "{}/../benches/data/bunny_room_200.obj",
        env!("CARGO_MANIFEST_DIR")
    );
    let scene = load_obj(std::path::Path::new(&path)).unwrap();
    let cfg = SolveConfig {
        level: 0,
        ..SolveConfig::default()
    };
    within_bound("bunny room (200 triangles)", &scene, cfg, 1e-2);
}

/// The budget is refused outside [0, 1).
#[test]
fn a_budget_outside_the_unit_interval_is_refused() {
    let scene = builtin("cornell").unwrap().unwrap();
    let mut cfg = SolveConfig {
        level: 0,
        ..SolveConfig::default()
    };
    for bad in [1.0, -1e-3, f64::NAN] {
        cfg.quad.visibility_budget = bad;
        let err = solve(&scene.problem(), &cfg, &CpuBackend).unwrap_err();
        assert!(
            err.to_string()
                .contains(&format!("visibility budget {bad}")),
            "{err}"
        );
    }
}

/// An adaptive solve keeps the approximation's bound within a quarter of
/// its target through the steps that reuse the previous plans (the pairs
/// kept from them count against each point's budget), and reports the
/// bound in what it compares with the target.
#[test]
fn an_adaptive_solve_keeps_the_bound_within_a_quarter_of_the_target() {
    use radcol_core::run::adapt::{solve_adaptive, AdaptOptions};
    let scene = builtin("cornell").unwrap().unwrap();
    let mut cfg = scene.solve_config(true);
    cfg.quad.visibility_budget = radcol_core::run::DEFAULT_VISIBILITY_BUDGET;
    let target = 1e-2;
    let opts = AdaptOptions {
        target,
        ..AdaptOptions::default()
    };
    let res = solve_adaptive(&scene.problem(), &cfg, &opts, &CpuBackend, |_| {}).unwrap();
    assert!(res.steps.len() > 1, "{} steps", res.steps.len());
    assert!(res.outcome.plan.pairs_approximate > 0);
    for c in &res.outcome.channels {
        let e = c.estimate.as_ref().unwrap();
        let bound = e.visibility_bound / e.scale;
        println!(
            "cornell to {target}: {} steps, bound {bound:.2e} of max|u|",
            res.steps.len()
        );
        assert!(
            bound > 0.0 && bound <= target / 4.0 * (1.0 + 1e-5),
            "{bound}"
        );
        assert!(e.shown_max_rel() >= bound);
    }
    let last = res.steps.last().unwrap();
    let bound = res.outcome.channels[0].estimate.as_ref().unwrap();
    assert!(last.estimate_elsewhere >= bound.visibility_bound / bound.scale);
}
