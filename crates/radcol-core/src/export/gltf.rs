//! glTF 2.0 meshes for engines: one node and mesh per input object (an OBJ
//! group, a glTF node of the input), each one triangle primitive with
//! POSITION, NORMAL, COLOR_0 and UNSIGNED_INT indices, under a root node
//! named after the scene whose scale turns scene units into metres (glTF's
//! unit): the positions keep the input's own units. Every primitive uses one
//! `KHR_materials_unlit` material, the form baked lighting ships in: a viewer
//! shows the vertex colours as they are instead of lighting them again (its
//! fallback for viewers without the extension is a rough, non-metallic white).
//!
//! Two containers: binary `.glb` ([`write_glb`]) and a single self-contained
//! `.gltf` whose buffer is an embedded base64 data URI ([`write_gltf`]; one file
//! to copy around, at 4/3 the size of the binary data).
//!
//! Layout of the one buffer, object after object: positions, normals, colours
//! (f32 VEC3 each, tightly packed, one bufferView each, so no byteStride is
//! needed), then the indices. Every section is a multiple of 4 bytes, so every
//! bufferView and accessor is 4-byte aligned as the spec requires. POSITION
//! carries min/max (required by the spec); COLOR_0 holds display-referred
//! *linear* values in [0, 1]: the radiance tone-mapped as for images, without
//! the sRGB encoding (glTF vertex colours are linear; viewers encode on output).

use super::{Context, Result};
use crate::mesh::Mesh;
use crate::render::{ToneMap, VertexMesh};
use base64::engine::general_purpose::STANDARD;
use base64::Engine;
use serde_json::{json, Value};
use std::io::Write;

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;

/// How the vertex mesh's triangles group into the input's objects, and the
/// scene's name and unit.
#[derive(Clone, Debug, PartialEq)]
pub struct Layout {
    /// The scene's name (the root node's).
    pub scene: String,
    /// Metres per scene unit (the root node's scale).
    pub metres_per_unit: f64,
    /// Object names, in the order of their nodes.
    pub objects: Vec<String>,
    /// Per element of the mesh: its object.
    pub object_of_element: Vec<u32>,
    /// Per patch of the surface: its object.
    pub object_of_patch: Vec<u32>,
}

impl Layout {
    /// One object holding every element.
    pub fn single(scene: &str, elements: usize) -> Self {
        Self {
            scene: scene.to_string(),
            metres_per_unit: 1.0,
            objects: vec![scene.to_string()],
            object_of_element: vec![0; elements],
            object_of_patch: Vec::new(),
        }
    }
}

impl Layout {
    /// The nodes of `mesh`'s scene: with `by_object`, one per object (a
    /// patch name's group, the part before '/': an OBJ group, a glTF node of
    /// the input), in the order they first appear; else one. `scene` names
    /// the root node, scaled by `metres_per_unit`.
    pub fn of_mesh(mesh: &Mesh, scene: &str, metres_per_unit: f64, by_object: bool) -> Self {
        let mut layout = Self::single(scene, mesh.len());
        layout.metres_per_unit = metres_per_unit;
        let patches = &mesh.surface().patches;
        if !by_object {
            layout.object_of_patch = vec![0; patches.len()];
            return layout;
        }
        layout.objects.clear();
        let object_of_patch: Vec<u32> = patches
            .iter()
            .map(|p| {
                let group = p.name.split('/').next().unwrap_or(&p.name).to_string();
                match layout.objects.iter().position(|o| *o == group) {
                    Some(i) => i as u32,
                    None => {
                        layout.objects.push(group);
                        (layout.objects.len() - 1) as u32
                    }
                }
            })
            .collect();
        layout.object_of_element = (mesh.elements().iter())
            .map(|e| object_of_patch[e.patch as usize])
            .collect();
        layout.object_of_patch = object_of_patch;
        layout
    }
}

/// One object's part of the vertex mesh, its vertices renumbered.
struct Part {
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    colors: Vec<[f32; 3]>,
    indices: Vec<u32>,
}

/// The vertex mesh cut into `layout`'s objects (objects without triangles
/// are left out, with their names).
fn parts(mesh: &VertexMesh, colors: &[[f32; 3]], layout: &Layout) -> Result<Vec<(String, Part)>> {
    let mut parts: Vec<Option<Part>> = (0..layout.objects.len()).map(|_| None).collect();
    let mut new_index = vec![u32::MAX; mesh.positions.len()];
    for (t, tri) in mesh.indices.chunks_exact(3).enumerate() {
        let e = mesh.element[t] as usize;
        let Some(&o) = layout.object_of_element.get(e) else {
            bail!("glTF: element {e} of triangle {t} has no object");
        };
        let part = parts[o as usize].get_or_insert_with(|| Part {
            positions: Vec::new(),
            normals: Vec::new(),
            colors: Vec::new(),
            indices: Vec::new(),
        });
        for &v in tri {
            let v = v as usize;
            // Elements' vertices are their own (u_n is discontinuous), so a
            // vertex belongs to one object: renumber it on first use.
            if new_index[v] == u32::MAX {
                new_index[v] = part.positions.len() as u32;
                part.positions.push(mesh.positions[v]);
                part.normals.push(mesh.normals[v]);
                part.colors.push(colors[v]);
            }
            part.indices.push(new_index[v]);
        }
    }
    Ok(layout
        .objects
        .iter()
        .cloned()
        .zip(parts)
        .filter_map(|(name, p)| p.map(|p| (name, p)))
        .collect())
}

