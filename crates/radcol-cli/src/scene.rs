//! Scene names on the command line -> core surfaces and material scenes.

use crate::error::{bad_input, BadInput};
use radcol_core::run::{shapes, Surface};
use radcol_core::scene::{builtin, load_gltf, load_obj, Scene, BUILTIN_SCENES};
use std::path::PathBuf;
use std::sync::Arc;

/// The forms a SCENE argument may take, for error messages.
pub const VALID_FORMS: &str = "sphere, sphere:R, ellipsoid:A,B,C, box:LX,LY,LZ, \
the built-in scenes cornell, room, lroom, shadow, plates, FILE.obj, or FILE.gltf/FILE.glb";

/// A parsed SCENE argument.
#[derive(Clone, Debug, PartialEq)]
pub enum SceneSpec {
    /// Sphere of radius R about the origin.
    Sphere(f64),
    /// Ellipsoid with semi-axes a, b, c.
    Ellipsoid(f64, f64, f64),
    /// The room \[0,lx\]×\[0,ly\]×\[0,lz\].
    Box(f64, f64, f64),
    /// A built-in OBJ scene (see [`BUILTIN_SCENES`]).
    Builtin(String),
    /// An OBJ file.
    Obj(PathBuf),
    /// A glTF 2.0 file (`.gltf` or `.glb`).
    Gltf(PathBuf),
}

/// What a SCENE argument loads to: a bare surface (ρ and E from the command
/// line) or a scene with materials (ρ = Kd, E = Ke per colour channel).
#[derive(Clone, Debug)]
pub enum Loaded {
    /// An analytic surface.
    Surface(Arc<Surface>),
    /// A triangle scene with materials.
    Scene(Arc<Scene>),
}

impl Loaded {
    /// The surface either way.
    pub fn surface(&self) -> &Arc<Surface> {
        match self {
            Loaded::Surface(s) => s,
            Loaded::Scene(s) => &s.surface,
        }
    }

    /// The scene, when there are materials.
    pub fn scene(&self) -> Option<&Arc<Scene>> {
        match self {
            Loaded::Surface(_) => None,
            Loaded::Scene(s) => Some(s),
        }
    }
}

impl SceneSpec {
    /// Parses `sphere`, `sphere:R`, `ellipsoid:A,B,C`, `box:LX,LY,LZ`, a
    /// built-in scene name, or a path ending in `.obj`, `.gltf` or `.glb`.
    pub fn parse(text: &str) -> Result<Self, BadInput> {
        let text = text.trim();
        let lower = text.to_ascii_lowercase();
        if lower.ends_with(".obj") {
            return Ok(SceneSpec::Obj(PathBuf::from(text)));
        }
        if lower.ends_with(".gltf") || lower.ends_with(".glb") {
            return Ok(SceneSpec::Gltf(PathBuf::from(text)));
        }
        if let Some((name, _)) = BUILTIN_SCENES
            .iter()
            .find(|(name, _)| name.eq_ignore_ascii_case(text))
        {
            return Ok(SceneSpec::Builtin(name.to_string()));
        }
        let (kind, params) = match text.split_once(':') {
            Some((k, p)) => (k.trim().to_ascii_lowercase(), Some(p)),
            None => (text.to_ascii_lowercase(), None),
        };
        match kind.as_str() {
            "sphere" => match params {
                None => Ok(SceneSpec::Sphere(1.0)),
                Some(p) => {
                    let [r] = numbers::<1>(text, p, "a radius R")?;
                    Ok(SceneSpec::Sphere(r))
                }
            },
            "ellipsoid" => {
                let [a, b, c] = numbers::<3>(text, params.unwrap_or(""), "three semi-axes A,B,C")?;
                Ok(SceneSpec::Ellipsoid(a, b, c))
            }
            "box" => {
                let [a, b, c] =
                    numbers::<3>(text, params.unwrap_or(""), "three side lengths LX,LY,LZ")?;
                Ok(SceneSpec::Box(a, b, c))
            }
            _ => Err(bad_input(format!(
                "unknown scene '{text}': valid scenes are {VALID_FORMS}"
            ))),
        }
    }

