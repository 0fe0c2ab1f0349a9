//! Integrals over one element of G(P, Q) · φ(Q) dS_Q / π for a point P on S:
//! the building block of matrix rows (φ = Lagrange basis), iterated solutions
//! and manufactured right-hand sides (φ = a known function).
//!
//! Three regimes, decided from the distance between P and the element:
//! * **far**: one rule of the [`RuleLadder`] whose degree makes the estimated
//!   error (R / 2d)^(p+1) of the kernel's Taylor expansion fall below `tol`,
//!   plus the degree of φ (and 2 for the Jacobian of curved elements);
//! * **near**: 4:1 subdivision of the element in parameter space until every
//!   piece is far for its own size (geometric grading towards the nearest
//!   point, which resolves the 1/r² behaviour next to polyhedral edges);
//! * **self** (P on the element): the element is split into three triangles at
//!   P and each is integrated in Duffy coordinates collapsed at P, where the
//!   bounded, direction-dependent kernel of a curved surface becomes smooth.

use crate::mesh::Mesh;
use crate::quadrature::{RuleLadder, TriangleRule, MAX_RULE_DEGREE};
use batch::PointBatch;
pub use batch::{Integrand, LagrangeBasis};
use glam::DVec3;
use split::split;
use std::f64::consts::FRAC_1_PI;
use std::sync::Arc;

mod batch;
mod rows;
mod self_pair;
mod split;
pub use self_pair::SelfRules;

/// How partly visible pairs (scenes that occlude) are integrated.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum VisibilityMode {
    /// Over the exactly clipped visible region of the element (the default):
    /// the integrand is smooth on every piece, so the rules keep their order.
    #[default]
    Clip,
    /// Over the whole element with V(P, Q) ∈ {0, 1} cast as a ray (a segment
    /// test against the pair's candidate occluders) at every quadrature point:
    /// the textbook approach, kept to measure against. The rules then
    /// integrate a discontinuous function, with O(1/√points)-type errors at
    /// shadow boundaries.
    Rays,
}

/// The smallest element-integral tolerance a solve accepts: f64 sums carry
/// about 1e-16 of rounding, and below that the adaptive rules subdivide to
/// their depth limit for nothing (the sphere at level 1: 0.05 s of assembly
/// at 1e-15, 2.7 s at 1e-40; issue 12 reports no answer after 300 s at
/// 1e-300).
pub const MIN_QUAD_TOL: f64 = 1e-15;

/// Accuracy settings for element integrals.
#[derive(Clone, Debug, PartialEq)]
pub struct QuadratureOptions {
    /// Target relative error of each element integral, at least
    /// [`MIN_QUAD_TOL`] (solves refuse smaller ones).
    pub tol: f64,
    /// Deepest 4:1 subdivision level for near pairs. Only the pieces nearest
    /// P are split at each level, so the cost grows with the depth reached,
    /// not with 4^depth; a piece at depth d is 2^-d of its element, so two
    /// surfaces a gap g apart resolve where 2^-d h < g (box:1,1e-6,1 at level
    /// 2 needs d ≈ 18: at the former limit 14 its nodal error was 0.45).
    pub max_depth: u32,
    /// Most Gauss points per direction in each Duffy window of a self pair
    /// (the top of its ladder of rules; at least 8 are used).
    pub self_order: usize,
    /// Partly visible pairs: exact clipping or rays per quadrature point.
    pub visibility: VisibilityMode,
    /// Per row point, at most this much unoccluded mass ((1/π) ∫ G over the
    /// element, bounded) of partly visible pairs whose element emits nothing
    /// may have its visibility approximated by a few rays instead of clipped
    /// (`visibility::bounce`; the bound it leaves is added to the
    /// error estimate). 0: every pair exact (the default).
    pub visibility_budget: f64,
}

impl Default for QuadratureOptions {
    fn default() -> Self {
        Self {
            tol: 1e-12,
            max_depth: 32,
            self_order: 20,
            visibility: VisibilityMode::Clip,
            visibility_budget: 0.0,
        }
    }
}

