//! Point queries (`radcol_core::query`): u_n and the iterated û_n = E + K u_n
//! at points that are not nodes.
//!
//! * The row of K at a collocation node, integrated by the query's own path
//!   (per point, per element), equals the assembled matrix's row, which the
//!   plan computes per row block with its own classes, far tables and
//!   occlusion walk: on a flat convex room, on the curved sphere and on
//!   occluding scenes (the shadow family, the Cornell box).
//! * On the sphere (closed form) û_n converges at random points at the
//!   nodal, superconvergent order, u_n at the global order r + 1.
//! * On the shadow family (exact u from Lambert's contour formula) the values
//!   at random floor points lie within the reported estimate of the exact u.

use glam::DVec3;
use radcol_core::alpha0::auto_alpha;
use radcol_core::assembly::{CpuBackend, QuadratureOptions};
use radcol_core::geometry::shapes::{box_room, floor_under_occluder};
use radcol_core::mesh::Located;
use radcol_core::problem::{Field, Problem};
use radcol_core::query::{query, PointEvaluator, QueryPoint, DEFAULT_SNAP};
use radcol_core::run::{solve, SolveConfig, SolveOutcome};
use radcol_core::scene::builtin;
use radcol_core::study::fitted_order;
use std::sync::Arc;

fn config(degree: usize, level: u32) -> SolveConfig {
    SolveConfig {
        degree,
        alpha: auto_alpha(degree),
        level,
        ..Default::default()
    }
}

/// max over the nodes of |row of K at the node (query path) − assembled row|.
fn worst_row_difference(out: &SolveOutcome, quad: &QuadratureOptions) -> f64 {
    let disc = out.discretization.clone();
    let m = out.operator.dense().expect("dense at this size");
    let eval = PointEvaluator::new(disc.clone(), quad.clone(), &out.visibility);
    let mut worst = 0.0f64;
    for (i, p) in disc.points().iter().enumerate() {
        let at = Located {
            element: p.element,
            st: p.st,
            position: p.position,
            normal: p.normal,
            distance: 0.0,
        };
        let (row, _) = eval.row(&at);
        for (a, b) in row.iter().zip(m.row(i)) {
            worst = worst.max((a - b).abs());
        }
    }
    worst
}

#[test]
fn rows_at_the_nodes_equal_the_assembled_rows() {
    let emitting = |surface| {
        Problem::new(
            Arc::new(surface),
            Field::parse("0.5").unwrap(),
            Field::parse("1").unwrap(),
        )
    };
    let cornell = builtin("cornell").unwrap().unwrap().problem();
    let cases: Vec<(&str, Problem, SolveConfig)> = vec![
        ("box room", emitting(box_room(1.0, 2.0, 1.5)), config(2, 1)),
        (
            "sphere",
            emitting(radcol_core::geometry::shapes::sphere(1.0)),
            config(2, 1),
        ),
        ("shadow floor", shadow_problem(), config(1, 2)),
        ("cornell", cornell, config(1, 0)),
    ];
    for (name, problem, cfg) in cases {
        let out = solve(
            &problem,
            &SolveConfig {
                estimate: false,
                ..cfg.clone()
            },
            &CpuBackend,
        )
        .expect("solves");
        let worst = worst_row_difference(&out, &cfg.quad);
        println!(
            "{name}: {} nodes, visibility {}, max |row difference| {worst:.2e}",
            out.discretization.len(),
            out.visibility.needed
        );
        assert!(worst <= 1e-10, "{name}: {worst:.3e}");
    }
}

/// Points spread over the unit sphere (a Fibonacci lattice), none at a node.
fn sphere_points(n: usize) -> Vec<QueryPoint> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - (2.0 * i as f64 + 1.0) / n as f64;
            let r = (1.0 - z * z).sqrt();
            let phi = golden * i as f64;
            QueryPoint {
                position: DVec3::new(r * phi.cos(), r * phi.sin(), z),
                normal: None,
            }
        })
        .collect()
}

