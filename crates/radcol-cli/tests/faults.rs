//! Bad and extreme inputs, each with the exact outcome it must have (issue
//! 12): a one-line error naming the flag, file, line or value; a success with
//! a named warning; or the right answer, computed here by hand. Every case runs
//! under a time limit, so a hang fails the test instead of stalling CI.
//!
//! Run alone with `cargo test --release -p radcol-cli --test faults`.

mod common;

use common::{radcol_bin, scratch};
use serde_json::Value;
use std::f64::consts::PI;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// What a case must give.
#[derive(Clone, Copy, Debug)]
enum Want {
    /// Exit code 2 (bad input) or 1 (the solve failed), exactly one
    /// `error: ` line on stderr, containing every needle (case-insensitive).
    Refused(i32, &'static [&'static str]),
    /// Success, with every needle in one `warning` line (of the report on
    /// stdout, or of the scene reader on stderr).
    Warned(&'static [&'static str]),
    /// Success, with stdout containing every needle.
    Says(&'static [&'static str]),
    /// Success with `--json`: the number at the JSON pointer within the
    /// relative tolerance of the value.
    Answer(&'static str, f64, f64),
    /// Success with `--json`: the value at the pointer is `true`.
    True(&'static str),
    /// Success with `--json`: the number at the pointer is at most the bound.
    Below(&'static str, f64),
}

use Want::*;

/// One case: arguments (`{dir}` is its scratch directory) and files to
/// write there first.
struct Case {
    name: &'static str,
    args: Vec<String>,
    files: Vec<(&'static str, Vec<u8>)>,
    want: Want,
}

/// Each case's limit; the slowest takes about a second.
const LIMIT: Duration = Duration::from_secs(120);

const WHITE: &str = "newmtl white\nKd 0.5 0.5 0.5\nKe 1 1 1\n";

/// An OBJ with the white material (Kd 0.5, Ke 1) and `body` after `usemtl`.
fn obj(body: &str) -> Vec<(&'static str, Vec<u8>)> {
    vec![
        ("w.mtl", WHITE.as_bytes().to_vec()),
        (
            "s.obj",
            format!("mtllib w.mtl\nusemtl white\n{body}").into_bytes(),
        ),
    ]
}

/// The L of 3 unit squares, (0,0) (2,0) (2,1) (1,1) (1,2) (0,2), as vertices
/// 1..6, and a face listing them from `start`.
fn l_face(start: usize) -> String {
    let corners = "v 0 0 0\nv 2 0 0\nv 2 1 0\nv 1 1 0\nv 1 2 0\nv 0 2 0\n";
    let order: Vec<String> = (0..6).map(|i| ((i + start) % 6 + 1).to_string()).collect();
    format!("{corners}f {}\n", order.join(" "))
}

fn case(name: &'static str, args: &[&str], want: Want) -> Case {
    Case {
        name,
        args: args.iter().map(|s| s.to_string()).collect(),
        files: Vec::new(),
        want,
    }
}

fn with_files(mut c: Case, files: Vec<(&'static str, Vec<u8>)>) -> Case {
    c.files = files;
    c
}

/// ∫ over the unit sphere of exp(−z²) = 2π √π erf(1).
const SPHERE_EXP_MINUS_Z2: f64 = 2.0 * PI * 1.772_453_850_905_516 * 0.842_700_792_949_714_9;

fn expression_cases() -> Vec<Case> {
    // With ρ = 0, u = E; the room's area is 6.
    let s = |e: &'static str| {
        [
            "solve",
            "box:1,1,1",
            "--level",
            "0",
            "--rho",
            "0",
            "--emission",
            e,
        ]
    };
    let deep = format!("{}x{}", "(".repeat(30_000), ")".repeat(30_000));
    vec![
        case(
            "exp(-z^2) is exp(-(z^2))",
            &["solve", "sphere", "--level", "2", "--emission", "exp(-z^2)"],
            Answer("/channels/0/integral_e", SPHERE_EXP_MINUS_Z2, 1e-4),
        ),
        case(
            "2^3^2 = 2^9",
            &s("2^3^2"),
            Answer("/channels/0/integral_u", 512.0 * 6.0, 1e-14),
        ),
        case(
            "8/4/2 = 1",
            &s("8/4/2"),
            Answer("/channels/0/integral_u", 6.0, 1e-14),
        ),
        case(
            "2/3 is not 0",
            &s("2/3"),
            Answer("/channels/0/integral_u", 4.0, 1e-14),
        ),
        case(
            "-2^2 = -4",
            &["solve", "sphere", "--rho", "-2^2"],
            Refused(2, &["--rho", "-4", "[0, 1)"]),
        ),
        case(
            "2x",
            &s("2x"),
            Refused(2, &["--emission", "operator is missing", "column 2"]),
        ),
        case("sin x", &s("sin x"), Refused(2, &["'sin'", "parentheses"])),
        case(
            "unclosed",
            &["solve", "sphere", "--exact", "(x"],
            Refused(2, &["--exact", "never closed"]),
        ),
        case("x + 1)", &s("x + 1)"), Refused(2, &["no matching '('"])),
        case("unknown name", &s("w*2"), Refused(2, &["unknown name 'w'"])),
        case(
            "empty",
            &["solve", "sphere", "--rho", " "],
            Refused(2, &["--rho", "empty"]),
        ),
        case(
            "x/0 exact",
            &["solve", "sphere", "--exact", "x/0"],
            Refused(2, &["exact solution", "inf"]),
        ),
        case(
            "log of negatives",
            &s("log(x - 2)"),
            Refused(2, &["--emission", "NaN"]),
        ),
        case("1e999", &s("1e999"), Refused(2, &["emission", "inf"])),
        case(
            "nan",
            &["solve", "sphere", "--rho", "nan"],
            Refused(2, &["reflectivity", "NaN"]),
        ),
        Case {
            name: "30 000 parentheses",
            args: ["solve", "sphere", "--emission", &deep]
                .map(String::from)
                .to_vec(),
            files: Vec::new(),
            want: Refused(2, &["nested more than 64"]),
        },
        case("% sign", &s("x % 2"), Refused(2, &["'%' at column 3"])),
    ]
}

fn magnitude_cases() -> Vec<Case> {
    let boxed = |e: &'static str| {
        [
            "solve",
            "box:1,1,1",
            "--level",
            "0",
            "--rho",
            "0.5",
            "--emission",
            e,
        ]
    };
    // u = E / (1 - ρ) = 2 on any closed surface, at a level.
    let two = |scene: String, level: &'static str| -> [&'static str; 10] {
        let s: &'static str = Box::leak(scene.into_boxed_str());
        [
            "solve",
            s,
            "--level",
            level,
            "--rho",
            "0.5",
            "--emission",
            "1",
            "--exact",
            "2",
        ]
    };
    let thin = |t: &str| two(format!("box:1,{t},1"), "2");
    // Flat ellipsoids: the rim's radius of curvature is c² (c = 1e-6: 1e-12).
    let flat = |c: &str| two(format!("ellipsoid:1,{c},1"), "1");
    let high = |rho: &'static str| {
        [
            "solve",
            "box:1,1,1",
            "--level",
            "1",
            "--rho",
            rho,
            "--emission",
            "1",
            "--quad-tol",
            "1e-14",
        ]
    };
    vec![
        // u = E / (1 − ρ) = 2E in a closed room; its area is 6.
        case(
            "E = 1e-300",
            &boxed("1e-300"),
            Answer("/channels/0/integral_u", 1.2e-299, 1e-12),
        ),
        case(
            "E = 1e160",
            &boxed("1e160"),
            Answer("/channels/0/integral_u", 1.2e161, 1e-12),
        ),
        case(
            "E = 1e300",
            &boxed("1e300"),
            Answer("/channels/0/integral_u", 1.2e301, 1e-12),
        ),
        case(
            "E = 1e308",
            &boxed("1e308"),
            Refused(1, &["overflows", "scale"]),
        ),
        case(
            "room 1e40 across",
            &[
                "solve",
                "box:1e40,1e40,1e40",
                "--level",
                "0",
                "--rho",
                "0.5",
                "--emission",
                "1",
            ],
            Answer("/channels/0/integral_u", 12e80, 1e-12),
        ),
        case(
            "room 1e-40 across",
            &[
                "solve",
                "box:1e-40,1e-40,1e-40",
                "--level",
                "0",
                "--rho",
                "0.5",
                "--emission",
                "1",
            ],
            Answer("/channels/0/integral_u", 12e-80, 1e-12),
        ),
        case(
            "room 1e300",
            &["solve", "box:1e300,1,1"],
            Refused(2, &["1e300 across", "rescale"]),
        ),
        case(
            "sphere 1e300",
            &["solve", "sphere:1e300"],
            Refused(2, &["across", "1e50"]),
        ),
        case(
            "sphere 1e-300",
            &["solve", "sphere:1e-300"],
            Refused(2, &["across", "1e-50"]),
        ),
        // ρ → 1: u = 1/(1 − ρ); GMRES stops at the rounding floor.
        case(
            "ρ = 0.9999",
            &high("0.9999"),
            Answer("/channels/0/integral_u", 6e4, 1e-9),
        ),
        case(
            "ρ = 0.99999",
            &high("0.99999"),
            Answer("/channels/0/integral_u", 6e5, 1e-8),
        ),
        case(
            "ρ = 0.999999",
            &high("0.999999"),
            Answer("/channels/0/integral_u", 6e6, 1e-8),
        ),
        case(
            "ρ = 0.999999 floor",
            &high("0.999999"),
            True("/channels/0/solver/at_rounding_floor"),
        ),
        case(
            "ρ = 0.999999 warns",
            &[
                "solve",
                "box:1,1,1",
                "--level",
                "1",
                "--rho",
                "0.999999",
                "--emission",
                "1",
            ],
            Warned(&["condition number is at least", "--quad-tol"]),
        ),
        // Two walls closer than their elements are wide: the near-pair rule
        // subdivides down to the gap (at most 32 levels).
        case(
            "box 1e-4 thin",
            &thin("1e-4"),
            Below("/channels/0/errors/global_max", 1e-8),
        ),
        case(
            "box 1e-6 thin",
            &thin("1e-6"),
            Below("/channels/0/errors/global_max", 1e-8),
        ),
        case(
            "box 1e-8 thin",
            &thin("1e-8"),
            Below("/channels/0/errors/global_max", 1e-8),
        ),
        case(
            "box 1e-11 thin",
            &thin("1e-11"),
            Warned(&[
                "quadrature:",
                "subdivision limit",
                "--quad-tol",
                "within 1.000e-11 of element",
            ]),
        ),
        // Self pairs on the rim of a flat ellipsoid: the Duffy rule's windows
        // are checked and split where the normal turns within them.
        case(
            "ellipsoid c = 0.1",
            &flat("0.1"),
            Below("/channels/0/errors/global_max", 1e-8),
        ),
        case(
            "ellipsoid c = 1e-3",
            &flat("1e-3"),
            Below("/channels/0/errors/global_max", 1e-8),
        ),
        case(
            "ellipsoid c = 1e-6",
            &flat("1e-6"),
            Below("/channels/0/errors/global_max", 1e-8),
        ),
        // Nodes with Lebesgue constant 3e8: LU's condition estimate (5e14)
        // times --quad-tol bounds u's relative error by 100: a failure, after
        // the report.
        case(
            "r = 6, α = 0.3 by LU",
            &[
                "solve", "sphere", "--level", "0", "--degree", "6", "--alpha", "0.3", "--solver",
                "lu",
            ],
            Refused(
                1,
                &[
                    "channel u",
                    "cannot be trusted",
                    "condition number is about",
                    "--alpha auto",
                ],
            ),
        ),
        case(
            "--tol 1e-20",
            &["solve", "sphere", "--level", "1", "--tol", "1e-20"],
            True("/channels/0/solver/at_rounding_floor"),
        ),
    ]
}

