//! Occlusion, checked against identities and closed forms.
//!
//! * A closed room with a floating cube in it: every ray from a point of the
//!   scene ends on a front face, so ∫ G V dS_Q = π and each row of the
//!   geometric matrix sums to 1 (Lemma 1(c) with visibility); with constant ρ
//!   and E the solution is the constant E / (1 - ρ).
//! * The same identity with a scanned mesh in a closed room: the Stanford
//!   bunny (200 triangles, closed) floating in a 550 mm box, where a pair
//!   sees many occluders and their shadows are merged before subtraction.
//! * Energy balance in that closed scene with per-material ρ and E: what is
//!   emitted is absorbed, ∫ E = ∫ (1 - ρ) K u, up to the discretization error.
//! * A blocker that hides exactly the half of an emitter beyond a line: the
//!   receiver's radiosity equals ρ times the closed-form view factor of the
//!   visible rectangle (Hottel's corner formula with superposition), and is
//!   half the unblocked value under the blocker's edge.
//! * The decision whether a scene needs visibility at all.
//! * Pairs the plan culls although they face each other: every ray between
//!   them (row points against a grid of the column element) is blocked.

use glam::DVec3;
use radcol_core::assembly::{AssemblyBackend, CpuBackend, VisibilityMode};
use radcol_core::run::{solve, SolveConfig, SolveOutcome};
use radcol_core::scene::{Material, Scene, SceneBuilder};
use radcol_core::visibility::analyze;
use radcol_tests::{assert_close, assert_symmetric};

/// The 12 triangles of the axis-aligned box [lo, hi], normals pointing out
/// (`inward` false) or in.
fn box_mesh(lo: DVec3, hi: DVec3, inward: bool) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let p = |i: u32| {
        DVec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    };
    let positions = (0..8).map(p).collect();
    // Quads listed counter-clockwise seen from outside.
    let quads: [[u32; 4]; 6] = [
        [0, 2, 3, 1], // z = lo
        [4, 5, 7, 6], // z = hi
        [0, 1, 5, 4], // y = lo
        [2, 6, 7, 3], // y = hi
        [0, 4, 6, 2], // x = lo
        [1, 3, 7, 5], // x = hi
    ];
    let mut tris = Vec::new();
    for [a, b, c, d] in quads {
        for t in [[a, b, c], [a, c, d]] {
            tris.push(if inward { [t[0], t[2], t[1]] } else { t });
        }
    }
    (positions, tris)
}

/// A 2 × 2 × 2 room with a cube of side 0.6 floating at its centre.
fn room_with_cube(room: Material, cube: Material) -> Scene {
    let mut b = SceneBuilder::new("room-with-cube");
    let mr = b.add_material(room).unwrap();
    let mc = b.add_material(cube).unwrap();
    let (p, t) = box_mesh(DVec3::ZERO, DVec3::splat(2.0), true);
    b.add_mesh_f64("room", &p, &t, mr).unwrap();
    let (p, t) = box_mesh(DVec3::splat(0.7), DVec3::splat(1.3), false);
    b.add_mesh_f64("cube", &p, &t, mc).unwrap();
    b.build().unwrap()
}

fn cfg(degree: usize, level: u32) -> SolveConfig {
    radcol_tests::lu_config(degree, level)
}

fn run(scene: &Scene, cfg: &SolveConfig, backend: &dyn AssemblyBackend) -> SolveOutcome {
    solve(&scene.problem(), cfg, backend).unwrap()
}

