//! Files the CLI writes: the nodal CSV, images and vertex meshes, and the
//! overwrite rule shared by every file.

use crate::files::create;
use crate::lightmap;
use crate::objects::layout;
use crate::progress::Bar;
use crate::report::Written;
use crate::setup::Look;
use crate::validate::{Output, OutputFile, OutputKind};
use anyhow::{Context, Result};
use radcol_core::export;
use radcol_core::render::{self, Image, VertexMesh};
use radcol_core::run::{Mesh, RelativeTo, Solution, SolveOutcome};
use std::time::Instant;

/// Writes every `--out` file, rendering the image and tessellating the
/// vertex mesh once each however many files use them.
pub fn write_all(
    outputs: &[Output],
    look: &Look,
    out: &SolveOutcome,
    bar: Option<&Bar>,
) -> Result<Vec<Written>> {
    let mesh = out.discretization.mesh();
    let solutions: Vec<&Solution> = out.channels.iter().map(|c| c.shown()).collect();
    let names: Vec<&str> = out.channels.iter().map(|c| c.name.as_str()).collect();
    let mut image: Option<Image> = None;
    let mut vertices: Option<VertexMesh> = None;
    let mut baked: Option<lightmap::Baked> = None;
    let mut written = Vec::new();
    for o in outputs {
        let t = Instant::now();
        let path = o.file.path.display().to_string();
        if let Some(b) = bar {
            b.spin(format!("writing {path}"));
        }
        if o.kind == OutputKind::ErrorMap {
            written.push(write_error_map(o, look, out, t)?);
            continue;
        }
        if let Some(what) = lightmap::output(o, look, mesh, &solutions, &mut baked, bar)? {
            written.push(Written {
                path,
                what,
                value: value_of(o.kind, out),
                seconds: t.elapsed().as_secs_f64(),
            });
            continue;
        }
        if o.kind.is_image() && image.is_none() {
            if let Some(b) = bar {
                b.spin(format!(
                    "rendering {}×{} ({} rays per pixel)",
                    look.render.width, look.render.height, look.render.samples_per_pixel
                ));
            }
            let camera = look.camera.unwrap_or_else(|| render::auto_camera(mesh));
            let emits = out.emitting_elements();
            image = Some(render::render_scene(
                mesh,
                &solutions,
                &emits,
                &camera,
                &look.render,
            )?);
        }
        if matches!(o.kind, OutputKind::Ply | OutputKind::Glb | OutputKind::Gltf)
            && vertices.is_none()
        {
            vertices = Some(vertex_mesh(mesh, &solutions, look)?);
        }
        let what = match o.kind {
            OutputKind::Csv => format!("{} node rows", write_csv(&o.file, out)?),
            OutputKind::Png => {
                let img = image.as_ref().expect("rendered above");
                let pixels = render::tone_map(img, &look.tone);
                let mut f = create(&o.file)?;
                export::png::write(&mut f, img.width, img.height, &pixels)
                    .with_context(|| format!("writing {path}"))?;
                f.commit()?;
                format!("{}×{} image", img.width, img.height)
            }
            OutputKind::Exr => {
                let img = image.as_ref().expect("rendered above");
                let mut f = create(&o.file)?;
                export::exr::write(&mut f, img).with_context(|| format!("writing {path}"))?;
                f.commit()?;
                format!("{}×{} linear radiance image", img.width, img.height)
            }
            OutputKind::ErrorMap | OutputKind::LightmapExr | OutputKind::LightmapPng => {
                unreachable!("written above")
            }
            OutputKind::Ply | OutputKind::Glb | OutputKind::Gltf => {
                let vm = vertices.as_ref().expect("tessellated above");
                write_vertices(o, vm, (look, out, &names))?
            }
        };
        written.push(Written {
            path,
            what,
            value: value_of(o.kind, out),
            seconds: t.elapsed().as_secs_f64(),
        });
    }
    Ok(written)
}

/// Writes the `.ply`/`.glb`/`.gltf` output `o` of the vertex mesh `vm`;
/// returns what it holds.
fn write_vertices(
    o: &Output,
    vm: &VertexMesh,
    (look, out, names): (&Look, &SolveOutcome, &[&str]),
) -> Result<String> {
    let mesh = out.discretization.mesh();
    let mut f = create(&o.file)?;
    match o.kind {
        OutputKind::Ply => {
            // Per vertex of an element: its element's estimate (a scene
            // triangle spans many elements: none).
            let errors = element_estimates(out)
                .filter(|_| look.input_vertices.is_none())
                .map(|e| vertex_values(vm, &e));
            export::ply::write(&mut f, vm, names, &look.tone, errors.as_deref())
        }
        OutputKind::Glb => export::gltf::write_glb(&mut f, vm, &look.tone, &layout(mesh, look)),
        _ => export::gltf::write_gltf(&mut f, vm, &look.tone, &layout(mesh, look)),
    }
    .with_context(|| format!("writing {}", o.file.path.display()))?;
    f.commit()?;
    Ok(format!(
        "{} vertices, {} triangles",
        vm.vertex_count(),
        vm.triangle_count()
    ))
}

