//! Writes a large scene: a closed hall with the Cornell box's materials (red
//! and green side walls, white elsewhere), square ceiling lights over every
//! other cell, and a grid of Stanford bunnies (the whole 3 674-triangle
//! bunny of `scenes/bunny_room.obj`, each turned by another angle) standing
//! on the floor. Twenty-eight bunnies make 10^5 triangles.
//!
//!     cargo run --release -p radcol-benches --example bunny_hall -- OUT.obj [BUNNIES]
//!
//! BUNNIES (default 28) are set in rows of ⌈√BUNNIES⌉ on a 300 mm pitch;
//! the hall is 550 mm high with a 50 mm margin around the grid. OUT.mtl is
//! written beside OUT.obj. Then, for what it will cost before solving:
//!
//!     radcol info OUT.obj --level 0 --plan
//!
//! The layout is deterministic: the same BUNNIES give the same file.

use glam::DVec3;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Grid pitch, room height and margin (mm).
const PITCH: f64 = 300.0;
const HEIGHT: f64 = 550.0;
const MARGIN: f64 = 50.0;
/// Side of a ceiling light (mm), centred in its cell.
const LIGHT: f64 = 130.0;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let out = PathBuf::from(args.next().ok_or("usage: bunny_hall OUT.obj [BUNNIES]")?);
    let count: usize = args.next().map(|a| a.parse()).transpose()?.unwrap_or(28);
    if count == 0 {
        return Err("BUNNIES must be at least 1".into());
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let (bunny_v, bunny_f) = read_bunny(&root.join("scenes/bunny_room.obj"))?;
    let cols = (count as f64).sqrt().ceil() as usize;
    let rows = count.div_ceil(cols);
    let (width, depth) = (
        cols as f64 * PITCH + 2.0 * MARGIN,
        rows as f64 * PITCH + 2.0 * MARGIN,
    );
    let mut obj = Obj::default();
    let mtl = out.with_extension("mtl");
    let mtl_name = mtl
        .file_name()
        .ok_or("OUT has no file name")?
        .to_string_lossy();
    writeln!(
        obj.text,
        "# A {width} x {depth} x {HEIGHT} mm hall with {count} Stanford bunnies (npm package `bunny`,\n\
         # the Stanford 3D Scanning Repository's scan), made by benches/examples/bunny_hall.rs.\n\
         mtllib {mtl_name}"
    )?;
    room(&mut obj, width, depth, cols, rows);
    // The bunny's centre on the floor, from its own vertices.
    let (lo, hi) = bunny_v.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), v| (lo.min(*v), hi.max(*v)),
    );
    let centre = DVec3::new(0.5 * (lo.x + hi.x), lo.y, 0.5 * (lo.z + hi.z));
    for b in 0..count {
        let (i, j) = (b % cols, b / cols);
        let at = DVec3::new(
            MARGIN + (i as f64 + 0.5) * PITCH,
            0.0,
            MARGIN + (j as f64 + 0.5) * PITCH,
        );
        // The golden angle between neighbours: no two alike.
        let (s, c) = (b as f64 * 2.399_963_229_728_653).sin_cos();
        let placed: Vec<DVec3> = bunny_v
            .iter()
            .map(|v| {
                let d = *v - centre;
                at + DVec3::new(c * d.x + s * d.z, d.y, -s * d.x + c * d.z)
            })
            .collect();
        obj.group(&format!("bunny{b}"), "white");
        let first = obj.vertices(&placed);
        for f in &bunny_f {
            obj.face(f.map(|k| first + k));
        }
    }
    std::fs::write(&out, &obj.text)?;
    // The bunny room's materials: the Cornell box's.
    let materials = root.join("scenes/bunny_room.mtl");
    std::fs::copy(&materials, &mtl).map_err(|e| format!("{}: {e}", materials.display()))?;
    println!(
        "{}: {} triangles ({count} bunnies of {}), {width} x {depth} x {HEIGHT} mm",
        out.display(),
        obj.faces,
        bunny_f.len()
    );
    Ok(())
}

/// An OBJ file being written.
#[derive(Default)]
struct Obj {
    text: String,
    vertices: usize,
    faces: usize,
}

impl Obj {
    /// Appends vertices; returns the (1-based) index of the first.
    fn vertices(&mut self, vs: &[DVec3]) -> usize {
        for v in vs {
            let _ = writeln!(self.text, "v {} {} {}", v.x, v.y, v.z);
        }
        self.vertices += vs.len();
        self.vertices - vs.len() + 1
    }

    fn face(&mut self, f: [usize; 3]) {
        let _ = writeln!(self.text, "f {} {} {}", f[0], f[1], f[2]);
        self.faces += 1;
    }

