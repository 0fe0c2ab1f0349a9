//! Which geometric operator a solve stores: the dense N×N matrix, or the
//! hierarchical matrix of [`crate::hmatrix`] (the same entries, far blocks
//! compressed to a relative tolerance), and why.

use super::size::{available_memory, MemoryEstimate, MemoryUse};
use super::{SolveConfig, SolverKind};
use crate::assembly::AssemblyPlan;
use crate::discretization::Discretization;
use crate::error::InputError;
use crate::hmatrix::radiosity::PlanEntries;
use crate::hmatrix::{HMatrix, HPrediction, HStats};
use crate::matrix::DenseMatrix;
use crate::solve::LinearOperator;
use serde::Serialize;

/// What the user asks for.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum OperatorChoice {
    /// Dense while its matrices fit in memory (or LU is asked for), else
    /// compressed.
    #[default]
    Auto,
    /// The dense matrix, refused when it does not fit.
    Dense,
    /// The hierarchical matrix (GMRES only).
    Compressed,
}

/// What a solve stores.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum OperatorKind {
    /// 8 N² bytes, filled by the assembly backend.
    Dense,
    /// A hierarchical matrix, sampled from the assembly plan on the CPU.
    Compressed,
}

/// The operator chosen for a solve, and why (for the report).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct OperatorDecision {
    /// Dense or compressed.
    pub kind: OperatorKind,
    /// One sentence: asked for, or the sizes that decided.
    pub reason: String,
    /// Auto chose dense by the matrix alone: the pipeline compresses
    /// instead when the dense solve's whole peak does not fit.
    #[serde(skip)]
    pub switchable: bool,
    /// The compressed operator's relative error of a product, measured at
    /// [`SAMPLED_ROWS`] rows against their exact entries
    /// ([`crate::hmatrix::HMatrix::sampled_error`]); None when dense.
    pub sampled_error: Option<f64>,
    /// The compressed operator's bytes as predicted from the geometry
    /// before it was built ([`HPrediction::bytes`]); None when dense.
    pub predicted_bytes: Option<f64>,
}

/// Rows of the dense matrix computed to check a compressed operator.
pub const SAMPLED_ROWS: usize = 64;

impl OperatorDecision {
    /// Compressed, because the dense solve's peak was refused with `why`.
    pub(crate) fn compress_instead(&self, why: &InputError) -> Self {
        Self {
            kind: OperatorKind::Compressed,
            reason: format!("the dense solve would not fit ({why}); compressed instead"),
            switchable: false,
            sampled_error: None,
            predicted_bytes: None,
        }
    }
}

/// Decides dense or compressed for N `unknowns` under `cfg` with
/// `available` bytes of memory (None: unknown, taken to fit).
///
/// # Errors
/// [`InputError::CompressionTolerance`] for a tolerance outside (0, 1);
/// [`InputError::CompressedLu`] when LU is asked for with a compressed
/// operator (LU needs every entry).
pub fn decide(
    cfg: &SolveConfig,
    unknowns: u64,
    available: Option<u64>,
) -> Result<OperatorDecision, InputError> {
    let tol = cfg.compression.tol;
    if !(tol > 0.0 && tol < 1.0) {
        return Err(InputError::CompressionTolerance { value: tol });
    }
    let estimate = MemoryEstimate::with_available(unknowns, available);
    let gib = |b: f64| format!("{:.2} GiB", b / (1u64 << 30) as f64);
    let decision = |kind, reason: String| {
        Ok(OperatorDecision {
            kind,
            reason,
            switchable: false,
            sampled_error: None,
            predicted_bytes: None,
        })
    };
    match (cfg.operator, cfg.solver) {
        (OperatorChoice::Compressed, SolverKind::Lu) => Err(InputError::CompressedLu),
        (OperatorChoice::Compressed, _) => decision(
            OperatorKind::Compressed,
            format!("asked for (--operator compressed), tolerance {tol:e}"),
        ),
        (OperatorChoice::Dense, _) => {
            decision(OperatorKind::Dense, "asked for (--operator dense)".into())
        }
        (OperatorChoice::Auto, SolverKind::Lu) => decision(
            OperatorKind::Dense,
            "LU needs the dense matrix (--solver lu)".into(),
        ),
        (OperatorChoice::Auto, SolverKind::Gmres) if estimate.fits_gmres => Ok(OperatorDecision {
            kind: OperatorKind::Dense,
            reason: format!(
                "the dense matrix ({}) fits in memory, and assembles faster than the compressed one; --operator compressed stores less",
                gib(estimate.matrix_bytes)
            ),
            switchable: true,
            sampled_error: None,
            predicted_bytes: None,
        }),
        (OperatorChoice::Auto, SolverKind::Gmres) => decision(
            OperatorKind::Compressed,
            format!(
                "the dense matrix ({}) does not fit in the {} of memory available; compressed to tolerance {tol:e}",
                gib(estimate.matrix_bytes),
                gib(available.unwrap_or(0) as f64)
            ),
        ),
    }
}