fn flag_cases() -> Vec<Case> {
    vec![
        case(
            "--hp --backend gpu",
            &[
                "solve",
                "shadow",
                "--target-error",
                "1e-2",
                "--hp",
                "--backend",
                "gpu",
            ],
            Refused(2, &["--hp", "GPU", "--backend cpu"]),
        ),
        case(
            "--hp --precision f32",
            &[
                "solve",
                "shadow",
                "--target-error",
                "1e-2",
                "--hp",
                "--precision",
                "f32",
            ],
            Refused(2, &["--hp", "f64", "--precision f32"]),
        ),
        case(
            "--hp without --target-error",
            &["solve", "shadow", "--hp"],
            Refused(2, &["--target-error"]),
        ),
        case(
            "--compression-tol 0",
            &[
                "solve",
                "sphere",
                "--operator",
                "compressed",
                "--compression-tol",
                "0",
            ],
            Refused(2, &["--compression-tol", "(0, 1)"]),
        ),
        case(
            "--compression-tol nan",
            &["solve", "sphere", "--compression-tol", "nan"],
            Refused(2, &["--compression-tol", "nan"]),
        ),
        case(
            "--compression-tol 1",
            &["solve", "sphere", "--compression-tol", "1"],
            Refused(2, &["--compression-tol", "(0, 1)"]),
        ),
        case(
            "--operator compressed --solver lu",
            &[
                "solve",
                "sphere",
                "--operator",
                "compressed",
                "--solver",
                "lu",
            ],
            Refused(2, &["--solver gmres", "--operator dense"]),
        ),
        case(
            "--operator sparse",
            &["solve", "sphere", "--operator", "sparse"],
            Refused(2, &["--operator", "sparse"]),
        ),
        case(
            "compressed sphere: u = E / (1 - rho) = 2",
            &[
                "solve",
                "sphere",
                "--level",
                "2",
                "--operator",
                "compressed",
                "--compression-tol",
                "1e-6",
            ],
            Answer("/channels/0/integral_u", 8.0 * PI, 1e-5),
        ),
        case(
            "compressed: the report says so",
            &["solve", "sphere", "--operator", "compressed"],
            Says(&["operator    compressed", "low-rank blocks"]),
        ),
        case(
            "--quad-tol 1e-300",
            &["solve", "sphere", "--quad-tol", "1e-300"],
            Refused(2, &["--quad-tol", "1e-15"]),
        ),
        case(
            "--alpha 1e-300",
            &["solve", "sphere", "--alpha", "1e-300"],
            Refused(2, &["--alpha", "1e-9"]),
        ),
        case(
            "--alpha 0.4",
            &["solve", "sphere", "--alpha", "0.4"],
            Refused(2, &["--alpha", "1/3"]),
        ),
        case(
            "--degree 7",
            &["solve", "sphere", "--degree", "7"],
            Refused(2, &["0..=6"]),
        ),
        case(
            "--level 40",
            &["solve", "sphere", "--level", "40"],
            Refused(2, &["GiB", "--level"]),
        ),
        case(
            "--max-edge 0",
            &["solve", "sphere", "--max-edge", "0"],
            Refused(2, &["--max-edge 0", "positive"]),
        ),
        case(
            "--max-edge 1e-9",
            &["solve", "sphere", "--max-edge", "1e-9"],
            Refused(
                2,
                &[
                    "more than 4 million",
                    "this run: --level 0 --max-edge",
                    "unknowns fit: --max-edge",
                ],
            ),
        ),
        case(
            "--grade 0.5",
            &["solve", "room", "--grade", "0.5"],
            Refused(2, &["--grade 0.5", "[1, 3]"]),
        ),
        case(
            "--grade NaN",
            &["solve", "room", "--grade", "NaN"],
            Refused(2, &["--grade NaN", "exponent"]),
        ),
        case(
            "--grade-zone -1",
            &["solve", "room", "--grade", "2", "--grade-zone", "-1"],
            Refused(2, &["--grade-zone -1", "positive"]),
        ),
        case(
            "--grade-zone without --grade",
            &["solve", "room", "--grade-zone", "1"],
            Refused(2, &["--grade"]),
        ),
        case(
            "--grade on a sphere",
            &["solve", "sphere", "-l", "1", "--grade", "2"],
            Warned(&["--grade", "no concave edge"]),
        ),
        case(
            "info --max-edge 1e-9",
            &["info", "sphere", "--max-edge", "1e-9"],
            Says(&["more than 4194304 (counting stopped there)"]),
        ),
        case(
            "--level 12",
            &["solve", "sphere", "--level", "12", "--degree", "2"],
            Refused(
                2,
                &["this run: --level 12 --degree 2", "unknowns fit: --level"],
            ),
        ),
        case(
            "info --json --max-edge 1e-9",
            &["info", "sphere", "--max-edge", "1e-9"],
            Answer("/counted_up_to", 4194304.0, 0.0),
        ),
        case(
            "--target-error 0",
            &["solve", "sphere", "--target-error", "0"],
            Refused(2, &["--target-error", "[1e-8, 1)"]),
        ),
        case(
            "--target-error 1e-300",
            &["solve", "sphere", "--target-error", "1e-300"],
            Refused(2, &["--target-error 1e-300", "[1e-8, 1)"]),
        ),
        case(
            "study --adaptive 1e-300",
            &[
                "study",
                "sphere",
                "--levels",
                "0..1",
                "--adaptive",
                "1e-300",
            ],
            Refused(2, &["--adaptive 1e-300", "[1e-8, 1)"]),
        ),
        case(
            "--at /dev/zero",
            &["solve", "sphere", "--level", "0", "--at", "/dev/zero"],
            Refused(2, &["--at /dev/zero", "not a regular file"]),
        ),
        case(
            "--threads 65535",
            &["--threads", "65535", "solve", "sphere", "--level", "0"],
            Refused(2, &["--threads 65535", "per logical CPU"]),
        ),
        case(
            "--target-error 2",
            &["solve", "sphere", "--target-error", "2"],
            Refused(2, &["--target-error"]),
        ),
        case(
            "--tol 0",
            &["solve", "sphere", "--tol", "0"],
            Refused(2, &["--tol"]),
        ),
        case(
            "image 32768²",
            &[
                "solve",
                "sphere",
                "--level",
                "0",
                "--out",
                "{dir}/a.png",
                "--width",
                "32768",
                "--height",
                "32768",
            ],
            Refused(2, &["32768", "rays"]),
        ),
        case(
            "camera at 1e308",
            &[
                "solve",
                "sphere",
                "--level",
                "0",
                "--out",
                "{dir}/a.png",
                "--camera",
                "1e308,0,0,0,0,0,0,0,1,40",
            ],
            Refused(2, &["--camera", "overflows"]),
        ),
        case(
            "camera eye = target",
            &[
                "solve",
                "sphere",
                "--level",
                "0",
                "--out",
                "{dir}/a.png",
                "--camera",
                "0,0,0,0,0,0,0,0,1,40",
            ],
            Refused(2, &["--camera: eye and target coincide"]),
        ),
        case(
            "--out in /proc",
            &[
                "solve",
                "sphere",
                "--level",
                "0",
                "--out",
                "/proc/radcol-nope.csv",
            ],
            Refused(2, &["--out", "/proc/radcol-nope.csv", "cannot be written"]),
        ),
        with_files(
            case(
                "--out a directory",
                &["solve", "sphere", "--level", "0", "--out", "{dir}/d.csv"],
                Refused(2, &["d.csv is a directory"]),
            ),
            vec![("d.csv/x", Vec::new())],
        ),
        case(
            "--out missing folder",
            &[
                "solve",
                "sphere",
                "--level",
                "0",
                "--out",
                "{dir}/no/such.csv",
            ],
            Refused(2, &["does not exist"]),
        ),
        case(
            "unknown scene",
            &["solve", "torus"],
            Refused(2, &["torus", "lroom", "shadow", "cornell"]),
        ),
        case(
            "--rho on cornell",
            &["solve", "cornell", "--rho", "0.3"],
            Refused(2, &["--rho", "materials"]),
        ),
    ]
}

