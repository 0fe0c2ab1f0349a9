//! What exact visibility costs at a fixed receiving mesh as the occluder
//! grows: the bunny rooms (`benches/data/bunny_room_*.obj`,
//! `scenes/bunny_room.obj`: the Stanford bunny decimated to 100 … 3 674
//! triangles) with the room alone meshed (its walls, floor, ceiling and
//! light split to edges of at most H, 100 mm by default) and the bunny an
//! occluder only: its triangles cast shadows but carry no unknowns, so the
//! matrix is the same size for every bunny, and what changes is the
//! visibility work of the room's pairs. For each bunny: the room's elements,
//! the partly visible (clipped) pairs, the plan's and the fill's seconds,
//! and their sum against the smallest bunny's; then the exponents of plan,
//! fill and their sum against the bunny's triangle count, fitted over the
//! run. Wall-clock figures of one run: compare them as ratios within it.
//!
//!     cargo run --release -p radcol-benches --example fixed_receivers [-- H [MAX_TRIANGLES]]

use radcol_benches::{bunny_rooms, fit_exponent as fit};
use radcol_core::assembly::{AssemblyBackend, AssemblyPlan, CpuBackend, QuadratureOptions};
use radcol_core::discretization::Discretization;
use radcol_core::mesh::Mesh;
use radcol_core::nodes::NodeSet;
use radcol_core::scene::load_obj;
use radcol_core::visibility::analyze;
use std::sync::Arc;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let h: f64 = args.next().map(|a| a.parse()).transpose()?.unwrap_or(100.0);
    let max: usize = args.next().map(|a| a.parse()).transpose()?.unwrap_or(3674);
    let files = bunny_rooms(&[100, 200, 400, 600, 1000, 2000, 3674], max);
    println!(
        "room elements split to edges of at most {h}; the bunny occludes, carries no unknowns"
    );
    println!("bunny triangles, room elements, unknowns, partly visible pairs, plan s, fill s, plan + fill s, against the first");
    let (mut plan_t, mut fill_t, mut both_t) = (Vec::new(), Vec::new(), Vec::new());
    let mut first = None;
    for (n, path) in files {
        let scene = load_obj(&path)?;
        let surface = scene.surface.clone();
        let occluder: Vec<bool> = surface
            .patches
            .iter()
            .map(|p| p.name.starts_with("bunny"))
            .collect();
        if !occluder.iter().any(|&o| o) {
            return Err(format!("{}: no patch named bunny*", path.display()).into());
        }
        let all = Mesh::with_max_edge(surface.clone(), 0, h);
        let room: Vec<_> = (all.elements().iter())
            .filter(|e| !occluder[e.patch as usize])
            .cloned()
            .collect();
        let mesh = Arc::new(Mesh::from_elements(surface.clone(), all.level(), room));
        let disc = Arc::new(Discretization::new(mesh, NodeSet::new(1, 1.0 / 6.0)?));
        let visibility = analyze(&surface);
        let t = Instant::now();
        let plan = AssemblyPlan::new(disc.clone(), QuadratureOptions::default(), &visibility);
        let plan_s = t.elapsed().as_secs_f64();
        let t = Instant::now();
        CpuBackend.assemble(&plan)?;
        let fill_s = t.elapsed().as_secs_f64();
        let both = plan_s + fill_s;
        let base = *first.get_or_insert(both);
        println!(
            "{n:>6} {:>6} {:>6} {:>9} {plan_s:>8.2} {fill_s:>8.2} {both:>8.2} {:>6.2}x",
            disc.mesh().len(),
            disc.len(),
            plan.stats().pairs_partial,
            both / base
        );
        plan_t.push((n as f64, plan_s));
        fill_t.push((n as f64, fill_s));
        both_t.push((n as f64, both));
    }
    if both_t.len() > 1 {
        println!(
            "exponents against the bunny's triangles: plan {:.2}, fill {:.2}, plan + fill {:.2}",
            fit(&plan_t),
            fit(&fill_t),
            fit(&both_t)
        );
    }
    Ok(())
}
