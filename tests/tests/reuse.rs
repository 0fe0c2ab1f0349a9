//! A plan updated from the plan of the mesh it refines
//! (`AssemblyPlan::updating`) and a matrix assembled reusing the old one's
//! entries are the plan and matrix built from scratch, bit for bit: on a
//! scene that occludes (the Cornell box: clipped pairs with occluder
//! candidates) and on a curved surface (the sphere: near and self pairs),
//! over two refinements in a row.

use radcol_core::assembly::{
    AssemblyBackend, AssemblyPlan, CpuBackend, QuadratureOptions, Unchanged,
};
use radcol_core::discretization::Discretization;
use radcol_core::geometry::shapes::sphere;
use radcol_core::mesh::Mesh;
use radcol_core::nodes::NodeSet;
use radcol_core::run::adapt::refine;
use radcol_core::scene::builtin;
use radcol_core::visibility;
use std::sync::Arc;

fn check(surface: Arc<radcol_core::geometry::Surface>, level: u32, degree: usize, what: &str) {
    let vis = visibility::analyze(&surface);
    let quad = QuadratureOptions::default();
    let nodes = NodeSet::new(degree, 0.1).unwrap();
    let mut mesh = Arc::new(Mesh::new(surface, level));
    let disc = Arc::new(Discretization::new(mesh.clone(), nodes.clone()));
    let mut plan = AssemblyPlan::new(disc, quad.clone(), &vis);
    let mut matrix = CpuBackend.assemble(&plan).unwrap().matrix;
    for step in 0..2 {
        // Every third element (shifted per step) split.
        let split: Vec<usize> = (step..mesh.len()).step_by(3).collect();
        let (refined, parents) = refine(&mesh, &split);
        let old_of: Vec<Option<usize>> = parents
            .iter()
            .map(|&p| (!split.contains(&p)).then_some(p))
            .collect();
        let unchanged = Arc::new(Unchanged::new(&old_of, mesh.len()));
        let refined = Arc::new(refined);
        let disc = Arc::new(Discretization::new(refined.clone(), nodes.clone()));
        let updated =
            AssemblyPlan::updating(disc.clone(), quad.clone(), &vis, None, &plan, unchanged);
        let fresh = AssemblyPlan::new(disc, quad.clone(), &vis);
        assert!(updated.unchanged().is_some(), "{what}: nothing reused");
        assert_eq!(
            updated.classes(),
            fresh.classes(),
            "{what} step {step}: classes"
        );
        assert_eq!(updated.stats(), fresh.stats(), "{what} step {step}: stats");
        let reused = CpuBackend.assemble_reusing(&updated, &matrix).unwrap();
        let full = CpuBackend.assemble(&fresh).unwrap();
        // Every entry of the updated plan filled anew (the merged candidate
        // lists of partly visible pairs included) is the fresh plan's too.
        let refilled = CpuBackend.assemble(&updated).unwrap();
        assert!(
            reused.matrix.as_slice() == full.matrix.as_slice(),
            "{what} step {step}: reused entries differ"
        );
        assert!(
            refilled.matrix.as_slice() == full.matrix.as_slice(),
            "{what} step {step}: updated plan differs"
        );
        println!(
            "{what} step {step}: {} -> {} elements, kernel evaluations {} reused vs {} fresh ({:.2})",
            mesh.len(),
            refined.len(),
            reused.kernel_evals,
            full.kernel_evals,
            reused.kernel_evals as f64 / full.kernel_evals as f64
        );
        assert!(reused.kernel_evals < full.kernel_evals);
        mesh = refined;
        plan = updated;
        matrix = reused.matrix;
    }
}

#[test]
fn updated_plans_and_reused_entries_equal_fresh_ones() {
    let cornell = builtin("cornell").unwrap().unwrap();
    check(cornell.problem().surface, 0, 1, "cornell r=1");
    check(Arc::new(sphere(1.0)), 1, 2, "sphere r=2");
}
