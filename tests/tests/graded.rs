//! A graded start (`AdaptOptions::graded_start`): elements of the starting
//! mesh that are small against the scene start at a lower degree than the
//! configured one. On the shadow family (u known everywhere: Lambert's
//! contour formula on the floor, 1 on the emitter, 0 on the occluder) with
//! the emitter and the occluder cut into small triangles, as a scanned
//! object's are, and the floor left whole.

use crate::shadows::{cases, problem_on};
use radcol_core::alpha0::auto_alpha;
use radcol_core::assembly::CpuBackend;
use radcol_core::geometry::shapes::floor_under_occluder;
use radcol_core::geometry::Surface;
use radcol_core::run::adapt::{solve_adaptive, AdaptOptions, AdaptStep, StopReason};
use radcol_core::run::{start_degree, SolveConfig};
use std::sync::Arc;

/// Each triangle cut 4:1 `times` times at its edges' midpoints.
fn cut(triangles: &[[glam::DVec3; 3]], times: u32) -> Vec<[glam::DVec3; 3]> {
    let mut t = triangles.to_vec();
    for _ in 0..times {
        t = t
            .iter()
            .flat_map(|&[a, b, c]| {
                let (ab, bc, ca) = ((a + b) / 2.0, (b + c) / 2.0, (c + a) / 2.0);
                [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
            })
            .collect();
    }
    t
}

/// The run to `target` at r = 2 from the surface's own triangles, graded
/// or not: every step, and the reason it stopped.
fn run(surface: &Arc<Surface>, graded: bool, target: f64) -> (Vec<AdaptStep>, StopReason) {
    let case = &cases()[0];
    let cfg = SolveConfig {
        degree: 2,
        alpha: auto_alpha(2),
        level: 0,
        ..Default::default()
    };
    let opts = AdaptOptions {
        target,
        graded_start: graded,
        ..Default::default()
    };
    let p = problem_on(case, surface.clone());
    let res = solve_adaptive(&p, &cfg, &opts, &CpuBackend, |_| {}).expect("solves");
    (res.steps, res.stop)
}

/// The emitter's and the occluder's 128 triangles each (longest edge 0.18
/// and 0.088 against a diagonal of 2.89) start at r = 1 to a target of
/// 1e-2 (the rule's (h/D)² ≤ 1e-2), the floor's two at r = 2; the run
/// reaches the target with its true error (everywhere on the lattice,
/// relative to max u) below it, as the uniform start does, with fewer
/// unknowns at every step: u is constant on the small elements, so nothing
/// there needs the higher degree.
#[test]
fn small_elements_start_lower_and_the_target_is_still_met() {
    let case = &cases()[0];
    let mut surface = floor_under_occluder(&case.emitter, &case.occluder);
    for patch in &mut surface.patches[1..] {
        patch.triangles = cut(&patch.triangles, 3);
    }
    let surface = Arc::new(surface);
    let target = 1e-2;
    let (graded, graded_stop) = run(&surface, true, target);
    let (uniform, uniform_stop) = run(&surface, false, target);
    for (name, steps, stop) in [
        ("graded", &graded, graded_stop),
        ("uniform", &uniform, uniform_stop),
    ] {
        for s in steps.iter() {
            println!(
                "  {name}: {} elements, {} unknowns, degrees {:?}, estimate {:.3e}, true {:.3e}",
                s.elements,
                s.unknowns,
                s.degrees,
                s.estimate,
                s.true_error.unwrap()
            );
        }
        assert_eq!(stop, StopReason::Reached, "{name}");
        let last = steps.last().unwrap();
        let true_err = last.true_error.unwrap();
        assert!(true_err <= target, "{name}: true error {true_err:.3e}");
        assert!(
            last.estimate >= 0.5 * true_err,
            "{name}: estimate {:.3e} against {true_err:.3e}",
            last.estimate
        );
    }
    assert_eq!(graded[0].degrees, vec![0, 256, 2], "the start's degrees");
    assert_eq!(uniform[0].degrees, vec![0, 0, 258]);
    assert_eq!(graded[0].unknowns, 256 * 3 + 2 * 6);
    let last = |s: &[AdaptStep]| s.last().unwrap().unknowns;
    assert!(
        last(&graded) < last(&uniform),
        "graded {} unknowns against uniform {}",
        last(&graded),
        last(&uniform)
    );
}

/// The rule itself: the lowest r with (h/D)^{r+1} within the target, the
/// configured degree when none is, and for a size that is not a number.
#[test]
fn start_degree_rule() {
    assert_eq!(start_degree(5.0, 1000.0, 1e-2, 2), 0);
    assert_eq!(start_degree(50.0, 1000.0, 1e-2, 2), 1);
    assert_eq!(start_degree(50.0, 1000.0, 1e-3, 2), 2);
    assert_eq!(start_degree(300.0, 1000.0, 1e-2, 2), 2);
    assert_eq!(start_degree(300.0, 1000.0, 1e-2, 4), 3);
    assert_eq!(start_degree(f64::NAN, 1000.0, 1e-2, 2), 2);
    assert_eq!(start_degree(1.0, 0.0, 1e-2, 2), 2);
}
