//! Built-in scenes solved end to end, checked against symmetries and the
//! scale invariance of radiosity (G dS is dimensionless).

use glam::DVec3;
use radcol_core::assembly::CpuBackend;
use radcol_core::run::{solve, SolveConfig, SolveOutcome};
use radcol_core::scene::{builtin, Material, Scene};
use radcol_tests::assert_symmetric;

fn cfg(degree: usize, level: u32) -> SolveConfig {
    radcol_tests::lu_config(degree, level)
}

fn run(scene: &Scene, cfg: &SolveConfig) -> SolveOutcome {
    solve(&scene.problem(), cfg, &CpuBackend).unwrap()
}

/// Two facing squares, triangulated along the diagonal x = y and mirror
/// images of each other: the solution is symmetric under x ↔ y; with both
/// plates emitting alike it is also symmetric under z ↔ 1 - z.
#[test]
fn symmetric_scenes_give_symmetric_radiosity() {
    let plates = builtin("plates").unwrap().unwrap();
    for (r, level) in [(1, 2), (2, 1)] {
        let out = run(&plates, &cfg(r, level));
        assert_symmetric(
            &out,
            |x| DVec3::new(x.y, x.x, x.z),
            &format!("plates r={r}: x <-> y"),
            1e-12,
        );
        let u = out.channels[0].solution.nodal();
        assert!(u.iter().all(|&v| v > 0.0));
    }

    let mut both = plates.clone();
    let light = both.materials.iter().position(|m| m.is_emitter()).unwrap();
    let white = 1 - light;
    both.materials[white] = Material::emitter("white", both.materials[white].rho, [1.0; 3]);
    assert_eq!(both.materials[white].rho, both.materials[light].rho);
    let out = run(&both, &cfg(1, 2));
    assert_symmetric(
        &out,
        |x| DVec3::new(x.x, x.y, 1.0 - x.z),
        "plates, both emitting: z <-> 1 - z",
        1e-12,
    );
}

/// Scaling a scene by 1e-3 or 1e3 changes no radiosity: the kernel G dS is
/// dimensionless and every tolerance in radcol is relative to the scene. The
/// Cornell box exercises the occluded path (clipping, BVH, SAT tolerances).
#[test]
fn radiosity_does_not_depend_on_units() {
    let cornell = builtin("cornell").unwrap().unwrap();
    let config = cfg(1, 0);
    let reference = run(&cornell, &config);
    for factor in [1e-3, 1e3] {
        let scaled = run(&cornell.scaled(factor), &config);
        assert_eq!(scaled.plan.pairs_partial, reference.plan.pairs_partial);
        assert_eq!(scaled.plan.pairs_culled, reference.plan.pairs_culled);
        let mut worst = 0.0f64;
        for (a, b) in reference.channels.iter().zip(&scaled.channels) {
            for (i, (&x, &y)) in a
                .solution
                .nodal()
                .iter()
                .zip(b.solution.nodal())
                .enumerate()
            {
                let rel = (x - y).abs() / x.abs();
                worst = worst.max(rel);
                assert!(
                    rel <= 1e-12,
                    "scale {factor}, channel {}, node {i}: {x} vs {y} (relative {rel:.3e})",
                    a.name
                );
            }
        }
        println!("scale {factor}: max relative change {worst:.2e}");
    }
}