/// The glTF JSON (buffer 0 with `uri` when given) and the binary buffer.
fn document(
    mesh: &VertexMesh,
    tm: &ToneMap,
    layout: &Layout,
    uri: Option<String>,
) -> Result<(Value, Vec<u8>)> {
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
    let mut bin = Vec::with_capacity(nv * 36 + mesh.indices.len() * 4);
    let (mut views, mut accessors, mut meshes, mut nodes) = (vec![], vec![], vec![], vec![]);
    let mut view = |bin: &mut Vec<u8>, offset: usize, target: u32| {
        views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": bin.len() - offset, "target": target}));
        views.len() - 1
    };
    for (name, part) in parts(mesh, &colors, layout)? {
        let n = part.positions.len();
        let (min, max) = position_bounds(&part.positions);
        let first = accessors.len();
        for (i, section) in [&part.positions, &part.normals, &part.colors]
            .into_iter()
            .enumerate()
        {
            let offset = bin.len();
            for x in section.as_flattened() {
                bin.extend_from_slice(&x.to_le_bytes());
            }
            let v = view(&mut bin, offset, ARRAY_BUFFER);
            let mut a =
                json!({"bufferView": v, "componentType": FLOAT, "count": n, "type": "VEC3"});
            if i == 0 {
                a["min"] = json!(min);
                a["max"] = json!(max);
            }
            accessors.push(a);
        }
        let offset = bin.len();
        for i in &part.indices {
            bin.extend_from_slice(&i.to_le_bytes());
        }
        let v = view(&mut bin, offset, ELEMENT_ARRAY_BUFFER);
        accessors.push(json!({"bufferView": v, "componentType": UNSIGNED_INT, "count": part.indices.len(), "type": "SCALAR"}));
        meshes.push(json!({"name": name, "primitives": [{
            "attributes": {"POSITION": first, "NORMAL": first + 1, "COLOR_0": first + 2},
            "indices": first + 3,
            "material": 0,
            "mode": 4
        }]}));
        nodes.push(json!({"mesh": meshes.len() - 1, "name": name}));
    }
    let root = root_node(layout, nodes.len())?;
    nodes.insert(0, root);
    let mut buffer = json!({"byteLength": bin.len()});
    if let Some(uri) = uri {
        buffer["uri"] = json!(uri);
    }
    let doc = json!({
        "asset": {"version": "2.0", "generator": concat!("radcol ", env!("CARGO_PKG_VERSION"))},
        "extensionsUsed": ["KHR_materials_unlit"],
        "scene": 0,
        "scenes": [{"name": layout.scene, "nodes": [0]}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": [{
            "name": "radiosity (unlit vertex colours)",
            "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.9},
            "extensions": {"KHR_materials_unlit": {}}
        }],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [buffer]
    });
    Ok((doc, bin))
}

/// Writes `mesh` as a binary glTF (GLB).
pub fn write_glb<W: Write>(w: W, mesh: &VertexMesh, tm: &ToneMap, layout: &Layout) -> Result<()> {
    let (doc, bin) = document(mesh, tm, layout, None)?;
    frame_glb(w, &doc, bin)
}

/// Writes `mesh` as one self-contained `.gltf` JSON file.
pub fn write_gltf<W: Write>(w: W, mesh: &VertexMesh, tm: &ToneMap, layout: &Layout) -> Result<()> {
    let (doc, bin) = document(mesh, tm, layout, None)?;
    embed_gltf(w, doc, &bin)
}

/// A document and its buffer as GLB: 12-byte header, a JSON chunk padded
/// with spaces and a BIN chunk padded with zeros, both to 4 bytes.
pub(super) fn frame_glb<W: Write>(mut w: W, doc: &Value, mut bin: Vec<u8>) -> Result<()> {
    let mut json = serde_json::to_vec(doc).context("glTF: encoding the JSON")?;
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
    w.write_all(&out).context("glTF: writing")?;
    w.flush().context("glTF: writing")?;
    Ok(())
}

/// A document as one `.gltf` JSON file, its buffer embedded as a
/// `data:application/octet-stream;base64,` URI.
pub(super) fn embed_gltf<W: Write>(mut w: W, mut doc: Value, bin: &[u8]) -> Result<()> {
    doc["buffers"][0]["uri"] = json!(format!(
        "data:application/octet-stream;base64,{}",
        STANDARD.encode(bin)
    ));
    serde_json::to_writer_pretty(&mut w, &doc).context("glTF: writing")?;
    w.write_all(b"\n").context("glTF: writing")?;
    w.flush().context("glTF: writing")?;
    Ok(())
}

