//! Embedding radcol: a scene from vertex and index buffers, solved in three
//! colour channels, printed per collocation node.
//!
//! Run with `cargo run --release -p radcol-core --example embed`.

use glam::Vec3;
use radcol_core::assembly::CpuBackend;
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
    Ok(())
}