/// A point P on S where an integral is wanted: position and inner normal, and,
/// when P lies on an element, which one and where (for the self split).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FieldPoint {
    /// Position of P.
    pub position: DVec3,
    /// Inner unit normal at P.
    pub normal: DVec3,
    /// (element, s, t) when P lies on an element of the mesh integrated over.
    pub on_element: Option<(usize, [f64; 2])>,
}

/// Integrates over elements of one mesh.
#[derive(Debug)]
pub struct ElementIntegrator<'a> {
    mesh: &'a Mesh,
    ladder: &'a RuleLadder,
    opts: QuadratureOptions,
    self_rule: Arc<SelfRules>,
    shortfall: Option<Arc<ShortfallLog>>,
}

/// An integral that stopped at a depth limit before it met the tolerance:
/// how many pieces did, and the closest such point–element pair.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Shortfall {
    /// Pieces that stopped at a depth limit: a near piece at
    /// [`QuadratureOptions::max_depth`], or a self-pair window at its own limit.
    pub pieces: u64,
    /// The element integrated over, in the closest such pair.
    pub element: usize,
    /// The point P of that pair.
    pub point: [f64; 3],
    /// The element P lies on, when it lies on one.
    pub point_element: Option<usize>,
    /// Distance from P to the centre of the piece that stopped, an upper
    /// bound of the gap between P and the element (0 on a self pair).
    pub distance: f64,
}

/// Collects [`Shortfall`]s from integrators running in parallel.
#[derive(Debug, Default)]
pub struct ShortfallLog {
    closest: std::sync::Mutex<Option<Shortfall>>,
}

impl ShortfallLog {
    fn record(&self, p: &FieldPoint, element: usize, distance: f64) {
        let mut closest = self.closest.lock().unwrap_or_else(|e| e.into_inner());
        let pieces = closest.map_or(0, |c| c.pieces) + 1;
        let here = Shortfall {
            pieces,
            element,
            point: p.position.to_array(),
            point_element: p.on_element.map(|(k, _)| k),
            distance,
        };
        *closest = Some(match *closest {
            Some(c) if c.distance <= distance => Shortfall { pieces, ..c },
            _ => here,
        });
    }

    /// What was recorded, if anything.
    pub fn summary(&self) -> Option<Shortfall> {
        *self.closest.lock().unwrap_or_else(|e| e.into_inner())
    }
}

impl<'a> ElementIntegrator<'a> {
    /// An integrator over `mesh` with rules from `ladder`.
    pub fn new(mesh: &'a Mesh, ladder: &'a RuleLadder, opts: QuadratureOptions) -> Self {
        let self_rule = Arc::new(SelfRules::new(opts.self_order));
        Self::with_self_rule(mesh, ladder, opts, self_rule)
    }

    /// As [`new`](Self::new), reusing self-pair rules built once by the caller
    /// with [`SelfRules::new`]`(opts.self_order)`.
    pub fn with_self_rule(
        mesh: &'a Mesh,
        ladder: &'a RuleLadder,
        opts: QuadratureOptions,
        self_rule: Arc<SelfRules>,
    ) -> Self {
        Self {
            mesh,
            ladder,
            opts,
            self_rule,
            shortfall: None,
        }
    }

    /// Records every integral that stops at a depth limit short of the
    /// tolerance in `log`.
    pub fn with_shortfall_log(mut self, log: Arc<ShortfallLog>) -> Self {
        self.shortfall = Some(log);
        self
    }

    fn note_shortfall(&self, p: &FieldPoint, element: usize, distance: f64) {
        if let Some(log) = &self.shortfall {
            log.record(p, element, distance);
        }
    }

    /// The options in force.
    pub fn options(&self) -> &QuadratureOptions {
        &self.opts
    }

