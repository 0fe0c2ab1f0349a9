//! The far-rule tables: for every far-rule degree some pair uses, the rule's
//! points, normals and weight × Jacobian / π on every element, structure of
//! arrays, so that the CPU's vectorised loop and the GPU's shader read the
//! same numbers.

use crate::discretization::Discretization;
use crate::quadrature::RuleLadder;
use rayon::prelude::*;

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

pub(super) fn build_table(disc: &Discretization, ladder: &RuleLadder, d: usize) -> FarTable {
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
