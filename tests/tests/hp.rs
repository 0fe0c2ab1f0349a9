//! Would a degree per element (hp) reach a tolerance with fewer unknowns
//! than one degree everywhere? Measured on the shadowed family
//! (`shadows.rs`), where the question has an exact answer: the floor sees
//! itself nowhere and the emitter and occluder reflect nothing, so the
//! collocation solution on the floor is the interpolant of the exact u at
//! the nodes (u_n(x_i) = E + K u(x_i) with u on the emitter constant), and
//! its max error on an element depends on that element alone. The mesh
//! with the fewest unknowns whose every element is within TOL is then
//! found exactly, element by element, over the 4:1 splits the adaptive loop
//! makes: for one degree r, an element is kept when its interpolant is
//! within TOL and split otherwise; with a degree per element (1..=`MAX_R`),
//! it takes the cheapest degree within TOL, or its four children where
//! those cost less. Both are the best any marking can reach with that
//! space, so their ratio bounds what hp can gain here.
//!
//! Errors are measured as the solver measures them (the lattice of
//! `norms::LATTICE` points of every element: vertices, edges, interiors)
//! relative to max u = 1 (the emitter).

use crate::shadows::{cases, floor_u, problem_on, Case};
use glam::DVec3;
use radcol_core::alpha0::auto_alpha;
use radcol_core::assembly::CpuBackend;
use radcol_core::geometry::shapes::floor_under_occluder;
use radcol_core::nodes::NodeSet;
use radcol_core::norms::LATTICE;
use radcol_core::run::adapt::{solve_adaptive, AdaptOptions, StopReason};
use radcol_core::run::{solve, RelativeTo, SolveConfig, SolveOutcome};
use std::sync::Arc;

/// Degrees a per-element choice may take.
const MAX_R: usize = 4;

/// Deepest split below the floor's two triangles (edges of 2^-20 of the
/// floor: far below what any tolerance here needs; reaching it is counted).
const MAX_DEPTH: u32 = 20;

type Tri = [DVec3; 3];

/// The point (s, t) of `t`: v0 + s (v1 − v0) + t (v2 − v0), as the mesh maps
/// a flat element.
fn at(tri: &Tri, s: f64, t: f64) -> DVec3 {
    tri[0] + (tri[1] - tri[0]) * s + (tri[2] - tri[0]) * t
}

/// The 4:1 split (edge midpoints), each child oriented as its parent.
fn children(t: &Tri) -> [Tri; 4] {
    let m = |a: usize, b: usize| (t[a] + t[b]) * 0.5;
    let (m01, m12, m20) = (m(0, 1), m(1, 2), m(2, 0));
    [
        [t[0], m01, m20],
        [m01, t[1], m12],
        [m20, m12, t[2]],
        [m01, m12, m20],
    ]
}

/// The node sets of degrees 1..=MAX_R (auto α), index r − 1.
fn node_sets() -> Vec<NodeSet> {
    (1..=MAX_R)
        .map(|r| NodeSet::new(r, auto_alpha(r)).expect("a valid node set"))
        .collect()
}

/// Max over the lattice of |u − I_r u| on `tri`, for every degree.
fn errors(case: &Case, tri: &Tri, sets: &[NodeSet]) -> Vec<f64> {
    let lattice: Vec<(f64, f64, f64)> = (0..=LATTICE)
        .flat_map(|a| (0..=LATTICE - a).map(move |b| (a, b)))
        .map(|(a, b)| {
            let (s, t) = (a as f64 / LATTICE as f64, b as f64 / LATTICE as f64);
            (s, t, floor_u(case, at(tri, s, t)))
        })
        .collect();
    sets.iter()
        .map(|nodes| {
            let values: Vec<f64> = nodes
                .points()
                .iter()
                .map(|&[s, t]| floor_u(case, at(tri, s, t)))
                .collect();
            let mut basis = vec![0.0; nodes.len()];
            lattice
                .iter()
                .map(|&(s, t, u)| {
                    nodes.eval_basis(s, t, &mut basis);
                    let un: f64 = basis.iter().zip(&values).map(|(l, v)| l * v).sum();
                    (u - un).abs()
                })
                .fold(0.0, f64::max)
        })
        .collect()
}

/// Unknowns of an element of degree r.
fn f(r: usize) -> usize {
    (r + 1) * (r + 2) / 2
}

