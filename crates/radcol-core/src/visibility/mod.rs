//! Visibility V(P, Q) for scenes that can occlude.
//!
//! The paper treats unoccluded surfaces (V ≡ 1). A scene needs visibility only
//! when some segment between two of its points can cross a third part of it;
//! [`analyze`] decides that from the geometry once, so convex enclosures (the
//! built-in analytic surfaces, a box room, two facing plates) never pay for it.

pub(crate) mod bounce;
pub mod clip;
mod hull;
mod occluder;
pub mod occluders;
pub(crate) mod partial_row;
pub(crate) mod sealed;
pub(crate) mod walk;

pub use occluders::Occluders;

/// A flat triangle's mapped vertices and unit normal.
pub(crate) type Plane = ([DVec3; 3], DVec3);

use crate::error::InputError;
use crate::geometry::Surface;
use glam::DVec3;
use serde::Serialize;

/// Whether a surface needs visibility tests, and why: decided once per
/// surface ([`analyze`]) and carried through the pipeline to the plan and
/// the reports.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct VisibilityAnalysis {
    /// True when some pair of points may be occluded.
    pub needed: bool,
    /// One sentence for reports.
    pub reason: String,
    /// The surface's name and its first curved patch, when visibility is
    /// needed because of it: radcol clips flat elements only, so such a
    /// surface is refused ([`VisibilityAnalysis::check_supported`]).
    #[serde(skip)]
    pub curved: Option<(String, String)>,
    /// Per patch: whether pairs with its elements as columns may have their
    /// visibility approximated within a budget
    /// ([`crate::assembly::QuadratureOptions::visibility_budget`]): the
    /// patches that emit nothing ([`VisibilityAnalysis::with_bounce_patches`]).
    /// Empty: none may (every pair exact).
    #[serde(skip)]
    pub bounce_patches: Vec<bool>,
}

impl VisibilityAnalysis {
    /// The analysis with `patches` ([`VisibilityAnalysis::bounce_patches`]).
    pub fn with_bounce_patches(self, patches: Vec<bool>) -> Self {
        Self {
            bounce_patches: patches,
            ..self
        }
    }

    /// Refuses a surface whose occlusion radcol cannot model (a curved patch
    /// in a surface not known to bound a convex set), instead of returning a
    /// silently wrong answer.
    pub fn check_supported(&self) -> Result<(), InputError> {
        match &self.curved {
            Some((surface, patch)) => Err(InputError::CurvedOcclusion {
                surface: surface.clone(),
                patch: patch.clone(),
            }),
            None => Ok(()),
        }
    }
}

/// The mapped straight triangles of every base triangle, oriented as given.
pub fn base_triangles(surface: &Surface) -> Vec<[DVec3; 3]> {
    surface
        .patches
        .iter()
        .flat_map(|p| p.triangles.iter().map(move |t| t.map(|x| p.map.map(x))))
        .collect()
}

/// Decides whether `surface` can occlude itself.
///
/// A surface whose every (flat) triangle has all of the surface's vertices on
/// its front side (or in its plane) lies on the boundary of the convex set
/// bounded by those planes, with its normals pointing inside: a segment
/// between two of its points then runs through the interior of that set or
/// within one face plane (where G = 0), so V ≡ 1 on every pair that matters.
/// Curved patches rely on [`Surface::convex_enclosure`], set by the code that
/// built them.
pub fn analyze(surface: &Surface) -> VisibilityAnalysis {
    if surface.convex_enclosure {
        return VisibilityAnalysis {
            needed: false,
            reason: "no visibility tests: the surface lies on the boundary of a convex set, facing inward"
                .into(),
            curved: None,
            bounce_patches: Vec::new(),
        };
    }
    if let Some(p) = surface.patches.iter().find(|p| !p.map.is_affine()) {
        return VisibilityAnalysis {
            needed: true,
            reason: format!(
                "visibility needed: patch '{}' is curved and the surface is not known to bound a convex set",
                p.name
            ),
            curved: Some((surface.name.clone(), p.name.clone())),
            bounce_patches: Vec::new(),
        };
    }
    let tris = base_triangles(surface);
    match concave_witness(&tris) {
        None => VisibilityAnalysis {
            needed: false,
            reason: "no visibility tests: every triangle's plane has the whole scene on its front side \
                     (the scene lies on the boundary of a convex set, facing inward)"
                .into(),
            curved: None,
            bounce_patches: Vec::new(),
        },
        Some((t, v)) => VisibilityAnalysis {
            needed: true,
            reason: format!(
                "visibility needed: vertex {:.6}, {:.6}, {:.6} lies behind the plane of triangle {t}, \
                 so parts of the scene may hide others",
                v.x, v.y, v.z
            ),
            curved: None,
            bounce_patches: Vec::new(),
        },
    }
}

