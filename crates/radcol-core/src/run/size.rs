//! How big a discretization is before it is built: elements, unknowns and the
//! memory of the dense matrices. The one place that counts them, for the
//! pipeline, `radcol info` and the CLI alike.

use super::SolverKind;
use crate::error::InputError;
use crate::geometry::Surface;
use crate::mesh::grading::{Grade, Grading};
use crate::mesh::{Mesh, MAX_EDGE_COUNT_CAP};
use crate::nodes::nodes_per_element;
use serde::Serialize;
use std::sync::Arc;

/// Elements of the mesh that uniform `level`, then `max_edge` (when given,
/// a positive finite length), then `grade` towards
/// concave lines ([`Grading`]) make of `surface`; saturates at `u64::MAX`.
/// Counts without storing the mesh (a graded count builds the ungraded one).
pub fn elements(
    surface: &Arc<Surface>,
    level: u32,
    max_edge: Option<f64>,
    grade: Option<&Grade>,
) -> u64 {
    if let Some(grade) = grade {
        let grading = Grading::towards_concave_lines(surface, grade);
        return Mesh::count_graded(
            surface.clone(),
            level,
            max_edge,
            &grading,
            MAX_EDGE_COUNT_CAP,
        );
    }
    match max_edge {
        Some(h) => Mesh::count_with_max_edge(surface.clone(), level, h),
        None => (surface.base_triangle_count() as u64).saturating_mul(4u64.saturating_pow(level)),
    }
}

/// The size of a discretization before it is built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MeshSize {
    /// Elements n.
    pub elements: u64,
    /// Unknowns N = n · f_r (saturating).
    pub unknowns: u64,
}

/// Elements and unknowns at degree r of the mesh that `level`, `max_edge`
/// and `grade` make of `surface` ([`elements`]; the refinement is counted
/// once).
pub fn mesh_size(
    surface: &Arc<Surface>,
    level: u32,
    max_edge: Option<f64>,
    grade: Option<&Grade>,
    degree: usize,
) -> MeshSize {
    let elements = elements(surface, level, max_edge, grade);
    MeshSize {
        elements,
        unknowns: elements.saturating_mul(nodes_per_element(degree) as u64),
    }
}

/// The memory available to this process's solve: [`available_memory`],
/// shared evenly among the ranks of a distributed solve that run on this
/// machine (each plans for its part; taken when the checks run, before the
/// others have allocated much).
pub(crate) fn available_for(cfg: &super::SolveConfig) -> Option<u64> {
    let local = cfg.distributed().map_or(1, |r| r.local_size().max(1)) as u64;
    available_memory().map(|a| a / local)
}

/// Bytes of memory available, from /proc/meminfo on Linux.
pub fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    text.lines()
        .find(|l| l.starts_with("MemAvailable:"))
        .and_then(|l| l.split_whitespace().nth(1))
        .and_then(|kb| kb.parse::<u64>().ok())
        .map(|kb| kb * 1024)
}

/// Of `available` bytes, what a solve may plan to use: nine tenths (the
/// rest for the allocator's overhead and what the estimates leave out).
pub fn usable(available: u64) -> f64 {
    (available / 10 * 9) as f64
}

/// Bytes of a dense N × N matrix of f64: 8 N².
pub fn dense_bytes(unknowns: u64) -> f64 {
    8.0 * (unknowns as f64).powi(2)
}

/// What a solve may spend of the machine's memory: the one place that
/// says how much of what is available may be planned for ([`usable`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct MemoryBudget {
    /// Bytes available (MemAvailable), when known; unknown means no limit.
    pub available: Option<u64>,
}

impl MemoryBudget {
    /// The memory available now ([`available_memory`]).
    pub fn now() -> Self {
        Self {
            available: available_memory(),
        }
    }

    /// The bytes that may be planned for ([`usable`]; infinite when the
    /// available memory is unknown).
    pub fn usable(&self) -> f64 {
        self.available.map_or(f64::INFINITY, usable)
    }

    /// Whether `bytes` fit in [`MemoryBudget::usable`].
    pub fn fits(&self, bytes: f64) -> bool {
        bytes <= self.usable()
    }

    /// The most unknowns whose `copies` dense matrices fit (None: no
    /// limit known).
    pub fn largest_dense(&self, copies: f64) -> Option<u64> {
        self.available
            .map(|a| (usable(a) / (8.0 * copies)).sqrt().floor() as u64)
    }
}

/// The dense matrices of N unknowns against the memory available.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct MemoryEstimate {
    /// Unknowns N.
    #[serde(skip)]
    pub unknowns: u64,
    /// 8 N² bytes of the geometric matrix.
    pub matrix_bytes: f64,
    /// Extra bytes of an LU copy ([`SolverKind::Lu`]).
    pub lu_extra_bytes: f64,
    /// Available memory (MemAvailable), when known.
    pub available_bytes: Option<u64>,
    /// The matrix fits (GMRES).
    pub fits_gmres: bool,
    /// Matrix and LU copy fit.
    pub fits_lu: bool,
}

