//! glTF 2.0 with a lightmap: the scene's own triangles (not radcol's
//! refinement) with TEXCOORD_0 into the lightmap atlas
//! ([`crate::render::lightmap`]), the atlas as an embedded PNG, and
//! one `KHR_materials_unlit` material whose base colour texture it is. One
//! node and mesh per object under the scene's root, as [`super::gltf`]
//! writes the vertex-colour mesh.

use super::gltf::{embed_gltf, frame_glb, position_bounds, root_node, Layout};
use super::Result;
use crate::geometry::Surface;
use crate::render::lightmap::Atlas;
use glam::DVec3;
use serde_json::{json, Value};
use std::io::Write;

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;
const LINEAR: u32 = 9729;
const CLAMP_TO_EDGE: u32 = 33071;

/// What the lightmapped glTF is made of.
#[derive(Debug)]
pub struct Lightmapped<'a> {
    /// The scene's triangles.
    pub surface: &'a Surface,
    /// Their charts in the atlas.
    pub atlas: &'a Atlas,
    /// The atlas, tone-mapped, as PNG bytes.
    pub png: &'a [u8],
    /// Scene name, unit and objects ([`Layout::objects`]).
    pub layout: &'a Layout,
    /// Per patch: its object.
    pub object_of_patch: &'a [u32],
}

/// One object's triangles: positions, normals, texture coordinates.
#[derive(Default)]
struct Part {
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    uvs: Vec<[f32; 2]>,
}

fn f32x3(v: DVec3) -> [f32; 3] {
    [v.x as f32, v.y as f32, v.z as f32]
}

/// The scene's triangles by object, with their texture coordinates.
fn parts(l: &Lightmapped<'_>) -> Result<Vec<Part>> {
    let mut parts: Vec<Part> = (0..l.layout.objects.len())
        .map(|_| Part::default())
        .collect();
    for chart in &l.atlas.charts {
        let patch = &l.surface.patches[chart.patch];
        let Some(&o) = l.object_of_patch.get(chart.patch) else {
            bail!("glTF: patch {} has no object", chart.patch);
        };
        let part = &mut parts[o as usize];
        for &t in &chart.triangles {
            let v = patch.triangles[t].map(|x| patch.map.map(x));
            let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
            for x in v {
                part.positions.push(f32x3(x));
                part.normals.push(f32x3(n));
                part.uvs.push(l.atlas.uv_on(chart, t, x));
            }
        }
    }
    Ok(parts)
}

/// The document and its buffer.
fn document(l: &Lightmapped<'_>) -> Result<(Value, Vec<u8>)> {
    let parts = parts(l)?;
    let mut bin: Vec<u8> = Vec::new();
    let (mut views, mut accessors, mut meshes, mut nodes) = (vec![], vec![], vec![], vec![]);
    let mut push_view = |bin: &mut Vec<u8>, bytes: &[u8], target: Option<u32>| {
        let offset = bin.len();
        bin.extend_from_slice(bytes);
        let mut v = json!({"buffer": 0, "byteOffset": offset, "byteLength": bytes.len()});
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        // Keep every later view 4-byte aligned.
        bin.resize(bin.len().next_multiple_of(4), 0);
        views.push(v);
        views.len() - 1
    };
    for (name, part) in l.layout.objects.iter().zip(&parts) {
        let n = part.positions.len();
        if n == 0 {
            continue;
        }
        let (min, max) = position_bounds(&part.positions);
        let le = |xs: &[f32]| xs.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
        let first = accessors.len();
        let pos = push_view(
            &mut bin,
            &le(part.positions.as_flattened()),
            Some(ARRAY_BUFFER),
        );
        accessors.push(json!({"bufferView": pos, "componentType": FLOAT, "count": n, "type": "VEC3", "min": min, "max": max}));
        let nrm = push_view(
            &mut bin,
            &le(part.normals.as_flattened()),
            Some(ARRAY_BUFFER),
        );
        accessors
            .push(json!({"bufferView": nrm, "componentType": FLOAT, "count": n, "type": "VEC3"}));
        let uv = push_view(&mut bin, &le(part.uvs.as_flattened()), Some(ARRAY_BUFFER));
        accessors
            .push(json!({"bufferView": uv, "componentType": FLOAT, "count": n, "type": "VEC2"}));
        let indices: Vec<u8> = (0..n as u32).flat_map(|i| i.to_le_bytes()).collect();
        let idx = push_view(&mut bin, &indices, Some(ELEMENT_ARRAY_BUFFER));
        accessors.push(
            json!({"bufferView": idx, "componentType": UNSIGNED_INT, "count": n, "type": "SCALAR"}),
        );
        meshes.push(json!({"name": name, "primitives": [{
            "attributes": {"POSITION": first, "NORMAL": first + 1, "TEXCOORD_0": first + 2},
            "indices": first + 3,
            "material": 0,
            "mode": 4
        }]}));
        nodes.push(json!({"mesh": meshes.len() - 1, "name": name}));
    }
    if meshes.is_empty() {
        bail!("glTF: the scene has no triangle to write");
    }
    let image = push_view(&mut bin, l.png, None);
    nodes.insert(0, root_node(l.layout, meshes.len())?);
    let doc = json!({
        "asset": {"version": "2.0", "generator": concat!("radcol ", env!("CARGO_PKG_VERSION"))},
        "extensionsUsed": ["KHR_materials_unlit"],
        "scene": 0,
        "scenes": [{"name": l.layout.scene, "nodes": [0]}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": [{
            "name": "radiosity (unlit lightmap)",
            "pbrMetallicRoughness": {
                "baseColorFactor": [1.0, 1.0, 1.0, 1.0],
                "baseColorTexture": {"index": 0},
                "metallicFactor": 0.0,
                "roughnessFactor": 0.9
            },
            "extensions": {"KHR_materials_unlit": {}}
        }],
        "textures": [{"sampler": 0, "source": 0}],
        "samplers": [{"magFilter": LINEAR, "minFilter": LINEAR, "wrapS": CLAMP_TO_EDGE, "wrapT": CLAMP_TO_EDGE}],
        "images": [{"bufferView": image, "mimeType": "image/png", "name": "lightmap"}],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": bin.len()}]
    });
    Ok((doc, bin))
}

/// Writes the lightmapped scene as GLB.
pub fn write_glb<W: Write>(w: W, l: &Lightmapped<'_>) -> Result<()> {
    let (doc, bin) = document(l)?;
    frame_glb(w, &doc, bin)
}

/// Writes the lightmapped scene as one self-contained `.gltf`.
pub fn write_gltf<W: Write>(w: W, l: &Lightmapped<'_>) -> Result<()> {
    let (doc, bin) = document(l)?;
    embed_gltf(w, doc, &bin)
}
