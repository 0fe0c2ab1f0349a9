//! Wavefront OBJ + MTL input.
//!
//! tobj reads the file's structure (objects/groups, materials, polygons).
//! tobj gives no line numbers and
//! (as the workspace builds it) parses in single precision, so a line scan
//! first reads every statement radcol needs in double precision with its
//! 1-based line: vertices, faces, `g`/`o`, `usemtl`, `mtllib` and the MTL
//! files' `newmtl`/`Kd`/`Ke`. tobj emits its models in file order (a new model
//! at every group or material change, faces in order), so its polygons are
//! matched one by one with the scanned faces; any disagreement in group,
//! material or position is an error rather than a silent mismatch. Polyline
//! (`l`) and point (`p`) statements are not surfaces: they are skipped with a
//! warning. Polygons are triangulated whatever their convexity
//! ([`super::polygon`]); a face may have up to [`MAX_FACE_VERTICES`] vertices.

use super::raw::RawScene;
use super::scan::{rest, syntax, Copies, ScanFace};
use super::validate::finish;
use super::{Material, Scene, SceneError};
use glam::DVec3;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// The largest scene file (OBJ or MTL) read: about 4 million triangles, far
/// beyond what a dense solve handles. A device (`/dev/zero`) or a runaway
/// file is refused instead of filling memory.
pub const MAX_SCENE_FILE_BYTES: u64 = 256 << 20;

/// The text of a scene file: a regular file of at most
/// [`MAX_SCENE_FILE_BYTES`], in UTF-8, without a leading byte-order mark.
fn read_text(path: &Path) -> Result<String, String> {
    use std::io::Read;
    let meta = std::fs::metadata(path).map_err(|e| e.to_string())?;
    if !meta.is_file() {
        return Err("not a regular file (a directory, device or pipe)".into());
    }
    let too_big = |size: u64| {
        format!(
            "{:.1} MiB is more than the {} MiB radcol reads (about 4 million triangles)",
            size as f64 / (1u64 << 20) as f64,
            MAX_SCENE_FILE_BYTES >> 20
        )
    };
    if meta.len() > MAX_SCENE_FILE_BYTES {
        return Err(too_big(meta.len()));
    }
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .and_then(|f| f.take(MAX_SCENE_FILE_BYTES + 1).read_to_end(&mut bytes))
        .map_err(|e| e.to_string())?;
    if bytes.len() as u64 > MAX_SCENE_FILE_BYTES {
        return Err(too_big(bytes.len() as u64));
    }
    let text = String::from_utf8(bytes).map_err(|e| {
        format!(
            "not UTF-8 text (invalid byte at offset {})",
            e.utf8_error().valid_up_to()
        )
    })?;
    Ok(match text.strip_prefix('\u{feff}') {
        Some(rest) => rest.to_string(),
        None => text,
    })
}

/// Reads an OBJ file and the MTL files it names (relative to its folder).
pub fn load_obj(path: &Path) -> Result<Scene, SceneError> {
    let text = read_text(path).map_err(|message| SceneError::Unreadable {
        path: path.to_path_buf(),
        message,
    })?;
    let dir = path.parent().unwrap_or(Path::new("")).to_path_buf();
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into());
    let resolve = |lib: &str| {
        let p = dir.join(lib);
        match read_text(&p) {
            Ok(t) => Ok((p.display().to_string(), t)),
            Err(e) => Err((p, e)),
        }
    };
    let mut scene = parse(&name, &path.display().to_string(), &text, &resolve)?;
    scene.source = Some(path.to_path_buf());
    Ok(scene)
}

/// Reads an OBJ text held in memory; `mtl` gives the text of each material
/// library by the name its `mtllib` statement uses. Messages call the OBJ
/// "`name`.obj" and each library by its name.
pub fn load_obj_str(name: &str, obj: &str, mtl: &[(&str, &str)]) -> Result<Scene, SceneError> {
    let resolve = |lib: &str| match mtl.iter().find(|(n, _)| *n == lib) {
        Some((n, t)) => Ok((n.to_string(), t.to_string())),
        None => Err((
            PathBuf::from(lib),
            "no such built-in material library".into(),
        )),
    };
    parse(name, &format!("{name}.obj"), obj, &resolve)
}

