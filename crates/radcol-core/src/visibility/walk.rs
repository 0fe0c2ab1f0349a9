//! Which element pairs of a scene that occludes are partly visible: the
//! refinement tree of every base triangle, walked per row block so that a
//! node's candidate occluders bound its descendants'.

use super::bounce::{choose, mass_bound, Bounce, Deferred};
use super::{clip, Occluders};
use crate::geometry::barycentric_st;
use crate::mesh::{Element, Mesh};
use glam::DVec3;
use std::cell::RefCell;

/// A flat triangle's mapped vertices and unit normal.
pub(crate) type Plane = ([DVec3; 3], DVec3);

/// The partial pairs of one row block: elements (ascending) and their
/// occluder candidates, flattened.
#[derive(Debug, Default)]
pub(crate) struct PartialRow {
    pub(crate) elements: Vec<u32>,
    ranges: Vec<(u32, u32)>,
    candidates: Vec<u32>,
    /// The closed components from whose front region every segment of the
    /// row element starts (ascending): their candidates facing away from
    /// a row point cannot block it ([`super::sealed`]).
    pub(crate) in_front: Vec<u32>,
    /// The pairs whose visibility is approximated ([`super::bounce`]),
    /// ascending: a subset of `elements`.
    approx: Vec<u32>,
    /// Their mass bounds, a row point's after another's per pair (f32
    /// rounded up).
    approx_mass: Vec<f32>,
}

impl PartialRow {
    /// Bytes held on the heap.
    pub(crate) fn heap_bytes(&self) -> usize {
        self.elements.capacity() * 4
            + self.ranges.capacity() * 8
            + self.candidates.capacity() * 4
            + self.in_front.capacity() * 4
            + self.approx.capacity() * 4
            + self.approx_mass.capacity() * 4
    }

    /// Whether the pair with element `k` is approximated.
    pub(crate) fn is_approx(&self, k: usize) -> bool {
        self.approx.binary_search(&(k as u32)).is_ok()
    }

    /// How many pairs are approximated.
    pub(crate) fn approximated(&self) -> usize {
        self.approx.len()
    }

    /// Per row point (`rows` of them), the summed mass bounds of the
    /// approximated pairs.
    pub(crate) fn bound_sums(&self, rows: usize) -> Vec<f64> {
        let mut sums = vec![0.0; rows];
        for masses in self.approx_mass.chunks_exact(rows.max(1)) {
            sums.iter_mut()
                .zip(masses)
                .for_each(|(s, &m)| *s += m as f64);
        }
        sums
    }

    /// Marks the last pushed pair approximated, with its mass bounds.
    pub(crate) fn push_approx(&mut self, k: usize, cands: &[u32], mass: &[f64]) {
        self.push(k, cands);
        self.approx.push(k as u32);
        // Rounded up: f32 holds 6e-8 of relative error.
        let up = |m: f64| (m * (1.0 + 1e-6)) as f32;
        self.approx_mass.extend(mass.iter().map(|&m| up(m)));
    }

    /// The mass bounds of approximated pair `i` (its index in `approx`).
    fn masses_of(&self, i: usize) -> &[f32] {
        let rows = self.approx_mass.len() / self.approx.len().max(1);
        &self.approx_mass[i * rows..(i + 1) * rows]
    }

    /// This row's pairs whose element `map` sends to a new index (the
    /// others dropped), with their candidates; `map` must keep the order.
    pub(crate) fn remapped(&self, map: impl Fn(usize) -> Option<usize>) -> PartialRow {
        let mut out = PartialRow {
            in_front: self.in_front.clone(),
            ..PartialRow::default()
        };
        for (i, &k) in self.elements.iter().enumerate() {
            if let Some(nk) = map(k as usize) {
                let (start, len) = self.ranges[i];
                out.push(nk, &self.candidates[start as usize..(start + len) as usize]);
                if let Ok(a) = self.approx.binary_search(&k) {
                    out.approx.push(nk as u32);
                    out.approx_mass.extend_from_slice(self.masses_of(a));
                }
            }
        }
        out
    }

