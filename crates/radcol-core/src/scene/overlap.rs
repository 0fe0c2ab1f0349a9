//! Coplanar triangles facing the same way that overlap: the same surface
//! given twice (a floor listed twice with different diagonals), which the
//! radiosity counts twice. Identical triangles are dropped as duplicates
//! before this; here the overlaps of different triangulations are found and
//! warned about.
//!
//! Triangles are grouped by oriented plane; within a plane they are projected
//! to 2D, bucketed in a grid of the plane's mean edge length, and each pair
//! sharing a cell is tested by separating axes (an overlap needs a positive
//! area in common: triangles meeting along an edge or at a vertex do not
//! overlap). The cost is linear in the number of triangles for meshes of
//! comparable edge lengths.

use glam::{DVec2, DVec3};
use std::collections::HashMap;

/// Pairs (i, j), i < j, of triangles of `tris` that overlap in their common
/// plane with the same orientation; `scale` is the scene's size, for the
/// plane tolerance.
pub(crate) fn coplanar_overlaps(tris: &[[DVec3; 3]], scale: f64) -> Vec<(usize, usize)> {
    let mut planes: HashMap<[i64; 4], Vec<usize>> = HashMap::new();
    for (i, t) in tris.iter().enumerate() {
        if let Some(key) = plane_key(t, scale) {
            planes.entry(key).or_default().push(i);
        }
    }
    let mut found = Vec::new();
    for members in planes.values().filter(|m| m.len() > 1) {
        found.extend(overlaps_in_plane(tris, members));
    }
    found.sort_unstable();
    found.dedup();
    found
}

/// Pairs (i, j) of triangles of `tris` that overlap seen along their
/// common normal, face each other and lie closer than 1e-9 of `scale`
/// apart (within the plane key's step) but not in one plane: the two walls
/// of a closed box thinner than quadrature can resolve. With the distance
/// between them. (Facing away, or at no distance, they are a two-sided
/// panel, which sees nothing of itself.)
pub(crate) fn facing_too_close(tris: &[[DVec3; 3]], scale: f64) -> Vec<(usize, usize, f64)> {
    let mut planes: HashMap<[i64; 4], Vec<usize>> = HashMap::new();
    for (i, t) in tris.iter().enumerate() {
        if let Some(key) = plane_key(t, scale) {
            planes.entry(key).or_default().push(i);
        }
    }
    let centre = |i: usize| (tris[i][0] + tris[i][1] + tris[i][2]) / 3.0;
    let mut found = Vec::new();
    for (key, front) in &planes {
        for step in -1..=1 {
            let flipped = [-key[0], -key[1], -key[2], -key[3] + step];
            let Some(back) = planes.get(&flipped) else {
                continue;
            };
            let members: Vec<usize> = front.iter().chain(back).copied().collect();
            let [a, b, c] = tris[front[0]];
            let n = (b - a).cross(c - a).normalize();
            for (i, j) in overlaps_in_plane(tris, &members) {
                let (k, l) = if front.contains(&i) { (i, j) } else { (j, i) };
                if !front.contains(&k) || !back.contains(&l) {
                    continue;
                }
                let gap = (centre(l) - centre(k)).dot(n);
                if gap > 0.0 {
                    found.push((k.min(l), k.max(l), gap));
                }
            }
        }
    }
    found.sort_by_key(|x| (x.0, x.1));
    found.dedup_by(|x, y| (x.0, x.1) == (y.0, y.1));
    found
}

/// The oriented plane of triangle `[a, b, c]` as a hashable key: unit
/// normal and offset (relative to `scale`) to 1e-9; None when degenerate.
pub(super) fn plane_key([a, b, c]: &[DVec3; 3], scale: f64) -> Option<[i64; 4]> {
    let n = (*b - *a).cross(*c - *a);
    let len = n.length();
    if !(len > 0.0 && len.is_finite()) {
        return None;
    }
    let n = n / len;
    let q = |x: f64| (x * 1e9).round() as i64;
    Some([q(n.x), q(n.y), q(n.z), q(a.dot(n) / scale)])
}

/// Overlapping pairs among `members`, all in one plane with one orientation.
fn overlaps_in_plane(tris: &[[DVec3; 3]], members: &[usize]) -> Vec<(usize, usize)> {
    let [a, b, c] = tris[members[0]];
    let n = (b - a).cross(c - a).normalize();
    let u = n.any_orthonormal_vector();
    let v = n.cross(u);
    let flat: Vec<[DVec2; 3]> = members
        .iter()
        .map(|&i| tris[i].map(|p| DVec2::new((p - a).dot(u), (p - a).dot(v))))
        .collect();
    let edges: f64 = flat
        .iter()
        .map(|t| {
            (0..3)
                .map(|e| (t[(e + 1) % 3] - t[e]).length())
                .sum::<f64>()
        })
        .sum();
    let h = edges / (3 * flat.len()) as f64;
    let cell = |p: DVec2| [(p.x / h).floor() as i64, (p.y / h).floor() as i64];
    let mut grid: HashMap<[i64; 2], Vec<usize>> = HashMap::new();
    for (k, t) in flat.iter().enumerate() {
        let lo = cell(t[0].min(t[1]).min(t[2]));
        let hi = cell(t[0].max(t[1]).max(t[2]));
        // A sliver across many cells is bucketed in each (bounded by its length / h).
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                grid.entry([x, y]).or_default().push(k);
            }
        }
    }
    let mut found = Vec::new();
    for list in grid.values() {
        for (p, &k) in list.iter().enumerate() {
            for &l in &list[p + 1..] {
                if overlap(&flat[k], &flat[l]) {
                    let (i, j) = (members[k], members[l]);
                    found.push((i.min(j), i.max(j)));
                }
            }
        }
    }
    found
}

