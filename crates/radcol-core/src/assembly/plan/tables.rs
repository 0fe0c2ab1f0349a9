//! The far-rule tables: for every far-rule degree some pair uses, the rule's
//! points, normals and weight × Jacobian / π on every element, structure of
//! arrays, so that the CPU's vectorised loop and the GPU's shader read the
//! same numbers.
//!
//! On a surface of flat elements the table keeps each element's affine map
//! (13 numbers, shared by every degree) and the rule, and the kernel is
//! evaluated from them (`FarTable::flat`, `kernels::far_kernel_flat`):
//! tabulated, every degree's points took about 120 KB an element (2.4 GB
//! of the room's 20 480 elements), more than the compressed operator at
//! that size. Curved elements keep their points tabulated
//! ([`FarTable::span`]); [`FarTable::point`] gives any element's point
//! (what the GPU uploads).

use crate::discretization::Discretization;
use crate::mesh::Mesh;
use crate::quadrature::RuleLadder;
use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::FRAC_1_PI;
use std::ops::Range;
use std::sync::Arc;

/// Far-rule data of one degree for every element.
///
/// For element k and rule point q: position, inner normal and `wj` = weight
/// × Jacobian / π ([`FarTable::point`], or a run's at once as arrays with
/// [`FarTable::span`]). `basis[j * nq + q]` = l_j at rule point q (the same
/// for all elements).
#[derive(Clone, Debug)]
pub struct FarTable {
    /// Degree of precision of the rule.
    pub degree: usize,
    /// Rule points per element.
    pub nq: usize,
    /// Per node set of the discretization ([`Discretization::node_sets`]),
    /// its Lagrange basis at the rule points, `f_r × nq`, row j contiguous:
    /// `basis[set][j * nq + q]` = l_j(point q).
    pub basis: Vec<Vec<f64>>,
    /// The same, transposed: `basis_t[set][q * f_r + j]`.
    pub basis_t: Vec<Vec<f64>>,
    /// The rule's points (s, t) in σ and its weights / π.
    s: Vec<f64>,
    t: Vec<f64>,
    w: Vec<f64>,
    points: Points,
}

/// Where the points of the elements come from.
#[derive(Clone, Debug)]
enum Points {
    /// Every element flat: made from its affine map as they are read.
    Flat(Arc<Vec<FlatElement>>),
    /// Tabulated, `n × nq` each, index `k * nq + q` (curved surfaces).
    Stored(Box<Soa>),
}

/// A flat element's map (s, t) ↦ origin + s e1 + t e2, its inner normal and
/// its Jacobian.
#[derive(Clone, Copy, Debug)]
pub(super) struct FlatElement {
    pub(super) origin: DVec3,
    pub(super) e1: DVec3,
    pub(super) e2: DVec3,
    pub(super) normal: DVec3,
    pub(super) jacobian: f64,
}

/// The maps of `mesh`'s elements when every one is flat, else None.
pub(super) fn flat_elements(mesh: &Mesh) -> Option<Arc<Vec<FlatElement>>> {
    if !(0..mesh.len()).all(|k| mesh.is_flat(k)) {
        return None;
    }
    let elements = (0..mesh.len())
        .into_par_iter()
        .map(|k| {
            let v = mesh.vertices(k);
            let c = mesh.point(k, 1.0 / 3.0, 1.0 / 3.0);
            FlatElement {
                origin: v[0],
                e1: v[1] - v[0],
                e2: v[2] - v[0],
                normal: c.normal,
                jacobian: c.jacobian,
            }
        })
        .collect();
    Some(Arc::new(elements))
}

/// Points, normals and weight × Jacobian / π, structure of arrays.
#[derive(Clone, Debug, Default)]
struct Soa {
    px: Vec<f64>,
    py: Vec<f64>,
    pz: Vec<f64>,
    nx: Vec<f64>,
    ny: Vec<f64>,
    nz: Vec<f64>,
    wj: Vec<f64>,
}

impl Soa {
    fn span(&self, r: Range<usize>) -> FarSpan<'_> {
        FarSpan {
            px: &self.px[r.clone()],
            py: &self.py[r.clone()],
            pz: &self.pz[r.clone()],
            nx: &self.nx[r.clone()],
            ny: &self.ny[r.clone()],
            nz: &self.nz[r.clone()],
            wj: &self.wj[r],
        }
    }

    fn heap_bytes(&self) -> usize {
        8 * [
            &self.px, &self.py, &self.pz, &self.nx, &self.ny, &self.nz, &self.wj,
        ]
        .iter()
        .map(|v| v.capacity())
        .sum::<usize>()
    }
}

