//! Tests of ray queries, rendering and the vertex read-back against closed forms.

use super::*;
use crate::discretization::Discretization;
use crate::geometry::shapes::{box_room, sphere};
use crate::geometry::{Patch, Surface};
use crate::nodes::NodeSet;
use glam::DVec3;
use std::sync::Arc;

const L: [f64; 3] = [2.0, 3.0, 1.5];

fn room(level: u32) -> Arc<Mesh> {
    Arc::new(Mesh::new(Arc::new(box_room(L[0], L[1], L[2])), level))
}

/// u_n interpolating `f` at the nodes of degree `r` (exact when f is a polynomial of degree ≤ r).
fn interpolate(mesh: &Arc<Mesh>, r: usize, f: impl Fn(DVec3) -> f64) -> Solution {
    let disc = Arc::new(Discretization::new(
        mesh.clone(),
        NodeSet::new(r, 0.1).unwrap(),
    ));
    let values = disc.points().iter().map(|p| f(p.position)).collect();
    Solution::new(disc, values)
}

/// The affine element map from the element's vertices: v0 + s (v1 - v0) + t (v2 - v0).
fn affine(mesh: &Mesh, k: usize, s: f64, t: f64) -> DVec3 {
    let [a, b, c] = mesh.vertices(k);
    a + s * (b - a) + t * (c - a)
}

/// Where a ray from inside the box [0, L] leaves it (closed form).
fn exit_box(o: DVec3, d: DVec3) -> DVec3 {
    let mut t = f64::INFINITY;
    for i in 0..3 {
        if d[i] > 0.0 {
            t = t.min((L[i] - o[i]) / d[i]);
        } else if d[i] < 0.0 {
            t = t.min(-o[i] / d[i]);
        }
    }
    o + t * d
}

/// Rays from inside the room to known points of each element hit that element
/// at its (s, t), at t = 1, on the front; from outside, on the back.
#[test]
fn hits_land_at_element_and_st() {
    let mesh = room(2);
    let bvh = ElementBvh::new(&mesh, 4);
    assert_eq!(bvh.facet_count(), mesh.len());
    let o = DVec3::new(0.7, 1.1, 0.6);
    for k in 0..mesh.len() {
        for (s, t) in [(0.2, 0.3), (0.6, 0.1), (0.05, 0.9)] {
            let p = affine(&mesh, k, s, t);
            let hit = bvh.closest_hit(o, p - o).expect("hit");
            assert_eq!(hit.element, k);
            assert!(
                (hit.st[0] - s).abs() < 1e-12 && (hit.st[1] - t).abs() < 1e-12,
                "{hit:?}"
            );
            crate::assert_close!(hit.t, 1.0, 1e-12);
            assert!(hit.front);
            // From just outside the wall, along the inner normal: the back face.
            let n = mesh.point(k, s, t).normal;
            let outside = p - 0.25 * n;
            let back = bvh.closest_hit(outside, p - outside).expect("hit");
            assert_eq!(back.element, k);
            assert!(!back.front);
            crate::assert_close!(back.t, 1.0, 1e-12);
            // Pointing away from the room misses.
            assert!(bvh.closest_hit(outside, outside - p).is_none());
        }
    }
}

/// Rays through vertices and edges shared by several elements (box corners, edge
/// midpoints) still hit: no ray slips between facets.
#[test]
fn rays_through_shared_edges_and_corners_hit() {
    let mesh = room(1);
    let bvh = ElementBvh::new(&mesh, 4);
    let o = DVec3::new(1.0, 1.5, 0.75);
    for k in 0..mesh.len() {
        for (s, t) in [
            (0.0, 0.0),
            (1.0, 0.0),
            (0.0, 1.0),
            (0.5, 0.0),
            (0.5, 0.5),
            (0.0, 0.5),
        ] {
            let p = affine(&mesh, k, s, t);
            let hit = bvh
                .closest_hit(o, p - o)
                .expect("ray through a shared vertex or edge");
            crate::assert_close!(hit.t, 1.0, 1e-12);
            let q = affine(&mesh, hit.element, hit.st[0], hit.st[1]);
            assert!((q - p).length() < 1e-12, "{p} vs {q}");
        }
    }
}

