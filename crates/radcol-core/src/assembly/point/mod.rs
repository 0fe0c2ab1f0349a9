//! The row of K at an arbitrary point of S: what a point query
//! ([`crate::query`]) and the error estimate's shadow probes evaluate.
//!
//! û_n(P) needs the row of K at P: for every element Δ_k, (1/π) ∫ G(P, Q)
//! V(P, Q) ℓ_j(Q) dS_Q over its basis functions ℓ_j. Each element is
//! integrated as the assembly would integrate it for a collocation point at
//! P: not at all when G ≡ 0 (P behind Δ_k's plane or Δ_k behind P's, or P on
//! a flat Δ_k), over the exactly clipped visible part when an occluder may
//! hide part of it or it straddles P's tangent plane, and otherwise with the
//! distance-adaptive rules (`ElementIntegrator::integrate`, the self split
//! on a curved Δ_k under P). The row costs about one row of the assembly.

mod edge;

use super::{ElementIntegrator, FieldPoint, QuadratureOptions};
use crate::discretization::Discretization;
use crate::mesh::{Located, Locator};
use crate::quadrature::RuleLadder;
use crate::visibility::{self, clip, Occluders, VisibilityAnalysis};
use glam::DVec3;
use std::sync::Arc;

/// What the rows of K at arbitrary points need: the discretization, the
/// solve's quadrature options and, in a scene that occludes, its occluders.
#[derive(Debug)]
pub struct PointEvaluator {
    pub(crate) disc: Arc<Discretization>,
    opts: QuadratureOptions,
    ladder: RuleLadder,
    /// The scene's triangles when it occludes, else none.
    occluders: Occluders,
    occluding: bool,
    pub(crate) locator: Locator,
    diagonal: f64,
}

impl PointEvaluator {
    /// For `disc` with the quadrature options `opts` and the solve's
    /// visibility decision.
    pub fn new(
        disc: Arc<Discretization>,
        opts: QuadratureOptions,
        visibility: &VisibilityAnalysis,
    ) -> Self {
        let surface = disc.mesh().surface();
        let occluding = visibility.needed;
        let occluders = if occluding {
            Occluders::new(&visibility::base_triangles(surface))
        } else {
            Occluders::new(&[])
        };
        let (lo, hi) = surface.bounding_box();
        Self {
            locator: Locator::new(disc.mesh()),
            disc,
            opts,
            ladder: RuleLadder::new(),
            occluders,
            occluding,
            diagonal: (hi - lo).length(),
        }
    }

    /// The diagonal of the scene's bounding box (the unit of [`crate::query::DEFAULT_SNAP`]).
    pub fn diagonal(&self) -> f64 {
        self.diagonal
    }

    /// The row of K at the point `at` of S: entry j is (1/π) ∫ G V ℓ_j, the
    /// basis function ℓ_j of u_n's discretization (length N). Returns the row
    /// and the kernel evaluations spent.
    pub fn row(&self, at: &Located) -> (Vec<f64>, u64) {
        let mesh = self.disc.mesh();
        let disc = &*self.disc;
        let integrator = ElementIntegrator::new(mesh, &self.ladder, self.opts.clone());
        let phi = |k: usize, st: [f64; 2], _q: DVec3, out: &mut [f64]| {
            disc.nodes_of(k).eval_basis(st[0], st[1], out)
        };
        let fp = FieldPoint {
            position: at.position,
            normal: at.normal,
            on_element: Some((at.element, at.st)),
        };
        let mut row = vec![0.0; self.disc.len()];
        let mut evals = 0;
        let mut cands = Vec::new();
        for k in 0..mesh.len() {
            let (r, out) = (disc.degree(k), &mut row[disc.range(k)]);
            if !mesh.is_flat(k) {
                evals += integrator.integrate(&fp, k, r, &phi, out);
                continue;
            }
            if k == at.element {
                continue; // coplanar: G = 0
            }
            let verts = mesh.vertices(k);
            let nk = mesh.point(k, 1.0 / 3.0, 1.0 / 3.0).normal;
            let p = at.position;
            let (c, rad) = mesh.bounding_ball(k);
            let tol = 1e-12 * (rad + (p - c).length());
            if (p - verts[0]).dot(nk).abs() <= 1e-9 * rad {
                // P in Δ_k's plane: G = 0 there, but its limit from P's
                // face is not where Δ_k touches P (an edge of a room).
                let basis =
                    |st: [f64; 2], out: &mut [f64]| disc.nodes_of(k).eval_basis(st[0], st[1], out);
                edge::add_edge_limit(mesh, at, k, 1e-9 * rad, &basis, out);
                continue;
            }
            let side = verts.map(|v| (v - p).dot(at.normal));
            let behind_k = (p - verts[0]).dot(nk) <= tol;
            if behind_k || side.iter().all(|&d| d <= tol) {
                continue;
            }
            let straddles = side.iter().any(|&d| d < -tol);
            cands.clear();
            if self.occluding {
                let planes = [(p, at.normal), (verts[0], nk)];
                let shaft = [p, verts[0], verts[1], verts[2]];
                self.occluders.candidates(&shaft, &planes, &mut cands);
            }
            if !straddles && cands.is_empty() {
                evals += integrator.integrate(&fp, k, r, &phi, out);
                continue;
            }
            let region = clip::visible_region(p, at.normal, &verts, &self.occluders, &cands);
            let free = FieldPoint {
                on_element: None,
                ..fp
            };
            for piece in region {
                for tri in clip::triangles(&piece) {
                    evals += integrator.integrate_region(&free, k, tri, r, &phi, out);
                }
            }
        }
        (row, evals)
    }
}

