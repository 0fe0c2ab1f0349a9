//! The operator and memory lines of `radcol solve`: the geometric operator
//! (dense or compressed, why, and what compression kept), and the memory
//! predicted and measured.

use radcol_core::run::SAMPLED_ROWS;
use radcol_core::run::{
    HStats, MemoryUse, OperatorChoice, OperatorDecision, OperatorKind, RanksReport, SampledSize,
    SolveOutcome,
};
use serde::Serialize;
use std::fmt;

/// The geometric operator a solve used.
#[derive(Clone, Debug, Serialize)]
pub struct OperatorReport {
    kind: OperatorKind,
    /// Why this kind (asked for, or what memory allowed).
    reason: String,
    /// Bytes of the stored numbers.
    bytes: u64,
    /// What the compressed operator holds; None when dense.
    compression: Option<HStats>,
    /// Its relative product error at sampled rows; None when dense.
    sampled_error: Option<f64>,
    /// Its bytes as predicted from the geometry before it was built.
    predicted_bytes: Option<f64>,
    /// Its bytes as predicted from the plan (occlusion included) before a
    /// block was computed.
    planned_bytes: Option<f64>,
    /// Its size as predicted from a sample of its admissible blocks, built
    /// first, before the others were computed.
    sampled_size: Option<SampledSize>,
    /// Under mpirun: how many ranks ran, and what each held and spent
    /// (`bytes` and `compression` above are rank 0's share).
    #[serde(skip_serializing_if = "Option::is_none")]
    ranks: Option<RanksReport>,
}

impl OperatorReport {
    /// The operator of `out`.
    pub fn new(out: &SolveOutcome) -> Self {
        Self {
            kind: out.operator.kind(),
            reason: with_flag(&out.operator_decision),
            bytes: out.operator.heap_bytes(),
            compression: out.operator.stats(),
            sampled_error: out.operator_decision.sampled_error,
            predicted_bytes: out.operator_decision.predicted_bytes,
            planned_bytes: out.operator_decision.planned_bytes,
            sampled_size: out.operator_decision.sampled_bytes,
            ranks: out.ranks.clone(),
        }
    }
}

/// The decision's reason, with the flag that asks for the other operator
/// when the choice was automatic, or the one that asked for it.
fn with_flag(d: &OperatorDecision) -> String {
    let name = match d.kind {
        OperatorKind::Dense => "dense",
        OperatorKind::Compressed => "compressed",
    };
    match d.instead {
        Some(OperatorChoice::Compressed) => format!("{} (--operator compressed)", d.reason),
        Some(_) => format!("{} (--operator dense keeps the dense matrix)", d.reason),
        None if d.asked => format!("{} (--operator {name})", d.reason),
        None => d.reason.clone(),
    }
}

fn gb(bytes: f64) -> String {
    format!("{:.3} GB", bytes / 1e9)
}

/// One line per rank of a distributed solve: rows, bytes, and seconds of
/// assembly, block products and communication.
fn fmt_ranks(f: &mut fmt::Formatter<'_>, r: &RanksReport) -> fmt::Result {
    let total: u64 = r.per_rank.iter().map(|p| p.stored_bytes).sum();
    writeln!(
        f,
        "  ranks       {} (the operator line is rank 0's share; all ranks together store {})",
        r.size,
        gb(total as f64)
    )?;
    for (k, p) in r.per_rank.iter().enumerate() {
        let product = p.products_s + p.gathers_s;
        writeln!(
            f,
            "    rank {k}    {} rows, {} ({:.1} %), {:.3e} kernel evaluations, assembly {:.2} s (its own work {:.2} s{}), products {:.2} s of which gathering x {:.2} s ({:.0} %), all communication {:.2} s (waiting for other ranks included)",
            p.rows,
            gb(p.stored_bytes as f64),
            100.0 * p.stored_bytes as f64 / (total as f64).max(1.0),
            p.kernel_evals as f64,
            p.assembly_s,
            p.work_s,
            p.work_cpu_s.map_or(String::new(), |c| format!(", {c:.2} s of CPU")),
            product,
            p.gathers_s,
            if product > 0.0 { 100.0 * p.gathers_s / product } else { 0.0 },
            p.communication_s,
        )?;
    }
    Ok(())
}

impl fmt::Display for OperatorReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.fmt_operator(f)?;
        match &self.ranks {
            Some(r) => fmt_ranks(f, r),
            None => Ok(()),
        }
    }
}

impl OperatorReport {
    fn fmt_operator(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.compression {
            None => writeln!(
                f,
                "  operator    dense, {}: {}",
                gb(self.bytes as f64),
                self.reason
            ),
            Some(s) => writeln!(
                f,
                "  operator    compressed, {} ({:.2} % of dense), product error {:.1e} at {SAMPLED_ROWS} rows: {} low-rank blocks (max rank {}{}), {} dense, {} zero (shadowed){}; {}; predicted {} from the geometry, {}, {}; {}",
                gb(self.bytes as f64),
                100.0 * s.compression(),
                self.sampled_error.unwrap_or(f64::NAN),
                s.low_rank_blocks,
                s.max_rank,
                if s.low_rank_failed > 0 {
                    format!(", {} left dense", s.low_rank_failed)
                } else {
                    String::new()
                },
                s.dense_blocks,
                s.zero_blocks,
                if s.reused_blocks > 0 {
                    format!(", {} taken from the previous step's", s.reused_blocks)
                } else {
                    String::new()
                },
                stored_shares(s),
                gb(self.predicted_bytes.unwrap_or(f64::NAN)),
                match self.planned_bytes {
                    Some(b) => format!("{} from the plan", gb(b)),
                    None if self.ranks.is_some() => {
                        "not from the plan (each rank predicts its share from its sample)".into()
                    }
                    None => "not from the plan (taken from the previous step)".into(),
                },
                match &self.sampled_size {
                    Some(z) => format!(
                        "{} from {} of its {} low-rank candidates built first ({:.1} % of their entries)",
                        gb(z.bytes),
                        z.sampled_blocks,
                        z.admissible_blocks,
                        100.0 * z.sampled_entries
                    ),
                    None => "no sample".into(),
                },
                self.reason
            ),
        }
    }
}

/// Where the compressed operator's numbers are, as shares of all it stores.
fn stored_shares(s: &HStats) -> String {
    let by = &s.stored_by_kind;
    let pct = |x: u64| 100.0 * x as f64 / (s.stored as f64).max(1.0);
    format!(
        "numbers stored {:.0} % in low-rank blocks, {:.0} % in admissible blocks left dense, {:.0} % in blocks split at shadows or tangent planes, {:.0} % near the diagonal",
        pct(by.low_rank),
        pct(by.left_dense),
        pct(by.split),
        pct(by.near)
    )
}

/// The memory line: the measured peak against the prediction, when the
/// platform measures it.
pub fn fmt_memory(f: &mut fmt::Formatter<'_>, m: &MemoryUse) -> fmt::Result {
    let Some(peak) = m.measured_peak_bytes else {
        return Ok(());
    };
    writeln!(
        f,
        "  memory      peak {} measured, {} predicted after planning (resident {} + operator {} + max(solver {}, estimate {}))",
        gb(peak),
        gb(m.predicted_peak_bytes),
        gb(m.after_plan_bytes),
        gb(m.matrix_bytes),
        gb(m.solver_bytes),
        gb(m.estimate_bytes)
    )
}