/// A room far from the origin, seen from far away: f32 boxes with f64 tests still
/// find every hit at the exact place.
#[test]
fn far_from_origin() {
    let shift = DVec3::new(1.0e5, -2.0e5, 3.0e4);
    let mut surface = box_room(L[0], L[1], L[2]);
    for p in &mut surface.patches {
        for tri in &mut p.triangles {
            *tri = tri.map(|v| v + shift);
        }
    }
    let shifted: Vec<Patch> = surface.patches.clone();
    let mesh = Mesh::new(
        Arc::new(Surface {
            patches: shifted,
            ..surface
        }),
        2,
    );
    let bvh = ElementBvh::new(&mesh, 1);
    let eye = shift + DVec3::new(-3.0e3, 1.0e3, 2.0e3);
    let mut front = 0;
    for k in 0..mesh.len() {
        let p = affine(&mesh, k, 0.25, 0.25);
        let hit = bvh.closest_hit(eye, p - eye).expect("hit");
        // The first surface along the ray may be another wall, but never beyond p.
        assert!(hit.t <= 1.0 + 1e-12);
        if hit.element == k {
            crate::assert_close!(hit.st[0], 0.25, 1e-9);
            crate::assert_close!(hit.st[1], 0.25, 1e-9);
        }
        // From outside, everything seen is a back face.
        assert!(!hit.front);
        front += hit.front as usize;
    }
    assert_eq!(front, 0);
}

/// On a sphere (curved elements cut into facets), a ray from the centre towards
/// m_k(s, t) hits element k, at a point within one facet diameter of m_k(s, t).
#[test]
fn curved_elements_map_back() {
    let mesh = Mesh::new(Arc::new(sphere(1.0)), 1);
    let n = 8;
    let bvh = ElementBvh::new(&mesh, n);
    assert_eq!(bvh.facet_count(), mesh.len() * (n * n) as usize);
    for k in 0..mesh.len() {
        let [a, b, c] = mesh.vertices(k);
        let facet = (b - a).length().max((c - a).length()).max((c - b).length()) / n as f64;
        let p = mesh.position(k, 0.3, 0.35);
        let hit = bvh.closest_hit(DVec3::ZERO, p).expect("hit");
        assert_eq!(hit.element, k);
        assert!(hit.front);
        let q = mesh.position(k, hit.st[0], hit.st[1]);
        assert!((q - p).length() < facet, "{} vs {facet}", (q - p).length());
    }
}

/// A constant solution renders as the constant radiance u / π on every pixel of
/// a view from inside the room (every pixel covered).
#[test]
fn constant_solution_renders_constant() {
    let mesh = room(1);
    let u = interpolate(&mesh, 1, |_| 2.0);
    let camera = Camera::parse("0.3,0.4,0.5, 1.8,2.5,1.2, 0,0,1, 100").unwrap();
    let opts = RenderOptions {
        width: 40,
        height: 30,
        samples_per_pixel: 4,
        background: [9.0; 3],
        curved_subdivisions: 1,
    };
    let img = render(&mesh, &[&u], &camera, &opts).unwrap();
    assert_eq!(img.rgb.len(), 1200);
    let want = (2.0 / std::f64::consts::PI) as f32;
    for (px, cov) in img.rgb.iter().zip(&img.coverage) {
        assert_eq!(*cov, 1.0);
        for c in px {
            assert!(
                (c - want).abs() <= 2.0 * f32::EPSILON * want,
                "{c} vs {want}"
            );
        }
    }
}

/// Seen from outside, the room's walls turn their backs to the camera: covered
/// pixels are black, uncovered ones the background.
#[test]
fn back_faces_black_misses_background() {
    let mesh = room(1);
    let u = interpolate(&mesh, 0, |_| 5.0);
    let camera = Camera::parse("1,-6,0.75, 1,1.5,0.75, 0,0,1, 30").unwrap();
    let bg = [0.1, 0.2, 0.3];
    let opts = RenderOptions {
        width: 21,
        height: 15,
        samples_per_pixel: 9,
        background: bg,
        curved_subdivisions: 1,
    };
    let img = render(&mesh, &[&u], &camera, &opts).unwrap();
    let centre = 7 * 21 + 10;
    assert_eq!(img.coverage[centre], 1.0);
    assert_eq!(img.rgb[centre], [0.0; 3]);
    assert_eq!(img.coverage[0], 0.0);
    assert_eq!(img.rgb[0], bg);
    for (px, &cov) in img.rgb.iter().zip(&img.coverage) {
        for c in 0..3 {
            let want = (1.0 - cov) * bg[c];
            crate::assert_close!(px[c], want, 1e-6);
        }
    }
}

