//! Fuzzing the readers of what a user hands radcol: OBJ, MTL, glTF (JSON
//! with its buffer, and GLB) and the `--at` points CSV.
//!
//! Each case takes a valid seed file and applies a few random edits (bytes
//! flipped, tokens of the format inserted, ranges deleted, duplicated or
//! cut off, numbers replaced by extreme ones), with proptest choosing the
//! edits and shrinking a failure to the smallest. The reader must return a
//! scene or an error; a panic, an abort or a case slower than
//! [`CASE_SECONDS`] fails the test with the input written to a file.
//!
//! The default run is short and the same every time (CI). A longer one,
//! with other edits, as the docs report:
//!
//! ```text
//! RADCOL_FUZZ_SEED=7 RADCOL_FUZZ_SECONDS=600 cargo test --release -p radcol-cli --test fuzz obj -- --nocapture
//! ```

use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestCaseError, TestRng, TestRunner};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The longest a case may take (a few KB of input; a hang otherwise).
const CASE_SECONDS: f64 = 30.0;

/// The random edits' generator of round `round`: from `RADCOL_FUZZ_SEED`
/// (a number), else a fixed seed, so that a run in CI is the same every
/// time.
fn rng(round: u64) -> TestRng {
    let seed: u64 = std::env::var("RADCOL_FUZZ_SEED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0x5eed_u64)
        .wrapping_add(round);
    let mut bytes = [0u8; 32];
    bytes[..8].copy_from_slice(&seed.to_le_bytes());
    TestRng::from_seed(RngAlgorithm::ChaCha, &bytes)
}

/// Cases per reader: `RADCOL_FUZZ_CASES`, else `default`.
fn cases(default: u32) -> u32 {
    std::env::var("RADCOL_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// One edit of a file's bytes; positions are taken modulo the length.
#[derive(Clone, Debug)]
enum Edit {
    Flip(usize, u8),
    Token(usize, usize),
    Delete(usize, usize),
    Duplicate(usize, usize, usize),
    Truncate(usize),
    Number(usize, usize),
}

/// Numbers that break assumptions, written as text.
const NUMBERS: &[&str] = &[
    "0",
    "-0",
    "1",
    "-1",
    "2",
    "3",
    "4294967295",
    "4294967296",
    "-2147483649",
    "18446744073709551616",
    "1e308",
    "-1e308",
    "1e-320",
    "nan",
    "inf",
    "-inf",
    "0.5",
    "1e-13",
    "65535",
    "999999999999",
];

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        (any::<usize>(), 1..=255u8).prop_map(|(p, x)| Edit::Flip(p, x)),
        (any::<usize>(), any::<usize>()).prop_map(|(p, t)| Edit::Token(p, t)),
        (any::<usize>(), 1..64usize).prop_map(|(p, n)| Edit::Delete(p, n)),
        (any::<usize>(), 1..256usize, any::<usize>())
            .prop_map(|(p, n, at)| Edit::Duplicate(p, n, at)),
        any::<usize>().prop_map(Edit::Truncate),
        (any::<usize>(), any::<usize>()).prop_map(|(p, n)| Edit::Number(p, n)),
    ]
}

/// `seed` with `edits` applied; `tokens` are the format's words.
fn mutate(seed: &[u8], edits: &[Edit], tokens: &[&str]) -> Vec<u8> {
    let mut b = seed.to_vec();
    for e in edits {
        let at = |p: usize, b: &[u8]| p % (b.len() + 1);
        match *e {
            Edit::Flip(p, x) if !b.is_empty() => {
                let i = p % b.len();
                b[i] ^= x;
            }
            Edit::Flip(..) => {}
            Edit::Token(p, t) => {
                let i = at(p, &b);
                let tok = tokens[t % tokens.len()].as_bytes();
                b.splice(i..i, tok.iter().copied());
            }
            Edit::Delete(p, n) => {
                let i = at(p, &b);
                let end = (i + n).min(b.len());
                b.drain(i..end);
            }
            Edit::Duplicate(p, n, to) => {
                let i = at(p, &b);
                let piece: Vec<u8> = b[i..(i + n).min(b.len())].to_vec();
                let j = at(to, &b);
                b.splice(j..j, piece);
            }
            Edit::Truncate(p) => {
                let i = at(p, &b);
                b.truncate(i.max(b.len() / 2));
            }
            Edit::Number(p, n) => {
                // The number at or after p replaced by an extreme one.
                let mut i = at(p, &b);
                while i < b.len() && !(b[i].is_ascii_digit() || b[i] == b'-') {
                    i += 1;
                }
                let mut end = i;
                while end < b.len() && (b[end].is_ascii_digit() || b"-+.eE".contains(&b[end])) {
                    end += 1;
                }
                let num = NUMBERS[n % NUMBERS.len()].as_bytes();
                b.splice(i..end, num.iter().copied());
            }
        }
    }
    b
}

/// A folder of its own for this test's files.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("radcol-fuzz-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn repo(path: &str) -> Vec<u8> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(path);
    std::fs::read(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// Runs `cases` cases of `check` on mutations of the seeds; `check`
/// returns whether the input was read (a scene, values), or Err with a
/// description when the reader misbehaved. Prints how many were read: a
/// run where none is read explores nothing past the first error.
fn fuzz(
    what: &str,
    seeds: &[Vec<u8>],
    tokens: &[&str],
    cases: u32,
    check: impl Fn(&[u8]) -> Result<bool, String>,
) {
    let read = std::cell::Cell::new(0u64);
    let started = Instant::now();
    // RADCOL_FUZZ_SECONDS: rounds of `cases` cases, each from the next
    // seed, until that long has passed.
    let seconds: f64 = std::env::var("RADCOL_FUZZ_SECONDS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0.0);
    let mut round = 0;
    loop {
        let config = Config {
            cases,
            failure_persistence: None,
            max_shrink_iters: 2000,
            ..Config::default()
        };
        let mut runner = TestRunner::new_with_rng(config, rng(round));
        let strategy = (0..seeds.len(), prop::collection::vec(edit(), 1..8));
        let result = runner.run(&strategy, |(s, edits)| {
            let input = mutate(&seeds[s], &edits, tokens);
            let t0 = Instant::now();
            let outcome = check(&input);
            let secs = t0.elapsed().as_secs_f64();
            let fail = match outcome {
                Err(e) => Some(e),
                Ok(_) if secs > CASE_SECONDS => Some(format!("took {secs:.1} s")),
                Ok(ok) => {
                    read.set(read.get() + u64::from(ok));
                    None
                }
            };
            if let Some(why) = fail {
                let keep = std::env::temp_dir().join(format!("radcol-fuzz-{what}-failure"));
                std::fs::write(&keep, &input).unwrap();
                return Err(TestCaseError::fail(format!(
                    "{what}: {why} (input in {})",
                    keep.display()
                )));
            }
            Ok(())
        });
        round += 1;
        if let Err(e) = result {
            panic!("{e} (round {round})");
        }
        if started.elapsed().as_secs_f64() >= seconds {
            break;
        }
    }
    println!(
        "{what}: {} cases in {:.1} s, {} of them read",
        u64::from(cases) * round,
        started.elapsed().as_secs_f64(),
        read.get()
    );
}

/// The reader in this process: whether it read the input, Err on a panic.
fn no_panic<T, E>(read: impl FnOnce() -> Result<T, E>) -> Result<bool, String> {
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(read)) {
        Ok(r) => Ok(r.is_ok()),
        Err(p) => Err(format!(
            "panicked: {}",
            p.downcast_ref::<String>()
                .cloned()
                .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default()
        )),
    }
}

const OBJ_TOKENS: &[&str] = &[
    "v ",
    "vt ",
    "vn ",
    "f ",
    "g ",
    "o ",
    "s ",
    "l ",
    "p ",
    "usemtl ",
    "mtllib ",
    "#",
    " ",
    "\t",
    "\n",
    "\r",
    "\r\n",
    "/",
    "//",
    "-",
    "1",
    "0",
    "-1",
    "99999",
    "1e308",
    "nan",
    "\u{feff}",
    "\\\n",
    "f 1 2 3\n",
    "f 1 1 1\n",
    "f 1 2 3 4 5 6 7 8 9\n",
    "usemtl white\n",
    "usemtl nosuch\n",
    "mtllib t.mtl\n",
    "mtllib ../t.mtl\n",
    "mtllib /dev/zero\n",
    "g \n",
    "v 0 0 0\n",
    "v 1e308 1e308 1e308\n",
    "\u{0}",
];

const MTL_TOKENS: &[&str] = &[
    "newmtl ",
    "Kd ",
    "Ke ",
    "Ka ",
    "Ks ",
    "Ns ",
    "d ",
    "illum ",
    "map_Kd ",
    " ",
    "\t",
    "\n",
    "\r",
    "#",
    "-1",
    "1",
    "0",
    "2",
    "nan",
    "1e308",
    "newmtl white\n",
    "newmtl light\n",
    "Kd 0.5 0.5 0.5\n",
    "Ke 1e308 0 0\n",
    "Kd 1 1 1\n",
    "\u{feff}",
];

/// Reading an OBJ scene and its MTL from files: `which` is mutated.
fn obj_case(dir: &Path, obj: &[u8], mtl: &[u8]) -> Result<bool, String> {
    let (o, m) = (dir.join("t.obj"), dir.join("t.mtl"));
    std::fs::write(&o, obj).unwrap();
    std::fs::write(&m, mtl).unwrap();
    no_panic(|| radcol_core::scene::load_obj(&o))
}

/// The built-in scenes' OBJ files, their `mtllib` renamed to t.mtl, and
/// their MTL files.
fn obj_seeds() -> Vec<(Vec<u8>, Vec<u8>)> {
    ["cornell", "room", "shadow", "plates"]
        .iter()
        .map(|name| {
            let obj = String::from_utf8(repo(&format!("scenes/{name}.obj"))).unwrap();
            let obj = obj.replace(&format!("mtllib {name}.mtl"), "mtllib t.mtl");
            (obj.into_bytes(), repo(&format!("scenes/{name}.mtl")))
        })
        .collect()
}

#[test]
fn obj_files_end_in_a_scene_or_an_error() {
    let dir = scratch("obj");
    let seeds = obj_seeds();
    let objs: Vec<Vec<u8>> = seeds.iter().map(|s| s.0.clone()).collect();
    // Each OBJ seed with its own MTL: the MTL of the seed whose OBJ this
    // mutation most resembles is not known, so every OBJ names t.mtl and
    // the MTL holds the materials of all four.
    let mtl: Vec<u8> = seeds.iter().flat_map(|s| s.1.clone()).collect();
    fuzz("obj", &objs, OBJ_TOKENS, cases(2000), |obj| {
        obj_case(&dir, obj, &mtl)
    });
}

#[test]
fn mtl_files_end_in_a_scene_or_an_error() {
    let dir = scratch("mtl");
    let seeds = obj_seeds();
    let obj = seeds[0].0.clone();
    let mtls: Vec<Vec<u8>> = vec![seeds[0].1.clone()];
    fuzz("mtl", &mtls, MTL_TOKENS, cases(2000), |mtl| {
        obj_case(&dir, &obj, mtl)
    });
}

const GLTF_TOKENS: &[&str] = &[
    "{",
    "}",
    "[",
    "]",
    ",",
    ":",
    "\"",
    "null",
    "true",
    "0",
    "-1",
    "1",
    "2",
    "3",
    "1e40",
    "4294967296",
    "\"nodes\"",
    "\"children\"",
    "\"mesh\"",
    "\"meshes\"",
    "\"primitives\"",
    "\"attributes\"",
    "\"POSITION\"",
    "\"indices\"",
    "\"mode\"",
    "\"material\"",
    "\"accessors\"",
    "\"bufferView\"",
    "\"byteOffset\"",
    "\"byteStride\"",
    "\"byteLength\"",
    "\"count\"",
    "\"componentType\"",
    "\"type\"",
    "\"VEC3\"",
    "\"SCALAR\"",
    "\"MAT4\"",
    "\"uri\"",
    "\"t.bin\"",
    "\"../t.bin\"",
    "\"/dev/zero\"",
    "\"data:application/octet-stream;base64,AAAA\"",
    "\"data:,%FF%FE\"",
    "\"rotation\"",
    "[0,0,0,2]",
    "\"scale\"",
    "[0,0,0]",
    "\"matrix\"",
    "\"translation\"",
    "\"sparse\"",
    "\"targets\"",
    "\"skin\"",
    "\"camera\"",
    "\"scene\"",
    "\"scenes\"",
    "\"emissiveFactor\"",
    "\"baseColorFactor\"",
    "\"extensions\"",
    "5120",
    "5121",
    "5122",
    "5123",
    "5125",
    "5126",
];

/// A small glTF: a floor quad (two triangles) under an emitting triangle,
/// one node each under a root, positions and u16 indices in t.bin.
fn gltf_seed() -> (Vec<u8>, Vec<u8>) {
    let positions: [[f32; 3]; 7] = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 0.0, 1.0],
        [0.0, 0.0, 1.0],
        [0.2, 1.0, 0.2],
        [0.2, 1.0, 0.8],
        [0.8, 1.0, 0.5],
    ];
    let indices: [u16; 9] = [0, 2, 1, 0, 3, 2, 4, 6, 5];
    let mut bin: Vec<u8> = positions
        .iter()
        .flatten()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let pos_len = bin.len();
    bin.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    let idx_len = bin.len() - pos_len;
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
"nodes":[{{"name":"root","children":[1,2]}},{{"name":"floor","mesh":0}},{{"name":"lamp","mesh":1,"translation":[0,0.5,0],"rotation":[0,0,0,1],"scale":[1,1,1]}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"material":0}}]}},{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":2,"material":1}}]}}],
"materials":[{{"name":"white","pbrMetallicRoughness":{{"baseColorFactor":[0.5,0.5,0.5,1]}}}},{{"name":"light","pbrMetallicRoughness":{{"baseColorFactor":[0.2,0.2,0.2,1]}},"emissiveFactor":[1,1,1]}}],
"buffers":[{{"uri":"t.bin","byteLength":{}}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{pos_len}}},{{"buffer":0,"byteOffset":{pos_len},"byteLength":{idx_len}}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":7,"type":"VEC3","min":[0,0,0],"max":[1,1,1]}},
{{"bufferView":1,"byteOffset":0,"componentType":5123,"count":6,"type":"SCALAR"}},
{{"bufferView":1,"byteOffset":12,"componentType":5123,"count":3,"type":"SCALAR"}}]}}"#,
        bin.len()
    );
    (json.into_bytes(), bin)
}

