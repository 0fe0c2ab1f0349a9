//! The assembly conformance suite: cases and comparisons every backend must
//! pass against the [`CpuBackend`] (style item 8: one suite, many backends).
//!
//! A GPU crate runs [`check_backend`] on its backend; core runs it on an
//! independent slow path ([`generic_matrix`]) that evaluates every far pair
//! point by point through [`ElementIntegrator::apply_rule`](super::ElementIntegrator::apply_rule) and
//! [`crate::kernel::g`] instead of the vectorised run loop. Near pairs take
//! the same walk as the backend ([`ElementIntegrator::integrate_rows`](super::ElementIntegrator::integrate_rows), whose
//! agreement with the row-by-row integral its own tests check).

use super::{AssemblyBackend, AssemblyPlan, CpuBackend, FieldPoint, PairClass, QuadratureOptions};
use crate::discretization::Discretization;
use crate::geometry::shapes::{box_room, ellipsoid, room_with_cube, sphere};
use crate::geometry::Surface;
use crate::matrix::DenseMatrix;
use crate::mesh::Mesh;
use crate::nodes::NodeSet;
use rayon::prelude::*;
use std::sync::Arc;

fn plan(surface: Surface, r: usize, level: u32) -> AssemblyPlan {
    let mesh = Arc::new(Mesh::new(Arc::new(surface), level));
    let disc = Arc::new(Discretization::new(
        mesh,
        NodeSet::new(r, 0.1).expect("0.1 is a valid alpha"),
    ));
    let visibility = crate::visibility::analyze(disc.mesh().surface());
    AssemblyPlan::new(disc, QuadratureOptions::default(), &visibility)
}

/// The conformance cases: sphere, ellipsoid (1, 1.5, 0.8), box room
/// (1, 2, 1.5) at r = 0..=3, α = 0.1, on small levels, and the occluding
/// [`room_with_cube`] at r = 0, 1 on level 0.
pub fn conformance_cases() -> Vec<(String, AssemblyPlan)> {
    let mut out = Vec::new();
    for r in 0..=1usize {
        out.push((
            format!("room with cube r={r} level=0"),
            plan(room_with_cube(), r, 0),
        ));
    }
    for r in 0..=3usize {
        let (ls, le, lb) = if r <= 1 { (2, 1, 2) } else { (1, 1, 1) };
        out.push((format!("sphere r={r} level={ls}"), plan(sphere(1.0), r, ls)));
        out.push((
            format!("ellipsoid r={r} level={le}"),
            plan(ellipsoid(1.0, 1.5, 0.8), r, le),
        ));
        out.push((
            format!("box r={r} level={lb}"),
            plan(box_room(1.0, 2.0, 1.5), r, lb),
        ));
    }
    out
}

/// Plans with a degree per element (0..=3 by element, in runs and alone,
/// so that far runs, near walks and self pairs meet elements of other
/// degrees): the ellipsoid, the box room and the occluding room with a cube.
pub fn mixed_degree_cases() -> Vec<(String, AssemblyPlan)> {
    let degree = |k: usize| [1, 3, 3, 0, 2, 2, 2, 1][k % 8];
    [
        ("ellipsoid", ellipsoid(1.0, 1.5, 0.8), 1),
        ("box", box_room(1.0, 2.0, 1.5), 1),
        ("room with cube", room_with_cube(), 0),
    ]
    .into_iter()
    .map(|(name, surface, level)| {
        let mesh = Arc::new(Mesh::new(Arc::new(surface), level));
        let sets = (0..=3)
            .map(|r| NodeSet::new(r, 0.1).expect("valid"))
            .collect();
        let degrees: Vec<usize> = (0..mesh.len()).map(degree).collect();
        let disc = Discretization::with_degrees(mesh, sets, &degrees).expect("sets of 0..=3");
        let visibility = crate::visibility::analyze(disc.mesh().surface());
        let plan = AssemblyPlan::new(Arc::new(disc), QuadratureOptions::default(), &visibility);
        (format!("{name} level={level}, r = 0..=3 by element"), plan)
    })
    .collect()
}

/// Largest differences found by [`compare_matrices`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MatrixDiff {
    /// max |got - want| / |want| over entries with want ≠ 0.
    pub entry_rel: f64,
    /// max |got - want| / max(|want|, row_floor · row max).
    pub floored_rel: f64,
}

