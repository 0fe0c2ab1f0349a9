//! Point queries: u_n and the iterated solution û_n = E + K u_n (eq. 21) at
//! given points of S, with the element's error estimate.
//!
//! A point is found on S through a BVH over the elements
//! ([`crate::mesh::Locator`]), within a snapping distance (points read from
//! a file carry rounding, and a path tracer's points lie on its own copy of
//! the triangles); a normal, when given, picks the face at an edge.
//!
//! û_n(P) needs the row of K at P ([`PointEvaluator::row`]: each element
//! integrated as the assembly would for a collocation point at P, about one
//! row of the assembly); the channels share it.
//!
//! On smooth surfaces û_n - u = K(u_n - u) converges at the nodal
//! (superconvergent) order at every point, where u_n converges at the
//! global order (`tests/tests/query.rs`).

pub use crate::assembly::point::PointEvaluator;
use crate::assembly::QuadratureOptions;
use crate::mesh::Located;
use crate::problem::Problem;
use crate::run::{ChannelResult, SolveOutcome};
use glam::DVec3;
use rayon::prelude::*;
use serde::Serialize;

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
    /// The estimated error of u_n(P) (absolute), when the solve estimated
    /// its error: u - u_n = (û_n - u_n) + (u - û_n) at P, so it is
    /// |û_n(P) - u_n(P)|, the residual at P (computed here, not
    /// estimated), plus `iterated_estimate`, the error that the elements P
    /// sees carry to it. The second part is what a point whose own element
    /// is well resolved gets wrong from a brighter or worse neighbour (a
    /// face of an object lit by an unresolved floor).
    pub estimate: Option<f64>,
    /// The estimated error of û_n(P) (absolute), when the solve estimated
    /// its error: û_n - u = ρ K (u_n - u) at P, so it is at most ρ(P) times
    /// the sum over the elements of P's view of each one's share of it
    /// (1/π) ∫_Δk G V, which the row of K holds, times its estimate. The
    /// shares sum to at most 1: this is a weighted mean of the element
    /// estimates that P sees, times ρ(P).
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

impl PointEvaluator {
    /// Finds `q` on S within `reach`: the nearest element (facing `q`'s
    /// normal when it has one), through a BVH over the elements.
    pub fn locate(&self, q: &QueryPoint, reach: f64) -> Option<Located> {
        self.locator
            .nearest(self.disc.mesh(), q.position, q.normal, reach)
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
                        let iterated = fields.emission.eval(&site) + rho * ku;
                        let iterated_estimate = ch.estimate.as_ref().map(|e| {
                            let seen: f64 = (share.iter().zip(&e.elements))
                                .map(|(m, x)| m.abs() * (x + e.visibility_bound))
                                .sum();
                            rho.abs() * seen
                        });
                        ChannelValue {
                            u,
                            iterated,
                            estimate: iterated_estimate.map(|ie| (iterated - u).abs() + ie),
                            iterated_estimate,
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
