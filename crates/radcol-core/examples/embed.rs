//! Embedding radcol: a scene from vertex and index buffers, solved in three
//! colour channels, printed per collocation node, then handed back as
//! per-vertex colours (for your own renderer) and as a rendered image.
//!
//! Run with `cargo run --release -p radcol-core --example embed`.

use glam::Vec3;
use radcol_core::backend::CpuBackend;
use radcol_core::render::{render, tone_map, vertex_mesh, RenderOptions, ToneMap};
use radcol_core::run::{solve, SolveConfig, SolverKind};
use radcol_core::scene::{Material, SceneBuilder};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // Two facing unit squares one unit apart; the top one is a warm lamp.
    let mut builder = SceneBuilder::new("two quads");
    let wall = builder.add_material(Material::diffuse("wall", [0.7, 0.6, 0.5]))?;
    let lamp = builder.add_material(Material::emitter("lamp", [0.2; 3], [1.0, 0.8, 0.5]))?;
    let square = |z: f32| {
        [
            Vec3::new(0.0, 0.0, z),
            Vec3::new(1.0, 0.0, z),
            Vec3::new(1.0, 1.0, z),
            Vec3::new(0.0, 1.0, z),
        ]
    };
    // Counter-clockwise seen from the side that receives and emits light.
    builder.add_mesh("floor", &square(0.0), &[[0, 1, 2], [0, 2, 3]], wall)?;
    builder.add_mesh("lamp", &square(1.0), &[[0, 2, 1], [0, 3, 2]], lamp)?;
    let scene = builder.build()?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }

    let config = SolveConfig {
        degree: 1,
        level: 1,
        solver: SolverKind::Lu,
        ..Default::default()
    };
    let outcome = solve(&scene.problem(), &config, &CpuBackend)?;
    let disc = &outcome.discretization;
    let [r, g, b] = [0, 1, 2].map(|c| outcome.channels[c].solution.nodal());
    println!(
        "{} elements, {} nodes; patch, x, y, z, R, G, B",
        disc.mesh().len(),
        disc.len()
    );
    for (i, p) in disc.points().iter().enumerate() {
        let patch = &scene.surface.patches[disc.mesh().elements()[p.element].patch as usize];
        println!(
            "{:>12} {:.4} {:.4} {:.4}  {:.6} {:.6} {:.6}",
            patch.name, p.position.x, p.position.y, p.position.z, r[i], g[i], b[i]
        );
    }

    // Per-vertex colours: every element tessellated 2 × 2, u evaluated at the
    // vertices, tone-mapped to sRGB bytes.
    let solutions: Vec<_> = outcome.channels.iter().map(|c| &c.solution).collect();
    let tone = ToneMap::default();
    let vertices = vertex_mesh(disc.mesh(), &solutions, 2)?;
    let colours = vertices.srgb8_colors(&tone);
    println!(
        "vertex mesh: {} vertices, {} triangles; first colour {:?}",
        vertices.vertex_count(),
        vertices.triangle_count(),
        colours[0]
    );

    // An image (linear radiance u/π, then 8 bits) from the scene's camera, or
    // one chosen to show the lit sides of the mesh.
    let camera = scene.camera_or_auto();
    let options = RenderOptions {
        width: 160,
        height: 120,
        ..Default::default()
    };
    let image = render(disc.mesh(), &solutions, &camera, &options)?;
    let pixels = tone_map(&image, &tone);
    let lit = pixels.iter().filter(|p| p.iter().any(|&c| c > 0)).count();
    println!(
        "image: {}×{}, {lit} pixels show the scene",
        image.width, image.height
    );
    Ok(())
}
