//! The Cornell box's radiance u_n/π at the 14 points of an independent path
//! tracer (Mitsuba 3, `tests/data/cornell_points_mitsuba.csv`, its provenance
//! in `../shared/reference/README.md`), against radcol's estimate of its own
//! error there: for each point, |u_n/π - reference|, the estimated error of
//! u_n at the point /π and the reference's 3σ, per channel; and the same for
//! the iterated solution û_n = E + K u_n at the points with its own estimate
//! (`radcol_core::query`, what `radcol solve --at` prints).
//!
//!     cargo run --release -p radcol-benches --example cornell_points [-- TARGET [DEGREE]]
//!
//! TARGET (default 1e-2) is `--target-error`'s: adaptive refinement from the
//! scene's 50 triangles, at DEGREE (default 2, `radcol solve`'s with a
//! target) and its auto α.

use glam::DVec3;
use radcol_core::assembly::CpuBackend;
use radcol_core::query::{query, QueryPoint, DEFAULT_SNAP};
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

fn main() {
    let target: f64 = std::env::args()
        .nth(1)
        .map(|s| s.parse().expect("TARGET is a number"))
        .unwrap_or(1e-2);
    let degree: usize = std::env::args()
        .nth(2)
        .map(|s| s.parse().expect("DEGREE is 0..=6"))
        .unwrap_or(2);
    let scene = builtin("cornell").expect("built in").expect("loads");
    let cfg = SolveConfig {
        degree,
        alpha: radcol_core::alpha0::auto_alpha(degree),
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
    println!(
        "target {target:.0e}: {:?} with {} unknowns",
        res.stop,
        out.discretization.len()
    );
    println!(
        "{:<36} {:>3} {:>11} {:>11} {:>11} {:>9} {:>9} {:>9} {:>9} {:>8}",
        "point",
        "ch",
        "u_n/pi",
        "iterated/pi",
        "mitsuba",
        "|u_n-ref|",
        "|it-ref|",
        "estimate",
        "it. est.",
        "3 sigma"
    );
    let refs = read_points();
    let pts: Vec<QueryPoint> = refs
        .iter()
        .map(|p| QueryPoint {
            position: p.x,
            normal: Some(p.n),
        })
        .collect();
    let values = query(&scene.problem(), out, cfg.quad.clone(), &pts, DEFAULT_SNAP)
        .expect("every reference point lies on the scene");
    let (mut within, mut within_it, mut total) = (0, 0, 0);
    let (mut rel_u, mut rel_it) = (Vec::new(), Vec::new());
    for (p, v) in refs.iter().zip(&values) {
        for (c, (ch, val)) in out.channels.iter().zip(&v.channels).enumerate() {
            let (u, it) = (val.u / PI, val.iterated / PI);
            let est = val.estimate.map_or(f64::NAN, |e| e / PI);
            let est_it = val.iterated_estimate.map_or(f64::NAN, |e| e / PI);
            let (du, dit) = ((u - p.radiance[c]).abs(), (it - p.radiance[c]).abs());
            let sigma3 = 3.0 * p.stderr[c];
            total += 1;
            within += usize::from(du <= est + sigma3);
            within_it += usize::from(dit <= est_it + sigma3);
            rel_u.push(du / p.radiance[c]);
            rel_it.push(dit / p.radiance[c]);
            println!(
                "{:<36} {:>3} {:>11.4e} {:>11.4e} {:>11.4e} {:>9.2e} {:>9.2e} {:>9.2e} {:>9.2e} {:>8.1e}",
                p.label, ch.name, u, it, p.radiance[c], du, dit, est, est_it, sigma3
            );
        }
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let max = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
    println!("{within} of {total} values u_n, {within_it} of {total} values û_n within their estimate + 3 sigma of the reference");
    println!(
        "relative difference to the reference: u_n median {:.2e}, max {:.2e}; û_n median {:.2e}, max {:.2e}",
        median(&mut rel_u),
        max(&rel_u),
        median(&mut rel_it),
        max(&rel_it)
    );
}