    /// The pairs of both rows (disjoint element sets), ascending.
    pub(crate) fn merged(&self, other: &PartialRow) -> PartialRow {
        // Facts about the same row element: either row's hold.
        let mut in_front = self.in_front.clone();
        in_front.extend_from_slice(&other.in_front);
        in_front.sort_unstable();
        in_front.dedup();
        let mut out = PartialRow {
            in_front,
            ..PartialRow::default()
        };
        let (mut i, mut j) = (0, 0);
        while i < self.elements.len() || j < other.elements.len() {
            let take_self = j == other.elements.len()
                || (i < self.elements.len() && self.elements[i] < other.elements[j]);
            let (row, at) = if take_self {
                (self, &mut i)
            } else {
                (other, &mut j)
            };
            let (start, len) = row.ranges[*at];
            let k = row.elements[*at];
            out.push(
                k as usize,
                &row.candidates[start as usize..(start + len) as usize],
            );
            if let Ok(a) = row.approx.binary_search(&k) {
                out.approx.push(k);
                out.approx_mass.extend_from_slice(row.masses_of(a));
            }
            *at += 1;
        }
        out
    }

    fn push(&mut self, k: usize, cands: &[u32]) {
        debug_assert!(self.elements.last().is_none_or(|&l| (l as usize) < k));
        self.elements.push(k as u32);
        self.ranges
            .push((self.candidates.len() as u32, cands.len() as u32));
        self.candidates.extend_from_slice(cands);
    }

    pub(crate) fn candidates_of(&self, k: usize) -> &[u32] {
        let i = self
            .elements
            .binary_search(&(k as u32))
            .expect("every partial pair is listed");
        let (start, len) = self.ranges[i];
        &self.candidates[start as usize..(start + len) as usize]
    }
}

/// What one row block (flat element A) sees of the other elements.
#[derive(Debug, Default)]
pub(crate) struct Seen {
    /// The partly visible pairs, with their candidate occluders.
    pub(crate) partial: PartialRow,
    /// Elements hidden from every row point: their entries are zero, and
    /// the plan culls them.
    pub(crate) hidden: Vec<u32>,
}

/// What flat element `a` (the row block's, with row points `rows`:
/// position and unit normal) sees: every element `k` with `live[k]` (not
/// culled, not the block's own, flat) that some occluder may hide from
/// `a`, or that straddles `a`'s plane, is partly visible with its candidate
/// occluders, unless the occluders hide it from every row point (its
/// clipped visible region is empty from each). `flat_geom[k]` is element
/// k's plane.
pub(crate) fn partial_pairs(
    occ: &Occluders,
    tree: &RefinementTree,
    a: Plane,
    rows: &[(DVec3, DVec3)],
    flat_geom: &[Plane],
    live: &[bool],
    bounce: Option<Bounce<'_>>,
) -> Seen {
    let walk = Walk {
        occ,
        a,
        rows,
        tree,
        live,
        flat_geom,
        front: RefCell::new(Vec::new()),
        bounce,
        deferred: RefCell::new(Vec::new()),
    };
    let mut seen = Seen::default();
    for &root in &tree.roots {
        walk.visit(root, None, &mut seen);
    }
    if let Some(b) = bounce {
        let (chosen, rest) = choose(walk.deferred.take(), b.spent, b.budget);
        let mut exact = Seen::default();
        for d in &rest {
            walk.mark_exact(d.k as usize, &d.cands, &mut exact);
        }
        let mut approx = PartialRow::default();
        for d in &chosen {
            approx.push_approx(d.k as usize, &d.cands, &d.mass);
        }
        seen.partial = seen.partial.merged(&exact.partial).merged(&approx);
        seen.hidden.extend(exact.hidden);
    }
    let mut in_front: Vec<u32> = walk
        .front
        .into_inner()
        .into_iter()
        .filter_map(|(c, yes)| yes.then_some(c))
        .collect();
    in_front.sort_unstable();
    seen.partial.in_front = in_front;
    seen
}

/// True when flat element B straddles the plane of flat element A: the
/// clamped cosine at A's points has a kink inside B, so B is integrated over
/// its part in front of each point (curved elements are never partial: curved
/// scenes that occlude are refused before assembly).
fn straddles((va, na): Plane, vb: [DVec3; 3], scale: f64) -> bool {
    let tol = 1e-12 * scale;
    let side = vb.map(|x| (x - va[0]).dot(na));
    side.iter().any(|&d| d > tol) && side.iter().any(|&d| d < -tol)
}

