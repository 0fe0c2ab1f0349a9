//! Packing the plan for the device: the used far rules and their basis
//! tables, the far points of a column tile (point-major), a tile's class
//! codes and its parameters. Pure functions of the plan, tested without a GPU.

use crate::error::GpuError;
use crate::layout::{GpuScalar, Params, RuleInfo, RULE_SLOTS};
use crate::tiling::Tile;
use radcol_core::backend::{AssemblyPlan, ClassTable, FarTable, MAX_RULE_DEGREE};
use rayon::prelude::*;

/// The used far rules, laid out for the device.
pub(super) struct Rules<'a> {
    /// (table, offset in an element record, offset in basis_t).
    pub(super) used: Vec<(&'a FarTable, usize, usize)>,
    pub(super) infos: Vec<RuleInfo>,
    pub(super) basis_t: Vec<f64>,
    pub(super) stride: usize,
}

impl<'a> Rules<'a> {
    pub(super) fn new(plan: &'a AssemblyPlan) -> Result<Self, GpuError> {
        let mut infos = vec![RuleInfo::default(); RULE_SLOTS];
        let mut used = Vec::new();
        let mut basis_t = Vec::new();
        let mut stride = 0usize;
        for d in 0..=MAX_RULE_DEGREE {
            let Some(t) = plan.far_table(d) else { continue };
            let code = d + 1;
            if code >= RULE_SLOTS {
                return Err(GpuError::Unsupported(format!(
                    "far rule degree {d} has no class code"
                )));
            }
            infos[code] = RuleInfo {
                offset: to_u32(stride, "far points per element")?,
                nq: to_u32(t.nq, "rule points")?,
                basis: to_u32(basis_t.len(), "basis table length")?,
                far: 1,
            };
            used.push((t, stride, basis_t.len()));
            basis_t.extend_from_slice(&t.basis_t[0]);
            stride += t.nq;
        }
        Ok(Self {
            used,
            infos,
            basis_t,
            stride,
        })
    }
}

/// The far points of elements `k0..k0 + nk`, point-major: `out[s · nk + e]` is
/// slot s (rule offset + q, the used rules in degree order) of element k0 + e.
pub(super) fn far_points<S: GpuScalar>(rules: &Rules<'_>, k0: usize, nk: usize) -> Vec<S::Point> {
    let stride = rules.stride;
    let mut out = vec![S::point([0.0; 3], [0.0; 3], 0.0); nk * stride];
    // Slot s = offset + q of a rule holds that point for every element of the tile.
    let mut slot_rule = Vec::with_capacity(stride);
    for &(t, offset, _) in &rules.used {
        for q in 0..t.nq {
            slot_rule.push((t, q));
            debug_assert_eq!(slot_rule.len(), offset + q + 1);
        }
    }
    out.par_chunks_exact_mut(nk)
        .zip(slot_rule.par_iter())
        .for_each(|(slot, &(t, q))| {
            for (e, rec) in slot.iter_mut().enumerate() {
                let (p, n, wj) = t.point(k0 + e, q);
                *rec = S::point(p, n, wj);
            }
        });
    out
}

/// The class codes of the row blocks that `tile` touches against its `nk`
/// elements, block-major, padded with zeros to a multiple of four bytes
/// (the shader reads them as u32). `classes` is the plan's table.
pub(super) fn tile_codes(classes: &ClassTable, f: usize, tile: &Tile) -> Vec<u8> {
    let kp0 = tile.row0 / f;
    let kp1 = (tile.row0 + tile.rows - 1) / f + 1;
    let mut codes = Vec::with_capacity(((kp1 - kp0) * tile.nk).div_ceil(4) * 4);
    for kp in kp0..kp1 {
        codes.extend_from_slice(&classes.row(kp, tile.k0..tile.k0 + tile.nk));
    }
    codes.resize(codes.len().div_ceil(4) * 4, 0);
    codes
}

/// The uniform parameters of `tile` (f nodes per element, `stride` far
/// points per element record).
pub(super) fn tile_params(tile: &Tile, f: usize, stride: usize) -> Result<Params, GpuError> {
    Ok(Params {
        row0: to_u32(tile.row0, "row")?,
        rows: to_u32(tile.rows, "rows")?,
        kp0: to_u32(tile.row0 / f, "element")?,
        f: f as u32,
        k0: to_u32(tile.k0, "element")?,
        nk: to_u32(tile.nk, "elements")?,
        stride: to_u32(stride, "stride")?,
        out_cols: to_u32(tile.nk * f, "columns")?,
    })
}

