use super::*;
use crate::progress::Cancel;
use crate::scene::builtin;
use glam::DVec3;

fn cornell() -> Scene {
    builtin("cornell").expect("built in").expect("loads")
}

/// The Cornell box to a coarse target (50 elements, a quarter of a
/// second): the identities below hold at any resolution.
/// The Cornell box to 0.1 of max |u| (the light's radiosity): a few
/// steps, met everywhere.
fn solved() -> Radiosity {
    let settings = Settings {
        target_error: Some(0.1),
        relative_to: RelativeTo::MaxU,
        ..Settings::default()
    };
    Radiosity::solve(cornell(), &settings).expect("solves")
}

/// The Cornell box's input triangles each cut into four elements.
fn refined() -> Radiosity {
    let scene = cornell();
    let config = SolveConfig {
        level: 1,
        max_edge: None,
        ..scene.solve_config(false)
    };
    Radiosity::solve_with(scene, config, None, &CpuBackend).expect("solves")
}

fn light_name(scene: &Scene) -> String {
    let light = scene.materials.iter().find(|m| m.is_emitter()).unwrap();
    light.name.clone()
}

#[test]
fn a_solved_scene_can_live_in_an_application_and_cross_threads() {
    fn owned<T: Send + Sync + 'static>() {}
    owned::<Radiosity>();
    owned::<Error>();
}

#[test]
fn the_default_settings_are_the_commands() {
    let scene = cornell();
    let (config, adapt) = Settings::default().configure(&scene);
    assert!(adapt.is_none());
    let command = scene.solve_config(false);
    assert_eq!(format!("{config:?}"), format!("{command:?}"));
    let (config, adapt) = Settings {
        target_error: Some(1e-2),
        ..Settings::default()
    }
    .configure(&scene);
    let adapt = adapt.expect("a target refines");
    assert!(adapt.graded_start && adapt.target == 1e-2);
    assert_eq!(config.degree, crate::run::ADAPTIVE_DEGREE);
    assert_eq!((config.level, config.max_edge), (0, None));
    let (config, adapt) = Settings {
        target_error: Some(1e-2),
        degree: Some(3),
        ..Settings::default()
    }
    .configure(&scene);
    assert!(!adapt.unwrap().graded_start);
    assert_eq!((config.degree, config.alpha), (3, auto_alpha(3)));
}

/// The system is linear in E: doubling the light doubles u_n and û_n at
/// every point, switching it off leaves zero, and putting it back gives the
/// first solve's values (to the solver's tolerance).
#[test]
fn relit_values_are_queried_like_the_first() {
    let mut solved = solved();
    let name = light_name(solved.scene());
    let e = solved
        .scene()
        .materials
        .iter()
        .find(|m| m.name == name)
        .unwrap()
        .emission;
    let points = four_points();
    let first = solved.query(&points).unwrap();
    assert!(first
        .iter()
        .all(|p| p.channels.iter().all(|c| c.estimate.is_some())));
    let max_u = (solved.channels().iter())
        .map(|c| {
            c.solution
                .nodal()
                .iter()
                .fold(0.0f64, |a, &b| a.max(b.abs()))
        })
        .fold(0.0, f64::max);

    solved
        .relight(&[(&name, MaterialChange::Emission(e.map(|x| 2.0 * x)))])
        .unwrap();
    let doubled = solved.query(&points).unwrap();
    for (a, b) in first.iter().zip(&doubled) {
        for (x, y) in a.channels.iter().zip(&b.channels) {
            assert!((y.u - 2.0 * x.u).abs() <= 1e-8 * max_u, "{} {}", x.u, y.u);
            assert!((y.iterated - 2.0 * x.iterated).abs() <= 1e-8 * max_u);
            assert!(y.estimate.is_none());
        }
    }

    solved
        .relight(&[(&name, MaterialChange::Emission([0.0; 3]))])
        .unwrap();
    let dark = solved.query(&points).unwrap();
    assert!(dark
        .iter()
        .all(|p| p.channels.iter().all(|c| c.u == 0.0 && c.iterated == 0.0)));

    solved
        .relight(&[(&name, MaterialChange::Emission(e))])
        .unwrap();
    let back = solved.query(&points).unwrap();
    for (a, b) in first.iter().zip(&back) {
        for (x, y) in a.channels.iter().zip(&b.channels) {
            assert!((y.iterated - x.iterated).abs() <= 1e-8 * max_u);
        }
    }
}

