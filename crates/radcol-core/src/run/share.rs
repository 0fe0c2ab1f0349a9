//! A solve spread over ranks: this rank's share of the compressed
//! operator, laid out from the geometry and built from its own plan.

use super::operator::{GeometricOperator, OperatorDecision, SAMPLED_ROWS};
use super::size::{available_for, MemoryUse};
use super::SolveConfig;
use crate::assembly::plan::AssemblyPlan;
use crate::discretization::Discretization;
use crate::error::InputError;
use crate::hmatrix::radiosity::PlanEntries;
use crate::hmatrix::RowShare;
use crate::visibility::VisibilityAnalysis;
use std::sync::Arc;

/// [`super::operator::build_compressed`] spread over `ranks`: this rank's share of the rows
/// ([`RowShare`]), its size predicted from its own sample and checked
/// against this process's memory; the product error measured over the
/// whole matrix's sample rows (each rank checks those it holds).
pub(super) fn build_share(
    entries: &PlanEntries<'_>,
    cfg: &SolveConfig,
    share: (
        std::sync::Arc<dyn crate::ranks::Ranks>,
        std::ops::Range<usize>,
    ),
    decision: &mut OperatorDecision,
    memory: &mut MemoryUse,
) -> Result<(GeometricOperator, u64), InputError> {
    let available = available_for(cfg).filter(|_| cfg.check_memory);
    let (rows, cols) = entries.boxes();
    let (share, sampled) = RowShare::build(&rows, &cols, entries, &cfg.compression, share, |s| {
        *memory = memory.with_matrix(Some(s.bytes));
        match cfg.check_memory {
            true => memory.check(available),
            false => Ok(()),
        }
    })?;
    if share.counts().contains(&0) {
        return Err(InputError::TooFewRows {
            unknowns: share.local().stats().shape.0,
            ranks: share.counts().len(),
        });
    }
    decision.sampled_bytes = Some(sampled);
    decision.sampled_error = Some(share.sampled_error(entries, SAMPLED_ROWS));
    if cfg.check_memory {
        memory.check_compressed(share.local(), available_for(cfg))?;
    }
    Ok((GeometricOperator::Shared(share), entries.evaluations()))
}

/// In a solve spread over ranks, this rank's process's CPU seconds so far,
/// when the rank is a process of its own (`Ranks::owns_its_process`).
pub(super) fn own_cpu_seconds(cfg: &SolveConfig) -> Option<f64> {
    cfg.distributed()
        .filter(|r| r.owns_its_process())
        .and_then(|_| crate::ranks::cpu_seconds())
}

/// What every rank held and spent, gathered from each rank's own (every
/// rank calls it together): `share`, its assembly's start (the instant and
/// [`own_cpu_seconds`] then), its seconds and its kernel evaluations.
pub(super) fn figures(
    share: &RowShare,
    (began, cpu): (std::time::Instant, Option<f64>),
    (assembly_s, kernel_evals): (f64, u64),
) -> super::RanksReport {
    let (end, end_cpu) = share.built();
    let mine = super::RankFigures {
        rows: share.rows().len(),
        stored_bytes: share.local().heap_bytes(),
        assembly_s,
        work_s: end.duration_since(began).as_secs_f64(),
        work_cpu_s: cpu.zip(end_cpu).map(|(a, b)| b - a),
        kernel_evals,
        products_s: share.product_seconds(),
        gathers_s: share.gather_seconds(),
        communication_s: share.ranks().seconds(),
    };
    super::RanksReport::gather(share.ranks(), mine)
}

/// This rank's share of `disc`'s compressed operator in a solve spread
/// over `ranks`, decided before any plan: the rows it holds and the
/// elements its plan classifies ([`crate::hmatrix::radiosity::layout`]),
/// balancing the geometry's predicted cost plus the visibility work of
/// the rows, sampled ([`visibility_cost`]).
pub(crate) fn share_layout(
    disc: &Arc<Discretization>,
    cfg: &SolveConfig,
    visibility: &VisibilityAnalysis,
    ranks: &dyn crate::ranks::Ranks,
) -> crate::hmatrix::share::Layout {
    let extra = visibility_cost(disc, cfg, visibility, ranks);
    crate::hmatrix::radiosity::layout(disc, &cfg.compression, &extra, (ranks.rank(), ranks.size()))
}

/// One element in this many is sampled for [`visibility_cost`]: its rows'
/// plan costs that share of the whole plan, spread over the ranks.
const SAMPLE_EVERY: usize = 32;

/// What the visibility work of a partly visible pair (point × element)
/// counts in the cut's cost, in entries of the geometry's prediction: its
/// occluder walk, its clipped integral, and its entries stored densely
/// where the geometry predicted a low-rank block. Fitted on the Cornell
/// box, each rank's CPU seconds of assembly against its rows' predicted
/// entries and partly visible pairs over 2, 3 and 4 ranks and several
/// cuts, least squares: 38 at 10 320 unknowns, 17 at 41 280 (residual
/// 5 % and 3 % rms, against 12 % and 11 % for the geometry alone; the
/// candidate occluders' count explained nothing more). Between the two.
const PARTIAL_PAIR: f64 = 24.0;

/// Per row (unknown): the visibility work a plan will do for it, in the
/// cut's units (entries, [`PARTIAL_PAIR`] per partly visible pair), the
/// same on every rank. Every
/// [`SAMPLE_EVERY`]-th element in mesh order is planned alone
/// (`AssemblyPlan::sampled`; the ranks share the samples and gather their
/// counts, deterministic, where timings would differ between ranks); its
/// partly visible pairs per row stand for it and the
/// elements after it up to the next sample (neighbours in mesh order lie
/// together). Nothing where the scene cannot occlude.
fn visibility_cost(
    disc: &Arc<Discretization>,
    cfg: &SolveConfig,
    visibility: &VisibilityAnalysis,
    ranks: &dyn crate::ranks::Ranks,
) -> Vec<f64> {
    let (n, elements) = (disc.len(), disc.mesh().len());
    if !visibility.needed {
        return vec![0.0; n];
    }
    let samples: Vec<usize> = (0..elements).step_by(SAMPLE_EVERY).collect();
    let (rank, size) = (ranks.rank(), ranks.size());
    let mine: Vec<usize> = samples.iter().copied().skip(rank).step_by(size).collect();
    let mut only = vec![false; elements];
    mine.iter().for_each(|&k| only[k] = true);
    let plan = AssemblyPlan::sampled(disc.clone(), None, cfg.quad.clone(), visibility, &only);
    let local: Vec<f64> = mine
        .iter()
        .map(|&k| PARTIAL_PAIR * plan.row_cost(k).partial as f64 / disc.nodes_per(k) as f64)
        .collect();
    // Rank p holds samples p, p + size, …: gathered in rank order, then
    // put back in sample order.
    let counts: Vec<usize> = (0..size)
        .map(|p| samples.len().saturating_sub(p).div_ceil(size))
        .collect();
    let mut gathered = vec![0.0; samples.len()];
    ranks.gather_all(&local, &counts, &mut gathered);
    let mut per_sample = vec![0.0; samples.len()];
    let mut at = 0;
    for (p, &c) in counts.iter().enumerate() {
        for j in 0..c {
            per_sample[p + j * size] = gathered[at + j];
        }
        at += c;
    }
    let mut cost = vec![0.0; n];
    for k in 0..elements {
        let per_row = per_sample[k / SAMPLE_EVERY];
        cost[disc.range(k)].iter_mut().for_each(|c| *c = per_row);
    }
    cost
}
