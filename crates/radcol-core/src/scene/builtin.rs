//! Built-in scenes, shipped as OBJ + MTL files under `scenes/` and read through
//! the same OBJ path as user files.

use super::{load_obj_str, Scene, SceneError};

/// Built-in scenes: (name, description).
pub const BUILTIN_SCENES: &[(&str, &str)] = &[];

/// The built-in scene `name`, or None when there is none of that name.
pub fn builtin(name: &str) -> Option<Result<Scene, SceneError>> {
    let _ = load_obj_str;
    let _ = name;
    None
}