/// [`sphere_points`] on the ellipsoid of semi-axes 1, 1.3, 0.8.
fn ellipsoid_points(n: usize) -> Vec<QueryPoint> {
    (sphere_points(n).into_iter())
        .map(|q| QueryPoint {
            position: q.position * DVec3::new(1.0, 1.3, 0.8),
            normal: None,
        })
        .collect()
}

/// Per level: mesh size h, max |u_n − u| and max |û_n − u| over `pts`,
/// and max |u_n − u| over the nodes, at degree `r`.
fn point_errors(
    problem: &Problem,
    r: usize,
    levels: std::ops::RangeInclusive<u32>,
    pts: &[QueryPoint],
) -> Vec<[f64; 4]> {
    let exact = problem.exact.clone().expect("closed form");
    levels
        .map(|level| {
            let cfg = SolveConfig {
                estimate: false,
                ..config(r, level)
            };
            let out = solve(problem, &cfg, &CpuBackend).expect("solves");
            let values = query(problem, &out, cfg.quad.clone(), pts, DEFAULT_SNAP).expect("on S");
            let mesh = out.discretization.mesh();
            let (mut eu, mut eh) = (0.0f64, 0.0f64);
            for v in &values {
                let [s, t] = v.located.st;
                let u = exact.eval(&mesh.site(v.located.element, s, t));
                eu = eu.max((v.channels[0].u - u).abs());
                eh = eh.max((v.channels[0].iterated - u).abs());
            }
            let nodes = out.channels[0].errors.expect("exact u known").nodes_max;
            println!(
                "  r = {r}, level {level}: max |u_n - u| {eu:.3e}, max |û_n - u| {eh:.3e} \
                 at {} points; nodes {nodes:.3e}",
                pts.len()
            );
            [out.h, eu, eh, nodes]
        })
        .collect()
}

/// û_n at points that are not nodes is as accurate as u_n at the nodes
/// (within 3×, at every level) and converges at least at the theory's nodal
/// order (r + 3 for odd r at α0, eq. 36; r + 2 for even r, eq. 39; less 0.3
/// for the fit), where u_n converges at the global order r + 1 (within 0.35:
/// the max over 60 points sees each level's mesh at different places).
#[test]
fn iterated_solution_superconverges_at_any_point() {
    let sphere = radcol_tests::sphere_closed_form();
    let ellipsoid = radcol_tests::ellipsoid_manufactured();
    let cases = [
        ("sphere", &sphere, 1, 1..=4, sphere_points(60)),
        ("sphere", &sphere, 2, 2..=4, sphere_points(60)),
        ("ellipsoid", &ellipsoid, 1, 1..=3, ellipsoid_points(60)),
    ];
    for (name, problem, r, levels, pts) in cases {
        println!("{name}, r = {r}:");
        let rows = point_errors(problem, r, levels, &pts);
        let h: Vec<f64> = rows.iter().map(|x| x[0]).collect();
        let order = |i: usize| fitted_order(&h, &rows.iter().map(|x| x[i]).collect::<Vec<_>>());
        let (ou, oh, on) = (order(1), order(2), order(3));
        let nodal = if r % 2 == 1 { r + 3 } else { r + 2 } as f64;
        println!(
            "  fitted orders: u_n {ou:.2}, û_n {oh:.2}, nodes {on:.2}; theory {} and {nodal}",
            r + 1
        );
        assert!(
            (ou - (r + 1) as f64).abs() <= 0.35,
            "{name} r = {r}: u_n order {ou:.2}"
        );
        assert!(oh >= nodal - 0.3, "{name} r = {r}: û_n order {oh:.2}");
        for x in &rows {
            assert!(
                x[2] <= 3.0 * x[3],
                "{name} r = {r}: û_n {:.3e}, nodes {:.3e}",
                x[2],
                x[3]
            );
        }
    }
}

fn shadow_problem() -> Problem {
    let case = &crate::shadows::cases()[0];
    let surface = floor_under_occluder(&case.emitter, &case.occluder);
    crate::shadows::problem_on(case, Arc::new(surface))
}

