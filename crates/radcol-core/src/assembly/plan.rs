//! The assembly plan: for every (element of the collocation point, element
//! integrated over) pair, which regime and which rule. Computed once, executed
//! by any [`AssemblyBackend`](super::AssemblyBackend); CPU and GPU read the same
//! classes and the same far-rule tables, so they agree to rounding.
//!
//! The f_r collocation points of one element form a *row block* and share a
//! class with each element: far pairs are judged from the block's nearest point,
//! so one rule serves all f_r rows and the element's quadrature data is loaded
//! once per block (it stays in L1 while the f_r rows are filled).

use super::integrate::{far_degree, piece_ball, ElementIntegrator, FieldPoint, QuadratureOptions};
use crate::discretization::Discretization;
use crate::quadrature::{RuleLadder, MAX_RULE_DEGREE};
use crate::visibility::{self, clip, Occluders, VisibilityAnalysis};
use rayon::prelude::*;
use serde::Serialize;
use std::sync::Arc;

/// Class code: G = 0 on the whole pair (coplanar or back-facing).
pub const CLASS_CULLED: u8 = 0;
/// Class code: partly visible pair in a scene that can occlude (CPU): some
/// triangle meets the hull of the two elements, or the element straddles the
/// tangent plane of the block's element. Each row integrates over the exactly
/// clipped visible part ([`clip::visible_region`]).
pub const CLASS_PARTIAL: u8 = 253;
/// Class code: near pair, adaptive subdivision (CPU).
pub const CLASS_NEAR: u8 = 254;
/// Class code: the collocation point lies on the element (curved elements), split at the point (CPU).
pub const CLASS_SELF: u8 = 255;

/// True for the classes a backend leaves to the CPU's [`AssemblyPlan::fill_block`]
/// with [`FillMode::SpecialOnly`]: partial, near and self pairs.
#[inline]
pub fn is_special(code: u8) -> bool {
    code >= CLASS_PARTIAL
}

/// Far-rule data of one degree for every element, structure-of-arrays.
///
/// For element k and rule point q, index `k * nq + q`: position (`px`, `py`,
/// `pz`), inner normal (`nx`, `ny`, `nz`) and `wj` = weight × Jacobian / π.
/// `basis[j * nq + q]` = l_j at rule point q (the same for all elements).
#[derive(Clone, Debug)]
pub struct FarTable {
    /// Degree of precision of the rule.
    pub degree: usize,
    /// Rule points per element.
    pub nq: usize,
    /// Lagrange basis at the rule points, `f_r × nq`, row j contiguous:
    /// `basis[j * nq + q]` = l_j(point q).
    pub basis: Vec<f64>,
    /// The same, transposed: `basis_t[q * f_r + j]`.
    pub basis_t: Vec<f64>,
    /// x of the rule points, `n × nq`.
    pub px: Vec<f64>,
    /// y of the rule points.
    pub py: Vec<f64>,
    /// z of the rule points.
    pub pz: Vec<f64>,
    /// x of the inner normals.
    pub nx: Vec<f64>,
    /// y of the inner normals.
    pub ny: Vec<f64>,
    /// z of the inner normals.
    pub nz: Vec<f64>,
    /// weight × Jacobian / π.
    pub wj: Vec<f64>,
}

/// Pair counts (collocation point × element) and far kernel evaluations.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct PlanStats {
    /// Pairs integrated with one far rule.
    pub pairs_far: u64,
    /// Pairs integrated adaptively.
    pub pairs_near: u64,
    /// Pairs whose collocation point lies on the element (curved surfaces).
    pub pairs_self: u64,
    /// Pairs with G ≡ 0 (coplanar, back-facing), not integrated.
    pub pairs_culled: u64,
    /// Pairs integrated over their clipped visible part (scenes that occlude).
    pub pairs_partial: u64,
    /// Kernel evaluations of the far pairs: Σ rule points.
    pub far_kernel_evals: u64,
}

