//! What an assembly and its error estimate will cost, predicted before
//! either is built from a sample of their row blocks: pair counts, the
//! occluder candidates of the partly visible pairs and the memory they hold,
//! and the seconds to classify and to fill, all extrapolated to every row
//! block with a standard error. In a scene whose visibility is the cost (a
//! scanned mesh of thousands of triangles), this is what its triangle count
//! costs, found in about a hundredth of the assembly's time.

use super::size::usable;
use crate::assembly::plan::RowCost;
use crate::assembly::{AssemblyPlan, FillMode, QuadratureOptions};
use crate::discretization::Discretization;
use crate::error::InputError;
use crate::estimate::{check_discretization, ESTIMATE_QUAD_TOL};
use crate::visibility::VisibilityAnalysis;
use serde::Serialize;
use std::sync::Arc;
use std::time::Instant;

/// Row blocks a prediction samples by default: enough for a standard error
/// of a few per cent on the bunny rooms' partly visible pairs, whose row
/// blocks differ by orders of magnitude (walls against the bunny's own).
pub const COST_SAMPLE_ROWS: usize = 64;

/// An amount over all row blocks, extrapolated from a sample of them, with
/// the standard error of that extrapolation (zero when every row block was
/// measured).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Extrapolated {
    /// The estimated total.
    pub value: f64,
    /// Its standard error (sampling without replacement).
    pub std_error: f64,
}

impl Extrapolated {
    /// The total over `rows` row blocks of an amount measured on `sample`
    /// of them (a simple random sample's estimate and error).
    pub fn from_sample(sample: &[f64], rows: usize) -> Self {
        let s = sample.len();
        if s == 0 {
            return Self::default();
        }
        let mean = sample.iter().sum::<f64>() / s as f64;
        let var = if s > 1 {
            sample.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (s - 1) as f64
        } else {
            0.0
        };
        let n = rows as f64;
        let finite = (1.0 - s as f64 / n).max(0.0);
        Self {
            value: n * mean,
            std_error: n * (var / s as f64 * finite).sqrt(),
        }
    }

    fn scaled(self, by: f64) -> Self {
        Self {
            value: self.value * by,
            std_error: self.std_error * by,
        }
    }
}

/// One matrix's predicted cost: the assembly's (rows at the collocation
/// points) or the error estimate's (rows at its check points).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct MatrixCost {
    /// Point × element pairs integrated with one far rule.
    pub pairs_far: Extrapolated,
    /// Near pairs (adaptive quadrature).
    pub pairs_near: Extrapolated,
    /// Pairs whose point lies on the element.
    pub pairs_on_element: Extrapolated,
    /// Culled pairs: facing away, coplanar, or hidden from every point.
    pub pairs_culled: Extrapolated,
    /// Partly visible pairs, each clipped exactly at every point.
    pub pairs_partial: Extrapolated,
    /// Candidate occluders summed over the partly visible element pairs.
    pub candidates: Extrapolated,
    /// Bytes the plan holds for the partly visible pairs and their
    /// candidates, while the matrix is built.
    pub partial_bytes: Extrapolated,
    /// Seconds to classify the pairs (the occlusion walk included), on
    /// [`AssemblyCost::threads`] threads.
    pub plan_seconds: Extrapolated,
    /// Seconds to fill the entries on the CPU, on as many threads.
    pub fill_seconds: Extrapolated,
}

impl MatrixCost {
    /// Seconds to plan and fill.
    pub fn seconds(&self) -> f64 {
        self.plan_seconds.value + self.fill_seconds.value
    }
}

/// The predicted cost of one solve's assembly and error estimate.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct AssemblyCost {
    /// Row blocks (elements).
    pub rows: usize,
    /// Row blocks measured.
    pub sampled: usize,
    /// Threads the seconds assume (the work is spread evenly over them).
    pub threads: usize,
    /// The geometric matrix's assembly on the CPU.
    pub assembly: MatrixCost,
    /// The error estimate: the kernel at the check points.
    pub estimate: MatrixCost,
}

impl AssemblyCost {
    /// Measures `samples` row blocks spread evenly over the mesh of `disc`
    /// (every block when there are no more) in the assembly with quadrature
    /// `quad` and in the error estimate, and extrapolates to all of them on
    /// this process's threads.
    pub fn predict(
        disc: &Arc<Discretization>,
        quad: &QuadratureOptions,
        visibility: &VisibilityAnalysis,
        samples: usize,
    ) -> Self {
        let (n, threads) = (disc.mesh().len(), rayon::current_num_threads());
        let (picked, only) = spread(n, samples);
        let s = picked.len();
        let plan = AssemblyPlan::sampled(disc.clone(), None, quad.clone(), visibility, &only);
        let assembly = measure(&plan, &picked, n, threads, true);
        let check = Arc::new(check_discretization(disc));
        let check_quad = QuadratureOptions {
            tol: quad.tol.max(ESTIMATE_QUAD_TOL),
            ..quad.clone()
        };
        let plan = AssemblyPlan::sampled(disc.clone(), Some(check), check_quad, visibility, &only);
        let estimate = measure(&plan, &picked, n, threads, true);
        Self {
            rows: n,
            sampled: s,
            threads,
            assembly,
            estimate,
        }
    }
}