/// POSITION's min and max, which the spec requires.
pub(super) fn position_bounds(positions: &[[f32; 3]]) -> ([f32; 3], [f32; 3]) {
    let mut min = [f32::INFINITY; 3];
    let mut max = [f32::NEG_INFINITY; 3];
    for p in positions {
        for c in 0..3 {
            min[c] = min[c].min(p[c]);
            max[c] = max[c].max(p[c]);
        }
    }
    (min, max)
}

/// The scene's root node over `children` nodes (1..=children), scaled to
/// metres.
pub(super) fn root_node(layout: &Layout, children: usize) -> Result<Value> {
    let s = layout.metres_per_unit;
    if !(s.is_finite() && s > 0.0) {
        bail!("glTF: metres per scene unit must be positive and finite, not {s}");
    }
    let mut root = json!({"name": layout.scene, "children": (1..=children).collect::<Vec<_>>()});
    if s != 1.0 {
        root["scale"] = json!([s, s, s]);
    }
    Ok(root)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::export::ply::tests::tiny;
    use crate::render::{srgb_decode, ToneOperator};
    use ::gltf::accessor::{DataType, Dimensions};

    fn tm() -> ToneMap {
        ToneMap {
            exposure: 0.0,
            operator: ToneOperator::Linear,
            auto: false,
        }
    }

    fn one() -> Layout {
        Layout::single("tiny", 2)
    }

    /// Two objects: a node and a mesh each, with their own vertices
    /// (renumbered from 0), under a root that scales millimetres to metres.
    #[test]
    fn one_node_per_object_under_a_scaled_root() {
        let layout = Layout {
            scene: "box".into(),
            metres_per_unit: 1e-3,
            objects: vec!["floor".into(), "unused".into(), "light".into()],
            object_of_element: vec![2, 0],
            object_of_patch: Vec::new(),
        };
        let mut bytes = Vec::new();
        write_glb(&mut bytes, &tiny(), &tm(), &layout).unwrap();
        let (doc, buffers, _) = ::gltf::import_slice(&bytes).unwrap();
        let root = doc.scenes().next().unwrap().nodes().next().unwrap();
        assert_eq!(root.transform().decomposed().2, [1e-3, 1e-3, 1e-3]);
        let children: Vec<_> = root
            .children()
            .map(|n| n.name().unwrap().to_string())
            .collect();
        // In the layout's order, the object without triangles left out.
        assert_eq!(children, ["floor", "light"]);
        for (node, first) in root.children().zip([[1.0, 0.0, 0.0], [0.0, 0.0, 0.0]]) {
            let prim = node.mesh().unwrap().primitives().next().unwrap();
            assert!(prim.material().unlit());
            let reader = prim.reader(|b| Some(&buffers[b.index()]));
            let p: Vec<[f32; 3]> = reader.read_positions().unwrap().collect();
            assert_eq!((p.len(), p[0]), (3, first));
            let i: Vec<u32> = reader.read_indices().unwrap().into_u32().collect();
            assert_eq!(i, [0, 1, 2]);
        }
    }

    /// RFC 4648 test vectors.
    /// Reads a file back with the gltf crate (validating) and checks structure and data.
    fn check(bytes: &[u8]) {
        let parsed = ::gltf::Gltf::from_slice(bytes).unwrap();
        assert_eq!(parsed.meshes().count(), 1);
        assert_eq!(parsed.scenes().count(), 1);
        // The root (the scene, no scale at 1 m per unit) and the object.
        assert_eq!(parsed.nodes().count(), 2);
        let root = parsed.scenes().next().unwrap().nodes().next().unwrap();
        assert_eq!(root.name(), Some("tiny"));
        assert_eq!(root.transform().decomposed().2, [1.0, 1.0, 1.0]);
        assert_eq!(root.children().count(), 1);
        assert_eq!(
            parsed.extensions_used().collect::<Vec<_>>(),
            ["KHR_materials_unlit"]
        );
        let material = parsed.materials().next().unwrap();
        assert!(material.unlit());
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
            crate::assert_close!(c[1][k] as f64, want[k], 1e-7);
        }
        // The PLY's 8-bit sRGB blue (209) decodes to the same linear colour to within a code.
        crate::assert_close!(srgb_decode(209.0 / 255.0), c[1][2] as f64, 0.005);
        let i: Vec<u32> = reader.read_indices().unwrap().into_u32().collect();
        assert_eq!(i, [0, 1, 2, 3, 4, 5]);
    }

    #[test]
    fn glb_round_trip_and_layout() {
        let mut bytes = Vec::new();
        write_glb(&mut bytes, &tiny(), &tm(), &one()).unwrap();
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
        write_gltf(&mut bytes, &tiny(), &tm(), &one()).unwrap();
        assert!(std::str::from_utf8(&bytes)
            .unwrap()
            .contains("\"version\": \"2.0\""));
        check(&bytes);
    }

    #[test]
    fn rejects_bad_meshes() {
        assert!(write_glb(Vec::new(), &VertexMesh::default(), &tm(), &one()).is_err());
        let mut bad = tiny();
        bad.indices[5] = 17;
        let err = write_glb(Vec::new(), &bad, &tm(), &one()).unwrap_err();
        assert!(
            err.to_string().contains("index 5 (triangle 1) = 17"),
            "{err}"
        );
    }
}