/// Which parts of a row block to fill.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FillMode {
    /// Every entry.
    All,
    /// Only partial, near and self pairs (what a GPU backend leaves to the CPU).
    SpecialOnly,
    /// Only far pairs (for throughput measurements of the far-field kernel).
    FarOnly,
}

/// The assembly plan of one discretization.
#[derive(Debug)]
pub struct AssemblyPlan {
    disc: Arc<Discretization>,
    opts: QuadratureOptions,
    ladder: RuleLadder,
    self_rule: Arc<super::integrate::SelfRules>,
    classes: Vec<u8>,
    tables: Vec<Option<FarTable>>,
    stats: PlanStats,
    visibility: VisibilityAnalysis,
    occluders: Option<Occluders>,
    partial: Vec<PartialRow>,
    progress: Option<crate::run::ProgressHandle>,
}

/// The partial pairs of one row block: elements (ascending) and their
/// occluder candidates, flattened.
#[derive(Debug, Default)]
struct PartialRow {
    elements: Vec<u32>,
    ranges: Vec<(u32, u32)>,
    candidates: Vec<u32>,
}

impl PartialRow {
    fn candidates_of(&self, k: usize) -> &[u32] {
        let i = self
            .elements
            .binary_search(&(k as u32))
            .expect("every partial pair is listed");
        let (start, len) = self.ranges[i];
        &self.candidates[start as usize..(start + len) as usize]
    }
}

impl AssemblyPlan {
    /// Classifies every pair and builds the far-rule tables that are used.
    pub fn new(disc: Arc<Discretization>, opts: QuadratureOptions) -> Self {
        Self::with_progress(disc, opts, None)
    }

