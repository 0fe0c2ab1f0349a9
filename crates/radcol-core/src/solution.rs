//! The collocation solution u_n (eq. 18): nodal values, evaluation anywhere on
//! S, the iterated solution û_n = E + K u_n (eq. 21) and ∫_S u_n.

use crate::assembly::{ElementIntegrator, FieldPoint};
use crate::discretization::Discretization;
use crate::nodes::MAX_DEGREE;
use crate::quadrature::RuleLadder;
use glam::DVec3;
use std::sync::Arc;

/// Nodal values of u_n on a discretization.
#[derive(Clone, Debug)]
pub struct Solution {
    disc: Arc<Discretization>,
    values: Vec<f64>,
}

impl Solution {
    /// Wraps nodal values (length N, ordered like the collocation points).
    pub fn new(disc: Arc<Discretization>, values: Vec<f64>) -> Self {
        assert_eq!(values.len(), disc.len(), "one value per collocation point");
        Self { disc, values }
    }

    /// The discretization.
    pub fn discretization(&self) -> &Arc<Discretization> {
        &self.disc
    }

    /// u_n(v_i), length N.
    pub fn nodal(&self) -> &[f64] {
        &self.values
    }

    /// u_n at (s, t) of element `k`.
    pub fn eval(&self, k: usize, s: f64, t: f64) -> f64 {
        let f = self.disc.nodes_per_element();
        let mut l = [0.0; (MAX_DEGREE + 1) * (MAX_DEGREE + 2) / 2];
        self.disc.nodes().eval_basis(s, t, &mut l[..f]);
        l[..f]
            .iter()
            .zip(&self.values[k * f..(k + 1) * f])
            .map(|(a, b)| a * b)
            .sum()
    }

    /// u_n at a point of S (None when the point is not on the mesh).
    pub fn eval_at(&self, x: DVec3) -> Option<f64> {
        let (k, [s, t]) = self.disc.mesh().locate(x)?;
        Some(self.eval(k, s, t))
    }

    /// ∫_S u_n dS (a rule exact for the polynomial on flat elements, r + 6 on curved ones).
    pub fn integral(&self) -> f64 {
        integrate_nodal(&self.disc, &self.values)
    }

    /// û_n(P) = E(P) + ρ(P) (1/π) ∫_S G(P, Q) u_n(Q) dS_Q at a point P of S, with
    /// `integrator` over this solution's mesh; `rho` and `emission` are ρ(P), E(P).
    pub fn iterated(
        &self,
        integrator: &ElementIntegrator<'_>,
        p: &FieldPoint,
        rho: f64,
        emission: f64,
    ) -> f64 {
        let f = self.disc.nodes_per_element();
        let nodes = self.disc.nodes();
        let phi = |k: usize, st: [f64; 2], _q: DVec3, out: &mut [f64]| {
            let mut l = [0.0; (MAX_DEGREE + 1) * (MAX_DEGREE + 2) / 2];
            nodes.eval_basis(st[0], st[1], &mut l[..f]);
            out[0] = l[..f]
                .iter()
                .zip(&self.values[k * f..(k + 1) * f])
                .map(|(a, b)| a * b)
                .sum();
        };
        let mut acc = [0.0];
        for k in 0..self.disc.mesh().len() {
            integrator.integrate(p, k, nodes.degree(), &phi, &mut acc);
        }
        emission + rho * acc[0]
    }
}

/// ∫_S of the interpolant with nodal values `values` (length N).
pub fn integrate_nodal(disc: &Discretization, values: &[f64]) -> f64 {
    let mesh = disc.mesh();
    let f = disc.nodes_per_element();
    let r = disc.nodes().degree();
    let ladder = RuleLadder::new();
    let mut l = vec![0.0; f];
    let mut total = 0.0;
    for k in 0..mesh.len() {
        let rule = ladder.rule(if mesh.is_flat(k) { r } else { r + 6 });
        for (&[s, t], &w) in rule.points.iter().zip(&rule.weights) {
            disc.nodes().eval_basis(s, t, &mut l);
            let u: f64 = l
                .iter()
                .zip(&values[k * f..(k + 1) * f])
                .map(|(a, b)| a * b)
                .sum();
            total += w * mesh.point(k, s, t).jacobian * u;
        }
    }
    total
}