#[test]
fn closed_room_with_a_cube_has_unit_row_sums_and_the_constant_solution() {
    let rho = [0.3, 0.6, 0.9];
    let e = [1.0, 2.0, 0.5];
    let m = |name: &str| Material::emitter(name, rho, e);
    let scene = room_with_cube(m("walls"), m("cube"));
    assert!(analyze(&scene.surface).needed);
    for (r, level) in [(0, 1), (1, 1), (2, 0)] {
        let out = run(&scene, &cfg(r, level), &CpuBackend);
        assert!(out.plan.pairs_partial > 0, "the cube must cast shadows");
        let mut worst = 0.0f64;
        for i in 0..out.operator.dense().expect("dense").nrows() {
            let row_sum: f64 = out.operator.dense().expect("dense").row(i).iter().sum();
            worst = worst.max((row_sum - 1.0).abs());
            assert_close(&format!("r={r} row sum"), i, row_sum, 1.0, 1e-11);
        }
        for (c, ch) in out.channels.iter().enumerate() {
            let exact = e[c] / (1.0 - rho[c]);
            for (i, &u) in ch.solution.nodal().iter().enumerate() {
                assert_close(&format!("r={r} u_{}", ch.name), i, u, exact, 1e-9 * exact);
            }
        }
        println!(
            "r = {r}, level {level}: {} unknowns, max |row sum - 1| = {worst:.2e}, {:?}",
            out.operator.dense().expect("dense").nrows(),
            out.plan
        );
    }
}

/// The bunny group of one of the bench's bunny rooms (`benches/data`), as
/// positions and triangles.
fn bunny_mesh(file: &str) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let path = format!("{}/../benches/data/{file}", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let (mut positions, mut tris, mut group) = (Vec::new(), Vec::new(), "");
    for line in text.lines() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                let x: Vec<f64> = words.map(|w| w.parse().unwrap()).collect();
                positions.push(DVec3::new(x[0], x[1], x[2]));
            }
            Some("g") => group = if line.ends_with("bunny") { "bunny" } else { "" },
            Some("f") if group == "bunny" => {
                let i: Vec<u32> = words.map(|w| w.parse::<u32>().unwrap() - 1).collect();
                tris.push([i[0], i[1], i[2]]);
            }
            _ => {}
        }
    }
    // Keep the bunny's vertices only, renumbered.
    let first = tris.iter().flatten().min().copied().unwrap();
    let positions = positions[first as usize..].to_vec();
    let tris = tris.iter().map(|t| t.map(|i| i - first)).collect();
    (positions, tris)
}

#[test]
fn closed_room_with_a_bunny_has_unit_row_sums() {
    let (rho, e) = ([0.5, 0.7, 0.9], [1.0, 2.0, 0.5]);
    let mut b = SceneBuilder::new("closed-bunny-room");
    let m = b.add_material(Material::emitter("all", rho, e)).unwrap();
    let (p, t) = box_mesh(DVec3::ZERO, DVec3::splat(550.0), true);
    b.add_mesh_f64("room", &p, &t, m).unwrap();
    let (p, t) = bunny_mesh("bunny_room_200.obj");
    // Lifted 20 mm off the floor: no contact line, a closed free space.
    let p: Vec<DVec3> = p.iter().map(|x| *x + DVec3::new(0.0, 20.0, 0.0)).collect();
    b.add_mesh_f64("bunny", &p, &t, m).unwrap();
    let scene = b.build().unwrap();
    let out = run(&scene, &cfg(1, 0), &CpuBackend);
    assert!(out.plan.pairs_partial > 10_000, "{:?}", out.plan);
    let a = out.operator.dense().expect("dense");
    let mut worst = 0.0f64;
    for i in 0..a.nrows() {
        let row_sum: f64 = a.row(i).iter().sum();
        worst = worst.max((row_sum - 1.0).abs());
        assert_close("row sum", i, row_sum, 1.0, 1e-11);
    }
    for (c, ch) in out.channels.iter().enumerate() {
        let exact = e[c] / (1.0 - rho[c]);
        for (i, &u) in ch.solution.nodal().iter().enumerate() {
            assert_close(&format!("u_{}", ch.name), i, u, exact, 1e-8 * exact);
        }
    }
    println!(
        "{} unknowns, max |row sum - 1| = {worst:.2e}, {:?}",
        a.nrows(),
        out.plan
    );
}

