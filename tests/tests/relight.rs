//! Relighting: a solve's assembled operator solves again for new emission
//! or new reflectance ([`Relighter`]), and the answer is the one a full solve
//! of the new problem gives (its matrix is the same: assembly does not
//! depend on ρ or E), to rounding; a problem on another surface is refused.

use radcol_core::assembly::CpuBackend;
use radcol_core::error::{Error, InputError};
use radcol_core::geometry::shapes::sphere;
use radcol_core::problem::{Field, Problem};
use radcol_core::run::{solve, Relighter, SolveConfig, SolverKind};
use radcol_core::scene::builtin;
use std::sync::Arc;

fn assert_same(what: &str, relit: &[f64], fresh: &[f64]) {
    assert_eq!(relit.len(), fresh.len());
    let scale = fresh.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for (i, (a, b)) in relit.iter().zip(fresh).enumerate() {
        assert!(
            (a - b).abs() <= 1e-13 * scale,
            "{what}: node {i}: {a} against {b}"
        );
    }
}

#[test]
fn relit_solutions_equal_fresh_solves() {
    // A scalar problem by GMRES: new emission, then new reflectance.
    let surface = Arc::new(sphere(1.0));
    let cfg = SolveConfig {
        level: 2,
        estimate: false,
        ..Default::default()
    };
    let first = Problem::new(surface.clone(), Field::Constant(0.5), Field::Constant(1.0));
    let outcome = solve(&first, &cfg, &CpuBackend).unwrap();
    let mut relight = Relighter::new(&outcome, &cfg);
    for (rho, e) in [("0.5", "exp(z)"), ("0.3 + 0.2*x", "1 + y^2")] {
        let p = Problem::new(
            surface.clone(),
            Field::parse(rho).unwrap(),
            Field::parse(e).unwrap(),
        );
        let relit = relight.solve(&p).unwrap();
        let fresh = solve(&p, &cfg, &CpuBackend).unwrap();
        assert_same(
            &format!("ρ = {rho}, E = {e}"),
            relit[0].solution.nodal(),
            fresh.channels[0].solution.nodal(),
        );
        assert_eq!(relit[0].integral_u, fresh.channels[0].integral_u);
    }

    // A scene by LU: the light dimmed and made blue, then the white walls
    // darker; three channels each.
    let scene = builtin("shadow").unwrap().unwrap();
    let cfg = SolveConfig {
        level: 1,
        solver: SolverKind::Lu,
        estimate: false,
        ..Default::default()
    };
    let outcome = solve(&scene.problem(), &cfg, &CpuBackend).unwrap();
    let mut relight = Relighter::new(&outcome, &cfg);
    let mut changed = scene.clone();
    for step in 0..2 {
        for m in &mut changed.materials {
            if step == 0 && m.is_emitter() {
                m.emission = [0.1, 0.2, 0.9];
            } else if step == 1 && !m.is_emitter() {
                m.rho = m.rho.map(|r| 0.5 * r);
            }
        }
        let p = changed.problem();
        let relit = relight.solve(&p).unwrap();
        let fresh = solve(&p, &cfg, &CpuBackend).unwrap();
        for (a, b) in relit.iter().zip(&fresh.channels) {
            assert_same(
                &format!("step {step}, channel {}", a.name),
                a.solution.nodal(),
                b.solution.nodal(),
            );
            assert!(a.solver.condition.is_some());
        }
    }

    // Another surface object, even an equal one, is refused.
    let other = Problem::new(
        Arc::new(sphere(1.0)),
        Field::Constant(0.5),
        Field::Constant(1.0),
    );
    let sphere_outcome = solve(
        &first,
        &SolveConfig {
            level: 0,
            estimate: false,
            ..Default::default()
        },
        &CpuBackend,
    )
    .unwrap();
    let err = Relighter::new(&sphere_outcome, &cfg)
        .solve(&other)
        .unwrap_err();
    assert!(
        matches!(err, Error::Input(InputError::OtherSurface { .. })),
        "{err}"
    );
}