/// Points on the shadow family's floor ([-1, 1]², z = 0), a jittered grid
/// that avoids the element edges of the uniform meshes.
fn floor_points(n: usize) -> Vec<QueryPoint> {
    let mut pts = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let x = -1.0 + 2.0 * (i as f64 + 0.37 + 0.21 * ((7 * j) % 5) as f64 / 5.0) / n as f64;
            let y = -1.0 + 2.0 * (j as f64 + 0.43 + 0.17 * ((3 * i) % 7) as f64 / 7.0) / n as f64;
            pts.push(QueryPoint {
                position: DVec3::new(x, y, 0.0),
                normal: Some(DVec3::Z),
            });
        }
    }
    pts
}

/// On the floor u = ρ F(visible part of the emitter), and the emitter's u_n
/// is exactly 1 (ρ = 0, E = 1), the occluder's 0: û_n = ρ K u_n is then the
/// exact u up to the element integrals, so û_n checks the query's clipped
/// visibility against Lambert's contour formula at every point. u_n lies
/// within its element's estimate at 99 % of the points and within 1.5× of
/// it at all (the estimate is not a bound: its effectivity is what the
/// estimate's tests measure). The point's own estimate, |û_n − u_n| plus
/// what the elements it sees carry (nothing here: the emitter and the
/// occluder are exact), is then u_n's error itself, to rounding.
#[test]
fn values_in_the_shadow_family_lie_within_the_estimate() {
    let problem = shadow_problem();
    let exact = problem.exact.clone().unwrap();
    let pts = floor_points(20);
    for level in [2, 3, 4] {
        let cfg = config(1, level);
        let out = solve(&problem, &cfg, &CpuBackend).expect("solves");
        let values = query(&problem, &out, cfg.quad.clone(), &pts, DEFAULT_SNAP).expect("on S");
        let mesh = out.discretization.mesh();
        let e = out.channels[0].estimate.as_ref().expect("estimated");
        let (mut within, mut worst_ratio, mut worst_hat) = (0, 0.0f64, 0.0f64);
        for v in &values {
            let [s, t] = v.located.st;
            let u = exact.eval(&mesh.site(v.located.element, s, t));
            let c = &v.channels[0];
            let est = e.elements[v.located.element] + e.visibility_bound;
            within += usize::from((c.u - u).abs() <= est);
            worst_ratio = worst_ratio.max((c.u - u).abs() / est);
            worst_hat = worst_hat.max((c.iterated - u).abs());
            let at_point = c.estimate.expect("estimated");
            assert!(
                ((c.u - u).abs() - at_point).abs() <= 1e-12,
                "level {level}: point estimate {at_point:e}, error {:e}",
                (c.u - u).abs()
            );
        }
        let n = pts.len();
        println!(
            "level {level}: u_n within its estimate at {within}/{n} points (worst error/estimate \
             {worst_ratio:.2}); max |û_n - u| {worst_hat:.2e}"
        );
        assert!(within * 100 >= 99 * n, "level {level}: {within}/{n}");
        assert!(worst_ratio <= 1.5, "level {level}: {worst_ratio:.2}");
        assert!(
            worst_hat <= 1e-12,
            "level {level}: û_n off by {worst_hat:.3e}"
        );
    }
}

