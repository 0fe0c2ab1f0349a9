//! The triangles that can hide one part of a scene from another, with a BVH
//! (obvhs) for the broad phase and an exact separating-axis test for the
//! narrow phase.
//!
//! For a pair of flat elements A and B every segment between a point of A and
//! a point of B lies in the convex hull H = conv(A ∪ B), and H is the union of
//! those segments. A triangle that does not meet H (touching its boundary
//! counts as not meeting: it blocks only a set of measure zero) can therefore
//! never occlude the pair: V ≡ 1 on it, and the pair keeps its ordinary far or
//! near rule. Only the triangles that do meet H are kept as candidates, and the
//! pair is integrated with the visible part clipped exactly
//! ([`super::clip`]).

use super::hull::{Facets, HullAxes, Place};
use super::sealed::Sealed;
use crate::geometry::bounds;
use glam::{DVec3, Vec3A};
use obvhs::aabb::Aabb;
use obvhs::bvh2::builder::build_bvh2;
use obvhs::bvh2::Bvh2;
use obvhs::{Boundable, BvhBuildParams};
use std::time::Duration;

pub use super::occluder::Occluder;

/// A padded f32 box around one triangle, for the BVH builder.
struct PaddedBox(Aabb);

impl Boundable for PaddedBox {
    fn aabb(&self) -> Aabb {
        self.0
    }
}

/// Every triangle of a scene as a potential occluder, in a BVH.
pub struct Occluders {
    tris: Vec<Occluder>,
    bvh: Bvh2,
    /// The closed meshes among them.
    sealed: Sealed,
    /// Diameter of the scene's bounding box: tolerances are relative to it.
    scale: f64,
}

impl std::fmt::Debug for Occluders {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Occluders")
            .field("triangles", &self.tris.len())
            .field("bvh_nodes", &self.bvh.nodes.len())
            .field("scale", &self.scale)
            .finish()
    }
}

/// Relative tolerance of the geometric tests (touching, coplanarity).
const REL_TOL: f64 = 1e-9;

/// What the exact test of an occluder knows of the pair: its elements'
/// planes, segments inside its hull, and the hull's facets when found.
type Own<'a> = (&'a [(DVec3, DVec3)], &'a [(DVec3, DVec3)], Option<&'a Facets>);

/// Scenes with more triangles than this walk their BVH against the hull's
/// facets ([`Facets`]); smaller ones against its bounding box only.
const HULL_WALK_ABOVE: usize = 256;

impl Occluders {
    /// The occluders of `tris` (degenerate triangles are left out: they hide nothing).
    pub fn new(tris: &[[DVec3; 3]]) -> Self {
        let (lo, hi) = bounds(tris.iter().flatten().copied());
        let scale = if tris.is_empty() {
            1.0
        } else {
            (hi - lo).length().max(f64::MIN_POSITIVE)
        };
        let tris: Vec<Occluder> = tris
            .iter()
            .filter_map(|&v| {
                let n = (v[1] - v[0]).cross(v[2] - v[0]);
                let len = n.length();
                (len > 0.0).then(|| Occluder { v, normal: n / len })
            })
            .collect();
        // Boxes widened by far more than f32 rounding, so the f32 broad phase
        // never drops a triangle the exact test would keep.
        let pad = 1e-5 * scale;
        let boxes: Vec<PaddedBox> = tris
            .iter()
            .map(|t| {
                let (a, b) = bounds(t.v);
                PaddedBox(Aabb::new(to_f32(a - pad), to_f32(b + pad)))
            })
            .collect();
        let bvh = build_bvh2(
            &boxes,
            BvhBuildParams::medium_build(),
            &mut Duration::default(),
        );
        let sealed = Sealed::new(&tris);
        Self {
            tris,
            bvh,
            sealed,
            scale,
        }
    }

    /// The closed components, and which of their triangles an element's
    /// segments can meet first ([`Sealed`]).
    pub(crate) fn sealed(&self) -> &Sealed {
        &self.sealed
    }

    /// Every occluder.
    pub(crate) fn all(&self) -> &[Occluder] {
        &self.tris
    }

    /// Number of occluders.
    pub fn len(&self) -> usize {
        self.tris.len()
    }

    /// True when there is none.
    pub fn is_empty(&self) -> bool {
        self.tris.is_empty()
    }

    /// Occluder `i`.
    pub fn get(&self, i: u32) -> &Occluder {
        &self.tris[i as usize]
    }