    /// [`AssemblyPlan::new`], reporting each classified row block to
    /// `progress` (stage "plan"), and then each filled row block (stage
    /// "assembly" is started by the caller, as [`crate::run::solve`] does).
    pub fn with_progress(
        disc: Arc<Discretization>,
        opts: QuadratureOptions,
        progress: Option<crate::run::ProgressHandle>,
    ) -> Self {
        if let Some(p) = &progress {
            p.start("plan", disc.mesh().len() as u64);
        }
        let mesh = disc.mesh().clone();
        let n = mesh.len();
        let f = disc.nodes_per_element();
        let r = disc.nodes().degree();
        let balls: Vec<_> = (0..n)
            .into_par_iter()
            .map(|k| {
                let flat = mesh.is_flat(k);
                let (c, rad) = piece_ball(&mesh, k, [[0., 0.], [1., 0.], [0., 1.]], !flat);
                (c, rad, flat)
            })
            .collect();
        let flat_geom: Vec<_> = (0..n)
            .map(|k| {
                let v = mesh.vertices(k);
                let nrm = mesh.point(k, 1.0 / 3.0, 1.0 / 3.0).normal;
                (v, nrm)
            })
            .collect();
        let pts = disc.points();
        let tol = opts.tol;
        let visibility = visibility::analyze(mesh.surface());
        let occluders = visibility
            .needed
            .then(|| Occluders::new(&visibility::base_triangles(mesh.surface())));
        let tree = if occluders.is_some() {
            RefinementTree::new(&mesh)
        } else {
            RefinementTree::default()
        };
        let rows: Vec<(Vec<u8>, PartialRow)> = (0..n)
            .into_par_iter()
            .map(|kp| {
                let block = &pts[kp * f..(kp + 1) * f];
                let balls = &balls;
                let flat_geom = &flat_geom;
                let classify = |k: usize| {
                    let (c, rad, flat) = balls[k];
                    if k == kp {
                        return if flat { CLASS_CULLED } else { CLASS_SELF };
                    }
                    let (verts, nk) = flat_geom[k];
                    let all_culled = block.iter().all(|p| {
                        let scale = 1e-12 * (rad + (p.position - c).length());
                        if flat {
                            let behind_k = (p.position - verts[0]).dot(nk) <= scale;
                            let all_behind_p = verts
                                .iter()
                                .all(|v| (*v - p.position).dot(p.normal) <= scale);
                            behind_k || all_behind_p
                        } else {
                            (c - p.position).dot(p.normal) + rad <= 0.0
                        }
                    });
                    if all_culled {
                        return CLASS_CULLED;
                    }
                    let dmin = block
                        .iter()
                        .map(|p| (p.position - c).length())
                        .fold(f64::INFINITY, f64::min);
                    match far_degree(tol, rad, dmin, r, !flat) {
                        Some(d) => (d + 1) as u8,
                        None => CLASS_NEAR,
                    }
                };
                let mut row: Vec<u8> = (0..n).map(classify).collect();
                let mut partial = PartialRow::default();
                if let (Some(occ), true) = (&occluders, balls[kp].2) {
                    let walk = Walk {
                        occ,
                        a: flat_geom[kp],
                        tree: &tree,
                        balls,
                        flat_geom,
                    };
                    for &root in &tree.roots {
                        walk.visit(root, None, &mut row, &mut partial);
                    }
                }
                if let Some(p) = &progress {
                    p.advance(1);
                }
                (row, partial)
            })
            .collect();
        let mut classes = Vec::with_capacity(n * n);
        let mut partial = Vec::with_capacity(if occluders.is_some() { n } else { 0 });
        for (row, p) in rows {
            classes.extend_from_slice(&row);
            if occluders.is_some() {
                partial.push(p);
            }
        }

        let ladder = RuleLadder::new();
        let mut used = [false; MAX_RULE_DEGREE + 1];
        let mut stats = PlanStats::default();
        for &c in &classes {
            match c {
                CLASS_CULLED => stats.pairs_culled += f as u64,
                CLASS_NEAR => stats.pairs_near += f as u64,
                CLASS_SELF => stats.pairs_self += f as u64,
                CLASS_PARTIAL => stats.pairs_partial += f as u64,
                d => {
                    let d = (d - 1) as usize;
                    used[d] = true;
                    stats.pairs_far += f as u64;
                    stats.far_kernel_evals += (f * ladder.rule(d).len()) as u64;
                }
            }
        }
        let tables = (0..=MAX_RULE_DEGREE)
            .map(|d| used[d].then(|| build_table(&disc, &ladder, d)))
            .collect();
        Self {
            self_rule: Arc::new(super::integrate::SelfRules::new(opts.self_order)),
            disc,
            opts,
            ladder,
            classes,
            tables,
            stats,
            visibility,
            occluders,
            partial,
            progress,
        }
    }

    /// Whether this plan models visibility, and why.
    pub fn visibility(&self) -> &VisibilityAnalysis {
        &self.visibility
    }

    /// The occluders, when the scene can occlude.
    pub fn occluders(&self) -> Option<&Occluders> {
        self.occluders.as_ref()
    }

    /// The discretization.
    pub fn discretization(&self) -> &Arc<Discretization> {
        &self.disc
    }

    /// Quadrature options.
    pub fn options(&self) -> &QuadratureOptions {
        &self.opts
    }

    /// The rule ladder.
    pub fn ladder(&self) -> &RuleLadder {
        &self.ladder
    }

    /// Class codes, `n × n`, row-major by (element of the collocation block, element):
    /// [`CLASS_CULLED`], far degree + 1, [`CLASS_PARTIAL`], [`CLASS_NEAR`] or [`CLASS_SELF`].
    pub fn classes(&self) -> &[u8] {
        &self.classes
    }

    /// The far table of degree `d`, when some pair uses it.
    pub fn far_table(&self, d: usize) -> Option<&FarTable> {
        self.tables.get(d).and_then(|t| t.as_ref())
    }

    /// Pair statistics.
    pub fn stats(&self) -> PlanStats {
        self.stats
    }

    /// Matrix dimension N.
    pub fn dim(&self) -> usize {
        self.disc.len()
    }