    fn group(&mut self, name: &str, material: &str) {
        let _ = writeln!(self.text, "g {name}\nusemtl {material}");
    }

    /// A planar quad, corners counter-clockwise seen from its front.
    fn quad(&mut self, corners: [DVec3; 4]) {
        let k = self.vertices(&corners);
        self.face([k, k + 1, k + 2]);
        self.face([k, k + 2, k + 3]);
    }
}

/// The hall's floor, walls and ceiling (normals inwards), the ceiling cut
/// into one cell per bunny with a light in every other cell.
fn room(obj: &mut Obj, w: f64, d: f64, cols: usize, rows: usize) {
    let h = HEIGHT;
    let p = DVec3::new;
    obj.group("floor", "white");
    obj.quad([p(0., 0., 0.), p(0., 0., d), p(w, 0., d), p(w, 0., 0.)]);
    obj.group("back_wall", "white");
    obj.quad([p(0., 0., d), p(0., h, d), p(w, h, d), p(w, 0., d)]);
    obj.group("front_wall", "white");
    obj.quad([p(0., 0., 0.), p(w, 0., 0.), p(w, h, 0.), p(0., h, 0.)]);
    obj.group("right_wall", "green");
    obj.quad([p(0., 0., 0.), p(0., h, 0.), p(0., h, d), p(0., 0., d)]);
    obj.group("left_wall", "red");
    obj.quad([p(w, 0., 0.), p(w, 0., d), p(w, h, d), p(w, h, 0.)]);
    // Cell edges: the margins belong to the outer cells.
    let edges = |n: usize, len: f64| -> Vec<f64> {
        (0..=n)
            .map(|i| match i {
                0 => 0.0,
                i if i == n => len,
                i => MARGIN + i as f64 * PITCH,
            })
            .collect()
    };
    let (xs, zs) = (edges(cols, w), edges(rows, d));
    // Facing down: counter-clockwise seen from below.
    let down = |x0: f64, x1: f64, z0: f64, z1: f64| {
        [p(x0, h, z0), p(x1, h, z0), p(x1, h, z1), p(x0, h, z1)]
    };
    for j in 0..rows {
        for i in 0..cols {
            let (x0, x1, z0, z1) = (xs[i], xs[i + 1], zs[j], zs[j + 1]);
            if (i + j) % 2 == 1 {
                obj.group("ceiling", "white");
                obj.quad(down(x0, x1, z0, z1));
                continue;
            }
            // A light centred on the cell's bunny, the rest of the cell as
            // four quads around it.
            let (cx, cz) = (
                MARGIN + (i as f64 + 0.5) * PITCH,
                MARGIN + (j as f64 + 0.5) * PITCH,
            );
            let (l0, l1, m0, m1) = (
                cx - 0.5 * LIGHT,
                cx + 0.5 * LIGHT,
                cz - 0.5 * LIGHT,
                cz + 0.5 * LIGHT,
            );
            obj.group("ceiling", "white");
            obj.quad(down(x0, x1, z0, m0));
            obj.quad(down(x0, x1, m1, z1));
            obj.quad(down(x0, l0, m0, m1));
            obj.quad(down(l1, x1, m0, m1));
            obj.group("light", "light");
            obj.quad(down(l0, l1, m0, m1));
        }
    }
}

/// Vertices and (0-based) triangles.
type Mesh = (Vec<DVec3>, Vec<[usize; 3]>);

/// The bunny of the bunny room.
fn read_bunny(path: &Path) -> Result<Mesh, Box<dyn std::error::Error>> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let (mut vs, mut fs, mut in_bunny) = (Vec::new(), Vec::new(), false);
    for (n, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                let x: Vec<f64> = words.map(str::parse).collect::<Result<_, _>>()?;
                vs.push(DVec3::new(x[0], x[1], x[2]));
            }
            Some("g") => in_bunny = words.next() == Some("bunny"),
            Some("f") if in_bunny => {
                let f: Vec<usize> = words.map(str::parse).collect::<Result<_, _>>()?;
                if f.len() != 3 {
                    return Err(format!("{}:{}: not a triangle", path.display(), n + 1).into());
                }
                fs.push([f[0] - 1, f[1] - 1, f[2] - 1]);
            }
            _ => {}
        }
    }
    // Keep the bunny's own vertices, renumbered from 0.
    let first = fs.iter().flatten().min().copied().ok_or("no bunny group")?;
    let last = fs.iter().flatten().max().copied().unwrap_or(first);
    let faces = fs.iter().map(|f| f.map(|k| k - first)).collect();
    Ok((vs[first..=last].to_vec(), faces))
}