/// Linear-in-space channels (exact in u_n for r ≥ 1) render, at pixel centres, as
/// the closed form at the ray's exit from the box, divided by π.
#[test]
fn linear_solution_matches_closed_form() {
    let mesh = room(1);
    let fs: [fn(DVec3) -> f64; 3] = [
        |p| 1.0 + 0.5 * p.x - 0.3 * p.y + 0.8 * p.z,
        |p| 2.0 - 0.2 * p.x + 0.1 * p.y,
        |p| 0.5 + 0.25 * p.z,
    ];
    let sols = fs.map(|f| interpolate(&mesh, 1, f));
    let camera = Camera::parse("0.7,1.1,0.6, 1.9,2.5,0.2, 0,0,1, 80").unwrap();
    let (w, h) = (32, 24);
    let opts = RenderOptions {
        width: w,
        height: h,
        samples_per_pixel: 1,
        background: [0.0; 3],
        curved_subdivisions: 1,
    };
    let img = render(&mesh, &[&sols[0], &sols[1], &sols[2]], &camera, &opts).unwrap();
    for y in 0..h {
        for x in 0..w {
            let d = camera.ray_direction(x as f64 + 0.5, y as f64 + 0.5, w, h);
            let p = exit_box(camera.eye, d);
            let got = img.rgb[(y * w + x) as usize];
            for c in 0..3 {
                let want = fs[c](p) / std::f64::consts::PI;
                assert!(
                    (got[c] as f64 - want).abs() < 1e-6 * want.abs().max(1.0),
                    "pixel ({x}, {y}) channel {c}: {} vs {want}",
                    got[c]
                );
            }
        }
    }
}

/// Bad input is reported, not panicked on.
#[test]
fn errors() {
    let mesh = room(0);
    let u = interpolate(&mesh, 0, |_| 1.0);
    let camera = Camera::parse("1,1,1, 0,0,0, 0,0,1, 60").unwrap();
    let opts = RenderOptions::default();
    assert!(matches!(
        render(&mesh, &[&u, &u], &camera, &opts),
        Err(RenderError::ChannelCount { count: 2 })
    ));
    let finer = room(1);
    let v = interpolate(&finer, 0, |_| 1.0);
    assert!(matches!(
        render(&mesh, &[&u, &v, &u], &camera, &opts),
        Err(RenderError::MeshMismatch { channel: 1, .. })
    ));
    let zero = RenderOptions { width: 0, ..opts };
    assert!(matches!(
        render(&mesh, &[&u], &camera, &zero),
        Err(RenderError::ImageSize { .. })
    ));
    let bad = Camera {
        fov_y_deg: 0.0,
        ..camera
    };
    assert!(matches!(
        render(&mesh, &[&u], &bad, &opts),
        Err(RenderError::Camera(_))
    ));
    assert!(matches!(
        vertex_mesh(&mesh, &[&u], 0),
        Err(RenderError::Subdivisions(0))
    ));
}

/// The vertex read-back: vertex values are u_n at the vertex's (s, t), positions
/// the affine element map there, normals point into the room, triangles cover
/// each element and their areas add up to the room's 2 (2·3 + 3·1.5 + 2·1.5) = 27.
#[test]
fn vertex_mesh_values_and_area() {
    let mesh = room(1);
    let u = interpolate(&mesh, 2, |p| 1.0 + p.x * p.y - 0.5 * p.z * p.z);
    let n = 3;
    let vm = vertex_mesh(&mesh, &[&u], n).unwrap();
    let pts = tessellation_points(n);
    let per = pts.len();
    assert_eq!(vm.vertex_count(), mesh.len() * per);
    assert_eq!(vm.triangle_count(), mesh.len() * 9);
    assert_eq!(vm.element.len(), vm.triangle_count());
    let centre = DVec3::from(L) * 0.5;
    for k in 0..mesh.len() {
        for (j, &[s, t]) in pts.iter().enumerate() {
            let v = k * per + j;
            let want = u.eval(k, s, t) as f32;
            assert_eq!(vm.values[v], [want; 3]);
            let p = affine(&mesh, k, s, t);
            let q = DVec3::from(vm.positions[v].map(f64::from));
            assert!((p - q).length() < 1e-6);
            let nrm = DVec3::from(vm.normals[v].map(f64::from));
            crate::assert_close!(nrm.length(), 1.0, 1e-6);
            // The inner normal of a box wall points straight at the centre plane.
            assert!(nrm.dot(centre - p) > 0.0);
        }
    }
    let mut area = 0.0;
    let mut per_element = vec![0.0; mesh.len()];
    for (tri, &k) in vm.indices.chunks(3).zip(&vm.element) {
        let [a, b, c] =
            [0, 1, 2].map(|i| DVec3::from(vm.positions[tri[i] as usize].map(f64::from)));
        // Every triangle uses only its own element's vertices.
        assert!(tri.iter().all(|&i| i as usize / per == k as usize));
        let cross = (b - a).cross(c - a);
        // Counter-clockwise seen from the front: along the vertex normal.
        assert!(cross.dot(DVec3::from(vm.normals[tri[0] as usize].map(f64::from))) > 0.0);
        area += 0.5 * cross.length();
        per_element[k as usize] += 0.5 * cross.length();
    }
    crate::assert_close!(area, 27.0, 1e-5, "{area}");
    crate::assert_close!(area, mesh.area(), 1e-5);
    for k in 0..mesh.len() {
        let [a, b, c] = mesh.vertices(k);
        crate::assert_close!(per_element[k], 0.5 * (b - a).cross(c - a).length(), 1e-6);
    }
    // Three channels come back as three channels.
    let w = interpolate(&mesh, 0, |_| 3.0);
    let rgb = vertex_mesh(&mesh, &[&u, &w, &u], 1).unwrap();
    assert_eq!(rgb.values[0][1], 3.0);
    assert_eq!(rgb.values[0][0], u.eval(0, 0.0, 0.0) as f32);
}

