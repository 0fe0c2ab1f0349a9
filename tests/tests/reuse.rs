//! A plan updated from the plan of the mesh it refines
//! (`AssemblyPlan::updating`) and a matrix assembled reusing the old one's
//! entries are the plan and matrix built from scratch, bit for bit: on a
//! scene that occludes (the Cornell box: clipped pairs with occluder
//! candidates) and on a curved surface (the sphere: near and self pairs),
//! over two refinements in a row. The estimate's check-point plan likewise
//! (`AssemblyPlan::at_points` updated), and the estimate through it equals
//! the one through a fresh plan. An estimate updated from the previous
//! step's (`estimate::estimate_updated`) is within its bound of the
//! computed one.

use radcol_core::assembly::{
    AssemblyBackend, AssemblyPlan, CpuBackend, QuadratureOptions, Unchanged,
};
use radcol_core::discretization::Discretization;
use radcol_core::estimate::{
    check_nodes, estimate, estimate_updated, ChannelFields, ErrorEstimate,
};
use radcol_core::geometry::shapes::sphere;
use radcol_core::geometry::Surface;
use radcol_core::hmatrix::radiosity::PlanEntries;
use radcol_core::hmatrix::HOptions;
use radcol_core::mesh::Mesh;
use radcol_core::nodes::NodeSet;
use radcol_core::run::adapt::{on_refined, refine};
use radcol_core::scene::builtin;
use radcol_core::solution::Solution;
use radcol_core::visibility::{self, VisibilityAnalysis};
use std::sync::Arc;

/// `mesh` with every `every`-th element from `first` split: the refined
/// mesh, each element's parent, its old element when unchanged, and that
/// as an `Unchanged`.
fn split_every(
    mesh: &Mesh,
    first: usize,
    every: usize,
) -> (Arc<Mesh>, Vec<usize>, Vec<Option<usize>>, Arc<Unchanged>) {
    let split: Vec<usize> = (first..mesh.len()).step_by(every).collect();
    let (refined, parents) = refine(mesh, &split);
    let old_of: Vec<Option<usize>> = parents
        .iter()
        .map(|&p| (!split.contains(&p)).then_some(p))
        .collect();
    let unchanged = Arc::new(Unchanged::new(&old_of, mesh.len()));
    (Arc::new(refined), parents, old_of, unchanged)
}

/// What each check starts from: the surface's visibility, the default
/// quadrature, the degree's nodes (α = 0.1) and the mesh at `level`.
fn start(
    surface: Arc<Surface>,
    level: u32,
    degree: usize,
) -> (VisibilityAnalysis, QuadratureOptions, NodeSet, Arc<Mesh>) {
    let vis = visibility::analyze(&surface);
    let nodes = NodeSet::new(degree, 0.1).unwrap();
    let mesh = Arc::new(Mesh::new(surface, level));
    (vis, QuadratureOptions::default(), nodes, mesh)
}

