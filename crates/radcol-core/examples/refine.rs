//! A solved scene refined to a smaller target, against solving for that
//! target from the start:
//! `cargo run --release -p radcol-core --example refine [-- SCENE COARSE FINE]`
//! (default: the Cornell box, 1e-2 then 1e-3).

use radcol_core::prelude::*;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let scene = || match args.first() {
        Some(path) => load_scene(std::path::Path::new(path)),
        None => Ok(Scene::builtin("cornell")?),
    };
    let number = |i: usize, default: f64| args.get(i).map_or(Ok(default), |a| a.parse());
    let (coarse, fine) = (number(1, 1e-2)?, number(2, 1e-3)?);
    let report = |what: &str, solved: &Radiosity, seconds: f64| {
        let r = solved.refinement().expect("adaptive");
        let last = r.steps.last().expect("a step");
        println!(
            "{what}: {seconds:.1} s, {} steps in all, {} unknowns, estimate {:.3e} \
             ({:.3e} away from the points named), {:?}",
            r.steps.len(),
            solved.outcome().discretization.len(),
            last.estimate_shown,
            last.estimate_elsewhere,
            r.stop
        );
    };

    let t = Instant::now();
    let mut solved = Radiosity::solve(scene()?, &Settings::target(coarse))?;
    report(
        &format!("to {coarse:e}"),
        &solved,
        t.elapsed().as_secs_f64(),
    );
    let t = Instant::now();
    solved.refine(fine)?;
    report(
        &format!("then refined to {fine:e}"),
        &solved,
        t.elapsed().as_secs_f64(),
    );
    let t = Instant::now();
    let direct = Radiosity::solve(scene()?, &Settings::target(fine))?;
    report(
        &format!("to {fine:e} from the start"),
        &direct,
        t.elapsed().as_secs_f64(),
    );
    Ok(())
}
