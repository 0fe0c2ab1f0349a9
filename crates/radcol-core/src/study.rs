//! Refinement studies: solve on levels A..=B and report errors with their
//! experimental orders of convergence (EOC).

use crate::assembly::AssemblyBackend;
use crate::error::{Error, InputError};
use crate::problem::Problem;
use crate::run::{solve, SolveConfig};
use serde::Serialize;

/// One level of a study.
#[derive(Clone, Debug, Serialize)]
pub struct StudyRow {
    /// Refinement level.
    pub level: u32,
    /// Elements n.
    pub elements: usize,
    /// Unknowns N.
    pub unknowns: usize,
    /// Mesh size h.
    pub h: f64,
    /// max error at the nodes.
    pub nodes_max: f64,
    /// max error over S.
    pub global_max: f64,
    /// L² error.
    pub l2: f64,
    /// EOC of `nodes_max` against the previous row (None on the first).
    pub eoc_nodes: Option<f64>,
    /// EOC of `global_max`.
    pub eoc_global: Option<f64>,
    /// EOC of `l2`.
    pub eoc_l2: Option<f64>,
    /// Assembly seconds.
    pub assembly_s: f64,
    /// Solve seconds.
    pub solve_s: f64,
    /// Total seconds of the level.
    pub total_s: f64,
    /// GMRES iterations (0 for LU).
    pub iterations: usize,
    /// Kernel evaluations of the assembly.
    pub kernel_evals: u64,
    /// Errors at or below this (1000 ε · max |u_n| at the nodes) are rounding,
    /// not discretization error: no EOC is computed from them and fitted orders
    /// leave them out.
    pub rounding_floor: f64,
}

/// Relative size of the rounding floor: 1000 machine epsilons (≈ 2.2e-13).
pub const ROUNDING_FLOOR: f64 = 1000.0 * f64::EPSILON;

/// log(e_prev / e) / log(h_prev / h), or None when either error is at or
/// below its rounding floor (an order computed from rounding is noise).
pub fn eoc(e_prev: f64, e: f64, h_prev: f64, h: f64, floor_prev: f64, floor: f64) -> Option<f64> {
    (e_prev > floor_prev && e > floor && e_prev > 0.0 && e > 0.0)
        .then(|| (e_prev / e).ln() / (h_prev / h).ln())
}

/// The fitted order of one norm over the rows whose error lies above their
/// rounding floor; None with fewer than two such rows.
pub fn fitted_order_above_rounding(rows: &[StudyRow], error: fn(&StudyRow) -> f64) -> Option<f64> {
    let (h, e): (Vec<f64>, Vec<f64>) = rows
        .iter()
        .filter(|r| error(r).is_finite() && error(r) > r.rounding_floor && error(r) > 0.0)
        .map(|r| (r.h, error(r)))
        .unzip();
    (h.len() >= 2)
        .then(|| fitted_order(&h, &e))
        .filter(|v| v.is_finite())
}

/// Least-squares slope of ln e against ln h: the fitted convergence order.
pub fn fitted_order(h: &[f64], e: &[f64]) -> f64 {
    let n = h.len() as f64;
    let xs: Vec<f64> = h.iter().map(|v| v.ln()).collect();
    let ys: Vec<f64> = e.iter().map(|v| v.ln()).collect();
    let (mx, my) = (xs.iter().sum::<f64>() / n, ys.iter().sum::<f64>() / n);
    let sxy: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = xs.iter().map(|x| (x - mx) * (x - mx)).sum();
    sxy / sxx
}

/// Solves on each level of `levels` and collects the errors (the problem must
/// carry an exact solution).
pub fn study(
    problem: &Problem,
    base: &SolveConfig,
    levels: std::ops::RangeInclusive<u32>,
    backend: &dyn AssemblyBackend,
    mut progress: impl FnMut(&StudyRow),
) -> Result<Vec<StudyRow>, Error> {
    if problem.exact.is_none() {
        return Err(InputError::Other(
            "a study needs the exact solution: give --exact EXPR".into(),
        )
        .into());
    }
    let mut rows: Vec<StudyRow> = Vec::new();
    for level in levels {
        let cfg = SolveConfig {
            level,
            ..base.clone()
        };
        let out = solve(problem, &cfg, backend)?;
        let ch = &out.channels[0];
        let e = ch.errors.expect("exact solution given");
        let prev = rows.last();
        let scale = ch
            .solution
            .nodal()
            .iter()
            .fold(0.0f64, |m, v| m.max(v.abs()));
        let floor = ROUNDING_FLOOR * scale;
        let row = StudyRow {
            level,
            elements: out.discretization.mesh().len(),
            unknowns: out.discretization.len(),
            h: out.h,
            nodes_max: e.nodes_max,
            global_max: e.global_max,
            l2: e.l2,
            eoc_nodes: prev.and_then(|p| {
                eoc(
                    p.nodes_max,
                    e.nodes_max,
                    p.h,
                    out.h,
                    p.rounding_floor,
                    floor,
                )
            }),
            eoc_global: prev.and_then(|p| {
                eoc(
                    p.global_max,
                    e.global_max,
                    p.h,
                    out.h,
                    p.rounding_floor,
                    floor,
                )
            }),
            eoc_l2: prev.and_then(|p| eoc(p.l2, e.l2, p.h, out.h, p.rounding_floor, floor)),
            assembly_s: out.timings.assembly_s,
            solve_s: out.timings.solve_s,
            total_s: out.timings.total_s,
            iterations: ch.solver.iterations,
            kernel_evals: out.kernel_evals,
            rounding_floor: floor,
        };
        progress(&row);
        rows.push(row);
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(h: f64, nodes: f64) -> StudyRow {
        StudyRow {
            level: 0,
            elements: 0,
            unknowns: 0,
            h,
            nodes_max: nodes,
            global_max: h * h,
            l2: h * h,
            eoc_nodes: None,
            eoc_global: None,
            eoc_l2: None,
            assembly_s: 0.0,
            solve_s: 0.0,
            total_s: 0.0,
            iterations: 0,
            kernel_evals: 0,
            rounding_floor: 2.2e-13,
        }
    }

    #[test]
    fn orders_ignore_errors_at_rounding() {
        assert_eq!(eoc(4e-16, 4e-16, 1.0, 0.5, 2.2e-13, 2.2e-13), None);
        assert_eq!(eoc(1e-9, 4e-16, 1.0, 0.5, 2.2e-13, 2.2e-13), None);
        let e = eoc(1e-6, 1e-6 / 16.0, 1.0, 0.5, 2.2e-13, 2.2e-13).unwrap();
        assert!((e - 4.0).abs() < 1e-12);
        let rows = [row(1.0, 1e-6), row(0.5, 1e-6 / 16.0), row(0.25, 4e-16)];
        let nodes = fitted_order_above_rounding(&rows, |r| r.nodes_max).unwrap();
        assert!((nodes - 4.0).abs() < 1e-12, "{nodes}");
        let global = fitted_order_above_rounding(&rows, |r| r.global_max).unwrap();
        assert!((global - 2.0).abs() < 1e-12);
        assert_eq!(
            fitted_order_above_rounding(&rows[2..], |r| r.nodes_max),
            None
        );
    }
}