    /// Diameter of the scene (the unit of every tolerance).
    pub fn scale(&self) -> f64 {
        self.scale
    }

    /// Appends to `out` the occluders that meet the interior of conv(`pts`),
    /// leaving out triangles coplanar with one of the planes in `own_planes`
    /// (point, unit normal): the faces the segments start or end on, and their
    /// coplanar neighbours, which a segment leaving the plane cannot cross.
    pub fn candidates(&self, pts: &[DVec3], own_planes: &[(DVec3, DVec3)], out: &mut Vec<u32>) {
        self.candidates_with(pts, own_planes, &[], &|_| false, out)
    }

    /// The occluders of the pair of non-coplanar triangles `a` and `b` (with
    /// their unit normals): [`Occluders::candidates`] of their six vertices.
    ///
    /// Segments from the centroid of one to the centroid and vertices of the
    /// other serve as witnesses: an occluder that one of them crosses
    /// transversally, strictly inside both, meets the hull's interior (the
    /// crossing point is not a vertex of the hull, so the occluder's plane
    /// cannot support the hull there), and is kept without the full
    /// separating-axis test. Most occluders of a shadowed pair are found so.
    pub fn pair_candidates(
        &self,
        a: ([DVec3; 3], DVec3),
        b: ([DVec3; 3], DVec3),
        out: &mut Vec<u32>,
    ) {
        self.pair_candidates_in(a, b, None, &|_| false, out)
    }

    /// [`Occluders::pair_candidates`] (`among`: None) or
    /// [`Occluders::pair_candidates_among`], without the exact test of the
    /// occluders that `skip` leaves out (those of a box taken whole are
    /// still listed).
    pub(crate) fn pair_candidates_skipping(
        &self,
        a: ([DVec3; 3], DVec3),
        b: ([DVec3; 3], DVec3),
        among: Option<&[u32]>,
        skip: &dyn Fn(u32) -> bool,
        out: &mut Vec<u32>,
    ) {
        self.pair_candidates_in(a, b, among, skip, out)
    }

    /// [`Occluders::pair_candidates`] restricted to the occluders `among`
    /// (sorted), without the BVH: for a triangle B inside a triangle B' whose
    /// candidates with A are `among`, conv(A ∪ B) ⊂ conv(A ∪ B'), so no other
    /// occluder can meet it.
    pub fn pair_candidates_among(
        &self,
        a: ([DVec3; 3], DVec3),
        b: ([DVec3; 3], DVec3),
        among: &[u32],
        out: &mut Vec<u32>,
    ) {
        self.pair_candidates_in(a, b, Some(among), &|_| false, out)
    }

    fn pair_candidates_in(
        &self,
        (a, na): ([DVec3; 3], DVec3),
        (b, nb): ([DVec3; 3], DVec3),
        among: Option<&[u32]>,
        skip: &dyn Fn(u32) -> bool,
        out: &mut Vec<u32>,
    ) {
        let ca = (a[0] + a[1] + a[2]) / 3.0;
        let cb = (b[0] + b[1] + b[2]) / 3.0;
        let witnesses = [
            (ca, cb),
            (ca, b[0]),
            (ca, b[1]),
            (ca, b[2]),
            (a[0], cb),
            (a[1], cb),
            (a[2], cb),
        ];
        let pts = [a[0], a[1], a[2], b[0], b[1], b[2]];
        let planes = [(a[0], na), (b[0], nb)];
        match among {
            None => self.candidates_with(&pts, &planes, &witnesses, skip, out),
            Some(among) => {
                let mut hull = None;
                let tol = REL_TOL * self.scale;
                // The facets pay for themselves once a few are tested.
                let facets = (among.len() > 4).then(|| Facets::new(&pts, tol));
                let own = (&planes[..], &witnesses[..], facets.as_ref());
                for &i in among {
                    if !skip(i) && self.meets_hull(i, &pts, own, &mut hull, tol) {
                        out.push(i);
                    }
                }
            }
        }
    }