/// The automatic camera sees lit faces: from inside for enclosures (sphere,
/// box room), from outside for the facing plates, whose lit sides face each
/// other and are seen at an angle.
#[test]
fn auto_camera_shows_front_faces() {
    let front_fraction = |mesh: &Mesh, cam: &Camera| {
        let bvh = ElementBvh::new(mesh, 2);
        let mut front = 0;
        for y in 0..20 {
            for x in 0..20 {
                let dir = cam.ray_direction(x as f64 + 0.5, y as f64 + 0.5, 20, 20);
                if bvh.closest_hit(cam.eye, dir).is_some_and(|h| h.front) {
                    front += 1;
                }
            }
        }
        front as f64 / 400.0
    };
    let ball = Mesh::new(Arc::new(sphere(1.0)), 1);
    let cam = auto_camera(&ball);
    assert!(cam.eye.length() < 1e-12, "inside the sphere: {cam:?}");
    assert!(front_fraction(&ball, &cam) == 1.0);
    let room = room(1);
    let cam = auto_camera(&room);
    assert!(front_fraction(&room, &cam) == 1.0, "{cam:?}");
    let plates = crate::scene::builtin("plates").unwrap().unwrap();
    let mesh = Mesh::new(plates.surface.clone(), 0);
    let cam = auto_camera(&mesh);
    assert!(front_fraction(&mesh, &cam) > 0.1, "{cam:?}");
    assert!(cam.validate().is_ok());
}

/// A square count is the regular grid of cell centres; any other count
/// (every other one, below) spreads over the pixel: every point inside it, no two alike, and each
/// half and quarter of the pixel holding its share to within 3 points for
/// every count up to 256 (independent random points would be off by about
/// √N / 2, 8 at 256).
#[test]
fn pixel_samples_cover_the_pixel() {
    assert_eq!(pixel_samples(1), vec![[0.5, 0.5]]);
    assert_eq!(
        pixel_samples(4),
        vec![[0.25, 0.25], [0.75, 0.25], [0.25, 0.75], [0.75, 0.75]]
    );
    let square = |n: u32| (1..=16).any(|m| m * m == n);
    for spp in (2..=256u32).filter(|&n| !square(n)) {
        let pts = pixel_samples(spp);
        assert_eq!(pts.len(), spp as usize);
        for (i, p) in pts.iter().enumerate() {
            assert!(p.iter().all(|c| (0.0..1.0).contains(c)), "{spp}: {p:?}");
            assert!(pts[..i].iter().all(|q| q != p), "{spp}: {p:?} twice");
        }
        let n = spp as f64;
        let count = |f: &dyn Fn(&[f64; 2]) -> bool| pts.iter().filter(|p| f(p)).count() as f64;
        for axis in 0..2 {
            let low = count(&|p| p[axis] < 0.5);
            assert!(
                (low - n / 2.0).abs() <= 3.0,
                "{spp}, axis {axis}: {low} below 1/2"
            );
        }
        for (qx, qy) in [(false, false), (false, true), (true, false), (true, true)] {
            let q = count(&|p| (p[0] < 0.5) == qx && (p[1] < 0.5) == qy);
            assert!((q - n / 4.0).abs() <= 3.0, "{spp}: {q} in a quarter");
        }
    }
}

