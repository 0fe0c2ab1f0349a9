//! `radcol nodes`: the node set of one degree, its weights and α0.

use super::alpha_text;
use crate::setup::Alpha;
use radcol_core::run::NodeSet;
use radcol_core::study::AlphaRoot;
use serde::Serialize;
use std::fmt;

/// One node.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Node {
    i: usize,
    j: usize,
    s: f64,
    t: f64,
    weight: f64,
}

/// Everything `radcol nodes` reports.
#[derive(Clone, Debug, Serialize)]
pub struct NodesReport {
    command: &'static str,
    degree: usize,
    alpha: f64,
    alpha_auto: bool,
    nodes: Vec<Node>,
    weight_sum: f64,
    precision: usize,
    lebesgue_constant: f64,
    alpha0: Option<f64>,
    alpha0_reason: String,
    best_alpha: f64,
    best_defect: f64,
    precision_at_best: usize,
    rejected_roots: Vec<(f64, f64)>,
    roots: Vec<AlphaRoot>,
}

impl NodesReport {
    /// The report of `set`, built with `alpha`.
    pub fn new(set: &NodeSet, alpha: &Alpha) -> Self {
        let a0 = &alpha.a0;
        Self {
            command: "nodes",
            degree: set.degree(),
            alpha: alpha.value,
            alpha_auto: alpha.auto,
            nodes: set
                .indices()
                .iter()
                .zip(set.points())
                .zip(set.weights())
                .map(|((&(i, j), &[s, t]), &weight)| Node { i, j, s, t, weight })
                .collect(),
            weight_sum: set.weights().iter().sum(),
            precision: set.precision(),
            lebesgue_constant: set.lebesgue_constant(),
            alpha0: a0.alpha0,
            alpha0_reason: a0.reason.clone(),
            best_alpha: a0.best_alpha,
            best_defect: a0.best_defect,
            precision_at_best: a0.precision_at_best,
            rejected_roots: a0.rejected_roots.clone(),
            roots: a0.roots.clone(),
        }
    }
}

impl fmt::Display for NodesReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let r = self.degree;
        writeln!(
            f,
            "radcol nodes: r = {r}, {}, {} nodes on the unit triangle",
            alpha_text(self.alpha, self.alpha_auto, r),
            self.nodes.len()
        )?;
        writeln!(
            f,
            "{:>3} {:>3} {:>22} {:>22} {:>22}",
            "i", "j", "s", "t", "weight"
        )?;
        for n in &self.nodes {
            writeln!(
                f,
                "{:>3} {:>3} {:>22.17} {:>22.17} {:>22.17}",
                n.i, n.j, n.s, n.t, n.weight
            )?;
        }
        writeln!(
            f,
            "sum of weights {:.17} (area of the unit triangle: 0.5)",
            self.weight_sum
        )?;
        writeln!(f, "degree of precision {}", self.precision)?;
        writeln!(
            f,
            "Lebesgue constant {:.6} (max over the triangle of Σ|l_j|: interpolation amplifies data by at most this)",
            self.lebesgue_constant
        )?;
        match self.alpha0 {
            Some(a) => writeln!(f, "alpha0 = {a:.17}")?,
            None => writeln!(
                f,
                "alpha0: none (best α = {:.17}, relative defect {:.3e})",
                self.best_alpha, self.best_defect
            )?,
        }
        writeln!(f, "  {}", self.alpha0_reason)
    }
}
