//! glTF 2.0 input (`.gltf` with its buffers, or `.glb`), read with the
//! `gltf` crate.
//!
//! The default scene (else the first) is walked from its root nodes; each
//! mesh primitive is placed by its node's world transform (in double
//! precision, metres kept: glTF's unit) and becomes a group named after its
//! node (else its mesh, else "node i"), with "/j" for the j-th primitive of
//! a mesh with several. A transform with a negative determinant mirrors the
//! primitive, so its triangles are rewound to keep their front faces (glTF
//! 2.0, 3.7.4). Triangle strips and fans are unrolled; points and lines are
//! not surfaces and are skipped with a warning.
//!
//! Materials: ρ = `baseColorFactor` (linear RGB; alpha ignored) and E =
//! `emissiveFactor` × `KHR_materials_emissive_strength` (read like an MTL
//! `Ke`, so `--ke` says whether that is exitance or radiance). A base
//! colour or emissive texture is not sampled: the factor alone is used and
//! the scene warns, naming the material. radcol's surfaces are one-sided,
//! so a `doubleSided` material is solved on its front (counter-clockwise)
//! side, with a warning. A primitive without a material would get glTF's
//! default (white, ρ = 1, a perfect reflector radcol cannot solve): it is
//! refused with the primitive named. The first perspective camera placed by
//! a node becomes the scene's camera.

use super::gltf_data::{check_accessors, read_buffers};
use super::obj::MAX_SCENE_FILE_BYTES;
use super::{Material, Scene, SceneBuilder, SceneError};
use crate::camera::Camera;
use glam::{DMat4, DVec3, Mat4};
use gltf::mesh::Mode;
use std::path::Path;

/// Reads a glTF 2.0 file (`.gltf` with external or embedded buffers, or a
/// binary `.glb`).
pub fn load_gltf(path: &Path) -> Result<Scene, SceneError> {
    let fail = |message: String| SceneError::Gltf {
        path: path.to_path_buf(),
        message,
    };
    let meta = std::fs::metadata(path).map_err(|e| fail(e.to_string()))?;
    if !meta.is_file() {
        return Err(fail(
            "not a regular file (a directory, device or pipe)".into(),
        ));
    }
    if meta.len() > MAX_SCENE_FILE_BYTES {
        return Err(fail(format!(
            "{:.1} MiB is more than the {} MiB radcol reads",
            meta.len() as f64 / (1u64 << 20) as f64,
            MAX_SCENE_FILE_BYTES >> 20
        )));
    }
    let gltf::Gltf { document, blob } = open_checked(path).map_err(fail)?;
    let buffers = read_buffers(&document, path, blob).map_err(fail)?;
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into());
    let mut scene = build(&name, &path.display().to_string(), &document, &buffers)?;
    scene.source = Some(path.to_path_buf());
    scene.metres_per_unit = Some(1.0);
    Ok(scene)
}

/// The document and binary chunk of the glTF or GLB at `path`, validated
/// by the gltf crate once the indices its validation follows unchecked are
/// checked here: a POSITION attribute naming an accessor that does not
/// exist panicked inside it (found by fuzzing).
fn open_checked(path: &Path) -> Result<gltf::Gltf, String> {
    use std::io::Read;
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .and_then(|f| f.take(MAX_SCENE_FILE_BYTES).read_to_end(&mut bytes))
        .map_err(|e| e.to_string())?;
    let gltf::Gltf { document, blob } =
        gltf::Gltf::from_slice_without_validation(&bytes).map_err(|e| e.to_string())?;
    let json = document.into_json();
    let accessors = json.accessors.len();
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let named = (primitive.attributes.values())
                .map(|a| a.value())
                .chain(primitive.indices.map(|i| i.value()));
            if let Some(i) = named.into_iter().find(|&i| i >= accessors) {
                return Err(format!(
                    "meshes[{m}].primitives[{p}] names accessor {i}, but there are {accessors}"
                ));
            }
        }
    }
    let document = gltf::Document::from_json(json).map_err(|e| e.to_string())?;
    Ok(gltf::Gltf { document, blob })
}