/// Checks |got - want| ≤ tol · max(|want|, row_floor · max_j |want_ij|) for every
/// entry. The floor exists because an entry is a sum Σ_q G_q w_q l_j(q) whose
/// terms have both signs: one that nearly cancels carries the rounding of its
/// row-sized terms. On failure the message names row, column, both values, the
/// difference and the tolerance.
pub fn compare_matrices(
    got: &DenseMatrix,
    want: &DenseMatrix,
    tol: f64,
    row_floor: f64,
) -> Result<MatrixDiff, String> {
    if (got.nrows(), got.ncols()) != (want.nrows(), want.ncols()) {
        return Err(format!(
            "shape {}×{} differs from {}×{}",
            got.nrows(),
            got.ncols(),
            want.nrows(),
            want.ncols()
        ));
    }
    let mut d = MatrixDiff::default();
    for i in 0..want.nrows() {
        let (g, w) = (got.row(i), want.row(i));
        let row_max = w.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        for (j, (&gj, &wj)) in g.iter().zip(w).enumerate() {
            let diff = (gj - wj).abs();
            if wj != 0.0 {
                d.entry_rel = d.entry_rel.max(diff / wj.abs());
            }
            let scale = wj.abs().max(row_floor * row_max);
            if scale > 0.0 {
                d.floored_rel = d.floored_rel.max(diff / scale);
            }
            // NaN differences fail too.
            if diff > tol * scale || diff.is_nan() {
                return Err(format!(
                    "entry ({i}, {j}): got {gj:.17e}, want {wj:.17e}, |diff| = {diff:.3e} > tol {:.3e}",
                    tol * scale
                ));
            }
        }
    }
    Ok(d)
}

/// Runs every conformance case on `backend` and compares with the CPU backend
/// (matrices with [`compare_matrices`], and kernel evaluation counts).
#[cfg(feature = "conformance")]
pub fn check_backend(
    backend: &dyn AssemblyBackend,
    tol: f64,
    row_floor: f64,
) -> Result<Vec<(String, MatrixDiff)>, String> {
    let mut out = Vec::new();
    for (name, p) in conformance_cases() {
        let want = CpuBackend
            .assemble(&p)
            .map_err(|e| format!("{name}: cpu: {e}"))?;
        let got = backend.assemble(&p).map_err(|e| format!("{name}: {e}"))?;
        if got.kernel_evals != want.kernel_evals {
            return Err(format!(
                "{name}: {} kernel evaluations, the CPU backend made {}",
                got.kernel_evals, want.kernel_evals
            ));
        }
        let d = compare_matrices(&got.matrix, &want.matrix, tol, row_floor)
            .map_err(|e| format!("{name}: {e}"))?;
        out.push((name, d));
    }
    Ok(out)
}

