//! The winding check: a triangle whose front (counter-clockwise) side faces
//! no other surface exchanges no light, which in a closed scene almost
//! always means it is wound the wrong way (a floor facing down gives an
//! almost black image). Such triangles are warned about, emitters with
//! their own message; a scene in which no two triangles face each other
//! gets one warning for the whole.

use super::overlap::plane_key;
use super::raw::{Capped, RawTriangle};
use super::Material;
use glam::DVec3;
use std::collections::HashSet;

/// At most this many triangle pairs are compared (the check stops early for
/// each triangle that faces something, so this bounds only scenes with very
/// many triangles facing nothing).
const MAX_PAIR_TESTS: u64 = 200_000_000;

/// The message of a scene in which no two triangles face each other.
pub(super) const NOTHING_FACES: &str = "no two triangles of the scene face each other, so no light passes between surfaces and u = E; counter-clockwise faces are the lit side";

/// Warns for every triangle of `tris` (from `kept`) with no other triangle
/// in front of it that it is also in front of; `scale` is the scene's size.
pub(super) fn facing_nothing(
    tris: &[[DVec3; 3]],
    kept: &[RawTriangle],
    materials: &[Material],
    scale: f64,
    warnings: &mut Vec<String>,
) {
    let eps = 1e-9 * scale;
    let normals: Vec<DVec3> = tris
        .iter()
        .map(|[a, b, c]| (*b - *a).cross(*c - *a).normalize_or_zero())
        .collect();
    // Whether some vertex of triangle j lies in front of triangle i's plane.
    let in_front = |i: usize, j: usize| {
        tris[j]
            .iter()
            .any(|v| (*v - tris[i][0]).dot(normals[i]) > eps)
    };
    // One triangle of each plane first: in a room a floor triangle meets a
    // wall among the first few instead of after every other floor triangle.
    let order = planes_first(tris, scale);
    let mut tests = 0u64;
    let mut lone = Vec::new();
    let mut stopped = None;
    for i in 0..tris.len() {
        if tests > MAX_PAIR_TESTS {
            stopped = Some(i);
            break;
        }
        let sees = order.iter().filter(|&&j| j != i).any(|&j| {
            tests += 1;
            in_front(i, j) && in_front(j, i)
        });
        if !sees {
            lone.push(i);
        }
    }
    if stopped.is_none() && lone.len() == tris.len() && !tris.is_empty() {
        warnings.push(NOTHING_FACES.to_string());
        return;
    }
    let mut capped = Capped::new(warnings, "facing-nothing");
    for i in lone {
        let t = &kept[i];
        let what = if materials[t.material].is_emitter() {
            "emitter: its front (counter-clockwise) side faces no other surface, so its light reaches nothing"
        } else {
            "its front (counter-clockwise) side faces no other surface, so it receives and reflects no light"
        };
        capped.push(format!(
            "{} (group '{}'): {what}; is it wound the wrong way?",
            t.at, t.group
        ));
    }
    if let Some(i) = stopped {
        capped.push(format!(
            "the winding check stopped after {MAX_PAIR_TESTS} triangle pairs (at {}): the scene has very many triangles whose front side faces nothing",
            kept[i].at
        ));
    }
}

/// Triangle indices with the first triangle of every distinct oriented
/// plane (the overlap check's [`plane_key`]) ahead of all the others.
fn planes_first(tris: &[[DVec3; 3]], scale: f64) -> Vec<usize> {
    let mut seen = HashSet::new();
    let (mut first, mut rest): (Vec<usize>, Vec<usize>) =
        (0..tris.len()).partition(|&i| plane_key(&tris[i], scale).is_some_and(|k| seen.insert(k)));
    first.append(&mut rest);
    first
}
