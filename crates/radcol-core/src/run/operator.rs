//! Which geometric operator a solve stores: the dense N×N matrix, or the
//! hierarchical matrix of `crate::hmatrix` (the same entries, far blocks
//! compressed to a relative tolerance), and why.

use super::size::{available_for, usable, MemoryEstimate, MemoryUse};
use super::{SolveConfig, SolverKind};
use crate::assembly::plan::Unchanged;
use crate::assembly::AssemblyPlan;
use crate::discretization::Discretization;
use crate::error::InputError;
use crate::hmatrix::radiosity::PlanEntries;
use crate::hmatrix::{HMatrix, HPrediction, HStats, RowShare};
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
    /// One sentence: asked for, or the sizes that decided (naming no
    /// setting: [`OperatorDecision::instead`] is the one to change).
    pub reason: String,
    /// When the choice was automatic and the other would fit, the
    /// [`OperatorChoice`] that makes it ([`SolveConfig::operator`]); None
    /// when the choice was asked for, or is the only one that fits.
    pub instead: Option<OperatorChoice>,
    /// The caller asked for this kind ([`OperatorChoice::Dense`] or
    /// [`OperatorChoice::Compressed`]).
    pub asked: bool,
    /// Auto chose dense by the matrix alone: the pipeline compresses
    /// instead when the dense solve's whole peak does not fit.
    #[serde(skip)]
    pub switchable: bool,
    /// The compressed operator's relative error of a product, measured at
    /// [`SAMPLED_ROWS`] rows against their exact entries
    /// (`crate::hmatrix::HMatrix::sampled_error`); None when dense.
    pub sampled_error: Option<f64>,
    /// The compressed operator's bytes as predicted from the geometry
    /// before the plan was built ([`HPrediction::bytes`]); None when dense.
    pub predicted_bytes: Option<f64>,
    /// The same predicted again from the plan, before a block is computed
    /// (`PlanEntries::predict`): occlusion's dense leaves included, so on
    /// occluded scenes it is the closer (low-rank blocks still counted at
    /// rank 1); None when dense.
    pub planned_bytes: Option<f64>,
    /// The same predicted a third time from a sample of the admissible
    /// blocks, built first ([`crate::hmatrix::SampledSize`]): the
    /// prediction that knows ranks; None when dense.
    pub sampled_bytes: Option<crate::hmatrix::SampledSize>,
}

/// Rows of the dense matrix computed to check a compressed operator.
pub const SAMPLED_ROWS: usize = 64;