    /// An integrator with this plan's options over its mesh.
    pub fn integrator(&self) -> ElementIntegrator<'_> {
        ElementIntegrator::with_self_rule(
            self.disc.mesh(),
            &self.ladder,
            self.opts.clone(),
            self.self_rule.clone(),
        )
    }

    /// Integrates the basis times G over the part of element `k` visible from
    /// the point (`position`, `normal`) of element `kp`, for a pair classed
    /// [`CLASS_PARTIAL`]: the visible region is clipped exactly
    /// ([`clip::visible_region`]) and each convex piece integrated adaptively.
    /// Overwrites `out` (f_r values); returns kernel evaluations.
    ///
    /// # Panics
    /// When the pair is not partial.
    #[allow(clippy::too_many_arguments)]
    pub fn integrate_partial(
        &self,
        integrator: &ElementIntegrator<'_>,
        position: glam::DVec3,
        normal: glam::DVec3,
        kp: usize,
        k: usize,
        phi: &super::integrate::Integrand<'_>,
        out: &mut [f64],
    ) -> u64 {
        let occ = self
            .occluders
            .as_ref()
            .expect("partial pairs exist only with occluders");
        let cands = self.partial[kp].candidates_of(k);
        let verts = self.disc.mesh().vertices(k);
        let r = self.disc.nodes().degree();
        let fp = FieldPoint {
            position,
            normal,
            on_element: None,
        };
        out.fill(0.0);
        if self.opts.visibility == super::VisibilityMode::Rays {
            let seen = |k: usize, st: [f64; 2], q: glam::DVec3, out: &mut [f64]| {
                if cands.iter().any(|&i| clip::blocks(position, q, occ.get(i))) {
                    out.fill(0.0);
                } else {
                    phi(k, st, q, out);
                }
            };
            let whole = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
            return integrator.integrate_region(&fp, k, whole, r, &seen, out);
        }
        let mut evals = 0;
        for piece in clip::visible_region(position, normal, &verts, occ, cands) {
            for tri in clip::triangles(&piece) {
                evals += integrator.integrate_region(&fp, k, tri, r, phi, out);
            }
        }
        evals
    }

    /// Fills the row block of element `kp`: `block` holds its f_r rows of the
    /// geometric matrix (length f_r · N, row-major). Returns kernel evaluations.
    pub fn fill_block(&self, kp: usize, block: &mut [f64], mode: FillMode) -> u64 {
        let n = self.disc.mesh().len();
        let f = self.disc.nodes_per_element();
        let ncols = n * f;
        debug_assert_eq!(block.len(), f * ncols);
        let pts = &self.disc.points()[kp * f..(kp + 1) * f];
        let classes = &self.classes[kp * n..(kp + 1) * n];
        let integrator = self.integrator();
        let nodes = self.disc.nodes();
        let phi = |_k: usize, st: [f64; 2], _q: glam::DVec3, out: &mut [f64]| {
            nodes.eval_basis(st[0], st[1], out)
        };
        let r = nodes.degree();
        let max_nq = self
            .tables
            .iter()
            .flatten()
            .map(|t| t.nq)
            .max()
            .unwrap_or(0);
        let mut g = vec![0.0f64; RUN_CHUNK * max_nq];
        let mut evals = 0u64;
        let mut k = 0;
        while k < n {
            // A run of consecutive elements with one class: refinement numbers
            // children consecutively, so neighbours in space share a rule and
            // their rule points are contiguous in the far table.
            let class = classes[k];
            let mut end = k + 1;
            while end < n && end - k < RUN_CHUNK && classes[end] == class {
                end += 1;
            }
            match class {
                CLASS_CULLED if mode == FillMode::All => {
                    for row in 0..f {
                        block[row * ncols + k * f..row * ncols + end * f].fill(0.0);
                    }
                }
                CLASS_CULLED => {}
                CLASS_NEAR | CLASS_SELF if mode != FillMode::FarOnly => {
                    for ke in k..end {
                        for (row, p) in pts.iter().enumerate() {
                            let out = &mut block[row * ncols + ke * f..row * ncols + (ke + 1) * f];
                            out.fill(0.0);
                            let fp = FieldPoint {
                                position: p.position,
                                normal: p.normal,
                                on_element: Some((kp, p.st)),
                            };
                            evals += integrator.integrate(&fp, ke, r, &phi, out);
                        }
                    }
                }
                CLASS_PARTIAL if mode != FillMode::FarOnly => {
                    for ke in k..end {
                        for (row, p) in pts.iter().enumerate() {
                            let out = &mut block[row * ncols + ke * f..row * ncols + (ke + 1) * f];
                            evals += self.integrate_partial(
                                &integrator,
                                p.position,
                                p.normal,
                                kp,
                                ke,
                                &phi,
                                out,
                            );
                        }
                    }
                }
                code if !is_special(code) && mode != FillMode::SpecialOnly => {
                    let t = self.tables[(code - 1) as usize]
                        .as_ref()
                        .expect("plan builds every table it uses");
                    let nq = t.nq;
                    let span = k * nq..end * nq;
                    let len = span.len();
                    let g = &mut g[..len];
                    for (row, p) in pts.iter().enumerate() {
                        far_kernel_row(
                            p.position,
                            p.normal,
                            &t.px[span.clone()],
                            &t.py[span.clone()],
                            &t.pz[span.clone()],
                            &t.nx[span.clone()],
                            &t.ny[span.clone()],
                            &t.nz[span.clone()],
                            &t.wj[span.clone()],
                            g,
                        );
                        let out = &mut block[row * ncols + k * f..row * ncols + end * f];
                        contract(g, &t.basis_t, nq, f, out);
                    }
                    evals += (f * len) as u64;
                }
                _ => {}
            }
            k = end;
        }
        if mode != FillMode::FarOnly {
            if let Some(p) = &self.progress {
                p.advance(1);
            }
        }
        evals
    }
}

