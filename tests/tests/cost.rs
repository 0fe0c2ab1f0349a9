//! The cost prediction before an assembly (`radcol info --plan`): measured
//! on every row block it is the plan itself (the same pair counts as the
//! whole plan, built independently of the sampling), and from a sample its
//! totals lie within a few standard errors of the plan's.

use radcol_core::assembly::{AssemblyPlan, PairClass, QuadratureOptions};
use radcol_core::discretization::Discretization;
use radcol_core::error::InputError;
use radcol_core::mesh::Mesh;
use radcol_core::nodes::NodeSet;
use radcol_core::run::{check_plan_memory, AssemblyCost, Extrapolated};
use radcol_core::scene::load_obj;
use radcol_core::visibility::analyze;
use std::path::Path;
use std::sync::Arc;

/// The 200-triangle bunny room at r = 1 on its own triangles.
fn bunny_room() -> (
    Arc<Discretization>,
    radcol_core::visibility::VisibilityAnalysis,
) {
    let path = format!(
        "{}/../benches/data/bunny_room_200.obj",
        env!("CARGO_MANIFEST_DIR")
    );
    let scene = load_obj(Path::new(&path)).unwrap();
    let mesh = Arc::new(Mesh::new(scene.surface.clone(), 0));
    let vis = analyze(&scene.surface);
    assert!(vis.needed);
    let disc = Discretization::new(mesh, NodeSet::new(1, 1.0 / 6.0).unwrap());
    (Arc::new(disc), vis)
}

fn within(what: &str, e: Extrapolated, exact: f64, sigmas: f64) {
    println!(
        "{what}: predicted {:.4e} ± {:.2e}, exact {exact:.4e} ({:+.1} σ)",
        e.value,
        e.std_error,
        (e.value - exact) / e.std_error
    );
    assert!(
        (e.value - exact).abs() <= sigmas * e.std_error,
        "{what}: {e:?} against {exact}"
    );
}

#[test]
fn the_cost_prediction_counts_what_the_plan_holds() {
    let (disc, vis) = bunny_room();
    let quad = QuadratureOptions::default();
    let plan = AssemblyPlan::new(disc.clone(), quad.clone(), &vis);
    let stats = plan.stats();
    let n = disc.mesh().len();
    // Candidates of the partly visible pairs, counted on the whole plan
    // through its public classes, row by row.
    let partial_elements: u64 = (0..n)
        .map(|kp| {
            (0..n)
                .filter(|&k| plan.class(kp, k) == PairClass::Partial)
                .count() as u64
        })
        .sum();
    assert!(stats.pairs_partial > 10_000, "{stats:?}");

    let full = AssemblyCost::predict(&disc, &quad, &vis, n);
    let a = &full.assembly;
    assert_eq!(full.sampled, n);
    for (what, got, want) in [
        ("far", a.pairs_far, stats.pairs_far),
        ("near", a.pairs_near, stats.pairs_near),
        ("partly visible", a.pairs_partial, stats.pairs_partial),
        ("culled", a.pairs_culled, stats.pairs_culled),
    ] {
        assert_eq!((got.value, got.std_error), (want as f64, 0.0), "{what}");
    }
    assert_eq!(a.pairs_partial.value, 3.0 * partial_elements as f64);
    assert!(a.candidates.value >= partial_elements as f64 / 2.0);
    assert!(full.estimate.pairs_partial.value > a.pairs_partial.value);

    // A sample of a sixth of the rows: its totals near the plan's.
    let sampled = AssemblyCost::predict(&disc, &quad, &vis, n / 6);
    assert!(sampled.sampled < n);
    within(
        "partly visible pairs",
        sampled.assembly.pairs_partial,
        stats.pairs_partial as f64,
        3.0,
    );
    within(
        "far pairs",
        sampled.assembly.pairs_far,
        stats.pairs_far as f64,
        3.0,
    );
    within(
        "candidates",
        sampled.assembly.candidates,
        a.candidates.value,
        3.0,
    );
}

/// A solve refuses, before planning, a plan whose candidate lists would not
/// fit: the prediction against the memory available, in the error.
#[test]
fn a_plan_that_cannot_fit_is_refused_before_it_is_built() {
    let (disc, vis) = bunny_room();
    let quad = QuadratureOptions::default();
    let full = AssemblyCost::predict(&disc, &quad, &vis, disc.mesh().len());
    let bytes = full.assembly.partial_bytes.value;
    assert!(bytes > 1e5, "{bytes}");
    // Sampled (64 of 216 row blocks, about ± 20 %): refused with half the
    // bytes available, passed with twice.
    let small = Some((bytes / 2.0) as u64);
    match check_plan_memory(&disc, &quad, &vis, small, 0) {
        Err(e @ InputError::VisibilityPlanTooLarge { .. }) => {
            let text = e.to_string();
            println!("{text}");
            assert!(text.contains("partly visible pairs") && text.contains("coarser mesh"));
        }
        other => panic!("{other:?}"),
    }
    assert!(check_plan_memory(&disc, &quad, &vis, Some((bytes * 2.0) as u64), 0).is_ok());
    // Meshes below the threshold are not sampled at all.
    assert!(check_plan_memory(&disc, &quad, &vis, Some(1), disc.mesh().len() + 1).is_ok());
}