#[test]
fn closed_room_with_a_cube_balances_energy() {
    // A bright cube in a dim room: emission only on the cube.
    let scene = room_with_cube(
        Material::diffuse("walls", [0.8, 0.5, 0.2]),
        Material::emitter("cube", [0.4, 0.4, 0.4], [1.0, 1.0, 1.0]),
    );
    let mut previous = [f64::INFINITY; 3];
    // Measured: 9.4e-2 .. 1.1e-1 at level 0, 4.6e-3 .. 5.1e-3 at level 2,
    // 3.9e-4 .. 9.3e-4 at level 3 (the edges where walls meet and the cube's
    // shadow boundaries limit the rate).
    for level in 0..=2 {
        let out = run(&scene, &cfg(1, level), &CpuBackend);
        for (c, ch) in out.channels.iter().enumerate() {
            // Irradiance H = K u at the nodes (the geometric matrix holds the
            // 1/π); a fraction 1 - ρ of it is absorbed.
            let u = ch.solution.nodal();
            let mut h = vec![0.0; u.len()];
            out.operator.dense().expect("dense").matvec(u, &mut h);
            let absorbed: Vec<f64> = h.iter().zip(&ch.rho).map(|(h, r)| (1.0 - r) * h).collect();
            let absorbed = radcol_core::solution::integrate_nodal(&out.discretization, &absorbed);
            let imbalance = (absorbed - ch.integral_e).abs() / ch.integral_e;
            println!(
                "level {level} {}: emitted {:.12}, absorbed {:.12}, relative imbalance {imbalance:.3e}",
                ch.name, ch.integral_e, absorbed
            );
            assert!(
                imbalance < 0.2,
                "level {level} {}: {imbalance:.3e}",
                ch.name
            );
            if level == 2 {
                assert!(imbalance < 1e-2, "level 2 {}: {imbalance:.3e}", ch.name);
            }
            assert!(
                imbalance < previous[c],
                "the imbalance is a discretization error and must shrink with h"
            );
            previous[c] = imbalance;
        }
    }
}

/// The room with the cube is symmetric under x ↔ y, triangulation included:
/// so is its solution, shadows and all.
#[test]
fn occluded_symmetric_scene_gives_symmetric_radiosity() {
    let scene = room_with_cube(
        Material::diffuse("walls", [0.7, 0.5, 0.3]),
        Material::emitter("cube", [0.2; 3], [1.0, 2.0, 3.0]),
    );
    let out = run(&scene, &cfg(1, 1), &CpuBackend);
    assert!(out.plan.pairs_partial > 0);
    assert_symmetric(
        &out,
        |x| DVec3::new(x.y, x.x, x.z),
        "room with cube: x <-> y",
        1e-12,
    );
}

/// Exact clipping against rays cast per quadrature point (the textbook way,
/// `VisibilityMode::Rays`), at the same rules: rays integrate a function that
/// jumps at the shadow boundary, so the blocker's closed form and the closed
/// room's unit row sums are met far less accurately.
#[test]
fn clipping_is_exact_where_rays_are_not() {
    let (a, h, rho) = (1.0, 1.0, 0.5);
    let scene = blocker_scene(a, h, rho);
    let mut rays = cfg(1, 2);
    rays.quad.visibility = VisibilityMode::Rays;
    let clip_err = blocker_error(&run(&scene, &cfg(1, 2), &CpuBackend), a, h, rho).0;
    let rays_err = blocker_error(&run(&scene, &rays, &CpuBackend), a, h, rho).0;
    println!("blocker, max |u - ρ F|: clipping {clip_err:.2e}, rays {rays_err:.2e}");

    let m = Material::emitter("m", [0.5; 3], [1.0; 3]);
    let room = room_with_cube(m.clone(), m);
    let mut rays = cfg(1, 1);
    rays.quad.visibility = VisibilityMode::Rays;
    let row_error = |out: &SolveOutcome| {
        (0..out.operator.dense().expect("dense").nrows())
            .map(|i| {
                (out.operator
                    .dense()
                    .expect("dense")
                    .row(i)
                    .iter()
                    .sum::<f64>()
                    - 1.0)
                    .abs()
            })
            .fold(0.0, f64::max)
    };
    let clip_rows = row_error(&run(&room, &cfg(1, 1), &CpuBackend));
    let rays_rows = row_error(&run(&room, &rays, &CpuBackend));
    println!("room with cube, max |row sum - 1|: clipping {clip_rows:.2e}, rays {rays_rows:.2e}");
    assert!(clip_err < 1e-10 && clip_rows < 1e-11);
    assert!(rays_err > 1e4 * clip_err.max(1e-16), "{rays_err:.2e}");
    assert!(rays_rows > 1e4 * clip_rows.max(1e-16), "{rays_rows:.2e}");
}

