//! Discontinuity meshing against adaptive refinement, on the shadowed family
//! (`shadows.rs`: exact answers from Lambert's contour formula).
//!
//! Across the lines where the part of the emitter a floor point sees
//! changes combinatorially, u is less smooth than elsewhere (its gradient
//! jumps where an occluder edge is parallel to an emitter edge, its second
//! derivatives elsewhere: Heckbert 1992, Lischinski et al. 1992). On a floor
//! under a horizontal emitter and occluder these lines are straight: the
//! shadow of each occluder edge cast from each emitter vertex (EV) and the
//! shadow of each occluder vertex cast from each emitter edge (VE).
//! Discontinuity meshing triangulates the floor with them as constraints
//! (spade's constrained Delaunay triangulation), so that no element
//! straddles one. Measured here: true max error against unknowns for
//! uniform refinement of the plain floor and of the discontinuity mesh, and
//! adaptive refinement from each.

use crate::shadows::{cases, problem_on, Case};
use glam::DVec3;
use radcol_core::alpha0::auto_alpha;
use radcol_core::assembly::CpuBackend;
use radcol_core::geometry::shapes::floor_under_occluder;
use radcol_core::geometry::Surface;
use radcol_core::run::adapt::{solve_adaptive, AdaptOptions};
use radcol_core::run::{solve, SolveConfig};
use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation};
use std::sync::Arc;

/// `x` seen from `from` on the floor z = 0.
fn cast(from: DVec3, x: DVec3) -> [f64; 2] {
    let p = from + (x - from) * (from.z / (from.z - x.z));
    [p.x, p.y]
}

/// The segment ab clipped to the floor square [-1, 1]² (Liang–Barsky).
fn clip([a, b]: [[f64; 2]; 2]) -> Option<[[f64; 2]; 2]> {
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    let d = [b[0] - a[0], b[1] - a[1]];
    for axis in 0..2 {
        for (p, q) in [(-d[axis], a[axis] + 1.0), (d[axis], 1.0 - a[axis])] {
            if p == 0.0 {
                if q < 0.0 {
                    return None;
                }
            } else {
                let r = q / p;
                if p < 0.0 {
                    t0 = t0.max(r);
                } else {
                    t1 = t1.min(r);
                }
            }
        }
    }
    let at = |t: f64| [a[0] + t * d[0], a[1] + t * d[1]];
    (t1 - t0 > 1e-12).then(|| [at(t0), at(t1)])
}

/// The EV and VE lines of `case` on the floor, clipped to it.
fn critical_segments(case: &Case) -> Vec<[[f64; 2]; 2]> {
    let (e, o) = (&case.emitter, &case.occluder);
    let mut out = Vec::new();
    for i in 0..e.len() {
        for j in 0..o.len() {
            let (o1, o2) = (o[j], o[(j + 1) % o.len()]);
            out.push([cast(e[i], o1), cast(e[i], o2)]);
            let (e1, e2) = (e[i], e[(i + 1) % e.len()]);
            out.push([cast(e1, o[j]), cast(e2, o[j])]);
        }
    }
    out.into_iter().filter_map(clip).collect()
}

/// The family's surface with the floor triangulated along its critical
/// lines.
fn discontinuity_meshed(case: &Case) -> Surface {
    let mut cdt = ConstrainedDelaunayTriangulation::<Point2<f64>>::new();
    let corners = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];
    let v: Vec<_> = corners
        .iter()
        .map(|c| cdt.insert(Point2::new(c[0], c[1])).unwrap())
        .collect();
    for k in 0..4 {
        cdt.add_constraint(v[k], v[(k + 1) % 4]);
    }
    // Endpoints cast from different vertices that are one point in exact
    // arithmetic differ in the last bits: snapped to a 1e-12 grid they are
    // one vertex, not a sliver.
    let snap =
        |x: [f64; 2]| Point2::new((x[0] * 1e12).round() / 1e12, (x[1] * 1e12).round() / 1e12);
    for [a, b] in critical_segments(case) {
        let va = cdt.insert(snap(a)).unwrap();
        let vb = cdt.insert(snap(b)).unwrap();
        if va != vb {
            cdt.add_constraint_and_split(va, vb, |x| x);
        }
    }
    let floor: Vec<[DVec3; 3]> = cdt
        .inner_faces()
        .map(|f| {
            f.vertices().map(|v| {
                let p = v.position();
                DVec3::new(p.x, p.y, 0.0)
            })
        })
        .collect();
    let mut s = floor_under_occluder(&case.emitter, &case.occluder);
    s.patches[0].triangles = floor;
    s
}

