//! A small shadow inside a large element: a small occluder close to the
//! floor of the shadow family casts a shadow far smaller than the floor's
//! first elements, which the check points of the error estimate can miss
//! (the estimate's shadow probes look for it: `radcol_core::run`, the
//! estimate stage). The exact u on the floor is Lambert's contour formula
//! (`crate::shadows::floor_u`).

use crate::shadows::{floor_u, problem_on, Case};
use glam::DVec3;
use radcol_core::alpha0::auto_alpha;
use radcol_core::assembly::CpuBackend;
use radcol_core::geometry::shapes::floor_under_occluder;
use radcol_core::query::{query, QueryPoint, DEFAULT_SNAP};
use radcol_core::run::adapt::{solve_adaptive, AdaptOptions, StopReason};
use radcol_core::run::SolveConfig;
use std::sync::Arc;

fn square(cx: f64, cy: f64, h: f64, z: f64) -> Vec<DVec3> {
    vec![
        DVec3::new(cx - h, cy - h, z),
        DVec3::new(cx + h, cy - h, z),
        DVec3::new(cx + h, cy + h, z),
        DVec3::new(cx - h, cy + h, z),
    ]
}

/// Square occluders of half-sides 0.04, 0.025 and 0.015 at heights 0.05,
/// 0.03 and 0.02 under the shadow family's emitter (side 1 at 0.6), over a
/// floor of side 2 that starts as two triangles: shadows 50 to 20 times
/// smaller than the elements the loop starts from. On a 9 × 9 grid over
/// each shadow, u_n lies within 1.5 times its element's estimate,
/// and where the loop says it reached the target, within 1.5 times the
/// target. Before the probes, the loop reported 3e-2 reached with u_n off
/// by 0.13 in the first shadow, and 1e-2 with 5.9e-2 in the second.
#[test]
fn a_small_shadow_inside_a_large_element_is_within_the_estimate() {
    let cfg = SolveConfig {
        degree: 1,
        alpha: auto_alpha(1),
        level: 0,
        ..Default::default()
    };
    for (h, z) in [(0.04, 0.05), (0.025, 0.03), (0.015, 0.02)] {
        let case = Case {
            name: "small occluder near the floor",
            emitter: square(0.0, 0.0, 0.5, 0.6),
            occluder: square(0.55, -0.45, h, z),
        };
        let surface = floor_under_occluder(&case.emitter, &case.occluder);
        let problem = problem_on(&case, Arc::new(surface));
        let pts: Vec<QueryPoint> = (0..81)
            .map(|ij| {
                let (i, j) = ((ij / 9) as f64 - 4.0, (ij % 9) as f64 - 4.0);
                let at = DVec3::new(0.55 + 0.625 * h * i, -0.45 + 0.625 * h * j, 0.0);
                QueryPoint {
                    position: at,
                    normal: Some(DVec3::Z),
                }
            })
            .collect();
        for target in [3e-2, 1e-2] {
            let opts = AdaptOptions {
                target,
                ..Default::default()
            };
            let res = solve_adaptive(&problem, &cfg, &opts, &CpuBackend, |_| {}).expect("solves");
            let values =
                query(&problem, &res.outcome, cfg.quad.clone(), &pts, DEFAULT_SNAP).expect("on S");
            let est = res.outcome.channels[0]
                .estimate
                .as_ref()
                .expect("estimated");
            let (mut worst, mut ratio) = (0.0f64, 0.0f64);
            for (v, q) in values.iter().zip(&pts) {
                let err = (v.channels[0].u - floor_u(&case, q.position)).abs();
                worst = worst.max(err);
                let figure = est.elements[v.located.element] + est.visibility_bound;
                ratio = ratio.max(err / figure);
            }
            let last = res.steps.last().unwrap();
            println!(
                "occluder {h} at {z}, target {target:.0e}: {:?} after {} steps, {} unknowns, \
                 estimate {:.3e}; in the shadow max |u_n - u| {worst:.3e}, at most {ratio:.2} \
                 times its element's estimate",
                res.stop,
                res.steps.len(),
                last.unknowns,
                last.estimate
            );
            assert!(
                ratio <= 1.5,
                "{h} at {z}, {target:e}: error/estimate {ratio:.2}"
            );
            if res.stop == StopReason::Reached {
                assert!(worst <= 1.5 * target, "{h} at {z}, {target:e}: {worst:.3e}");
            }
        }
    }
}
