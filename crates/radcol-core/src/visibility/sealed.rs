//! Closed meshes among the occluders, and which of their triangles a segment
//! can meet first.
//!
//! Let C be a closed, consistently oriented triangle mesh (every edge shared
//! by exactly two of its triangles, in opposite directions), and R its
//! *front region*: the side its normals point to (the outside of a bunny,
//! the inside of a room whose walls face in). A segment that starts in R and
//! meets C crosses it first from R to the other side, through a triangle T
//! whose front faces the start P: (P − T.v0)·n_T > 0. So a segment from P is
//! blocked by C if and only if it is blocked by a triangle of C facing P,
//! and the triangles of C that face away from every point of an element A
//! can be left out of A's candidates, when segments from A start in R.
//!
//! That holds for an element A of C itself (a segment into A's front
//! half-space starts on A's front side, which is R), and for an element
//! clear of C whose points lie in R (a ray's crossings with C, counted).
//! An element touching C, or lying on it the other way round (a floor
//! under a box's coplanar bottom face), is never given the shortcut: its
//! candidates stay complete, and visibility exact either way.
//!
//! Behind a closed mesh about half its triangles face away from an element,
//! and the polygon overlay of the merged shadows crosses fewer edges.

use super::occluder::Occluder;
use glam::DVec3;
use std::collections::HashMap;

/// Occluders of no closed component.
const NONE: u32 = u32::MAX;

/// The closed, consistently oriented components of a set of occluders.
#[derive(Debug, Default)]
pub(crate) struct Sealed {
    /// Per occluder, its closed component, or [`NONE`].
    comp: Vec<u32>,
    comps: Vec<Component>,
}

#[derive(Debug)]
struct Component {
    tris: Vec<u32>,
    /// True when the normals point out of the enclosed volume (positive
    /// signed volume): the front region is the outside.
    outward: bool,
    lo: DVec3,
    hi: DVec3,
}

/// Bit pattern of a position (-0 read as 0), so that vertices shared by
/// triangles match exactly.
fn key(v: DVec3) -> [u64; 3] {
    v.to_array().map(|x| (x + 0.0).to_bits())
}

fn find(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        let up = parent[parent[i as usize] as usize];
        parent[i as usize] = up;
        i = up;
    }
    i
}

impl Sealed {
    /// Finds the closed components of `tris` (connected through shared
    /// edges; every directed edge matched by exactly one reverse edge).
    pub(crate) fn new(tris: &[Occluder]) -> Self {
        let n = tris.len();
        let mut ids: HashMap<[u64; 3], u32> = HashMap::new();
        let vid: Vec<[u32; 3]> = tris
            .iter()
            .map(|t| {
                t.v.map(|v| {
                    let next = ids.len() as u32;
                    *ids.entry(key(v)).or_insert(next)
                })
            })
            .collect();
        // Directed edges: the triangles using each.
        let mut edges: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
        for (i, v) in vid.iter().enumerate() {
            for e in 0..3 {
                edges
                    .entry((v[e], v[(e + 1) % 3]))
                    .or_default()
                    .push(i as u32);
            }
        }
        let mut parent: Vec<u32> = (0..n as u32).collect();
        let mut open = vec![false; n];
        for (&(a, b), users) in &edges {
            let back = edges.get(&(b, a));
            match back {
                Some(r) if users.len() == 1 && r.len() == 1 => {
                    let (x, y) = (find(&mut parent, users[0]), find(&mut parent, r[0]));
                    parent[x as usize] = y;
                }
                _ => users.iter().for_each(|&i| open[i as usize] = true),
            }
        }
        let mut members: HashMap<u32, Vec<u32>> = HashMap::new();
        for i in 0..n as u32 {
            let r = find(&mut parent, i);
            members.entry(r).or_default().push(i);
        }
        let mut sealed = Self {
            comp: vec![NONE; n],
            comps: Vec::new(),
        };
        let mut roots: Vec<_> = members.into_iter().collect();
        roots.sort_unstable_by_key(|(r, _)| *r);
        for (_, tri_ids) in roots {
            if tri_ids.iter().any(|&i| open[i as usize]) {
                continue;
            }
            let volume: f64 = tri_ids
                .iter()
                .map(|&i| {
                    let v = tris[i as usize].v;
                    v[0].dot(v[1].cross(v[2]))
                })
                .sum();
            let (lo, hi) =
                crate::geometry::bounds(tri_ids.iter().flat_map(|&i| tris[i as usize].v));
            if volume == 0.0 {
                continue;
            }
            let c = sealed.comps.len() as u32;
            for &i in &tri_ids {
                sealed.comp[i as usize] = c;
            }
            sealed.comps.push(Component {
                tris: tri_ids,
                outward: volume > 0.0,
                lo,
                hi,
            });
        }
        sealed
    }