fn check(surface: Arc<Surface>, level: u32, degree: usize, what: &str) {
    let (vis, quad, nodes, mut mesh) = start(surface, level, degree);
    let disc = Arc::new(Discretization::new(mesh.clone(), nodes.clone()));
    let mut plan = AssemblyPlan::new(disc.clone(), quad.clone(), &vis);
    let mut matrix = CpuBackend.assemble(&plan).unwrap().matrix;
    let check_rows = |d: &Arc<Discretization>| {
        Arc::new(Discretization::new(
            d.mesh().clone(),
            check_nodes(degree, nodes.alpha()),
        ))
    };
    let mut check = AssemblyPlan::at_points(
        disc.clone(),
        check_rows(&disc),
        quad.clone(),
        &vis,
        (None, None),
    );
    fill_all(&check);
    for step in 0..2 {
        // Every third element (shifted per step) split.
        let (refined, _, _, unchanged) = split_every(&mesh, step, 3);
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
        // The check-point plan updated against a fresh one, and the estimate
        // through each (u_n = 1 + x, ρ = 0.5, E = 1 at the rows).
        let disc = updated.discretization().clone();
        let check_updated = AssemblyPlan::at_points(
            disc.clone(),
            check_rows(&disc),
            quad.clone(),
            &vis,
            (Some((&check, unchanged.clone())), None),
        );
        let check_fresh = AssemblyPlan::at_points(
            disc.clone(),
            check_rows(&disc),
            quad.clone(),
            &vis,
            (None, None),
        );
        assert_eq!(
            check_updated.classes(),
            check_fresh.classes(),
            "{what} step {step}: check classes"
        );
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
        let b = estimate(&check_updated, &fields);
        assert!(
            a[0].elements == b[0].elements && a[0].max == b[0].max && a[0].l2 == b[0].l2,
            "{what} step {step}: estimates differ"
        );
        // Taking the square plan's candidate lists changes nothing either.
        let rows = check_rows(&disc);
        let known = (None, Some(&updated));
        let check_known = AssemblyPlan::at_points(disc.clone(), rows, quad.clone(), &vis, known);
        assert_eq!(
            check_known.classes(),
            check_fresh.classes(),
            "{what} step {step}: check classes with the square plan's candidates"
        );
        // The updated plan copies the entries of unchanged partly visible
        // pairs whose shadows are merged (more than 24 candidates) that the
        // previous check plan stored (it was filled: by `fill_all` before
        // the first step, by the estimate after); they are the clipped ones
        // bit for bit, at fewer kernel evaluations. The Cornell box's and
        // the sphere's pairs have fewer candidates: nothing is stored.
        let (fresh_entries, fresh_evals) = fill_all(&check_fresh);
        let (updated_entries, updated_evals) = fill_all(&check_updated);
        assert!(
            fresh_entries == updated_entries,
            "{what} step {step}: stored check entries differ"
        );
        println!(
            "{what} step {step}: check rows' kernel evaluations {updated_evals} with the stored entries vs {fresh_evals} fresh"
        );
        if what.starts_with("bunny room") {
            assert!(
                updated_evals < fresh_evals,
                "{what} step {step}: no stored entry taken"
            );
        }
        let c = estimate(&check_known, &fields);
        assert!(
            a[0].elements == c[0].elements && a[0].max == c[0].max && a[0].l2 == c[0].l2,
            "{what} step {step}: estimates with the square plan's candidates differ"
        );
        mesh = refined;
        plan = updated;
        matrix = reused.matrix;
        check = check_updated;
    }
}

/// Every row block of `plan` filled, and the kernel evaluations.
fn fill_all(plan: &AssemblyPlan) -> (Vec<f64>, u64) {
    let (mut all, mut evals) = (Vec::new(), 0);
    for kp in 0..plan.rows().mesh().len() {
        let mut block = vec![0.0; plan.rows().nodes_per(kp) * plan.dim()];
        evals += plan.fill_block(kp, &mut block, radcol_core::assembly::FillMode::All);
        all.extend(block);
    }
    (all, evals)
}

#[test]
fn updated_plans_and_reused_entries_equal_fresh_ones() {
    on_both(check, 0, 1);
}

/// A degree per element (the adaptive loop with hp): steps that raise
/// some elements one degree and split others, lowering their children's,
/// reuse the entries of the pairs of unchanged elements bit for bit (a
/// raised element counts as changed; the unchanged ones keep their set).
#[test]
fn raised_and_lowered_elements_reuse_like_split_ones() {
    on_both(check_raise, 0, 1);
}