/// What the walk gathers besides the builder's triangles.
struct Walk<'a> {
    file: &'a str,
    buffers: &'a [Vec<u8>],
    builder: SceneBuilder,
    /// radcol material index per glTF material index.
    materials: Vec<Option<usize>>,
    camera: Option<Camera>,
    warnings: Vec<String>,
}

fn build(
    name: &str,
    file: &str,
    doc: &gltf::Document,
    buffers: &[Vec<u8>],
) -> Result<Scene, SceneError> {
    let syntax = |message: String| SceneError::Syntax {
        at: file.to_string(),
        message,
    };
    let root = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| syntax("the file has no scene".into()))?;
    let mut walk = Walk {
        file,
        buffers,
        builder: SceneBuilder::new(name),
        materials: vec![None; doc.materials().len()],
        camera: None,
        warnings: Vec::new(),
    };
    walk.nodes(root.nodes(), doc.nodes().len())?;
    if let Some(c) = walk.camera {
        walk.builder.camera(c);
    }
    let mut scene = walk.builder.build()?;
    scene.warnings.splice(0..0, walk.warnings);
    Ok(scene)
}

impl Walk<'_> {
    /// Places the trees under `roots` (of a document with `count` nodes),
    /// depth first without recursion (a chain of nodes may be as deep as
    /// the file is long). glTF's nodes form disjoint trees: a node reached
    /// twice (a loop, or two parents) is refused, naming it.
    fn nodes<'a>(
        &mut self,
        roots: impl Iterator<Item = gltf::Node<'a>>,
        count: usize,
    ) -> Result<(), SceneError> {
        let mut seen = vec![false; count];
        let mut stack: Vec<(gltf::Node<'a>, DMat4)> = roots.map(|n| (n, DMat4::IDENTITY)).collect();
        stack.reverse();
        while let Some((node, parent)) = stack.pop() {
            let i = node.index();
            if std::mem::replace(&mut seen[i], true) {
                return Err(SceneError::Syntax {
                    at: self.file.to_string(),
                    message: format!(
                        "node {i} is reached twice (a node that is its own ancestor, or has two parents): glTF's nodes form trees"
                    ),
                });
            }
            let world = parent * self.local(&node)?;
            self.node(&node, world)?;
            let children: Vec<_> = node.children().collect();
            stack.extend(children.into_iter().rev().map(|c| (c, world)));
        }
        Ok(())
    }

    /// `node`'s own transform. A rotation that is not a unit quaternion
    /// (glTF 2.0, 5.25: it must be) would scale as well as turn: it is
    /// normalised, with a warning naming the node; a zero or non-finite one
    /// is refused.
    fn local(&mut self, node: &gltf::Node) -> Result<DMat4, SceneError> {
        let gltf::scene::Transform::Decomposed {
            translation,
            rotation,
            scale,
        } = node.transform()
        else {
            return Ok(Mat4::from_cols_array_2d(&node.transform().matrix()).as_dmat4());
        };
        let q = glam::DQuat::from_array(rotation.map(f64::from));
        let norm = q.length();
        if !(norm.is_finite() && norm > 0.0) {
            return Err(SceneError::Syntax {
                at: self.file.to_string(),
                message: format!(
                    "node {}: rotation {rotation:?} is not a rotation (glTF asks for a unit quaternion)",
                    node.index()
                ),
            });
        }
        if (norm - 1.0).abs() > 1e-6 {
            self.warnings.push(format!(
                "{}: node {}: rotation {rotation:?} has length {norm:.6}, not 1 (glTF asks for a unit quaternion); normalised, so that it turns without scaling",
                self.file,
                node.index()
            ));
        }
        Ok(DMat4::from_scale_rotation_translation(
            DVec3::from_array(scale.map(f64::from)),
            q / norm,
            DVec3::from_array(translation.map(f64::from)),
        ))
    }

    /// Places `node`'s mesh and camera by its world transform `world`.
    fn node(&mut self, node: &gltf::Node, world: DMat4) -> Result<(), SceneError> {
        let label = node
            .name()
            .map(str::to_string)
            .or_else(|| node.mesh().and_then(|m| m.name().map(str::to_string)))
            .unwrap_or_else(|| format!("node {}", node.index()));
        if let Some(mesh) = node.mesh() {
            let count = mesh.primitives().len();
            for (j, prim) in mesh.primitives().enumerate() {
                let group = if count > 1 {
                    format!("{label}/{j}")
                } else {
                    label.clone()
                };
                self.primitive(&prim, &group, world)?;
            }
        }
        if let (None, Some(cam)) = (self.camera, node.camera()) {
            self.camera = camera(&cam, world, &label, &mut self.warnings);
        }
        Ok(())
    }

    /// Adds one primitive's triangles, placed by `world`, as `group`.
    fn primitive(
        &mut self,
        prim: &gltf::Primitive,
        group: &str,
        world: DMat4,
    ) -> Result<(), SceneError> {
        let at = format!("{}: mesh '{group}'", self.file);
        let mode = prim.mode();
        if matches!(
            mode,
            Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip
        ) {
            self.warnings.push(format!(
                "{at}: a primitive of {mode:?} is not a surface and was skipped"
            ));
            return Ok(());
        }
        let material = self.material(&prim.material(), &at)?;
        check_accessors(prim, self.buffers, &at)?;
        if prim.morph_targets().len() > 0 {
            self.warnings.push(format!(
                "{at}: {} morph targets are not applied: the base shape is solved",
                prim.morph_targets().len()
            ));
        }
        let reader = prim.reader(|b| self.buffers.get(b.index()).map(Vec::as_slice));
        let positions: Vec<DVec3> = reader
            .read_positions()
            .ok_or_else(|| SceneError::Syntax {
                at: at.clone(),
                message: "a primitive has no POSITION attribute".into(),
            })?
            .map(|p| world.transform_point3(DVec3::from_array(p.map(f64::from))))
            .collect();
        let indices: Vec<u32> = match (prim.indices(), reader.read_indices()) {
            (_, Some(ix)) => ix.into_u32().collect(),
            (None, None) => (0..positions.len() as u32).collect(),
            (Some(a), None) => {
                return Err(SceneError::Syntax {
                    at,
                    message: format!("the indices (accessor {}) cannot be read", a.index()),
                })
            }
        };
        if mode == Mode::Triangles && !indices.len().is_multiple_of(3) {
            return Err(SceneError::Syntax {
                at,
                message: format!(
                    "{} {} is not a multiple of 3: a triangle list would drop the last {}",
                    indices.len(),
                    if prim.indices().is_some() {
                        "indices"
                    } else {
                        "vertices"
                    },
                    indices.len() % 3
                ),
            });
        }
        let mut tris = triangles(mode, &indices);
        if world.determinant() < 0.0 {
            for t in &mut tris {
                t.swap(1, 2);
            }
        }
        // TEXCOORD_1 is the lightmap set by convention (three.js, Unity's
        // exporters); a mesh with one set has it in TEXCOORD_0.
        let uvs: Option<Vec<[f64; 2]>> = reader
            .read_tex_coords(1)
            .or_else(|| reader.read_tex_coords(0))
            .map(|t| t.into_f32().map(|[u, v]| [u as f64, v as f64]).collect());
        match uvs {
            Some(uvs) if uvs.len() == positions.len() => self
                .builder
                .add_mesh_with_uvs(group, &positions, &uvs, &tris, material),
            _ => self
                .builder
                .add_mesh_f64(group, &positions, &tris, material),
        }
    }

    /// The radcol material of glTF material `m` (added on first use).
    fn material(&mut self, m: &gltf::Material, at: &str) -> Result<usize, SceneError> {
        let Some(index) = m.index() else {
            return Err(SceneError::NoMaterial {
                at: at.to_string(),
                message: "glTF's default material is white (ρ = 1, a perfect reflector, which radcol cannot solve: ρ must be < 1); give the primitive a material".into(),
            });
        };
        if let Some(k) = self.materials[index] {
            return Ok(k);
        }
        let name = m
            .name()
            .map(str::to_string)
            .unwrap_or_else(|| format!("material {index}"));
        let pbr = m.pbr_metallic_roughness();
        let [r, g, b, _] = pbr.base_color_factor().map(f64::from);
        let strength = f64::from(m.emissive_strength().unwrap_or(1.0));
        let emission = m.emissive_factor().map(|e| f64::from(e) * strength);
        for (what, texture) in [
            ("base colour", pbr.base_color_texture().is_some()),
            ("emissive", m.emissive_texture().is_some()),
        ] {
            if texture {
                self.warnings.push(format!(
                    "{}: material '{name}': its {what} texture is not sampled; the factor alone is used",
                    self.file
                ));
            }
        }
        if m.double_sided() {
            self.warnings.push(format!(
                "{}: material '{name}' is double-sided; radcol solves the front (counter-clockwise) side only",
                self.file
            ));
        }
        let k = self.builder.add_material(Material {
            name,
            rho: [r, g, b],
            emission,
        })?;
        self.materials[index] = Some(k);
        Ok(k)
    }
}

