//! Rule points of near and self pairs in batches.
//!
//! Point by point, each rule point of a curved element pays a call of the
//! surface map, a call of φ and a kernel whose loads wait for φ's stores:
//! several times what the far field pays for a kernel evaluation on its
//! tabulated points. Here a batch of up to [`FRAME_BATCH`] points gets its
//! geometry in one call ([`Mesh::frames`](crate::mesh::Mesh::frames)), φ at
//! every point before any is used, and the kernel and the sums over the
//! points in loops over plain arrays that the compiler vectorizes.

use super::{ElementMap, FieldPoint};
use crate::discretization::Discretization;
use crate::geometry::{FrameBatch, FRAME_BATCH};
use crate::kernel::g;
use crate::quadrature::TriangleRule;
use glam::DVec3;
use std::f64::consts::FRAC_1_PI;

/// The factor φ of an integrand G(P, Q) φ(Q): given element k, (s, t) and
/// the point Q = m_k(s, t), its `m` values. Any
/// `Fn(usize, [f64; 2], DVec3, &mut [f64]) + Sync` is one.
pub trait Integrand: Sync {
    /// Writes the `m` factors at one point into `out`.
    fn eval(&self, k: usize, st: [f64; 2], q: DVec3, out: &mut [f64]);

    /// Factor j at point i of a batch of element `k` (at (`s[i]`, `t[i]`),
    /// Q_i = `q.get(i).0`) into `out[j * FRAME_BATCH + i]`. The default
    /// calls [`eval`](Self::eval) at each point.
    fn eval_batch(&self, k: usize, s: &[f64], t: &[f64], q: &FrameBatch, out: &mut [f64]) {
        let mut at = [0.0f64; 64];
        let m = out.len() / FRAME_BATCH;
        for (i, (&si, &ti)) in s.iter().zip(t).enumerate() {
            self.eval(k, [si, ti], q.get(i).0, &mut at[..m]);
            for (j, v) in at[..m].iter().enumerate() {
                out[j * FRAME_BATCH + i] = *v;
            }
        }
    }
}

impl<F: Fn(usize, [f64; 2], DVec3, &mut [f64]) + Sync> Integrand for F {
    fn eval(&self, k: usize, st: [f64; 2], q: DVec3, out: &mut [f64]) {
        self(k, st, q, out)
    }
}

/// φ = the Lagrange basis of each element's node set: the integrand of the
/// collocation matrix, with the batch evaluated by
/// [`NodeSet::eval_basis_batch`](crate::nodes::NodeSet::eval_basis_batch).
#[derive(Clone, Copy, Debug)]
pub struct LagrangeBasis<'a>(pub &'a Discretization);

impl Integrand for LagrangeBasis<'_> {
    fn eval(&self, k: usize, st: [f64; 2], _q: DVec3, out: &mut [f64]) {
        self.0.nodes_of(k).eval_basis(st[0], st[1], out)
    }

    fn eval_batch(&self, k: usize, s: &[f64], t: &[f64], _q: &FrameBatch, out: &mut [f64]) {
        self.0.nodes_of(k).eval_basis_batch(s, t, out, FRAME_BATCH)
    }
}

/// Points of one element with their weights, geometry and φ.
pub(super) struct PointBatch {
    frames: FrameBatch,
    st: [[f64; FRAME_BATCH]; 2],
    /// The rule weight of each point, times its Jacobian after
    /// [`evaluate`](Self::evaluate).
    weight: [f64; FRAME_BATCH],
    /// φ_j at point i in `basis[j * FRAME_BATCH + i]`.
    basis: Vec<f64>,
    /// G(P, Q_i) times the weight, for the point P being added.
    gw: [f64; FRAME_BATCH],
    m: usize,
}

impl PointBatch {
    /// An empty batch for an integrand of `m` factors.
    pub(super) fn new(m: usize) -> Self {
        Self {
            frames: FrameBatch::default(),
            st: [[0.0; FRAME_BATCH]; 2],
            weight: [0.0; FRAME_BATCH],
            basis: vec![0.0; m * FRAME_BATCH],
            gw: [0.0; FRAME_BATCH],
            m,
        }
    }

    /// Empties the batch.
    pub(super) fn clear(&mut self) {
        self.frames.len = 0;
    }

