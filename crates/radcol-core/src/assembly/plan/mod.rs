//! The assembly plan: for every (element of the collocation point, element
//! integrated over) pair, which regime and which rule. Computed once, executed
//! by any [`AssemblyBackend`](super::AssemblyBackend); CPU and GPU read the same
//! classes and the same far-rule tables, so they agree to rounding.
//!
//! The f_r collocation points of one element form a *row block* and share a
//! class with each element: far pairs are judged from the block's nearest point,
//! so one rule serves all f_r rows and the element's quadrature data is loaded
//! once per block (it stays in L1 while the f_r rows are filled).
//!
//! By phase: `classify` (pair classes), the occlusion walk
//! ([`crate::visibility`]), `tables` (far-rule data), `execute` (filling a
//! row block) and `kernels` (the vectorised far loop).

mod class_table;
mod classify;
mod execute;
mod kernels;
mod reuse;
mod sample;
mod stored;
mod tables;

pub use class_table::{
    elements_within as pair_table_elements, estimated_bytes as pair_table_bytes,
};
pub use class_table::ClassTable;
pub use classify::PairClass;
pub use reuse::Unchanged;
pub use sample::RowCost;
pub use tables::FarTable;

use super::integrate::{ElementIntegrator, QuadratureOptions, SelfRules, Shortfall, ShortfallLog};
use crate::discretization::Discretization;
use crate::progress::ProgressHandle;
use crate::quadrature::{RuleLadder, MAX_RULE_DEGREE};
use crate::visibility::bounce::Bounce;
use crate::visibility::walk::PartialRow;
use crate::visibility::{self, Occluders, VisibilityAnalysis};
use classify::{bounce_columns, classify_all};
use serde::Serialize;
use std::sync::{Arc, Weak};
use stored::Stored;

/// Pair counts (collocation point × element) and far kernel evaluations.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct PlanStats {
    /// Pairs integrated with one far rule.
    pub pairs_far: u64,
    /// Pairs integrated adaptively.
    pub pairs_near: u64,
    /// Pairs whose collocation point lies on the element (curved surfaces).
    pub pairs_self: u64,
    /// Pairs with G ≡ 0 (coplanar, back-facing), not integrated.
    pub pairs_culled: u64,
    /// Pairs integrated over their clipped visible part (scenes that occlude).
    pub pairs_partial: u64,
    /// Of those, the pairs whose visibility is approximated within the
    /// budget ([`QuadratureOptions::visibility_budget`]).
    pub pairs_approximate: u64,
    /// The largest sum of the approximated pairs' mass bounds at a row
    /// point: the residual moves by at most ρ times this times max |u|.
    pub visibility_bound: f64,
    /// Kernel evaluations of the far pairs: Σ rule points.
    pub far_kernel_evals: u64,
    /// Integrals of the assembly so far that stopped at a depth limit short
    /// of the quadrature tolerance (touching or nearly touching surfaces).
    pub shortfall: Option<Shortfall>,
}

/// Which parts of a row block to fill.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FillMode {
    /// Every entry.
    All,
    /// Only partial, near and self pairs (what a GPU backend leaves to the CPU).
    SpecialOnly,
    /// Only far pairs (for throughput measurements of the far-field kernel).
    FarOnly,
    /// Every entry except those of pairs of two unchanged elements, in a
    /// plan built by [`AssemblyPlan::updating`] (whose entries are the old
    /// matrix's: `Unchanged::copy_blocks`); `All` in other plans.
    NotReused,
}

