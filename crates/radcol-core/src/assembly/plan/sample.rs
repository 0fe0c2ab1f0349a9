//! A plan of a few row blocks, to measure what the whole plan and its fill
//! will cost before either is built: the rows left out are culled, so only
//! the sampled rows classify their pairs and walk the occluders.

use super::{AssemblyPlan, PairClass};
use crate::assembly::integrate::QuadratureOptions;
use crate::discretization::Discretization;
use crate::visibility::VisibilityAnalysis;
use std::sync::Arc;

/// What one sampled row block of a plan holds and cost to classify.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RowCost {
    /// Point × element pairs by class: far, near, on the element, culled
    /// (hidden included), partly visible.
    pub far: u64,
    /// Near pairs.
    pub near: u64,
    /// Pairs whose points lie on the element.
    pub on_element: u64,
    /// Culled pairs.
    pub culled: u64,
    /// Partly visible pairs (point × element).
    pub partial: u64,
    /// Candidate occluders over the row's partly visible element pairs.
    pub candidates: u64,
    /// Bytes the row's partly visible pairs and their candidates hold.
    pub partial_bytes: u64,
    /// Seconds this row block took to classify (one thread).
    pub plan_seconds: f64,
}

impl AssemblyPlan {
    /// The plan of the row blocks `only[kp]` (the other rows culled, for
    /// [`AssemblyPlan::row_cost`] and [`AssemblyPlan::fill_block`] on the
    /// sampled rows only). `rows`: the points of the rows when they are not
    /// `disc`'s collocation points ([`AssemblyPlan::at_points`]).
    ///
    /// # Panics
    /// When `only` does not have one entry per element.
    pub fn sampled(
        disc: Arc<Discretization>,
        rows: Option<Arc<Discretization>>,
        opts: QuadratureOptions,
        visibility: &VisibilityAnalysis,
        only: &[bool],
    ) -> Self {
        assert_eq!(only.len(), disc.mesh().len(), "one flag per row block");
        Self::build(disc, rows, opts, visibility, None, (None, None), Some(only))
    }

    /// What the row block of element `kp` holds, and, in a plan built by
    /// [`AssemblyPlan::sampled`], the seconds it took to classify (zero in
    /// other plans).
    pub fn row_cost(&self, kp: usize) -> RowCost {
        let f = self.rows().nodes_per(kp) as u64;
        let mut cost = RowCost {
            plan_seconds: self.row_seconds.get(kp).map_or(0.0, |&t| f64::from(t)),
            ..RowCost::default()
        };
        for (run, c) in self.classes.runs(kp, 0..self.classes.width()) {
            let pairs = f * run.len() as u64;
            match PairClass::from_code(c) {
                PairClass::Culled => cost.culled += pairs,
                PairClass::Near => cost.near += pairs,
                PairClass::OnElement => cost.on_element += pairs,
                PairClass::Partial => cost.partial += pairs,
                PairClass::Far(_) => cost.far += pairs,
            }
        }
        if let Some(p) = self.partial.get(kp) {
            cost.candidates = p
                .elements
                .iter()
                .map(|&k| p.candidates_of(k as usize).len() as u64)
                .sum();
            cost.partial_bytes = p.heap_bytes() as u64;
        }
        cost
    }
}
