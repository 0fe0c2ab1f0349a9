//! Tests of scene input: every error and warning from a tiny OBJ/MTL or builder
//! input, with the file and line (or group and face) it must name.

use super::*;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// A fresh folder under the system temp dir holding `files`.
fn write_files(files: &[(&str, &str)]) -> PathBuf {
    static N: AtomicUsize = AtomicUsize::new(0);
    let dir = std::env::temp_dir().join(format!(
        "radcol-scene-test-{}-{}",
        std::process::id(),
        N.fetch_add(1, Ordering::Relaxed)
    ));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, text) in files {
        std::fs::write(dir.join(name), text).unwrap();
    }
    dir
}

const MTL: &str =
    "# materials\nnewmtl white\nKd 0.5 0.5 0.5\n\nnewmtl lamp\nKd 0.2 0.3 0.4\nKe 1 2 3\n";

/// Loads `obj` (as t.obj) with `mtl` (as t.mtl).
fn load(obj: &str, mtl: &str) -> (PathBuf, Result<Scene, SceneError>) {
    let dir = write_files(&[("t.obj", obj), ("t.mtl", mtl)]);
    let path = dir.join("t.obj");
    let r = load_obj(&path);
    (path, r)
}

/// The error's message, checked to name `file:line`.
fn err_at(obj: &str, mtl: &str, file: &str, line: usize) -> String {
    let (path, r) = load(obj, mtl);
    let msg = r.expect_err("must fail").to_string();
    let want = format!("{}:{line}:", path.with_file_name(file).display());
    assert!(msg.contains(&want), "'{msg}' should name '{want}'");
    msg
}

/// A unit square in z = 0 facing +z, then `extra`.
fn square(extra: &str) -> String {
    format!("mtllib t.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\ng floor\nusemtl white\nf 1 2 3\nf 1 3 4\n{extra}")
}

/// `s` without the warning that no two of its triangles face each other,
/// which a lone square (most scenes here) must carry as its last warning,
/// and, when nothing of it emits, without the warning that says so just
/// before.
fn alone(mut s: Scene) -> Scene {
    assert_eq!(
        s.warnings.pop().as_deref(),
        Some(super::facing::NOTHING_FACES),
        "{:?}",
        s.warnings
    );
    if !s.problem().emits() {
        assert_eq!(
            s.warnings.pop().as_deref(),
            Some(super::validate::NO_EMITTER),
            "{:?}",
            s.warnings
        );
    }
    s
}

/// A scene none of whose triangles emits is warned about (its solution is
/// zero), one with an emitter is not; an emitting material that no
/// triangle uses does not count.
#[test]
fn a_scene_without_emitters_is_warned_about() {
    let unlit = "newmtl white\nKd 0.5 0.5 0.5\nnewmtl lamp\nKd 0 0 0\nKe 1 1 1\n";
    let (_, r) = load(&square(""), unlit);
    let s = r.unwrap();
    assert!(!s.problem().emits());
    assert!(
        s.warnings.iter().any(|w| w == super::validate::NO_EMITTER),
        "{:?}",
        s.warnings
    );
    let lit = square("v 0 0 1\nv 1 0 1\nv 1 1 1\ng lamp\nusemtl lamp\nf 7 6 5\n");
    let (_, r) = load(&lit, unlit);
    let s = r.unwrap();
    assert!(s.problem().emits());
    assert!(
        !s.warnings.iter().any(|w| w == super::validate::NO_EMITTER),
        "{:?}",
        s.warnings
    );
}

#[test]
fn loads_a_square_with_materials() {
    let (path, r) = load(&square(""), MTL);
    let s = alone(r.unwrap());
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    assert_eq!(s.source.as_deref(), Some(path.as_path()));
    assert_eq!(s.name, "t");
    assert_eq!(s.triangle_count(), 2);
    assert_eq!(s.vertex_count(), 4);
    assert_eq!(s.surface.patches.len(), 1);
    assert_eq!(s.surface.patches[0].name, "floor/white");
    crate::assert_close!(s.area(), 1.0, 1e-15);
    let [a, b, c] = s.surface.patches[0].triangles[0];
    assert!(
        (b - a).cross(c - a).z > 0.0,
        "front face is counter-clockwise"
    );
    assert_eq!(s.bounding_box(), (DVec3::ZERO, DVec3::new(1.0, 1.0, 0.0)));
}

#[test]
fn unreadable_obj_and_mtl() {
    let dir = write_files(&[]);
    let path = dir.join("missing.obj");
    let msg = load_obj(&path).unwrap_err().to_string();
    assert!(msg.contains(&path.display().to_string()), "{msg}");
    let msg = err_at(&square("").replace("t.mtl", "nope.mtl"), MTL, "t.obj", 1);
    assert!(msg.contains("nope.mtl"), "{msg}");
}