fn check_raise(surface: Arc<Surface>, level: u32, degree: usize, what: &str) {
    let (vis, quad, _, mut mesh) = start(surface, level, degree);
    let sets: Vec<NodeSet> = (0..=3).map(|r| NodeSet::new(r, 0.1).unwrap()).collect();
    let mut degrees = vec![degree; mesh.len()];
    let disc = Discretization::with_degrees(mesh.clone(), sets.clone(), &degrees).unwrap();
    let mut plan = AssemblyPlan::new(Arc::new(disc), quad.clone(), &vis);
    let mut matrix = CpuBackend.assemble(&plan).unwrap().matrix;
    for step in 0..2 {
        // Every third element raised, every fifth split with its children
        // one degree lower (at least 1), from a shifting start.
        let n = mesh.len();
        let raise = |k: usize| (k + step).is_multiple_of(3) && degrees[k] < 3;
        let split: Vec<usize> = (0..n)
            .filter(|&k| (k + step) % 5 == 1 && !raise(k))
            .collect();
        let (refined, parents) = refine(&mesh, &split);
        let changed: Vec<bool> = (0..n).map(|k| raise(k) || split.contains(&k)).collect();
        let next: Vec<usize> = parents
            .iter()
            .map(|&p| match (raise(p), split.contains(&p)) {
                (true, _) => degrees[p] + 1,
                (_, true) => degrees[p].saturating_sub(1).max(1),
                _ => degrees[p],
            })
            .collect();
        let refined = Arc::new(refined);
        let disc =
            Arc::new(Discretization::with_degrees(refined.clone(), sets.clone(), &next).unwrap());
        let unchanged = Arc::new(Unchanged::refined(&parents, &changed));
        let updated =
            AssemblyPlan::updating(disc.clone(), quad.clone(), &vis, None, &plan, unchanged);
        let fresh = AssemblyPlan::new(disc, quad.clone(), &vis);
        assert!(
            updated.unchanged().is_some(),
            "{what} step {step}: nothing reused"
        );
        assert_eq!(
            updated.classes(),
            fresh.classes(),
            "{what} step {step}: classes"
        );
        let reused = CpuBackend.assemble_reusing(&updated, &matrix).unwrap();
        let full = CpuBackend.assemble(&fresh).unwrap();
        assert!(
            reused.matrix.as_slice() == full.matrix.as_slice(),
            "{what} step {step}: reused entries differ"
        );
        assert!(
            reused.kernel_evals < full.kernel_evals,
            "{what} step {step}"
        );
        (mesh, degrees, plan, matrix) = (refined, next, updated, reused.matrix);
    }
}

/// `check` on the Cornell box at r = 1 (mesh level `cornell`) and on the
/// unit sphere at r = 2 (level `sphere`).
fn on_both(check: fn(Arc<Surface>, u32, usize, &str), cornell: u32, sphere_level: u32) {
    let box_ = builtin("cornell").unwrap().unwrap();
    check(box_.problem().surface, cornell, 1, "cornell r=1");
    check(Arc::new(sphere(1.0)), sphere_level, 2, "sphere r=2");
}

/// The bunny room with the bunny decimated to 100 triangles: pairs behind
/// the bunny have dozens of candidate occluders, whose shadows are merged.
#[test]
fn a_bunny_room_reuses_the_entries_of_merged_shadows() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../benches/data/bunny_room_100.obj");
    let room = radcol_core::scene::load_obj(&path).unwrap();
    check(room.problem().surface, 0, 1, "bunny room r=1");
}