/// The fraction of rays that hit a surface covering part of a pixel tends
/// to the covered fraction for counts that are not squares too: on a view
/// whose pixels the room's edges cut, 7 and 50 rays give the coverage of
/// the 7 × 7 grid to within two rays' worth, 2/N (measured: one ray at 7,
/// 0.017 at 50).
#[test]
fn coverage_agrees_across_sample_counts() {
    let mesh = room(1);
    let u = interpolate(&mesh, 0, |_| 5.0);
    let camera = Camera::parse("1,-6,0.75, 1,1.5,0.75, 0,0,1, 30").unwrap();
    let cov = |spp| {
        let opts = RenderOptions {
            width: 21,
            height: 15,
            samples_per_pixel: spp,
            background: [0.0; 3],
            curved_subdivisions: 1,
        };
        render(&mesh, &[&u], &camera, &opts).unwrap().coverage
    };
    let (grid, r50, r7) = (cov(49), cov(50), cov(7));
    let partial: Vec<usize> = (0..grid.len())
        .filter(|&i| grid[i] > 0.0 && grid[i] < 1.0)
        .collect();
    assert!(!partial.is_empty(), "the view cuts no pixel");
    for &i in &partial {
        for (r, n) in [(&r50, 50.0), (&r7, 7.0)] {
            let d = (r[i] - grid[i]).abs();
            assert!(d <= 2.0 / n, "pixel {i}, {n} rays: {} vs {}", r[i], grid[i]);
        }
    }
}

/// A room whose ceiling emits (u = 100) and whose other walls reflect
/// (u = 1), seen from inside with the ceiling in a good part of the view.
/// Exposed from every covered pixel, the walls show nearly black (the 99th
/// percentile is the ceiling's); told which elements emit, auto exposure
/// maps the walls' radiance to 1.0 before the curve, and a wall pixel
/// shows ACES(1) in sRGB: 2.54 / 3.16 = 0.80380, encoded
/// 1.055 · 0.80380^(1/2.4) − 0.055 = 0.90835, code 232.
#[test]
fn auto_exposure_follows_the_reflected_light() {
    let mesh = room(1);
    let ceiling = |p: DVec3| (p.z - L[2]).abs() < 1e-9;
    let u = interpolate(&mesh, 0, |p| if ceiling(p) { 100.0 } else { 1.0 });
    let emits: Vec<bool> = (0..mesh.len())
        .map(|k| mesh.vertices(k).iter().all(|&v| ceiling(v)))
        .collect();
    assert_eq!(emits.iter().filter(|&&e| e).count(), 8);
    let camera = Camera::parse("1,0.2,0.4, 1,2.8,1.3, 0,0,1, 70").unwrap();
    let opts = RenderOptions {
        width: 40,
        height: 30,
        samples_per_pixel: 4,
        ..Default::default()
    };
    let tone = ToneMap::default();
    let plain = render(&mesh, &[&u], &camera, &opts).unwrap();
    let lit = render_scene(&mesh, &[&u], &emits, &camera, &opts).unwrap();
    assert_eq!(plain.rgb, lit.rgb);
    assert!(plain.emitted.is_empty());
    let light_share = lit.emitted.iter().filter(|&&e| e == 1.0).count() as f64 / 1200.0;
    assert!(light_share > 0.05, "the light covers {light_share}");
    let walls: Vec<usize> = (0..1200)
        .filter(|&i| lit.emitted[i] == 0.0 && lit.coverage[i] == 1.0)
        .collect();
    assert!(walls.len() > 600, "{}", walls.len());
    let (dark, bright) = (tone_map(&plain, &tone), tone_map(&lit, &tone));
    for &i in &walls {
        assert!(dark[i][0] < 40, "exposed for the light: {:?}", dark[i]);
        assert_eq!(bright[i], [232; 3], "pixel {i}");
    }
    let aces1: f64 = 2.54 / 3.16;
    let code = (255.0 * (1.055 * aces1.powf(1.0 / 2.4) - 0.055)).round();
    assert_eq!(code, 232.0);
    // An emitter list of the wrong length is refused.
    assert!(render_scene(&mesh, &[&u], &emits[1..], &camera, &opts).is_err());
}