impl OperatorDecision {
    /// Compressed, because the dense solve's peak was refused with `why`.
    pub(crate) fn compress_instead(&self, why: &InputError) -> Self {
        Self {
            kind: OperatorKind::Compressed,
            reason: format!("the dense solve would not fit ({why}); compressed instead"),
            instead: None,
            asked: false,
            switchable: false,
            sampled_error: None,
            predicted_bytes: None,
            planned_bytes: None,
            sampled_bytes: None,
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
    if let Some(ranks) = cfg.distributed().map(|r| r.size()) {
        return match (cfg.operator, cfg.solver) {
            (OperatorChoice::Dense, _) | (_, SolverKind::Lu) => {
                Err(InputError::NotDistributed { ranks })
            }
            (choice, SolverKind::Gmres) => Ok(OperatorDecision {
                kind: OperatorKind::Compressed,
                reason: format!(
                    "{} over {ranks} ranks, each storing its share of the rows, tolerance {tol:e}",
                    if choice == OperatorChoice::Compressed {
                        "asked for"
                    } else {
                        "spread"
                    }
                ),
                instead: None,
                asked: choice == OperatorChoice::Compressed,
                switchable: false,
                sampled_error: None,
                predicted_bytes: None,
                planned_bytes: None,
                sampled_bytes: None,
            }),
        };
    }
    let decision = |kind, reason: String, instead, asked| {
        Ok(OperatorDecision {
            kind,
            reason,
            instead,
            asked,
            switchable: false,
            sampled_error: None,
            predicted_bytes: None,
            planned_bytes: None,
            sampled_bytes: None,
        })
    };
    match (cfg.operator, cfg.solver) {
        (OperatorChoice::Compressed, SolverKind::Lu) => Err(InputError::CompressedLu),
        (OperatorChoice::Compressed, _) => decision(
            OperatorKind::Compressed,
            format!("asked for, tolerance {tol:e}"),
            None,
            true,
        ),
        (OperatorChoice::Dense, _) => {
            decision(OperatorKind::Dense, "asked for".into(), None, true)
        }
        (OperatorChoice::Auto, SolverKind::Lu) => decision(
            OperatorKind::Dense,
            "LU needs the dense matrix".into(),
            None,
            false,
        ),
        (OperatorChoice::Auto, SolverKind::Gmres) if estimate.fits_gmres => Ok(OperatorDecision {
            kind: OperatorKind::Dense,
            reason: format!(
                "the dense matrix ({}) fits in memory, and assembles faster than the compressed one, which stores less",
                gib(estimate.matrix_bytes)
            ),
            instead: Some(OperatorChoice::Compressed),
            asked: false,
            switchable: true,
            sampled_error: None,
            predicted_bytes: None,
            planned_bytes: None,
            sampled_bytes: None,
        }),
        (OperatorChoice::Auto, SolverKind::Gmres) => decision(
            OperatorKind::Compressed,
            format!(
                "the dense matrix ({}) does not fit in the {} of memory available; compressed to tolerance {tol:e}",
                gib(estimate.matrix_bytes),
                gib(available.unwrap_or(0) as f64)
            ),
            None,
            false,
        ),
    }
}

/// [`decide`] with the memory available now, and, when
/// `cfg.check_memory`, the refusals of what cannot fit before anything is
/// built: the dense matrices ([`MemoryEstimate::check`]), or for the
/// compressed operator the plan's table of pair classes
/// ([`crate::assembly::pair_table_bytes`]; the operator's own size is
/// predicted next, and known once built: [`super::MemoryUse::check`]).
pub(crate) fn decide_now(
    cfg: &SolveConfig,
    unknowns: u64,
    elements: u64,
) -> Result<OperatorDecision, InputError> {
    let available = available_for(cfg);
    let d = decide(cfg, unknowns, available)?;
    if !cfg.check_memory {
        return Ok(d);
    }
    match d.kind {
        OperatorKind::Dense => {
            MemoryEstimate::with_available(unknowns, available).check(cfg.solver)?
        }
        OperatorKind::Compressed => {
            let bytes = crate::assembly::pair_table_bytes(elements as f64);
            if let Some(a) = available.filter(|&a| bytes > usable(a)) {
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

/// Auto keeps a dense choice while what the dense solve still needs takes
/// at most this fraction of the memory available...
const DENSE_COMFORT: f64 = 0.5;

/// ...or while the compressed operator, predicted from the geometry, is not
/// at most this fraction of the dense matrix. The prediction is a lower
/// bound (far blocks at rank 1, occlusion splitting more): 0.29 on the
/// default Cornell box, which builds at 0.80; on the shadowed floor at 39 204
/// unknowns, adaptively refined, 0.04, built to the byte (zero blocks and
/// dense leaves only), 55 s and 3.6 GB against 84 s and 22.8 GB dense.
const LIGHTER: f64 = 1.0 / 8.0;

/// Auto's second look at a dense choice whose solve would take `to_come`
/// bytes (the peak still to come) of the `available`: compressed instead
/// when that is more than [`DENSE_COMFORT`] of them and the compressed
/// operator of `disc`, with its pair table, is predicted at most
/// [`LIGHTER`] of the dense matrix; None keeps dense.
pub(crate) fn lighter_than_dense(
    decision: &OperatorDecision,
    disc: &Discretization,
    cfg: &SolveConfig,
    to_come: f64,
    available: Option<u64>,
) -> Option<OperatorDecision> {
    let available = available? as f64;
    if !decision.switchable || to_come <= DENSE_COMFORT * available {
        return None;
    }
    let dense = super::dense_bytes(disc.len() as u64);
    let pair_table = crate::assembly::pair_table_bytes(disc.mesh().len() as f64);
    let limit = LIGHTER * dense - pair_table;
    let p = crate::hmatrix::radiosity::predict(disc, &cfg.compression, limit.max(0.0));
    if !p.complete || p.bytes() > limit {
        return None;
    }
    let gib = |b: f64| format!("{:.2} GiB", b / (1u64 << 30) as f64);
    Some(OperatorDecision {
        kind: OperatorKind::Compressed,
        reason: format!(
            "the dense solve would take {} of the {} of memory available, and the compressed operator is predicted from the geometry at {} ({:.1} % of the dense matrix); compressed to tolerance {:e}",
            gib(to_come),
            gib(available),
            gib(p.bytes()),
            100.0 * p.bytes() / dense,
            cfg.compression.tol
        ),
        instead: Some(OperatorChoice::Dense),
        asked: false,
        switchable: false,
        sampled_error: None,
        predicted_bytes: Some(p.bytes()),
        planned_bytes: None,
        sampled_bytes: None,
    })
}

/// The compressed operator of `disc` under `cfg`, predicted from the
/// geometry ([`crate::hmatrix::radiosity::predict`], counted no further
/// than four times the memory available); when `cfg.check_memory`, refused where
/// with the plan's table of pair classes it passes nine tenths of the
/// memory available.
///
/// # Errors
/// [`InputError::CompressedWontFit`].
pub(crate) fn predict_compressed(
    disc: &Discretization,
    cfg: &SolveConfig,
) -> Result<HPrediction, InputError> {
    let available = available_for(cfg).filter(|_| cfg.check_memory);
    let pair_table = crate::assembly::pair_table_bytes(disc.mesh().len() as f64);
    let p = crate::hmatrix::radiosity::predict(disc, &cfg.compression, count_limit(available));
    // Spread over ranks, each holds about its share.
    let ranks = cfg.distributed().map_or(1, |r| r.size()) as f64;
    match available {
        Some(a) if pair_table + p.bytes() / ranks > usable(a) => {
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

/// Where a count of the compressed operator's bytes stops: past what fits
/// (nine tenths of `available`), to four times as much, so that a refusal
/// can say how much coarser would fit; no limit where memory is unknown or
/// not checked.
fn count_limit(available: Option<u64>) -> f64 {
    available.map_or(f64::INFINITY, |a| 4.0 * usable(a))
}

/// Builds the compressed operator from `plan`'s integrators (in a solve
/// spread over ranks, `super::share::build_share` builds a rank's share
/// instead), measures its
/// product error at [`SAMPLED_ROWS`] rows into `decision`, and puts its
/// predicted size into `memory`; returns it with its kernel evaluations.
/// Its size is predicted twice before it is built: from the plan before
/// any block is computed (occlusion's dense leaves exactly, low-rank blocks
/// at rank 1), then from a sample of the admissible blocks built first
/// ([`crate::hmatrix::SampledSize`]), which is what `memory` keeps. When
/// `cfg.check_memory`, a peak that does not fit is refused at each of the
/// two, and again once the operator is built.
///
/// # Errors
/// [`InputError::PeakTooLarge`] from either prediction,
/// [`InputError::CompressedTooLarge`] once built.
pub(crate) fn build_compressed(
    plan: &AssemblyPlan,
    cfg: &SolveConfig,
    previous: Option<(&HMatrix, &Unchanged)>,
    decision: &mut OperatorDecision,
    memory: &mut MemoryUse,
) -> Result<(GeometricOperator, u64), InputError> {
    let entries = PlanEntries::new(plan);
    let available = available_for(cfg).filter(|_| cfg.check_memory);
    // Counted over the plan's block tree before any block is computed;
    // not when blocks are taken from the previous step's operator, where
    // that walk would cost more than the blocks built (the sample below
    // still checks before most are).
    if previous.is_none() {
        let planned = entries
            .predict(&cfg.compression, count_limit(available))
            .bytes();
        decision.planned_bytes = Some(planned);
        *memory = memory.with_matrix(Some(planned));
        if cfg.check_memory {
            memory.check(available)?;
        }
    }
    let (h, sampled) = entries.build_checked(&cfg.compression, previous, |s| {
        *memory = memory.with_matrix(Some(s.bytes));
        match cfg.check_memory {
            true => memory.check(available),
            false => Ok(()),
        }
    })?;
    decision.sampled_bytes = Some(sampled);
    decision.sampled_error = Some(h.sampled_error(&entries, SAMPLED_ROWS));
    if cfg.check_memory {
        memory.check_compressed(&h, available_for(cfg))?;
    }
    Ok((GeometricOperator::Compressed(h), entries.evaluations()))
}

/// The geometric operator Gm of a solve (no ρ: every channel, emission and
/// set of reflectances reuses it).
#[derive(Clone, Debug)]
pub enum GeometricOperator {
    /// The dense matrix.
    Dense(DenseMatrix),
    /// The hierarchical matrix.
    Compressed(HMatrix),
    /// This rank's share of the hierarchical matrix's rows, in a solve
    /// spread over ranks: as an operator, it maps this rank's rows of x to
    /// its rows of G x ([`RowShare`]).
    Shared(RowShare),
}

impl GeometricOperator {
    /// The dense matrix, when that is what is stored.
    pub fn dense(&self) -> Option<&DenseMatrix> {
        match self {
            Self::Dense(m) => Some(m),
            Self::Compressed(_) | Self::Shared(_) => None,
        }
    }

    /// The hierarchical matrix, when that is what is stored.
    pub fn compressed(&self) -> Option<&HMatrix> {
        match self {
            Self::Dense(_) | Self::Shared(_) => None,
            Self::Compressed(h) => Some(h),
        }
    }

    /// This rank's share, in a solve spread over ranks.
    pub fn shared(&self) -> Option<&RowShare> {
        match self {
            Self::Shared(s) => Some(s),
            _ => None,
        }
    }

    /// Dense or compressed.
    pub fn kind(&self) -> OperatorKind {
        match self {
            Self::Dense(_) => OperatorKind::Dense,
            Self::Compressed(_) | Self::Shared(_) => OperatorKind::Compressed,
        }
    }

    /// What the hierarchical matrix holds (None when dense; of a share,
    /// this rank's leaves).
    pub fn stats(&self) -> Option<HStats> {
        match self {
            Self::Dense(_) => None,
            Self::Compressed(h) => Some(h.stats()),
            Self::Shared(s) => Some(s.local().stats()),
        }
    }

    /// Bytes of the stored numbers (of a share, this rank's).
    pub fn heap_bytes(&self) -> u64 {
        match self {
            Self::Dense(m) => 8 * (m.nrows() * m.ncols()) as u64,
            Self::Compressed(h) => h.heap_bytes(),
            Self::Shared(s) => s.local().heap_bytes(),
        }
    }
}

impl LinearOperator for GeometricOperator {
    /// Of a share, this rank's rows.
    fn dim(&self) -> usize {
        match self {
            Self::Dense(m) => m.dim(),
            Self::Compressed(h) => h.dim(),
            Self::Shared(s) => s.dim(),
        }
    }

    fn apply(&self, x: &[f64], y: &mut [f64]) {
        match self {
            Self::Dense(m) => m.apply(x, y),
            Self::Compressed(h) => h.apply(x, y),
            Self::Shared(s) => s.apply(x, y),
        }
    }

    fn apply_many(&self, xs: &[&[f64]], ys: &mut [&mut [f64]]) {
        match self {
            Self::Dense(m) => m.apply_many(xs, ys),
            Self::Compressed(h) => h.apply_many(xs, ys),
            Self::Shared(s) => s.apply_many(xs, ys),
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

    /// Under memory pressure auto compresses where the geometry predicts a
    /// far smaller operator (two facing plates: zero within each plate,
    /// rank 1 between them), and nowhere else: not with memory to spare,
    /// not where the prediction is a large part of dense (the Cornell box),
    /// not when dense was asked for.
    #[test]
    #[cfg(feature = "scenes")]
    fn pressure_compresses_only_what_is_much_smaller() {
        use crate::run::discretize;
        let disc = |name: &str, level, max_edge| {
            let scene = crate::scene::builtin(name).unwrap().unwrap();
            let cfg = SolveConfig {
                level,
                max_edge,
                ..Default::default()
            };
            discretize(&scene.problem(), &cfg).unwrap()
        };
        let auto = cfg(OperatorChoice::Auto, SolverKind::Gmres, 1e-8);
        let plates = disc("plates", 3, None);
        let n = plates.len() as u64;
        let dense = decide(&auto, n, Some(u64::MAX)).unwrap();
        assert!(dense.switchable);
        let to_come = crate::run::dense_bytes(n);
        let tight = Some((1.5 * to_come) as u64);
        let c = lighter_than_dense(&dense, &plates, &auto, to_come, tight).unwrap();
        assert_eq!(c.kind, OperatorKind::Compressed);
        assert!(c.predicted_bytes.unwrap() <= LIGHTER * to_come);
        assert!(
            c.reason.contains("predicted from the geometry"),
            "{}",
            c.reason
        );
        let roomy = Some((2.5 * to_come) as u64);
        assert!(lighter_than_dense(&dense, &plates, &auto, to_come, roomy).is_none());
        assert!(lighter_than_dense(&dense, &plates, &auto, to_come, None).is_none());
        let asked = decide(
            &cfg(OperatorChoice::Dense, SolverKind::Gmres, 1e-8),
            n,
            None,
        )
        .unwrap();
        assert!(lighter_than_dense(&asked, &plates, &auto, to_come, tight).is_none());
        let cornell = disc("cornell", 0, Some(120.0));
        let to_come = crate::run::dense_bytes(cornell.len() as u64);
        let tight = Some((1.5 * to_come) as u64);
        assert!(lighter_than_dense(&dense, &cornell, &auto, to_come, tight).is_none());
    }
}
