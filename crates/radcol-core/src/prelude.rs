//! The facade for embedding programs: what a scene-to-solution program
//! needs, in one `use radcol_core::prelude::*;`, with one error type,
//! [`Error`], that every fallible call here converts into with `?`.
//!
//! ```
//! use radcol_core::prelude::*;
//!
//! let scene = builtin("cornell").expect("a built-in scene")?;
//! let config = SolveConfig { degree: 1, level: 0, ..Default::default() };
//! let outcome = solve(&scene.problem(), &config, &CpuBackend)?;
//! let at = [QueryPoint { position: DVec3::new(278.0, 0.0, 280.0), normal: None }];
//! let values = query(&scene.problem(), &outcome, config.quad.clone(), &at, DEFAULT_SNAP)?;
//! assert!(values[0].channels.iter().all(|c| c.iterated > 0.0));
//! let shown: Vec<&Solution> = outcome.channels.iter().map(|c| c.shown()).collect();
//! let options = RenderOptions { width: 32, height: 24, ..Default::default() };
//! let image = render(outcome.discretization.mesh(), &shown, &scene.camera_or_auto(), &options)?;
//! assert_eq!(tone_map(&image, &ToneMap::default()).len(), 32 * 24);
//! # Ok::<(), radcol_core::prelude::Error>(())
//! ```

pub use crate::assembly::{AssemblyBackend, BackendInfo, CpuBackend, QuadratureOptions};
pub use crate::backend_kind::{BackendKind, Scalar};
pub use crate::camera::Camera;
pub use crate::error::InputError;
pub use crate::problem::{Field, Problem};
pub use crate::progress::{Progress, ProgressHandle};
pub use crate::query::{query, PointEvaluator, PointValues, QueryError, QueryPoint, DEFAULT_SNAP};
pub use crate::render::lightmap::{bake as bake_lightmap, Atlas, Resolution};
pub use crate::render::{
    input_vertex_mesh, render, render_scene, tone_map, vertex_mesh, Corners, Image, RenderError,
    RenderOptions, ToneMap, VertexMesh,
};
pub use crate::run::adapt::{solve_adaptive, AdaptOptions, AdaptOutcome, AdaptStep, StopReason};
pub use crate::run::{
    solve, MemoryBudget, OperatorChoice, Relighter, SolveConfig, SolveOutcome, SolverKind,
    StartMesh,
};
#[cfg(feature = "gltf")]
pub use crate::scene::load_gltf;
pub use crate::scene::{
    builtin, load_obj, Material, Scene, SceneBuilder, SceneError, TriangleOrigin, BUILTIN_SCENES,
};
pub use crate::solution::Solution;
/// The vector types of every position and normal (`DVec3`), re-exported so
/// that a program needs no glam dependency of its own.
pub use glam::{self, DVec3};

pub use crate::estimate::RelativeTo;
pub use crate::progress::Cancel;
pub use crate::radiosity::{CornerValues, Error, Radiosity, Refinement, Settings};
#[cfg(feature = "export")]
pub use crate::radiosity::{ImageFormat, Lightmap, LightmapFormat, MeshFormat};
pub use crate::scene::MaterialChange;
use std::path::Path;

/// Loads a scene file by its extension: `.obj` ([`load_obj`]), `.gltf` or
/// `.glb` ([`load_gltf`]); anything else is refused with the path named.
pub fn load_scene(path: &Path) -> Result<Scene, Error> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    Ok(match ext.as_deref() {
        Some("obj") => load_obj(path)?,
        #[cfg(feature = "gltf")]
        Some("gltf" | "glb") => load_gltf(path)?,
        #[cfg(not(feature = "gltf"))]
        Some("gltf" | "glb") => {
            return Err(SceneError::Gltf {
                path: path.to_path_buf(),
                message: "this build of radcol-core reads no glTF (its feature `gltf` is off)"
                    .into(),
            }
            .into())
        }
        _ => {
            return Err(SceneError::Unreadable {
                path: path.to_path_buf(),
                message: "not a scene file: the name must end in .obj, .gltf or .glb".into(),
            }
            .into())
        }
    })
}