/// One node of a base triangle's refinement tree: the consecutive elements
/// inside triangle `vertices` (refinement numbers descendants consecutively).
struct TreeNode {
    start: usize,
    end: usize,
    /// Mapped vertices and unit normal of the node's (flat) triangle.
    vertices: [DVec3; 3],
    normal: DVec3,
    /// Child nodes (indices into `RefinementTree::nodes`).
    children: Vec<u32>,
    /// First element of the range not under a child (`end` when the
    /// elements follow the refinement, as radcol's meshes do).
    rest: usize,
}

/// The refinement trees of the base triangles over the elements of a mesh,
/// built once per plan for scenes that occlude (flat patches).
#[derive(Default)]
pub(crate) struct RefinementTree {
    nodes: Vec<TreeNode>,
    roots: Vec<u32>,
}

impl RefinementTree {
    /// Falls back to one root per element when the elements are not grouped
    /// by base triangle.
    pub(crate) fn new(mesh: &Mesh) -> Self {
        let mut tree = Self::default();
        let mut k = 0;
        for (j, p) in mesh.surface().patches.iter().enumerate() {
            for &param in &p.triangles {
                let root = Element {
                    patch: j as u32,
                    param,
                };
                let start = k;
                while k < mesh.len() && inside(mesh, &root, k) {
                    k += 1;
                }
                if k > start {
                    let id = tree.build(mesh, root, start..k);
                    tree.roots.push(id);
                }
            }
        }
        if k == mesh.len() {
            return tree;
        }
        let mut tree = Self::default();
        for k in 0..mesh.len() {
            let id = tree.build(mesh, mesh.elements()[k], k..k + 1);
            tree.roots.push(id);
        }
        tree
    }

    fn build(&mut self, mesh: &Mesh, node: Element, range: std::ops::Range<usize>) -> u32 {
        let map = &mesh.surface().patches[node.patch as usize].map;
        let vertices = node.param.map(|x| map.map(x));
        let normal = (vertices[1] - vertices[0])
            .cross(vertices[2] - vertices[0])
            .normalize_or_zero();
        let id = self.nodes.len();
        self.nodes.push(TreeNode {
            start: range.start,
            end: range.end,
            vertices,
            normal,
            children: Vec::new(),
            rest: range.end,
        });
        if range.len() > 1 {
            let mut k = range.start;
            let mut children = Vec::with_capacity(4);
            for child in node.children() {
                let start = k;
                while k < range.end && inside(mesh, &child, k) {
                    k += 1;
                }
                if k > start {
                    children.push(self.build(mesh, child, start..k));
                }
            }
            self.nodes[id].children = children;
            self.nodes[id].rest = k;
        }
        id as u32
    }
}

/// True when element `k`'s parameter centroid lies in `node`'s triangle.
fn inside(mesh: &Mesh, node: &Element, k: usize) -> bool {
    let e = &mesh.elements()[k];
    let x = (e.param[0] + e.param[1] + e.param[2]) / 3.0;
    let [a, b, c] = node.param;
    e.patch == node.patch && barycentric_st(a, b, c, x).is_some()
}

/// Finds the partly visible elements of one row block (flat element A) by
/// walking the refinement tree of every base triangle: an occluder that
/// misses conv(A ∪ T) for a node T of the tree misses conv(A ∪ B) for every
/// element B below it, so each node is tested only against its parent's
/// candidates, and a subtree without any is not descended.
struct Walk<'a> {
    occ: &'a Occluders,
    a: Plane,
    rows: &'a [(DVec3, DVec3)],
    tree: &'a RefinementTree,
    live: &'a [bool],
    flat_geom: &'a [Plane],
    /// Per closed component met so far: whether A's segments start in its
    /// front region ([`super::sealed::Sealed::starts_in_front`]).
    front: RefCell<Vec<(u32, bool)>>,
    /// What may be approximated, and the pairs set aside for it.
    bounce: Option<Bounce<'a>>,
    deferred: RefCell<Vec<Deferred>>,
}