/// The texture coordinates of a face's vertices, when all have them.
type FaceUvs = Option<Vec<[f64; 2]>>;

type Resolver<'a> = dyn Fn(&str) -> Result<(String, String), (PathBuf, String)> + 'a;

fn parse(name: &str, file: &str, text: &str, resolve: &Resolver) -> Result<Scene, SceneError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let at = |line: usize| format!("{file}:{line}");
    let mut positions: Vec<DVec3> = Vec::new();
    let mut texcoords: Vec<[f64; 2]> = Vec::new();
    let mut materials: Vec<Material> = Vec::new();
    let mut by_name: HashMap<String, usize> = HashMap::new();
    let mut libs: HashMap<String, String> = HashMap::new();
    let mut group = "unnamed_object".to_string();
    let mut material: Option<usize> = None;
    let mut faces: Vec<ScanFace> = Vec::new();
    let mut warnings = Vec::new();
    let mut skipped: Vec<usize> = Vec::new();
    let mut ignored = super::ignored::Ignored::default();
    let mut copies = Copies::default();
    // What tobj reads: the same lines, trimmed, with l/p statements blanked so
    // that line-for-line structure is kept.
    let mut for_tobj = String::with_capacity(text.len());

    for (i, raw) in text.lines().enumerate() {
        let line_no = i + 1;
        let line = raw.trim();
        let mut words = line.split_whitespace();
        let keyword = words.next().unwrap_or("");
        let mut pass = true;
        match keyword {
            "v" => positions.push(parse_vertex(line, words, &at(line_no))?),
            "vt" => texcoords.push(parse_texcoord(line, words, &at(line_no))?),
            "f" => {
                let (here, group) = (&at(line_no), group.clone());
                let face = scan_face(
                    words,
                    here,
                    line_no,
                    group,
                    material,
                    (&positions, &texcoords),
                    &mut warnings,
                )?;
                // A copy of an earlier triangle is left out of what tobj reads.
                pass = copies.keep(face, &positions, &mut faces, &at);
            }
            "l" | "p" => {
                skipped.push(line_no);
                pass = false;
            }
            "g" | "o" => {
                group = rest(line, keyword).to_string();
                if group.is_empty() {
                    group = "unnamed_object".into();
                }
            }
            "mtllib" => {
                let library = (&mut materials, &mut by_name, &mut libs);
                read_mtllib(
                    rest(line, keyword),
                    resolve,
                    &at(line_no),
                    library,
                    &mut warnings,
                )?;
            }
            "usemtl" => material = Some(named(&by_name, rest(line, keyword), &at(line_no))?),
            "" => {}
            k if k.starts_with('#') => {}
            k => ignored.note(k, line_no),
        }
        if pass {
            for_tobj.push_str(line);
        }
        for_tobj.push('\n');
    }
    if let (Some(first), n) = (skipped.first(), skipped.len()) {
        warnings.push(format!(
            "{}: {n} polyline/point statement(s) (l, p) skipped: they are not surfaces",
            at(*first)
        ));
    }
    warnings.extend(ignored.warnings(file));
    let duplicates = copies.dropped();

    let (scan, w) = ((&faces[..], &positions[..], &materials[..]), &mut warnings);
    let triangles = super::tobj_match::match_tobj(file, &for_tobj, &libs, scan, w)?;
    finish(RawScene {
        name: name.into(),
        materials,
        triangles,
        camera: None,
        warnings,
        source: None,
        duplicates,
    })
}

/// The material a `usemtl` statement at `at` names.
fn named(by_name: &HashMap<String, usize>, name: &str, at: &str) -> Result<usize, SceneError> {
    by_name
        .get(name)
        .copied()
        .ok_or_else(|| SceneError::UndefinedMaterial {
            at: at.to_string(),
            name: name.into(),
        })
}

/// The face statement at `line_no` (`at`) with the vertex `words`, in
/// `group` with the current `material`; a non-planar polygon is warned about.
fn scan_face<'a>(
    words: impl Iterator<Item = &'a str>,
    at: &str,
    line_no: usize,
    group: String,
    material: Option<usize>,
    (positions, texcoords): (&[DVec3], &[[f64; 2]]),
    warnings: &mut Vec<String>,
) -> Result<ScanFace, SceneError> {
    let (vertices, uvs) = parse_face(words, positions, texcoords, at)?;
    let Some(material) = material else {
        return Err(SceneError::NoMaterial {
            at: at.to_string(),
            message: "no usemtl statement before it".into(),
        });
    };
    if let Some(w) = planarity_warning(&vertices, positions, at) {
        warnings.push(w);
    }
    Ok(ScanFace {
        line: line_no,
        group,
        material,
        vertices,
        uvs,
    })
}