/// ∫ over the rectangle [x1, x2] × [y1, y2] at height h of cosθ cosθ' / (π r²),
/// seen from the origin facing up: Hottel's corner formula
/// F(a, b) = (1/2π) [a/√(1+a²) atan(b/√(1+a²)) + b/√(1+b²) atan(a/√(1+b²))]
/// (odd in a and b), combined by inclusion–exclusion.
fn view_factor(x1: f64, x2: f64, y1: f64, y2: f64, h: f64) -> f64 {
    let corner = |x: f64, y: f64| {
        let (a, b) = (x / h, y / h);
        let (sa, sb) = ((1.0 + a * a).sqrt(), (1.0 + b * b).sqrt());
        (a / sa * (b / sa).atan() + b / sb * (a / sb).atan()) / (2.0 * std::f64::consts::PI)
    };
    corner(x2, y2) - corner(x1, y2) - corner(x2, y1) + corner(x1, y1)
}

/// The closed form against composite Simpson quadrature of the integrand
/// h² / (π (x² + y² + h²)²), on rectangles in every position relative to the
/// foot of the perpendicular.
#[test]
fn view_factor_closed_form_matches_quadrature() {
    let simpson = |x1: f64, x2: f64, y1: f64, y2: f64, h: f64| {
        let n = 400;
        let w = |i: usize| match i {
            0 => 1.0,
            i if i == n => 1.0,
            i if i % 2 == 1 => 4.0,
            _ => 2.0,
        };
        let (dx, dy) = ((x2 - x1) / n as f64, (y2 - y1) / n as f64);
        let mut sum = 0.0;
        for i in 0..=n {
            for j in 0..=n {
                let (x, y) = (x1 + i as f64 * dx, y1 + j as f64 * dy);
                let d = x * x + y * y + h * h;
                sum += w(i) * w(j) * h * h / (std::f64::consts::PI * d * d);
            }
        }
        sum * dx * dy / 9.0
    };
    for (x1, x2, y1, y2, h) in [
        (-1.0, 1.0, -1.0, 1.0, 1.0),
        (-0.3, 1.7, -1.0, 0.4, 0.8),
        (0.5, 2.0, 0.25, 1.0, 1.0),
        (-2.0, -0.5, -1.0, 1.0, 0.5),
    ] {
        let want = simpson(x1, x2, y1, y2, h);
        let got = view_factor(x1, x2, y1, y2, h);
        radcol_core::assert_close!(got, want, 1e-9, "{got} vs {want}");
    }
    // The whole plane is seen whole.
    radcol_core::assert_close!(view_factor(-1e8, 1e8, -1e8, 1e8, 1.0), 1.0, 1e-7);
}