/// The vertex mesh of .ply/.glb/.gltf: on the elements, or on the scene's
/// triangles (--vertices).
fn vertex_mesh(mesh: &Mesh, solutions: &[&Solution], look: &Look) -> Result<VertexMesh> {
    Ok(match look.input_vertices {
        Some(corners) => render::input_vertex_mesh(mesh, solutions, corners)?,
        None => render::vertex_mesh(mesh, solutions, look.tessellation)?,
    })
}

/// The `--error-map` PNG: every element's estimate relative to max |u_n|
/// (worst channel), seen by the image camera.
fn write_error_map(o: &Output, look: &Look, out: &SolveOutcome, t: Instant) -> Result<Written> {
    let path = o.file.path.display().to_string();
    let mesh = out.discretization.mesh();
    let errors = element_estimates(out)
        .with_context(|| format!("--error-map {path}: the solve has no error estimate"))?;
    let camera = look.camera.unwrap_or_else(|| render::auto_camera(mesh));
    let img = render::render_element_values(mesh, &errors, &camera, &look.render)?;
    let mut f = create(&o.file)?;
    export::png::write(
        &mut f,
        img.width,
        img.height,
        &crate::error_map::pixels(&img),
    )
    .with_context(|| format!("writing {path}"))?;
    f.commit()?;
    let (lo, hi) = crate::error_map::DECADES;
    Ok(Written {
        path,
        what: format!(
            "{}×{} error map (estimated max error per element relative to the reflected light, log scale 1e{lo} .. 1e{hi})",
            img.width, img.height
        ),
        value: value_of(o.kind, out),
        seconds: t.elapsed().as_secs_f64(),
    })
}

/// Which value of the solution an output of kind `kind` carries, in the
/// report's words. The CSV holds u_n at the nodes as computed; images,
/// vertex meshes and lightmaps show u_n sampled wherever they need it,
/// limited where it dips below zero (unless --keep-negative). Not û_n =
/// E + K u_n, the better value at a point: it costs a row of K per point
/// (about 2 ms on the default Cornell box, 2 cores), hours for the
/// hundreds of thousands of samples of an image or a lightmap; `--at`
/// gives it, with its estimate, at the points asked for.
pub fn value_of(kind: OutputKind, out: &SolveOutcome) -> String {
    let limited = out.channels.iter().any(|c| c.limited.is_some());
    match kind {
        OutputKind::Csv => "u_n at the nodes, as computed".into(),
        OutputKind::ErrorMap => "the estimated error of u_n per element".into(),
        _ if limited => "u_n, scaled towards element means where it dipped below 0".into(),
        _ => "u_n".into(),
    }
}

/// A per-element value at every vertex of `vm` (through its triangles).
fn vertex_values(vm: &radcol_core::render::VertexMesh, per_element: &[f64]) -> Vec<f32> {
    let mut v = vec![0.0f32; vm.vertex_count()];
    for (tri, &k) in vm.indices.chunks_exact(3).zip(&vm.element) {
        for &i in tri {
            v[i as usize] = per_element[k as usize] as f32;
        }
    }
    v
}

/// Per element, the worst channel's estimated max error relative to its
/// reflected light (max |u_n| where nothing is reflected), as the report's
/// figures; None without an estimate.
pub fn element_estimates(out: &SolveOutcome) -> Option<Vec<f64>> {
    let mut worst = vec![0.0f64; out.discretization.mesh().len()];
    for ch in &out.channels {
        let estimate = ch.estimate.as_ref()?;
        let to_reflected = estimate.rescale(RelativeTo::Reflected);
        for (w, e) in worst.iter_mut().zip(estimate.elements_rel()) {
            *w = w.max(e * to_reflected);
        }
    }
    Some(worst)
}

/// Writes one row per collocation node ([`export::csv::write_nodes`]).
/// Returns the number of rows.
pub fn write_csv(file: &OutputFile, out: &SolveOutcome) -> Result<usize> {
    let mut w = create(file)?;
    let rows = export::csv::write_nodes(&mut w, &out.discretization, &out.channels)
        .with_context(|| format!("writing {}", file.path.display()))?;
    w.commit()?;
    Ok(rows)
}