#[test]
fn material_errors_name_the_mtl_line() {
    let msg = err_at(&square(""), "newmtl white\nKs 1 1 1\n", "t.mtl", 1);
    assert!(msg.contains("no Kd") && msg.contains("white"), "{msg}");
    let msg = err_at(
        &square(""),
        "newmtl white\n# c\nKd 0.5 1.0 0.5\n",
        "t.mtl",
        3,
    );
    assert!(
        msg.contains("Kd G = 1 ") && msg.contains("'white'"),
        "{msg}"
    );
    let msg = err_at(&square(""), "newmtl white\nKd 0.5 0.5 -0.1\n", "t.mtl", 2);
    assert!(msg.contains("Kd B = -0.1"), "{msg}");
    let msg = err_at(
        &square(""),
        "newmtl white\nKd 0.5 0.5 0.5\nKe -1 0 0\n",
        "t.mtl",
        3,
    );
    assert!(msg.contains("Ke R = -1"), "{msg}");
    let msg = err_at(
        &square(""),
        "newmtl white\nKd 0.5 0.5 0.5\nKe 0 nan 0\n",
        "t.mtl",
        3,
    );
    assert!(msg.contains("Ke G = NaN"), "{msg}");
    let msg = err_at(
        &square(""),
        "newmtl white\nKd 0.5 0.5 0.5\nKe 0 0 inf\n",
        "t.mtl",
        3,
    );
    assert!(msg.contains("Ke B = inf"), "{msg}");
    // tobj would panic on a short Kd: the scan refuses it first.
    let msg = err_at(&square(""), "newmtl white\nKd 0.5\n", "t.mtl", 2);
    assert!(msg.contains("three numbers"), "{msg}");
}

#[test]
fn face_errors_name_the_obj_line() {
    let msg = err_at(&square("usemtl chrome\n"), MTL, "t.obj", 10);
    assert!(msg.contains("'chrome'"), "{msg}");
    let no_mtl = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    let msg = err_at(no_mtl, MTL, "t.obj", 4);
    assert!(msg.contains("no material"), "{msg}");
    let msg = err_at(&square("f 1 2 5\n"), MTL, "t.obj", 10);
    assert!(
        msg.contains("index 5") && msg.contains("4 vertices"),
        "{msg}"
    );
    let msg = err_at(&square("f 1 -5 2\n"), MTL, "t.obj", 10);
    assert!(msg.contains("index -5"), "{msg}");
    let msg = err_at(&square("f 0 1 2\n"), MTL, "t.obj", 10);
    assert!(msg.contains("index 0"), "{msg}");
    let msg = err_at(&square("f 1 2\n"), MTL, "t.obj", 10);
    assert!(msg.contains("2 vertices"), "{msg}");
    let msg = err_at(&square("v 1 nan 0\n"), MTL, "t.obj", 10);
    assert!(msg.contains("NaN"), "{msg}");
    let msg = err_at(&square("v inf 0 0\n"), MTL, "t.obj", 10);
    assert!(msg.contains("inf"), "{msg}");
    let msg = err_at(&square("v 1 x 0\n"), MTL, "t.obj", 10);
    assert!(msg.contains("cannot parse"), "{msg}");
}

#[test]
fn empty_scenes_are_errors() {
    let (_, r) = load("mtllib t.mtl\nv 0 0 0\n", MTL);
    assert!(matches!(r, Err(SceneError::Empty { .. })));
    // Only degenerate triangles: empty after the repair.
    let (_, r) = load(
        "mtllib t.mtl\nv 0 0 0\nv 1 0 0\nusemtl white\nf 1 2 2\n",
        MTL,
    );
    let msg = r.unwrap_err().to_string();
    assert!(msg.contains("1 degenerate"), "{msg}");
}

/// Groups that come back: tobj starts a new model at each change, in file
/// order, and every triangle keeps the line of its own face.
#[test]
fn interleaved_groups_map_to_their_lines() {
    let obj = "mtllib t.mtl\n\
        v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n\
        g a\nusemtl white\nf 1 2 3\n\
        g b\nusemtl lamp\nf 5 7 6\n\
        g a\nusemtl white\nf 1 3 4\n\
        usemtl lamp\nf 5 8 7\n\
        g b\nf 1 4 8 5\n";
    // Lines: 10 g a, 12 f, 15 f, 18 f, 20 f (a/lamp), 22 f quad (b/lamp).
    let (_, r) = load(obj, MTL);
    let s = r.unwrap();
    let names: Vec<&str> = s.surface.patches.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names, ["a/white", "b/lamp", "a/lamp"]);
    assert_eq!(
        s.surface
            .patches
            .iter()
            .map(|p| p.triangles.len())
            .collect::<Vec<_>>(),
        [2, 3, 1]
    );
    // Duplicate each face at the end of the file: every duplicate warning
    // names the original's line and the copy's.
    let copy = format!(
        "{obj}g a\nusemtl white\nf 1 2 3\ng b\nusemtl lamp\nf 5 7 6\ng a\nusemtl white\nf 1 3 4\nusemtl lamp\nf 5 8 7\n"
    );
    let (path, r) = load(&copy, MTL);
    let w = r.unwrap().warnings;
    let f = path.display().to_string();
    for (copy_line, orig) in [(25, 12), (28, 15), (31, 18), (33, 20)] {
        let want = format!("{f}:{copy_line}: duplicate of the triangle at {f}:{orig} ");
        assert!(w.iter().any(|m| m.starts_with(&want)), "{want} in {w:#?}");
    }
}

