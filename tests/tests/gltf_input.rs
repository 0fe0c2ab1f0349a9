//! glTF input against OBJ input: the Cornell box written as glTF 2.0 by
//! this test (one node per patch under a translated parent, rotated,
//! scaled and mirrored child transforms, f32 buffers, materials with
//! `KHR_materials_emissive_strength`, a camera) and as OBJ + MTL with the
//! world positions and material values the glTF encodes (computed here from
//! the f32 data and the node matrices in f64) gives the same radiosity to
//! 1e-12. The writer below is independent of the loader: serde_json and raw
//! little-endian buffers. Its TEXCOORD_1 (a lightmap layout) is the scene's
//! texture coordinates, not its tiling TEXCOORD_0.

use glam::{DMat4, DQuat, DVec3};
use radcol_core::assembly::CpuBackend;
use radcol_core::run::{solve, SolveConfig};
use radcol_core::scene::{builtin, load_gltf, load_obj, Scene, SceneError};
use serde_json::{json, Value};
use std::fmt::Write as _;
use std::path::PathBuf;

/// A fresh directory for one test's files.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("radcol-gltf-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The child transform of patch `i`: a quarter turn about y with scale 1/2
/// for even i, a mirror in x with scale 2 for odd i (negative determinant:
/// the loader must rewind), each with a translation; entries exact in f32.
fn child(i: usize) -> DMat4 {
    let t = DVec3::new(3.0 * i as f64, -2.0, 0.5);
    if i.is_multiple_of(2) {
        DMat4::from_scale_rotation_translation(
            DVec3::splat(0.5),
            DQuat::from_xyzw(
                0.0,
                std::f64::consts::FRAC_1_SQRT_2,
                0.0,
                std::f64::consts::FRAC_1_SQRT_2,
            ),
            t,
        )
    } else {
        DMat4::from_translation(t) * DMat4::from_scale(DVec3::new(-2.0, 2.0, 2.0))
    }
}

/// The f32 matrix glTF stores for `m`, read back as f64 (what the loader sees).
fn stored(m: DMat4) -> DMat4 {
    m.as_mat4().as_dmat4()
}

/// Writes `scene` as `dir/cornell.gltf` (+ `.bin`) and, from what that glTF
/// encodes, `dir/cornell.obj` (+ `.mtl`).
/// The lightmap coordinates (TEXCOORD_1) written for corner `k` of
/// triangle `t` of patch `i`: exact in f32, inside [0, 1].
fn lightmap_uv(i: usize, t: usize, k: usize) -> [f32; 2] {
    [(i as f32 + 0.25 * k as f32) / 64.0, (t as f32 + 0.5) / 16.0]
}

