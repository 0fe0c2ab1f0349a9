//! A plan updated from the plan of the mesh it refines
//! (`AssemblyPlan::updating`) and a matrix assembled reusing the old one's
//! entries are the plan and matrix built from scratch, bit for bit: on a
//! scene that occludes (the Cornell box: clipped pairs with occluder
//! candidates) and on a curved surface (the sphere: near and self pairs),
//! over two refinements in a row. The estimate's check rows likewise
//! (`AssemblyPlan::at_points` updated, `estimate::check_matrix` reusing the
//! old rows), and the estimate from them equals the one filled block by
//! block.

use radcol_core::assembly::{
    AssemblyBackend, AssemblyPlan, CpuBackend, QuadratureOptions, Unchanged,
};
use radcol_core::discretization::Discretization;
use radcol_core::estimate::{check_matrix, check_nodes, estimate, estimate_from, ChannelFields};
use radcol_core::geometry::shapes::sphere;
use radcol_core::matrix::DenseMatrix;
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
    let mut plan = AssemblyPlan::new(disc.clone(), quad.clone(), &vis);
    let mut matrix = CpuBackend.assemble(&plan).unwrap().matrix;
    let check_rows = |d: &Arc<Discretization>| {
        Arc::new(Discretization::new(
            d.mesh().clone(),
            check_nodes(degree, nodes.alpha()),
        ))
    };
    let mut check =
        AssemblyPlan::at_points(disc.clone(), check_rows(&disc), quad.clone(), &vis, None);
    let mut rows: DenseMatrix = check_matrix(&check, None).0;
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
        let updated = AssemblyPlan::updating(
            disc.clone(),
            quad.clone(),
            &vis,
            None,
            &plan,
            unchanged.clone(),
        );
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
        // The check rows: updated plan reusing the old rows against a fresh
        // plan filled whole, and the estimate from them against the one
        // filled block by block (u_n = 1 + x, ρ = 0.5, E = 1 at the rows).
        let disc = updated.discretization().clone();
        let check_updated = AssemblyPlan::at_points(
            disc.clone(),
            check_rows(&disc),
            quad.clone(),
            &vis,
            Some((&check, unchanged.clone())),
        );
        let check_fresh =
            AssemblyPlan::at_points(disc.clone(), check_rows(&disc), quad.clone(), &vis, None);
        let (rows_reused, evals_reused) = check_matrix(&check_updated, Some(&rows));
        let (rows_fresh, evals_fresh) = check_matrix(&check_fresh, None);
        assert!(
            rows_reused.as_slice() == rows_fresh.as_slice(),
            "{what} step {step}: reused check rows differ"
        );
        assert!(evals_reused < evals_fresh);
        let solution = radcol_core::solution::Solution::new(
            disc.clone(),
            disc.points().iter().map(|p| 1.0 + p.position.x).collect(),
        );
        let m = check_fresh.rows().len();
        let (rho, e, en) = (vec![0.5; m], vec![1.0; m], vec![1.0; disc.len()]);
        let fields = [ChannelFields {
            solution: &solution,
            rho: &rho,
            emission: &e,
            emission_nodes: &en,
        }];
        let a = estimate(&check_fresh, &fields);
        let b = estimate_from(&check_updated, &rows_reused, &fields);
        assert!(
            a[0].elements == b[0].elements && a[0].max == b[0].max && a[0].l2 == b[0].l2,
            "{what} step {step}: estimates differ"
        );
        mesh = refined;
        plan = updated;
        matrix = reused.matrix;
        check = check_updated;
        rows = rows_reused;
    }
}

#[test]
fn updated_plans_and_reused_entries_equal_fresh_ones() {
    let cornell = builtin("cornell").unwrap().unwrap();
    check(cornell.problem().surface, 0, 1, "cornell r=1");
    check(Arc::new(sphere(1.0)), 1, 2, "sphere r=2");
}
