//! What exact visibility costs against the number of occluding triangles:
//! the bunny rooms (`benches/data/bunny_room_*.obj`, `scenes/bunny_room.obj`:
//! a 550 mm room with the Stanford bunny decimated to 100 … 3 674 triangles)
//! assembled at r = 1 on the scene's own triangles (level 0). For each: the
//! elements, the partly visible (clipped) pairs, the plan's and the fill's
//! seconds, and the fill's microseconds per partly visible pair; then the
//! compressed operator of the same plan (tolerance 1e-8): its seconds and
//! the numbers it stores against the dense N²; then the exponents of those
//! against the bunny's triangle count and against the elements, fitted over
//! the run. Wall-clock figures of one run: compare them as ratios within it.
//!
//!     cargo run --release -p radcol-benches --example visibility [-- MAX_TRIANGLES [BUDGET]]
//!
//! BUDGET (default 0: exact) approximates the visibility of the partly
//! visible pairs that emit nothing within that share of each point's view
//! (`QuadratureOptions::visibility_budget`).
//! MAX_TRIANGLES (default 1000) leaves out the larger bunnies: the whole
//! bunny (3 674) takes about a minute and a half on 2 cores.

use radcol_benches::{bunny_rooms, fit_exponent as fit};
use radcol_core::assembly::{AssemblyBackend, AssemblyPlan, CpuBackend, QuadratureOptions};
use radcol_core::discretization::Discretization;
use radcol_core::hmatrix::radiosity::PlanEntries;
use radcol_core::hmatrix::HOptions;
use radcol_core::mesh::Mesh;
use radcol_core::nodes::NodeSet;
use radcol_core::scene::load_obj;
use radcol_core::visibility::analyze;
use std::sync::Arc;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let max: usize = args.next().map(|a| a.parse()).transpose()?.unwrap_or(1000);
    // A visibility budget: the bounce pairs' approximation (0: exact).
    let budget: f64 = args.next().map(|a| a.parse()).transpose()?.unwrap_or(0.0);
    let files = bunny_rooms(&[100, 200, 400, 600, 1000, 2000, 3674], max);
    println!("visibility budget {budget}");
    println!("bunny triangles, elements, partly visible pairs, of them approximated, plan s, fill s, fill µs per partly visible pair, compressed s, stored numbers, of N²");
    let (mut per_pair, mut fill_s) = (Vec::new(), Vec::new());
    let (mut stored_t, mut stored_e) = (Vec::new(), Vec::new());
    for (n, path) in files {
        let scene = load_obj(&path)?;
        let mesh = Arc::new(Mesh::new(scene.surface.clone(), 0));
        let disc = Arc::new(Discretization::new(mesh, NodeSet::new(1, 1.0 / 6.0)?));
        let dark = (0..scene.surface.patches.len()).map(|j| !scene.material_of(j).is_emitter());
        let visibility = analyze(disc.mesh().surface()).with_bounce_patches(dark.collect());
        let quad = QuadratureOptions {
            visibility_budget: budget,
            ..QuadratureOptions::default()
        };
        let t = Instant::now();
        let plan = AssemblyPlan::new(disc.clone(), quad, &visibility);
        let plan_s = t.elapsed().as_secs_f64();
        let t = Instant::now();
        CpuBackend.assemble(&plan)?;
        let fill = t.elapsed().as_secs_f64();
        let partial = plan.stats().pairs_partial;
        let approximate = plan.stats().pairs_approximate;
        let us = 1e6 * fill / partial as f64;
        let t = Instant::now();
        let h = PlanEntries::new(&plan).build(&HOptions::default());
        let compressed_s = t.elapsed().as_secs_f64();
        let stored = h.stats().stored as f64;
        let nn = (disc.len() as f64).powi(2);
        println!(
            "{n:>6} {:>6} {partial:>9} {approximate:>9} {plan_s:>8.2} {fill:>8.2} {us:>8.1} {compressed_s:>8.2} {stored:>11.4e} {:>6.2} %",
            disc.mesh().len(),
            100.0 * stored / nn
        );
        per_pair.push((n as f64, us));
        fill_s.push((n as f64, fill));
        stored_t.push((n as f64, stored));
        stored_e.push((disc.mesh().len() as f64, stored));
    }
    if per_pair.len() > 1 {
        println!(
            "exponents against the bunny's triangles: fill {:.2}, per partly visible pair {:.2}, compressed numbers {:.2}; compressed numbers against the elements {:.2}",
            fit(&fill_s),
            fit(&per_pair),
            fit(&stored_t),
            fit(&stored_e)
        );
    }
    Ok(())
}