/// The assembly plan of one discretization.
#[derive(Debug)]
pub struct AssemblyPlan {
    disc: Arc<Discretization>,
    /// The points of the rows, when they are not `disc`'s collocation points
    /// (same mesh): [`AssemblyPlan::at_points`].
    rows: Option<Arc<Discretization>>,
    opts: QuadratureOptions,
    ladder: RuleLadder,
    self_rule: Arc<SelfRules>,
    shortfall: Arc<ShortfallLog>,
    classes: ClassTable,
    tables: Vec<Option<FarTable>>,
    stats: PlanStats,
    visibility: VisibilityAnalysis,
    occluders: Option<Occluders>,
    partial: Vec<PartialRow>,
    progress: Option<ProgressHandle>,
    /// With `unchanged`: the previous plan's columns' and rows'
    /// discretizations.
    unchanged: Option<(Arc<Unchanged>, Arc<Discretization>, Arc<Discretization>)>,
    /// Of a sampled plan ([`AssemblyCost`]): the seconds each row block took
    /// to classify (zero for the rows left out); empty otherwise.
    row_seconds: Vec<f32>,
    /// Of an [`AssemblyPlan::at_points`] plan in a scene that occludes: the
    /// entries of its partly visible pairs, for the plan of a refined mesh
    /// ([`stored`]).
    stored: Option<Arc<Stored>>,
    /// The store of the previous plan this one reused, if it is alive.
    previous_stored: Option<Weak<Stored>>,
    /// Built for some row blocks only (the others culled): a rank's share
    /// of a distributed solve, or a cost sample. Never reused by a later
    /// plan, whose rows may be others.
    only_some_rows: bool,
}

impl AssemblyPlan {
    /// Classifies every pair and builds the far-rule tables that are used.
    /// `visibility` is the surface's analysis ([`visibility::analyze`]): when
    /// it says visibility is needed, partly visible pairs are found and
    /// integrated over their clipped visible parts.
    pub fn new(
        disc: Arc<Discretization>,
        opts: QuadratureOptions,
        visibility: &VisibilityAnalysis,
    ) -> Self {
        Self::with_progress(disc, opts, visibility, None)
    }

    /// [`AssemblyPlan::new`], reporting each classified row block to
    /// `progress` (stage "plan"), and then each filled row block (stage
    /// "assembly" is started by the caller, as [`crate::run::solve`] does).
    pub fn with_progress(
        disc: Arc<Discretization>,
        opts: QuadratureOptions,
        visibility: &VisibilityAnalysis,
        progress: Option<ProgressHandle>,
    ) -> Self {
        Self::build(disc, None, opts, visibility, progress, (None, None), None)
    }

    /// The plan of the rectangular matrix whose rows are the points of
    /// `rows` and whose columns are the basis of `disc` (the same mesh): the
    /// kernel at other points than the collocation nodes, such as the error
    /// estimate's check points, against u_n's own basis. With `previous` (a
    /// plan at the points of the mesh this one refines, and how their
    /// elements relate) the pairs of unchanged elements are reused as in
    /// [`AssemblyPlan::updating`]. Such a plan is executed with
    /// [`AssemblyPlan::fill_block`] (row blocks of `rows`' points per
    /// element); backends assemble square plans only.
    ///
    /// `square`: the plan of `disc`'s own nodes, when there is one; the
    /// candidate occluders of a pair depend on its two elements alone, so
    /// the pairs it searched are not searched again (on the bunny room the
    /// search was half of the check points' plan).
    pub fn at_points(
        disc: Arc<Discretization>,
        rows: Arc<Discretization>,
        opts: QuadratureOptions,
        visibility: &VisibilityAnalysis,
        (previous, square): (
            Option<(&AssemblyPlan, Arc<Unchanged>)>,
            Option<&AssemblyPlan>,
        ),
    ) -> Self {
        assert!(
            Arc::ptr_eq(disc.mesh(), rows.mesh()),
            "rows and columns on one mesh"
        );
        let prev = previous.filter(|(p, u)| {
            p.rows
                .as_ref()
                .is_some_and(|r| same_nodes_where_unchanged(r, &rows, u))
                && p.reusable_by(&disc, &opts, visibility, u)
        });
        let square = square.filter(|s| {
            s.rows.is_none()
                && Arc::ptr_eq(s.disc.mesh(), disc.mesh())
                && s.visibility.needed == visibility.needed
                && s.opts.visibility_budget == opts.visibility_budget
        });
        Self::build(
            disc,
            Some(rows),
            opts,
            visibility,
            None,
            (prev, square),
            None,
        )
    }