    fn candidates_with(
        &self,
        pts: &[DVec3],
        own_planes: &[(DVec3, DVec3)],
        witnesses: &[(DVec3, DVec3)],
        skip: &dyn Fn(u32) -> bool,
        out: &mut Vec<u32>,
    ) {
        if self.tris.is_empty() {
            return;
        }
        let tol = REL_TOL * self.scale;
        // The BVH walked against the hull itself, not only its bounding
        // box: the hull of two elements far apart is a thin slab across
        // its box, and a mesh inside the box is mostly beside the slab.
        // Below HULL_WALK_ABOVE triangles the box alone is cheaper (finding
        // the facets costs about as much as a few exact tests).
        let facets = if self.tris.len() > HULL_WALK_ABOVE {
            Facets::new(pts, tol)
        } else {
            Facets::box_only(pts, tol)
        };
        let mut hull: Option<HullAxes> = None;
        let test = |i: u32, hull: &mut Option<HullAxes>| {
            let own = (own_planes, witnesses, Some(&facets));
            !skip(i) && self.meets_hull(i, pts, own, hull, tol)
        };
        self.walk(0, &facets, &mut |i| test(i, &mut hull), out);
        out.sort_unstable();
        out.dedup();
    }

    /// The occluders below BVH node `id` that `test` accepts, appended to
    /// `out`: boxes beyond one of the hull's facets skipped, boxes strictly
    /// inside every facet taken whole (each of their triangles meets the
    /// hull's interior). Recursive: the depth is the BVH's.
    fn walk(
        &self,
        id: u32,
        facets: &Facets,
        test: &mut impl FnMut(u32) -> bool,
        out: &mut Vec<u32>,
    ) {
        let node = &self.bvh.nodes[id as usize];
        let (lo, hi) = (to_f64(node.aabb().min), to_f64(node.aabb().max));
        let place = facets.classify(lo, hi);
        let slots = node.first_index..node.first_index + node.prim_count;
        match place {
            Place::Outside => {}
            Place::Inside if node.is_leaf() => {
                out.extend(slots.map(|slot| self.bvh.primitive_indices[slot as usize]));
            }
            Place::Across if node.is_leaf() => {
                for slot in slots {
                    let i = self.bvh.primitive_indices[slot as usize];
                    if test(i) {
                        out.push(i);
                    }
                }
            }
            Place::Inside => {
                let all = Facets::everything();
                self.walk(node.first_index, &all, test, out);
                self.walk(node.first_index + 1, &all, test, out);
            }
            Place::Across => {
                self.walk(node.first_index, facets, test, out);
                self.walk(node.first_index + 1, facets, test, out);
            }
        }
    }

    /// The exact test of occluder `i` against the interior of conv(`pts`),
    /// not of the planes `own_planes` (the pair's elements), with segments
    /// inside the hull (`witnesses`) and its `facets` (when known) to
    /// decide most occluders before the separating-axis test.
    fn meets_hull(
        &self,
        i: u32,
        pts: &[DVec3],
        (own_planes, witnesses, facets): Own<'_>,
        hull: &mut Option<HullAxes>,
        tol: f64,
    ) -> bool {
        let t = &self.tris[i as usize];
        let coplanar = own_planes
            .iter()
            .any(|&(p, n)| t.v.iter().all(|v| (*v - p).dot(n).abs() <= tol));
        if coplanar {
            return false;
        }
        // The occluder's own plane first: most candidates of the box test
        // lie wholly on one side of it.
        let (mut below, mut above) = (false, false);
        for p in pts {
            let d = (*p - t.v[0]).dot(t.normal);
            below |= d < -tol;
            above |= d > tol;
        }
        if !(below && above) {
            return false;
        }
        // A corner strictly inside the hull, or every corner beyond one of
        // its facets, decides it as the separating axes would.
        match facets.map_or(Place::Across, |f| f.place_triangle(&t.v)) {
            Place::Inside => return true,
            Place::Outside => return false,
            Place::Across => {}
        }
        witnesses.iter().any(|&(p, q)| crosses(p, q, t, tol))
            || hull
                .get_or_insert_with(|| HullAxes::new(pts))
                .meets(pts, t, tol)
    }
}

/// True when the segment p q crosses the plane of `t` transversally (its ends
/// more than `tol` on either side) at a point more than `tol` inside `t`.
pub(crate) fn crosses(p: DVec3, q: DVec3, t: &Occluder, tol: f64) -> bool {
    let dp = (p - t.v[0]).dot(t.normal);
    let dq = (q - t.v[0]).dot(t.normal);
    if !((dp > tol && dq < -tol) || (dp < -tol && dq > tol)) {
        return false;
    }
    let x = p + (q - p) * (dp / (dp - dq));
    (0..3).all(|i| {
        let (u, v) = (t.v[i], t.v[(i + 1) % 3]);
        let e = v - u;
        // Signed distance of x from the edge line, inside positive.
        e.cross(x - u).dot(t.normal) > tol * e.length()
    })
}

