//! The Cornell box solved, queried, relit, written and cancelled, through the
//! prelude only: `cargo run --release -p radcol-core --example front_door`.

use radcol_core::prelude::*;
use std::{fs::File, io::BufWriter, thread, time::Duration};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let cornell = || Scene::builtin("cornell");
    let mut solved = Radiosity::solve(cornell()?, &Settings::target(1e-2))?;
    let unknowns = solved.outcome().discretization.len();
    println!(
        "{unknowns} unknowns, {:?}",
        solved.refinement().map(|r| r.stop)
    );

    // Floor, ceiling, back wall, red wall, tall block's top (û_n: the better value).
    let at = [
        [276.7, 0.0, 61.3],
        [279.3, 548.8, 62.0],
        [278.0, 274.0, 559.2],
        [555.4, 448.6, 303.1],
        [300.0, 330.0, 350.0],
    ]
    .map(|p| QueryPoint::at(DVec3::from_array(p)));
    let show = |solved: &Radiosity, what: &str| -> Result<(), Error> {
        let values = solved.query(&at)?;
        let red: Vec<String> = values
            .iter()
            .map(|p| format!("{:.3}", p.channels[0].iterated))
            .collect();
        println!("{what:>10}: red û_n {}", red.join(" "));
        Ok(())
    };
    show(&solved, "as solved")?;
    solved.relight(&[("light", MaterialChange::Emission([20.0, 5.0, 5.0]))])?;
    show(&solved, "warm light")?;
    solved.relight(&[("red", MaterialChange::Reflectance([0.1, 0.1, 0.6]))])?;
    show(&solved, "blue wall")?;

    let path = std::env::temp_dir().join("cornell-radiosity.gltf");
    let file = BufWriter::new(File::create(&path)?);
    solved.write_mesh(file, MeshFormat::Gltf, &ToneMap::default())?;
    println!("wrote {}", path.display());

    // A finer solve, stopped from another thread after 50 ms.
    let cancel = Cancel::new();
    let (scene, finer) = (
        cornell()?,
        Settings::target(1e-4).with_progress(cancel.handle()),
    );
    let second = thread::scope(|s| {
        s.spawn(|| {
            thread::sleep(Duration::from_millis(50));
            cancel.cancel();
        });
        Radiosity::solve(scene, &finer)
    });
    println!("second solve: {:?}", second.err().map(|e| e.to_string()));
    Ok(())
}