/// The geometric matrix of `plan` by the slow generic path: every far pair
/// point by point through [`ElementIntegrator::apply_rule`](super::ElementIntegrator::apply_rule),
/// near and self pairs as the CPU backend does them.
pub fn generic_matrix(plan: &AssemblyPlan) -> DenseMatrix {
    let disc = plan.discretization();
    let n = disc.mesh().len();
    let dim = plan.dim();
    let mut m = DenseMatrix::zeros(dim, dim);
    if dim == 0 {
        return m;
    }
    let phi = |k: usize, st: [f64; 2], _q: glam::DVec3, out: &mut [f64]| {
        disc.nodes_of(k).eval_basis(st[0], st[1], out)
    };
    m.as_mut_slice()
        .par_chunks_exact_mut(dim)
        .enumerate()
        .for_each(|(i, row)| {
            let integrator = plan.integrator();
            let p = disc.points()[i];
            let fp = FieldPoint {
                position: p.position,
                normal: p.normal,
                on_element: Some((p.element, p.st)),
            };
            for k in 0..n {
                let (r, f) = (disc.degree(k), disc.nodes_per(k));
                let out = &mut row[disc.range(k)];
                match plan.class(p.element, k) {
                    PairClass::Culled => {}
                    PairClass::Near | PairClass::OnElement if k == p.element => {
                        integrator.integrate(&fp, k, r, &phi, out);
                    }
                    PairClass::Near | PairClass::OnElement => {
                        // Near pairs are walked for the element's rows at
                        // once (checked against row by row in `rows.rs`).
                        let ps: Vec<FieldPoint> = disc.points()[disc.range(p.element)]
                            .iter()
                            .map(|q| FieldPoint {
                                position: q.position,
                                normal: q.normal,
                                on_element: None,
                            })
                            .collect();
                        let mut rows = vec![0.0; ps.len() * f];
                        integrator.integrate_rows(&ps, k, r, &phi, &mut rows);
                        out.copy_from_slice(&rows[p.node * f..(p.node + 1) * f]);
                    }
                    PairClass::Partial => {
                        plan.integrate_partial(
                            &integrator,
                            p.position,
                            p.normal,
                            p.element,
                            k,
                            &phi,
                            out,
                        );
                    }
                    PairClass::Far(d) => {
                        let rule = plan.ladder().rule(d as usize);
                        let tri = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
                        integrator.apply_rule(&fp, k, tri, rule, &phi, out);
                    }
                }
            }
        });
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The vectorised far loop (SoA runs, register contraction) agrees with the
    /// point-by-point generic path on every conformance case.
    #[test]
    fn cpu_backend_matches_the_generic_path() {
        for (name, p) in conformance_cases() {
            matches_the_generic_path(&name, &p);
        }
    }

    /// The CPU backend's matrix of `p`, checked against [`generic_matrix`].
    fn matches_the_generic_path(name: &str, p: &AssemblyPlan) -> DenseMatrix {
        let fast = CpuBackend.assemble(p).unwrap().matrix;
        let slow = generic_matrix(p);
        let d =
            compare_matrices(&fast, &slow, 1e-13, 1e-3).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(d.floored_rel <= 1e-13, "{name}: {d:?}");
        fast
    }

    /// With a degree per element, the backend's runs (one node set each)
    /// agree with the point-by-point path, and each element's entries with
    /// those of a plan of its degree alone: a column of element k depends
    /// only on k's node set, a row only on its point.
    #[test]
    fn a_degree_per_element_matches_each_degree_alone() {
        for (name, p) in mixed_degree_cases() {
            let fast = matches_the_generic_path(&name, &p);
            let disc = p.discretization();
            for r in 0..=3 {
                let one = Arc::new(Discretization::new(
                    disc.mesh().clone(),
                    NodeSet::new(r, 0.1).unwrap(),
                ));
                let visibility = crate::visibility::analyze(one.mesh().surface());
                let alone =
                    AssemblyPlan::new(one.clone(), QuadratureOptions::default(), &visibility);
                let m = CpuBackend.assemble(&alone).unwrap().matrix;
                // Rows of elements of degree r, columns of elements of degree r.
                for kp in (0..disc.mesh().len()).filter(|&k| disc.degree(k) == r) {
                    for (a, i) in disc.range(kp).enumerate() {
                        let i_alone = one.range(kp).start + a;
                        let scale = m.row(i_alone).iter().fold(0.0f64, |x, v| x.max(v.abs()));
                        for k in (0..disc.mesh().len()).filter(|&k| disc.degree(k) == r) {
                            for (j, j_alone) in disc.range(k).zip(one.range(k)) {
                                let (got, want) = (fast.row(i)[j], m.row(i_alone)[j_alone]);
                                assert!(
                                    (got - want).abs() <= 1e-13 * scale,
                                    "{name}: ({i}, {j}) {got} against {want} alone at r = {r}"
                                );
                            }
                        }
                    }
                }
            }
        }
    }

    /// Lemma 1(c) with a degree per element: every case bounds its
    /// enclosure (the box room and the room with a cube are closed, the
    /// ellipsoid convex), so each row sums to 1 (∫_S G V dS_Q = π, and each
    /// element's basis sums to 1 whatever its degree).
    #[test]
    fn a_degree_per_element_keeps_unit_row_sums() {
        for (name, p) in mixed_degree_cases() {
            let m = CpuBackend.assemble(&p).unwrap().matrix;
            for i in 0..m.nrows() {
                let sum: f64 = m.row(i).iter().sum();
                assert!((sum - 1.0).abs() <= 1e-11, "{name}: row {i} sums to {sum}");
            }
        }
    }

    #[test]
    fn comparison_names_the_entry_that_differs() {
        let want = DenseMatrix::from_row_major(2, 2, vec![1.0, 2.0, 3.0, 4.0]);
        let mut got = want.clone();
        got.as_mut_slice()[3] = 4.0 + 1e-9;
        let err = compare_matrices(&got, &want, 1e-13, 1e-3).unwrap_err();
        assert!(err.contains("entry (1, 1)"), "{err}");
        assert!(compare_matrices(&want, &want, 0.0, 0.0).is_ok());
    }
}