    /// The far-rule degree for an element (or piece) of bounding radius `radius` at
    /// distance `dist` from P, when the integrand carries a polynomial factor of
    /// degree `poly_degree`; `None` when no rule of the ladder is accurate enough.
    pub fn far_degree(
        &self,
        radius: f64,
        dist: f64,
        poly_degree: usize,
        curved: bool,
    ) -> Option<usize> {
        far_degree(self.opts.tol, radius, dist, poly_degree, curved)
    }

    /// Adds ∫_{Δ_k} G(P, Q) φ(Q) dS_Q / π to `out[..m]`, choosing the regime from
    /// the geometry. Returns the number of kernel evaluations.
    pub fn integrate(
        &self,
        p: &FieldPoint,
        k: usize,
        poly_degree: usize,
        phi: &dyn Integrand,
        out: &mut [f64],
    ) -> u64 {
        if let Some((ke, st)) = p.on_element {
            if ke == k {
                if self.mesh.is_flat(k) {
                    return 0; // coplanar: G = 0
                }
                return self.integrate_self(p, k, st, phi, out);
            }
        }
        let tri = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        self.integrate_adaptive(p, k, tri, 0, poly_degree, phi, out)
    }

    /// Adds the integral over the sub-triangle `tri` (in σ coordinates) of
    /// element `k`, with the same far/near regimes as [`integrate`](Self::integrate)
    /// (used for the visible pieces of partly hidden elements). Returns the
    /// number of kernel evaluations.
    pub fn integrate_region(
        &self,
        p: &FieldPoint,
        k: usize,
        tri: [[f64; 2]; 3],
        poly_degree: usize,
        phi: &dyn Integrand,
        out: &mut [f64],
    ) -> u64 {
        self.integrate_adaptive(p, k, tri, 0, poly_degree, phi, out)
    }

    /// Applies `rule` on the sub-triangle `tri` (in σ coordinates) of element `k`.
    pub fn apply_rule(
        &self,
        p: &FieldPoint,
        k: usize,
        tri: [[f64; 2]; 3],
        rule: &TriangleRule,
        phi: &dyn Integrand,
        out: &mut [f64],
    ) -> u64 {
        let [a, b, c] = tri;
        let (e1, e2) = ([b[0] - a[0], b[1] - a[1]], [c[0] - a[0], c[1] - a[1]]);
        let det = (e1[0] * e2[1] - e1[1] * e2[0]).abs();
        let map = self.element_map(k);
        if let ElementMap::Affine(v0, es, et, q0) = map {
            let flat = FlatPiece {
                v0,
                es,
                et,
                normal: q0.normal,
                scale: q0.jacobian * det * FRAC_1_PI,
                a,
                e1,
                e2,
            };
            flat.apply(p, k, rule, phi, out);
            return rule.len() as u64;
        }
        let mut batch = PointBatch::new(out.len());
        batch.for_rule((&map, k, phi), rule, tri, |b| b.add(p, out));
        rule.len() as u64
    }

    /// Element `k`'s map, ready to evaluate at many (s, t).
    #[inline]
    fn element_map(&self, k: usize) -> ElementMap<'_> {
        if self.mesh.is_flat(k) {
            let [v0, v1, v2] = self.mesh.vertices(k);
            let q0 = self.mesh.point(k, 0.0, 0.0);
            ElementMap::Affine(v0, v1 - v0, v2 - v0, q0)
        } else {
            ElementMap::Curved(self.mesh, k)
        }
    }

    fn integrate_adaptive(
        &self,
        p: &FieldPoint,
        k: usize,
        tri: [[f64; 2]; 3],
        depth: u32,
        poly_degree: usize,
        phi: &dyn Integrand,
        out: &mut [f64],
    ) -> u64 {
        let curved = !self.mesh.is_flat(k);
        let (centre, radius) = piece_ball(self.mesh, k, tri, curved);
        let dist = (p.position - centre).length();
        let degree = match far_degree(self.opts.tol, radius, dist, poly_degree, curved) {
            Some(d) => d,
            None if depth >= self.opts.max_depth => {
                self.note_shortfall(p, k, dist);
                MAX_RULE_DEGREE
            }
            None => {
                return split(tri)
                    .into_iter()
                    .map(|t| self.integrate_adaptive(p, k, t, depth + 1, poly_degree, phi, out))
                    .sum();
            }
        };
        self.apply_rule(p, k, tri, self.ladder.rule(degree), phi, out)
    }
}