#[test]
fn a_bad_relight_changes_nothing() {
    let mut solved = solved();
    let before: Vec<f64> = solved.channels().iter().map(|c| c.integral_u).collect();
    let name = light_name(solved.scene());
    let err = solved
        .relight(&[
            (&name, MaterialChange::Emission([0.0; 3])),
            ("no such", MaterialChange::Emission([1.0; 3])),
        ])
        .unwrap_err();
    assert!(matches!(
        err,
        Error::Scene(crate::scene::SceneError::NoSuchMaterial { .. })
    ));
    let err = solved
        .relight(&[(&name, MaterialChange::Reflectance([1.5, 0.5, 0.5]))])
        .unwrap_err();
    assert!(err.to_string().contains("Kd R = 1.5"), "{err}");
    let after: Vec<f64> = solved.channels().iter().map(|c| c.integral_u).collect();
    assert_eq!(before, after);
    assert!(solved
        .scene()
        .materials
        .iter()
        .any(|m| m.name == name && m.is_emitter()));
}

/// Each input triangle's corner values are the shown solution at that
/// corner, found the other way round: by locating a point a hair inside
/// the triangle from the corner and evaluating there.
#[test]
fn corner_values_are_the_solution_at_the_input_corners() {
    let solved = refined();
    let corners = solved.corner_values().unwrap();
    let scene = solved.scene();
    assert_eq!(corners.len(), scene.triangle_count());
    let origins: Vec<_> = scene.origins.iter().flatten().collect();
    let mut points = Vec::new();
    for cv in &corners {
        let o = origins.iter().find(|o| o.input == cv.input).unwrap();
        assert_eq!(o.vertices, cv.vertices);
        let centre = (o.corners[0] + o.corners[1] + o.corners[2]) / 3.0;
        let normal = (o.corners[1] - o.corners[0]).cross(o.corners[2] - o.corners[0]);
        for c in o.corners {
            points.push(QueryPoint {
                position: c + 1e-7 * (centre - c),
                normal: Some(normal),
            });
        }
    }
    // Located, not queried: û_n's row at a point next to a corner of the
    // room is slow to integrate, and only the element and (s, t) are needed.
    let mesh = solved.outcome().discretization.mesh();
    let locator = crate::mesh::Locator::new(mesh);
    let reach = 1e-6 * solved.scene().diagonal();
    let located: Vec<_> = (points.iter())
        .map(|q| {
            locator
                .nearest(mesh, q.position, q.normal, reach)
                .expect("on S")
        })
        .collect();
    let shown = solved.shown();
    let max_u = (shown.iter())
        .map(|s| s.nodal().iter().fold(0.0f64, |a, &b| a.max(b.abs())))
        .fold(0.0, f64::max);
    for (i, at) in located.iter().enumerate() {
        let (cv, c) = (&corners[i / 3], i % 3);
        for ch in 0..3 {
            let want = shown[ch].eval(at.element, at.st[0], at.st[1]);
            let got = f64::from(cv.values[c][ch]);
            assert!(
                (got - want).abs() <= 1e-5 * max_u,
                "input triangle {}, corner {c}, channel {ch}: {got} against {want}",
                cv.input
            );
        }
    }
}