impl MemoryEstimate {
    /// The estimate for `unknowns` with the memory available now.
    pub fn new(unknowns: u64) -> Self {
        Self::with_available(unknowns, available_memory())
    }

    /// The estimate for `unknowns` with `available` bytes (None: unknown,
    /// and then everything is taken to fit).
    pub fn with_available(unknowns: u64, available: Option<u64>) -> Self {
        let matrix_bytes = dense_bytes(unknowns);
        let budget = MemoryBudget { available };
        let fits = |bytes: f64| budget.fits(bytes);
        Self {
            unknowns,
            matrix_bytes,
            lu_extra_bytes: matrix_bytes,
            available_bytes: available,
            fits_gmres: fits(matrix_bytes),
            fits_lu: fits(2.0 * matrix_bytes),
        }
    }

    /// Refuses, with the sizes, when the matrices `solver` needs do not fit.
    pub fn check(&self, solver: SolverKind) -> Result<(), InputError> {
        let (fits, lu) = match solver {
            SolverKind::Gmres => (self.fits_gmres, 0.0),
            SolverKind::Lu => (self.fits_lu, self.lu_extra_bytes),
        };
        if fits {
            return Ok(());
        }
        Err(InputError::TooLarge {
            unknowns: self.unknowns,
            bytes_matrix: self.matrix_bytes,
            bytes_lu: lu,
            bytes_available: self.available_bytes.unwrap_or(0),
        })
    }
}

/// This process's resident memory now and its high-water mark so far
/// (VmRSS and VmHWM of /proc/self/status, Linux), bytes.
pub fn process_memory() -> Option<(u64, u64)> {
    let text = std::fs::read_to_string("/proc/self/status").ok()?;
    let field = |name: &str| {
        text.lines()
            .find(|l| l.starts_with(name))
            .and_then(|l| l.split_whitespace().nth(1))
            .and_then(|kb| kb.parse::<u64>().ok())
            .map(|kb| kb * 1024)
    };
    Some((field("VmRSS:")?, field("VmHWM:")?))
}

/// One solve's memory: predicted once its plan is built, from what the
/// process holds then (measured) and what is still to come (counted), and
/// the high-water mark measured at its end.
///
/// The peak comes after the matrix is filled: either while the linear
/// solver runs (LU's factors, one more n × n copy; GMRES's Krylov basis) or
/// while the error estimate runs (its plan, pairing the check points with
/// the same elements, about as large as the solve's, and a row block per
/// thread), whichever is larger.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct MemoryUse {
    /// Resident bytes once the plan was built (scene, mesh, visibility,
    /// plan, fields); 0 where the platform does not say.
    pub after_plan_bytes: f64,
    /// What building the plan cost (its heap, or the growth of the resident
    /// set while it was built where that is larger: allocator overhead).
    pub plan_bytes: f64,
    /// 8 N² bytes of the geometric matrix.
    pub matrix_bytes: f64,
    /// The linear solver's working memory.
    pub solver_bytes: f64,
    /// The error estimate's working memory.
    pub estimate_bytes: f64,
    /// after_plan + matrix + max(solver, estimate).
    pub predicted_peak_bytes: f64,
    /// The process's measured high-water mark at the end of the solve.
    pub measured_peak_bytes: Option<f64>,
}

impl MemoryUse {
    /// The prediction for N `unknowns`, a plan of `plan_bytes`, `solver`
    /// (GMRES keeping `krylov` vectors of N: `restart` + 4 per channel, the
    /// channels run in lockstep), and the estimate when `estimate` (its
    /// plan).
    pub fn predict(
        unknowns: usize,
        plan_bytes: u64,
        solver: SolverKind,
        krylov: usize,
        estimate: bool,
    ) -> Self {
        let n = unknowns as f64;
        let after_plan_bytes = process_memory().map_or(0.0, |(rss, _)| rss as f64);
        let matrix_bytes = dense_bytes(unknowns as u64);
        let solver_bytes = match solver {
            SolverKind::Lu => matrix_bytes,
            SolverKind::Gmres => 8.0 * n * krylov as f64,
        };
        let estimate_bytes = if estimate { plan_bytes as f64 } else { 0.0 };
        Self {
            after_plan_bytes,
            plan_bytes: plan_bytes as f64,
            matrix_bytes,
            solver_bytes,
            estimate_bytes,
            predicted_peak_bytes: after_plan_bytes
                + matrix_bytes
                + solver_bytes.max(estimate_bytes),
            measured_peak_bytes: None,
        }
    }

    /// Refuses, with the figures, when what is still to come exceeds the
    /// nine tenths of `available` bytes that the dense matrices may take.
    pub fn check(&self, available: Option<u64>) -> Result<(), InputError> {
        let to_come = self.predicted_peak_bytes - self.after_plan_bytes;
        match available {
            Some(a) if to_come > usable(a) => Err(InputError::PeakTooLarge {
                to_come,
                matrix: self.matrix_bytes,
                solver: self.solver_bytes,
                estimate: self.estimate_bytes,
                available: a,
            }),
            _ => Ok(()),
        }
    }