/// A closed box with ρ = 1/2 and E = 1 has u ≡ 2 (its rows of K sum to 1,
/// every point seeing the whole room). At points on its edges and corners,
/// each asked from every face that meets there (the normal names it), û_n
/// is that limit, 2, where it used to miss the faces seen edge-on (1.5 on
/// an edge, 1.25 at a corner); and u_n is 2 there too.
#[test]
fn edges_and_corners_of_a_closed_room_give_the_limit_from_their_face() {
    let (lx, ly, lz) = (1.0, 2.0, 1.5);
    let surface = Arc::new(box_room(lx, ly, lz));
    let problem = Problem::new(surface, Field::Constant(0.5), Field::Constant(1.0));
    let cfg = config(1, 1);
    let out = solve(&problem, &cfg, &CpuBackend).unwrap();
    // Inner normals of the six walls.
    let faces = [
        DVec3::Z,
        -DVec3::Z,
        DVec3::Y,
        -DVec3::Y,
        DVec3::X,
        -DVec3::X,
    ];
    let on = |n: DVec3, p: DVec3| {
        let (lo, hi) = (0.0, n.abs().dot(DVec3::new(lx, ly, lz)));
        let coord = n.abs().dot(p);
        (coord - if n.max_element() > 0.0 { lo } else { hi }).abs() < 1e-12
    };
    let mut points = Vec::new();
    let corners = [0.0, 1.0];
    let mids = [0.0, 0.5, 1.0];
    for x in mids {
        for y in mids {
            for z in mids {
                let p = DVec3::new(x * lx, y * ly, z * lz);
                let ends = [x, y, z].iter().filter(|v| corners.contains(v)).count();
                if ends < 2 {
                    continue; // not on an edge
                }
                for n in faces.iter().filter(|&&n| on(n, p)) {
                    points.push(QueryPoint {
                        position: p,
                        normal: Some(*n),
                    });
                }
            }
        }
    }
    // 12 edge midpoints × 2 faces + 8 corners × 3 faces.
    assert_eq!(points.len(), 12 * 2 + 8 * 3);
    let values = query(&problem, &out, cfg.quad.clone(), &points, DEFAULT_SNAP).unwrap();
    for (q, v) in points.iter().zip(&values) {
        let c = v.channels[0];
        assert!(
            (c.iterated - 2.0).abs() < 1e-7 && (c.u - 2.0).abs() < 1e-7,
            "at {} from the face {}: û_n = {}, u_n = {}",
            q.position,
            q.normal.unwrap(),
            c.iterated,
            c.u
        );
    }
}

/// The estimate of û_n covers its error at every point: on the sphere
/// (closed form) and the ellipsoid (manufactured u), r = 1, three levels,
/// 60 points each. It is ρ(P) times P's view-weighted mean of the element
/// estimates, so it is also below the estimate of u_n on P's element on
/// average (û_n being the better value).
#[test]
fn the_estimate_of_the_iterated_value_covers_its_error() {
    let sphere = radcol_tests::sphere_closed_form();
    let ellipsoid = radcol_tests::ellipsoid_manufactured();
    let cases = [
        ("sphere", &sphere, sphere_points(60)),
        ("ellipsoid", &ellipsoid, ellipsoid_points(60)),
    ];
    for (name, problem, pts) in cases {
        let exact = problem.exact.clone().expect("closed form");
        for level in 1..=3 {
            let cfg = config(1, level);
            let out = solve(problem, &cfg, &CpuBackend).expect("solves");
            let values = query(problem, &out, cfg.quad.clone(), &pts, DEFAULT_SNAP).unwrap();
            let mesh = out.discretization.mesh();
            let e = out.channels[0].estimate.as_ref().expect("estimated");
            let (mut worst, mut mean_ratio) = (0.0f64, 0.0);
            for v in &values {
                let [s, t] = v.located.st;
                let u = exact.eval(&mesh.site(v.located.element, s, t));
                let c = &v.channels[0];
                let est = c.iterated_estimate.expect("estimated");
                worst = worst.max((c.iterated - u).abs() / est);
                let figure = e.elements[v.located.element] + e.visibility_bound;
                mean_ratio += est / figure / pts.len() as f64;
            }
            println!(
                "{name}, level {level}: max |û_n - u| / its estimate {worst:.3}; \
                 its estimate / u_n's, mean {mean_ratio:.3}"
            );
            assert!(worst <= 1.0, "{name}, level {level}: {worst:.3}");
            assert!(mean_ratio < 1.0, "{name}, level {level}: {mean_ratio:.3}");
        }
    }
}