impl Walk<'_> {
    fn live(&self, k: usize) -> bool {
        self.live[k]
    }

    fn candidates(&self, b: Plane, among: Option<&[u32]>, out: &mut Vec<u32>) {
        if among.is_some_and(|a| a.is_empty()) {
            return;
        }
        let skip = |i: u32| self.faces_away(i);
        self.occ
            .pair_candidates_skipping(self.a, b, among, &skip, out);
        // Boxes taken whole were not asked.
        out.retain(|&i| !self.faces_away(i));
    }

    /// True when occluder `i` belongs to a closed mesh from whose front
    /// region A's segments start, and faces away from every point of A: it
    /// cannot be the first of that mesh a segment from A meets, so it
    /// cannot block one ([`super::sealed`]).
    fn faces_away(&self, i: u32) -> bool {
        let sealed = self.occ.sealed();
        let Some(c) = sealed.component(i) else {
            return false;
        };
        let t = self.occ.get(i);
        if self.a.0.iter().any(|&x| (x - t.v[0]).dot(t.normal) > 0.0) {
            return false;
        }
        if let Some(&(_, yes)) = self.front.borrow().iter().find(|(k, _)| *k == c) {
            return yes;
        }
        let tol = 1e-9 * self.occ.scale();
        let yes = sealed.starts_in_front(c, self.occ.all(), &self.a.0, self.a.1, tol);
        self.front.borrow_mut().push((c, yes));
        yes
    }

    /// True when the occluders `cands` hide triangle `v` from every row
    /// point: a whole subtree of the refinement is then culled at once
    /// (a floor's elements behind a block are mostly found so).
    fn hidden(&self, v: &[DVec3; 3], cands: &[u32]) -> bool {
        !cands.is_empty()
            && self
                .rows
                .iter()
                .all(|&(p, n)| clip::visible_region(p, n, v, self.occ, cands).is_empty())
    }

    fn mark(&self, k: usize, cands: &[u32], seen: &mut Seen) {
        if !self.defer(k, cands) {
            self.mark_exact(k, cands, seen);
        }
    }

    /// Sets the pair aside for [`choose`] when its visibility may be
    /// approximated: occluders meet it, its element emits nothing and lies
    /// in front of A's plane, and its mass bound is within the budget at
    /// every row point. Its hidden test is then left to `choose`'s rest.
    fn defer(&self, k: usize, cands: &[u32]) -> bool {
        let Some(b) = self.bounce else {
            return false;
        };
        if cands.is_empty()
            || !b.columns[k]
            || straddles(self.a, self.flat_geom[k].0, self.occ.scale())
        {
            return false;
        }
        let mass: Vec<f64> = self
            .rows
            .iter()
            .map(|&(p, n)| mass_bound(p, n, self.flat_geom[k]))
            .collect();
        if !mass.iter().all(|&m| m <= b.budget) {
            return false;
        }
        self.deferred.borrow_mut().push(Deferred {
            k: k as u32,
            cands: cands.to_vec(),
            mass,
        });
        true
    }

    fn mark_exact(&self, k: usize, cands: &[u32], seen: &mut Seen) {
        if self.hidden(&self.flat_geom[k].0, cands) {
            seen.hidden.push(k as u32);
        } else if straddles(self.a, self.flat_geom[k].0, self.occ.scale()) || !cands.is_empty() {
            seen.partial.push(k, cands);
        }
    }

    fn visit(&self, id: u32, among: Option<&[u32]>, seen: &mut Seen) {
        let node = &self.tree.nodes[id as usize];
        if !(node.start..node.end).any(|k| self.live(k)) {
            return;
        }
        let mut cands = Vec::new();
        if node.end - node.start == 1 {
            // The node is the element itself.
            let k = node.start;
            self.candidates(self.flat_geom[k], among, &mut cands);
            self.mark(k, &cands, seen);
            return;
        }
        self.candidates((node.vertices, node.normal), among, &mut cands);
        if cands.is_empty() || self.hidden(&node.vertices, &cands) {
            for k in node.start..node.end {
                if self.live(k) {
                    self.mark_whole(k, &cands, seen);
                }
            }
            return;
        }
        for &child in &node.children {
            self.visit(child, Some(&cands), seen);
        }
        // Elements not in refinement order (not produced by radcol's meshes):
        // tested one by one against this node's candidates.
        let mut one = Vec::new();
        for k in node.rest..node.end {
            if self.live(k) {
                one.clear();
                self.candidates(self.flat_geom[k], Some(&cands), &mut one);
                self.mark(k, &one, seen);
            }
        }
    }

    /// Element `k` of a node that no occluder meets (`cands` empty) or that
    /// `cands` hide from every row point.
    fn mark_whole(&self, k: usize, cands: &[u32], seen: &mut Seen) {
        if !cands.is_empty() {
            seen.hidden.push(k as u32);
        } else if straddles(self.a, self.flat_geom[k].0, self.occ.scale()) {
            seen.partial.push(k, &[]);
        }
    }
}