/// The seed as one GLB: header, JSON chunk (without the buffer's uri),
/// binary chunk.
fn glb_seed() -> Vec<u8> {
    let (json, bin) = gltf_seed();
    let json = String::from_utf8(json)
        .unwrap()
        .replace(r#""uri":"t.bin","#, "");
    let mut json = json.into_bytes();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut glb = Vec::with_capacity(total);
    glb.extend(b"glTF");
    glb.extend(2u32.to_le_bytes());
    glb.extend((total as u32).to_le_bytes());
    glb.extend((json.len() as u32).to_le_bytes());
    glb.extend(b"JSON");
    glb.extend(&json);
    glb.extend((bin.len() as u32).to_le_bytes());
    glb.extend(b"BIN\0");
    glb.extend(&bin);
    glb
}

/// Fuzzes the glTF reader on `path` (t.gltf or t.glb in a folder holding
/// t.bin when needed) from `seed`, once the seed is checked to read.
fn fuzz_gltf(what: &str, path: &Path, seed: Vec<u8>) {
    // The seed reads: the fuzzing starts from a valid scene.
    std::fs::write(path, &seed).unwrap();
    let scene = radcol_core::scene::load_gltf(path).expect("the seed reads");
    assert_eq!(scene.triangle_count(), 3);
    fuzz(what, &[seed], GLTF_TOKENS, cases(2000), |doc| {
        std::fs::write(path, doc).unwrap();
        no_panic(|| radcol_core::scene::load_gltf(path))
    });
}

#[test]
fn gltf_files_end_in_a_scene_or_an_error() {
    let dir = scratch("gltf");
    let (json, bin) = gltf_seed();
    std::fs::write(dir.join("t.bin"), &bin).unwrap();
    fuzz_gltf("gltf", &dir.join("t.gltf"), json);
}

#[test]
fn glb_files_end_in_a_scene_or_an_error() {
    fuzz_gltf("glb", &scratch("glb").join("t.glb"), glb_seed());
}

const CSV_TOKENS: &[&str] = &[
    ",",
    "\n",
    "\r",
    "\r\n",
    "\"",
    "\"\"",
    " ",
    "\t",
    "x",
    "y",
    "z",
    "nx",
    "ny",
    "nz",
    "label",
    "x,y,z\n",
    "x,x,y,z\n",
    "1,2,3\n",
    "0,0,0,0,0,0\n",
    "nan",
    "inf",
    "1e308",
    "-1e308",
    "#",
    "\u{feff}",
    "\u{0}",
    "a,b\n",
    ",,,,,,,,,,\n",
];

/// `radcol solve` of the two plates with `--at` the points file; Err when
/// it panicked (an internal error), died of a signal, or did not end.
fn points_case(dir: &Path, csv: &[u8]) -> Result<bool, String> {
    let at = dir.join("p.csv");
    std::fs::write(&at, csv).unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/plates.obj");
    let mut child = Command::new(env!("CARGO_BIN_EXE_radcol"))
        .args([
            "solve",
            "--level",
            "0",
            "--degree",
            "0",
            "--no-estimate",
            "-q",
            "--at",
        ])
        .arg(&at)
        .arg(&scene)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let deadline = Instant::now() + Duration::from_secs_f64(CASE_SECONDS);
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            return Err("did not end".into());
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let mut err = String::new();
    use std::io::Read;
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut err)
        .unwrap();
    match status.code() {
        _ if err.contains("internal error") => Err(format!("internal error: {err}")),
        None => Err(format!("killed by a signal: {err}")),
        Some(0) => Ok(true),
        Some(_) if err.contains("error:") => Ok(false),
        Some(c) => Err(format!("exit {c} without an error line: {err}")),
    }
}

