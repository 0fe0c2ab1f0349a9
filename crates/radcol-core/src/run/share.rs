//! A solve spread over ranks: this rank's share of the compressed
//! operator, laid out from the geometry and built from its own plan.

use super::operator::{GeometricOperator, OperatorDecision, SAMPLED_ROWS};
use super::size::{available_for, MemoryUse};
use super::SolveConfig;
use crate::discretization::Discretization;
use crate::error::InputError;
use crate::hmatrix::radiosity::PlanEntries;
use crate::hmatrix::RowShare;

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

/// This rank's share of `disc`'s compressed operator in a solve spread
/// over `ranks`, from the geometry alone: the rows it holds and the
/// elements its plan classifies ([`crate::hmatrix::radiosity::layout`]).
pub(crate) fn share_layout(
    disc: &Discretization,
    cfg: &SolveConfig,
    ranks: &dyn crate::ranks::Ranks,
) -> crate::hmatrix::share::Layout {
    crate::hmatrix::radiosity::layout(disc, &cfg.compression, (ranks.rank(), ranks.size()))
}
