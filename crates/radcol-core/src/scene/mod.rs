//! Scenes for graphics users: triangle meshes with materials (OBJ files, built-ins, vertex/index buffers).
//!
//! A [`Scene`] is a flat-faceted [`Surface`] (one `Patch` per OBJ group and
//! material, map `Identity`, triangles in world coordinates) with one
//! [`Material`] per patch, an optional [`Camera`] and the warnings its input
//! produced. It turns into a three-channel [`Problem`] ("R", "G", "B") with
//! [`Scene::problem`].
//!
//! Every input path ([`load_obj`], [`load_obj_str`], [`SceneBuilder`],
//! [`builtin`]) goes through the same checks (see [`SceneError`] for the
//! errors). Repairs, each reported in [`Scene::warnings`]:
//!
//! * degenerate triangles (area ≤ 1e-12 × the squared bounding-box diagonal,
//!   repeated vertices included) are dropped;
//! * duplicate triangles (the same three positions in the same cyclic order as
//!   an earlier triangle) are dropped;
//! * two coincident triangles of *opposite* orientation are both kept: they are
//!   a two-sided panel, each side emitting and reflecting on its own.
//!
//! Warnings only (the collocation method uses interior nodes on discontinuous
//! elements and needs no conforming mesh; the superconvergence theorems do):
//! T-junctions (a vertex inside another triangle's edge), non-manifold edges
//! (shared by more than two triangles), non-planar OBJ polygons (triangulated
//! in the plane of their mean normal) and self-intersecting ones. Each kind lists at most
//! [`MAX_WARNINGS_PER_KIND`] cases and then counts the rest.
//!
//! Units are whatever the input uses: every tolerance is relative to the
//! scene's size.

mod builder;
mod builtin;
mod change;
mod facing;
#[cfg(feature = "gltf")]
mod gltf;
#[cfg(feature = "gltf")]
mod gltf_data;
mod ignored;
pub mod imprint;
mod mtl;
mod obj;
mod overlap;
mod polygon;
mod raw;
mod scan;
mod tobj_match;
mod validate;

pub use builder::SceneBuilder;
pub use builtin::{builtin, BUILTIN_SCENES};
pub use change::MaterialChange;
#[cfg(feature = "gltf")]
pub use gltf::load_gltf;
pub use imprint::Imprinted;
pub use obj::{load_obj, load_obj_str};

use crate::camera::Camera;
use crate::geometry::Surface;
#[cfg(doc)]
use crate::geometry::{Identity, Patch};
use crate::problem::{Channel, Field, Problem};
use glam::DVec3;
use std::collections::HashSet;
use std::path::PathBuf;
use std::sync::Arc;

/// At most this many warnings of one kind are listed; the rest are counted.
pub const MAX_WARNINGS_PER_KIND: usize = 20;

/// A diffuse material: reflectance and emission per colour channel.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name (the MTL `newmtl` name).
    pub name: String,
    /// Diffuse reflectance ρ (MTL `Kd`), each component in [0, 1).
    pub rho: [f64; 3],
    /// Emitted radiosity E (MTL `Ke`), each component ≥ 0 and finite.
    pub emission: [f64; 3],
}

impl Material {
    /// A material that reflects `rho` and emits nothing.
    pub fn diffuse(name: &str, rho: [f64; 3]) -> Self {
        Self {
            name: name.into(),
            rho,
            emission: [0.0; 3],
        }
    }

    /// A material that reflects `rho` and emits `emission`.
    pub fn emitter(name: &str, rho: [f64; 3], emission: [f64; 3]) -> Self {
        Self {
            name: name.into(),
            rho,
            emission,
        }
    }

    /// True when some channel emits.
    pub fn is_emitter(&self) -> bool {
        self.emission.iter().any(|&e| e > 0.0)
    }
}