#[test]
fn a_scene_without_light_is_refused_and_a_cancelled_solve_stops() {
    let mut dark = cornell();
    let name = light_name(&dark);
    dark.change_material(&name, MaterialChange::Emission([0.0; 3]))
        .unwrap();
    let err = Radiosity::solve(dark, &Settings::default()).unwrap_err();
    assert!(matches!(
        err,
        Error::Solve(crate::error::Error::Input(InputError::NoEmission))
    ));

    let cancel = Cancel::new();
    cancel.cancel();
    let settings = Settings {
        progress: Some(cancel.handle()),
        ..Settings::default()
    };
    let err = Radiosity::solve(cornell(), &settings).unwrap_err();
    // Cancelled before the plan: nothing was assembled.
    assert!(
        matches!(err, Error::Solve(crate::error::Error::Cancelled { .. })),
        "{err}"
    );
}

#[test]
fn an_image_shows_the_lit_room() {
    let solved = solved();
    let options = RenderOptions {
        width: 24,
        height: 18,
        ..RenderOptions::default()
    };
    let image = solved.render(None, &options).unwrap();
    let pixels = crate::render::tone_map(&image, &crate::render::ToneMap::default());
    assert_eq!(pixels.len(), 24 * 18);
    let lit = pixels.iter().filter(|p| p.iter().any(|&c| c > 0)).count();
    assert!(lit > 24 * 18 / 2, "{lit} lit pixels");
}

/// The mesh written as GLB and read back by the gltf crate: every input
/// triangle once, under one node per object of the input, inside the room.
#[cfg(feature = "export")]
#[test]
fn the_written_mesh_is_the_input_mesh_with_its_objects() {
    let solved = solved();
    let mut glb = Vec::new();
    let tone = crate::render::ToneMap::default();
    solved.write_mesh(&mut glb, MeshFormat::Glb, &tone).unwrap();
    let (doc, buffers, _) = gltf::import_slice(&glb).expect("a valid GLB");
    let scene = solved.scene();
    let (lo, hi) = scene.bounding_box();
    let mut triangles = 0;
    let mut names = Vec::new();
    for node in doc.nodes() {
        let Some(mesh) = node.mesh() else { continue };
        names.push(node.name().unwrap_or_default().to_string());
        for prim in mesh.primitives() {
            let reader = prim.reader(|b| Some(&buffers[b.index()]));
            triangles += reader.read_indices().unwrap().into_u32().count() / 3;
            for p in reader.read_positions().unwrap() {
                let p = DVec3::new(p[0].into(), p[1].into(), p[2].into());
                assert!(p.cmpge(lo - 1e-3).all() && p.cmple(hi + 1e-3).all(), "{p}");
            }
            assert!(reader.read_colors(0).is_some());
        }
    }
    assert_eq!(triangles, scene.triangle_count());
    let groups: std::collections::BTreeSet<String> = (scene.surface.patches.iter())
        .map(|p| p.name.split('/').next().unwrap().to_string())
        .collect();
    assert_eq!(
        names
            .iter()
            .cloned()
            .collect::<std::collections::BTreeSet<_>>(),
        groups
    );
    assert!(names.len() > 1, "{names:?}");

    let mut ply = Vec::new();
    solved.write_mesh(&mut ply, MeshFormat::Ply, &tone).unwrap();
    let header = String::from_utf8_lossy(&ply[..ply.len().min(600)]);
    let faces = format!("element face {}", scene.triangle_count());
    assert!(
        header.starts_with("ply\n") && header.contains(&faces),
        "{header}"
    );
}

