//! Baking a scene's diffuse light through the library's facade
//! (`radcol_core::prelude`): load a scene, refine adaptively to a target
//! error while a progress observer reports the stages, then read the light
//! back at points (û_n, the iterated solution, with the element's estimate),
//! as an image and as a UV lightmap.
//!
//!     cargo run --release -p radcol-core --example bake -- [SCENE] [TARGET] [OUT.ppm] [LIGHTMAP.ppm]
//!
//! SCENE is a `.obj`, `.gltf` or `.glb` file or a built-in name (default
//! `cornell`), TARGET the estimated max error relative to the reflected light (default
//! 1e-2), OUT a binary PPM image of the scene's camera view, LIGHTMAP the
//! scene's 1024² lightmap atlas, tone-mapped (default: neither).

use radcol_core::prelude::*;
use std::io::Write;
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

/// Prints each stage as it starts and its units when it ends.
#[derive(Default)]
struct Stages {
    current: Mutex<Option<(String, u64)>>,
    done: AtomicU64,
}

impl Stages {
    fn finish(&self) {
        if let Some((stage, total)) = self.current.lock().unwrap().take() {
            eprintln!("    {stage}: {}/{total}", self.done.load(Ordering::Relaxed));
        }
    }
}

impl Progress for Stages {
    fn start(&self, stage: &str, total: u64) {
        self.finish();
        *self.current.lock().unwrap() = Some((stage.to_string(), total));
        self.done.store(0, Ordering::Relaxed);
    }
    fn advance(&self, n: u64) {
        self.done.fetch_add(n, Ordering::Relaxed);
    }
}

fn main() -> Result<(), Error> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let name = args.first().map_or("cornell", String::as_str);
    let target: f64 = args.get(1).and_then(|t| t.parse().ok()).unwrap_or(1e-2);
    let scene = match builtin(name) {
        Some(scene) => scene?,
        None => load_scene(Path::new(name))?,
    };
    let problem = scene.problem();
    let stages = Arc::new(Stages::default());
    let config = SolveConfig {
        degree: 1,
        level: 0,
        progress: Some(ProgressHandle(stages.clone())),
        ..Default::default()
    };
    let opts = AdaptOptions {
        target,
        ..Default::default()
    };
    let baked = solve_adaptive(&problem, &config, &opts, &CpuBackend, |step| {
        stages.finish();
        eprintln!(
            "  step: {} elements, {} unknowns, estimate {:.2e}, {:.1} s",
            step.elements, step.unknowns, step.estimate, step.seconds
        );
    })?;
    let outcome = &baked.outcome;
    println!(
        "{}: {:?} with {} unknowns",
        scene.name,
        baked.stop,
        outcome.discretization.len()
    );
    // The light at the centre of every object's first triangle, facing out.
    let points: Vec<(String, QueryPoint)> = scene
        .surface
        .patches
        .iter()
        .map(|p| {
            let t = p.triangles[0].map(|x| p.map.map(x));
            let normal = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
            let position = (t[0] + t[1] + t[2]) / 3.0;
            let point = QueryPoint {
                position,
                normal: Some(normal),
            };
            (p.name.clone(), point)
        })
        .collect();
    let at: Vec<QueryPoint> = points.iter().map(|(_, q)| *q).collect();
    let values = query(&problem, outcome, config.quad.clone(), &at, DEFAULT_SNAP)?;
    for ((name, _), v) in points.iter().zip(&values) {
        let radiance: Vec<String> = v
            .channels
            .iter()
            .map(|c| {
                let est = c.estimate.unwrap_or(f64::NAN);
                format!(
                    "{:.4e} ± {:.1e}",
                    c.iterated / std::f64::consts::PI,
                    est / std::f64::consts::PI
                )
            })
            .collect();
        println!("  {name:<28} radiance {}", radiance.join(", "));
    }
    if let Some(out) = args.get(3) {
        let shown: Vec<&Solution> = outcome.channels.iter().map(|c| c.shown()).collect();
        // The scene's own texture coordinates (OBJ vt, glTF TEXCOORD_1 or
        // _0) when it has them, else radcol's planar charts.
        let atlas = match &scene.uvs {
            Some(uvs) => Atlas::from_uvs(&scene.surface, uvs, 1024)?,
            None => Atlas::new(&scene.surface, 1024)?,
        };
        let lightmap = bake_lightmap(outcome.discretization.mesh(), &shown, &atlas)?;
        write_ppm(out, &lightmap);
        if atlas.is_input() {
            println!("wrote {out}: in the scene's texture coordinates");
        } else {
            let charts = atlas.generated_charts.unwrap_or_default();
            println!("wrote {out}: {charts} charts");
        }
    }
    if let Some(out) = args.get(2) {
        let shown: Vec<&Solution> = outcome.channels.iter().map(|c| c.shown()).collect();
        let options = RenderOptions {
            width: 320,
            height: 240,
            ..Default::default()
        };
        let camera = scene.camera_or_auto();
        let image = render(outcome.discretization.mesh(), &shown, &camera, &options)?;
        write_ppm(out, &image);
        println!("wrote {out}");
    }
    Ok(())
}

/// A binary PPM of `image`, tone-mapped.
fn write_ppm(path: &str, image: &Image) {
    let pixels = tone_map(image, &ToneMap::default());
    let mut f = std::io::BufWriter::new(std::fs::File::create(path).expect("writable"));
    write!(f, "P6\n{} {}\n255\n", image.width, image.height).expect("written");
    f.write_all(pixels.as_flattened()).expect("written");
}