/// True when every triangle has all vertices of `tris` on its front side.
#[cfg(any(test, feature = "scenes", feature = "internals"))]
pub fn is_convex_enclosure(tris: &[[DVec3; 3]]) -> bool {
    concave_witness(tris).is_none()
}

/// A triangle index and a vertex strictly behind its plane, if any (relative
/// tolerance 1e-9 of the scene's size, so that units do not matter).
///
/// Each distinct plane is tested once against every vertex, in parallel: a
/// flat floor of 361 k triangles is one plane (the test over every triangle
/// had taken minutes before a memory check could refuse the scene).
fn concave_witness(tris: &[[DVec3; 3]]) -> Option<(usize, DVec3)> {
    use rayon::prelude::*;
    let (lo, hi) = crate::geometry::bounds(tris.iter().flatten().copied());
    let scale = (hi - lo).length();
    let mut verts: Vec<DVec3> = tris.iter().flatten().copied().collect();
    verts.sort_by(|a, b| {
        a.to_array()
            .partial_cmp(&b.to_array())
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    verts.dedup();
    // One representative triangle per plane (unit normal and offset rounded
    // to 1e-12; planes split by the rounding are merely tested twice).
    let mut planes: std::collections::HashMap<[i64; 4], usize> = Default::default();
    for (i, [a, b, c]) in tris.iter().enumerate() {
        let n = (*b - *a).cross(*c - *a);
        let len = n.length();
        if len.is_nan() || len <= 0.0 {
            continue;
        }
        let n = n / len;
        let q = |x: f64| (x * 1e12).round() as i64;
        planes
            .entry([q(n.x), q(n.y), q(n.z), q(a.dot(n) / scale)])
            .or_insert(i);
    }
    let mut reps: Vec<usize> = planes.into_values().collect();
    reps.sort_unstable();
    reps.par_iter().find_map_first(|&i| {
        let [a, b, c] = tris[i];
        let n = (b - a).cross(c - a).normalize();
        verts
            .iter()
            .find(|v| (**v - a).dot(n) < -1e-9 * scale)
            .map(|v| (i, *v))
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::shapes::box_room;

    #[test]
    fn box_room_is_convex_and_a_room_with_a_cube_is_not() {
        let room = box_room(1.0, 2.0, 1.5);
        let tris = base_triangles(&room);
        assert!(is_convex_enclosure(&tris));
        // Turning one wall around (normal outward) breaks it.
        let mut flipped = tris.clone();
        flipped[0] = [flipped[0][0], flipped[0][2], flipped[0][1]];
        assert!(!is_convex_enclosure(&flipped));
        // A small floating triangle facing up inside the room: the room's
        // walls are behind it.
        let mut with_blocker = tris;
        with_blocker.push([
            DVec3::new(0.4, 0.4, 0.5),
            DVec3::new(0.6, 0.4, 0.5),
            DVec3::new(0.5, 0.6, 0.5),
        ]);
        assert!(!is_convex_enclosure(&with_blocker));
    }

    #[test]
    fn facing_plates_are_convex() {
        let sq = |z: f64, up: bool| {
            let (a, b, c, d) = (
                DVec3::new(0., 0., z),
                DVec3::new(1., 0., z),
                DVec3::new(1., 1., z),
                DVec3::new(0., 1., z),
            );
            if up {
                vec![[a, b, c], [a, c, d]]
            } else {
                vec![[a, c, b], [a, d, c]]
            }
        };
        let mut tris = sq(0.0, true);
        tris.extend(sq(1.0, false));
        assert!(is_convex_enclosure(&tris));
        // Plates facing away from each other see nothing of each other but
        // are not a convex enclosure facing inward.
        let mut away = sq(0.0, false);
        away.extend(sq(1.0, true));
        assert!(!is_convex_enclosure(&away));
    }
}