/// True when flat element B straddles the plane of flat element A: the
/// clamped cosine at A's points has a kink inside B, so B is integrated over
/// its part in front of each point (curved elements are never partial: curved
/// scenes that occlude are refused before assembly).
fn straddles((va, na): ([glam::DVec3; 3], glam::DVec3), vb: [glam::DVec3; 3], scale: f64) -> bool {
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
    vertices: [glam::DVec3; 3],
    normal: glam::DVec3,
    /// Child nodes (indices into `RefinementTree::nodes`).
    children: Vec<u32>,
    /// First element of the range not under a child (`end` when the
    /// elements follow the refinement, as radcol's meshes do).
    rest: usize,
}

/// The refinement trees of the base triangles over the elements of a mesh,
/// built once per plan for scenes that occlude (flat patches).
#[derive(Default)]
struct RefinementTree {
    nodes: Vec<TreeNode>,
    roots: Vec<u32>,
}

impl RefinementTree {
    /// Falls back to one root per element when the elements are not grouped
    /// by base triangle.
    fn new(mesh: &crate::mesh::Mesh) -> Self {
        let mut tree = Self::default();
        let mut k = 0;
        for (j, p) in mesh.surface().patches.iter().enumerate() {
            for &param in &p.triangles {
                let root = crate::mesh::Element {
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

    fn build(
        &mut self,
        mesh: &crate::mesh::Mesh,
        node: crate::mesh::Element,
        range: std::ops::Range<usize>,
    ) -> u32 {
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
fn inside(mesh: &crate::mesh::Mesh, node: &crate::mesh::Element, k: usize) -> bool {
    let e = &mesh.elements()[k];
    let x = (e.param[0] + e.param[1] + e.param[2]) / 3.0;
    let [a, b, c] = node.param;
    e.patch == node.patch && crate::problem::barycentric_st(a, b, c, x).is_some()
}

/// Finds the partly visible elements of one row block (flat element A) by
/// walking the refinement tree of every base triangle: an occluder that
/// misses conv(A ∪ T) for a node T of the tree misses conv(A ∪ B) for every
/// element B below it, so each node is tested only against its parent's
/// candidates, and a subtree without any is not descended.
struct Walk<'a> {
    occ: &'a Occluders,
    a: ([glam::DVec3; 3], glam::DVec3),
    tree: &'a RefinementTree,
    balls: &'a [(glam::DVec3, f64, bool)],
    flat_geom: &'a [([glam::DVec3; 3], glam::DVec3)],
}

impl Walk<'_> {
    fn live(&self, row: &[u8], k: usize) -> bool {
        row[k] != CLASS_CULLED && row[k] != CLASS_SELF && self.balls[k].2
    }

    fn candidates(
        &self,
        b: ([glam::DVec3; 3], glam::DVec3),
        among: Option<&[u32]>,
        out: &mut Vec<u32>,
    ) {
        match among {
            None => self.occ.pair_candidates(self.a, b, out),
            Some([]) => {}
            Some(among) => self.occ.pair_candidates_among(self.a, b, among, out),
        }
    }

    fn mark(&self, k: usize, cands: &[u32], row: &mut [u8], partial: &mut PartialRow) {
        if straddles(self.a, self.flat_geom[k].0, self.occ.scale()) || !cands.is_empty() {
            row[k] = CLASS_PARTIAL;
            partial.elements.push(k as u32);
            partial
                .ranges
                .push((partial.candidates.len() as u32, cands.len() as u32));
            partial.candidates.extend_from_slice(cands);
        }
    }

    fn visit(&self, id: u32, among: Option<&[u32]>, row: &mut [u8], partial: &mut PartialRow) {
        let node = &self.tree.nodes[id as usize];
        if !(node.start..node.end).any(|k| self.live(row, k)) {
            return;
        }
        let mut cands = Vec::new();
        if node.end - node.start == 1 {
            // The node is the element itself.
            let k = node.start;
            self.candidates(self.flat_geom[k], among, &mut cands);
            self.mark(k, &cands, row, partial);
            return;
        }
        self.candidates((node.vertices, node.normal), among, &mut cands);
        if cands.is_empty() {
            for k in node.start..node.end {
                if self.live(row, k) {
                    self.mark(k, &[], row, partial);
                }
            }
            return;
        }
        for &child in &node.children {
            self.visit(child, Some(&cands), row, partial);
        }
        // Elements not in refinement order (not produced by radcol's meshes):
        // tested one by one against this node's candidates.
        let mut one = Vec::new();
        for k in node.rest..node.end {
            if self.live(row, k) {
                one.clear();
                self.candidates(self.flat_geom[k], Some(&cands), &mut one);
                self.mark(k, &one, row, partial);
            }
        }
    }
}

/// Elements per run at most (bounds the kernel buffer).
const RUN_CHUNK: usize = 64;

/// out[e * f + j] = Σ_q g[e * nq + q] · basis_t[q * f + j] for every element e
/// of a run: one small product per element, accumulated in registers for the
/// node counts of r = 0..=6 (no horizontal reductions).
#[inline]
fn contract(g: &[f64], basis_t: &[f64], nq: usize, f: usize, out: &mut [f64]) {
    match f {
        1 => contract_fixed::<1>(g, basis_t, nq, out),
        3 => contract_fixed::<3>(g, basis_t, nq, out),
        6 => contract_fixed::<6>(g, basis_t, nq, out),
        10 => contract_fixed::<10>(g, basis_t, nq, out),
        15 => contract_fixed::<15>(g, basis_t, nq, out),
        21 => contract_fixed::<21>(g, basis_t, nq, out),
        28 => contract_fixed::<28>(g, basis_t, nq, out),
        _ => {
            for (ge, oe) in g.chunks_exact(nq).zip(out.chunks_exact_mut(f)) {
                oe.fill(0.0);
                for (gq, bq) in ge.iter().zip(basis_t.chunks_exact(f)) {
                    for (o, b) in oe.iter_mut().zip(bq) {
                        *o += gq * b;
                    }
                }
            }
        }
    }
}

#[inline]
fn contract_fixed<const F: usize>(g: &[f64], basis_t: &[f64], nq: usize, out: &mut [f64]) {
    let basis_t = &basis_t[..nq * F];
    for (ge, oe) in g.chunks_exact(nq).zip(out.chunks_exact_mut(F)) {
        // Four independent accumulators hide the latency of the additions.
        let mut acc = [[0.0f64; F]; 4];
        let mut gc = ge.chunks_exact(4);
        let mut bc = basis_t.chunks_exact(4 * F);
        for (g4, b4) in (&mut gc).zip(&mut bc) {
            for u in 0..4 {
                for j in 0..F {
                    acc[u][j] += g4[u] * b4[u * F + j];
                }
            }
        }
        for (gq, bq) in gc.remainder().iter().zip(bc.remainder().chunks_exact(F)) {
            for j in 0..F {
                acc[0][j] += gq * bq[j];
            }
        }
        for j in 0..F {
            oe[j] = (acc[0][j] + acc[1][j]) + (acc[2][j] + acc[3][j]);
        }
    }
}

/// `g[q] = G(P, Q_q) · wj[q]` for one collocation point against one element's rule
/// points: the hot loop of far assembly, written over slices so it vectorises.
#[inline]
pub fn far_kernel_row(
    p: glam::DVec3,
    n_p: glam::DVec3,
    px: &[f64],
    py: &[f64],
    pz: &[f64],
    nx: &[f64],
    ny: &[f64],
    nz: &[f64],
    wj: &[f64],
    g: &mut [f64],
) {
    let nq = g.len();
    let (px, py, pz) = (&px[..nq], &py[..nq], &pz[..nq]);
    let (nx, ny, nz, wj) = (&nx[..nq], &ny[..nq], &nz[..nq], &wj[..nq]);
    for q in 0..nq {
        let dx = px[q] - p.x;
        let dy = py[q] - p.y;
        let dz = pz[q] - p.z;
        let a = (dx * n_p.x + dy * n_p.y + dz * n_p.z).max(0.0);
        let b = (-(dx * nx[q] + dy * ny[q] + dz * nz[q])).max(0.0);
        let r2 = dx * dx + dy * dy + dz * dz;
        g[q] = a * b / (r2 * r2) * wj[q];
    }
}

fn build_table(disc: &Discretization, ladder: &RuleLadder, d: usize) -> FarTable {
    let rule = ladder.rule(d);
    let nq = rule.len();
    let mesh = disc.mesh();
    let n = mesh.len();
    let f = disc.nodes_per_element();
    let mut basis = vec![0.0; f * nq];
    let mut basis_t = vec![0.0; f * nq];
    let mut l = vec![0.0; f];
    for (q, &[s, t]) in rule.points.iter().enumerate() {
        disc.nodes().eval_basis(s, t, &mut l);
        for j in 0..f {
            basis[j * nq + q] = l[j];
            basis_t[q * f + j] = l[j];
        }
    }
    let per_elem: Vec<[f64; 7]> = (0..n)
        .into_par_iter()
        .flat_map_iter(|k| {
            rule.points
                .iter()
                .zip(&rule.weights)
                .map(move |(&[s, t], &w)| {
                    let q = mesh.point(k, s, t);
                    [
                        q.position.x,
                        q.position.y,
                        q.position.z,
                        q.normal.x,
                        q.normal.y,
                        q.normal.z,
                        w * q.jacobian * std::f64::consts::FRAC_1_PI,
                    ]
                })
        })
        .collect();
    let col = |c: usize| per_elem.iter().map(|v| v[c]).collect::<Vec<f64>>();
    FarTable {
        degree: rule.degree,
        nq,
        basis,
        basis_t,
        px: col(0),
        py: col(1),
        pz: col(2),
        nx: col(3),
        ny: col(4),
        nz: col(5),
        wj: col(6),
    }
}