/// The rule points of a run of elements, element-major (`e * nq + q`).
#[derive(Clone, Copy, Debug)]
pub struct FarSpan<'a> {
    /// x of the points.
    pub px: &'a [f64],
    /// y of the points.
    pub py: &'a [f64],
    /// z of the points.
    pub pz: &'a [f64],
    /// x of the inner normals.
    pub nx: &'a [f64],
    /// y of the inner normals.
    pub ny: &'a [f64],
    /// z of the inner normals.
    pub nz: &'a [f64],
    /// weight × Jacobian / π.
    pub wj: &'a [f64],
}

impl FarTable {
    /// Position, inner normal and weight × Jacobian / π of rule point `q`
    /// on element `k`.
    pub fn point(&self, k: usize, q: usize) -> ([f64; 3], [f64; 3], f64) {
        match &self.points {
            Points::Flat(e) => {
                let (p, n, wj) = self.flat_point(&e[k], q);
                (p.to_array(), n.to_array(), wj)
            }
            Points::Stored(s) => {
                let i = k * self.nq + q;
                (
                    [s.px[i], s.py[i], s.pz[i]],
                    [s.nx[i], s.ny[i], s.nz[i]],
                    s.wj[i],
                )
            }
        }
    }

    #[inline]
    fn flat_point(&self, e: &FlatElement, q: usize) -> (DVec3, DVec3, f64) {
        let (s, t) = (self.s[q], self.t[q]);
        (
            DVec3::new(
                e.origin.x + s * e.e1.x + t * e.e2.x,
                e.origin.y + s * e.e1.y + t * e.e2.y,
                e.origin.z + s * e.e1.z + t * e.e2.z,
            ),
            e.normal,
            self.w[q] * e.jacobian,
        )
    }

    /// On a flat surface: every element's map, and the rule's s, t and
    /// weights / π.
    pub(super) fn flat(&self) -> Option<(&[FlatElement], [&[f64]; 3])> {
        match &self.points {
            Points::Flat(e) => Some((&e[..], [&self.s[..], &self.t[..], &self.w[..]])),
            Points::Stored(_) => None,
        }
    }

    /// The tabulated points of the elements `run` (None on a flat
    /// surface, whose points are made from `FarTable::flat`).
    pub fn span(&self, run: Range<usize>) -> Option<FarSpan<'_>> {
        match &self.points {
            Points::Stored(s) => Some(s.span(run.start * self.nq..run.end * self.nq)),
            Points::Flat(_) => None,
        }
    }

    /// Bytes on the heap but for the flat elements' maps, which the tables
    /// of one plan share ([`FarTable::shared_bytes`]).
    pub fn heap_bytes(&self) -> usize {
        let points = match &self.points {
            Points::Flat(_) => 0,
            Points::Stored(s) => s.heap_bytes(),
        };
        8 * (self.basis.iter().map(Vec::capacity).sum::<usize>()
            + self.basis_t.iter().map(Vec::capacity).sum::<usize>()
            + self.s.capacity()
            + self.t.capacity()
            + self.w.capacity())
            + points
    }

    /// Bytes of the flat elements' maps, shared by the tables of one plan.
    pub fn shared_bytes(&self) -> usize {
        match &self.points {
            Points::Flat(e) => e.capacity() * std::mem::size_of::<FlatElement>(),
            Points::Stored(_) => 0,
        }
    }
}