    /// True for scenes whose materials give ρ and E.
    pub fn has_materials(&self) -> bool {
        matches!(
            self,
            SceneSpec::Builtin(_) | SceneSpec::Obj(_) | SceneSpec::Gltf(_)
        )
    }

    /// Builds or reads the scene. OBJ and glTF errors (file, line or mesh,
    /// value) are bad input.
    pub fn load(&self) -> Result<Loaded, BadInput> {
        let scene = match *self {
            SceneSpec::Sphere(r) => return Ok(Loaded::Surface(Arc::new(shapes::sphere(r)))),
            SceneSpec::Ellipsoid(a, b, c) => {
                return Ok(Loaded::Surface(Arc::new(shapes::ellipsoid(a, b, c))))
            }
            SceneSpec::Box(a, b, c) => {
                return Ok(Loaded::Surface(Arc::new(shapes::box_room(a, b, c))))
            }
            SceneSpec::Builtin(ref name) => {
                builtin(name).expect("parse accepts only built-in names")
            }
            SceneSpec::Obj(ref path) => load_obj(path),
            SceneSpec::Gltf(ref path) => load_gltf(path),
        };
        scene
            .map(|s| Loaded::Scene(Arc::new(s)))
            .map_err(|e| bad_input(e.to_string()))
    }
}

/// Exactly `N` comma-separated finite positive numbers.
fn numbers<const N: usize>(scene: &str, text: &str, what: &str) -> Result<[f64; N], BadInput> {
    let parts: Vec<&str> = if text.trim().is_empty() {
        Vec::new()
    } else {
        text.split(',').map(str::trim).collect()
    };
    if parts.len() != N {
        return Err(bad_input(format!(
            "scene '{scene}' needs {what}, got {} number{}",
            parts.len(),
            if parts.len() == 1 { "" } else { "s" }
        )));
    }
    let mut out = [0.0; N];
    for (o, p) in out.iter_mut().zip(&parts) {
        let v: f64 = p
            .parse()
            .map_err(|_| bad_input(format!("scene '{scene}': '{p}' is not a number")))?;
        if !(v.is_finite() && v > 0.0) {
            return Err(bad_input(format!(
                "scene '{scene}': {what} must be finite and > 0, got {p}"
            )));
        }
        *o = v;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_the_documented_forms() {
        assert_eq!(SceneSpec::parse("sphere").unwrap(), SceneSpec::Sphere(1.0));
        assert_eq!(
            SceneSpec::parse("sphere:2.5").unwrap(),
            SceneSpec::Sphere(2.5)
        );
        assert_eq!(
            SceneSpec::parse("ellipsoid:1,2,3").unwrap(),
            SceneSpec::Ellipsoid(1.0, 2.0, 3.0)
        );
        assert_eq!(
            SceneSpec::parse("box:1,1,2").unwrap(),
            SceneSpec::Box(1.0, 1.0, 2.0)
        );
        assert_eq!(
            SceneSpec::parse("Cornell").unwrap(),
            SceneSpec::Builtin("cornell".into())
        );
        assert_eq!(
            SceneSpec::parse("plates").unwrap(),
            SceneSpec::Builtin("plates".into())
        );
        assert!(matches!(
            SceneSpec::parse("room.OBJ").unwrap(),
            SceneSpec::Obj(_)
        ));
    }

    #[test]
    fn rejects_bad_scenes_with_clear_messages() {
        let msg = |s: &str| SceneSpec::parse(s).unwrap_err().to_string();
        assert!(msg("torus").contains("valid scenes"));
        assert!(msg("box:1,2").contains("got 2 numbers"));
        assert!(msg("sphere:-1").contains("> 0"));
        assert!(msg("sphere:inf").contains("finite"));
        assert!(msg("ellipsoid:1,x,2").contains("'x' is not a number"));
        let missing = SceneSpec::parse("no/such/file.obj").unwrap().load();
        let msg = missing.unwrap_err().to_string();
        assert!(msg.contains("no/such/file.obj"), "{msg}");
    }
}