    /// Whether a plan for `disc` may take this plan's pairs of `unchanged` elements.
    fn reusable_by(
        &self,
        disc: &Discretization,
        opts: &QuadratureOptions,
        visibility: &VisibilityAnalysis,
        unchanged: &Unchanged,
    ) -> bool {
        !self.only_some_rows
            && self.opts == *opts
            && self.visibility.needed == visibility.needed
            && unchanged.len() == disc.mesh().len()
            && unchanged.old_len() == self.disc.mesh().len()
            && same_nodes_where_unchanged(&self.disc, disc, unchanged)
    }

    /// [`AssemblyPlan::with_progress`] for a mesh refined from `previous`'s
    /// (`unchanged` relates their elements): the pairs of two unchanged
    /// elements take `previous`'s classes and candidates instead of being
    /// classified and walked again. When the node sets or the quadrature
    /// options differ, nothing is reused.
    pub fn updating(
        disc: Arc<Discretization>,
        opts: QuadratureOptions,
        visibility: &VisibilityAnalysis,
        progress: Option<ProgressHandle>,
        previous: &AssemblyPlan,
        unchanged: Arc<Unchanged>,
    ) -> Self {
        let same =
            previous.rows.is_none() && previous.reusable_by(&disc, &opts, visibility, &unchanged);
        let prev = same.then_some((previous, unchanged));
        Self::build(disc, None, opts, visibility, progress, (prev, None), None)
    }

    fn build(
        disc: Arc<Discretization>,
        rows: Option<Arc<Discretization>>,
        opts: QuadratureOptions,
        visibility: &VisibilityAnalysis,
        progress: Option<ProgressHandle>,
        (prev, square): (
            Option<(&AssemblyPlan, Arc<Unchanged>)>,
            Option<&AssemblyPlan>,
        ),
        only: Option<&[bool]>,
    ) -> Self {
        if let Some(p) = &progress {
            p.start("plan", disc.mesh().len() as u64);
        }
        let occluders = visibility
            .needed
            .then(|| Occluders::new(&visibility::base_triangles(disc.mesh().surface())));
        let columns = bounce_columns(&disc, &opts, visibility);
        let bounce = columns.as_deref().map(|columns| Bounce {
            budget: opts.visibility_budget,
            columns,
            spent: &[],
        });
        let (classes, partial, row_seconds) = classify_all(
            &disc,
            rows.as_deref().unwrap_or(&disc),
            (opts.tol, bounce),
            occluders.as_ref(),
            &progress,
            (prev.as_ref().map(|(p, u)| (*p, &**u)), square),
            only,
        );
        let ladder = RuleLadder::new();
        let (mut stats, used) = count(&classes, rows.as_deref().unwrap_or(&disc), &ladder);
        let row_disc = rows.as_deref().unwrap_or(&disc);
        (stats.pairs_approximate, stats.visibility_bound) =
            crate::visibility::walk::totals(&partial, |kp| row_disc.nodes_per(kp));
        let flat = tables::flat_elements(disc.mesh());
        let tables = (0..=MAX_RULE_DEGREE)
            .map(|d| used[d].then(|| tables::build_table(&disc, &ladder, d, flat.as_ref())))
            .collect();
        let stored = (rows.is_some() && occluders.is_some())
            .then(|| Arc::new(Stored::new(disc.mesh().len())));
        Self {
            self_rule: Arc::new(SelfRules::new(opts.self_order)),
            shortfall: Arc::default(),
            disc,
            rows,
            opts,
            ladder,
            classes,
            tables,
            stats,
            visibility: visibility.clone(),
            occluders,
            partial,
            progress,
            previous_stored: prev
                .as_ref()
                .and_then(|(p, _)| p.stored.as_ref().map(Arc::downgrade)),
            unchanged: prev.map(|(p, u)| (u, p.disc.clone(), p.rows().clone())),
            row_seconds,
            stored,
            only_some_rows: only.is_some(),
        }
    }