/// [`decide`] with the memory available now, and, when
/// `cfg.check_memory`, the refusals of what cannot fit before anything is
/// built: the dense matrices ([`MemoryEstimate::check`]), or for the
/// compressed operator the plan's n² bytes of pair classes (its own size
/// is known once built: [`super::MemoryUse::check`]).
pub(crate) fn decide_now(
    cfg: &SolveConfig,
    unknowns: u64,
    elements: u64,
) -> Result<OperatorDecision, InputError> {
    let available = available_memory();
    let d = decide(cfg, unknowns, available)?;
    if !cfg.check_memory {
        return Ok(d);
    }
    match d.kind {
        OperatorKind::Dense => {
            MemoryEstimate::with_available(unknowns, available).check(cfg.solver)?
        }
        OperatorKind::Compressed => {
            let bytes = (elements as f64).powi(2);
            if let Some(a) = available.filter(|&a| bytes > (a / 10 * 9) as f64) {
                return Err(InputError::PairTableTooLarge {
                    elements,
                    bytes,
                    available: a,
                });
            }
        }
    }
    Ok(d)
}

/// The compressed operator of `disc` under `cfg`, predicted from the
/// geometry ([`crate::hmatrix::radiosity::predict`], counted no further
/// than four times the memory available); when `cfg.check_memory`, refused where
/// with the plan's n² bytes of pair classes it passes nine tenths of the
/// memory available.
///
/// # Errors
/// [`InputError::CompressedWontFit`].
pub(crate) fn predict_compressed(
    disc: &Discretization,
    cfg: &SolveConfig,
) -> Result<HPrediction, InputError> {
    let available = available_memory().filter(|_| cfg.check_memory);
    let pair_table = (disc.mesh().len() as f64).powi(2);
    // Counted on past what fits, to four times as much, so that a refusal
    // can say how much coarser would fit.
    let limit = available.map_or(f64::INFINITY, |a| 4.0 * (a / 10 * 9) as f64);
    let p = crate::hmatrix::radiosity::predict(disc, &cfg.compression, limit);
    match available {
        Some(a) if pair_table + p.bytes() > (a / 10 * 9) as f64 => {
            Err(InputError::CompressedWontFit {
                unknowns: disc.len() as u64,
                operator: p.bytes(),
                near: p.near_bytes,
                complete: p.complete,
                pair_table,
                available: a,
            })
        }
        _ => Ok(p),
    }
}

/// Builds the compressed operator from `plan`'s integrators, measures its
/// product error at [`SAMPLED_ROWS`] rows into `decision`, and puts its
/// size into `memory` (refused, when `cfg.check_memory`, where the rest of
/// the peak no longer fits); returns it with its kernel evaluations.
///
/// # Errors
/// [`InputError::CompressedTooLarge`].
pub(crate) fn build_compressed(
    plan: &AssemblyPlan,
    cfg: &SolveConfig,
    decision: &mut OperatorDecision,
    memory: &mut MemoryUse,
) -> Result<(HMatrix, u64), InputError> {
    let entries = PlanEntries::new(plan);
    let h = entries.build(&cfg.compression);
    decision.sampled_error = Some(h.sampled_error(&entries, SAMPLED_ROWS));
    // Not predicted again: the resident set now holds the operator.
    *memory = memory.with_matrix(Some(h.heap_bytes() as f64));
    if cfg.check_memory {
        memory.check_compressed(&h, available_memory())?;
    }
    Ok((h, entries.evaluations()))
}