#[test]
fn points_files_end_in_values_or_an_error() {
    let dir = scratch("points");
    let seeds = vec![
        b"x,y,z,nx,ny,nz,label\n0.5,0.5,0,0,0,1,a\n0.2,0.3,1,0,0,-1,b\n".to_vec(),
        b"0.5,0.5,0\n0.1,0.9,1\n".to_vec(),
        b"label,z,y,x\nfirst,0,0.5,0.5\n".to_vec(),
    ];
    points_case(&dir, &seeds[0]).expect("the seed answers");
    fuzz("points", &seeds, CSV_TOKENS, cases(300), |csv| {
        points_case(&dir, csv)
    });
}

/// What the fuzzing found, kept as a test: a POSITION attribute naming an
/// accessor that does not exist panicked inside the gltf crate's
/// validation; it is refused, naming the primitive and the accessor.
#[test]
fn a_position_naming_no_accessor_is_refused() {
    let dir = scratch("position");
    let (json, bin) = gltf_seed();
    let json = String::from_utf8(json).unwrap().replacen(
        r#""POSITION":0},"indices":2"#,
        r#""POSITION":4294967295},"indices":2"#,
        1,
    );
    std::fs::write(dir.join("t.bin"), &bin).unwrap();
    let path = dir.join("t.gltf");
    std::fs::write(&path, json).unwrap();
    let err = radcol_core::scene::load_gltf(&path)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("t.gltf")
            && err.contains("meshes[1].primitives[0] names accessor 4294967295, but there are 3"),
        "{err}"
    );
}

/// What the fuzzing found, kept as a test: a Cornell box with two floor
/// vertices moved made spade's constrained triangulation panic while the
/// blocks' contact lines were imprinted on the floor ("Failed to locate
/// position. This is a bug in spade."). The floor triangle is kept whole
/// instead, and the scene reads.
#[test]
fn a_triangulation_that_fails_inside_spade_keeps_the_triangle() {
    let dir = scratch("spade");
    let obj = include_bytes!("data/fuzz-spade.obj");
    let mtl: Vec<u8> = obj_seeds().iter().flat_map(|s| s.1.clone()).collect();
    assert_eq!(obj_case(&dir, obj, &mtl), Ok(true));
}