    /// The plan of the row blocks `only[kp]` alone (the others culled), a
    /// rank's share of a distributed solve: square (`rows` None) or at
    /// other points, taking the pairs `square` searched where it has them
    /// ([`AssemblyPlan::at_points`]). Such a plan is never reused.
    ///
    /// # Panics
    /// When `only` does not have one entry per element.
    pub(crate) fn of_rows(
        disc: Arc<Discretization>,
        (rows, square): (Option<Arc<Discretization>>, Option<&AssemblyPlan>),
        opts: QuadratureOptions,
        visibility: &VisibilityAnalysis,
        progress: Option<ProgressHandle>,
        only: &[bool],
    ) -> Self {
        assert_eq!(only.len(), disc.mesh().len(), "one flag per row block");
        let square = square.filter(|s| {
            rows.is_some()
                && s.rows.is_none()
                && Arc::ptr_eq(s.disc.mesh(), disc.mesh())
                && s.visibility.needed == visibility.needed
                && s.opts.visibility_budget == opts.visibility_budget
        });
        Self::build(disc, rows, opts, visibility, progress, (None, square), Some(only))
    }

    /// The relation to the previous plan's elements, for a plan built by
    /// [`AssemblyPlan::updating`] that reused it.
    pub fn unchanged(&self) -> Option<&Unchanged> {
        self.unchanged.as_ref().map(|(u, _, _)| &**u)
    }

    /// With [`AssemblyPlan::unchanged`]: where each element's unknowns
    /// begin in the previous plan ([`Discretization::offsets`]).
    pub fn previous_offsets(&self) -> Option<&[usize]> {
        self.unchanged.as_ref().map(|(_, d, _)| d.offsets())
    }

    /// With [`AssemblyPlan::unchanged`]: where each element's rows begin in
    /// the previous plan.
    pub fn previous_row_offsets(&self) -> Option<&[usize]> {
        self.unchanged.as_ref().map(|(_, _, r)| r.offsets())
    }

    /// Whether this plan models visibility, and why.
    pub fn visibility(&self) -> &VisibilityAnalysis {
        &self.visibility
    }