/// The cheapest meshes of one element's tree within `tol`.
#[derive(Clone, Debug, Default)]
struct Cost {
    /// Unknowns with one degree r everywhere, index r − 1.
    fixed: Vec<usize>,
    /// Unknowns with a degree per element.
    hp: usize,
    /// Elements of each degree in the hp mesh, index r − 1.
    hp_degrees: Vec<usize>,
    /// Elements kept at `MAX_DEPTH` although above `tol` at some degree.
    capped: usize,
}

/// The cheapest meshes of `tri`'s tree within `tol`, for each degree and
/// per element.
fn cheapest(case: &Case, tri: &Tri, sets: &[NodeSet], tol: f64, depth: u32) -> Cost {
    let e = errors(case, tri, sets);
    let within: Vec<bool> = e.iter().map(|&e| e <= tol).collect();
    // The cheapest degree within tol; four children cost at least 4 f(1).
    let best = (1..=MAX_R).find(|&r| within[r - 1]);
    let hp_done = best.is_some_and(|r| f(r) <= 4 * f(1));
    let one = |r: usize| {
        let mut d = vec![0; MAX_R];
        d[r - 1] = 1;
        d
    };
    if (within.iter().all(|&w| w) && hp_done) || depth == MAX_DEPTH {
        let r = best.unwrap_or(1);
        return Cost {
            fixed: (1..=MAX_R).map(f).collect(),
            hp: f(r),
            hp_degrees: one(r),
            capped: usize::from(!within.iter().all(|&w| w)),
        };
    }
    let kids: Vec<Cost> = children(tri)
        .iter()
        .map(|c| cheapest(case, c, sets, tol, depth + 1))
        .collect();
    let sum = |g: &dyn Fn(&Cost) -> usize| kids.iter().map(g).sum::<usize>();
    let fixed = (1..=MAX_R)
        .map(|r| {
            if within[r - 1] {
                f(r)
            } else {
                sum(&|c| c.fixed[r - 1])
            }
        })
        .collect();
    let split_hp = sum(&|c| c.hp);
    let (hp, hp_degrees) = match best {
        Some(r) if f(r) <= split_hp => (f(r), one(r)),
        _ => (
            split_hp,
            (0..MAX_R).map(|i| sum(&|c| c.hp_degrees[i])).collect(),
        ),
    };
    Cost {
        fixed,
        hp,
        hp_degrees,
        capped: sum(&|c| c.capped),
    }
}

/// The floor's two triangles, as `floor_under_occluder` makes them.
fn floor(case: &Case) -> Vec<Tri> {
    floor_under_occluder(&case.emitter, &case.occluder).patches[0]
        .triangles
        .clone()
}

/// The cheapest mesh with one degree `r` everywhere within `tol`: its
/// triangles.
fn fixed_mesh(case: &Case, tri: &Tri, nodes: &NodeSet, tol: f64, out: &mut Vec<Tri>) {
    if errors(case, tri, std::slice::from_ref(nodes))[0] <= tol {
        out.push(*tri);
    } else {
        for c in children(tri) {
            fixed_mesh(case, &c, nodes, tol, out);
        }
    }
}

/// The solver's solution of `case` at degree r on the floor `mesh` (as
/// given: level 0), with or without the estimate.
fn solve_on(case: &Case, mesh: &[Tri], r: usize, estimate: bool) -> SolveOutcome {
    let mut surface = floor_under_occluder(&case.emitter, &case.occluder);
    surface.patches[0].triangles = mesh.to_vec();
    let cfg = SolveConfig {
        degree: r,
        alpha: auto_alpha(r),
        level: 0,
        estimate,
        ..Default::default()
    };
    solve(&problem_on(case, Arc::new(surface)), &cfg, &CpuBackend).expect("solves")
}

/// The premise: on the cheapest mesh for r within TOL, the solver's own
/// solution is the interpolant. Its nodal error is quadrature-level and its
/// max error everywhere is the interpolant's (≤ TOL), found by the solver's
/// error measure independently of this file's.
#[test]
fn on_the_shadow_family_the_floor_solution_is_the_interpolant() {
    let tol = 1e-2;
    for case in cases() {
        for r in 1..=2 {
            let nodes = NodeSet::new(r, auto_alpha(r)).unwrap();
            let mut mesh = Vec::new();
            for t in floor(&case) {
                fixed_mesh(&case, &t, &nodes, tol, &mut mesh);
            }
            let worst = mesh
                .iter()
                .map(|t| errors(&case, t, std::slice::from_ref(&nodes))[0])
                .fold(0.0, f64::max);
            let out = solve_on(&case, &mesh, r, false);
            let errors = out.channels[0].errors.unwrap();
            println!(
                "{} r = {r}: {} floor elements, interpolant {worst:.6e}, solver {:.6e}, nodes {:.1e}",
                case.name,
                mesh.len(),
                errors.global_max,
                errors.nodes_max
            );
            assert!(mesh.len() > 2, "{}: the tolerance splits", case.name);
            assert!(errors.nodes_max < 1e-11, "{}: nodes", case.name);
            assert!(worst <= tol && worst > tol / 10.0);
            radcol_tests::assert_close(case.name, r, errors.global_max, worst, 1e-10);
        }
    }
}