fn obj_cases() -> Vec<Case> {
    let solve = ["solve", "{dir}/s.obj"];
    let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    let big_library: String = (0..20_000)
        .map(|i| format!("newmtl m{i}\nKd 0.5 0.5 0.5\n"))
        .chain([WHITE.to_string()])
        .collect();
    let many_mtllib = format!(
        "{}{tri}usemtl white\nf 1 2 3\n",
        "mtllib w.mtl\n".repeat(5_000)
    );
    // A closed unit box 1e-13 thick, its faces turned inwards.
    let thin_box = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
                    v 0 0 1e-13\nv 1 0 1e-13\nv 1 1 1e-13\nv 0 1 1e-13\n\
                    f 1 2 3 4\nf 5 8 7 6\nf 1 5 6 2\nf 2 6 7 3\nf 3 7 8 4\nf 4 8 5 1\n";
    let mut cases = vec![
        with_files(
            case(
                "a closed box 1e-13 thick",
                &["info", "{dir}/s.obj"],
                Warned(&[
                    "s.obj:12: faces the triangle at",
                    "s.obj:11",
                    "1.0e-13 away",
                    "cannot be resolved",
                ]),
            ),
            obj(thin_box),
        ),
        with_files(
            case(
                "5 000 mtllib lines of a 20 000-material library",
                &solve,
                // The text report: the JSON lists the 20 001 materials.
                Says(&["1 triangles, 20001 materials", "∫E = 0.500000000000"]),
            ),
            vec![
                ("w.mtl", big_library.into_bytes()),
                ("s.obj", many_mtllib.into_bytes()),
            ],
        ),
        with_files(
            case(
                "one material name in two MTL files",
                &solve,
                Warned(&["2 materials are named 'white'", "different values"]),
            ),
            vec![
                ("w.mtl", WHITE.as_bytes().to_vec()),
                ("v.mtl", b"newmtl white\nKd 0.2 0.2 0.2\n".to_vec()),
                (
                    "s.obj",
                    format!("mtllib w.mtl\nmtllib v.mtl\n{tri}usemtl white\nf 1 2 3\n")
                        .into_bytes(),
                ),
            ],
        ),
        with_files(
            case(
                "UTF-8 byte-order marks",
                &solve,
                Answer("/channels/0/integral_e", 0.5, 1e-14),
            ),
            vec![
                (
                    "w.mtl",
                    [b"\xef\xbb\xbf".as_slice(), WHITE.as_bytes()].concat(),
                ),
                (
                    "s.obj",
                    format!("\u{feff}mtllib w.mtl\n{tri}usemtl white\nf 1 2 3\n").into_bytes(),
                ),
            ],
        ),
        with_files(
            case(
                "v 1e-40",
                &solve,
                Answer("/channels/0/integral_e", 0.5, 1e-14),
            ),
            obj("v 1e-40 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
        ),
        with_files(
            case("bow tie", &solve, Warned(&["s.obj:7", "cross each other"])),
            obj("v 0 0 0\nv 1 1 0\nv 1 0 0\nv 0 1 0\nf 1 2 3 4\n"),
        ),
        with_files(
            case(
                "non-planar quad",
                &solve,
                Warned(&["s.obj:7", "not planar"]),
            ),
            obj("v 0 0 0\nv 1 0 0\nv 1 1 0.5\nv 0 1 0\nf 1 2 3 4\n"),
        ),
        with_files(
            case(
                "4097-vertex face",
                &solve,
                Refused(2, &["s.obj:6", "more than 4096 vertices"]),
            ),
            obj(&format!("{tri}f {}\n", vec!["1 2 3"; 1366].join(" "))),
        ),
        with_files(
            case("index out of range", &solve, Refused(2, &["s.obj:6", "9"])),
            obj(&format!("{tri}f 1 2 9\n")),
        ),
        with_files(
            case("two-vertex face", &solve, Refused(2, &["s.obj:6"])),
            obj(&format!("{tri}f 1 2\n")),
        ),
        with_files(
            case("NaN vertex", &solve, Refused(2, &["s.obj:5", "NaN"])),
            obj("v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n"),
        ),
        with_files(
            case(
                "undefined material",
                &solve,
                Refused(2, &["s.obj:2", "'nope'"]),
            ),
            vec![
                ("w.mtl", WHITE.into()),
                ("s.obj", b"mtllib w.mtl\nusemtl nope\n".to_vec()),
            ],
        ),
        with_files(
            case(
                "face before usemtl",
                &solve,
                Refused(2, &["s.obj:4", "no material"]),
            ),
            vec![("s.obj", format!("{tri}f 1 2 3\n").into_bytes())],
        ),
        with_files(
            case(
                "missing mtllib",
                &solve,
                Refused(2, &["s.obj:1", "gone.mtl"]),
            ),
            vec![("s.obj", b"mtllib gone.mtl\n".to_vec())],
        ),
        with_files(
            case("Kd 1.2", &solve, Refused(2, &["w.mtl:2", "1.2", "[0, 1)"])),
            vec![
                ("w.mtl", b"newmtl white\nKd 1.2 0.5 0.5\n".to_vec()),
                (
                    "s.obj",
                    format!("mtllib w.mtl\n{tri}usemtl white\nf 1 2 3\n").into_bytes(),
                ),
            ],
        ),
        with_files(
            case("Ke -1", &solve, Refused(2, &["w.mtl:3", "-1"])),
            vec![
                (
                    "w.mtl",
                    b"newmtl white\nKd 0.5 0.5 0.5\nKe -1 0 0\n".to_vec(),
                ),
                (
                    "s.obj",
                    format!("mtllib w.mtl\n{tri}usemtl white\nf 1 2 3\n").into_bytes(),
                ),
            ],
        ),
        with_files(
            case("empty file", &solve, Refused(2, &["no triangles"])),
            vec![("s.obj", Vec::new())],
        ),
        with_files(
            case(
                "only degenerate",
                &solve,
                Refused(2, &["no triangles", "1 degenerate"]),
            ),
            obj("v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n"),
        ),
        with_files(
            case(
                "duplicate triangle",
                &solve,
                Warned(&["s.obj:7", "duplicate of the triangle at", "s.obj:6"]),
            ),
            obj(&format!("{tri}f 1 2 3\nf 1 2 3\n")),
        ),
        with_files(
            case("polyline", &solve, Warned(&["s.obj:7", "polyline"])),
            obj(&format!("{tri}f 1 2 3\nl 1 2\n")),
        ),
        with_files(
            case("not UTF-8", &solve, Refused(2, &["s.obj", "UTF-8"])),
            vec![
                ("w.mtl", WHITE.into()),
                ("s.obj", b"mtllib w.mtl\nv 0 0 \xff\n".to_vec()),
            ],
        ),
        with_files(
            case(
                "a directory named .obj",
                &["solve", "{dir}/d.obj"],
                Refused(2, &["d.obj", "not a regular file"]),
            ),
            vec![("d.obj/x", Vec::new())],
        ),
        case(
            "/dev/zero",
            &["solve", "{dir}/zero.obj"],
            Refused(2, &["zero.obj", "not a regular file"]),
        ),
        case(
            "300 MiB file",
            &["solve", "{dir}/big.obj"],
            Refused(2, &["big.obj", "300.0 MiB", "256 MiB"]),
        ),
    ];
    // A floor given twice with the other diagonal: counted twice, warned.
    cases.push(with_files(
        case(
            "floor twice",
            &solve,
            Warned(&[
                "s.obj:9: overlaps the triangle at",
                "s.obj:7",
                "counted twice",
            ]),
        ),
        obj("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\nf 1 2 4\nf 2 3 4\n"),
    ));
    // A unit light and floor, and one far triangle at 1.2e8: degeneracy is
    // judged per triangle, so the light stays (∫E of R = its area 0.5).
    cases.push(with_files(
        case(
            "vertex at 1.2e8",
            &solve,
            Answer("/channels/0/integral_e", 0.5, 1e-14),
        ),
        vec![
            ("w.mtl", format!("{WHITE}newmtl grey\nKd 0.5 0.5 0.5\n").into_bytes()),
            (
                "s.obj",
                "mtllib w.mtl\nv 0 0 1\nv 0 1 1\nv 1 0 1\nv 0 0 0\nv 1 0 0\nv 0 1 0\n\
                 v 1.2e8 0 0\nv 1.2e8 1 0\nv 1.2e8 0 1\nusemtl white\nf 1 2 3\nusemtl grey\nf 4 5 6\nf 7 8 9\n"
                    .into(),
            ),
        ],
    ));
    // A light over a wall and a floor wound clockwise (facing down): each
    // floor triangle is named, instead of an almost black image with no warning.
    cases.push(with_files(
        case(
            "floor wound the wrong way",
            &solve,
            Warned(&["s.obj:15 (group 'floor')", "faces no other surface", "wound the wrong way"]),
        ),
        vec![
            ("w.mtl", format!("{WHITE}newmtl grey\nKd 0.5 0.5 0.5\n").into_bytes()),
            (
                "s.obj",
                "mtllib w.mtl\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
                 g light\nusemtl white\nf 1 4 3 2\ng floor\nusemtl grey\nf 5 8 7 6\ng wall\nf 5 8 4 1\n"
                    .into(),
            ),
        ],
    ));
    // The L from every corner: ear clipping covers exactly its area 3 (a fan
    // from 4 of the 6 corners flipped a triangle over the notch).
    for start in 0..6 {
        cases.push(with_files(
            case(
                [
                    "L from 1", "L from 2", "L from 3", "L from 4", "L from 5", "L from 6",
                ][start],
                &solve,
                Answer("/channels/0/integral_e", 3.0, 1e-14),
            ),
            obj(&l_face(start)),
        ));
    }
    cases
}

/// Writes the case's files (and the special ones) into `dir`, runs it and
/// returns a description of what went wrong, if anything.
fn run(c: &Case, dir: &Path) -> Option<String> {
    for (name, bytes) in &c.files {
        let path = dir.join(name);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, bytes).unwrap();
    }
    if c.name == "/dev/zero" {
        std::os::unix::fs::symlink("/dev/zero", dir.join("zero.obj")).unwrap();
    }
    if c.name == "300 MiB file" {
        // Sparse: no disk space used.
        let f = std::fs::File::create(dir.join("big.obj")).unwrap();
        f.set_len(300 << 20).unwrap();
    }
    let mut args: Vec<String> = c
        .args
        .iter()
        .map(|a| a.replace("{dir}", dir.to_str().unwrap()))
        .collect();
    if matches!(c.want, Answer(..) | True(_) | Below(..)) {
        args.push("--json".into());
    }
    let mut child = Command::new(radcol_bin())
        .args(&args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > LIMIT {
            let _ = child.kill();
            return Some(format!("no answer after {LIMIT:?}"));
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    let out = child.wait_with_output().unwrap();
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    let has = |text: &str, needles: &[&str]| {
        needles
            .iter()
            .all(|n| text.to_lowercase().contains(&n.to_lowercase()))
    };
    if stderr.contains("panicked") {
        return Some(format!("panicked: {stderr}"));
    }
    let ok = out.status.success();
    match c.want {
        Refused(code, needles) => {
            let lines: Vec<&str> = stderr.lines().collect();
            let good = out.status.code() == Some(code)
                && lines.len() == 1
                && lines[0].starts_with("error: ")
                && has(&stderr, needles);
            (!good).then(|| {
                format!(
                    "want exit {code} and one error line with {needles:?}; got {:?}: {stderr}",
                    out.status.code()
                )
            })
        }
        Warned(needles) => {
            let warned = stdout
                .lines()
                .chain(stderr.lines())
                .any(|l| l.contains("warning") && has(l, needles));
            (!(ok && warned)).then(|| {
                format!(
                    "want success and a warning with {needles:?}; got {:?}: {stderr}",
                    out.status.code()
                )
            })
        }
        Says(needles) => (!(ok && has(&stdout, needles)))
            .then(|| format!("want {needles:?} on stdout; got {stdout}{stderr}")),
        Answer(..) | True(_) | Below(..) if !ok => Some(format!("want success; failed: {stderr}")),
        Below(pointer, bound) => {
            let Ok(json) = serde_json::from_str::<Value>(&stdout) else {
                return Some(format!("stdout is not JSON: {stdout}"));
            };
            let got = json.pointer(pointer).and_then(Value::as_f64);
            (!got.is_some_and(|g| g <= bound))
                .then(|| format!("{pointer}: want at most {bound:e}, got {got:?}"))
        }
        Answer(pointer, value, tol) => {
            let Ok(json) = serde_json::from_str::<Value>(&stdout) else {
                return Some(format!("stdout is not JSON: {stdout}"));
            };
            let got = json.pointer(pointer).and_then(Value::as_f64);
            match got {
                Some(g) if (g - value).abs() <= tol * value.abs() => None,
                _ => Some(format!(
                    "{pointer}: want {value:e} within {tol:e}, got {got:?}"
                )),
            }
        }
        True(pointer) => {
            let Ok(json) = serde_json::from_str::<Value>(&stdout) else {
                return Some(format!("stdout is not JSON: {stdout}"));
            };
            (json.pointer(pointer) != Some(&Value::Bool(true)))
                .then(|| format!("{pointer}: want true, got {:?}", json.pointer(pointer)))
        }
    }
}

#[test]
fn every_bad_or_extreme_input_has_its_outcome() {
    let cases: Vec<Case> = [
        expression_cases(),
        magnitude_cases(),
        flag_cases(),
        obj_cases(),
    ]
    .into_iter()
    .flatten()
    .collect();
    assert!(cases.len() >= 60, "{} cases", cases.len());
    println!("{} cases", cases.len());
    let root = scratch("faults");
    let threads = std::thread::available_parallelism()
        .map_or(2, |n| n.get())
        .min(4);
    let failures: Vec<String> = std::thread::scope(|s| {
        let chunks: Vec<_> = (0..threads)
            .map(|t| {
                let (cases, root) = (&cases, &root);
                s.spawn(move || {
                    let mut failed = Vec::new();
                    for (i, c) in cases.iter().enumerate().skip(t).step_by(threads) {
                        let dir = root.join(format!("case{i:03}"));
                        std::fs::create_dir_all(&dir).unwrap();
                        if let Some(why) = run(c, &dir) {
                            failed.push(format!("[{i}] {}: {why}", c.name));
                        }
                    }
                    failed
                })
            })
            .collect();
        chunks.into_iter().flat_map(|h| h.join().unwrap()).collect()
    });
    assert!(
        failures.is_empty(),
        "{} of {} cases:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}

/// Outputs never take an input's place, nor leave a partial file: an
/// output that is the scene being read or the `--at` file (under another
/// spelling, with `--force`) is refused and the input kept byte for byte;
/// one file named twice is refused; a pipe is refused, not opened (opening
/// it waited for a reader); a replaced output leaves no temporary file
/// beside it, and a symbolic link stays a link to the file it names.
#[test]
fn outputs_never_take_an_inputs_place() {
    let dir = scratch("outputs");
    let at = |c: Case, d: &Path| run(&c, d).map(|why| format!("{}: {why}", c.name));
    let mut failed: Vec<String> = Vec::new();
    let points = vec![("p.csv", b"x,y,z\n100,0,100\n".to_vec())];
    let quick = ["solve", "cornell", "--max-edge", "300"];
    fn with<'a>(quick: &[&'a str], extra: &[&'a str]) -> Vec<&'a str> {
        quick.iter().chain(extra).copied().collect()
    }
    failed.extend(at(
        case(
            "a glb",
            &with(&quick, &["-o", "{dir}/c.glb"]),
            Says(&["wrote"]),
        ),
        &dir,
    ));
    let glb = std::fs::read(dir.join("c.glb")).expect("written");
    failed.extend(at(
        case(
            "the scene as --out",
            &[
                "solve",
                "{dir}/c.glb",
                "--max-edge",
                "300",
                "-o",
                "{dir}/./c.glb",
                "--force",
            ],
            Refused(2, &["--out", "the scene", "reads"]),
        ),
        &dir,
    ));
    assert_eq!(
        std::fs::read(dir.join("c.glb")).unwrap(),
        glb,
        "the scene kept"
    );
    failed.extend(at(
        with_files(
            case(
                "--at-out on --at",
                &with(
                    &quick,
                    &[
                        "--at",
                        "{dir}/p.csv",
                        "--at-out",
                        "{dir}/./p.csv",
                        "--force",
                    ],
                ),
                Refused(2, &["--at-out", "--at points file"]),
            ),
            points.clone(),
        ),
        &dir,
    ));
    assert_eq!(std::fs::read(dir.join("p.csv")).unwrap(), points[0].1);
    failed.extend(at(
        case(
            "one file twice",
            &with(
                &quick,
                &[
                    "-o",
                    "{dir}/a.csv",
                    "-o",
                    "{dir}/../outputs/a.csv",
                    "--force",
                ],
            ),
            Refused(2, &["one file"]),
        ),
        &dir,
    ));
    let fifo = dir.join("f.csv");
    assert!(Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    failed.extend(at(
        case(
            "a pipe",
            &with(&quick, &["-o", "{dir}/f.csv", "--force"]),
            Refused(2, &["not a regular file"]),
        ),
        &dir,
    ));
    std::fs::write(dir.join("a.csv"), "old").unwrap();
    std::os::unix::fs::symlink("a.csv", dir.join("link.csv")).unwrap();
    failed.extend(at(
        case(
            "replaced through a link",
            &with(&quick, &["-o", "{dir}/link.csv", "--force"]),
            Says(&["wrote"]),
        ),
        &dir,
    ));
    assert!(failed.is_empty(), "{}", failed.join("\n"));
    let link = std::fs::symlink_metadata(dir.join("link.csv")).unwrap();
    assert!(link.file_type().is_symlink(), "the link stays a link");
    let text = std::fs::read_to_string(dir.join("a.csv")).unwrap();
    assert!(text.starts_with("element,node,"), "{text:.40}");
    let left: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".tmp"))
        .collect();
    assert!(left.is_empty(), "temporary files left: {left:?}");
}

/// Ctrl-C (SIGINT) in the middle of a solve ends the run with exit code
/// 130 and a line saying so, and leaves no file: neither the output nor a
/// hidden temporary one (what a signal during a write would leave is
/// removed by the same handler: `files::tests`).
#[cfg(unix)]
#[test]
fn an_interrupted_run_says_so_and_leaves_no_file() {
    let dir = scratch("interrupted");
    let out = dir.join("c.png");
    let child = Command::new(radcol_bin())
        .args(["solve", "cornell", "--max-edge", "25", "--out"])
        .arg(&out)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("radcol starts");
    // Long enough to be inside the solve (this one takes minutes).
    std::thread::sleep(Duration::from_millis(1500));
    let killed = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(killed.success());
    let started = Instant::now();
    let output = child.wait_with_output().expect("radcol ends");
    assert!(started.elapsed() < Duration::from_secs(10));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(130), "{stderr}");
    assert!(stderr.contains("interrupted"), "{stderr}");
    let left: Vec<_> = std::fs::read_dir(&dir).unwrap().flatten().collect();
    assert!(left.is_empty(), "{left:?}");
}