/// Why a scene could not be built. Messages name the file and 1-based line
/// (OBJ/MTL input) or the mesh group and face index (builder input), and the
/// value at fault.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SceneError {
    /// The OBJ file could not be read.
    #[error("cannot read OBJ file {}: {message}", path.display())]
    Unreadable {
        /// The file.
        path: PathBuf,
        /// The system's reason.
        message: String,
    },
    /// A glTF file (or one of its buffers) could not be read or parsed.
    #[error("cannot read glTF file {}: {message}", path.display())]
    Gltf {
        /// The file.
        path: PathBuf,
        /// The reason (the system's or the glTF reader's).
        message: String,
    },
    /// A `mtllib` file is missing or unreadable.
    #[error("{at}: cannot read material library {}: {message}", mtl.display())]
    MaterialLibrary {
        /// OBJ file and line of the `mtllib` statement.
        at: String,
        /// The material library's path.
        mtl: PathBuf,
        /// The system's reason.
        message: String,
    },
    /// A statement that cannot be parsed.
    #[error("{at}: {message}")]
    Syntax {
        /// File and line.
        at: String,
        /// What is wrong.
        message: String,
    },
    /// `usemtl` of a material no loaded library defines.
    #[error("{at}: usemtl '{name}': no material of that name is defined (by the mtllib statements before this line)")]
    UndefinedMaterial {
        /// File and line of the `usemtl`.
        at: String,
        /// The material name.
        name: String,
    },
    /// A face before any `usemtl`, or a builder mesh with an unknown material index.
    #[error("{at}: face has no material ({message})")]
    NoMaterial {
        /// File and line, or group and face.
        at: String,
        /// Details.
        message: String,
    },
    /// A material without a diffuse reflectance.
    #[error("{at}: material '{material}' has no Kd (diffuse reflectance)")]
    MissingKd {
        /// MTL file and line of `newmtl`.
        at: String,
        /// The material.
        material: String,
    },
    /// A built-in scene asked for by a name there is none of.
    #[error("there is no built-in scene '{name}' (there are {known})")]
    NoSuchBuiltin {
        /// The name asked for.
        name: String,
        /// The built-in scenes' names, comma-separated.
        known: String,
    },
    /// A material asked for by name that the scene does not have.
    #[error("the scene has no material '{name}' (it has {known})")]
    NoSuchMaterial {
        /// The name asked for.
        name: String,
        /// The scene's material names, comma-separated.
        known: String,
    },
    /// A reflectance component outside [0, 1).
    #[error("{at}: material '{material}': Kd {component} = {value} lies outside [0, 1)")]
    Reflectance {
        /// MTL file and line of `Kd` (or the builder's material index).
        at: String,
        /// The material.
        material: String,
        /// "R", "G" or "B".
        component: &'static str,
        /// The value.
        value: f64,
    },
    /// An emission component that is negative, NaN or infinite.
    #[error(
        "{at}: material '{material}': Ke {component} = {value} must be finite and non-negative"
    )]
    Emission {
        /// MTL file and line of `Ke` (or the builder's material index).
        at: String,
        /// The material.
        material: String,
        /// "R", "G" or "B".
        component: &'static str,
        /// The value.
        value: f64,
    },
    /// A vertex coordinate that is NaN or infinite.
    #[error("{at}: vertex coordinate {value} is not finite")]
    Vertex {
        /// File and line of the `v` statement, or group and vertex index.
        at: String,
        /// The value.
        value: f64,
    },
    /// A face index outside the vertices defined so far.
    #[error("{at}: vertex index {index} is out of range ({count} vertices defined)")]
    IndexOutOfRange {
        /// File and line of the face, or group and face index.
        at: String,
        /// The index as written.
        index: i64,
        /// Number of vertices available.
        count: usize,
    },
    /// A face with fewer than three vertices.
    #[error("{at}: face has {count} vertices, at least 3 are needed")]
    TooFewVertices {
        /// File and line of the face.
        at: String,
        /// Its vertex count.
        count: usize,
    },
    /// No triangle is left (none given, or all degenerate).
    #[error("scene '{name}' has no triangles{detail}")]
    Empty {
        /// The scene.
        name: String,
        /// Why (for example "after dropping 3 degenerate triangles").
        detail: String,
    },
    /// The built-in camera is degenerate.
    #[error("scene '{name}': {message}")]
    Camera {
        /// The scene.
        name: String,
        /// Camera validation message.
        message: String,
    },
    /// tobj rejected the file, or read it differently from radcol's line scan.
    #[error("{at}: OBJ reader: {message}")]
    Reader {
        /// File (and line when known).
        at: String,
        /// Details.
        message: String,
    },
}

