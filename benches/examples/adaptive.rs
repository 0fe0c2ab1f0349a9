//! Unknowns and seconds to reach an estimated max error of 1e-2, 1e-3 (and,
//! with `--deep`, 1e-4), adaptive refinement against uniform, on the
//! shadowed family (a floor lit by a square emitter through a floating
//! square) and the Cornell box. Wall-clock figures of one run; compare them
//! as ratios within a run.
//!
//!     cargo run --release -p radcol-benches --example adaptive [-- --deep] [-- --cornell]
//!     cargo run --release -p radcol-benches --example adaptive -- --degrees 1,2,3 [--deep]
//!
//! `--degrees` runs the shadowed floor adaptively at each degree given (auto
//! α), the measurement behind the choice of one degree for every element:
//! where the solution is rough (penumbrae) low degrees are cheaper per
//! unit of error, where it is smooth high ones.
//!
//! Uniform refinement stops at `UNIFORM_CAP` unknowns (a dense matrix of
//! 3.2 GB); a target it has not reached by then is reported as such.

use glam::DVec3;
use radcol_core::alpha0::auto_alpha;
use radcol_core::assembly::CpuBackend;
use radcol_core::geometry::shapes::floor_under_occluder;
use radcol_core::problem::{Field, Problem};
use radcol_core::run::adapt::{solve_adaptive, AdaptOptions, StopReason};
use radcol_core::run::{mesh_size, solve, SolveConfig};
use radcol_core::scene::builtin;
use std::sync::Arc;
use std::time::Instant;

const UNIFORM_CAP: u64 = 20_000;

fn square(h: f64, z: f64, cx: f64) -> Vec<DVec3> {
    [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
        .map(|(x, y)| DVec3::new(cx + h * x, h * y, z))
        .to_vec()
}

fn shadow_problem() -> Problem {
    let surface = floor_under_occluder(&square(0.5, 0.6, 0.0), &square(0.25, 0.3, 0.1));
    Problem::new(
        Arc::new(surface),
        Field::PerPatch(Arc::new(vec![0.9, 0.0, 0.0])),
        Field::PerPatch(Arc::new(vec![0.0, 1.0, 0.0])),
    )
}

/// Worst channel's estimated max error of what is shown (the limited
/// solution), relative to max |u_n|: what the adaptive loop stops on.
fn worst(out: &radcol_core::run::SolveOutcome) -> f64 {
    out.channels
        .iter()
        .filter_map(|c| c.estimate.as_ref())
        .fold(0.0, |m, e| m.max(e.shown_max_rel()))
}

fn uniform(problem: &Problem, cfg: &SolveConfig, target: f64) -> String {
    let t = Instant::now();
    for level in cfg.level.. {
        let c = SolveConfig {
            level,
            ..cfg.clone()
        };
        let n = mesh_size(
            &problem.surface,
            level,
            cfg.max_edge,
            cfg.grade.as_ref(),
            cfg.degree,
        )
        .unknowns;
        if n > UNIFORM_CAP {
            return format!(
                "not reached by {UNIFORM_CAP} unknowns ({:.1} s)",
                t.elapsed().as_secs_f64()
            );
        }
        let out = solve(problem, &c, &CpuBackend).expect("solves");
        let e = worst(&out);
        if e <= target {
            return format!(
                "{n} unknowns (level {level}, estimate {e:.2e}), {:.1} s",
                t.elapsed().as_secs_f64()
            );
        }
    }
    unreachable!()
}

fn adaptive(problem: &Problem, cfg: &SolveConfig, target: f64) -> String {
    let t = Instant::now();
    let opts = AdaptOptions {
        target,
        ..Default::default()
    };
    let res = solve_adaptive(problem, cfg, &opts, &CpuBackend, |_| {}).expect("solves");
    let last = res.steps.last().expect("one step at least");
    let elsewhere = match res.stop {
        StopReason::Singular => format!(", {:.2e} elsewhere", last.estimate_elsewhere),
        _ => String::new(),
    };
    format!(
        "{} unknowns ({} steps, estimate {:.2e}{elsewhere}, {:?}), {:.1} s",
        last.unknowns,
        res.steps.len(),
        last.estimate_shown,
        res.stop,
        t.elapsed().as_secs_f64()
    )
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let deep = args.iter().any(|a| a == "--deep");
    let targets: &[f64] = if deep {
        &[1e-2, 1e-3, 1e-4]
    } else {
        &[1e-2, 1e-3]
    };
    if let Some(i) = args.iter().position(|a| a == "--degrees") {
        let degrees: Vec<usize> = args
            .get(i + 1)
            .expect("--degrees R,R,…")
            .split(',')
            .map(|r| r.parse().expect("a degree"))
            .collect();
        for &target in targets {
            for &r in &degrees {
                let cfg = SolveConfig {
                    degree: r,
                    alpha: auto_alpha(r),
                    level: 1,
                    ..Default::default()
                };
                println!(
                    "shadowed floor, r = {r}, target {target:.0e}: adaptive {}",
                    adaptive(&shadow_problem(), &cfg, target)
                );
            }
        }
        return;
    }
    let mut cases = vec![(
        "shadowed floor, r = 1".to_string(),
        shadow_problem(),
        SolveConfig {
            degree: 1,
            alpha: 1.0 / 6.0,
            level: 1,
            ..Default::default()
        },
    )];
    if args.iter().any(|a| a == "--cornell") {
        let scene = builtin("cornell").expect("built in").expect("loads");
        cases.push((
            "Cornell box, r = 1".to_string(),
            scene.problem(),
            SolveConfig {
                degree: 1,
                alpha: 1.0 / 6.0,
                level: 0,
                ..Default::default()
            },
        ));
    }
    for (name, problem, cfg) in &cases {
        for &target in targets {
            println!("{name}, target {target:.0e}");
            println!("  adaptive: {}", adaptive(problem, cfg, target));
            println!("  uniform:  {}", uniform(problem, cfg, target));
        }
    }
}