/// 100 000 copies of one triangle (rotated and not), in another group and
/// between polygon faces, are dropped while the file is read: the scene
/// holds the two triangles of the square, the first 20 copies are named
/// with their line and the original's, the rest counted exactly, and a
/// copy of a quadrilateral's triangle is still found by the shared checks.
#[test]
fn copies_of_a_triangle_are_dropped_while_reading() {
    let copies = 100_000;
    let mut extra = String::from("g other\n");
    for i in 0..copies {
        extra.push_str(if i % 2 == 0 { "f 1 2 3\n" } else { "f 2 3 1\n" });
    }
    // A quadrilateral and a copy of one of its triangles (after it).
    extra.push_str("v 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\nusemtl lamp\nf 5 8 7 6\nf 5 8 7\n");
    let (p, r) = load(&square(&extra), MTL);
    let s = r.unwrap();
    assert_eq!(s.triangle_count(), 4);
    let f = p.display().to_string();
    let dups: Vec<&String> = s
        .warnings
        .iter()
        .filter(|w| w.contains("duplicate of"))
        .collect();
    assert_eq!(dups.len(), MAX_WARNINGS_PER_KIND, "{:#?}", s.warnings);
    // Lines 10.. are the copies of line 8's triangle.
    for (i, w) in dups.iter().enumerate() {
        let want = format!("{f}:{}: duplicate of the triangle at {f}:8 ", 11 + i);
        assert!(w.starts_with(&want), "{w} should start with {want}");
    }
    let more = format!(
        "... and {} more duplicate-triangle warnings",
        copies + 1 - MAX_WARNINGS_PER_KIND
    );
    assert!(s.warnings.contains(&more), "{more} in {:#?}", s.warnings);
}

#[test]
fn repairs_and_warnings_name_lines() {
    let f = |p: &Path| p.display().to_string();
    // A repeated vertex and a collinear triangle: dropped.
    let (p, r) = load(&square("v 2 0 0\nf 1 2 5\nf 1 1 2\n"), MTL);
    let s = alone(r.unwrap());
    assert_eq!(s.triangle_count(), 2);
    assert!(
        s.warnings[0].starts_with(&format!("{}:11: degenerate", f(&p))),
        "{:?}",
        s.warnings
    );
    assert!(
        s.warnings[1].starts_with(&format!("{}:12: degenerate", f(&p))),
        "{:?}",
        s.warnings
    );
    assert_eq!(s.warnings.len(), 2);
    // The same triangle rotated (same orientation): dropped.
    let (p, r) = load(&square("f 2 3 1\n"), MTL);
    let s = alone(r.unwrap());
    assert_eq!(s.triangle_count(), 2);
    assert!(s.warnings[0].contains(&format!(
        "{}:10: duplicate of the triangle at {}:8",
        f(&p),
        f(&p)
    )));
    // Opposite orientation: a two-sided panel, kept without a warning.
    let (_, r) = load(&square("usemtl lamp\nf 1 3 2\nf 1 4 3\n"), MTL);
    let s = alone(r.unwrap());
    assert_eq!(s.triangle_count(), 4);
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    // Non-planar quad.
    let (p, r) = load(
        &square("v 0 0 1\nv 1 0 1\nv 1 1 1.5\nv 0 1 1\nf 5 6 7 8\n"),
        MTL,
    );
    let s = alone(r.unwrap());
    assert_eq!(s.triangle_count(), 4);
    assert!(
        s.warnings.iter().any(|w| w.starts_with(&format!(
            "{}:14: polygon with 4 vertices is not planar",
            f(&p)
        ))),
        "{:?}",
        s.warnings
    );
    // Polylines are skipped.
    let (p, r) = load(&square("l 1 2 3\n"), MTL);
    let s = alone(r.unwrap());
    assert_eq!(s.triangle_count(), 2);
    assert!(
        s.warnings[0].starts_with(&format!("{}:10: 1 polyline", f(&p))),
        "{:?}",
        s.warnings
    );
}

#[test]
fn t_junctions_and_non_manifold_edges_warn() {
    let f = |p: &Path| p.display().to_string();
    // A triangle whose vertex 5 = (0.5, 0, 0) lies inside the edge 1-2 of line 8.
    let (p, r) = load(&square("v 0.5 0 0\nv 0.5 -1 0\nf 5 6 2\n"), MTL);
    let s = alone(r.unwrap());
    assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
    let w = &s.warnings[0];
    assert!(
        w.contains("T-junction")
            && w.contains(&format!("{}:12", f(&p)))
            && w.contains(&format!("{}:8", f(&p))),
        "{w}"
    );
    // A fin on the diagonal 1-3: three triangles share it.
    // The fin faces the triangle of line 8 only: the one of line 9 faces
    // nothing and is named.
    let (p, r) = load(&square("v 0 0 1\nf 1 3 5\n"), MTL);
    let s = r.unwrap();
    assert_eq!(s.warnings.len(), 3, "{:?}", s.warnings);
    assert_eq!(s.warnings[1], super::validate::NO_EMITTER);
    assert!(
        s.warnings[2].starts_with(&format!("{}:9 (group 'floor'): its front", f(&p))),
        "{:?}",
        s.warnings
    );
    let w = &s.warnings[0];
    assert!(
        w.contains("non-manifold") && w.contains("3 triangles"),
        "{w}"
    );
    for l in [8, 9, 11] {
        assert!(w.contains(&format!("{}:{l}", f(&p))), "{w}");
    }
}