    /// The same prediction with the error estimate holding `bytes` more
    /// (the entries of its partly visible pairs, kept for the next step).
    pub fn with_estimate_store(self, bytes: f64) -> Self {
        if self.estimate_bytes == 0.0 {
            return self;
        }
        let before = self.solver_bytes.max(self.estimate_bytes);
        let estimate_bytes = self.estimate_bytes + bytes;
        Self {
            estimate_bytes,
            predicted_peak_bytes: self.predicted_peak_bytes - before
                + self.solver_bytes.max(estimate_bytes),
            ..self
        }
    }

    /// The same prediction with a geometric operator of `matrix` bytes
    /// instead of the dense 8 N² (None: unchanged): a compressed one, 0
    /// before it is built.
    pub fn with_matrix(self, matrix: Option<f64>) -> Self {
        match matrix {
            None => self,
            Some(m) => Self {
                matrix_bytes: m,
                predicted_peak_bytes: self.predicted_peak_bytes - self.matrix_bytes + m,
                ..self
            },
        }
    }

    /// Once the compressed operator `h` is built (and resident): refuses,
    /// with its size, when the rest of the peak exceeds nine tenths of
    /// `available` bytes.
    pub(crate) fn check_compressed(
        &self,
        h: &crate::hmatrix::HMatrix,
        available: Option<u64>,
    ) -> Result<(), InputError> {
        let to_come = self.solver_bytes.max(self.estimate_bytes);
        match available {
            Some(a) if to_come > usable(a) => Err(InputError::CompressedTooLarge {
                stored: h.heap_bytes() as f64,
                fraction: h.stats().compression(),
                to_come,
                available: a,
            }),
            _ => Ok(()),
        }
    }

    /// Records the process's high-water mark now.
    pub fn measured(self) -> Self {
        Self {
            measured_peak_bytes: process_memory().map(|(_, hwm)| hwm as f64),
            ..self
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The largest dense size of a budget is the last that fits, for one
    /// matrix and for a matrix with its LU copy.
    #[test]
    fn the_largest_dense_size_is_the_last_that_fits() {
        let budget = MemoryBudget {
            available: Some(23_000_000_000),
        };
        for copies in [1.0, 2.0] {
            let n = budget.largest_dense(copies).unwrap();
            assert!(budget.fits(copies * dense_bytes(n)), "{n}");
            assert!(!budget.fits(copies * dense_bytes(n + 1)), "{n}");
        }
        assert_eq!(MemoryBudget { available: None }.largest_dense(1.0), None);
        assert!(MemoryBudget { available: None }.fits(f64::MAX));
    }

    #[test]
    fn the_peak_is_the_matrix_and_the_larger_of_solver_and_estimate() {
        // N = 1000: 8 MB of matrix; LU 8 MB more; GMRES (restart 30, one
        // channel) 34·8 kB.
        let lu = MemoryUse::predict(1000, 5_000_000, SolverKind::Lu, 34, true);
        let to_come = lu.predicted_peak_bytes - lu.after_plan_bytes;
        assert_eq!(
            (lu.matrix_bytes, lu.solver_bytes, lu.estimate_bytes),
            (8e6, 8e6, 5e6)
        );
        assert_eq!(to_come, 16e6);
        let gm = MemoryUse::predict(1000, 5_000_000, SolverKind::Gmres, 34, true);
        // The estimate's plan wins over GMRES.
        assert_eq!(gm.estimate_bytes, 5e6);
        assert_eq!(gm.predicted_peak_bytes - gm.after_plan_bytes, 8e6 + 5e6);
        // The estimate's stored entries add to it, and to the peak where
        // it is the larger; nothing without an estimate.
        let stored = gm.with_estimate_store(1e6);
        assert_eq!(stored.predicted_peak_bytes - gm.after_plan_bytes, 8e6 + 6e6);
        let lu_stored = lu.with_estimate_store(1e6);
        assert_eq!(lu_stored.predicted_peak_bytes - lu.after_plan_bytes, 16e6);
        let lu_more = lu.with_estimate_store(4e6);
        assert_eq!(
            lu_more.predicted_peak_bytes - lu.after_plan_bytes,
            8e6 + 9e6
        );
        let none = MemoryUse::predict(1000, 5_000_000, SolverKind::Gmres, 34, false);
        let none_stored = none.with_estimate_store(1e6);
        assert_eq!(none_stored.predicted_peak_bytes, none.predicted_peak_bytes);
        assert_eq!(
            none.predicted_peak_bytes - none.after_plan_bytes,
            8e6 + 8.0 * 1000.0 * 34.0
        );
        // Refused when it exceeds 0.9 of what is available, with the figures.
        assert!(lu.check(Some(18_000_000)).is_ok());
        let err = lu.check(Some(17_000_000)).unwrap_err().to_string();
        assert!(
            err.contains("0.01 GiB more memory") && err.contains("skip the estimate"),
            "{err}"
        );
        assert!(lu.check(None).is_ok());
    }
}