pub(super) fn to_u32(x: usize, what: &str) -> Result<u32, GpuError> {
    u32::try_from(x).map_err(|_| GpuError::TooLarge {
        message: format!("{what} = {x} exceeds u32"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use radcol_core::assembly::QuadratureOptions;
    use radcol_core::discretization::Discretization;
    use radcol_core::geometry::shapes::sphere;
    use radcol_core::mesh::Mesh;
    use radcol_core::nodes::NodeSet;
    use std::sync::Arc;

    fn plan() -> AssemblyPlan {
        let mesh = Arc::new(Mesh::new(Arc::new(sphere(1.0)), 1));
        let disc = Arc::new(Discretization::new(mesh, NodeSet::new(1, 0.1).unwrap()));
        let visibility = radcol_core::visibility::analyze(disc.mesh().surface());
        AssemblyPlan::new(disc, QuadratureOptions::default(), &visibility)
    }

    /// The used rules are laid out in degree order, each at the running sum
    /// of the previous rules' points, with its basis table at its offset.
    #[test]
    fn rules_are_concatenated_in_degree_order() {
        let plan = plan();
        let rules = Rules::new(&plan).unwrap();
        assert!(!rules.used.is_empty());
        let mut stride = 0;
        let mut basis = 0;
        for d in 0..=MAX_RULE_DEGREE {
            let info = rules.infos[d + 1];
            match plan.far_table(d) {
                Some(t) => {
                    assert_eq!((info.offset, info.nq, info.far), (stride, t.nq as u32, 1));
                    assert_eq!(info.basis as usize, basis);
                    assert_eq!(
                        &rules.basis_t[basis..basis + t.basis_t[0].len()],
                        &t.basis_t[0][..]
                    );
                    stride += t.nq as u32;
                    basis += t.basis_t[0].len();
                }
                None => assert_eq!(info.far, 0, "degree {d} is unused"),
            }
        }
        assert_eq!(rules.stride, stride as usize);
        assert_eq!(rules.infos[0].far, 0, "code 0 (culled) has no rule");
    }

    /// Slot s of element e in a column tile holds rule point q of element
    /// k0 + e, for the rule whose slots contain s.
    #[test]
    fn far_points_are_point_major() {
        let plan = plan();
        let rules = Rules::new(&plan).unwrap();
        let (k0, nk) = (5, 7);
        let out = far_points::<f64>(&rules, k0, nk);
        assert_eq!(out.len(), nk * rules.stride);
        for &(t, offset, _) in &rules.used {
            for q in [0, t.nq - 1] {
                for e in [0, nk - 1] {
                    let rec = out[(offset + q) * nk + e];
                    let (p, n, wj) = t.point(k0 + e, q);
                    assert_eq!((rec.p, rec.n, rec.wj), (p, n, wj));
                }
            }
        }
    }

    /// A tile's codes are its row blocks' classes against its elements,
    /// block-major, zero-padded to whole u32 words; its parameters name it.
    #[test]
    fn tile_codes_and_params_describe_the_tile() {
        let plan = plan();
        let f = plan.discretization().max_nodes_per_element();
        // Rows 4..10 touch row blocks 1..=3 (f = 3); elements 2..7.
        let tile = Tile {
            row0: 4,
            rows: 6,
            k0: 2,
            nk: 5,
        };
        let codes = tile_codes(plan.classes(), f, &tile);
        assert_eq!(codes.len(), (3 * 5usize).div_ceil(4) * 4);
        for (b, kp) in (1..=3).enumerate() {
            for e in 0..5 {
                assert_eq!(codes[b * 5 + e], plan.class(kp, 2 + e).code());
            }
        }
        assert!(codes[15..].iter().all(|&c| c == 0));
        let p = tile_params(&tile, f, 40).unwrap();
        assert_eq!(
            (p.row0, p.rows, p.kp0, p.f, p.k0, p.nk, p.stride, p.out_cols),
            (4, 6, 1, 3, 2, 5, 40, 15)
        );
    }
}