/// The assembly plan's pairs and the memory its partly visible pairs will
/// hold, predicted from `samples` row blocks without filling any (a
/// solve's check before planning), with the row blocks measured.
pub fn predict_plan(
    disc: &Arc<Discretization>,
    quad: &QuadratureOptions,
    visibility: &VisibilityAnalysis,
    samples: usize,
) -> (MatrixCost, usize) {
    let (n, threads) = (disc.mesh().len(), rayon::current_num_threads());
    let (picked, only) = spread(n, samples);
    let plan = AssemblyPlan::sampled(disc.clone(), None, quad.clone(), visibility, &only);
    (measure(&plan, &picked, n, threads, false), picked.len())
}

/// Meshes of at least this many elements in scenes that occlude have the
/// memory of their plan's candidate lists predicted before it is built
/// ([`check_plan_memory`]): from 20 000 elements on, they can hold tens of
/// GB (the 10^5-triangle bunny hall: about 61 GB), and the prediction costs
/// well under one per cent of the plan.
pub const PREDICT_PLAN_ABOVE: usize = 20_000;

/// Refuses, before the plan is built, a mesh whose plan would hold
/// candidate lists larger than the memory `available` allows
/// ([`predict_plan`] from [`COST_SAMPLE_ROWS`] row blocks; meshes of at
/// least `above` elements in scenes that occlude only: a solve passes
/// [`PREDICT_PLAN_ABOVE`]).
///
/// # Errors
/// [`InputError::VisibilityPlanTooLarge`].
pub fn check_plan_memory(
    disc: &Arc<Discretization>,
    quad: &QuadratureOptions,
    visibility: &VisibilityAnalysis,
    available: Option<u64>,
    above: usize,
) -> Result<(), InputError> {
    let elements = disc.mesh().len();
    let Some(available) = available.filter(|_| visibility.needed && elements >= above) else {
        return Ok(());
    };
    let (cost, sampled) = predict_plan(disc, quad, visibility, COST_SAMPLE_ROWS);
    let bytes = cost.partial_bytes;
    if bytes.value <= usable(available) {
        return Ok(());
    }
    Err(InputError::VisibilityPlanTooLarge {
        elements: elements as u64,
        partial_pairs: cost.pairs_partial.value,
        relative_error: bytes.std_error / bytes.value,
        bytes: bytes.value,
        sampled,
        available,
    })
}

/// `samples` of `n` row blocks spread evenly (all when there are no more),
/// and a flag per row block.
fn spread(n: usize, samples: usize) -> (Vec<usize>, Vec<bool>) {
    let s = samples.clamp(1, n.max(1)).min(n);
    let picked: Vec<usize> = (0..s).map(|i| (2 * i + 1) * n / (2 * s)).collect();
    let mut only = vec![false; n];
    for &k in &picked {
        only[k] = true;
    }
    (picked, only)
}

/// The sampled rows `picked` of `plan`, each filled once and timed when
/// `fill`, extrapolated to `n` rows on `threads` threads.
fn measure(
    plan: &AssemblyPlan,
    picked: &[usize],
    n: usize,
    threads: usize,
    fill: bool,
) -> MatrixCost {
    let width = plan.dim();
    let mut rows: Vec<(RowCost, f64)> = Vec::with_capacity(picked.len());
    let mut block = Vec::new();
    for &kp in picked {
        if !fill {
            rows.push((plan.row_cost(kp), 0.0));
            continue;
        }
        block.clear();
        block.resize(plan.rows().nodes_per(kp) * width, 0.0);
        let t = Instant::now();
        plan.fill_block(kp, &mut block, FillMode::All);
        rows.push((plan.row_cost(kp), t.elapsed().as_secs_f64()));
    }
    let total = |f: &dyn Fn(&(RowCost, f64)) -> f64| {
        let xs: Vec<f64> = rows.iter().map(f).collect();
        Extrapolated::from_sample(&xs, n)
    };
    let per_thread = 1.0 / threads.max(1) as f64;
    MatrixCost {
        pairs_far: total(&|r| r.0.far as f64),
        pairs_near: total(&|r| r.0.near as f64),
        pairs_on_element: total(&|r| r.0.on_element as f64),
        pairs_culled: total(&|r| r.0.culled as f64),
        pairs_partial: total(&|r| r.0.partial as f64),
        candidates: total(&|r| r.0.candidates as f64),
        partial_bytes: total(&|r| r.0.partial_bytes as f64),
        plan_seconds: total(&|r| r.0.plan_seconds).scaled(per_thread),
        fill_seconds: total(&|r| r.1).scaled(per_thread),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A full sample is the total itself, with no error; a sample of a
    /// constant is exact too.
    #[test]
    fn extrapolation_of_full_and_constant_samples_is_exact() {
        let e = Extrapolated::from_sample(&[1.0, 2.0, 6.0], 3);
        assert_eq!((e.value, e.std_error), (9.0, 0.0));
        let e = Extrapolated::from_sample(&[4.0; 10], 1000);
        assert_eq!((e.value, e.std_error), (4000.0, 0.0));
    }

    /// The standard error of a sample's total against its definition:
    /// N s / √n √(1 − n/N), s the sample's standard deviation.
    #[test]
    fn extrapolation_error_is_the_sampling_formula() {
        let xs = [1.0, 3.0, 5.0, 7.0];
        // mean 4, sample variance (9 + 1 + 1 + 9) / 3.
        let e = Extrapolated::from_sample(&xs, 100);
        assert_eq!(e.value, 400.0);
        let want = 100.0 * (20.0f64 / 3.0 / 4.0 * (1.0 - 4.0 / 100.0)).sqrt();
        assert!((e.std_error - want).abs() < 1e-12 * want);
    }
}
