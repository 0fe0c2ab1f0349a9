//! The Cornell box's radiance u_n/π at the 14 points of an independent path
//! tracer (Mitsuba 3, `tests/data/cornell_points_mitsuba.csv`, its provenance
//! in `../shared/reference/README.md`), against radcol's estimate of its own
//! error there: for each point, |u_n/π - reference|, the element's estimated
//! max error /π and the reference's 3σ, per channel.
//!
//!     cargo run --release -p radcol-benches --example cornell_points [-- TARGET]
//!
//! TARGET (default 1e-2) is `--target-error`'s: adaptive refinement from the
//! scene's 50 triangles.

use glam::DVec3;
use radcol_core::assembly::CpuBackend;
use radcol_core::geometry::barycentric_st;
use radcol_core::mesh::Mesh;
use radcol_core::run::adapt::{solve_adaptive, AdaptOptions};
use radcol_core::run::SolveConfig;
use radcol_core::scene::builtin;
use std::f64::consts::PI;

/// One reference point: label, position, normal, radiance and standard error per channel.
struct RefPoint {
    label: String,
    x: DVec3,
    n: DVec3,
    radiance: [f64; 3],
    stderr: [f64; 3],
}

fn read_points() -> Vec<RefPoint> {
    let text = include_str!("../../tests/data/cornell_points_mitsuba.csv");
    text.lines()
        .skip(1)
        .map(|line| {
            let (label, rest) = line[1..].split_once("\",").expect("quoted label");
            let v: Vec<f64> = rest
                .split(',')
                .map(|s| s.parse().expect("number"))
                .collect();
            RefPoint {
                label: label.to_string(),
                x: DVec3::new(v[0], v[1], v[2]),
                n: DVec3::new(v[3], v[4], v[5]),
                radiance: [v[6], v[7], v[8]],
                stderr: [v[9], v[10], v[11]],
            }
        })
        .collect()
}

/// The element holding `x` on its front side `n` (within 0.5 scene units of
/// its plane, projected onto it), and (s, t) there. The red wall is a
/// non-planar quadrilateral (its x runs from 549.6 to 556): the reference's
/// points on it lie on the path tracer's own triangles, a fraction of a
/// millimetre off radcol's.
fn find(mesh: &Mesh, x: DVec3, n: DVec3) -> Option<(usize, [f64; 2])> {
    (0..mesh.len()).find_map(|k| {
        let [a, b, c] = mesh.vertices(k);
        let normal = mesh.point(k, 1.0 / 3.0, 1.0 / 3.0).normal;
        let off_plane = (x - a).dot(normal).abs();
        if normal.dot(n) < 0.99 || off_plane > 0.5 {
            return None;
        }
        // The reference's coordinates are single precision: project first.
        let on_plane = x - normal * (x - a).dot(normal);
        barycentric_st(a, b, c, on_plane).map(|st| (k, st))
    })
}

fn main() {
    let target: f64 = std::env::args()
        .nth(1)
        .map(|s| s.parse().expect("TARGET is a number"))
        .unwrap_or(1e-2);
    let scene = builtin("cornell").expect("built in").expect("loads");
    let cfg = SolveConfig {
        degree: 1,
        alpha: 1.0 / 6.0,
        level: 0,
        ..Default::default()
    };
    let opts = AdaptOptions {
        target,
        ..Default::default()
    };
    let res = solve_adaptive(&scene.problem(), &cfg, &opts, &CpuBackend, |s| {
        eprintln!(
            "  {} elements, {} unknowns, estimate {:.3e}, {:.1} s",
            s.elements, s.unknowns, s.estimate, s.seconds
        )
    })
    .expect("solves");
    let out = &res.outcome;
    let mesh = out.discretization.mesh();
    println!(
        "target {target:.0e}: {:?} with {} unknowns",
        res.stop,
        out.discretization.len()
    );
    println!(
        "{:<36} {:>3} {:>11} {:>11} {:>10} {:>10} {:>9}",
        "point", "ch", "radcol", "mitsuba", "|diff|", "estimate", "3 sigma"
    );
    let (mut within, mut total) = (0, 0);
    for p in read_points() {
        let Some((k, [s, t])) = find(mesh, p.x, p.n) else {
            println!("{:<36} not on the mesh", p.label);
            continue;
        };
        for (c, ch) in out.channels.iter().enumerate() {
            let u = ch.solution.eval(k, s, t) / PI;
            let est = ch
                .estimate
                .as_ref()
                .map_or(f64::NAN, |e| e.elements[k] / PI);
            let diff = (u - p.radiance[c]).abs();
            let sigma3 = 3.0 * p.stderr[c];
            total += 1;
            if diff <= est + sigma3 {
                within += 1;
            }
            println!(
                "{:<36} {:>3} {:>11.4e} {:>11.4e} {:>10.2e} {:>10.2e} {:>9.1e}",
                p.label, ch.name, u, p.radiance[c], diff, est, sigma3
            );
        }
    }
    println!("{within} of {total} values within the element's estimate + 3 sigma of the reference");
}
