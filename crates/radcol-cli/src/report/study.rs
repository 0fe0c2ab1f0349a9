//! `radcol study`: a header, one line per level as it completes, and the
//! fitted orders beside the theory's.

use super::{alpha_text, ProblemText};
use crate::setup::Setup;
use radcol_core::prelude::BackendInfo;
use radcol_core::run::SolverKind;
use radcol_core::study::{fitted_order_above_rounding, PredictedOrders, StudyRow};
use serde::Serialize;
use std::fmt;

/// What the table is of: printed before the first level is solved.
#[derive(Clone, Debug, Serialize)]
pub struct StudyHeader {
    command: &'static str,
    scene: String,
    degree: usize,
    alpha: f64,
    alpha_auto: bool,
    levels: [u32; 2],
    problem: ProblemText,
    solver: SolverKind,
    backend: BackendInfo,
}

impl StudyHeader {
    /// The header of a study of `s` over `levels`.
    pub fn new(s: &Setup, levels: (u32, u32)) -> Self {
        Self {
            command: "study",
            scene: s.scene.clone(),
            degree: s.cfg.degree,
            alpha: s.alpha.value,
            alpha_auto: s.alpha.auto,
            levels: [levels.0, levels.1],
            problem: ProblemText::of(s),
            solver: s.cfg.solver,
            backend: s.backend.info(),
        }
    }

    /// The plot's title.
    pub fn title(&self) -> String {
        format!(
            "radcol study: {}, r = {}, α = {:.6}, ρ = {}, u = {}",
            self.scene,
            self.degree,
            self.alpha,
            self.problem.rho,
            self.problem.exact.as_deref().unwrap_or("-")
        )
    }
}

impl fmt::Display for StudyHeader {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "radcol study: {}, r = {}, {}, ρ = {}, u = {}, E = {}, levels {}..={}, backend {}",
            self.scene,
            self.degree,
            alpha_text(self.alpha, self.alpha_auto, self.degree),
            self.problem.rho,
            self.problem.exact.as_deref().unwrap_or("-"),
            self.problem.emission,
            self.levels[0],
            self.levels[1],
            self.backend
        )?;
        if self.problem.exact.is_none() {
            writeln!(
                f,
                "errors estimated (no --exact): global_max and l2 of η = E + K u_n - u_n at check points; nodes_max is not estimable (η = 0 at the nodes)"
            )?;
        }
        writeln!(
            f,
            "{:>5} {:>9} {:>9} {:>10} {:>10} {:>10} {:>10} {:>9} {:>10} {:>7} {:>11} {:>10}",
            "level",
            "elements",
            "unknowns",
            "h",
            "nodes_max",
            "global_max",
            "l2",
            "eoc_nodes",
            "eoc_global",
            "eoc_l2",
            "assembly_s",
            "solve_s"
        )
    }
}

/// One line of the table.
#[derive(Clone, Copy, Debug)]
pub struct StudyLine<'a>(pub &'a StudyRow);

impl fmt::Display for StudyLine<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let r = self.0;
        let eoc = |v: Option<f64>| v.map(|x| format!("{x:.3}")).unwrap_or_else(|| "-".into());
        let err = |v: f64| {
            if v.is_finite() {
                format!("{v:.3e}")
            } else {
                "-".into()
            }
        };
        writeln!(
            f,
            "{:>5} {:>9} {:>9} {:>10.6} {:>10} {:>10} {:>10} {:>9} {:>10} {:>7} {:>11.4} {:>10.4}",
            r.level,
            r.elements,
            r.unknowns,
            r.h,
            err(r.nodes_max),
            err(r.global_max),
            err(r.l2),
            eoc(r.eoc_nodes),
            eoc(r.eoc_global),
            eoc(r.eoc_l2),
            r.assembly_s,
            r.solve_s
        )
    }
}

/// Fitted orders (least squares over the levels whose error lies above the
/// rounding floor) of the three norms; None with fewer than two such levels.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Fitted {
    nodes_max: Option<f64>,
    global_max: Option<f64>,
    l2: Option<f64>,
}

impl Fitted {
    /// The fitted orders of `rows`.
    pub fn of(rows: &[StudyRow]) -> Self {
        let fit = |e: fn(&StudyRow) -> f64| fitted_order_above_rounding(rows, e);
        Self {
            nodes_max: fit(|r| r.nodes_max),
            global_max: fit(|r| r.global_max),
            l2: fit(|r| r.l2),
        }
    }
}

/// The fitted orders and the theory, after the table.
#[derive(Clone, Debug, Serialize)]
pub struct StudyFooter {
    fitted: Fitted,
    theory: PredictedOrders,
    plot: Option<String>,
    /// The first level whose nodal error is at rounding while the global
    /// error is not (then every later level's too): no nodal order can be
    /// measured from this exact solution on these meshes.
    nodes_at_rounding: Option<u32>,
}

/// The first level of `rows` from which on the nodal error lies at or below
/// the rounding floor while the global error lies above it.
fn nodes_at_rounding(rows: &[StudyRow]) -> Option<u32> {
    let exact = |r: &StudyRow| r.nodes_max <= r.rounding_floor && r.global_max > r.rounding_floor;
    let tail = rows.iter().rev().take_while(|r| exact(r)).count();
    (tail > 0).then(|| rows[rows.len() - tail].level)
}

impl StudyFooter {
    /// The footer of `rows` with the theory's `predicted` orders and the plot written.
    pub fn new(rows: &[StudyRow], predicted: PredictedOrders, plot: Option<String>) -> Self {
        Self {
            fitted: Fitted::of(rows),
            theory: predicted,
            plot,
            nodes_at_rounding: nodes_at_rounding(rows),
        }
    }
}

impl fmt::Display for StudyFooter {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let v = |x: Option<f64>| x.map(|x| format!("{x:.3}")).unwrap_or_else(|| "-".into());
        let ft = &self.fitted;
        writeln!(
            f,
            "fitted orders (least squares over the levels above rounding, 1000 ε max|u_n|): nodes_max {}, global_max {}, l2 {}",
            v(ft.nodes_max),
            v(ft.global_max),
            v(ft.l2)
        )?;
        if let Some(level) = self.nodes_at_rounding {
            writeln!(
                f,
                "note: the nodal errors are at rounding from level {level} on, where the global ones are not: the discrete equations reproduce this u at the nodes (on the sphere K u = ∫u / 4πR², and for a u such as x*y+z, whose integral is 0, the symmetric meshes' node rule gives 0 exactly too), so no nodal order is measured; an exact solution without that symmetry, such as exp(x), shows it"
            )?;
        }
        writeln!(f, "{}", self.theory.note)?;
        if let Some(p) = &self.plot {
            writeln!(f, "wrote plot to {p}")?;
        }
        Ok(())
    }
}

/// Everything `radcol study` reports.
#[derive(Clone, Debug, Serialize)]
pub struct StudyReport {
    #[serde(flatten)]
    header: StudyHeader,
    rows: Vec<StudyRow>,
    #[serde(flatten)]
    footer: StudyFooter,
}

impl StudyReport {
    /// The whole report.
    pub fn new(header: StudyHeader, rows: Vec<StudyRow>, footer: StudyFooter) -> Self {
        Self {
            header,
            rows,
            footer,
        }
    }
}

impl fmt::Display for StudyReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.header)?;
        for r in &self.rows {
            write!(f, "{}", StudyLine(r))?;
        }
        write!(f, "{}", self.footer)
    }
}
