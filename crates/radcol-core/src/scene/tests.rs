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

#[test]
fn loads_a_square_with_materials() {
    let (path, r) = load(&square(""), MTL);
    let s = r.unwrap();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    assert_eq!(s.source.as_deref(), Some(path.as_path()));
    assert_eq!(s.name, "t");
    assert_eq!(s.triangle_count(), 2);
    assert_eq!(s.vertex_count(), 4);
    assert_eq!(s.surface.patches.len(), 1);
    assert_eq!(s.surface.patches[0].name, "floor/white");
    assert!((s.area() - 1.0).abs() < 1e-15);
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

#[test]
fn repairs_and_warnings_name_lines() {
    let f = |p: &Path| p.display().to_string();
    // A repeated vertex and a collinear triangle: dropped.
    let (p, r) = load(&square("v 2 0 0\nf 1 2 5\nf 1 1 2\n"), MTL);
    let s = r.unwrap();
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
    let s = r.unwrap();
    assert_eq!(s.triangle_count(), 2);
    assert!(s.warnings[0].contains(&format!(
        "{}:10: duplicate of the triangle at {}:8",
        f(&p),
        f(&p)
    )));
    // Opposite orientation: a two-sided panel, kept without a warning.
    let (_, r) = load(&square("usemtl lamp\nf 1 3 2\nf 1 4 3\n"), MTL);
    let s = r.unwrap();
    assert_eq!(s.triangle_count(), 4);
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    // Non-planar quad.
    let (p, r) = load(
        &square("v 0 0 1\nv 1 0 1\nv 1 1 1.5\nv 0 1 1\nf 5 6 7 8\n"),
        MTL,
    );
    let s = r.unwrap();
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
    let s = r.unwrap();
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
    let s = r.unwrap();
    assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
    let w = &s.warnings[0];
    assert!(
        w.contains("T-junction")
            && w.contains(&format!("{}:12", f(&p)))
            && w.contains(&format!("{}:8", f(&p))),
        "{w}"
    );
    // A fin on the diagonal 1-3: three triangles share it.
    let (p, r) = load(&square("v 0 0 1\nf 1 3 5\n"), MTL);
    let s = r.unwrap();
    assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
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
    assert!((t.area() - 6.25 * s.area()).abs() < 1e-12 * t.area());
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