/// An estimate updated from the previous step's
/// (`estimate::estimate_updated`) is within the bound it reports of the
/// estimate computed afresh, element by element, with u_n changed a little
/// on the unchanged elements and much on the new ones; a change too large
/// everywhere is refused, and so is an update of an estimate whose
/// allowance is spent.
fn check_update(surface: Arc<Surface>, level: u32, degree: usize, what: &str) {
    let (vis, quad, nodes, mesh) = start(surface, level, degree);
    let disc = Arc::new(Discretization::new(mesh.clone(), nodes.clone()));
    let check_rows = |d: &Arc<Discretization>| {
        Arc::new(Discretization::new(
            d.mesh().clone(),
            check_nodes(degree, nodes.alpha()),
        ))
    };
    let old_check = AssemblyPlan::at_points(
        disc.clone(),
        check_rows(&disc),
        quad.clone(),
        &vis,
        (None, None),
    );
    let wave = |p: glam::DVec3| 1.0 + 0.5 * (p.x + 2.0 * p.y).sin() + 0.2 * p.z;
    let u_old = Solution::new(
        disc.clone(),
        disc.points().iter().map(|p| wave(p.position)).collect(),
    );
    let fields = |check: &AssemblyPlan, u: &'_ Solution| {
        let m = check.rows().len();
        (
            vec![0.6; m],
            vec![1.0; m],
            vec![1.0; u.discretization().len()],
        )
    };
    let (rho, e, en) = fields(&old_check, &u_old);
    let old = estimate(
        &old_check,
        &[ChannelFields {
            solution: &u_old,
            rho: &rho,
            emission: &e,
            emission_nodes: &en,
        }],
    );
    // Every fifteenth element split: a fifth of the new mesh's elements are new.
    let (refined, parents, old_of, unchanged) = split_every(&mesh, 0, 15);
    let g = on_refined(&u_old, &refined, &parents);
    let disc = Arc::new(Discretization::new(refined.clone(), nodes.clone()));
    let updated = AssemblyPlan::at_points(
        disc.clone(),
        check_rows(&disc),
        quad.clone(),
        &vis,
        (Some((&old_check, unchanged.clone())), None),
    );
    let fresh = AssemblyPlan::at_points(
        disc.clone(),
        check_rows(&disc),
        quad.clone(),
        &vis,
        (None, None),
    );
    let scale = u_old.nodal().iter().fold(0.0f64, |m, u| m.max(u.abs()));
    // Δ: 1e-2 on new elements, `small` on unchanged ones (varying by node).
    let change_of = |small: f64| -> Vec<f64> {
        disc.points()
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let w = if old_of[p.element].is_some() {
                    small
                } else {
                    1e-2
                };
                w * scale * ((i % 5) as f64 - 2.0) / 2.0
            })
            .collect()
    };
    let within = 1e-4;
    // u_n = g + Δ: its estimate computed afresh, and updated from `prev`.
    let both = |delta: &[f64], prev: &ErrorEstimate| {
        let u_new = Solution::new(
            disc.clone(),
            g.iter().zip(delta).map(|(g, d)| g + d).collect(),
        );
        let (rho, e, en) = fields(&fresh, &u_new);
        let ch = [ChannelFields {
            solution: &u_new,
            rho: &rho,
            emission: &e,
            emission_nodes: &en,
        }];
        let a = estimate(&fresh, &ch).remove(0);
        let b = estimate_updated(&updated, &ch, &[prev], &[delta.to_vec()], within);
        (a, b.map(|mut b| b.remove(0)))
    };
    for small in [0.0, 1e-9, 1e-6] {
        let delta = change_of(small);
        let (a, b) = both(&delta, &old[0]);
        let b = b.unwrap_or_else(|| panic!("{what}: Δ {small:e} on unchanged elements refused"));
        let bound = b.updated_within.expect("an update says so");
        assert!(
            bound > 0.0 && bound <= within * scale * 1.0001,
            "{what}: bound {bound:e}"
        );
        let worst = a
            .elements
            .iter()
            .zip(&b.elements)
            .map(|(x, y)| (y - x).abs())
            .fold(0.0f64, f64::max);
        println!(
            "{what}, Δ {small:e} on unchanged: bound {:.2e}, largest deviation {:.2e} (of max|u| {scale:.3})",
            bound, worst
        );
        assert!(
            worst <= bound,
            "{what}, Δ {small:e}: {worst:e} > bound {bound:e}"
        );
        assert!(
            (b.max - a.max).abs() <= bound,
            "{what}: max {:e} against {:e}",
            b.max,
            a.max
        );
        // Not vacuous: dropping the new elements' columns from the update
        // would move η by about 1e-2 max|u| times their form factors.
        assert!(
            bound < 1e-3 * a.max.max(1e-6 * scale),
            "{what}: bound {bound:e} against max {:e}",
            a.max
        );
        // A previous estimate that already spent the allowance is not
        // updated again.
        let lc = check_nodes(degree, nodes.alpha()).lebesgue_constant();
        let spent = ErrorEstimate {
            check_ku_drift: within * scale / (lc * 0.6),
            ..old[0].clone()
        };
        assert!(both(&delta, &spent).1.is_none(), "{what}: spent allowance");
    }
    // A change of 1e-2 everywhere leaves no column to bound: refused.
    let delta = vec![1e-2 * scale; disc.len()];
    assert!(
        both(&delta, &old[0]).1.is_none(),
        "{what}: changed everywhere"
    );
}

