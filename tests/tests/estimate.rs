//! The a posteriori estimate η = E + K u_n - u_n (crate `radcol_core::estimate`)
//! against the true error, on every case with an exact answer: effectivity
//! (estimate / true), in max over the whole surface (the lattice of every
//! element, vertices and edges included) and in L², lies in [0.3, 3] at every
//! level and degree tested. The shadowed family is in `shadows.rs`.

use radcol_core::alpha0::auto_alpha;
use radcol_core::assembly::CpuBackend;
use radcol_core::geometry::shapes::box_room;
use radcol_core::problem::{Field, Problem, ReferenceOperator};
use radcol_core::run::{solve, SolveConfig};
use radcol_tests::{ellipsoid_manufactured, sphere_closed_form};
use std::sync::Arc;

/// Solves `problem` at each (r, level) and checks both effectivities.
fn check_effectivity(label: &str, problem: &Problem, cases: &[(usize, u32)]) {
    for &(r, level) in cases {
        let cfg = SolveConfig {
            degree: r,
            alpha: auto_alpha(r),
            level,
            ..Default::default()
        };
        let out = solve(problem, &cfg, &CpuBackend).expect("solves");
        let ch = &out.channels[0];
        let err = ch.errors.expect("exact solution known");
        let est = ch.estimate.as_ref().expect("estimated by default");
        let eff_max = est.max / err.global_max;
        let eff_l2 = est.l2 / err.l2;
        println!(
            "{label} r = {r} level {level}: N = {:6}, true max {:.3e} L2 {:.3e}, \
             estimate max {:.3e} L2 {:.3e}, effectivity max {eff_max:.3} L2 {eff_l2:.3}",
            out.discretization.len(),
            err.global_max,
            err.l2,
            est.max,
            est.l2
        );
        for (what, eff) in [("max", eff_max), ("L2", eff_l2)] {
            assert!(
                (0.3..=3.0).contains(&eff),
                "{label} r = {r} level {level}: {what} effectivity {eff:.3} outside [0.3, 3]"
            );
        }
    }
}

#[test]
fn estimate_tracks_the_error_on_the_sphere() {
    let cases = [
        (0, 1),
        (0, 2),
        (0, 3),
        (1, 1),
        (1, 2),
        (1, 3),
        (2, 1),
        (2, 2),
        (3, 1),
        (3, 2),
    ];
    check_effectivity("sphere", &sphere_closed_form(), &cases);
}

#[test]
fn estimate_tracks_the_error_on_the_manufactured_ellipsoid() {
    check_effectivity(
        "ellipsoid",
        &ellipsoid_manufactured(),
        &[(0, 1), (0, 2), (1, 1), (1, 2), (2, 1)],
    );
}

/// The box room (edges where the walls meet at 90°: K is not compact there,
/// but E manufactured from a smooth u keeps u smooth).
#[test]
fn estimate_tracks_the_error_on_the_manufactured_box() {
    let surface = Arc::new(box_room(1.0, 2.0, 1.5));
    let problem = Problem::manufactured(
        surface.clone(),
        Field::parse("0.6 - 0.1*z").unwrap(),
        Field::parse("1 + 0.5*sin(x + 0.7*y) + 0.3*z*z").unwrap(),
        ReferenceOperator::new(surface, 2),
    );
    check_effectivity(
        "box",
        &problem,
        &[(0, 0), (0, 1), (0, 2), (1, 0), (1, 1), (2, 0), (2, 1)],
    );
}

/// The reflected light's scale is max over the nodes of u_n − E. On the
/// sphere u − E = (0.5 + 0.2 x) c with c = 2 sinh(a)/a (the closed form),
/// so it is that maximum over the node positions, to within the solution's
/// max error at the nodes.
#[test]
fn the_reflected_scale_is_the_closed_forms_at_the_nodes() {
    let problem = sphere_closed_form();
    let a = (0.3f64 * 0.3 + 0.5 * 0.5 + 0.8 * 0.8).sqrt();
    let c = 2.0 * a.sinh() / a;
    for (r, level) in [(1, 1), (2, 2)] {
        let cfg = SolveConfig {
            degree: r,
            alpha: auto_alpha(r),
            level,
            ..Default::default()
        };
        let out = solve(&problem, &cfg, &CpuBackend).expect("solves");
        let ch = &out.channels[0];
        let est = ch.estimate.as_ref().expect("estimated by default");
        let exact = out
            .discretization
            .points()
            .iter()
            .map(|p| (0.5 + 0.2 * p.position.x) * c)
            .fold(f64::MIN, f64::max);
        let nodal_error = ch.errors.expect("exact solution known").nodes_max;
        let d = (est.reflected_scale - exact).abs();
        println!(
            "r = {r} level {level}: reflected {} against {exact}, nodal error {nodal_error:.3e}",
            est.reflected_scale
        );
        // |max(a + e) − max a| ≤ max |e|, to rounding.
        assert!(
            d <= nodal_error + 1e-12 * exact,
            "r = {r} level {level}: {} against {exact}",
            est.reflected_scale
        );
        let rel = est.max_rel_reflected().expect("light is reflected");
        assert_eq!(rel, est.max / est.reflected_scale);
        assert!(
            rel > est.max_rel,
            "the reflected light is the smaller scale here"
        );
    }
}