/// The geometric operator Gm of a solve (no ρ: every channel, emission and
/// set of reflectances reuses it).
#[derive(Clone, Debug)]
pub enum GeometricOperator {
    /// The dense matrix.
    Dense(DenseMatrix),
    /// The hierarchical matrix.
    Compressed(HMatrix),
}

impl GeometricOperator {
    /// The dense matrix, when that is what is stored.
    pub fn dense(&self) -> Option<&DenseMatrix> {
        match self {
            Self::Dense(m) => Some(m),
            Self::Compressed(_) => None,
        }
    }

    /// The hierarchical matrix, when that is what is stored.
    pub fn compressed(&self) -> Option<&HMatrix> {
        match self {
            Self::Dense(_) => None,
            Self::Compressed(h) => Some(h),
        }
    }

    /// Dense or compressed.
    pub fn kind(&self) -> OperatorKind {
        match self {
            Self::Dense(_) => OperatorKind::Dense,
            Self::Compressed(_) => OperatorKind::Compressed,
        }
    }

    /// What the hierarchical matrix holds (None when dense).
    pub fn stats(&self) -> Option<HStats> {
        self.compressed().map(HMatrix::stats)
    }

    /// Bytes of the stored numbers.
    pub fn heap_bytes(&self) -> u64 {
        match self {
            Self::Dense(m) => 8 * (m.nrows() * m.ncols()) as u64,
            Self::Compressed(h) => h.heap_bytes(),
        }
    }
}

impl LinearOperator for GeometricOperator {
    fn dim(&self) -> usize {
        match self {
            Self::Dense(m) => m.dim(),
            Self::Compressed(h) => h.dim(),
        }
    }

    fn apply(&self, x: &[f64], y: &mut [f64]) {
        match self {
            Self::Dense(m) => m.apply(x, y),
            Self::Compressed(h) => h.apply(x, y),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hmatrix::HOptions;

    fn cfg(operator: OperatorChoice, solver: SolverKind, tol: f64) -> SolveConfig {
        SolveConfig {
            operator,
            solver,
            compression: HOptions {
                tol,
                ..Default::default()
            },
            ..Default::default()
        }
    }

    /// Auto is dense while 8 N² bytes fit in 0.9 of the memory, else
    /// compressed; LU is dense or refused; a bad tolerance is refused.
    #[test]
    fn the_choice_follows_memory_and_solver() {
        use OperatorChoice::*;
        // N = 10 000: 0.8 GB of matrix.
        let auto = cfg(Auto, SolverKind::Gmres, 1e-8);
        let d = decide(&auto, 10_000, Some(1_000_000_000)).unwrap();
        assert_eq!(d.kind, OperatorKind::Dense, "{}", d.reason);
        let c = decide(&auto, 10_000, Some(800_000_000)).unwrap();
        assert_eq!(c.kind, OperatorKind::Compressed);
        assert!(c.reason.contains("does not fit"), "{}", c.reason);
        assert_eq!(
            decide(&auto, 10_000, None).unwrap().kind,
            OperatorKind::Dense
        );
        let lu = cfg(Auto, SolverKind::Lu, 1e-8);
        assert_eq!(
            decide(&lu, 10_000, Some(1)).unwrap().kind,
            OperatorKind::Dense
        );
        let clu = cfg(Compressed, SolverKind::Lu, 1e-8);
        assert!(matches!(
            decide(&clu, 10, None),
            Err(InputError::CompressedLu)
        ));
        let dense = cfg(Dense, SolverKind::Gmres, 1e-8);
        assert_eq!(
            decide(&dense, 10_000, Some(1)).unwrap().kind,
            OperatorKind::Dense
        );
        for bad in [0.0, -1e-6, 1.0, f64::NAN, f64::INFINITY] {
            let err = decide(&cfg(Compressed, SolverKind::Gmres, bad), 10, None).unwrap_err();
            assert!(err.to_string().contains("compression tolerance"), "{err}");
        }
    }
}