/// Emitter z = h (ρ = 0, E = 1) over a floor z = 0 (ρ), both [-a, a]², and a
/// black blocker x ≥ 0 at z = h/2 wide enough that a segment from the floor
/// to the light crosses it exactly when x_P + x_Q ≥ 0.
fn blocker_scene(a: f64, h: f64, rho: f64) -> Scene {
    let mut b = SceneBuilder::new("blocker");
    let light = b
        .add_material(Material::emitter("light", [0.0; 3], [1.0; 3]))
        .unwrap();
    let floor = b
        .add_material(Material::diffuse("floor", [rho; 3]))
        .unwrap();
    let black = b
        .add_material(Material::diffuse("black", [0.0; 3]))
        .unwrap();
    let square = |z: f64, x0: f64, x1: f64, y0: f64, y1: f64| {
        vec![
            DVec3::new(x0, y0, z),
            DVec3::new(x1, y0, z),
            DVec3::new(x1, y1, z),
            DVec3::new(x0, y1, z),
        ]
    };
    let up = [[0, 1, 2], [0, 2, 3]];
    let down = [[0, 2, 1], [0, 3, 2]];
    b.add_mesh_f64("light", &square(h, -a, a, -a, a), &down, light)
        .unwrap();
    b.add_mesh_f64("floor", &square(0.0, -a, a, -a, a), &up, floor)
        .unwrap();
    // Half-plane x ≥ 0 at mid-height, wide enough that a segment from the
    // floor to the light crosses it exactly when x_P + x_Q ≥ 0.
    b.add_mesh_f64(
        "blocker",
        &square(0.5 * h, 0.0, 3.0, -3.0, 3.0),
        &down,
        black,
    )
    .unwrap();
    b.build().unwrap()
}

/// Largest |u - ρ F_visible| over the floor nodes, and their number.
fn blocker_error(out: &SolveOutcome, a: f64, h: f64, rho: f64) -> (f64, usize) {
    let u = out.channels[0].solution.nodal();
    let mut worst = 0.0f64;
    let mut count = 0;
    for (i, p) in out.discretization.points().iter().enumerate() {
        let x = p.position;
        if x.z.abs() > 1e-12 {
            continue;
        }
        let want = rho * view_factor(-a - x.x, (-x.x).min(a) - x.x, -a - x.y, a - x.y, h);
        worst = worst.max((u[i] - want).abs());
        count += 1;
    }
    (worst, count)
}

#[test]
fn a_blocker_hides_the_closed_form_part_of_the_light() {
    let (a, h, rho) = (1.0, 1.0, 0.5);
    let scene = blocker_scene(a, h, rho);
    assert!(analyze(&scene.surface).needed);

    let mut outs = vec![("cpu", run(&scene, &cfg(2, 2), &CpuBackend))];
    // The GPU backend must honour visibility too (partly visible pairs are
    // integrated on the CPU while the device fills the far pairs).
    if let Some(ctx) = radcol_gpu::testing::test_context("blocker") {
        let gpu = radcol_gpu::GpuBackend::new(ctx, radcol_gpu::Precision::Auto).unwrap();
        outs.push(("gpu", run(&scene, &cfg(2, 2), &gpu)));
    }
    for (name, out) in &outs {
        let u = out.channels[0].solution.nodal();
        let mut checked = 0;
        let mut worst = 0.0f64;
        for (i, p) in out.discretization.points().iter().enumerate() {
            let x = p.position;
            if x.z.abs() > 1e-12 {
                continue;
            }
            let visible = view_factor(-a - x.x, (-x.x).min(a) - x.x, -a - x.y, a - x.y, h);
            let want = rho * visible;
            let tol = if out.backend.precision == radcol_core::assembly::Scalar::F64 {
                1e-10
            } else {
                1e-5
            };
            worst = worst.max((u[i] - want).abs());
            assert_close(&format!("{name} floor u"), i, u[i], want, tol);
            checked += 1;
        }
        println!("{name}: {checked} floor nodes, max |u - ρ F_visible| = {worst:.2e}");
        assert!(checked > 0);
    }

    // Under the blocker's edge exactly half of the light is seen.
    let full = view_factor(-a, a, -a, a, h);
    let half = view_factor(-a, 0.0, -a, a, h);
    radcol_core::assert_close!(half / full, 0.5, 1e-15);
}

