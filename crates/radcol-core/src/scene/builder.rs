//! [`SceneBuilder`]: scenes from vertex and index buffers, for programs that
//! embed radcol.

use super::raw::{RawScene, RawTriangle};
use super::validate::{check_material, finish};
use super::{Material, Scene, SceneError, TriangleOrigin};
use crate::camera::Camera;
use glam::{DVec3, Vec3};
use std::collections::HashMap;

/// Builds a [`Scene`] from materials and indexed triangle meshes.
///
/// Triangles `[i, j, k]` index the mesh's `positions`; their front face (the
/// side light leaves from) is the one they are counter-clockwise from. Faces
/// are numbered per group across all `add_mesh` calls of that group, and
/// errors and warnings name them as "mesh 'group' face n". The checks and
/// repairs are those of the [module](super).
///
/// ```
/// use radcol_core::backend::CpuBackend;
/// use radcol_core::run::{solve, SolveConfig};
/// use radcol_core::scene::{Material, SceneBuilder};
/// use glam::Vec3;
///
/// // Two facing unit squares one unit apart: the top one emits.
/// let mut b = SceneBuilder::new("plates");
/// let white = b.add_material(Material::diffuse("white", [0.5, 0.5, 0.5]))?;
/// let light = b.add_material(Material::emitter("light", [0.0; 3], [1.0, 1.0, 1.0]))?;
/// let square = |z: f32| [Vec3::new(0., 0., z), Vec3::new(1., 0., z), Vec3::new(1., 1., z), Vec3::new(0., 1., z)];
/// b.add_mesh("floor", &square(0.0), &[[0, 1, 2], [0, 2, 3]], white)?;
/// b.add_mesh("lamp", &square(1.0), &[[0, 2, 1], [0, 3, 2]], light)?;
/// let scene = b.build()?;
/// assert!(scene.warnings.is_empty());
/// assert_eq!(scene.emitters(), vec![1]);
///
/// let config = SolveConfig { degree: 0, level: 1, ..Default::default() };
/// let out = solve(&scene.problem(), &config, &CpuBackend)?;
/// // The lamp reflects nothing, so its radiosity is its emission.
/// let lamp = &out.channels[0].solution;
/// assert!((lamp.nodal()[out.discretization.len() - 1] - 1.0).abs() < 1e-12);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct SceneBuilder {
    name: String,
    materials: Vec<Material>,
    triangles: Vec<RawTriangle>,
    faces_per_group: HashMap<String, usize>,
    camera: Option<Camera>,
}

impl SceneBuilder {
    /// An empty scene called `name`.
    pub fn new(name: &str) -> Self {
        Self {
            name: name.into(),
            materials: Vec::new(),
            triangles: Vec::new(),
            faces_per_group: HashMap::new(),
            camera: None,
        }
    }

    /// Adds a material and returns its index; rejects ρ outside [0, 1) and
    /// negative or non-finite emission.
    pub fn add_material(&mut self, material: Material) -> Result<usize, SceneError> {
        let at = format!("material {} '{}'", self.materials.len(), material.name);
        check_material(&material, &at)?;
        self.materials.push(material);
        Ok(self.materials.len() - 1)
    }

    /// Adds an indexed triangle mesh with single-precision positions.
    pub fn add_mesh(
        &mut self,
        group: &str,
        positions: &[Vec3],
        triangles: &[[u32; 3]],
        material: usize,
    ) -> Result<(), SceneError> {
        let p: Vec<DVec3> = positions.iter().map(|v| v.as_dvec3()).collect();
        self.add_mesh_f64(group, &p, triangles, material)
    }

    /// Adds an indexed triangle mesh with double-precision positions.
    pub fn add_mesh_f64(
        &mut self,
        group: &str,
        positions: &[DVec3],
        triangles: &[[u32; 3]],
        material: usize,
    ) -> Result<(), SceneError> {
        self.add(group, positions, None, triangles, material)
    }

    /// Adds an indexed triangle mesh with texture coordinates per vertex
    /// (`uvs[i]` of `positions[i]`; v down from the image's top edge, as in
    /// glTF): lightmaps then bake into these coordinates
    /// ([`Scene::uvs`](super::Scene::uvs)) when every triangle of the scene
    /// has them.
    pub fn add_mesh_with_uvs(
        &mut self,
        group: &str,
        positions: &[DVec3],
        uvs: &[[f64; 2]],
        triangles: &[[u32; 3]],
        material: usize,
    ) -> Result<(), SceneError> {
        if uvs.len() != positions.len() {
            return Err(SceneError::Syntax {
                at: format!("mesh '{group}'"),
                message: format!(
                    "{} texture coordinates for {} positions: one per vertex",
                    uvs.len(),
                    positions.len()
                ),
            });
        }
        if let Some((i, uv)) = uvs
            .iter()
            .enumerate()
            .find(|(_, uv)| !uv.iter().all(|x| x.is_finite()))
        {
            return Err(SceneError::Syntax {
                at: format!("mesh '{group}' vertex {i}"),
                message: format!("texture coordinates ({}, {}) are not finite", uv[0], uv[1]),
            });
        }
        self.add(group, positions, Some(uvs), triangles, material)
    }

    fn add(
        &mut self,
        group: &str,
        positions: &[DVec3],
        uvs: Option<&[[f64; 2]]>,
        triangles: &[[u32; 3]],
        material: usize,
    ) -> Result<(), SceneError> {
        let first = self.faces_per_group.get(group).copied().unwrap_or(0);
        let at = |f: usize| format!("mesh '{group}' face {}", first + f);
        if material >= self.materials.len() {
            return Err(SceneError::NoMaterial {
                at: at(0),
                message: format!(
                    "material index {material}, but only {} materials were added",
                    self.materials.len()
                ),
            });
        }
        for (i, v) in positions.iter().enumerate() {
            if let Some(&x) = v.to_array().iter().find(|x| !x.is_finite()) {
                return Err(SceneError::Vertex {
                    at: format!("mesh '{group}' vertex {i}"),
                    value: x,
                });
            }
        }
        let mut new = Vec::with_capacity(triangles.len());
        for (f, t) in triangles.iter().enumerate() {
            let mut v = [DVec3::ZERO; 3];
            for c in 0..3 {
                v[c] =
                    *positions
                        .get(t[c] as usize)
                        .ok_or_else(|| SceneError::IndexOutOfRange {
                            at: at(f),
                            index: t[c] as i64,
                            count: positions.len(),
                        })?;
            }
            new.push(RawTriangle {
                group: group.into(),
                material,
                vertices: v,
                at: at(f),
                uv: uvs.map(|uv| t.map(|i| uv[i as usize])),
                origin: TriangleOrigin {
                    input: self.triangles.len() + f,
                    vertices: *t,
                    corners: v,
                    at: at(f),
                },
            });
        }
        self.triangles.extend(new);
        self.faces_per_group
            .insert(group.into(), first + triangles.len());
        Ok(())
    }

    /// Sets the scene's camera.
    pub fn camera(&mut self, camera: Camera) -> &mut Self {
        self.camera = Some(camera);
        self
    }

    /// Checks, repairs and builds the scene.
    pub fn build(&self) -> Result<Scene, SceneError> {
        finish(RawScene {
            name: self.name.clone(),
            materials: self.materials.clone(),
            triangles: self.triangles.clone(),
            camera: self.camera,
            warnings: Vec::new(),
            source: None,
            duplicates: Default::default(),
        })
    }
}