#[test]
fn updated_estimates_are_within_their_bound_of_computed_ones() {
    on_both(check_update, 1, 1);
}

/// The compressed operator of a mesh refined at a few elements, built from
/// the previous mesh's (`PlanEntries::build_checked` with the previous
/// matrix), takes most of its blocks from it, computes a fraction of the
/// kernel evaluations of a fresh build, and is as accurate: its product
/// and a fresh compressed operator's are within the tolerance of the dense
/// matrix's (Cornell box, r = 1, where blocks are zero, shadow-split and
/// low rank; the sphere, r = 2, with near and self pairs on curved
/// elements).
fn check_compressed(surface: Arc<Surface>, level: u32, degree: usize, what: &str) {
    let (vis, quad, nodes, mesh) = start(surface, level, degree);
    let opts = HOptions {
        tol: 1e-8,
        ..Default::default()
    };
    let disc = Arc::new(Discretization::new(mesh.clone(), nodes.clone()));
    let plan = AssemblyPlan::new(disc, quad.clone(), &vis);
    let previous = PlanEntries::new(&plan).build(&opts);
    let split = [3, mesh.len() / 2, mesh.len() - 7];
    let (refined, parents) = refine(&mesh, &split);
    let mut marked = vec![false; mesh.len()];
    split.iter().for_each(|&k| marked[k] = true);
    let unchanged = Arc::new(Unchanged::refined(&parents, &marked));
    let disc = Arc::new(Discretization::new(Arc::new(refined), nodes));
    let updated = AssemblyPlan::updating(
        disc.clone(),
        quad.clone(),
        &vis,
        None,
        &plan,
        unchanged.clone(),
    );
    let (taken, fresh) = (PlanEntries::new(&updated), PlanEntries::new(&updated));
    let ok = |_: &_| Ok::<(), ()>(());
    let (h, _) = taken
        .build_checked(&opts, Some((&previous, &unchanged)), ok)
        .unwrap();
    let (f, _) = fresh.build_checked(&opts, None, ok).unwrap();
    let dense = CpuBackend
        .assemble(&AssemblyPlan::new(disc.clone(), quad, &vis))
        .unwrap()
        .matrix;
    let n = disc.len();
    let x: Vec<f64> = (0..n).map(|i| 1.0 + (i as f64 * 0.7).sin()).collect();
    let mut exact = vec![0.0; n];
    dense.matvec(&x, &mut exact);
    let error = |m: &radcol_core::hmatrix::HMatrix| {
        let mut y = vec![0.0; n];
        m.matvec(&x, &mut y);
        let num: f64 = y.iter().zip(&exact).map(|(a, b)| (a - b).powi(2)).sum();
        (num / exact.iter().map(|b| b * b).sum::<f64>()).sqrt()
    };
    let (s, leaves) = (h.stats(), |s: radcol_core::hmatrix::HStats| {
        s.zero_blocks + s.dense_blocks + s.low_rank_blocks
    });
    let (e_taken, e_fresh) = (error(&h), error(&f));
    println!(
        "{what}: {} of {} leaves taken, kernel evaluations {} against {} fresh; product error {e_taken:.2e} against {e_fresh:.2e} fresh",
        s.reused_blocks,
        leaves(s),
        taken.evaluations(),
        fresh.evaluations()
    );
    assert!(2 * s.reused_blocks > leaves(s), "{what}: {s:?}");
    assert!(3 * taken.evaluations() < fresh.evaluations(), "{what}");
    assert!(
        e_taken < 1e-7 && e_fresh < 1e-7,
        "{what}: {e_taken:e}, {e_fresh:e}"
    );
}

#[test]
fn compressed_operators_take_untouched_blocks_from_the_previous_step() {
    on_both(check_compressed, 2, 3);
}
