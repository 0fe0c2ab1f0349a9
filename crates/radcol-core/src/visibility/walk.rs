//! Which element pairs of a scene that occludes are partly visible: the
//! refinement tree of every base triangle, walked per row block so that a
//! node's candidate occluders bound its descendants'.

use super::bounce::{choose, mass_bound, Bounce, Deferred};
use super::{clip, Occluders};
use crate::geometry::barycentric_st;
use crate::mesh::{Element, Mesh};
use glam::DVec3;
use std::cell::RefCell;

pub(crate) use super::partial_row::{totals, PartialRow};
pub(crate) use super::Plane;

/// What one row block (flat element A) sees of the other elements.
#[derive(Debug, Default)]
pub(crate) struct Seen {
    /// The partly visible pairs, with their candidate occluders.
    pub(crate) partial: PartialRow,
    /// Elements hidden from every row point: their entries are zero, and
    /// the plan culls them.
    pub(crate) hidden: Vec<u32>,
}

/// Appends to `out` (when given) the candidate occluders of the pair (A,
/// element k) and returns true, when another plan of the same mesh found
/// them already (false: not known, nothing appended).
pub(crate) type Known<'a> = &'a dyn Fn(usize, Option<&mut Vec<u32>>) -> bool;

/// What flat element `a` (the row block's, with row points `rows`:
/// position and unit normal) sees: every element `k` with `live[k]` (not
/// culled, not the block's own, flat) that some occluder may hide from
/// `a`, or that straddles `a`'s plane, is partly visible with its candidate
/// occluders, unless the occluders hide it from every row point (its
/// clipped visible region is empty from each). `flat_geom[k]` is element
/// k's plane. An element whose candidates `known` gives is not searched
/// for them: they depend on the two elements alone, not on the row points.
pub(crate) fn partial_pairs(
    occ: &Occluders,
    tree: &RefinementTree,
    a: Plane,
    rows: &[(DVec3, DVec3)],
    flat_geom: &[Plane],
    (live, known): (&[bool], Option<Known<'_>>),
    bounce: Option<Bounce<'_>>,
) -> Seen {
    let walk = Walk {
        occ,
        a,
        rows,
        tree,
        live,
        known,
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
    known: Option<Known<'a>>,
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
    /// (a floor's elements behind a block are mostly found so). A row point
    /// that a ray shows to see part of `v` ([`clip::sees_a_point`]) is not
    /// clipped: the pair is partly visible whatever the clip would add, and
    /// the fill clips it anyway. (Only a ray grazing an occluder's edge can
    /// call a hidden pair partly visible; its clipped region is then empty,
    /// and its entries zero, as culled.) On the bunny room at r = 1 the
    /// clip here was a third of the plan's.
    fn hidden(&self, v: &[DVec3; 3], cands: &[u32]) -> bool {
        !cands.is_empty()
            && self.rows.iter().all(|&(p, n)| {
                !clip::sees_a_point(p, n, v, self.occ, cands)
                    && clip::visible_region(p, n, v, self.occ, cands).is_empty()
            })
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
            if !self.known.is_some_and(|known| known(k, Some(&mut cands))) {
                self.candidates(self.flat_geom[k], among, &mut cands);
            }
            self.mark(k, &cands, seen);
            return;
        }
        if self.known_below(node) {
            // Every element below has its candidates from the other plan:
            // the node's own search would only bound theirs.
            for &child in &node.children {
                self.visit(child, None, seen);
            }
            return self.visit_rest(node, None, seen);
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
        self.visit_rest(node, Some(&cands), seen);
    }

    /// Whether the other plan gave the candidates of every live element
    /// below `node` (then its walk searches none of them).
    fn known_below(&self, node: &TreeNode) -> bool {
        self.known
            .is_some_and(|known| (node.start..node.end).all(|k| !self.live(k) || known(k, None)))
    }

    /// Elements not in refinement order (not produced by radcol's meshes):
    /// tested one by one against `node`'s candidates `among`.
    fn visit_rest(&self, node: &TreeNode, among: Option<&[u32]>, seen: &mut Seen) {
        let mut one = Vec::new();
        for k in node.rest..node.end {
            if self.live(k) {
                one.clear();
                if !self.known.is_some_and(|known| known(k, Some(&mut one))) {
                    self.candidates(self.flat_geom[k], among, &mut one);
                }
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