/// A triangle scene with materials, ready to solve: read from an OBJ or
/// glTF file, built from one's own buffers ([`SceneBuilder`]), or one of
/// the built-ins.
///
/// ```
/// use radcol_core::scene::Scene;
///
/// let cornell = Scene::builtin("cornell")?;
/// let light = cornell.materials.iter().find(|m| m.is_emitter()).expect("a light");
/// assert_eq!(light.name, "light");
/// assert!(cornell.triangle_count() > 30);
/// let problem = cornell.problem(); // one channel per colour, R, G, B
/// assert_eq!(problem.channels.len(), 3);
/// # Ok::<(), radcol_core::scene::SceneError>(())
/// ```
#[derive(Clone, Debug)]
pub struct Scene {
    /// Scene name (file stem or built-in name).
    pub name: String,
    /// The surface: one patch per (group, material), named "group/material".
    pub surface: Arc<Surface>,
    /// The materials.
    pub materials: Vec<Material>,
    /// Index into [`Scene::materials`] of each patch.
    pub patch_material: Vec<usize>,
    /// The scene's camera, if it has one.
    pub camera: Option<Camera>,
    /// Repairs and suspicious input, one sentence each.
    pub warnings: Vec<String>,
    /// The file the scene was read from.
    pub source: Option<PathBuf>,
    /// Contact lines imprinted on the faces they rest on ([`imprint`]); the
    /// triangle count of the scene includes the pieces.
    pub imprinted: Imprinted,
    /// Metres per scene unit, when known: glTF input is in metres (1), the
    /// built-in Cornell box in millimetres (0.001); OBJ files do not say.
    pub metres_per_unit: Option<f64>,
    /// The input's texture coordinates of every surface triangle
    /// (`uvs[patch][triangle]`, the corners of `surface.patches[patch]
    /// .triangles[triangle]`, v down from the top as in glTF), when every
    /// triangle has them: OBJ `vt`, glTF TEXCOORD_1 (the lightmap set by
    /// convention) or else TEXCOORD_0. Pieces of imprinted triangles get
    /// their triangle's coordinates interpolated. Lightmaps bake into them.
    pub uvs: Option<Vec<Vec<[[f64; 2]; 3]>>>,
    /// The input triangle of every surface triangle (`origins[patch]
    /// [triangle]`): which one it is, or which one it is a piece of where a
    /// contact line was imprinted. [`Scene::element_origins`] maps a
    /// mesh's elements to them.
    pub origins: Vec<Vec<TriangleOrigin>>,
}

/// Where a surface triangle came from in the scene's input.
#[derive(Clone, Debug, PartialEq)]
pub struct TriangleOrigin {
    /// The input triangle's position among all the triangles read, in
    /// order: OBJ faces in file order (a polygon's triangles in turn),
    /// glTF primitives in node order, `SceneBuilder` meshes as added.
    pub input: usize,
    /// Its corners' vertex indices in the input: 0-based OBJ `v` indices,
    /// or indices into the positions of the glTF primitive or
    /// `SceneBuilder` mesh.
    pub vertices: [u32; 3],
    /// Its corners' positions (the input triangle's, also for a piece).
    pub corners: [DVec3; 3],
    /// Where it is written: "file.obj:12", "file.gltf: mesh 'm' face 3",
    /// "mesh 'floor' face 0".
    pub at: String,
}

impl Scene {
    /// The input triangle of every element of `mesh` (a mesh of this
    /// scene's surface), through [`crate::mesh::Mesh::base_triangles`]; None for an
    /// element outside every surface triangle (a mesh of another surface).
    pub fn element_origins(&self, mesh: &crate::mesh::Mesh) -> Vec<Option<&TriangleOrigin>> {
        mesh.base_triangles()
            .into_iter()
            .map(|b| b.and_then(|(j, t)| self.origins.get(j as usize)?.get(t as usize)))
            .collect()
    }