/// True when two triangles share a positive area: no edge of either is a
/// separating axis (touching along an edge or at a point counts as apart, to
/// a tolerance of 1e-9 of their size).
fn overlap(s: &[DVec2; 3], t: &[DVec2; 3]) -> bool {
    let size = s
        .iter()
        .chain(t)
        .map(|p| (*p - s[0]).length())
        .fold(0.0, f64::max);
    let tol = 1e-9 * size;
    let separates = |tri: &[DVec2; 3], other: &[DVec2; 3]| {
        (0..3).any(|e| {
            let d = tri[(e + 1) % 3] - tri[e];
            let normal = DVec2::new(d.y, -d.x).normalize_or_zero();
            let own = tri.iter().map(|p| p.dot(normal));
            let theirs = other.iter().map(|p| p.dot(normal));
            let (own_lo, own_hi) = own.fold((f64::MAX, f64::MIN), |(l, h), x| (l.min(x), h.max(x)));
            let (lo, hi) = theirs.fold((f64::MAX, f64::MIN), |(l, h), x| (l.min(x), h.max(x)));
            lo >= own_hi - tol || hi <= own_lo + tol
        })
    };
    !separates(s, t) && !separates(t, s)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad(z: f64, diagonal: bool) -> Vec<[DVec3; 3]> {
        let p = |x: f64, y: f64| DVec3::new(x, y, z);
        let (a, b, c, d) = (p(0.0, 0.0), p(1.0, 0.0), p(1.0, 1.0), p(0.0, 1.0));
        if diagonal {
            vec![[a, b, c], [a, c, d]]
        } else {
            vec![[a, b, d], [b, c, d]]
        }
    }

    #[test]
    fn a_box_thinner_than_rounding_is_found_and_a_two_sided_panel_is_not() {
        // A unit square floor (up) under a ceiling (down) 1e-13 above it.
        let floor = quad(0.0, false);
        let flip = |t: &[DVec3; 3]| [t[0], t[2], t[1]];
        let ceiling: Vec<[DVec3; 3]> = (quad(1e-13, true).iter()).map(flip).collect();
        let thin: Vec<[DVec3; 3]> = floor.iter().chain(&ceiling).copied().collect();
        let found = facing_too_close(&thin, 1.0);
        assert!(!found.is_empty() && found.iter().all(|f| f.2 > 0.0 && f.2 < 1e-12));
        // The same faces turned outwards, and a panel at no distance: apart.
        let outward: Vec<[DVec3; 3]> = (quad(0.0, false).iter())
            .map(flip)
            .chain(quad(1e-13, true))
            .collect();
        assert!(facing_too_close(&outward, 1.0).is_empty());
        let panel: Vec<[DVec3; 3]> = floor
            .iter()
            .chain(floor.iter().map(flip).collect::<Vec<_>>().iter())
            .copied()
            .collect();
        assert!(facing_too_close(&panel, 1.0).is_empty());
        // A real room's floor and ceiling are far apart.
        let room: Vec<[DVec3; 3]> = floor
            .iter()
            .copied()
            .chain((quad(0.5, false).iter()).map(flip))
            .collect();
        assert!(facing_too_close(&room, 1.0).is_empty());
    }

    #[test]
    fn a_floor_given_twice_with_other_diagonals_overlaps() {
        let mut tris = quad(0.0, true);
        assert!(coplanar_overlaps(&tris, 1.0).is_empty(), "a split square");
        tris.extend(quad(0.0, false));
        let found = coplanar_overlaps(&tris, 1.0);
        // Each of the first pair overlaps each of the second.
        assert_eq!(found, vec![(0, 2), (0, 3), (1, 2), (1, 3)]);
    }

    #[test]
    fn neighbours_two_sided_panels_and_parallel_planes_do_not() {
        // A 10 × 10 grid of split squares: edges and corners shared only.
        let mut grid = Vec::new();
        for i in 0..10 {
            for j in 0..10 {
                let o = DVec3::new(i as f64, j as f64, 0.0);
                grid.extend(
                    quad(0.0, (i + j) % 2 == 0)
                        .into_iter()
                        .map(|t| t.map(|p| p + o)),
                );
            }
        }
        assert!(coplanar_overlaps(&grid, 15.0).is_empty());
        // The back side of a panel faces the other way: not a duplicate.
        let mut panel = quad(0.0, true);
        panel.extend(quad(0.0, false).into_iter().map(|[a, b, c]| [a, c, b]));
        assert!(coplanar_overlaps(&panel, 1.0).is_empty());
        // The same square 1e-3 higher: another plane.
        let mut stacked = quad(0.0, true);
        stacked.extend(quad(1e-3, false));
        assert!(coplanar_overlaps(&stacked, 1.0).is_empty());
    }
}
