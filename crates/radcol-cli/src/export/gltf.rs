//! glTF 2.0 meshes: one mesh, one triangle primitive with POSITION, NORMAL,
//! COLOR_0 and UNSIGNED_INT indices, in one scene with one node.
//!
//! Two containers: binary `.glb` ([`write_glb`]) and a single self-contained
//! `.gltf` whose buffer is an embedded base64 data URI ([`write_gltf`]; one file
//! to copy around, at 4/3 the size of the binary data).
//!
//! Layout of the one buffer: positions, normals, colours (f32 VEC3 each, tightly
//! packed, one bufferView each, so no byteStride is needed), then the indices.
//! Every section is a multiple of 4 bytes, so every bufferView and accessor is
//! 4-byte aligned as the spec requires. POSITION carries min/max (required by
//! the spec); COLOR_0 holds display-referred *linear* values in [0, 1]: the
//! radiance tone-mapped as for images, without the sRGB encoding (glTF vertex
//! colours are linear; viewers encode on output).

use anyhow::{bail, Result};
use base64::engine::general_purpose::STANDARD;
use base64::Engine;
use radcol_core::render::{ToneMap, VertexMesh};
use serde_json::{json, Value};
use std::io::Write;

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;

/// The glTF JSON (buffer 0 with `uri` when given) and the binary buffer.
fn document(mesh: &VertexMesh, tm: &ToneMap, uri: Option<String>) -> Result<(Value, Vec<u8>)> {
    let nv = mesh.positions.len();
    if nv == 0 || mesh.indices.is_empty() {
        bail!("glTF: the vertex mesh is empty (accessors need at least one element)");
    }
    super::check_vertex_mesh("glTF", mesh, u32::MAX)?;
    if let Some((i, p)) = mesh
        .positions
        .iter()
        .enumerate()
        .find(|(_, p)| !p.iter().all(|x| x.is_finite()))
    {
        bail!("glTF: vertex {i} has a non-finite position {p:?}");
    }
    let colors = mesh.linear_colors(tm);
    let mut min = [f32::INFINITY; 3];
    let mut max = [f32::NEG_INFINITY; 3];
    for p in &mesh.positions {
        for c in 0..3 {
            min[c] = min[c].min(p[c]);
            max[c] = max[c].max(p[c]);
        }
    }
    let mut bin = Vec::with_capacity(nv * 36 + mesh.indices.len() * 4);
    let mut views = Vec::new();
    for (section, target) in [
        (&mesh.positions, ARRAY_BUFFER),
        (&mesh.normals, ARRAY_BUFFER),
        (&colors, ARRAY_BUFFER),
    ] {
        let offset = bin.len();
        for x in section.as_flattened() {
            bin.extend_from_slice(&x.to_le_bytes());
        }
        views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": bin.len() - offset, "target": target}));
    }
    let offset = bin.len();
    for i in &mesh.indices {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": bin.len() - offset, "target": ELEMENT_ARRAY_BUFFER}));
    let mut buffer = json!({"byteLength": bin.len()});
    if let Some(uri) = uri {
        buffer["uri"] = json!(uri);
    }
    let doc = json!({
        "asset": {"version": "2.0", "generator": concat!("radcol ", env!("CARGO_PKG_VERSION"))},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": "radiosity"}],
        "meshes": [{"name": "radiosity", "primitives": [{
            "attributes": {"POSITION": 0, "NORMAL": 1, "COLOR_0": 2},
            "indices": 3,
            "mode": 4
        }]}],
        "accessors": [
            {"bufferView": 0, "componentType": FLOAT, "count": nv, "type": "VEC3", "min": min, "max": max},
            {"bufferView": 1, "componentType": FLOAT, "count": nv, "type": "VEC3"},
            {"bufferView": 2, "componentType": FLOAT, "count": nv, "type": "VEC3"},
            {"bufferView": 3, "componentType": UNSIGNED_INT, "count": mesh.indices.len(), "type": "SCALAR"}
        ],
        "bufferViews": views,
        "buffers": [buffer]
    });
    Ok((doc, bin))
}

/// Writes `mesh` as a binary glTF (GLB): 12-byte header, a JSON chunk padded with
/// spaces and a BIN chunk padded with zeros, both to 4 bytes.
pub fn write_glb<W: Write>(mut w: W, mesh: &VertexMesh, tm: &ToneMap) -> Result<()> {
    let (doc, mut bin) = document(mesh, tm, None)?;
    let mut json = serde_json::to_vec(&doc)?;
    json.resize(json.len().next_multiple_of(4), b' ');
    bin.resize(bin.len().next_multiple_of(4), 0);
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let Ok(total) = u32::try_from(total) else {
        bail!("glTF: {total} bytes exceed the 4 GiB limit of GLB");
    };
    let mut out = Vec::with_capacity(total as usize);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&total.to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    w.write_all(&out)?;
    w.flush()?;
    Ok(())
}

/// Writes `mesh` as one self-contained `.gltf` JSON file, the buffer embedded as
/// a `data:application/octet-stream;base64,` URI.
pub fn write_gltf<W: Write>(mut w: W, mesh: &VertexMesh, tm: &ToneMap) -> Result<()> {
    let (mut doc, bin) = document(mesh, tm, None)?;
    doc["buffers"][0]["uri"] = json!(format!(
        "data:application/octet-stream;base64,{}",
        STANDARD.encode(&bin)
    ));
    serde_json::to_writer_pretty(&mut w, &doc)?;
    w.write_all(b"\n")?;
    w.flush()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::export::ply::tests::tiny;
    use ::gltf::accessor::{DataType, Dimensions};
    use radcol_core::render::{srgb_decode, ToneOperator};

    fn tm() -> ToneMap {
        ToneMap {
            exposure: 0.0,
            operator: ToneOperator::Linear,
            auto: false,
        }
    }

    /// RFC 4648 test vectors.
    /// Reads a file back with the gltf crate (validating) and checks structure and data.
    fn check(bytes: &[u8]) {
        let parsed = ::gltf::Gltf::from_slice(bytes).unwrap();
        assert_eq!(parsed.meshes().count(), 1);
        assert_eq!(parsed.scenes().count(), 1);
        assert_eq!(parsed.nodes().count(), 1);
        let (doc, buffers, _) = ::gltf::import_slice(bytes).unwrap();
        let prim = doc.meshes().next().unwrap().primitives().next().unwrap();
        assert_eq!(prim.mode(), ::gltf::mesh::Mode::Triangles);
        let pos = prim.get(&::gltf::Semantic::Positions).unwrap();
        assert_eq!(
            (pos.count(), pos.data_type(), pos.dimensions()),
            (6, DataType::F32, Dimensions::Vec3)
        );
        assert_eq!(pos.min().unwrap(), json!([0.0, 0.0, -0.5]));
        assert_eq!(pos.max().unwrap(), json!([1.0, 1.0, 0.0]));
        let col = prim.get(&::gltf::Semantic::Colors(0)).unwrap();
        assert_eq!(
            (col.data_type(), col.dimensions()),
            (DataType::F32, Dimensions::Vec3)
        );
        let idx = prim.indices().unwrap();
        assert_eq!((idx.count(), idx.data_type()), (6, DataType::U32));
        for a in doc.accessors() {
            let v = a.view().unwrap();
            assert_eq!((a.offset() + v.offset()) % 4, 0);
            assert!(v.stride().is_none());
        }
        let reader = prim.reader(|b| Some(&buffers[b.index()]));
        let p: Vec<[f32; 3]> = reader.read_positions().unwrap().collect();
        assert_eq!(p[4], [1.0, 1.0, -0.5]);
        let n: Vec<[f32; 3]> = reader.read_normals().unwrap().collect();
        assert_eq!(n[2], [0.0, 0.0, 1.0]);
        let c: Vec<[f32; 3]> = reader.read_colors(0).unwrap().into_rgb_f32().collect();
        // Vertex 1: radiosity (π, 0.5, 2) is radiance (1, 0.5/π, 2/π), clamped linearly.
        let want = [1.0, 0.5 / std::f64::consts::PI, 2.0 / std::f64::consts::PI];
        for k in 0..3 {
            radcol_core::assert_close!(c[1][k] as f64, want[k], 1e-7);
        }
        // The PLY's 8-bit sRGB blue (209) decodes to the same linear colour to within a code.
        radcol_core::assert_close!(srgb_decode(209.0 / 255.0), c[1][2] as f64, 0.005);
        let i: Vec<u32> = reader.read_indices().unwrap().into_u32().collect();
        assert_eq!(i, [0, 1, 2, 3, 4, 5]);
    }

    #[test]
    fn glb_round_trip_and_layout() {
        let mut bytes = Vec::new();
        write_glb(&mut bytes, &tiny(), &tm()).unwrap();
        check(&bytes);
        // Header and chunk framing by hand.
        assert_eq!(&bytes[0..4], b"glTF");
        assert_eq!(u32::from_le_bytes(bytes[4..8].try_into().unwrap()), 2);
        assert_eq!(
            u32::from_le_bytes(bytes[8..12].try_into().unwrap()) as usize,
            bytes.len()
        );
        let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
        assert_eq!(json_len % 4, 0);
        assert_eq!(&bytes[16..20], b"JSON");
        let json = &bytes[20..20 + json_len];
        assert!(json.ends_with(b"}") || json.ends_with(b" "));
        let bin_at = 20 + json_len;
        let bin_len = u32::from_le_bytes(bytes[bin_at..bin_at + 4].try_into().unwrap()) as usize;
        assert_eq!(bin_len % 4, 0);
        assert_eq!(&bytes[bin_at + 4..bin_at + 8], b"BIN\0");
        // 6 vertices × 3 attributes × 12 bytes + 6 indices × 4 bytes.
        assert_eq!(bin_len, 6 * 36 + 24);
        assert_eq!(bin_at + 8 + bin_len, bytes.len());
    }

    #[test]
    fn gltf_round_trip() {
        let mut bytes = Vec::new();
        write_gltf(&mut bytes, &tiny(), &tm()).unwrap();
        assert!(std::str::from_utf8(&bytes)
            .unwrap()
            .contains("\"version\": \"2.0\""));
        check(&bytes);
    }

    #[test]
    fn rejects_bad_meshes() {
        assert!(write_glb(Vec::new(), &VertexMesh::default(), &tm()).is_err());
        let mut bad = tiny();
        bad.indices[5] = 17;
        let err = write_glb(Vec::new(), &bad, &tm()).unwrap_err();
        assert!(
            err.to_string().contains("index 5 (triangle 1) = 17"),
            "{err}"
        );
    }
}