#[test]
fn problem_carries_material_values_per_patch() {
    let (_, r) = load(
        &square("v 0 0 1\nv 1 0 1\nv 1 1 1\ng top\nusemtl lamp\nf 5 7 6\n"),
        MTL,
    );
    let s = r.unwrap();
    assert_eq!(s.emitters(), vec![1]);
    let p = s.problem();
    let names: Vec<&str> = p.channels.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["R", "G", "B"]);
    assert!(p.exact.is_none());
    let want_rho = [[0.5, 0.2], [0.5, 0.3], [0.5, 0.4]];
    let want_e = [[0.0, 1.0], [0.0, 2.0], [0.0, 3.0]];
    for (c, ch) in p.channels.iter().enumerate() {
        let (Field::PerPatch(rho), Field::PerPatch(e)) = (&ch.rho, &ch.emission) else {
            panic!("per-patch fields expected");
        };
        assert_eq!(rho.as_slice(), want_rho[c]);
        assert_eq!(e.as_slice(), want_e[c]);
    }
}

#[test]
fn scaled_scales_the_bounding_box() {
    let (_, r) = load(&square("v 0 0 2\nusemtl lamp\nf 1 5 2\n"), MTL);
    let s = r.unwrap();
    let t = s.scaled(2.5);
    let (lo, hi) = s.bounding_box();
    assert_eq!(t.bounding_box(), (lo * 2.5, hi * 2.5));
    crate::assert_close!(t.area(), 6.25 * s.area(), 1e-12 * t.area());
    assert_eq!(t.materials, s.materials);
}

#[test]
fn in_memory_obj_names_its_files() {
    let msg = load_obj_str("mem", &square(""), &[("t.mtl", "newmtl white\n")])
        .unwrap_err()
        .to_string();
    assert!(msg.starts_with("t.mtl:1:"), "{msg}");
    let msg = load_obj_str("mem", &square("f 1 2 9\n"), &[("t.mtl", MTL)])
        .unwrap_err()
        .to_string();
    assert!(msg.starts_with("mem.obj:10:"), "{msg}");
}

/// Shoelace area of a planar polygon given by its corners.
fn polygon_area(p: &[DVec3]) -> f64 {
    let n: DVec3 = (0..p.len()).map(|i| p[i].cross(p[(i + 1) % p.len()])).sum();
    0.5 * n.length()
}

fn patch<'a>(s: &'a Scene, name: &str) -> &'a crate::geometry::Patch {
    s.surface
        .patches
        .iter()
        .find(|p| p.name == name)
        .unwrap_or_else(|| panic!("no patch {name}"))
}

fn patch_area(s: &Scene, name: &str) -> f64 {
    patch(s, name)
        .triangles
        .iter()
        .map(|[a, b, c]| 0.5 * (*b - *a).cross(*c - *a).length())
        .sum()
}

fn normal([a, b, c]: &[DVec3; 3]) -> DVec3 {
    (*b - *a).cross(*c - *a).normalize()
}

fn centroid(t: &[DVec3; 3]) -> DVec3 {
    (t[0] + t[1] + t[2]) / 3.0
}

#[test]
fn builtins_load_without_warnings_or_duplicates() {
    assert!(builtin("nope").is_none());
    for (name, _) in BUILTIN_SCENES {
        let s = builtin(name).unwrap().unwrap();
        assert!(s.warnings.is_empty(), "{name}: {:?}", s.warnings);
        assert!(s.camera.is_some());
        // No face twice, in either orientation.
        let mut keys: Vec<_> = s
            .triangles()
            .map(|(_, t)| {
                let mut k = t.map(|v| v.to_array().map(f64::to_bits));
                k.sort();
                k
            })
            .collect();
        let n = keys.len();
        keys.sort();
        keys.dedup();
        assert_eq!(keys.len(), n, "{name}");
        assert_eq!(s.emitters().len(), 1, "{name}");
    }
}