/// A sub-triangle of a flat element, for [`ElementIntegrator::apply_rule`]:
/// the element's affine map, its normal, the piece's corner `a` and edges
/// `e1`, `e2` in σ, and Jacobian · |det| / π.
struct FlatPiece {
    v0: DVec3,
    es: DVec3,
    et: DVec3,
    normal: DVec3,
    scale: f64,
    a: [f64; 2],
    e1: [f64; 2],
    e2: [f64; 2],
}

/// Rule points per batch of [`FlatPiece::apply`].
const FLAT_BATCH: usize = 32;

impl FlatPiece {
    /// What the general loop of [`ElementIntegrator::apply_rule`] adds, the
    /// kernel of a batch of rule points first and then φ where it is not
    /// zero. On a flat element d · n_Q is the same for every Q (d = Q − P),
    /// so a pair whose P lies behind the element's plane adds nothing; the
    /// kernels of a batch are independent of each other and of φ, so their
    /// divisions overlap instead of waiting for each φ (the partly visible
    /// pairs of an occluding scene spend most of their time here).
    fn apply(
        &self,
        p: &FieldPoint,
        k: usize,
        rule: &TriangleRule,
        phi: &dyn Integrand,
        out: &mut [f64],
    ) {
        let d0 = self.v0 - p.position;
        let b = (-d0.dot(self.normal)).max(0.0);
        if b == 0.0 {
            return;
        }
        let m = out.len();
        let mut basis = [0.0f64; 64];
        let (mut s, mut t, mut gw) = ([0.0; FLAT_BATCH], [0.0; FLAT_BATCH], [0.0; FLAT_BATCH]);
        let n_p = p.normal;
        for (xy, w) in rule
            .points
            .chunks(FLAT_BATCH)
            .zip(rule.weights.chunks(FLAT_BATCH))
        {
            let len = xy.len();
            for (i, (&[x, y], &wq)) in xy.iter().zip(w).enumerate() {
                let (si, ti) = (
                    self.a[0] + x * self.e1[0] + y * self.e2[0],
                    self.a[1] + x * self.e1[1] + y * self.e2[1],
                );
                let d = d0 + self.es * si + self.et * ti;
                let cos_p = d.dot(n_p).max(0.0);
                let r2 = d.length_squared();
                (s[i], t[i]) = (si, ti);
                gw[i] = cos_p * b / (r2 * r2) * wq * self.scale;
            }
            for i in 0..len {
                if gw[i] == 0.0 {
                    continue;
                }
                let q = self.v0 + self.es * s[i] + self.et * t[i];
                phi.eval(k, [s[i], t[i]], q, &mut basis[..m]);
                for (o, v) in out.iter_mut().zip(&basis[..m]) {
                    *o += gw[i] * v;
                }
            }
        }
    }
}

/// An element's map for evaluating many points: a flat element is affine in
/// (s, t), with position from its mapped vertices and one normal and
/// Jacobian, without the surface map per point.
enum ElementMap<'a> {
    /// Vertex, edge vectors (s, t) and the constant normal and Jacobian.
    Affine(DVec3, DVec3, DVec3, crate::mesh::SurfacePoint),
    /// A curved element of a mesh.
    Curved(&'a Mesh, usize),
}