/// The solver's element estimates against the true element errors, on
/// meshes whose elements straddle the shadow lines: within [0.5, 2] on
/// every floor element with an error above 1e-4 of max u, at r = 1..=3.
/// With the check points at α_c = 0.12 (what r = 3 took before) for every
/// degree it fails at r = 1 already (0.13–1.59; `estimate::CHECK_ALPHA`).
#[test]
fn element_estimates_follow_the_error_across_shadow_lines() {
    for case in cases() {
        for r in 1..=3 {
            let nodes = NodeSet::new(r, auto_alpha(r)).unwrap();
            let mut mesh = Vec::new();
            for t in floor(&case) {
                fixed_mesh(&case, &t, &nodes, 1e-2, &mut mesh);
            }
            let out = solve_on(&case, &mesh, r, true);
            let estimate = out.channels[0].estimate.as_ref().unwrap();
            radcol_tests::assert_close("max u_n is the emitter's", r, estimate.scale, 1.0, 1e-12);
            let disc_mesh = out.discretization.mesh();
            let (mut lo, mut hi, mut counted) = (f64::INFINITY, 0.0f64, 0);
            for (k, (tri, est)) in mesh.iter().zip(estimate.elements_rel()).enumerate() {
                let centroid = (tri[0] + tri[1] + tri[2]) / 3.0;
                let site = disc_mesh.site(k, 1.0 / 3.0, 1.0 / 3.0);
                assert!((site.position - centroid).length() < 1e-12, "element {k}");
                let truth = errors(&case, tri, std::slice::from_ref(&nodes))[0];
                if truth > 1e-4 {
                    let e = est / truth;
                    (lo, hi, counted) = (lo.min(e), hi.max(e), counted + 1);
                }
            }
            println!(
                "{} r = {r}: {counted} elements, estimate / true {lo:.2}..{hi:.2}",
                case.name
            );
            assert!(counted > 20, "{}: too few elements", case.name);
            assert!(
                lo >= 0.5 && hi <= 2.0,
                "{} r = {r}: element effectivity {lo:.2}..{hi:.2}",
                case.name
            );
        }
    }
}

/// The cheapest meshes of `case` within `tol` (summed over the floor's
/// triangles).
fn cheapest_floor(case: &Case, sets: &[NodeSet], tol: f64) -> Cost {
    let costs: Vec<Cost> = floor(case)
        .iter()
        .map(|t| cheapest(case, t, sets, tol, 0))
        .collect();
    let total = |g: &dyn Fn(&Cost) -> usize| costs.iter().map(g).sum::<usize>();
    Cost {
        fixed: (0..MAX_R).map(|i| total(&|c| c.fixed[i])).collect(),
        hp: total(&|c| c.hp),
        hp_degrees: (0..MAX_R).map(|i| total(&|c| c.hp_degrees[i])).collect(),
        capped: total(&|c| c.capped),
    }
}

/// What the ignored study shows, at 1e-3 and r = 2, 3 (seconds): the loop
/// ends within 1.4× the unknowns of the cheapest mesh of its degree
/// (measured 1.11–1.24×; before the estimate change r = 3 took 4.5×), and a
/// degree per element would need at least 1.3× fewer than the best single
/// degree (measured 2.2× and 1.4×). Mutation runs: with the check points at
/// α_c = 0.12 the r = 2 run ends at a true 5.9e-3 against its 1e-3 target;
/// with stalls judged over 3 splits the r = 3 run stops short as singular.
#[test]
fn the_loop_ends_near_the_cheapest_mesh_of_its_degree() {
    let sets = node_sets();
    let tol = 1e-3;
    for case in cases() {
        let cost = cheapest_floor(&case, &sets, tol);
        assert_eq!(cost.capped, 0, "{}", case.name);
        let best = *cost.fixed.iter().min().expect("degrees");
        let gain = best as f64 / cost.hp as f64;
        for r in 2..=3 {
            let (unknowns, true_error, _) = adaptive(&case, r, tol, false);
            let ratio = unknowns as f64 / cost.fixed[r - 1] as f64;
            println!(
                "{} r = {r}: loop {unknowns} unknowns ({ratio:.2}x the cheapest), true {true_error:.3e}; degree per element {gain:.2}x fewer than one",
                case.name
            );
            assert!(true_error <= tol, "{} r = {r}: {true_error:.3e}", case.name);
            assert!(ratio <= 1.4, "{} r = {r}: {ratio:.2}x", case.name);
        }
        assert!(gain >= 1.3, "{}: {gain:.2}", case.name);
    }
}