#[test]
fn cornell_box_geometry_orientation_and_materials() {
    let s = builtin("cornell").unwrap().unwrap();
    assert_eq!(s.triangle_count(), 14 + 8 + 2 + 3 * 2 + 2 * 10);
    assert!(!s.surface.convex_enclosure, "the blocks occlude");
    let v = |x, y, z| DVec3::new(x, y, z);
    // Areas from the published corners (shoelace), independent of the triangulation.
    let floor = [
        v(552.8, 0., 0.),
        v(0., 0., 0.),
        v(0., 0., 559.2),
        v(549.6, 0., 559.2),
    ];
    let ceiling = [
        v(556., 548.8, 0.),
        v(556., 548.8, 559.2),
        v(0., 548.8, 559.2),
        v(0., 548.8, 0.),
    ];
    let light = [
        v(343., 548.8, 227.),
        v(343., 548.8, 332.),
        v(213., 548.8, 332.),
        v(213., 548.8, 227.),
    ];
    // The blocks' footprints, cut out of the floor.
    let footprints = [
        [
            v(130., 0., 65.),
            v(82., 0., 225.),
            v(240., 0., 272.),
            v(290., 0., 114.),
        ],
        [
            v(423., 0., 247.),
            v(265., 0., 296.),
            v(314., 0., 456.),
            v(472., 0., 406.),
        ],
    ];
    let rel = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b;
    assert!(rel(
        patch_area(&s, "floor/white"),
        polygon_area(&floor) - polygon_area(&footprints[0]) - polygon_area(&footprints[1])
    ));
    assert!(rel(patch_area(&s, "light/light"), 130.0 * 105.0));
    assert!(rel(polygon_area(&light), 130.0 * 105.0));
    // The hole: ceiling ring + light = full ceiling, so they do not overlap.
    assert!(rel(
        patch_area(&s, "ceiling/white") + patch_area(&s, "light/light"),
        polygon_area(&ceiling)
    ));
    // The light is emitted downwards, into the room.
    for t in &patch(&s, "light/light").triangles {
        assert!(
            normal(t).dot(DVec3::NEG_Y) > 1.0 - 1e-12,
            "light faces down"
        );
    }
    // Room faces point to the room's centre, block faces away from their axis.
    let room_centre = v(278.0, 274.4, 279.6);
    for name in [
        "floor/white",
        "ceiling/white",
        "back_wall/white",
        "right_wall/green",
        "left_wall/red",
    ] {
        for t in &patch(&s, name).triangles {
            assert!(normal(t).dot(room_centre - centroid(t)) > 0.0, "{name}");
        }
    }
    for (name, top, h) in [
        (
            "short_block/white",
            [
                v(130., 165., 65.),
                v(82., 165., 225.),
                v(240., 165., 272.),
                v(290., 165., 114.),
            ],
            165.0,
        ),
        (
            "tall_block/white",
            [
                v(423., 330., 247.),
                v(265., 330., 296.),
                v(314., 330., 456.),
                v(472., 330., 406.),
            ],
            330.0,
        ),
    ] {
        let c = (top[0] + top[1] + top[2] + top[3]) / 4.0 - DVec3::Y * (h / 2.0);
        let tris = &patch(&s, name).triangles;
        assert_eq!(tris.len(), 10);
        for t in tris {
            assert!(normal(t).dot(centroid(t) - c) > 0.0, "{name}");
        }
        let sides: f64 = (0..4)
            .map(|i| (top[(i + 1) % 4] - top[i]).length() * h)
            .sum();
        assert!(
            rel(patch_area(&s, name), polygon_area(&top) + sides),
            "{name}"
        );
    }
    // Red wall at x ≈ 556 appears on the left of the camera's image.
    let cam = s.camera.unwrap();
    assert!(
        (cam.fov_y_deg - 39.3076481).abs() < 1e-6,
        "{}",
        cam.fov_y_deg
    );
    let (right, _, _) = cam.basis();
    let red = centroid(&patch(&s, "left_wall/red").triangles[0]);
    assert!((red - cam.eye).dot(right) < 0.0);
    let red_m = s.material_of(
        s.surface
            .patches
            .iter()
            .position(|p| p.name == "left_wall/red")
            .unwrap(),
    );
    assert_eq!(red_m.rho, [0.63, 0.065, 0.05]);
    let light_m = s.material_of(s.emitters()[0]);
    assert_eq!(
        (light_m.rho, light_m.emission),
        ([0.78; 3], [17.0, 12.0, 4.0])
    );
}

#[test]
fn room_is_a_convex_box_with_a_ceiling_light() {
    let s = builtin("room").unwrap().unwrap();
    assert!(s.surface.convex_enclosure);
    assert_eq!(s.triangle_count(), 2 + 8 + 2 + 4 * 2);
    let rel = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b;
    assert!(rel(s.area(), 2.0 * (4.0 * 3.0 + 4.0 * 5.0 + 3.0 * 5.0)));
    assert!(rel(patch_area(&s, "light/light"), 1.0));
    assert!(rel(patch_area(&s, "ceiling/white"), 19.0));
    let c = DVec3::new(2.0, 1.5, 2.5);
    for (_, t) in s.triangles() {
        assert!(normal(&t).dot(c - centroid(&t)) > 0.0);
    }
    let (lo, hi) = s.bounding_box();
    assert_eq!((lo, hi), (DVec3::ZERO, DVec3::new(4.0, 3.0, 5.0)));
    let cam = s.camera.unwrap();
    assert!(
        cam.eye.cmpgt(lo).all() && cam.eye.cmplt(hi).all(),
        "camera inside"
    );
}