    /// The closed component of occluder `i`, if any.
    #[inline]
    pub(crate) fn component(&self, i: u32) -> Option<u32> {
        self.comp.get(i as usize).copied().filter(|&c| c != NONE)
    }

    /// Number of closed components.
    #[cfg(test)]
    pub(crate) fn len(&self) -> usize {
        self.comps.len()
    }

    /// True when every segment from a point of the flat triangle `a` (unit
    /// normal `n_a`) into its front half-space starts in component `c`'s
    /// front region: `a` lies on `c` facing the same way, or clear of `c` in
    /// its front region. False when that is not certain (`a` touching `c`,
    /// or a ray's count of crossings ambiguous). `tol`: the scene's length
    /// tolerance.
    pub(crate) fn starts_in_front(
        &self,
        c: u32,
        tris: &[Occluder],
        a: &[DVec3; 3],
        n_a: DVec3,
        tol: f64,
    ) -> bool {
        let comp = &self.comps[c as usize];
        let (lo, hi) = crate::geometry::bounds(a.iter().copied());
        if (lo - comp.hi).max_element() > tol || (comp.lo - hi).max_element() > tol {
            // Clear of the component's box: outside the enclosed volume.
            return comp.outward;
        }
        for &i in &comp.tris {
            let t = &tris[i as usize];
            if let Some(same) = lies_on(a, n_a, t, tol) {
                return same;
            }
        }
        let near = |t: &Occluder| {
            let (tl, th) = crate::geometry::bounds(t.v);
            (lo - th).max_element() <= tol && (tl - hi).max_element() <= tol
        };
        if comp
            .tris
            .iter()
            .map(|&i| &tris[i as usize])
            .any(|t| near(t) && !apart(a, t, tol))
        {
            return false;
        }
        let centre = (a[0] + a[1] + a[2]) / 3.0;
        match inside(centre, comp.tris.iter().map(|&i| &tris[i as usize]), tol) {
            Some(inside) => inside != comp.outward,
            None => false,
        }
    }
}

/// Of the candidates `cands` of a pair, those that can block a segment from
/// the point `p` of the row element: leaves out the triangles of the closed
/// components `in_front` (from whose front region the row element's
/// segments start) that face away from `p`.
pub(crate) fn facing_point<'a>(
    occ: &super::Occluders,
    in_front: &[u32],
    cands: &'a [u32],
    p: DVec3,
) -> std::borrow::Cow<'a, [u32]> {
    let sealed = occ.sealed();
    let away = |i: u32| {
        sealed
            .component(i)
            .is_some_and(|c| in_front.binary_search(&c).is_ok())
            && {
                let t = occ.get(i);
                (p - t.v[0]).dot(t.normal) <= 0.0
            }
    };
    if in_front.is_empty() || !cands.iter().any(|&i| away(i)) {
        return std::borrow::Cow::Borrowed(cands);
    }
    std::borrow::Cow::Owned(cands.iter().copied().filter(|&i| !away(i)).collect())
}