/// The loop with a degree per element (`AdaptOptions::hp`) from r = 2:
/// the true max error, sampled on every element's lattice (vertices, edges,
/// interior), is within the target, with fewer unknowns than the loop at
/// one degree, and no fewer than the cheapest mesh with a degree per
/// element (which would mean the error is measured wrong).
#[test]
fn a_degree_per_element_reaches_the_target_with_fewer_unknowns() {
    let sets = node_sets();
    let tol = 1e-3;
    for case in cases() {
        let (one, _, _) = adaptive(&case, 2, tol, false);
        let (hp, true_error, _) = adaptive(&case, 2, tol, true);
        let cheapest = cheapest_floor(&case, &sets, tol).hp;
        println!(
            "{}: hp {hp} unknowns (true {true_error:.3e}), one degree {one} ({:.2}x), cheapest {cheapest}",
            case.name,
            one as f64 / hp as f64
        );
        assert!(true_error <= tol, "{}: {true_error:.3e}", case.name);
        assert!(
            hp as f64 * GAIN <= one as f64,
            "{}: {hp} against {one}",
            case.name
        );
        assert!(hp >= cheapest, "{}: {hp} below {cheapest}", case.name);
    }
}

/// The least gain (unknowns at one degree over unknowns with hp) the test
/// above accepts.
const GAIN: f64 = 1.1;

/// The study: for TOL = 1e-2, 1e-3, 1e-4, the unknowns on the floor of the
/// cheapest mesh within TOL with one degree r = 1..=4 everywhere and with a
/// degree per element; then, to 1e-2 and 1e-3, what the adaptive loop
/// reaches from level 1 at r = 1..=3 (all unknowns: the emitter's and
/// occluder's few elements included), for comparison with the cheapest
/// mesh of its degree (`cargo test --release -p radcol-tests --test
/// integration hp::study -- --ignored --nocapture`, a minute; the figures
/// are docs/accuracy.md's).
#[test]
#[ignore]
fn study() {
    let sets = node_sets();
    for case in cases() {
        for tol in [1e-2, 1e-3, 1e-4] {
            let Cost {
                fixed,
                hp,
                hp_degrees: degrees,
                capped,
            } = cheapest_floor(&case, &sets, tol);
            let best = *fixed.iter().min().unwrap();
            println!(
                "{} tol {tol:.0e}: one degree r = 1..{MAX_R}: {fixed:?} unknowns; per element: {hp} ({:.2}x fewer than the best single degree; elements of r = 1..{MAX_R}: {degrees:?}); capped {}",
                case.name,
                best as f64 / hp as f64,
                capped
            );
        }
        for tol in [1e-2, 1e-3] {
            for r in 1..=3 {
                let (unknowns, true_error, seconds) = adaptive(&case, r, tol, false);
                println!(
                    "{} tol {tol:.0e}: adaptive loop, r = {r}: {unknowns} unknowns, true {true_error:.3e}, {seconds:.1} s",
                    case.name
                );
            }
        }
    }
}

/// The adaptive loop's last step from level 1 at degree `r` to `tol`, with
/// a degree per element when `hp`: (unknowns, true max error / max u, wall
/// seconds).
fn adaptive(case: &Case, r: usize, tol: f64, hp: bool) -> (usize, f64, f64) {
    let surface = Arc::new(floor_under_occluder(&case.emitter, &case.occluder));
    let cfg = SolveConfig {
        degree: r,
        alpha: auto_alpha(r),
        level: 1,
        ..Default::default()
    };
    // Relative to max u (the emitter's 1), in which the cheapest meshes
    // were measured.
    let opts = AdaptOptions {
        target: tol,
        hp,
        relative_to: RelativeTo::MaxU,
        ..Default::default()
    };
    let t = std::time::Instant::now();
    let res = solve_adaptive(&problem_on(case, surface), &cfg, &opts, &CpuBackend, |_| {})
        .expect("solves");
    assert_eq!(res.stop, StopReason::Reached, "{} r = {r}", case.name);
    let last = res.steps.last().expect("a step");
    (
        last.unknowns,
        last.true_error.expect("exact u"),
        t.elapsed().as_secs_f64(),
    )
}
