//! Near pairs for every row point of one element at once.
//!
//! Row by row, [`ElementIntegrator::integrate`] subdivides the column element
//! towards each point P and evaluates the surface map, its Jacobian and φ at
//! every rule point of every piece; on curved elements that costs several
//! times the kernel itself. The row points of one element lie close together,
//! so their subdivisions share most pieces. Here the pieces are walked once
//! for all rows: a row leaves the walk at the first piece that is far enough
//! for it (the pieces of the row-by-row walk), and the rows that leave at one
//! piece share one rule there, the highest degree any of them needs, so the
//! geometry and φ are evaluated once per rule point for all of them. No row
//! gets a lower degree than it would alone (the ellipsoid at level 3, one
//! run: the near pairs 2.3–2.4× faster than row by row at r = 2 and 3, for
//! 12–18 % more kernel evaluations).

use super::batch::PointBatch;
use super::{far_degree, piece_ball, ElementIntegrator, FieldPoint, Integrand};
use crate::quadrature::MAX_RULE_DEGREE;
use std::cell::RefCell;

/// A sub-triangle of σ.
type Tri = [[f64; 2]; 3];

/// What every piece of one [`ElementIntegrator::integrate_rows`] walk shares.
struct RowWalk<'a> {
    ps: &'a [FieldPoint],
    k: usize,
    poly_degree: usize,
    phi: &'a dyn Integrand,
    m: usize,
    /// The rule points of the piece being integrated.
    batch: RefCell<PointBatch>,
}