#[test]
fn plates_are_mirror_images() {
    let s = builtin("plates").unwrap().unwrap();
    assert!(s.surface.convex_enclosure);
    let bottom = &patch(&s, "bottom/white").triangles;
    let top = &patch(&s, "top/light").triangles;
    assert_eq!((bottom.len(), top.len()), (2, 2));
    let mirror = |v: DVec3| DVec3::new(v.x, v.y, 1.0 - v.z);
    let sorted = |t: [DVec3; 3]| {
        let mut k = t.map(|v| v.to_array().map(f64::to_bits));
        k.sort();
        k
    };
    for (b, t) in bottom.iter().zip(top) {
        assert_eq!(sorted(b.map(mirror)), sorted(*t));
        assert_eq!(normal(b), DVec3::Z);
        assert_eq!(normal(t), DVec3::NEG_Z);
    }
    assert_eq!(s.problem().channels[0].name, "R");
    assert_eq!(s.emitters(), vec![1]);
    assert_eq!(s.material_of(1).emission, [1.0; 3]);
    assert_eq!(s.material_of(1).rho, [0.5; 3]);
    assert_eq!(s.material_of(0).rho, [0.5; 3]);
}

#[test]
fn builder_errors_name_group_and_face() {
    use glam::Vec3;
    let mut b = SceneBuilder::new("b");
    let msg = b
        .add_material(Material::diffuse("bad", [0.5, 1.0, 0.5]))
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("material 0 'bad'") && msg.contains("Kd G = 1"),
        "{msg}"
    );
    let msg = b
        .add_material(Material::emitter("hot", [0.5; 3], [0.0, 0.0, -2.0]))
        .unwrap_err()
        .to_string();
    assert!(msg.contains("Ke B = -2"), "{msg}");
    let white = b
        .add_material(Material::diffuse("white", [0.5; 3]))
        .unwrap();
    let quad = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
    let msg = b
        .add_mesh("m", &quad, &[[0, 1, 2]], 7)
        .unwrap_err()
        .to_string();
    assert!(msg.contains("material index 7"), "{msg}");
    let msg = b
        .add_mesh("m", &quad, &[[0, 1, 2], [0, 2, 4]], white)
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("mesh 'm' face 1") && msg.contains("index 4"),
        "{msg}"
    );
    let msg = b
        .add_mesh(
            "m",
            &[Vec3::ZERO, Vec3::X, Vec3::new(0.0, f32::NAN, 0.0)],
            &[[0, 1, 2]],
            white,
        )
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("mesh 'm' vertex 2") && msg.contains("NaN"),
        "{msg}"
    );
    assert!(matches!(b.build(), Err(SceneError::Empty { .. })));
    // Faces are numbered per group across calls: the second call's faces are 2 and 3.
    b.add_mesh("m", &quad, &[[0, 1, 2], [0, 2, 3]], white)
        .unwrap();
    b.add_mesh("m", &quad, &[[0, 1, 1], [2, 3, 0]], white)
        .unwrap();
    let s = b.build().unwrap();
    assert_eq!(s.triangle_count(), 2);
    assert!(
        s.warnings[0].starts_with("mesh 'm' face 2: degenerate"),
        "{:?}",
        s.warnings
    );
    assert!(
        s.warnings[1].starts_with("mesh 'm' face 3: duplicate of the triangle at mesh 'm' face 1"),
        "{:?}",
        s.warnings
    );
    // A degenerate camera is refused.
    b.camera(crate::camera::Camera {
        eye: DVec3::ZERO,
        target: DVec3::ZERO,
        up: DVec3::Y,
        fov_y_deg: 40.0,
    });
    assert!(matches!(b.build(), Err(SceneError::Camera { .. })));
}

/// Many warnings of one kind are capped and counted.
#[test]
fn warnings_are_capped() {
    let mut b = SceneBuilder::new("cap");
    let white = b
        .add_material(Material::diffuse("white", [0.5; 3]))
        .unwrap();
    let p = [DVec3::ZERO, DVec3::X, DVec3::Y];
    let tris: Vec<[u32; 3]> = std::iter::repeat_n([0, 1, 2], MAX_WARNINGS_PER_KIND + 6).collect();
    b.add_mesh_f64("g", &p, &tris, white).unwrap();
    let s = alone(b.build().unwrap());
    assert_eq!(s.warnings.len(), MAX_WARNINGS_PER_KIND + 1);
    assert_eq!(
        s.warnings.last().unwrap(),
        "... and 5 more duplicate-triangle warnings"
    );
}