/// The table of degree `d` on `disc`: from `flat`'s maps when every element
/// is flat, else tabulated.
pub(super) fn build_table(
    disc: &Discretization,
    ladder: &RuleLadder,
    d: usize,
    flat: Option<&Arc<Vec<FlatElement>>>,
) -> FarTable {
    let rule = ladder.rule(d);
    let nq = rule.len();
    let mesh = disc.mesh();
    let (mut basis, mut basis_t) = (Vec::new(), Vec::new());
    for nodes in disc.node_sets() {
        let f = nodes.len();
        let mut b = vec![0.0; f * nq];
        let mut b_t = vec![0.0; f * nq];
        let mut l = vec![0.0; f];
        for (q, &[s, t]) in rule.points.iter().enumerate() {
            nodes.eval_basis(s, t, &mut l);
            for j in 0..f {
                b[j * nq + q] = l[j];
                b_t[q * f + j] = l[j];
            }
        }
        basis.push(b);
        basis_t.push(b_t);
    }
    let points = match flat {
        Some(e) => Points::Flat(Arc::clone(e)),
        None => {
            let per_elem: Vec<[f64; 7]> = (0..mesh.len())
                .into_par_iter()
                .flat_map_iter(|k| {
                    rule.points
                        .iter()
                        .zip(&rule.weights)
                        .map(move |(&[s, t], &w)| {
                            let q = mesh.point(k, s, t);
                            let (p, n) = (q.position, q.normal);
                            [p.x, p.y, p.z, n.x, n.y, n.z, w * q.jacobian * FRAC_1_PI]
                        })
                })
                .collect();
            let col = |c: usize| per_elem.iter().map(|v| v[c]).collect::<Vec<f64>>();
            Points::Stored(Box::new(Soa {
                px: col(0),
                py: col(1),
                pz: col(2),
                nx: col(3),
                ny: col(4),
                nz: col(5),
                wj: col(6),
            }))
        }
    };
    FarTable {
        degree: rule.degree,
        nq,
        basis,
        basis_t,
        s: rule.points.iter().map(|p| p[0]).collect(),
        t: rule.points.iter().map(|p| p[1]).collect(),
        w: rule.weights.iter().map(|w| w * FRAC_1_PI).collect(),
        points,
    }
}

#[cfg(test)]
mod tests {
    use super::super::kernels::{far_kernel_flat, far_kernel_row};
    use super::*;
    use crate::nodes::NodeSet;

    /// A flat element's points from its map are the mesh's own to
    /// rounding, and the kernel evaluated from the map alone equals the
    /// one over the tabulated points (the same mesh tabulated) to rounding,
    /// from points in front of the elements, beside them (cosines clamped
    /// to 0 at some rule points) and behind them.
    #[test]
    fn flat_tables_agree_with_tabulated_ones() {
        let surface = Arc::new(crate::geometry::shapes::box_room(2.0, 3.0, 1.5));
        let mesh = Arc::new(Mesh::new(surface, 2));
        let disc = Discretization::new(mesh.clone(), NodeSet::new(2, 0.2).unwrap());
        let ladder = RuleLadder::new();
        let flat = flat_elements(&mesh).expect("a room is flat");
        for d in [0, 4, 9, 20] {
            let t = build_table(&disc, &ladder, d, Some(&flat));
            let stored = build_table(&disc, &ladder, d, None);
            assert!(t.span(0..1).is_none());
            let (elements, rule) = t.flat().unwrap();
            let nq = t.nq;
            for k in 0..mesh.len() {
                for q in 0..nq {
                    let (p, n, wj) = t.point(k, q);
                    let (ps, ns, wjs) = stored.point(k, q);
                    assert!(
                        (DVec3::from(p) - DVec3::from(ps)).length() < 1e-14,
                        "{k} {q}"
                    );
                    assert!((DVec3::from(n) - DVec3::from(ns)).length() < 1e-14);
                    crate::assert_close!(wj, wjs, 1e-14 * wjs.abs());
                }
            }
            let run = 0..mesh.len();
            let s = stored.span(run.clone()).unwrap();
            let pts = [
                (DVec3::new(1.0, 1.5, 0.0), DVec3::Z),
                (
                    DVec3::new(0.3, 0.2, 0.7),
                    DVec3::new(1.0, 1.0, 0.2).normalize(),
                ),
                (
                    DVec3::new(1.9, 2.9, 1.4),
                    DVec3::new(-0.3, -1.0, -0.5).normalize(),
                ),
                (DVec3::new(1.0, 1.5, -0.5), DVec3::Z),
            ];
            for (p, np) in pts {
                let mut want = vec![0.0; run.len() * nq];
                far_kernel_row(p, np, s.px, s.py, s.pz, s.nx, s.ny, s.nz, s.wj, &mut want);
                let mut got = vec![0.0; run.len() * nq];
                for (e, g) in elements.iter().zip(got.chunks_exact_mut(nq)) {
                    far_kernel_flat(p, np, e, rule, g);
                }
                let scale = want.iter().fold(0.0f64, |m, x| m.max(x.abs()));
                let zeros = want.iter().filter(|&&x| x == 0.0).count();
                assert!(zeros > 0 && zeros < want.len(), "degree {d}: {zeros} zeros");
                for (i, (a, b)) in got.iter().zip(&want).enumerate() {
                    assert!(
                        (a - b).abs() <= 1e-12 * scale,
                        "degree {d}, {i}: {a} vs {b}"
                    );
                }
            }
        }
        let sphere = Mesh::new(Arc::new(crate::geometry::shapes::sphere(1.0)), 1);
        assert!(flat_elements(&sphere).is_none());
    }
}