    /// The partly visible pairs of row block `kp` whose visible part is
    /// clipped exactly (not approximated): each column element with its
    /// candidate occluders.
    pub(crate) fn clipped_pairs(&self, kp: usize) -> impl Iterator<Item = (usize, &[u32])> + '_ {
        self.partial.get(kp).into_iter().flat_map(|row| {
            (row.elements.iter())
                .map(|&k| k as usize)
                .filter(|&k| !row.is_approx(k))
                .map(|k| (k, row.candidates_of(k)))
        })
    }

    /// The occluders, when the scene can occlude.
    pub fn occluders(&self) -> Option<&Occluders> {
        self.occluders.as_ref()
    }

    /// The discretization.
    pub fn discretization(&self) -> &Arc<Discretization> {
        &self.disc
    }

    /// Quadrature options.
    pub fn options(&self) -> &QuadratureOptions {
        &self.opts
    }

    /// The rule ladder.
    pub fn ladder(&self) -> &RuleLadder {
        &self.ladder
    }

    /// Class codes ([`PairClass::code`]) by (element of the collocation
    /// block, element), stored as runs.
    pub fn classes(&self) -> &ClassTable {
        &self.classes
    }

    /// The class of the pair (row block of element `kp`, element `k`).
    pub fn class(&self, kp: usize, k: usize) -> PairClass {
        PairClass::from_code(self.classes.get(kp, k))
    }

    /// The far table of degree `d`, when some pair uses it.
    pub fn far_table(&self, d: usize) -> Option<&FarTable> {
        self.tables.get(d).and_then(|t| t.as_ref())
    }

    /// Bytes the plan holds on the heap: pair classes, far-rule tables and
    /// the partly visible pairs with their candidate occluders (the last
    /// dominate in occluding scenes: Cornell, r = 1, 8 592 unknowns: about
    /// 0.2 GB against 0.59 GB of matrix).
    pub fn heap_bytes(&self) -> u64 {
        let tables: usize = self.tables.iter().flatten().map(|t| t.heap_bytes()).sum();
        let shared = self.tables.iter().flatten().map(|t| t.shared_bytes()).max();
        let tables = tables + shared.unwrap_or(0);
        let partial: usize = self.partial.iter().map(|r| r.heap_bytes()).sum::<usize>()
            + self.partial.capacity() * std::mem::size_of::<PartialRow>();
        let stored = self.stored.as_ref().map_or(0, |s| s.heap_bytes());
        (self.classes.heap_bytes() + tables + partial + stored) as u64
    }

    /// Pair statistics, with the integrals filled so far that fell short of
    /// the tolerance.
    pub fn stats(&self) -> PlanStats {
        PlanStats {
            shortfall: self.shortfall.summary(),
            ..self.stats
        }
    }

    /// Matrix dimension N (columns; rows too unless the plan is
    /// [`AssemblyPlan::at_points`]).
    pub fn dim(&self) -> usize {
        self.disc.len()
    }

    /// The discretization whose points are the rows: the collocation points
    /// of [`AssemblyPlan::discretization`] unless the plan is
    /// [`AssemblyPlan::at_points`].
    pub fn rows(&self) -> &Arc<Discretization> {
        self.rows.as_ref().unwrap_or(&self.disc)
    }

    /// An integrator with this plan's options over its mesh.
    pub fn integrator(&self) -> ElementIntegrator<'_> {
        ElementIntegrator::with_self_rule(
            self.disc.mesh(),
            &self.ladder,
            self.opts.clone(),
            self.self_rule.clone(),
        )
        .with_shortfall_log(self.shortfall.clone())
    }
}

/// The class codes of every row block, and (with occluders) each block's
/// partly visible pairs with their candidate occluders; with `prev`, the
/// pairs of two unchanged elements are taken from the previous plan.
/// Whether the elements `unchanged` keeps have the same node set (degree
/// and α) in `new` as in `old`: only then are their pairs' classes and
/// entries the same.
fn same_nodes_where_unchanged(
    old: &Discretization,
    new: &Discretization,
    unchanged: &Unchanged,
) -> bool {
    (0..new.mesh().len()).all(|k| {
        unchanged.old(k).is_none_or(|ok| {
            let (a, b) = (old.nodes_of(ok), new.nodes_of(k));
            a.degree() == b.degree() && a.alpha() == b.alpha()
        })
    })
}

/// Pair statistics and the far-rule degrees in use.
fn count(
    classes: &ClassTable,
    rows: &Discretization,
    ladder: &RuleLadder,
) -> (PlanStats, [bool; MAX_RULE_DEGREE + 1]) {
    let mut used = [false; MAX_RULE_DEGREE + 1];
    let mut stats = PlanStats::default();
    let runs = (0..classes.len()).flat_map(|kp| {
        let f = rows.nodes_per(kp);
        classes.runs(kp, 0..classes.width()).map(move |r| (r, f))
    });
    for ((run, c), f) in runs {
        let pairs = (f * run.len()) as u64;
        match PairClass::from_code(c) {
            PairClass::Culled => stats.pairs_culled += pairs,
            PairClass::Near => stats.pairs_near += pairs,
            PairClass::OnElement => stats.pairs_self += pairs,
            PairClass::Partial => stats.pairs_partial += pairs,
            PairClass::Far(d) => {
                let d = d as usize;
                used[d] = true;
                stats.pairs_far += pairs;
                stats.far_kernel_evals += (f * ladder.rule(d).len()) as u64 * run.len() as u64;
            }
        }
    }
    (stats, used)
}
