//! Scene names on the command line -> core surfaces.

use crate::error::{bad_input, BadInput};
use radcol_core::geometry::{shapes, Surface};

/// The forms a SCENE argument may take, for error messages.
pub const VALID_FORMS: &str = "sphere, sphere:R, ellipsoid:A,B,C, box:LX,LY,LZ \
(cornell and FILE.obj are accepted but not yet supported)";

/// A parsed SCENE argument.
#[derive(Clone, Debug, PartialEq)]
pub enum SceneSpec {
    /// Sphere of radius R about the origin.
    Sphere(f64),
    /// Ellipsoid with semi-axes a, b, c.
    Ellipsoid(f64, f64, f64),
    /// The room [0,lx]×[0,ly]×[0,lz].
    Box(f64, f64, f64),
    /// A mesh file (or the built-in Cornell box, which will be one).
    Obj(String),
}

impl SceneSpec {
    /// Parses `sphere`, `sphere:R`, `ellipsoid:A,B,C`, `box:LX,LY,LZ`, `cornell`, `*.obj`.
    pub fn parse(text: &str) -> Result<Self, BadInput> {
        let text = text.trim();
        if text.eq_ignore_ascii_case("cornell") || text.to_ascii_lowercase().ends_with(".obj") {
            return Ok(SceneSpec::Obj(text.to_string()));
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

    /// The core surface of this scene.
    pub fn surface(&self) -> Result<Surface, BadInput> {
        match *self {
            SceneSpec::Sphere(r) => Ok(shapes::sphere(r)),
            SceneSpec::Ellipsoid(a, b, c) => Ok(shapes::ellipsoid(a, b, c)),
            SceneSpec::Box(a, b, c) => Ok(shapes::box_room(a, b, c)),
            SceneSpec::Obj(ref path) => Err(bad_input(format!(
                "OBJ scenes are not yet supported (coming with the OBJ scene work): {path}"
            ))),
        }
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
        assert!(matches!(
            SceneSpec::parse("cornell").unwrap(),
            SceneSpec::Obj(_)
        ));
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
        assert!(SceneSpec::parse("cornell").unwrap().surface().is_err());
    }
}