impl ElementIntegrator<'_> {
    /// For every point `ps[i]` off element `k`, adds ∫_{Δ_k} G(P_i, Q) φ(Q)
    /// dS_Q / π to `out[i m..(i + 1) m]` (m = `out.len() / ps.len()`), on the
    /// pieces [`integrate`](Self::integrate) uses for that point alone, each
    /// with a rule of at least the degree it uses there. Returns the number
    /// of kernel evaluations.
    pub fn integrate_rows(
        &self,
        ps: &[FieldPoint],
        k: usize,
        poly_degree: usize,
        phi: &dyn Integrand,
        out: &mut [f64],
    ) -> u64 {
        debug_assert!(ps.iter().all(|p| p.on_element.is_none_or(|(e, _)| e != k)));
        let rows: Vec<usize> = (0..ps.len()).collect();
        let walk = RowWalk {
            ps,
            k,
            poly_degree,
            phi,
            m: out.len() / ps.len().max(1),
            batch: RefCell::new(PointBatch::new(out.len() / ps.len().max(1))),
        };
        let whole = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        self.walk_rows(&walk, &rows, whole, 0, out)
    }

    fn walk_rows(
        &self,
        w: &RowWalk<'_>,
        rows: &[usize],
        tri: Tri,
        depth: u32,
        out: &mut [f64],
    ) -> u64 {
        let curved = !self.mesh.is_flat(w.k);
        let (centre, radius) = piece_ball(self.mesh, w.k, tri, curved);
        let mut ready = Vec::with_capacity(rows.len());
        let mut pending = Vec::new();
        let mut degree = 0;
        for &i in rows {
            let dist = (w.ps[i].position - centre).length();
            match far_degree(self.opts.tol, radius, dist, w.poly_degree, curved) {
                Some(d) => {
                    degree = degree.max(d);
                    ready.push(i);
                }
                None if depth >= self.opts.max_depth => {
                    self.note_shortfall(&w.ps[i], w.k, dist);
                    degree = MAX_RULE_DEGREE;
                    ready.push(i);
                }
                None => pending.push(i),
            }
        }
        let mut evals = 0;
        if !ready.is_empty() {
            evals += self.rule_rows(w, &ready, degree, tri, out);
        }
        if !pending.is_empty() {
            let [a, b, c] = tri;
            let mid = |u: [f64; 2], v: [f64; 2]| [(u[0] + v[0]) * 0.5, (u[1] + v[1]) * 0.5];
            let (ab, bc, ca) = (mid(a, b), mid(b, c), mid(c, a));
            for t in [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]] {
                evals += self.walk_rows(w, &pending, t, depth + 1, out);
            }
        }
        evals
    }

    /// The rule of `degree` on `tri` for each of `rows`: what
    /// [`apply_rule`](Self::apply_rule) adds for each alone, with the
    /// surface point and φ evaluated once per rule point.
    fn rule_rows(
        &self,
        w: &RowWalk<'_>,
        rows: &[usize],
        degree: usize,
        tri: Tri,
        out: &mut [f64],
    ) -> u64 {
        let rule = self.ladder.rule(degree);
        let map = self.element_map(w.k);
        let mut batch = w.batch.borrow_mut();
        batch.for_rule((&map, w.k, w.phi), rule, tri, |b| {
            for &i in rows {
                b.add(&w.ps[i], &mut out[i * w.m..(i + 1) * w.m]);
            }
        });
        (rule.len() * rows.len()) as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::assembly::QuadratureOptions;
    use crate::geometry::shapes::{box_room, ellipsoid, sphere};
    use crate::mesh::Mesh;
    use crate::nodes::NodeSet;
    use crate::quadrature::RuleLadder;
    use glam::DVec3;
    use std::sync::Arc;

    /// Points of the other elements near element `k` (inside twice its
    /// ball), at nodes and close to vertices and edges: the near regime.
    fn near_points(mesh: &Mesh, k: usize) -> Vec<FieldPoint> {
        let (centre, radius) = mesh.bounding_ball(k);
        let sts = [
            [0.1, 0.1],
            [0.8, 0.1],
            [0.1, 0.8],
            [1e-3, 1e-3],
            [0.5, 1e-4],
            [0.3, 0.3],
        ];
        (0..mesh.len())
            .filter(|&kp| kp != k)
            .flat_map(|kp| sts.map(|[s, t]| mesh.point(kp, s, t)))
            .filter(|q| (q.position - centre).length() < 2.0 * radius)
            .map(|q| FieldPoint {
                position: q.position,
                normal: q.normal,
                on_element: None,
            })
            .collect()
    }

    /// On the unit sphere G ≡ 1/4, so every row is ∫_Δ φ dS / 4π
    /// ([`unit_sphere_row`](super::super::tests::unit_sphere_row)).
    #[test]
    fn rows_on_the_sphere_are_the_closed_form() {
        let mesh = Mesh::new(Arc::new(sphere(1.0)), 2);
        let ladder = RuleLadder::new();
        let integrator = ElementIntegrator::new(&mesh, &ladder, QuadratureOptions::default());
        let nodes = NodeSet::new(2, 0.1).unwrap();
        let phi = |_k: usize, st: [f64; 2], _q: DVec3, out: &mut [f64]| {
            nodes.eval_basis(st[0], st[1], out)
        };
        let f = nodes.len();
        for k in [0, 17, 63] {
            let ps = near_points(&mesh, k);
            assert!(ps.len() > 20, "{} near points", ps.len());
            let exact = super::super::tests::unit_sphere_row(&mesh, k, &nodes, &ladder);
            let mut out = vec![0.0; ps.len() * f];
            integrator.integrate_rows(&ps, k, 2, &phi, &mut out);
            let scale: f64 = exact.iter().map(|x| x.abs()).sum();
            for row in out.chunks_exact(f) {
                for (a, b) in row.iter().zip(&exact) {
                    assert!((a - b).abs() <= 1e-11 * scale, "{a} against {b}");
                }
            }
        }
    }

    /// On curved and flat elements every row agrees with the row-by-row
    /// integral to the tolerance, and none took fewer kernel evaluations.
    #[test]
    fn rows_together_match_rows_alone() {
        for surface in [ellipsoid(1.0, 0.6, 0.3), box_room(1.0, 2.0, 1.5)] {
            let mesh = Mesh::new(Arc::new(surface), 2);
            let ladder = RuleLadder::new();
            let integrator = ElementIntegrator::new(&mesh, &ladder, QuadratureOptions::default());
            let nodes = NodeSet::new(3, 0.1).unwrap();
            let phi = |_k: usize, st: [f64; 2], _q: DVec3, out: &mut [f64]| {
                nodes.eval_basis(st[0], st[1], out)
            };
            let f = nodes.len();
            for k in [0, 5, 40] {
                let ps = near_points(&mesh, k);
                assert!(!ps.is_empty());
                let mut together = vec![0.0; ps.len() * f];
                let evals_together = integrator.integrate_rows(&ps, k, 3, &phi, &mut together);
                let mut evals_alone = 0;
                for (p, row) in ps.iter().zip(together.chunks_exact(f)) {
                    let mut alone = vec![0.0; f];
                    evals_alone += integrator.integrate(p, k, 3, &phi, &mut alone);
                    let scale: f64 = alone.iter().map(|x| x.abs()).sum();
                    for (a, b) in row.iter().zip(&alone) {
                        assert!((a - b).abs() <= 1e-11 * scale, "{a} against {b}");
                    }
                }
                assert!(evals_together >= evals_alone);
            }
        }
    }
}
