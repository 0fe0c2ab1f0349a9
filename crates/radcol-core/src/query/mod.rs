//! Point queries: u_n and the iterated solution û_n = E + K u_n (eq. 21) at
//! given points of S, with the element's error estimate.
//!
//! A point is found on S through a BVH over the elements
//! ([`crate::mesh::Locator`]), within a snapping distance (points read from
//! a file carry rounding, and a path tracer's points lie on its own copy of
//! the triangles); a normal, when given, picks the face at an edge.
//!
//! û_n(P) needs the row of K at P: for every element Δ_k, (1/π) ∫ G(P, Q)
//! V(P, Q) ℓ_j(Q) dS_Q over its basis functions ℓ_j. Each element is
//! integrated as the assembly would integrate it for a collocation point at
//! P: not at all when G ≡ 0 (P behind Δ_k's plane or Δ_k behind P's, or P on
//! a flat Δ_k), over the exactly clipped visible part when an occluder may
//! hide part of it or it straddles P's tangent plane, and otherwise with the
//! distance-adaptive rules (`ElementIntegrator::integrate`, the self split
//! on a curved Δ_k under P). The row costs about one row of the assembly;
//! the channels share it.
//!
//! On smooth surfaces û_n - u = K(u_n - u) converges at the nodal
//! (superconvergent) order at every point, where u_n converges at the
//! global order (`tests/tests/query.rs`).

mod edge;

use crate::assembly::{ElementIntegrator, FieldPoint, QuadratureOptions};
use crate::discretization::Discretization;
use crate::mesh::{Located, Locator};
use crate::problem::Problem;
use crate::quadrature::RuleLadder;
use crate::run::{ChannelResult, SolveOutcome};
use crate::visibility::{self, clip, Occluders, VisibilityAnalysis};
use glam::DVec3;
use rayon::prelude::*;
use serde::Serialize;
use std::sync::Arc;

/// How far from S a query point may lie and still be taken onto it, as a
/// fraction of the scene's bounding-box diagonal: the Cornell box's
/// reference points lie up to 0.5 mm (5e-4 of its diagonal) off radcol's
/// red wall, which is not planar.
pub const DEFAULT_SNAP: f64 = 1e-3;

/// A point asked for: where, and optionally the normal of the face meant
/// (any face whose normal has a positive component along it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QueryPoint {
    /// Position.
    pub position: DVec3,
    /// The face's normal (the side light leaves from), when known.
    pub normal: Option<DVec3>,
}

impl QueryPoint {
    /// The point `position`, on whichever face it lies.
    pub fn at(position: DVec3) -> Self {
        Self {
            position,
            normal: None,
        }
    }
}

/// One channel's values at a query point.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct ChannelValue {
    /// u_n(P).
    pub u: f64,
    /// û_n(P) = E(P) + ρ(P) (K u_n)(P).
    pub iterated: f64,
    /// The estimated max error of u_n on P's element (absolute), when the
    /// solve estimated its error.
    pub estimate: Option<f64>,
    /// The estimated error of û_n(P) (absolute), when the solve estimated
    /// its error: û_n - u = ρ K (u_n - u) at P, so it is at most ρ(P) times
    /// the sum over the elements of P's view of each one's share of it
    /// (1/π) ∫_Δk G V, which the row of K holds, times its estimate. The
    /// shares sum to at most 1: this is a weighted mean of the element
    /// estimates that P sees, times ρ(P), and usually well below
    /// `estimate`.
    pub iterated_estimate: Option<f64>,
}

/// The values at one query point.
#[derive(Clone, Debug)]
pub struct PointValues {
    /// Where the point was found.
    pub located: Located,
    /// Per channel, in the problem's order.
    pub channels: Vec<ChannelValue>,
}

/// Why a point could not be answered.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum QueryError {
    /// No face (facing the normal given) within the snapping distance.
    #[error(
        "point {index} ({x}, {y}, {z}) is not on the surface: no element{facing} within {reach:.3e}",
        x = position.x, y = position.y, z = position.z,
        facing = if *faced { " facing its normal" } else { "" }
    )]
    NotOnSurface {
        /// Index of the point (0-based) in the list given.
        index: usize,
        /// Its position.
        position: DVec3,
        /// Whether a normal restricted the faces.
        faced: bool,
        /// The snapping distance.
        reach: f64,
    },
}

/// What the rows of K at arbitrary points need: the discretization, the
/// solve's quadrature options and, in a scene that occludes, its occluders.
#[derive(Debug)]
pub struct PointEvaluator {
    disc: Arc<Discretization>,
    opts: QuadratureOptions,
    ladder: RuleLadder,
    /// The scene's triangles when it occludes, else none.
    occluders: Occluders,
    occluding: bool,
    locator: Locator,
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