/// A `vt u [v [w]]` statement: finite coordinates, stored as (u, 1 - v),
/// v down from the image's top edge as in glTF (OBJ's v points up).
fn parse_texcoord<'a>(
    line: &str,
    words: impl Iterator<Item = &'a str>,
    at: &str,
) -> Result<[f64; 2], SceneError> {
    let nums: Vec<f64> = words
        .map(|w| w.parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| {
            syntax(
                at.to_string(),
                format!("cannot parse texture coordinates '{line}'"),
            )
        })?;
    match nums[..] {
        [] => Err(syntax(
            at.to_string(),
            format!("texture coordinates need u: '{line}'"),
        )),
        _ if nums.iter().any(|x| !x.is_finite()) => Err(syntax(
            at.to_string(),
            format!("texture coordinates are not finite: '{line}'"),
        )),
        [u] => Ok([u, 1.0]),
        [u, v, ..] => Ok([u, 1.0 - v]),
    }
}

/// What the libraries read so far hold: the materials, their index by
/// name, and each library's text by the name its `mtllib` uses.
type Library<'a> = (
    &'a mut Vec<Material>,
    &'a mut HashMap<String, usize>,
    &'a mut HashMap<String, String>,
);

/// Reads the material library `lib` of an `mtllib` statement through
/// `resolve` and adds its materials to `library`. A library named again
/// adds nothing: it is read once (5 000 `mtllib` lines of one
/// 20 000-material library held 10^8 materials).
fn read_mtllib(
    lib: &str,
    resolve: &Resolver,
    at: &str,
    (materials, by_name, libs): Library<'_>,
    warnings: &mut Vec<String>,
) -> Result<(), SceneError> {
    if lib.is_empty() {
        return Err(syntax(at.to_string(), "mtllib without a file name"));
    }
    if libs.contains_key(lib) {
        return Ok(());
    }
    let (label, mtl_text) = resolve(lib).map_err(|(mtl, message)| SceneError::MaterialLibrary {
        at: at.to_string(),
        mtl,
        message,
    })?;
    let first = materials.len();
    materials.extend(super::mtl::parse_mtl(&label, &mtl_text, warnings)?);
    for (m, mat) in materials.iter().enumerate().skip(first) {
        by_name.insert(mat.name.clone(), m);
    }
    libs.insert(lib.to_string(), mtl_text);
    Ok(())
}

/// A `v x y z [w]` statement: finite coordinates, divided by w when given.
fn parse_vertex<'a>(
    line: &str,
    words: impl Iterator<Item = &'a str>,
    at: &str,
) -> Result<DVec3, SceneError> {
    let nums: Vec<f64> = words
        .map(|w| w.parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| syntax(at.to_string(), format!("cannot parse vertex '{line}'")))?;
    if nums.len() < 3 {
        return Err(syntax(
            at.to_string(),
            format!("vertex needs 3 coordinates: '{line}'"),
        ));
    }
    if let Some(&x) = nums[..3].iter().find(|x| !x.is_finite()) {
        return Err(SceneError::Vertex {
            at: at.to_string(),
            value: x,
        });
    }
    let mut v = DVec3::new(nums[0], nums[1], nums[2]);
    // A fourth number is the homogeneous weight w (tobj divides by it too).
    if nums.len() == 4 {
        if !(nums[3].is_finite() && nums[3] != 0.0) {
            return Err(SceneError::Vertex {
                at: at.to_string(),
                value: nums[3],
            });
        }
        v /= nums[3];
    }
    Ok(v)
}

/// The vertex indices of an `f` statement (1-based or negative, resolved
/// against the `positions` read so far); at least three.
/// Most vertices of one face. A face's triangles all meet its boundary, so a
/// face of many vertices is a fan of slivers, and the scene checks (T-junctions,
/// contact lines) grow with the square of its size: a circle of 20 000
/// vertices took 7.7 s to read, of 80 000 137 s.
pub const MAX_FACE_VERTICES: usize = 4096;