fn write_both(scene: &Scene, dir: &std::path::Path) {
    let parent = stored(DMat4::from_translation(DVec3::new(100.0, -50.0, 25.0)));
    let mut bin: Vec<u8> = Vec::new();
    let (mut views, mut accessors, mut meshes, mut nodes) = (vec![], vec![], vec![], vec![]);
    let (mut obj, mut mtl) = (String::from("mtllib cornell.mtl\n"), String::new());
    let mut children = Vec::new();
    for (i, patch) in scene.surface.patches.iter().enumerate() {
        let c = stored(child(i));
        let world = parent * c;
        let inverse = world.inverse();
        let mut positions: Vec<[f32; 3]> = Vec::new();
        let mut texcoords: Vec<[f32; 2]> = Vec::new();
        for (n, t) in patch.triangles.iter().enumerate() {
            // A mirrored node draws its triangles reversed.
            let order = if c.determinant() < 0.0 {
                [0, 2, 1]
            } else {
                [0, 1, 2]
            };
            for k in order {
                positions.push(inverse.transform_point3(t[k]).as_vec3().to_array());
                texcoords.push(lightmap_uv(i, n, k));
            }
        }
        let offset = bin.len();
        for p in &positions {
            for x in p {
                bin.extend_from_slice(&x.to_le_bytes());
            }
        }
        let index_offset = bin.len();
        for k in 0..positions.len() as u32 {
            bin.extend_from_slice(&k.to_le_bytes());
        }
        // TEXCOORD_0 a tiling set (outside [0, 1]), TEXCOORD_1 the lightmap's.
        let uv_offset = bin.len();
        for (k, uv) in texcoords.iter().enumerate() {
            for x in [4.0 * k as f32, -1.5] {
                bin.extend_from_slice(&x.to_le_bytes());
            }
            for x in uv {
                bin.extend_from_slice(&x.to_le_bytes());
            }
        }
        let (lo, hi) = positions.iter().fold(
            ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]),
            |(lo, hi), p| {
                (
                    [0, 1, 2].map(|a| lo[a].min(p[a])),
                    [0, 1, 2].map(|a| hi[a].max(p[a])),
                )
            },
        );
        views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": index_offset - offset, "target": 34962}));
        views.push(json!({"buffer": 0, "byteOffset": index_offset, "byteLength": uv_offset - index_offset, "target": 34963}));
        views.push(json!({"buffer": 0, "byteOffset": uv_offset, "byteLength": bin.len() - uv_offset, "byteStride": 16, "target": 34962}));
        accessors.push(json!({"bufferView": 3 * i, "componentType": 5126, "count": positions.len(), "type": "VEC3", "min": lo, "max": hi}));
        accessors.push(json!({"bufferView": 3 * i + 1, "componentType": 5125, "count": positions.len(), "type": "SCALAR"}));
        accessors.push(json!({"bufferView": 3 * i + 2, "componentType": 5126, "count": positions.len(), "type": "VEC2"}));
        accessors.push(json!({"bufferView": 3 * i + 2, "byteOffset": 8, "componentType": 5126, "count": positions.len(), "type": "VEC2"}));
        meshes.push(json!({"primitives": [{"attributes": {"POSITION": 4 * i, "TEXCOORD_0": 4 * i + 2, "TEXCOORD_1": 4 * i + 3}, "indices": 4 * i + 1, "material": scene.patch_material[i]}]}));
        nodes.push(
            json!({"name": format!("p{i}"), "mesh": i, "matrix": c.as_mat4().to_cols_array()}),
        );
        children.push(i + 1);
        // The OBJ: the same triangles at the world positions the glTF encodes.
        writeln!(
            obj,
            "g p{i}\nusemtl {}",
            scene.materials[scene.patch_material[i]].name
        )
        .unwrap();
        for tri in positions.chunks(3) {
            let tri: Vec<DVec3> = tri
                .iter()
                .map(|p| world.transform_point3(glam::Vec3::from_array(*p).as_dvec3()))
                .collect();
            let tri = if c.determinant() < 0.0 {
                [tri[0], tri[2], tri[1]]
            } else {
                [tri[0], tri[1], tri[2]]
            };
            for v in tri {
                writeln!(obj, "v {:?} {:?} {:?}", v.x, v.y, v.z).unwrap();
            }
            obj.push_str("f -3 -2 -1\n");
        }
    }
    let mut materials = Vec::new();
    for m in &scene.materials {
        let rho = m.rho.map(|r| r as f32);
        let strength = m.emission.iter().cloned().fold(0.0, f64::max).max(1.0) as f32;
        let factor = m.emission.map(|e| (e / f64::from(strength)) as f32);
        let mut mat = json!({
            "name": m.name,
            "pbrMetallicRoughness": {"baseColorFactor": [rho[0], rho[1], rho[2], 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0},
            "emissiveFactor": factor,
        });
        if strength > 1.0 {
            mat["extensions"] =
                json!({"KHR_materials_emissive_strength": {"emissiveStrength": strength}});
        }
        materials.push(mat);
        let e = factor.map(|f| f64::from(f) * f64::from(strength));
        let r = rho.map(f64::from);
        writeln!(
            mtl,
            "newmtl {}\nKd {:?} {:?} {:?}\nKe {:?} {:?} {:?}",
            m.name, r[0], r[1], r[2], e[0], e[1], e[2]
        )
        .unwrap();
    }
    // The camera: at (278, 273, -800) turned half about y (looking down +z).
    let camera_node = nodes.len() + 1;
    nodes.insert(
        0,
        json!({"name": "room", "translation": [100.0, -50.0, 25.0], "children": children}),
    );
    nodes.push(json!({"name": "eye", "camera": 0, "translation": [278.0, 273.0, -800.0], "rotation": [0.0, 1.0, 0.0, 0.0]}));
    let doc: Value = json!({
        "asset": {"version": "2.0", "generator": "radcol tests"},
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "scene": 0,
        "scenes": [{"nodes": [0, camera_node]}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.6981317, "znear": 0.1}}],
        "buffers": [{"uri": "cornell.bin", "byteLength": bin.len()}],
        "bufferViews": views,
        "accessors": accessors,
    });
    std::fs::write(dir.join("cornell.bin"), &bin).unwrap();
    std::fs::write(
        dir.join("cornell.gltf"),
        serde_json::to_vec_pretty(&doc).unwrap(),
    )
    .unwrap();
    std::fs::write(dir.join("cornell.obj"), obj).unwrap();
    std::fs::write(dir.join("cornell.mtl"), mtl).unwrap();
}