/// Points a hair inside every element of the Cornell box from each of its
/// corners (1e-7 of the way to its centre), as a program asking for the
/// value at each input vertex does. Next to a block's foot corner the
/// visible part of the floor repeats a vertex; its fan held triangles of
/// no area, which the adaptive quadrature split into segments covering
/// each other, doubling its work at every level down to its depth limit
/// (8 to 270 s for one point). The kernel evaluations of every point's
/// row are now within 20 times the median point's.
#[test]
fn points_next_to_corners_cost_no_more_than_others() {
    let cornell = builtin("cornell").unwrap().unwrap().problem();
    let cfg = SolveConfig {
        estimate: false,
        ..config(1, 0)
    };
    let out = solve(&cornell, &cfg, &CpuBackend).unwrap();
    let mesh = out.discretization.mesh().clone();
    let eval = PointEvaluator::new(
        out.discretization.clone(),
        cfg.quad.clone(),
        &out.visibility,
    );
    let mut evals = Vec::new();
    for k in 0..mesh.len() {
        let v = mesh.vertices(k);
        let centre = (v[0] + v[1] + v[2]) / 3.0;
        let normal = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
        for c in v {
            let q = QueryPoint {
                position: c + 1e-7 * (centre - c),
                normal: Some(normal),
            };
            let at = eval.locate(&q, 1e-6).expect("on the surface");
            evals.push((eval.row(&at).1, k, c));
        }
    }
    let mut sorted: Vec<u64> = evals.iter().map(|e| e.0).collect();
    sorted.sort_unstable();
    let median = sorted[sorted.len() / 2];
    let worst = evals.iter().max_by_key(|e| e.0).unwrap();
    println!(
        "{} points: kernel evaluations median {median}, most {} (element {}, corner {:?})",
        evals.len(),
        worst.0,
        worst.1,
        worst.2
    );
    assert!(worst.0 <= 20 * median, "{worst:?} against median {median}");
}

/// A well resolved region that sees a badly resolved one: the sphere
/// (closed form) meshed at level 4 on one of its eight base triangles and
/// at level 1 on the rest. On the fine part the residual is small but u_n's
/// error is what the coarse part carries to it (u − u_n = η + ρ K (u − u_n),
/// and K averages the error over the whole sphere): the point's estimate,
/// |û_n − u_n| plus û_n's estimate, covers it at every point (measured:
/// the error is at most 0.03 of it, a pessimistic cover: the coarse part's
/// errors cancel in part in the mean), where its element's estimate alone
/// falls short (up to 1.97 times below the error).
#[test]
fn a_point_estimate_counts_the_error_its_point_sees() {
    use radcol_core::mesh::{Element, Mesh};
    use radcol_core::run::solve_on_mesh;
    let problem = radcol_tests::sphere_closed_form();
    let exact = problem.exact.clone().unwrap();
    let coarse = Mesh::new(problem.surface.clone(), 1);
    let mut elements: Vec<Element> = Vec::new();
    let mut fine = Vec::new();
    for (i, e) in coarse.elements().iter().enumerate() {
        if i >= 4 {
            elements.push(*e);
            continue;
        }
        let mut level = vec![*e];
        for _ in 0..3 {
            level = level.iter().flat_map(|x| x.children()).collect();
        }
        fine.extend(elements.len()..elements.len() + level.len());
        elements.extend(level);
    }
    let mesh = Arc::new(Mesh::from_elements(problem.surface.clone(), 1, elements));
    let cfg = config(1, 1);
    let out = solve_on_mesh(&problem, &cfg, mesh.clone(), &CpuBackend, None).expect("solves");
    let e = out.channels[0].estimate.as_ref().unwrap();
    // Points inside the fine elements.
    let pts: Vec<QueryPoint> = fine
        .iter()
        .step_by(7)
        .map(|&k| QueryPoint::at(mesh.position(k, 0.27, 0.31)))
        .collect();
    let values = query(&problem, &out, cfg.quad.clone(), &pts, DEFAULT_SNAP).unwrap();
    let (mut old_worst, mut new_worst) = (0.0f64, 0.0f64);
    for v in &values {
        let [s, t] = v.located.st;
        let u = exact.eval(&mesh.site(v.located.element, s, t));
        let c = &v.channels[0];
        let err = (c.u - u).abs();
        old_worst = old_worst.max(err / (e.elements[v.located.element] + e.visibility_bound));
        new_worst = new_worst.max(err / c.estimate.unwrap());
    }
    println!(
        "{} points on the fine part: error / element estimate up to {old_worst:.2}, \
         error / point estimate up to {new_worst:.2}",
        pts.len()
    );
    assert!(old_worst > 1.2, "the case tests nothing: {old_worst:.2}");
    assert!(new_worst <= 1.0, "{new_worst:.2}");
}