/// Some(true) when the flat triangle `a` lies in triangle `t` with the same
/// orientation, Some(false) when with the opposite one, None otherwise.
fn lies_on(a: &[DVec3; 3], n_a: DVec3, t: &Occluder, tol: f64) -> Option<bool> {
    let cos = n_a.dot(t.normal);
    if cos.abs() < 1.0 - 1e-9 || a.iter().any(|&x| (x - t.v[0]).dot(t.normal).abs() > tol) {
        return None;
    }
    let inside = a.iter().all(|&x| {
        let (e0, e1, e2) = (t.v[1] - t.v[0], t.v[2] - t.v[1], t.v[0] - t.v[2]);
        let edge_ok = |e: DVec3, from: DVec3| e.cross(x - from).dot(t.normal) >= -tol * e.length();
        edge_ok(e0, t.v[0]) && edge_ok(e1, t.v[1]) && edge_ok(e2, t.v[2])
    });
    inside.then_some(cos > 0.0)
}

/// True when triangles `a` and `t` are separated by a gap wider than `tol`
/// along one of the separating-axis theorem's axes (touching is not apart).
fn apart(a: &[DVec3; 3], t: &Occluder, tol: f64) -> bool {
    let gap = |axis: DVec3| -> bool {
        let len = axis.length();
        if len <= 1e-300 {
            return false;
        }
        let (mut a0, mut a1) = (f64::INFINITY, f64::NEG_INFINITY);
        for x in a {
            let d = x.dot(axis);
            (a0, a1) = (a0.min(d), a1.max(d));
        }
        let (mut t0, mut t1) = (f64::INFINITY, f64::NEG_INFINITY);
        for x in &t.v {
            let d = x.dot(axis);
            (t0, t1) = (t0.min(d), t1.max(d));
        }
        (t0 - a1).max(a0 - t1) > tol * len
    };
    let ea = [a[1] - a[0], a[2] - a[1], a[0] - a[2]];
    let et = [t.v[1] - t.v[0], t.v[2] - t.v[1], t.v[0] - t.v[2]];
    let na = ea[0].cross(ea[1]);
    gap(na)
        || gap(t.normal)
        || ea.iter().any(|&e| et.iter().any(|&f| gap(e.cross(f))))
        || ea.iter().any(|&e| gap(e.cross(na)))
        || et.iter().any(|&f| gap(f.cross(t.normal)))
}

/// Whether `p` is inside the closed mesh `tris` (an odd number of crossings
/// along a ray), or None when three rays in unrelated directions all graze
/// an edge, a vertex or a face's plane.
fn inside<'a>(
    p: DVec3,
    tris: impl Iterator<Item = &'a Occluder> + Clone,
    tol: f64,
) -> Option<bool> {
    const DIRS: [[f64; 3]; 3] = [
        [0.573_462_1, 0.613_287_5, 0.543_250_9],
        [-0.312_771_4, 0.887_136_2, -0.339_434_1],
        [0.701_353_3, -0.214_980_7, -0.679_606_2],
    ];
    'ray: for d in DIRS {
        let d = DVec3::from_array(d).normalize();
        let mut crossings = 0u32;
        for t in tris.clone() {
            match crossing(p, d, t, tol) {
                Crossing::No => {}
                Crossing::Yes => crossings += 1,
                Crossing::Grazing => continue 'ray,
            }
        }
        return Some(crossings % 2 == 1);
    }
    None
}

enum Crossing {
    No,
    Yes,
    Grazing,
}