fn to_f64(v: Vec3A) -> DVec3 {
    DVec3::new(v.x as f64, v.y as f64, v.z as f64)
}

fn to_f32(v: DVec3) -> Vec3A {
    // Rounding outward is not needed: the padding is 100× f32's relative step.
    Vec3A::new(v.x as f32, v.y as f32, v.z as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> [DVec3; 3] {
        [DVec3::from(a), DVec3::from(b), DVec3::from(c)]
    }

    /// A blocker between two parallel squares is a candidate; one beside them
    /// is not; one touching the hull only along an edge is not.
    #[test]
    fn candidates_between_two_plates() {
        let floor = [
            DVec3::new(0., 0., 0.),
            DVec3::new(1., 0., 0.),
            DVec3::new(0., 1., 0.),
        ];
        let ceiling = [
            DVec3::new(0., 0., 1.),
            DVec3::new(0., 1., 1.),
            DVec3::new(1., 0., 1.),
        ];
        let tris = vec![
            floor,
            ceiling,
            // 0: a horizontal blocker half way up, inside the hull.
            tri([0.1, 0.1, 0.5], [0.3, 0.1, 0.5], [0.1, 0.3, 0.5]),
            // 1: beside the hull.
            tri([2.0, 2.0, 0.5], [3.0, 2.0, 0.5], [2.0, 3.0, 0.5]),
            // 2: a wall in the plane x = 0 touching the hull along its face.
            tri([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]),
            // 3: a vertical blade crossing the hull.
            tri([0.2, -0.5, 0.2], [0.2, 1.5, 0.2], [0.2, 0.5, 0.8]),
        ];
        let occ = Occluders::new(&tris);
        let pts: Vec<DVec3> = floor.iter().chain(&ceiling).copied().collect();
        let planes = [(floor[0], DVec3::Z), (ceiling[0], -DVec3::Z)];
        let mut out = Vec::new();
        occ.candidates(&pts, &planes, &mut out);
        assert_eq!(out, vec![2, 5], "candidate indices");
    }

    /// Scale invariance: the same configuration scaled by 1e-3 and 1e3 gives
    /// the same candidates.
    #[test]
    fn candidates_do_not_depend_on_units() {
        for s in [1e-3, 1.0, 1e3] {
            let sc = |t: [DVec3; 3]| t.map(|v| v * s);
            let a = sc(tri([0., 0., 0.], [1., 0., 0.], [0., 1., 0.]));
            let b = sc(tri([0., 0., 1.], [0., 1., 1.], [1., 0., 1.]));
            let blocker = sc(tri([0.1, 0.1, 0.5], [0.3, 0.1, 0.5], [0.1, 0.3, 0.5]));
            let grazing = sc(tri([1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [1.0, 0.0, 1.0]));
            let occ = Occluders::new(&[a, b, blocker, grazing]);
            let pts: Vec<DVec3> = a.iter().chain(&b).copied().collect();
            let mut out = Vec::new();
            occ.candidates(&pts, &[(a[0], DVec3::Z), (b[0], -DVec3::Z)], &mut out);
            assert_eq!(out, vec![2], "scale {s}");
        }
    }

    /// Walking the BVH against the hull's facets (boxes beyond one skipped,
    /// boxes strictly inside taken whole) finds exactly the triangles that
    /// the exact test finds among all of them, on a dense cloud of small
    /// triangles where both kinds of box occur.
    #[test]
    fn the_hull_walk_finds_what_testing_every_triangle_finds() {
        let mut rnd = crate::testing::uniform(0x853c49e6748fea9bu64);
        let mut p = || DVec3::new(rnd(), rnd(), rnd());
        let tris: Vec<[DVec3; 3]> = (0..2000)
            .map(|_| {
                let c = p();
                let d = [p(), p(), p()];
                d.map(|x| c + (x - DVec3::splat(0.5)) * 0.05)
            })
            .collect();
        let occ = Occluders::new(&tris);
        let tol = REL_TOL * occ.scale();
        let (mut found, mut inside_boxes) = (0, 0);
        for case in 0..60 {
            let a = [p(), p(), p()];
            let b = [p(), p(), p()];
            let pts = [a[0], a[1], a[2], b[0], b[1], b[2]];
            let planes = [
                (a[0], (a[1] - a[0]).cross(a[2] - a[0]).normalize()),
                (b[0], (b[1] - b[0]).cross(b[2] - b[0]).normalize()),
            ];
            let mut walked = Vec::new();
            occ.candidates(&pts, &planes, &mut walked);
            let mut hull = None;
            let every: Vec<u32> = (0..occ.len() as u32)
                .filter(|&i| occ.meets_hull(i, &pts, (&planes, &[], None), &mut hull, tol))
                .collect();
            assert_eq!(walked, every, "case {case}");
            found += every.len();
            let facets = Facets::new(&pts, tol);
            inside_boxes += occ
                .bvh
                .nodes
                .iter()
                .filter(|n| {
                    let (lo, hi) = (to_f64(n.aabb().min), to_f64(n.aabb().max));
                    matches!(facets.classify(lo, hi), Place::Inside)
                })
                .count();
        }
        assert!(
            found > 1000 && inside_boxes > 10,
            "{found} candidates, {inside_boxes} inside boxes"
        );
    }

    /// The hull's facets decide an occluder (a corner strictly inside, or
    /// every corner beyond one facet) as the separating axes do, and decide
    /// most of those that the walk leaves to the exact test.
    #[test]
    fn the_facets_decide_as_the_separating_axes_do() {
        let mut rnd = crate::testing::uniform(0x9e3779b97f4a7c15u64);
        let mut p = || DVec3::new(rnd(), rnd(), rnd());
        let tris: Vec<[DVec3; 3]> = (0..400)
            .map(|_| {
                let c = p();
                let d = [p(), p(), p()];
                d.map(|x| c + (x - DVec3::splat(0.5)) * 0.2)
            })
            .collect();
        let occ = Occluders::new(&tris);
        let tol = REL_TOL * occ.scale();
        let (mut inside, mut outside, mut across) = (0, 0, 0);
        for _ in 0..40 {
            let pts = [p(), p(), p(), p(), p(), p()];
            let facets = Facets::new(&pts, tol);
            let axes = HullAxes::new(&pts);
            for i in 0..occ.len() as u32 {
                let t = occ.get(i);
                let meets = axes.meets(&pts, t, tol);
                match facets.place_triangle(&t.v) {
                    Place::Inside => {
                        assert!(meets, "occluder {i} inside but separated");
                        inside += 1;
                    }
                    Place::Outside => {
                        assert!(!meets, "occluder {i} outside but meeting");
                        outside += 1;
                    }
                    Place::Across => across += 1,
                }
            }
        }
        assert!(
            inside > 1000 && outside > 1000 && across > 100,
            "{inside} inside, {outside} outside, {across} undecided"
        );
    }

    /// The witness segments only short-cut the separating-axis test: on
    /// random pairs among random occluders the candidates are the same as
    /// the plain test's.
    #[test]
    fn witnesses_do_not_change_the_candidates() {
        let mut rnd = crate::testing::uniform(0x2545f4914f6cdd1du64);
        let mut p = || DVec3::new(rnd(), rnd(), rnd());
        let tris: Vec<[DVec3; 3]> = (0..60)
            .map(|_| {
                let c = p();
                let d = [p(), p(), p()];
                d.map(|x| c + (x - DVec3::splat(0.5)) * 0.4)
            })
            .collect();
        let occ = Occluders::new(&tris);
        let (mut found, mut pairs) = (0, 0);
        for i in 0..tris.len() {
            for j in 0..tris.len() {
                let (a, b) = (tris[i], tris[j]);
                let na = occ.get(i as u32).normal;
                let nb = occ.get(j as u32).normal;
                if i == j || na.cross(nb).length() < 1e-3 {
                    continue;
                }
                let (mut fast, mut plain) = (Vec::new(), Vec::new());
                occ.pair_candidates((a, na), (b, nb), &mut fast);
                let pts = [a[0], a[1], a[2], b[0], b[1], b[2]];
                occ.candidates(&pts, &[(a[0], na), (b[0], nb)], &mut plain);
                assert_eq!(fast, plain, "pair ({i}, {j})");
                found += plain.len();
                pairs += 1;
            }
        }
        assert!(found > pairs, "the configuration must have many occluders");
    }
}