/// The far-rule degree, see [`ElementIntegrator::far_degree`].
///
/// The kernel G(P, ·) is analytic in a ball of radius ≈ d around the piece's
/// centre; a rule of degree p on a piece of radius R then errs by about
/// (R / 2d)^(p+1) relative to the integral. A polynomial factor of degree q
/// adds q to the degree needed, a curved Jacobian 2 more.
pub fn far_degree(
    tol: f64,
    radius: f64,
    dist: f64,
    poly_degree: usize,
    curved: bool,
) -> Option<usize> {
    // (NaN distances fall through to None as well.)
    if dist.partial_cmp(&(radius * 1.0001)) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let eta = radius / (2.0 * dist);
    let extra = poly_degree + if curved { 2 } else { 0 };
    let pg = if eta <= 0.0 {
        0
    } else {
        ((tol.ln() / eta.ln()).ceil() as i64 - 1).max(0) as usize
    };
    let p = pg + extra;
    (p <= MAX_RULE_DEGREE).then_some(p.max(extra).max(1))
}

/// A ball around the image of sub-triangle `tri` of element `k`: the image of its
/// centroid and the largest distance to the images of its vertices and edge
/// midpoints (5 % more on curved elements).
pub fn piece_ball(mesh: &Mesh, k: usize, tri: [[f64; 2]; 3], curved: bool) -> (DVec3, f64) {
    let [a, b, c] = tri;
    let at = |u: f64, v: f64, w: f64| {
        mesh.position(
            k,
            u * a[0] + v * b[0] + w * c[0],
            u * a[1] + v * b[1] + w * c[1],
        )
    };
    let centre = at(1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0);
    let mut r: f64 = 0.0;
    for (u, v, w) in [(1., 0., 0.), (0., 1., 0.), (0., 0., 1.)] {
        r = r.max((at(u, v, w) - centre).length());
    }
    if curved {
        for (u, v, w) in [(0.5, 0.5, 0.), (0., 0.5, 0.5), (0.5, 0., 0.5)] {
            r = r.max((at(u, v, w) - centre).length());
        }
        r *= 1.05;
    }
    (centre, r)
}

#[cfg(test)]
pub(crate) mod tests {
    use crate::mesh::Mesh;
    use crate::nodes::NodeSet;
    use crate::quadrature::RuleLadder;

    /// ∫_{Δ_k} φ_j dS / 4π on the unit sphere, where G ≡ 1/4: what every
    /// row of element k's integrals equals, near or on the element. From a
    /// degree-30 rule on σ cut into 8 × 8 × 2 triangles (the Jacobian is far
    /// from a polynomial on an octant), with no kernel and no subdivision
    /// towards a point.
    pub(crate) fn unit_sphere_row(
        mesh: &Mesh,
        k: usize,
        nodes: &NodeSet,
        ladder: &RuleLadder,
    ) -> Vec<f64> {
        let f = nodes.len();
        let mut exact = vec![0.0; f];
        let mut basis = vec![0.0; f];
        let rule = ladder.rule(30);
        let n = 8;
        let h = 1.0 / n as f64;
        for i in 0..n {
            for j in 0..n - i {
                let (s0, t0) = (i as f64 * h, j as f64 * h);
                let mut pieces = vec![[[s0, t0], [s0 + h, t0], [s0, t0 + h]]];
                if i + j + 1 < n {
                    pieces.push([[s0 + h, t0 + h], [s0, t0 + h], [s0 + h, t0]]);
                }
                for [a, b, c] in pieces {
                    for (&[x, y], &w) in rule.points.iter().zip(&rule.weights) {
                        let s = a[0] + x * (b[0] - a[0]) + y * (c[0] - a[0]);
                        let t = a[1] + x * (b[1] - a[1]) + y * (c[1] - a[1]);
                        nodes.eval_basis(s, t, &mut basis);
                        let jw =
                            mesh.point(k, s, t).jacobian * w * h * h / (4.0 * std::f64::consts::PI);
                        exact.iter_mut().zip(&basis).for_each(|(e, b)| *e += jw * b);
                    }
                }
            }
        }
        exact
    }
}