/// Whether the ray p + s d (s > 0) crosses triangle `t` in its interior.
fn crossing(p: DVec3, d: DVec3, t: &Occluder, tol: f64) -> Crossing {
    let h = (p - t.v[0]).dot(t.normal);
    let along = d.dot(t.normal);
    if along.abs() < 1e-12 {
        // Parallel: only a ray within the plane could meet it.
        return if h.abs() <= tol {
            Crossing::Grazing
        } else {
            Crossing::No
        };
    }
    let s = -h / along;
    if s < -tol {
        return Crossing::No;
    }
    let x = p + s * d;
    let mut least = f64::INFINITY;
    for e in 0..3 {
        let (a, b) = (t.v[e], t.v[(e + 1) % 3]);
        let edge = b - a;
        let side = edge.cross(x - a).dot(t.normal) / edge.length();
        least = least.min(side);
    }
    if least < -tol {
        Crossing::No
    } else if least <= tol || s <= tol {
        Crossing::Grazing
    } else {
        Crossing::Yes
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::shapes::room_with_cube;
    use crate::visibility::{base_triangles, Occluders};

    /// The room [0, 2]³ (normals in, occluders 0..12) and the cube
    /// [0.7, 1.3]³ (normals out, 12..24) of `room_with_cube`.
    fn room_and_cube() -> Occluders {
        Occluders::new(&base_triangles(&room_with_cube()))
    }

    #[test]
    fn closed_boxes_are_sealed_and_open_ones_are_not() {
        let occ = room_and_cube();
        let mut tris = occ.all().to_vec();
        // An open box: the cube moved, one face missing.
        let shift = DVec3::new(0.5, 0.0, 0.0);
        tris.extend(occ.all()[12..22].iter().map(|t| Occluder {
            v: t.v.map(|x| x + shift),
            normal: t.normal,
        }));
        let s = Sealed::new(&tris);
        assert_eq!(s.len(), 2);
        assert!((0..24).all(|i| s.component(i).is_some()));
        assert!((24..34).all(|i| s.component(i).is_none()));
        let (room, cube) = (s.component(0).unwrap(), s.component(12).unwrap());
        assert!(!s.comps[room as usize].outward && s.comps[cube as usize].outward);
    }

    /// Which elements get the shortcut for the cube (normals out) and the
    /// room around it (normals in).
    #[test]
    fn elements_start_in_front_only_where_that_is_certain() {
        let occ = room_and_cube();
        let s = occ.sealed();
        let (room, cube) = (s.component(0).unwrap(), s.component(12).unwrap());
        let tol = 1e-9;
        let tri = |a: [f64; 3], b: [f64; 3], c: [f64; 3]| {
            let v = [DVec3::from(a), DVec3::from(b), DVec3::from(c)];
            let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
            (v, n)
        };
        let check =
            |(v, n): ([DVec3; 3], DVec3), c: u32| s.starts_in_front(c, occ.all(), &v, n, tol);
        // A part of one of the cube's triangles (z = 0.7, facing -z).
        let on_face = tri([0.75, 0.85, 0.7], [0.75, 1.0, 0.7], [0.85, 1.0, 0.7]);
        assert!(on_face.1.z < -0.999);
        assert!(check(on_face, cube));
        // The same place facing the other way (into the cube): no.
        let (v, n) = on_face;
        assert!(!check(([v[0], v[2], v[1]], -n), cube));
        // Clear of the cube, outside it: yes; inside the cube: no.
        let beside = tri([1.6, 0.1, 0.1], [1.6, 0.3, 0.1], [1.6, 0.1, 0.3]);
        assert!(check(beside, cube));
        assert!(!check(
            tri([0.9, 0.9, 1.0], [1.1, 0.9, 1.0], [0.9, 1.1, 1.0]),
            cube
        ));
        // Touching the cube (a floor in the plane of its bottom): no.
        let floor = tri([0.5, 0.5, 0.7], [1.5, 0.5, 0.7], [0.5, 1.5, 0.7]);
        assert!(!check(floor, cube));
        // Cutting through the cube: no.
        assert!(!check(
            tri([1.0, 1.0, 0.5], [1.0, 1.0, 1.5], [1.5, 1.0, 1.0]),
            cube
        ));
        // Inside the room (its front region): yes; outside it: no.
        assert!(check(beside, room));
        assert!(!check(
            tri([2.5, 0.5, 0.5], [2.5, 0.7, 0.5], [2.5, 0.5, 0.7]),
            room
        ));
    }
}
