//! tobj's reading of an OBJ, matched against radcol's line scan (see
//! [`super::obj`]): polygon by polygon, the same group, material and
//! positions, then each polygon triangulated ([`super::polygon`]).

use super::raw::{Capped, RawTriangle};
use super::scan::ScanFace;
use super::{Material, SceneError, TriangleOrigin};
use glam::DVec3;
use std::collections::HashMap;

/// tobj's models and materials of the scanned `text`, its libraries read
/// from `libs`.
fn run_tobj(
    file: &str,
    text: &str,
    libs: &HashMap<String, String>,
) -> Result<(Vec<tobj::Model>, Vec<tobj::Material>), SceneError> {
    let reader_error = |message: String| SceneError::Reader {
        at: file.into(),
        message,
    };
    // More fields exist when tobj's optional features are on, hence the update.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: false,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    // A library named again gives nothing new (as in the line scan): tobj
    // would parse it once per mtllib line.
    let read = std::cell::RefCell::new(std::collections::HashSet::new());
    let (models, materials) = tobj::load_obj_buf(&mut text.as_bytes(), &options, |p| {
        let name = p.to_string_lossy().into_owned();
        if !read.borrow_mut().insert(name.clone()) {
            return Ok((Vec::new(), Default::default()));
        }
        match libs.get(&name) {
            Some(t) => tobj::load_mtl_buf(&mut t.as_bytes()),
            None => Err(tobj::LoadError::OpenFileFailed),
        }
    })
    .map_err(|e| reader_error(e.to_string()))?;
    Ok((models, materials.map_err(|e| reader_error(e.to_string()))?))
}

/// Runs tobj on the scanned text and pairs its polygons, in order, with the
/// scanned faces, checking group, material and positions; then triangulates
/// each face ([`super::polygon`]), warning about self-intersecting ones.
pub(super) fn match_tobj(
    file: &str,
    text: &str,
    libs: &HashMap<String, String>,
    (faces, positions, materials): (&[ScanFace], &[DVec3], &[Material]),
    warnings: &mut Vec<String>,
) -> Result<Vec<RawTriangle>, SceneError> {
    let reader_error = |at: String, message: String| SceneError::Reader { at, message };
    let (models, tobj_materials) = run_tobj(file, text, libs)?;

    let mut expected = faces.iter();
    let mut out = Vec::new();
    let mut crossing = Capped::new(warnings, "self-intersecting-polygon");
    for model in &models {
        let mesh = &model.mesh;
        let mat_name = mesh
            .material_id
            .and_then(|id| tobj_materials.get(id))
            .map(|m| m.name.as_str());
        let arities: Vec<usize> = if mesh.face_arities.is_empty() {
            vec![3; mesh.indices.len() / 3]
        } else {
            mesh.face_arities.iter().map(|&a| a as usize).collect()
        };
        let mut first = 0;
        for arity in arities {
            let polygon = &mesh.indices[first..first + arity];
            first += arity;
            let Some(face) = expected.next() else {
                return Err(reader_error(
                    file.into(),
                    format!(
                        "tobj read more faces than the file has (group '{}')",
                        model.name
                    ),
                ));
            };
            let at = format!("{file}:{}", face.line);
            if model.name != face.group || mat_name != Some(materials[face.material].name.as_str())
            {
                return Err(reader_error(
                    at,
                    format!(
                        "tobj assigns this face to group '{}' material {:?}, the line scan to '{}' material '{}'",
                        model.name, mat_name, face.group, materials[face.material].name
                    ),
                ));
            }
            let points: Vec<DVec3> = face.vertices.iter().map(|&v| positions[v]).collect();
            check_agrees(&mesh.positions, polygon, &points, &at)?;
            let t = super::polygon::triangulate(&points);
            if t.self_intersecting.is_some() {
                crossing.push(format!(
                    "{at}: the polygon's edges cross each other; its triangulation is one of several readings, \
                     split it into simple polygons"
                ));
            }
            for [a, b, c] in t.triangles {
                out.push(RawTriangle {
                    group: face.group.clone(),
                    material: face.material,
                    vertices: [points[a], points[b], points[c]],
                    at: at.clone(),
                    uv: face.uvs.as_ref().map(|u| [u[a], u[b], u[c]]),
                    origin: TriangleOrigin {
                        input: out.len(),
                        vertices: [a, b, c].map(|k| face.vertices[k] as u32),
                        corners: [points[a], points[b], points[c]],
                        at: at.clone(),
                    },
                });
            }
        }
    }
    if let Some(face) = expected.next() {
        return Err(reader_error(
            format!("{file}:{}", face.line),
            "tobj read fewer faces than the file has".into(),
        ));
    }
    drop(crossing);
    Ok(out)
}

/// tobj's single-precision positions of a polygon's vertices agree with the
/// line scan's (to f32's precision, subnormal ones included).
fn check_agrees(
    tobj_positions: &[f32],
    polygon: &[u32],
    ours: &[DVec3],
    at: &str,
) -> Result<(), SceneError> {
    if polygon.len() != ours.len() {
        return Err(SceneError::Reader {
            at: at.into(),
            message: format!(
                "tobj reads {} vertices in this face, the line scan {}",
                polygon.len(),
                ours.len()
            ),
        });
    }
    for (c, (&ti, p)) in polygon.iter().zip(ours).enumerate() {
        let theirs = &tobj_positions[3 * ti as usize..3 * ti as usize + 3];
        let ours = p.to_array();
        let agree = (0..3).all(|d| {
            let diff = (theirs[d] as f64 - ours[d]).abs();
            diff <= 1e-6 * ours[d].abs() || diff <= f32::MIN_POSITIVE as f64
        });
        if !agree {
            return Err(SceneError::Reader {
                at: at.into(),
                message: format!(
                    "tobj (single precision) reads vertex {} of this face as ({:e}, {:e}, {:e}), the line scan as ({:e}, {:e}, {:e})",
                    c + 1,
                    theirs[0],
                    theirs[1],
                    theirs[2],
                    ours[0],
                    ours[1],
                    ours[2]
                ),
            });
        }
    }
    Ok(())
}
