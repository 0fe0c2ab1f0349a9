//! Pair classes: for every (row block, element) pair, culled, far with a rule
//! degree, partly visible, near, or on the element, judged from the block's
//! points and the element's bounding ball.

use crate::assembly::integrate::{far_degree, piece_ball};
use crate::discretization::CollocationPoint;
use crate::mesh::Mesh;
use crate::visibility::walk::Plane;
use glam::DVec3;
use rayon::prelude::*;

/// How one (row block, element) pair is integrated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PairClass {
    /// G = 0 on the whole pair (coplanar or back-facing): not integrated.
    Culled,
    /// One far rule of this degree of precision (0..=30).
    Far(u8),
    /// Partly visible pair in a scene that can occlude (CPU): some triangle
    /// meets the hull of the two elements, or the element straddles the
    /// tangent plane of the block's element. Each row integrates over the
    /// exactly clipped visible part ([`crate::visibility::clip::visible_region`]).
    Partial,
    /// Near pair: adaptive subdivision (CPU).
    Near,
    /// The collocation points lie on the element (curved elements): split at
    /// each point (CPU).
    OnElement,
}

/// Code of [`PairClass::Culled`].
const CULLED: u8 = 0;
/// Code of [`PairClass::Partial`].
const PARTIAL: u8 = 253;
/// Code of [`PairClass::Near`].
const NEAR: u8 = 254;
/// Code of [`PairClass::OnElement`].
const ON_ELEMENT: u8 = 255;

impl PairClass {
    /// The byte stored in the plan and read by the GPU shader: 0 culled,
    /// degree + 1 far, 253 partial, 254 near, 255 on the element.
    #[inline]
    pub const fn code(self) -> u8 {
        match self {
            PairClass::Culled => CULLED,
            PairClass::Far(d) => d + 1,
            PairClass::Partial => PARTIAL,
            PairClass::Near => NEAR,
            PairClass::OnElement => ON_ELEMENT,
        }
    }

    /// The class of a stored code.
    #[inline]
    pub const fn from_code(code: u8) -> Self {
        match code {
            CULLED => PairClass::Culled,
            PARTIAL => PairClass::Partial,
            NEAR => PairClass::Near,
            ON_ELEMENT => PairClass::OnElement,
            d => PairClass::Far(d - 1),
        }
    }

    /// True for the classes a backend leaves to the CPU's
    /// [`super::AssemblyPlan::fill_block`] with [`super::FillMode::SpecialOnly`]:
    /// partial, near and on-element pairs.
    #[inline]
    pub const fn is_special(self) -> bool {
        matches!(
            self,
            PairClass::Partial | PairClass::Near | PairClass::OnElement
        )
    }
}

/// What classification needs of every element: bounding ball (centre,
/// radius), whether it is flat, and its plane (mapped vertices, normal at
/// the centroid).
pub(super) struct ElementShapes {
    pub(super) balls: Vec<(DVec3, f64, bool)>,
    pub(super) planes: Vec<Plane>,
}

impl ElementShapes {
    pub(super) fn new(mesh: &Mesh) -> Self {
        let n = mesh.len();
        let balls = (0..n)
            .into_par_iter()
            .map(|k| {
                let flat = mesh.is_flat(k);
                let (c, rad) = piece_ball(mesh, k, [[0., 0.], [1., 0.], [0., 1.]], !flat);
                (c, rad, flat)
            })
            .collect();
        let planes = (0..n)
            .map(|k| {
                let v = mesh.vertices(k);
                let nrm = mesh.point(k, 1.0 / 3.0, 1.0 / 3.0).normal;
                (v, nrm)
            })
            .collect();
        Self { balls, planes }
    }

    /// True when element `k` is flat.
    pub(super) fn is_flat(&self, k: usize) -> bool {
        self.balls[k].2
    }

    /// The class of the pair (row block of element `kp` with points `block`,
    /// element `k`) before visibility: culled, far of some degree, near, or
    /// on the element. `tol` is the quadrature tolerance, `r` the degree.
    pub(super) fn classify(
        &self,
        kp: usize,
        block: &[CollocationPoint],
        k: usize,
        tol: f64,
        r: usize,
    ) -> PairClass {
        let (c, rad, flat) = self.balls[k];
        if k == kp {
            return if flat {
                PairClass::Culled
            } else {
                PairClass::OnElement
            };
        }
        let (verts, nk) = self.planes[k];
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
            return PairClass::Culled;
        }
        let dmin = block
            .iter()
            .map(|p| (p.position - c).length())
            .fold(f64::INFINITY, f64::min);
        match far_degree(tol, rad, dmin, r, !flat) {
            Some(d) => PairClass::Far(d as u8),
            None => PairClass::Near,
        }
    }
}
