//! The plan's pair classes of a block, read for the block tree.

use super::consecutive_runs;
use crate::assembly::plan::{ClassTable, PairClass};
use std::ops::{ControlFlow, Range};

/// The plan's pair classes of a block's rows against its column elements
/// (sorted, distinct), read from the class table's runs over each stretch
/// of consecutive column elements only: a cluster's elements are scattered
/// over a span of element numbers many times their count, and reading the
/// runs over the whole span cost most of the block tree's time.
pub(super) struct ClassesAlong<'a> {
    classes: &'a ClassTable,
    /// The stretches of consecutive column elements ([`consecutive_runs`]).
    stretches: Vec<Range<usize>>,
}

impl<'a> ClassesAlong<'a> {
    pub(super) fn new(classes: &'a ClassTable, col_elems: &[usize]) -> Self {
        Self {
            classes,
            stretches: consecutive_runs(col_elems),
        }
    }

    /// Row element `kp`'s classes, in order: `f` gets the positions in the
    /// column elements that share one class, until it breaks.
    pub(super) fn row(
        &self,
        kp: usize,
        mut f: impl FnMut(Range<usize>, PairClass) -> ControlFlow<()>,
    ) -> ControlFlow<()> {
        // Position in the column elements of the stretch's first.
        let mut at = 0;
        for s in &self.stretches {
            for (run, code) in self.classes.runs(kp, s.clone()) {
                let local = at + (run.start - s.start)..at + (run.end - s.start);
                f(local, PairClass::from_code(code))?;
            }
            at += s.len();
        }
        ControlFlow::Continue(())
    }
}

#[cfg(test)]
mod tests {
    /// On the Cornell box (culled, partly visible and far pairs), the
    /// classes read along scattered column elements are each pair's own
    /// class, in order.
    #[test]
    #[cfg(feature = "scenes")]
    fn classes_along_scattered_columns_are_the_pairs_classes() {
        use super::*;
        use crate::assembly::plan::AssemblyPlan;
        use crate::assembly::QuadratureOptions;
        use crate::discretization::Discretization;
        use crate::mesh::Mesh;
        use crate::nodes::NodeSet;
        use crate::scene::builtin;
        use crate::visibility;
        use std::sync::Arc;

        let surface = builtin("cornell").unwrap().unwrap().surface.clone();
        let vis = visibility::analyze(&surface);
        let mesh = Arc::new(Mesh::with_max_edge(surface, 0, 200.0));
        let n = mesh.len();
        let disc = Arc::new(Discretization::new(mesh, NodeSet::new(0, 0.1).unwrap()));
        let plan = AssemblyPlan::new(disc, QuadratureOptions::default(), &vis);
        let classes = plan.classes();
        // Stretches of several lengths with gaps between them.
        let cols: Vec<usize> = (0..n).filter(|k| k % 7 < 3 || k % 11 == 5).collect();
        let along = ClassesAlong::new(classes, &cols);
        let mut seen = [0usize; 4];
        for kp in (0..n).step_by(3) {
            let all = classes.row(kp, 0..n);
            let mut got = Vec::new();
            let flow = along.row(kp, |at, class| {
                got.extend(at.map(|b| (cols[b], class)));
                ControlFlow::Continue(())
            });
            assert!(flow.is_continue());
            let want: Vec<(usize, PairClass)> = cols
                .iter()
                .map(|&k| (k, PairClass::from_code(all[k])))
                .collect();
            assert_eq!(got, want, "row element {kp}");
            for (_, c) in got {
                seen[match c {
                    PairClass::Culled => 0,
                    PairClass::Partial => 1,
                    PairClass::Far(_) => 2,
                    _ => 3,
                }] += 1;
            }
        }
        // Culled, partly visible and far pairs all among them.
        assert!(seen[..3].iter().all(|&s| s > 0), "{seen:?}");
    }
}