fn cfg(level: u32) -> SolveConfig {
    SolveConfig {
        degree: 1,
        alpha: auto_alpha(1),
        level,
        ..Default::default()
    }
}

/// (unknowns, true max error / max u) of a uniform solve.
fn uniform(case: &Case, surface: Surface, level: u32) -> (usize, f64) {
    let out = solve(
        &problem_on(case, Arc::new(surface)),
        &cfg(level),
        &CpuBackend,
    )
    .unwrap();
    let ch = &out.channels[0];
    let scale = ch.estimate.as_ref().unwrap().scale;
    (
        out.discretization.len(),
        ch.errors.unwrap().global_max / scale,
    )
}

/// The discontinuity mesh is a triangulation of the floor: its area is the
/// floor's, its triangles face up, and no critical line passes through an
/// element's interior.
#[test]
fn discontinuity_mesh_follows_the_critical_lines() {
    for case in cases() {
        let s = discontinuity_meshed(&case);
        let floor = &s.patches[0].triangles;
        let area: f64 = floor
            .iter()
            .map(|[a, b, c]| 0.5 * (*b - *a).cross(*c - *a).z)
            .sum();
        radcol_tests::assert_close("floor area", 0, area, 4.0, 1e-12);
        assert!(floor
            .iter()
            .all(|[a, b, c]| (*b - *a).cross(*c - *a).z > 0.0));
        let lines = critical_segments(&case);
        // No critical segment passes through an element's interior (checked
        // at 199 points of each segment, strictly inside by 1e-9).
        let inside = |t: &[DVec3; 3], x: [f64; 2]| {
            let cross =
                |a: DVec3, b: DVec3| (b.x - a.x) * (x[1] - a.y) - (b.y - a.y) * (x[0] - a.x);
            (0..3).all(|i| cross(t[i], t[(i + 1) % 3]) > 1e-9)
        };
        for [p, q] in &lines {
            for k in 1..200 {
                let f = k as f64 / 200.0;
                let x = [p[0] + f * (q[0] - p[0]), p[1] + f * (q[1] - p[1])];
                if let Some(t) = floor.iter().find(|t| inside(t, x)) {
                    panic!("{}: {t:?} straddles {p:?}-{q:?} at {x:?}", case.name);
                }
            }
        }
        println!(
            "{}: {} critical segments, {} floor triangles",
            case.name,
            lines.len(),
            floor.len()
        );
    }
}

/// The measurement (a few minutes):
///
///     cargo test --release -p radcol-tests --test integration discontinuity::study -- --ignored --nocapture
#[test]
#[ignore]
fn study() {
    for case in cases() {
        println!("{}", case.name);
        for level in 1..=4 {
            let plain = floor_under_occluder(&case.emitter, &case.occluder);
            let (n, e) = uniform(&case, plain, level);
            println!("  uniform, plain floor, level {level}: {n} unknowns, true {e:.3e}");
        }
        for level in 0..=3 {
            let (n, e) = uniform(&case, discontinuity_meshed(&case), level);
            println!("  uniform, discontinuity mesh, level {level}: {n} unknowns, true {e:.3e}");
        }
        for (name, surface, level) in [
            (
                "plain floor, level 1",
                floor_under_occluder(&case.emitter, &case.occluder),
                1,
            ),
            (
                "discontinuity mesh, level 0",
                discontinuity_meshed(&case),
                0,
            ),
        ] {
            for target in [1e-2, 1e-3] {
                let t = std::time::Instant::now();
                let opts = AdaptOptions {
                    target,
                    ..Default::default()
                };
                let p = problem_on(&case, Arc::new(surface.clone()));
                let res = solve_adaptive(&p, &cfg(level), &opts, &CpuBackend, |_| {}).unwrap();
                let last = res.steps.last().unwrap();
                println!(
                    "  adaptive to {target:.0e} from the {name}: {} unknowns, {} steps, true {:.3e}, {:?}, {:.1} s",
                    last.unknowns,
                    res.steps.len(),
                    last.true_error.unwrap(),
                    res.stop,
                    t.elapsed().as_secs_f64()
                );
            }
        }
    }
}