#[test]
fn unoccluded_scenes_are_recognised() {
    use radcol_core::geometry::shapes::{box_room, ellipsoid, sphere};
    for s in [
        sphere(1.0),
        ellipsoid(1.0, 2.0, 0.5),
        box_room(1.0, 2.0, 3.0),
    ] {
        assert!(!analyze(&s).needed, "{}", s.name);
    }
    for (name, needed) in [("room", false), ("plates", false), ("cornell", true)] {
        let scene = radcol_core::scene::builtin(name).unwrap().unwrap();
        let v = analyze(&scene.surface);
        assert_eq!(v.needed, needed, "{name}: {}", v.reason);
    }
    let m = Material::diffuse("m", [0.5; 3]);
    let with_cube = room_with_cube(m.clone(), m);
    assert!(analyze(&with_cube.surface).needed);
}

/// The plan culls element pairs hidden from every row point (their clipped
/// visible region is empty) instead of clipping them at every fill. Checked
/// by rays against every occluder of the scene, not the pair's candidates:
/// for each culled pair, each row point P and grid point Q that face each
/// other (where G(P, Q) > 0 without occlusion), some occluder crosses PQ.
#[test]
fn pairs_that_face_each_other_are_culled_only_when_every_ray_is_blocked() {
    use radcol_core::assembly::plan::{AssemblyPlan, PairClass};
    use radcol_core::assembly::QuadratureOptions;
    use radcol_core::discretization::Discretization;
    use radcol_core::mesh::Mesh;
    use radcol_core::nodes::NodeSet;
    use radcol_core::visibility::clip::blocks;
    use std::sync::Arc;

    let m = Material::diffuse("m", [0.5; 3]);
    let scene = room_with_cube(m.clone(), m);
    let mesh = Arc::new(Mesh::new(scene.surface.clone(), 2));
    let disc = Arc::new(Discretization::new(mesh, NodeSet::new(1, 0.2).unwrap()));
    let plan = AssemblyPlan::new(
        disc.clone(),
        QuadratureOptions::default(),
        &analyze(&scene.surface),
    );
    let occ = plan.occluders().expect("the cube occludes");
    let (n, f) = (disc.mesh().len(), disc.max_nodes_per_element());
    let grid: Vec<(f64, f64)> = (0..=4)
        .flat_map(|i| (0..=4 - i).map(move |j| (i as f64 / 4.0, j as f64 / 4.0)))
        .map(|(s, t)| (0.05 + 0.9 * s, 0.05 + 0.9 * t))
        .filter(|(s, t)| s + t <= 0.95)
        .collect();
    let (mut hidden, mut partial) = (0, 0);
    for kp in 0..n {
        let rows = &disc.points()[kp * f..(kp + 1) * f];
        for k in 0..n {
            match plan.class(kp, k) {
                PairClass::Partial => partial += 1,
                PairClass::Culled if k != kp => {
                    let mut facing = false;
                    for p in rows {
                        for &(s, t) in &grid {
                            let q = disc.mesh().point(k, s, t);
                            let d = q.position - p.position;
                            if d.dot(p.normal) > 1e-9 && -d.dot(q.normal) > 1e-9 {
                                facing = true;
                                assert!(
                                    (0..occ.len() as u32).any(|i| blocks(
                                        p.position,
                                        q.position,
                                        occ.get(i)
                                    )),
                                    "pair ({kp}, {k}) culled, but {:?} sees {:?}",
                                    p.position,
                                    q.position
                                );
                            }
                        }
                    }
                    hidden += facing as usize;
                }
                _ => {}
            }
        }
    }
    // Floor against ceiling, wall against opposite wall behind the cube:
    // many pairs face each other and are wholly hidden.
    println!("{hidden} hidden pairs culled, {partial} partly visible");
    assert!(hidden > n, "{hidden} hidden pairs culled of {n}²");
}