/// A closed box with its floor wound the wrong way: each floor triangle is
/// named; an emitter facing out of the box gets the emitter's message; the
/// box as it should be has no warning.
#[test]
fn triangles_facing_nothing_are_named() {
    // The unit cube's faces, counter-clockwise seen from inside.
    let faces = [
        "f 1 2 3 4", // floor z = 0, facing +z
        "f 5 8 7 6", // ceiling z = 1, facing -z
        "f 1 5 6 2", // y = 0, facing +y
        "f 4 3 7 8", // y = 1, facing -y
        "f 1 4 8 5", // x = 0, facing +x
        "f 2 6 7 3", // x = 1, facing -x
    ];
    let obj = |floor: &str, ceiling: &str| {
        let mut t = String::from("mtllib t.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n");
        t += &format!("g floor\nusemtl white\n{floor}\ng ceiling\nusemtl lamp\n{ceiling}\ng walls\nusemtl white\n");
        for f in &faces[2..] {
            t += f;
            t += "\n";
        }
        t
    };
    let (_, r) = load(&obj(faces[0], faces[1]), MTL);
    let s = r.unwrap();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);

    let (p, r) = load(&obj("f 4 3 2 1", faces[1]), MTL);
    let s = r.unwrap();
    let f = p.display().to_string();
    assert_eq!(s.warnings.len(), 2, "{:?}", s.warnings);
    for w in &s.warnings {
        assert!(
            w.starts_with(&format!(
                "{f}:12 (group 'floor'): its front (counter-clockwise) side faces no other surface"
            )) && w.ends_with("is it wound the wrong way?"),
            "{w}"
        );
    }

    let (_, r) = load(&obj(faces[0], "f 5 6 7 8"), MTL);
    let s = r.unwrap();
    assert_eq!(s.warnings.len(), 2, "{:?}", s.warnings);
    assert!(
        s.warnings
            .iter()
            .all(|w| w.contains("(group 'ceiling'): emitter: its front")),
        "{:?}",
        s.warnings
    );
}

/// OBJ and MTL statements radcol does not read are warned about once per
/// kind, with the count and the first line.
#[test]
fn ignored_statements_are_warned_once_per_kind() {
    let mtl = "newmtl white\nKd 0.5 0.5 0.5\nNs 10\nmap_Kd wood.png\nNs 20\n";
    let (p, r) = load(&square("vn 0 0 1\nvn 0 0 1\ns 1\n"), mtl);
    let s = alone(r.unwrap());
    let obj = p.display().to_string();
    let mtl = p.with_file_name("t.mtl").display().to_string();
    let want = [
        format!("{mtl}:4: 1 'map_Kd' statement ignored: a texture map"),
        format!("{mtl}:3: 2 'Ns' statements ignored: not a diffuse property"),
        format!("{obj}:12: 1 's' statement ignored: smoothing groups"),
        format!("{obj}:10: 2 'vn' statements ignored: vertex normals"),
    ];
    assert_eq!(s.warnings.len(), want.len(), "{:?}", s.warnings);
    for w in want {
        assert!(
            s.warnings.iter().any(|s| s.starts_with(&w)),
            "{w} in {:?}",
            s.warnings
        );
    }
}

/// OBJ texture coordinates reach the scene: per surface triangle, in the
/// triangle's corner order, v flipped to glTF's top-down convention, from
/// `v/vt` and `v/vt/vn` entries with positive or negative indices. A scene
/// where only some faces have them keeps none and says so; an index
/// beyond the vt statements is refused by line.
#[test]
fn obj_texture_coordinates_follow_the_triangles() {
    let head = "mtllib t.mtl\nv 0 0 0\nv 2 0 0\nv 2 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 0.5\nvt 0 0.5\ng floor\nusemtl white\n";
    for face in ["f 1/1 2/2 3/3 4/4", "f 1/-4/1 2/-3/1 3/-2/1 4/-1/1"] {
        let (_, r) = load(&format!("{head}{face}\n"), MTL);
        let s = alone(r.unwrap());
        let uvs = s.uvs.as_ref().expect("every triangle has vt");
        let patch = &s.surface.patches[0];
        assert_eq!(uvs[0].len(), patch.triangles.len());
        for (tri, uv) in patch.triangles.iter().zip(&uvs[0]) {
            for (x, uv) in tri.iter().zip(uv) {
                // u = x / 2, v (down) = 1 - y / 2
                assert_eq!(*uv, [x.x / 2.0, 1.0 - x.y / 2.0], "{face}");
            }
        }
    }
    let (_, r) = load(&format!("{head}f 1/1 2/2 3/3\nf 1 3 4\n"), MTL);
    let s = r.unwrap();
    assert!(s.uvs.is_none());
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains(":13: 1 of 2 triangles have no texture coordinates")),
        "{:?}",
        s.warnings
    );
    let msg = err_at(&format!("{head}f 1/1 2/5 3/3\n"), MTL, "t.obj", 12);
    assert!(
        msg.contains("texture coordinate index 5 is out of range (4 vt"),
        "{msg}"
    );
}