    /// True when no more points fit.
    pub(super) fn is_full(&self) -> bool {
        self.frames.len == FRAME_BATCH
    }

    /// Adds the point (s, t) of the element with rule weight `weight`.
    pub(super) fn push(&mut self, [s, t]: [f64; 2], weight: f64) {
        let i = self.frames.len;
        (self.st[0][i], self.st[1][i], self.weight[i]) = (s, t, weight);
        self.frames.len += 1;
    }

    /// Takes `rule`'s points on the sub-triangle `tri` of element `k` a
    /// batch at a time: evaluates each batch ([`evaluate`](Self::evaluate))
    /// and hands it to `add`.
    pub(super) fn for_rule(
        &mut self,
        (map, k, phi): (&ElementMap<'_>, usize, &dyn Integrand),
        rule: &TriangleRule,
        [a, b, c]: [[f64; 2]; 3],
        mut add: impl FnMut(&mut Self),
    ) {
        let (e1, e2) = ([b[0] - a[0], b[1] - a[1]], [c[0] - a[0], c[1] - a[1]]);
        let scale = (e1[0] * e2[1] - e1[1] * e2[0]).abs() * FRAC_1_PI;
        let batches = rule.points.chunks(FRAME_BATCH);
        for (xys, ws) in batches.zip(rule.weights.chunks(FRAME_BATCH)) {
            self.clear();
            for (&[x, y], &w) in xys.iter().zip(ws) {
                let st = [a[0] + x * e1[0] + y * e2[0], a[1] + x * e1[1] + y * e2[1]];
                self.push(st, w * scale);
            }
            self.evaluate(map, k, phi);
            add(self);
        }
    }

    /// The surface point and φ at every point of the batch, and the weights
    /// times the Jacobian.
    pub(super) fn evaluate(&mut self, map: &ElementMap<'_>, k: usize, phi: &dyn Integrand) {
        let n = self.frames.len;
        let f = &mut self.frames;
        match *map {
            ElementMap::Curved(mesh, k) => {
                f.x[0][..n].copy_from_slice(&self.st[0][..n]);
                f.x[1][..n].copy_from_slice(&self.st[1][..n]);
                mesh.frames(k, f);
            }
            ElementMap::Affine(v0, es, et, q0) => {
                let normal = q0.normal.to_array();
                for i in 0..n {
                    let x = v0 + es * self.st[0][i] + et * self.st[1][i];
                    for (c, p) in x.to_array().into_iter().enumerate() {
                        (f.position[c][i], f.normal[c][i]) = (p, normal[c]);
                    }
                    f.jacobian[i] = q0.jacobian;
                }
            }
        }
        for (w, jac) in self.weight[..n].iter_mut().zip(&f.jacobian) {
            *w *= jac;
        }
        let (s, t) = (&self.st[0][..n], &self.st[1][..n]);
        phi.eval_batch(k, s, t, f, &mut self.basis);
        // The slots up to the next multiple of 4 enter the sums with weight
        // 0; a value left there by an earlier batch could be infinite.
        let padded = n.div_ceil(4) * 4;
        for j in 0..self.m {
            self.basis[j * FRAME_BATCH + n..j * FRAME_BATCH + padded].fill(0.0);
        }
    }

    /// Adds Σ_i G(P, Q_i) w_i φ_j(Q_i) to `out[j]` for every factor j.
    pub(super) fn add(&mut self, p: &FieldPoint, out: &mut [f64]) {
        let n = self.frames.len;
        // Sums run over whole groups of four, the slots past n weighing 0.
        let padded = n.div_ceil(4) * 4;
        let f = &self.frames;
        for i in 0..n {
            let (q, n_q, _) = f.get(i);
            self.gw[i] = g(p.position, p.normal, q, n_q) * self.weight[i];
        }
        self.gw[n..padded].fill(0.0);
        for (j, o) in out[..self.m].iter_mut().enumerate() {
            let phi = &self.basis[j * FRAME_BATCH..j * FRAME_BATCH + padded];
            let mut acc = [0.0f64; 4];
            for (g4, p4) in self.gw[..padded].chunks_exact(4).zip(phi.chunks_exact(4)) {
                for l in 0..4 {
                    acc[l] += g4[l] * p4[l];
                }
            }
            *o += (acc[0] + acc[1]) + (acc[2] + acc[3]);
        }
    }
}