/// The triangles of a primitive drawn in `mode` from `indices` (strips and
/// fans unrolled with the winding of their first triangle).
fn triangles(mode: Mode, indices: &[u32]) -> Vec<[u32; 3]> {
    match mode {
        Mode::TriangleStrip => (2..indices.len())
            .map(|i| {
                let (a, b, c) = (indices[i - 2], indices[i - 1], indices[i]);
                if i.is_multiple_of(2) {
                    [a, b, c]
                } else {
                    [b, a, c]
                }
            })
            .collect(),
        Mode::TriangleFan => (2..indices.len())
            .map(|i| [indices[0], indices[i - 1], indices[i]])
            .collect(),
        _ => indices
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect(),
    }
}

/// The render camera of a perspective glTF camera placed by `world` (it
/// looks down its local -z with +y up); an orthographic one is skipped with
/// a warning.
fn camera(
    cam: &gltf::Camera,
    world: DMat4,
    label: &str,
    warnings: &mut Vec<String>,
) -> Option<Camera> {
    match cam.projection() {
        gltf::camera::Projection::Perspective(p) => {
            let eye = world.transform_point3(DVec3::ZERO);
            let forward = world.transform_vector3(-DVec3::Z);
            let c = Camera {
                eye,
                target: eye + forward,
                up: world.transform_vector3(DVec3::Y),
                fov_y_deg: f64::from(p.yfov()).to_degrees(),
            };
            match c.validate() {
                Ok(()) => Some(c),
                Err(e) => {
                    warnings.push(format!("camera of node '{label}' skipped: {e}"));
                    None
                }
            }
        }
        gltf::camera::Projection::Orthographic(_) => {
            warnings.push(format!(
                "camera of node '{label}' is orthographic; radcol renders perspective only, so it was skipped"
            ));
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Strips alternate their winding back to the first triangle's; fans
    /// turn about their first vertex; lists are taken three by three.
    #[test]
    fn strips_and_fans_unroll_with_one_winding() {
        let ix = [0, 1, 2, 3, 4];
        assert_eq!(
            triangles(Mode::TriangleStrip, &ix),
            vec![[0, 1, 2], [2, 1, 3], [2, 3, 4]]
        );
        assert_eq!(
            triangles(Mode::TriangleFan, &ix),
            vec![[0, 1, 2], [0, 2, 3], [0, 3, 4]]
        );
        assert_eq!(triangles(Mode::Triangles, &ix), vec![[0, 1, 2]]);
        // A strip of a unit square's 4 corners: both triangles face +z.
        let p = [[0., 0.], [1., 0.], [0., 1.], [1., 1.]];
        for [a, b, c] in triangles(Mode::TriangleStrip, &[0, 1, 2, 3]) {
            let (a, b, c) = (p[a as usize], p[b as usize], p[c as usize]);
            let cross = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
            assert!(cross > 0.0);
        }
    }
}
