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
}

/// log(e_prev / e) / log(h_prev / h).
pub fn eoc(e_prev: f64, e: f64, h_prev: f64, h: f64) -> Option<f64> {
    (e_prev > 0.0 && e > 0.0).then(|| (e_prev / e).ln() / (h_prev / h).ln())
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
        let row = StudyRow {
            level,
            elements: out.discretization.mesh().len(),
            unknowns: out.discretization.len(),
            h: out.h,
            nodes_max: e.nodes_max,
            global_max: e.global_max,
            l2: e.l2,
            eoc_nodes: prev.and_then(|p| eoc(p.nodes_max, e.nodes_max, p.h, out.h)),
            eoc_global: prev.and_then(|p| eoc(p.global_max, e.global_max, p.h, out.h)),
            eoc_l2: prev.and_then(|p| eoc(p.l2, e.l2, p.h, out.h)),
            assembly_s: out.timings.assembly_s,
            solve_s: out.timings.solve_s,
            total_s: out.timings.total_s,
            iterations: ch.solver.iterations,
            kernel_evals: out.kernel_evals,
        };
        progress(&row);
        rows.push(row);
    }
    Ok(rows)
}
