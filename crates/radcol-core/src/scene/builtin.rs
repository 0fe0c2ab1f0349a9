//! Built-in scenes, shipped as OBJ + MTL files under `scenes/` at the
//! repository root and read through the same OBJ path as user files.

use super::{load_obj_str, Scene, SceneError};
use crate::camera::Camera;
use glam::DVec3;

/// Built-in scenes: (name, description).
pub const BUILTIN_SCENES: &[(&str, &str)] = &[
    (
        "cornell",
        "the Cornell box (Cornell University measured geometry, mm; Bitterli's RGB materials), light cut into the ceiling",
    ),
    (
        "room",
        "an empty 4 x 3 x 5 m box room with white walls and a 1 x 1 m ceiling light (convex: no visibility tests)",
    ),
    (
        "lroom",
        "an L-shaped 3 m high room (legs 6 x 4 and 3 x 4 m) with a ceiling light in one leg: concave edges and the shadow of its re-entrant corner",
    ),
    (
        "shadow",
        "a floor lit by a square light through a floating square occluder (umbra and penumbra; exact answer by Lambert's formula)",
    ),
    (
        "plates",
        "two facing unit squares one unit apart, the top one emitting (mirror-image triangulations)",
    ),
];

impl Scene {
    /// The built-in scene `name` (see [`BUILTIN_SCENES`]); an unknown name
    /// is [`SceneError::NoSuchBuiltin`], listing the names there are.
    pub fn builtin(name: &str) -> Result<Scene, SceneError> {
        builtin(name).unwrap_or_else(|| {
            let known: Vec<&str> = BUILTIN_SCENES.iter().map(|(n, _)| *n).collect();
            Err(SceneError::NoSuchBuiltin {
                name: name.into(),
                known: known.join(", "),
            })
        })
    }
}

/// The built-in scene `name` (see [`BUILTIN_SCENES`]), or None when there is
/// none of that name.
pub fn builtin(name: &str) -> Option<Result<Scene, SceneError>> {
    // Metres per unit: the Cornell box's data are millimetres, the rooms'
    // metres; the shadow and plates scenes are unitless (taken as metres).
    let metres = if name == "cornell" { 1e-3 } else { 1.0 };
    let (obj, mtl_name, mtl, camera) = match name {
        "cornell" => (
            include_str!("../../../../scenes/cornell.obj"),
            "cornell.mtl",
            include_str!("../../../../scenes/cornell.mtl"),
            // A 35 mm lens on 25 mm film.
            Camera {
                eye: DVec3::new(278.0, 273.0, -800.0),
                target: DVec3::new(278.0, 273.0, 0.0),
                up: DVec3::Y,
                fov_y_deg: 2.0 * (12.5f64 / 35.0).atan().to_degrees(),
            },
        ),
        "room" => (
            include_str!("../../../../scenes/room.obj"),
            "room.mtl",
            include_str!("../../../../scenes/room.mtl"),
            // Standing near the front wall, looking at the back wall.
            Camera {
                eye: DVec3::new(2.0, 1.6, 0.3),
                target: DVec3::new(2.0, 1.3, 5.0),
                up: DVec3::Y,
                fov_y_deg: 60.0,
            },
        ),
        "lroom" => (
            include_str!("../../../../scenes/lroom.obj"),
            "lroom.mtl",
            include_str!("../../../../scenes/lroom.mtl"),
            // In the lit leg's corner, looking down the room towards the
            // re-entrant edge and the second leg behind it.
            Camera {
                eye: DVec3::new(5.6, 1.7, 0.3),
                target: DVec3::new(1.5, 1.0, 6.0),
                up: DVec3::Y,
                fov_y_deg: 70.0,
            },
        ),
        "shadow" => (
            include_str!("../../../../scenes/shadow.obj"),
            "shadow.mtl",
            include_str!("../../../../scenes/shadow.mtl"),
            // Between the occluder's and the light's heights, off a corner:
            // the shadow and the light's underside.
            Camera {
                eye: DVec3::new(-1.9, -1.5, 0.5),
                target: DVec3::new(0.1, 0.0, 0.0),
                up: DVec3::Z,
                fov_y_deg: 50.0,
            },
        ),
        "plates" => (
            include_str!("../../../../scenes/plates.obj"),
            "plates.mtl",
            include_str!("../../../../scenes/plates.mtl"),
            // From the side, level with the gap between the plates.
            Camera {
                eye: DVec3::new(0.5, -2.5, 0.5),
                target: DVec3::new(0.5, 0.5, 0.5),
                up: DVec3::Z,
                fov_y_deg: 40.0,
            },
        ),
        _ => return None,
    };
    Some(
        load_obj_str(name, obj, &[(mtl_name, mtl)]).and_then(|mut scene| {
            camera.validate().map_err(|message| SceneError::Camera {
                name: name.into(),
                message,
            })?;
            scene.camera = Some(camera);
            scene.metres_per_unit = Some(metres);
            Ok(scene)
        }),
    )
}