/// A written .gltf (its buffer a base64 data URI) loads again as a scene
/// with the same triangles and bounding box.
#[cfg(all(feature = "export", feature = "gltf"))]
#[test]
fn a_written_gltf_loads_again() {
    let solved = solved();
    let dir = std::env::temp_dir().join(format!("radcol-written-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("cornell.gltf");
    let tone = crate::render::ToneMap::default();
    let mut written = Vec::new();
    solved
        .write_mesh(&mut written, MeshFormat::Gltf, &tone)
        .unwrap();
    // Its unlit white (a base colour of 1) is no reflectance a scene may
    // have: read it as grey.
    let mut doc: serde_json::Value = serde_json::from_slice(&written).unwrap();
    doc["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"] =
        serde_json::json!([0.5, 0.5, 0.5, 1.0]);
    std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
    let again = crate::scene::load_gltf(&path).expect("loads");
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(again.triangle_count(), solved.scene().triangle_count());
    // The root node scales scene units to metres, and the reader applies it.
    let m = solved.scene().metres_per_unit.unwrap_or(1.0);
    let (a, b) = (again.bounding_box(), solved.scene().bounding_box());
    let tol = 1e-6 * solved.scene().diagonal() * m;
    assert!(
        (a.0 - m * b.0).abs().max_element() < tol,
        "{a:?} {b:?} × {m}"
    );
    assert!(
        (a.1 - m * b.1).abs().max_element() < tol,
        "{a:?} {b:?} × {m}"
    );
}

/// Four points away from the blocks' feet: floor, right wall, ceiling.
fn four_points() -> Vec<QueryPoint> {
    [
        DVec3::new(276.72, 0.0, 61.3),
        DVec3::new(520.02, 0.0, 501.11),
        DVec3::new(555.42, 448.64, 303.1),
        DVec3::new(279.28, 548.8, 62.04),
    ]
    .map(|position| QueryPoint {
        position,
        normal: None,
    })
    .to_vec()
}

/// u_n and û_n at `points` are `before`'s, bit for bit.
fn assert_unchanged(solved: &Radiosity, points: &[QueryPoint], before: &[PointValues]) {
    let after = solved.query(points).unwrap();
    for (p, q) in before.iter().zip(&after) {
        for (x, y) in p.channels.iter().zip(&q.channels) {
            assert_eq!((x.u, x.iterated), (y.u, y.iterated));
        }
    }
}

/// Refining a solve to a smaller target continues its loop: new steps on
/// a larger mesh, the estimate at the stop below the new target (away from
/// the points it names), and values that agree, within the two estimates,
/// with a solve made for that target from the start (another path through
/// the loop, to another mesh).
#[test]
fn refining_to_a_smaller_target_continues_the_loop() {
    let mut solved = solved();
    let steps = solved.refinement().expect("adaptive").steps.len();
    let unknowns = solved.outcome().discretization.len();
    let target = 1e-2;
    let refinement = solved.refine(target).expect("refines").clone();
    assert!(refinement.steps.len() > steps);
    let last = refinement.steps.last().unwrap();
    match refinement.stop {
        StopReason::Reached => assert!(last.estimate_shown <= target),
        StopReason::Singular => assert!(last.estimate_elsewhere <= target),
        other => panic!("stopped: {other}"),
    }
    assert!(solved.outcome().discretization.len() > unknowns);

    let settings = Settings {
        relative_to: RelativeTo::MaxU,
        ..Settings::target(target)
    };
    let direct = Radiosity::solve(cornell(), &settings).expect("solves");
    let points = four_points();
    let (a, b) = (
        solved.query(&points).unwrap(),
        direct.query(&points).unwrap(),
    );
    for (p, q) in a.iter().zip(&b) {
        for (x, y) in p.channels.iter().zip(&q.channels) {
            let (ex, ey) = (x.estimate.unwrap(), y.estimate.unwrap());
            assert!((x.u - y.u).abs() <= ex + ey, "u_n {} {}", x.u, y.u);
            let (ix, iy) = (x.iterated_estimate.unwrap(), y.iterated_estimate.unwrap());
            let d = (x.iterated - y.iterated).abs();
            assert!(d <= ix + iy, "û_n {} {}", x.iterated, y.iterated);
        }
    }
}

/// A target already met solves nothing: the same mesh, the same values,
/// the loop's stop "reached".
#[test]
fn refining_to_a_target_already_met_changes_nothing() {
    let mut solved = solved();
    let steps = solved.refinement().unwrap().steps.len();
    let points = four_points();
    let before = solved.query(&points).unwrap();
    let unknowns = solved.outcome().discretization.len();
    let refinement = solved.refine(0.5).expect("stands");
    assert_eq!(
        (refinement.steps.len(), refinement.stop),
        (steps, StopReason::Reached)
    );
    assert_eq!(solved.outcome().discretization.len(), unknowns);
    assert_unchanged(&solved, &points, &before);
}

/// After a relight, refining solves the current lights on the current
/// mesh first. With the light doubled and a target the mesh already
/// meets, that is one step on the same mesh whose values are twice the
/// first solve's (the system is linear in E), with an estimate again.
#[test]
fn refining_after_a_relight_solves_the_new_lights() {
    let mut solved = solved();
    let name = light_name(solved.scene());
    let light = solved.scene().materials.iter().find(|m| m.name == name);
    let e = light.unwrap().emission;
    let points = four_points();
    let first = solved.query(&points).unwrap();
    let unknowns = solved.outcome().discretization.len();
    let steps = solved.refinement().unwrap().steps.len();
    solved
        .relight(&[(&name, MaterialChange::Emission(e.map(|x| 2.0 * x)))])
        .unwrap();
    let refinement = solved.refine(0.1).expect("solves");
    assert_eq!(
        (refinement.steps.len(), refinement.stop),
        (steps + 1, StopReason::Reached)
    );
    assert_eq!(solved.outcome().discretization.len(), unknowns);
    let max_u = solved.outcome().channels.iter().map(|c| {
        c.solution
            .nodal()
            .iter()
            .fold(0.0f64, |a, &b| a.max(b.abs()))
    });
    let max_u = max_u.fold(0.0, f64::max);
    let doubled = solved.query(&points).unwrap();
    for (p, q) in first.iter().zip(&doubled) {
        for (x, y) in p.channels.iter().zip(&q.channels) {
            assert!((y.u - 2.0 * x.u).abs() <= 1e-8 * max_u, "{} {}", x.u, y.u);
            assert!((y.iterated - 2.0 * x.iterated).abs() <= 1e-8 * max_u);
            assert!(y.estimate.is_some());
        }
    }
}

/// A refine cancelled through the solve's progress handle returns
/// `Cancelled` and leaves the solved scene as it was.
#[test]
fn a_cancelled_refine_changes_nothing() {
    let cancel = Cancel::new();
    let settings = Settings::target(0.1).with_progress(cancel.handle());
    let mut solved = Radiosity::solve(cornell(), &settings).expect("solves");
    let points = four_points();
    let before = solved.query(&points).unwrap();
    let (unknowns, steps) = (
        solved.outcome().discretization.len(),
        solved.refinement().unwrap().steps.len(),
    );
    cancel.cancel();
    let err = solved.refine(1e-2).unwrap_err();
    assert!(
        matches!(err, Error::Solve(crate::error::Error::Cancelled { .. })),
        "{err}"
    );
    assert_eq!(solved.outcome().discretization.len(), unknowns);
    assert_eq!(solved.refinement().unwrap().steps.len(), steps);
    assert_unchanged(&solved, &points, &before);
}

/// The lightmap follows the current lights (linear in E: twice the light,
/// twice every texel; no light, none), and its files read back: the GLB by
/// the gltf crate with every input triangle, texture coordinates in the
/// unit square and the atlas as its image; the PNG and EXR by their magic
/// numbers.
#[test]
fn the_lightmap_follows_the_lights_and_its_files_read_back() {
    use crate::render::lightmap::Resolution;
    let mut solved = solved();
    let first = solved.bake_lightmap(Resolution::Size(64), true).unwrap();
    assert_eq!((first.image.width, first.image.height), (64, 64));
    let lit = first.image.rgb.iter().filter(|p| p[0] > 0.0).count();
    assert!(lit > 64 * 64 / 4, "{lit} lit texels");
    let name = light_name(solved.scene());
    let light = solved.scene().materials.iter().find(|m| m.name == name);
    let e = light.unwrap().emission;
    solved
        .relight(&[(&name, MaterialChange::Emission(e.map(|x| 2.0 * x)))])
        .unwrap();
    let doubled = solved.bake_lightmap(Resolution::Size(64), true).unwrap();
    let max = first
        .image
        .rgb
        .iter()
        .flatten()
        .fold(0.0f32, |a, &b| a.max(b));
    for (a, b) in first.image.rgb.iter().zip(&doubled.image.rgb) {
        for (x, y) in a.iter().zip(b) {
            assert!((y - 2.0 * x).abs() <= 1e-6 * max, "{x} {y}");
        }
    }
    solved
        .relight(&[(&name, MaterialChange::Emission([0.0; 3]))])
        .unwrap();
    let dark = solved.bake_lightmap(Resolution::Size(64), true).unwrap();
    assert!(dark.image.rgb.iter().flatten().all(|&x| x == 0.0));

    let tone = crate::render::ToneMap::default();
    let mut glb = Vec::new();
    solved
        .write_lightmap(&first, &mut glb, LightmapFormat::Glb, &tone)
        .unwrap();
    let (doc, buffers, images) = gltf::import_slice(&glb).expect("a valid GLB");
    assert_eq!(
        (images.len(), images[0].width, images[0].height),
        (1, 64, 64)
    );
    let mut triangles = 0;
    for mesh in doc.meshes() {
        for prim in mesh.primitives() {
            let reader = prim.reader(|b| Some(&buffers[b.index()]));
            triangles += reader.read_indices().unwrap().into_u32().count() / 3;
            let uvs = reader.read_tex_coords(0).expect("texture coordinates");
            assert!(uvs.into_f32().flatten().all(|t| (0.0..=1.0).contains(&t)));
        }
    }
    assert_eq!(triangles, solved.scene().triangle_count());
    let mut png = Vec::new();
    solved
        .write_lightmap(&first, &mut png, LightmapFormat::Png, &tone)
        .unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    let mut exr = Vec::new();
    solved
        .write_lightmap(&first, &mut exr, LightmapFormat::Exr, &tone)
        .unwrap();
    assert_eq!(&exr[..4], &[0x76, 0x2f, 0x31, 0x01]);
}

/// The nodes' CSV holds one row per unknown with u_n as computed (read
/// back bit for bit) and the estimate columns while the solve's estimate
/// stands; after a relight, the new values and no estimate.
#[test]
fn the_nodes_csv_reads_back() {
    let mut solved = solved();
    let read = |solved: &Radiosity| {
        let mut csv = Vec::new();
        let rows = solved.write_nodes_csv(&mut csv).unwrap();
        let text = String::from_utf8(csv).unwrap();
        let mut lines = text.lines();
        let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
        let body: Vec<Vec<f64>> = lines
            .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
            .collect();
        assert_eq!(body.len(), rows);
        (header, body)
    };
    let (header, body) = read(&solved);
    assert_eq!(body.len(), solved.outcome().discretization.len());
    assert_eq!(header.len(), 5 + 3 + 3, "{header:?}");
    assert!(header[5].starts_with("u_") && header[8].ends_with("_error_estimate"));
    for (c, ch) in solved.channels().iter().enumerate() {
        let estimate = &ch.estimate.as_ref().unwrap().elements;
        for (row, &u) in body.iter().zip(ch.solution.nodal()) {
            assert_eq!(row[5 + c], u);
            assert_eq!(row[8 + c], estimate[row[0] as usize]);
        }
    }
    let name = light_name(solved.scene());
    solved
        .relight(&[(&name, MaterialChange::Emission([0.0; 3]))])
        .unwrap();
    let (header, body) = read(&solved);
    assert_eq!(header.len(), 5 + 3);
    assert!(body.iter().all(|row| row[5..].iter().all(|&u| u == 0.0)));
}

/// A written PNG decodes (with the png crate) to the size asked, showing
/// the lit room; a written EXR starts with the format's magic number.
#[test]
fn the_written_image_reads_back() {
    let solved = solved();
    let options = RenderOptions {
        width: 48,
        height: 32,
        ..RenderOptions::default()
    };
    let tone = crate::render::ToneMap::default();
    let mut png = Vec::new();
    solved
        .write_image(&mut png, None, &options, ImageFormat::Png, &tone)
        .unwrap();
    let mut reader = png::Decoder::new(std::io::Cursor::new(png)).read_info().unwrap();
    let mut pixels = vec![0; reader.output_buffer_size().unwrap()];
    let frame = reader.next_frame(&mut pixels).unwrap();
    assert_eq!((frame.width, frame.height), (48, 32));
    let lit = pixels.iter().filter(|&&b| b > 16).count();
    assert!(lit > pixels.len() / 4, "{lit} of {} bytes lit", pixels.len());
    let mut exr = Vec::new();
    solved
        .write_image(&mut exr, None, &options, ImageFormat::Exr, &tone)
        .unwrap();
    assert_eq!(&exr[..4], &[0x76, 0x2f, 0x31, 0x01]);
}

/// A solve without a target refines too: the loop starts on its mesh (one
/// degree everywhere, no history) and stops below the target away from
/// the points it names, on a larger mesh.
#[test]
fn a_solve_without_a_target_refines_from_its_mesh() {
    let mut solved = refined();
    assert!(solved.refinement().is_none());
    let unknowns = solved.outcome().discretization.len();
    let first = solved.outcome().channels.iter();
    // Relative to the reflected light, the default.
    let estimate = first.map(|c| {
        let e = c.estimate.as_ref().unwrap();
        e.shown_max_rel() * e.rescale(RelativeTo::Reflected)
    });
    let target = 0.5 * estimate.fold(0.0, f64::max);
    let refinement = solved.refine(target).expect("refines").clone();
    let last = refinement.steps.last().expect("a step");
    match refinement.stop {
        StopReason::Reached => assert!(last.estimate_shown <= target),
        StopReason::Singular => assert!(last.estimate_elsewhere <= target),
        other => panic!("stopped: {other}"),
    }
    assert!(solved.outcome().discretization.len() > unknowns);
    assert_eq!(last.unknowns, solved.outcome().discretization.len());
}

/// A solve without a target whose settings ask for targets relative to
/// the reflected light refines relative to it: the last step's estimate is
/// the worst channel's max over its reflected light, not over max |u|.
#[test]
fn a_refine_follows_the_settings_relative_to() {
    let settings = Settings {
        relative_to: RelativeTo::Reflected,
        ..Settings::default()
    };
    let shadow = builtin("shadow").expect("built in").expect("loads");
    let mut solved = Radiosity::solve(shadow, &settings).expect("solves");
    let estimate = |s: &Radiosity| {
        let channels = s.outcome().channels.iter();
        channels.fold((0.0f64, 0.0f64), |(r, m), c| {
            let e = c.estimate.as_ref().unwrap();
            (r.max(e.max / e.reflected_scale), m.max(e.max_rel))
        })
    };
    let (reflected, max_u) = estimate(&solved);
    assert!(reflected > 2.0 * max_u, "{reflected} against {max_u}");
    let refinement = solved.refine(0.9 * reflected).expect("refines").clone();
    let last = refinement.steps.last().expect("a step");
    let (reflected, _) = estimate(&solved);
    assert!((last.estimate - reflected).abs() <= 1e-12 * reflected, "{} against {reflected}", last.estimate);
}