    /// The diagonal of the scene's bounding box (the unit of [`DEFAULT_SNAP`]).
    pub fn diagonal(&self) -> f64 {
        self.diagonal
    }

    /// Finds `q` on S within `reach` ([`Locator::nearest`]).
    pub fn locate(&self, q: &QueryPoint, reach: f64) -> Option<Located> {
        self.locator
            .nearest(self.disc.mesh(), q.position, q.normal, reach)
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

/// u_n, û_n and the element estimate of every channel of `outcome` at
/// `points`, with `problem`'s ρ and E and the quadrature options `opts`
/// (the solve's); points are taken onto S within `snap` times the scene's
/// diagonal. Points are answered in parallel.
///
/// ```
/// use radcol_core::backend::CpuBackend;
/// use radcol_core::query::{query, QueryPoint, DEFAULT_SNAP};
/// use radcol_core::run::{shapes::sphere, solve, Field, Problem, SolveConfig};
/// use std::sync::Arc;
///
/// // On the unit sphere G ≡ 1/4: with ρ = 0.5 and E = 1, u ≡ 2 everywhere,
/// // between the nodes too.
/// let problem = Problem::new(Arc::new(sphere(1.0)), Field::Constant(0.5), Field::Constant(1.0));
/// let config = SolveConfig { degree: 1, level: 1, ..Default::default() };
/// let outcome = solve(&problem, &config, &CpuBackend)?;
/// let p = glam::DVec3::new(0.6, 0.0, 0.8);
/// let values = query(&problem, &outcome, config.quad.clone(), &[QueryPoint::at(p)], DEFAULT_SNAP)?;
/// let red = &values[0].channels[0];
/// assert!((red.u - 2.0).abs() < 1e-9 && (red.iterated - 2.0).abs() < 1e-9);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn query(
    problem: &Problem,
    outcome: &SolveOutcome,
    opts: QuadratureOptions,
    points: &[QueryPoint],
    snap: f64,
) -> Result<Vec<PointValues>, QueryError> {
    let eval = PointEvaluator::new(outcome.discretization.clone(), opts, &outcome.visibility);
    eval.query(problem, &outcome.channels, points, snap)
}

impl PointEvaluator {
    /// [`query`] for the solutions `channels` on this evaluator's
    /// discretization (a solve's, or a relit set's: their estimates are
    /// None), with `problem`'s ρ and E.
    ///
    /// # Panics
    /// When a channel's solution lies on another discretization.
    pub fn query(
        &self,
        problem: &Problem,
        channels: &[ChannelResult],
        points: &[QueryPoint],
        snap: f64,
    ) -> Result<Vec<PointValues>, QueryError> {
        assert!(
            (channels.iter()).all(|c| c.solution.nodal().len() == self.disc.len()),
            "the solutions lie on another discretization"
        );
        let reach = snap * self.diagonal();
        let located: Vec<Located> = points
            .iter()
            .enumerate()
            .map(|(index, q)| {
                self.locate(q, reach).ok_or(QueryError::NotOnSurface {
                    index,
                    position: q.position,
                    faced: q.normal.is_some(),
                    reach,
                })
            })
            .collect::<Result<_, _>>()?;
        let mesh = self.disc.mesh();
        Ok(located
            .into_par_iter()
            .map(|at| {
                let (row, _) = self.row(&at);
                let site = mesh.site(at.element, at.st[0], at.st[1]);
                // Each element's share of P's view: its basis functions sum to 1.
                let share: Vec<f64> = (0..mesh.len())
                    .map(|k| row[self.disc.range(k)].iter().sum())
                    .collect();
                let channels = channels
                    .iter()
                    .zip(&problem.channels)
                    .map(|(ch, fields)| {
                        let values = ch.solution.nodal();
                        let ku: f64 = row.iter().zip(values).map(|(a, b)| a * b).sum();
                        let u = ch.solution.eval(at.element, at.st[0], at.st[1]);
                        let rho = fields.rho.eval(&site);
                        let est = ch.estimate.as_ref();
                        ChannelValue {
                            u,
                            iterated: fields.emission.eval(&site) + rho * ku,
                            estimate: est.map(|e| e.elements[at.element] + e.visibility_bound),
                            iterated_estimate: est.map(|e| {
                                let seen: f64 = (share.iter().zip(&e.elements))
                                    .map(|(m, x)| m.abs() * (x + e.visibility_bound))
                                    .sum();
                                rho.abs() * seen
                            }),
                        }
                    })
                    .collect();
                PointValues {
                    located: at,
                    channels,
                }
            })
            .collect())
    }
}