/// A 4 × 4 floor and a 1 × 1 × 1 box standing on it at (1..2, 1..2) with
/// an open bottom, whose walls imprint the floor; with `uvs`, the floor's
/// texture coordinates are (x / 4, y / 4) and the walls' (x / 4, z).
fn contact_scene(uvs: bool) -> Scene {
    let mut b = crate::scene::SceneBuilder::new("contact");
    let white = b
        .add_material(Material::diffuse("white", [0.5; 3]))
        .unwrap();
    let c = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    let floor = [c(0., 0., 0.), c(4., 0., 0.), c(4., 4., 0.), c(0., 4., 0.)];
    let walls = [
        c(1., 1., 0.),
        c(2., 1., 0.),
        c(2., 2., 0.),
        c(1., 2., 0.),
        c(1., 1., 1.),
        c(2., 1., 1.),
        c(2., 2., 1.),
        c(1., 2., 1.),
    ];
    let faces = [
        [0, 1, 5],
        [0, 5, 4],
        [1, 2, 6],
        [1, 6, 5],
        [2, 3, 7],
        [2, 7, 6],
        [3, 0, 4],
        [3, 4, 7],
        [4, 5, 6],
        [4, 6, 7],
    ];
    let floor_tris = [[0, 1, 2], [0, 2, 3]];
    if uvs {
        let uv = |p: &[DVec3], f: fn(&DVec3) -> [f64; 2]| p.iter().map(f).collect::<Vec<_>>();
        b.add_mesh_with_uvs(
            "floor",
            &floor,
            &uv(&floor, |p| [p.x / 4.0, p.y / 4.0]),
            &floor_tris,
            white,
        )
        .unwrap();
        b.add_mesh_with_uvs(
            "box",
            &walls,
            &uv(&walls, |p| [p.x / 4.0, p.z]),
            &faces,
            white,
        )
        .unwrap();
    } else {
        b.add_mesh_f64("floor", &floor, &floor_tris, white).unwrap();
        b.add_mesh_f64("box", &walls, &faces, white).unwrap();
    }
    b.build().unwrap()
}

/// A face split by an imprinted contact line gives its pieces the
/// texture coordinates of their corners' positions on the face.
#[test]
fn imprinted_pieces_interpolate_texture_coordinates() {
    let s = contact_scene(true);
    assert!(s.imprinted.triangles > 0, "{:?}", s.imprinted);
    let uvs = s.uvs.as_ref().unwrap();
    let floor_patch = &s.surface.patches[0];
    assert!(floor_patch.triangles.len() > 2);
    for (tri, uv) in floor_patch.triangles.iter().zip(&uvs[0]) {
        for (x, uv) in tri.iter().zip(uv) {
            assert!((uv[0] - x.x / 4.0).abs() < 1e-12 && (uv[1] - x.y / 4.0).abs() < 1e-12);
        }
    }
}

/// Every surface triangle knows its input triangle: the running index,
/// the OBJ's 0-based `v` indices of its corners and the line, also through
/// a polygon's triangulation; imprinted pieces keep the face they were cut
/// from, and every element of a refined mesh lies inside its origin.
#[test]
fn surface_triangles_and_elements_know_their_input_triangle() {
    let text = "mtllib t.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 0 1 1\ng floor\nusemtl white\nf 1 2 3 4\ng wall\nusemtl white\nf 1 4 6 5\n";
    let (p, r) = load(text, MTL);
    let s = r.unwrap();
    let f = p.display().to_string();
    let all: Vec<&TriangleOrigin> = s.origins.iter().flatten().collect();
    assert_eq!(
        all.iter().map(|o| o.input).collect::<Vec<_>>(),
        [0, 1, 2, 3]
    );
    for (patch, origins) in s.surface.patches.iter().zip(&s.origins) {
        for (tri, o) in patch.triangles.iter().zip(origins) {
            assert_eq!(*tri, o.corners, "not imprinted: the piece is the triangle");
            let positions = [
                DVec3::ZERO,
                DVec3::X,
                DVec3::new(1., 1., 0.),
                DVec3::Y,
                DVec3::Z,
                DVec3::new(0., 1., 1.),
            ];
            assert_eq!(o.vertices.map(|v| positions[v as usize]), o.corners);
        }
    }
    assert!(all[..2].iter().all(|o| o.at == format!("{f}:10")));
    assert!(all[2..].iter().all(|o| o.at == format!("{f}:13")));

    // The contact scene: the floor's pieces keep the floor's triangles.
    let s = contact_scene(false);
    assert!(s.imprinted.triangles > 0);
    let inside = |o: &TriangleOrigin, x: DVec3| {
        let [a, b, c] = o.corners;
        let n = (b - a).cross(c - a);
        [(a, b), (b, c), (c, a)]
            .iter()
            .all(|&(p, q)| (q - p).cross(x - p).dot(n) >= -1e-12 * n.length_squared())
            && (x - a).dot(n).abs() <= 1e-12 * n.length()
    };
    for (patch, origins) in s.surface.patches.iter().zip(&s.origins) {
        for (tri, o) in patch.triangles.iter().zip(origins) {
            let want = if patch.name.starts_with("floor") {
                0..2
            } else {
                2..12
            };
            assert!(want.contains(&o.input), "{o:?}");
            assert_eq!(
                o.at,
                format!(
                    "mesh '{}' face {}",
                    &patch.name[..patch.name.find('/').unwrap()],
                    o.input - want.start
                )
            );
            assert!(tri.iter().all(|&x| inside(o, x)), "{tri:?} outside {o:?}");
        }
    }
    let mesh = crate::mesh::Mesh::new(s.surface.clone(), 2);
    let origins = s.element_origins(&mesh);
    assert_eq!(origins.len(), mesh.len());
    for (k, o) in origins.iter().enumerate() {
        let o = o.expect("every element has an input triangle");
        let centroid = mesh.vertices(k).iter().sum::<DVec3>() / 3.0;
        assert!(inside(o, centroid), "element {k} outside {o:?}");
    }
}