fn parse_face<'a>(
    words: impl Iterator<Item = &'a str>,
    positions: &[DVec3],
    texcoords: &[[f64; 2]],
    at: &str,
) -> Result<(Vec<usize>, FaceUvs), SceneError> {
    let mut vertices = Vec::new();
    let mut uvs = Some(Vec::new());
    for w in words {
        if vertices.len() == MAX_FACE_VERTICES {
            return Err(syntax(
                at.to_string(),
                format!(
                    "a face of more than {MAX_FACE_VERTICES} vertices: radcol triangulates faces of up to \
                     {MAX_FACE_VERTICES} (larger ones become slivers no mesh resolves, at a cost growing with \
                     the square of the count); split it into smaller polygons"
                ),
            ));
        }
        let first = w.split('/').next().unwrap_or("");
        let index: i64 = first
            .parse()
            .map_err(|_| syntax(at.to_string(), format!("cannot parse face index '{w}'")))?;
        let Some(resolved) = resolve(index, positions.len()) else {
            return Err(SceneError::IndexOutOfRange {
                at: at.to_string(),
                index,
                count: positions.len(),
            });
        };
        vertices.push(resolved);
        match w.split('/').nth(1).filter(|t| !t.is_empty()) {
            Some(t) => {
                let uv = texcoord(t, texcoords, at)?;
                if let Some(uvs) = &mut uvs {
                    uvs.push(uv);
                }
            }
            None => uvs = None,
        }
    }
    if vertices.len() < 3 {
        return Err(SceneError::TooFewVertices {
            at: at.to_string(),
            count: vertices.len(),
        });
    }
    Ok((vertices, uvs))
}

/// The texture coordinates of a face vertex's `vt` index `t` (1-based or
/// negative, resolved against the `texcoords` read so far).
fn texcoord(t: &str, texcoords: &[[f64; 2]], at: &str) -> Result<[f64; 2], SceneError> {
    let index: i64 = t
        .parse()
        .map_err(|_| syntax(at.to_string(), format!("cannot parse texture index '{t}'")))?;
    match resolve(index, texcoords.len()) {
        Some(i) => Ok(texcoords[i]),
        None => Err(syntax(
            at.to_string(),
            format!(
                "texture coordinate index {index} is out of range ({} vt statements before it)",
                texcoords.len()
            ),
        )),
    }
}

/// The 0-based position of an OBJ index (1-based, or negative from the
/// end) among `count` statements read so far, if it is one of them.
fn resolve(index: i64, count: usize) -> Option<usize> {
    let n = count as i64;
    let resolved = if index < 0 { n + index } else { index - 1 };
    (index != 0 && (0..n).contains(&resolved)).then_some(resolved as usize)
}

/// The warning for a polygon of more than three vertices that is not planar.
fn planarity_warning(vertices: &[usize], positions: &[DVec3], at: &str) -> Option<String> {
    if vertices.len() <= 3 {
        return None;
    }
    let p: Vec<DVec3> = vertices.iter().map(|&v| positions[v]).collect();
    non_planarity(&p).map(|off| {
        format!(
            "{at}: polygon with {} vertices is not planar (a vertex lies {off:.3e} of its diameter off its plane); triangulated in the plane of its mean normal",
            p.len()
        )
    })
}

/// The largest distance of a vertex from the polygon's plane (Newell normal
/// through the centroid) relative to its diameter, when above 1e-6.
fn non_planarity(p: &[DVec3]) -> Option<f64> {
    let n: DVec3 = (0..p.len()).map(|i| p[i].cross(p[(i + 1) % p.len()])).sum();
    let c = p.iter().sum::<DVec3>() / p.len() as f64;
    let diameter = p
        .iter()
        .flat_map(|a| p.iter().map(move |b| (*a - *b).length()))
        .fold(0.0, f64::max);
    let len = n.length();
    if len.is_nan() || len <= 0.0 || diameter <= 0.0 {
        // Collinear polygons are degenerate: the triangle checks report them.
        return None;
    }
    let off = p
        .iter()
        .map(|v| ((*v - c).dot(n / len)).abs())
        .fold(0.0, f64::max)
        / diameter;
    (off > 1e-6).then_some(off)
}