/// The glTF Cornell box and its OBJ twin: same patches, same materials,
/// the glTF camera, and the same radiosity to 1e-12 at every node.
#[test]
fn gltf_cornell_box_matches_its_obj_twin() {
    let dir = scratch("cornell");
    let scene = builtin("cornell").unwrap().unwrap();
    write_both(&scene, &dir);
    let g = load_gltf(&dir.join("cornell.gltf")).unwrap();
    let o = load_obj(&dir.join("cornell.obj")).unwrap();
    let names = |s: &Scene| {
        s.surface
            .patches
            .iter()
            .map(|p| p.name.clone())
            .collect::<Vec<_>>()
    };
    assert_eq!(names(&g), names(&o));
    let sorted = |s: &Scene| {
        let mut m = s.materials.clone();
        m.sort_by(|a, b| a.name.cmp(&b.name));
        m
    };
    assert_eq!(sorted(&g), sorted(&o));
    assert_eq!(g.triangle_count(), o.triangle_count());
    assert!(g.warnings.is_empty(), "{:?}", g.warnings);
    // TEXCOORD_1 (the lightmap set) wins over the tiling TEXCOORD_0, corner
    // by corner through the mirrored nodes' rewinding; the OBJ has no vt.
    let uvs = g.uvs.as_ref().expect("every triangle has TEXCOORD_1");
    for (i, patch) in uvs.iter().enumerate() {
        for (t, corners) in patch.iter().enumerate() {
            for (k, uv) in corners.iter().enumerate() {
                assert_eq!(
                    *uv,
                    lightmap_uv(i, t, k).map(f64::from),
                    "patch {i} triangle {t}"
                );
            }
        }
    }
    assert!(o.uvs.is_none());
    let cam = g.camera.expect("the glTF camera");
    assert!(
        (cam.eye - DVec3::new(278.0, 273.0, -800.0)).length() < 1e-9,
        "{cam:?}"
    );
    assert!(
        ((cam.target - cam.eye).normalize() - DVec3::Z).length() < 1e-7,
        "{cam:?}"
    );
    assert!((cam.fov_y_deg - 40.0).abs() < 1e-5, "{cam:?}");
    let cfg = SolveConfig {
        degree: 1,
        level: 1,
        ..Default::default()
    };
    let (sg, so) = (
        solve(&g.problem(), &cfg, &CpuBackend).unwrap(),
        solve(&o.problem(), &cfg, &CpuBackend).unwrap(),
    );
    for (cg, co) in sg.channels.iter().zip(&so.channels) {
        let (a, b) = (cg.solution.nodal(), co.solution.nodal());
        let scale = b.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let worst = a
            .iter()
            .zip(b)
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        println!(
            "channel {}: max |u_gltf - u_obj| / max |u| = {:.2e}",
            co.name,
            worst / scale
        );
        assert!(
            worst <= 1e-12 * scale,
            "{}: {worst:.3e} of {scale:.3e}",
            co.name
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The positions of the unit right triangle (0,0,0), (1,0,0), (0,1,0), as
/// a glTF buffer of little-endian f32 (36 bytes).
fn triangle_bin() -> Vec<u8> {
    [[0f32, 0., 0.], [1., 0., 0.], [0., 1., 0.]]
        .iter()
        .flat_map(|p| p.iter().flat_map(|x| x.to_le_bytes()))
        .collect()
}

/// A primitive without a material (glTF's default is white, ρ = 1) is
/// refused naming the file and mesh; a broken file is refused naming it.
#[test]
fn gltf_faults_name_the_file_and_the_mesh() {
    let dir = scratch("faults");
    let bin = triangle_bin();
    let doc = json!({
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "floor", "mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "buffers": [{"uri": "t.bin", "byteLength": bin.len()}],
        "bufferViews": [{"buffer": 0, "byteLength": bin.len()}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}],
    });
    std::fs::write(dir.join("t.bin"), &bin).unwrap();
    let path = dir.join("t.gltf");
    std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
    let e = load_gltf(&path).unwrap_err();
    assert!(matches!(e, SceneError::NoMaterial { .. }), "{e}");
    let msg = e.to_string();
    assert!(
        msg.contains("t.gltf") && msg.contains("mesh 'floor'") && msg.contains("ρ = 1"),
        "{msg}"
    );
    std::fs::write(&path, b"{ not json").unwrap();
    let msg = load_gltf(&path).unwrap_err().to_string();
    assert!(
        msg.starts_with("cannot read glTF file") && msg.contains("t.gltf"),
        "{msg}"
    );
    let msg = load_gltf(&dir.join("missing.glb")).unwrap_err().to_string();
    assert!(msg.contains("missing.glb"), "{msg}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Node hierarchies a hostile file may hold: a node its own child, two
/// nodes in a loop and a node with two parents are refused naming the node
/// (they overflowed the stack); a valid chain 20 000 nodes deep loads; a
/// rotation that is not a unit quaternion is normalised with a warning (it
/// scaled the mesh: ∫ over the triangle is its area 1/2 either way here,
/// checked by the area of the placed triangle), and a zero one is refused.
#[test]
fn gltf_node_trees_from_hostile_files() {
    let dir = scratch("nodes");
    let bin = triangle_bin();
    std::fs::write(dir.join("t.bin"), &bin).unwrap();
    let doc = |nodes: Value, roots: Value| {
        json!({
            "asset": {"version": "2.0"},
            "scenes": [{"nodes": roots}],
            "nodes": nodes,
            "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1]}, "emissiveFactor": [1, 1, 1]}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "material": 0}]}],
            "buffers": [{"uri": "t.bin", "byteLength": bin.len()}],
            "bufferViews": [{"buffer": 0, "byteLength": bin.len()}],
            "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}],
        })
    };
    let path = dir.join("t.gltf");
    let load = |d: Value| {
        std::fs::write(&path, serde_json::to_vec(&d).unwrap()).unwrap();
        load_gltf(&path)
    };
    let refused = [
        (
            "own child",
            json!([{"mesh": 0, "children": [0]}]),
            json!([0]),
        ),
        (
            "a loop",
            json!([{"mesh": 0, "children": [1]}, {"children": [0]}]),
            json!([0]),
        ),
        (
            "two parents",
            json!([{"children": [2]}, {"children": [2]}, {"mesh": 0}]),
            json!([0, 1]),
        ),
    ];
    for (what, nodes, roots) in refused {
        let msg = match load(doc(nodes, roots)) {
            Ok(_) => panic!("{what}: loaded"),
            Err(e) => e.to_string(),
        };
        assert!(
            msg.contains("t.gltf") && msg.contains("reached twice"),
            "{what}: {msg}"
        );
    }
    let depth = 20_000;
    let chain: Vec<Value> = (0..depth)
        .map(|i| match i + 1 < depth {
            true => json!({"children": [i + 1]}),
            false => json!({"mesh": 0}),
        })
        .collect();
    let scene = load(doc(Value::Array(chain), json!([0]))).expect("a deep chain loads");
    assert_eq!(
        scene
            .surface
            .patches
            .iter()
            .map(|p| p.triangles.len())
            .sum::<usize>(),
        1
    );
    let area = |s: &Scene| {
        let t = s.surface.patches[0].triangles[0];
        0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length()
    };
    // A quarter turn about z, written with length 2.
    let turned = json!([{"mesh": 0, "rotation": [0, 0, std::f64::consts::SQRT_2, std::f64::consts::SQRT_2]}]);
    let scene = load(doc(turned, json!([0]))).expect("normalised");
    assert!((area(&scene) - 0.5).abs() < 1e-6, "area {}", area(&scene));
    let warned = scene
        .warnings
        .iter()
        .any(|w| w.contains("node 0") && w.contains("unit quaternion"));
    assert!(warned, "{:?}", scene.warnings);
    let zero = json!([{"mesh": 0, "rotation": [0, 0, 0, 0]}]);
    let msg = match load(doc(zero, json!([0]))) {
        Ok(_) => panic!("a zero rotation loaded"),
        Err(e) => e.to_string(),
    };
    assert!(
        msg.contains("node 0") && msg.contains("not a rotation"),
        "{msg}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Buffers a hostile file may name: outside the scene's directory, a
/// device, a name that percent-decodes to bytes that are not UTF-8, a file
/// shorter than its byteLength — each refused naming the buffer (they were
/// read as the buffer, read forever, or panicked) — and a 16 GiB file
/// (sparse) of which the buffer is the first 36 bytes: no more is read
/// (reading it whole asked for 16 GiB).
#[test]
fn gltf_buffers_from_hostile_files() {
    let dir = scratch("buffers");
    let bin = triangle_bin();
    let path = dir.join("t.gltf");
    let load = |uri: &str, length: usize| {
        let doc = json!({
            "asset": {"version": "2.0"},
            "scenes": [{"nodes": [0]}],
            "nodes": [{"mesh": 0}],
            "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1]}, "emissiveFactor": [1, 1, 1]}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "material": 0}]}],
            "buffers": [{"uri": uri, "byteLength": length}],
            "bufferViews": [{"buffer": 0, "byteLength": 36}],
            "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}],
        });
        std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
        load_gltf(&path).map_err(|e| e.to_string())
    };
    let refused = |uri: &str, length: usize, needles: &[&str]| {
        let msg = load(uri, length)
            .err()
            .unwrap_or_else(|| panic!("{uri}: loaded"));
        for n in needles {
            assert!(msg.contains(n) && msg.contains("buffer 0"), "{uri}: {msg}");
        }
    };
    refused(
        "../../../../../../etc/passwd",
        36,
        &["outside the scene's directory"],
    );
    refused("file:///dev/zero", 36, &["outside the scene's directory"]);
    std::os::unix::fs::symlink("/dev/zero", dir.join("zero.bin")).unwrap();
    refused("zero.bin", 36, &["outside the scene's directory"]);
    refused("%FF%FE.bin", 36, &["does not decode to UTF-8"]);
    std::fs::write(dir.join("short.bin"), &bin[..20]).unwrap();
    refused("short.bin", 36, &["20 bytes", "byteLength says 36"]);
    let big = std::fs::File::create(dir.join("big.bin")).unwrap();
    big.set_len(1 << 34).unwrap();
    drop(big);
    std::fs::OpenOptions::new()
        .write(true)
        .open(dir.join("big.bin"))
        .and_then(|mut f| std::io::Write::write_all(&mut f, &bin))
        .unwrap();
    load("big.bin", 36).expect("the first 36 bytes are the buffer");
    std::fs::write(dir.join("t.bin"), &bin).unwrap();
    load("t.bin", 36).expect("a plain buffer");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Accessors a hostile file may hold, each refused naming what is wrong
/// (they were read as "no indices" and solved 2 of 12 triangles, dropped
/// indices silently, or tripped the gltf crate's assertions): 35 indices,
/// an index accessor past its view, an index view with a byteStride, a
/// position view whose byteStride is shorter than a position, float
/// indices. Morph targets are warned about: the base shape is solved.
#[test]
fn gltf_accessors_from_hostile_files() {
    let dir = scratch("accessors");
    let mut bin = triangle_bin();
    // 36 indices (u16) after the positions: 0, 1, 2 twelve times.
    bin.extend((0..36u16).flat_map(|i| (i % 3).to_le_bytes()));
    std::fs::write(dir.join("t.bin"), &bin).unwrap();
    let path = dir.join("t.gltf");
    let load = |views: Value, accessors: Value, primitive: Value| {
        let doc = json!({
            "asset": {"version": "2.0"},
            "scenes": [{"nodes": [0]}],
            "nodes": [{"mesh": 0}],
            "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1]}, "emissiveFactor": [1, 1, 1]}],
            "meshes": [{"primitives": [primitive]}],
            "buffers": [{"uri": "t.bin", "byteLength": bin.len()}],
            "bufferViews": views,
            "accessors": accessors,
        });
        std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
        load_gltf(&path)
    };
    let position = json!({"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]});
    let views = |index_view: Value| json!([{"buffer": 0, "byteLength": 36}, index_view]);
    let indices = |count: usize, component: u32| json!({"bufferView": 1, "componentType": component, "count": count, "type": "SCALAR"});
    let indexed = json!({"attributes": {"POSITION": 0}, "indices": 1, "material": 0});
    let plain_view = json!({"buffer": 0, "byteOffset": 36, "byteLength": 72});
    let scene = load(
        views(plain_view.clone()),
        json!([position, indices(36, 5123)]),
        indexed.clone(),
    )
    .expect("36 indices");
    // Twelve copies of one triangle are one piece of surface.
    assert_eq!(scene.surface.patches[0].triangles.len(), 1);
    let cases = [
        (
            "35 indices",
            views(plain_view.clone()),
            json!([position, indices(35, 5123)]),
            "not a multiple of 3",
        ),
        (
            "past its view",
            views(json!({"buffer": 0, "byteOffset": 36, "byteLength": 40})),
            json!([position, indices(36, 5123)]),
            "run to byte 72",
        ),
        (
            "strided indices",
            views(json!({"buffer": 0, "byteOffset": 36, "byteLength": 72, "byteStride": 4})),
            json!([position, indices(18, 5123)]),
            "byteStride",
        ),
        (
            "float indices",
            views(plain_view.clone()),
            json!([position, indices(18, 5126)]),
            "not unsigned integers",
        ),
        (
            "short position stride",
            json!([{"buffer": 0, "byteLength": 36, "byteStride": 4}, plain_view.clone()]),
            json!([position, indices(36, 5123)]),
            "less than its 12-byte elements",
        ),
    ];
    for (what, v, a, needle) in cases {
        let msg = match load(v, a, indexed.clone()) {
            Ok(_) => panic!("{what}: loaded"),
            Err(e) => e.to_string(),
        };
        assert!(
            msg.contains("t.gltf") && msg.contains(needle),
            "{what}: {msg}"
        );
    }
    let morphed =
        json!({"attributes": {"POSITION": 0}, "material": 0, "targets": [{"POSITION": 0}]});
    let scene = load(views(plain_view), json!([position]), morphed).expect("loads");
    let warned = scene.warnings.iter().any(|w| w.contains("morph targets"));
    assert!(warned, "{:?}", scene.warnings);
    let _ = std::fs::remove_dir_all(&dir);
}