    /// The colour problem: channels "R", "G", "B" with ρ = Kd and E = Ke per
    /// patch; no exact solution.
    pub fn problem(&self) -> Problem {
        let per_patch = |f: &dyn Fn(&Material) -> f64| {
            Field::PerPatch(Arc::new(
                self.patch_material
                    .iter()
                    .map(|&m| f(&self.materials[m]))
                    .collect(),
            ))
        };
        let channels = ["R", "G", "B"]
            .iter()
            .enumerate()
            .map(|(c, name)| Channel {
                name: (*name).into(),
                rho: per_patch(&|m| m.rho[c]),
                emission: per_patch(&|m| m.emission[c]),
            })
            .collect();
        Problem {
            surface: self.surface.clone(),
            channels,
            exact: None,
        }
    }

    /// The material of patch `patch`.
    pub fn material_of(&self, patch: usize) -> &Material {
        &self.materials[self.patch_material[patch]]
    }

    /// Indices of the patches whose material emits.
    pub fn emitters(&self) -> Vec<usize> {
        (0..self.surface.patches.len())
            .filter(|&j| self.material_of(j).is_emitter())
            .collect()
    }

    /// Every triangle (world coordinates, front-face orientation) with its patch index.
    pub fn triangles(&self) -> impl Iterator<Item = (usize, [DVec3; 3])> + '_ {
        self.surface.patches.iter().enumerate().flat_map(|(j, p)| {
            p.triangles
                .iter()
                .map(move |t| (j, t.map(|x| p.map.map(x))))
        })
    }

    /// Axis-aligned bounding box (min, max).
    pub fn bounding_box(&self) -> (DVec3, DVec3) {
        self.surface.bounding_box()
    }

    /// The diagonal of [`Scene::bounding_box`].
    pub fn diagonal(&self) -> f64 {
        let (lo, hi) = self.bounding_box();
        (hi - lo).length()
    }

    /// What `radcol solve` runs on this scene given no flag (`adaptive`:
    /// with a target error): [`crate::run::SolveConfig::recommended`].
    pub fn solve_config(&self, adaptive: bool) -> crate::run::SolveConfig {
        crate::run::SolveConfig::recommended(Some(self.diagonal()), adaptive)
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.surface.base_triangle_count()
    }

    /// Number of distinct vertex positions.
    pub fn vertex_count(&self) -> usize {
        self.triangles()
            .flat_map(|(_, t)| t)
            .map(|v| v.to_array().map(f64::to_bits))
            .collect::<HashSet<_>>()
            .len()
    }

    /// Total area, and the area of each patch.
    pub fn patch_areas(&self) -> Vec<f64> {
        let mut areas = vec![0.0; self.surface.patches.len()];
        for (j, [a, b, c]) in self.triangles() {
            areas[j] += 0.5 * (b - a).cross(c - a).length();
        }
        areas
    }

    /// Total surface area.
    pub fn area(&self) -> f64 {
        self.patch_areas().iter().sum()
    }

    /// The scene with all geometry (and the camera) scaled by `factor` about
    /// the origin; materials unchanged. Radiosity is scale invariant, so the
    /// solution must not change.
    pub fn scaled(&self, factor: f64) -> Scene {
        let mut surface = (*self.surface).clone();
        for p in &mut surface.patches {
            for t in &mut p.triangles {
                *t = t.map(|v| v * factor);
            }
        }
        let mut origins = self.origins.clone();
        for o in origins.iter_mut().flatten() {
            o.corners = o.corners.map(|v| v * factor);
        }
        Scene {
            surface: Arc::new(surface),
            origins,
            camera: self.camera.map(|c| Camera {
                eye: c.eye * factor,
                target: c.target * factor,
                ..c
            }),
            ..self.clone()
        }
    }

    /// A camera for the scene: its own, else one chosen to show the lit sides
    /// of its triangles ([`crate::render::auto_camera`]).
    #[cfg(feature = "render")]
    pub fn camera_or_auto(&self) -> Camera {
        self.camera.unwrap_or_else(|| {
            crate::render::auto_camera(&crate::mesh::Mesh::new(self.surface.clone(), 0))
        })
    }
}

#[cfg(test)]
mod tests;
