//! Refinement studies: solve on levels A..=B and report errors with their
//! experimental orders of convergence (EOC); [`speed`]: which setting
//! (degree, uniform level or adaptive step) reaches each error decade
//! fastest.

pub mod speed;

// The method's node sets and their α0, which the studies measure.
pub use crate::alpha0::{find_alpha0, Alpha0Report, AlphaRoot};
pub use crate::nodes::NodeSet;

use crate::assembly::AssemblyBackend;
use crate::error::{Error, InputError};
use crate::norms::ErrorNorms;
use crate::problem::Problem;
use crate::run::{check_size, solve, SolveConfig};
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
    /// True when the problem has no exact solution and the error columns are
    /// the a posteriori estimate (`crate::estimate`): `global_max` and `l2`
    /// estimated, `nodes_max` not estimable (η vanishes at the nodes: NaN).
    pub estimated: bool,
    /// The estimate's max and L² (absolute, first channel), when estimated.
    pub estimate_max: Option<f64>,
    /// See `estimate_max`.
    pub estimate_l2: Option<f64>,
    /// Estimate / true global max error, when both are known.
    pub effectivity: Option<f64>,
    /// Errors at or below this (1000 ε · max |u_n| at the nodes) are rounding,
    /// not discretization error: no EOC is computed from them and fitted orders
    /// leave them out.
    pub rounding_floor: f64,
    /// max |u_n| over the nodes: the scale of relative errors.
    pub scale: f64,
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

/// What the theory predicts for degree r at node parameter α.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PredictedOrders {
    /// Order of the global max and L² errors, r + 1 (eq. 23).
    pub global_max: usize,
    /// The same for L².
    pub l2: usize,
    /// Order at the nodes, when the theory predicts one at this α: r + 2 for
    /// even r (eq. 39), r + 3 (times log h) for odd r at α = α0 (eq. 36).
    pub nodes_max: Option<usize>,
    /// One sentence naming the equations.
    pub note: String,
}

/// The orders the theory predicts for degree `r` at `alpha`, given the α0
/// search for `r` (`a0`, from [`crate::alpha0::find_alpha0`]).
pub fn predicted_orders(r: usize, alpha: f64, a0: &Alpha0Report) -> PredictedOrders {
    let global = r + 1;
    let head = format!("theory for r = {r}: global max and L2 O(h^{global}) (eq. 23); ");
    let (nodes, tail) = if r.is_multiple_of(2) {
        (
            Some(r + 2),
            format!("nodes O(h^{}) (even r, any α: eq. 39)", r + 2),
        )
    } else {
        match a0.alpha0 {
            Some(a) if (a - alpha).abs() <= 1e-12 => (
                Some(r + 3),
                format!("nodes O(h^{} log h) (odd r at α = α0: eq. 36)", r + 3),
            ),
            Some(a) => (
                None,
                format!(
                    "nodes O(h^{} log h) only at α0 = {a} (this run uses α = {alpha})",
                    r + 3
                ),
            ),
            None => (
                None,
                format!(
                    "nodes O(h^{} log h) needs α0, which does not exist for r = {r} (see `radcol nodes --degree {r}`)",
                    r + 3
                ),
            ),
        }
    };
    PredictedOrders {
        global_max: global,
        l2: global,
        nodes_max: nodes,
        note: head + &tail,
    }
}

/// A refinement study that has been checked and may run: the problem has an
/// exact solution or its errors are estimated, and the finest level fits in
/// memory, so a study that cannot finish is refused before its first level
/// is solved.
#[derive(Debug)]
pub struct Study<'a> {
    problem: &'a Problem,
    base: SolveConfig,
    levels: std::ops::RangeInclusive<u32>,
}

impl<'a> Study<'a> {
    /// Checks `problem` and the finest of `levels` with `base`'s settings.
    pub fn new(
        problem: &'a Problem,
        base: &SolveConfig,
        levels: std::ops::RangeInclusive<u32>,
    ) -> Result<Self, Error> {
        if problem.exact.is_none() && !base.estimate {
            return Err(InputError::NoExactSolution.into());
        }
        check_size(
            problem,
            &SolveConfig {
                level: *levels.end(),
                ..base.clone()
            },
        )?;
        Ok(Self {
            problem,
            base: base.clone(),
            levels,
        })
    }

    /// Solves on each level and collects the errors, calling `progress`
    /// with each row as it completes.
    pub fn run(
        self,
        backend: &dyn AssemblyBackend,
        progress: impl FnMut(&StudyRow),
    ) -> Result<Vec<StudyRow>, Error> {
        run_levels(self.problem, &self.base, self.levels, backend, progress)
    }
}

/// Solves on each level of `levels` and collects the errors (the problem must
/// carry an exact solution): [`Study::new`] then [`Study::run`].
pub fn study(
    problem: &Problem,
    base: &SolveConfig,
    levels: std::ops::RangeInclusive<u32>,
    backend: &dyn AssemblyBackend,
    progress: impl FnMut(&StudyRow),
) -> Result<Vec<StudyRow>, Error> {
    Study::new(problem, base, levels)?.run(backend, progress)
}

fn run_levels(
    problem: &Problem,
    base: &SolveConfig,
    levels: std::ops::RangeInclusive<u32>,
    backend: &dyn AssemblyBackend,
    mut progress: impl FnMut(&StudyRow),
) -> Result<Vec<StudyRow>, Error> {
    let mut rows: Vec<StudyRow> = Vec::new();
    for level in levels {
        let cfg = SolveConfig {
            level,
            ..base.clone()
        };
        let out = solve(problem, &cfg, backend)?;
        let ch = &out.channels[0];
        let estimate = ch.estimate.as_ref();
        let e = match (ch.errors, estimate) {
            (Some(e), _) => e,
            (None, Some(est)) => ErrorNorms {
                nodes_max: f64::NAN,
                global_max: est.max,
                l2: est.l2,
            },
            (None, None) => return Err(InputError::NoExactSolution.into()),
        };
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
            estimated: ch.errors.is_none(),
            estimate_max: estimate.map(|x| x.max),
            estimate_l2: estimate.map(|x| x.l2),
            effectivity: match (ch.errors, estimate) {
                (Some(e), Some(x)) if e.global_max > 0.0 => Some(x.max / e.global_max),
                _ => None,
            },
            rounding_floor: floor,
            scale,
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
            estimated: false,
            estimate_max: None,
            estimate_l2: None,
            effectivity: None,
            rounding_floor: 2.2e-13,
            scale: 1.0,
        }
    }

    #[test]
    fn orders_ignore_errors_at_rounding() {
        assert_eq!(eoc(4e-16, 4e-16, 1.0, 0.5, 2.2e-13, 2.2e-13), None);
        assert_eq!(eoc(1e-9, 4e-16, 1.0, 0.5, 2.2e-13, 2.2e-13), None);
        let e = eoc(1e-6, 1e-6 / 16.0, 1.0, 0.5, 2.2e-13, 2.2e-13).unwrap();
        crate::assert_close!(e, 4.0, 1e-12);
        let rows = [row(1.0, 1e-6), row(0.5, 1e-6 / 16.0), row(0.25, 4e-16)];
        let nodes = fitted_order_above_rounding(&rows, |r| r.nodes_max).unwrap();
        crate::assert_close!(nodes, 4.0, 1e-12, "{nodes}");
        let global = fitted_order_above_rounding(&rows, |r| r.global_max).unwrap();
        crate::assert_close!(global, 2.0, 1e-12);
        assert_eq!(
            fitted_order_above_rounding(&rows[2..], |r| r.nodes_max),
            None
        );
    }
}
