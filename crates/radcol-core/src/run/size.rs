//! How big a discretization is before it is built: elements, unknowns and the
//! memory of the dense matrices. The one place that counts them, for the
//! pipeline, `radcol info` and the CLI alike.

use super::SolverKind;
use crate::error::InputError;
use crate::geometry::Surface;
use crate::mesh::Mesh;
use crate::nodes::nodes_per_element;
use serde::Serialize;
use std::sync::Arc;

/// Elements of the mesh that uniform `level` and then `max_edge` (when
/// given, a positive finite length) make of `surface`; saturates at
/// `u64::MAX`. Counts without building the mesh.
pub fn elements(surface: &Arc<Surface>, level: u32, max_edge: Option<f64>) -> u64 {
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

/// Elements and unknowns at degree r of the mesh that `level` and
/// `max_edge` make of `surface` (the refinement is counted once).
pub fn mesh_size(
    surface: &Arc<Surface>,
    level: u32,
    max_edge: Option<f64>,
    degree: usize,
) -> MeshSize {
    let elements = elements(surface, level, max_edge);
    MeshSize {
        elements,
        unknowns: elements.saturating_mul(nodes_per_element(degree) as u64),
    }
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
        let n = unknowns as f64;
        let matrix_bytes = 8.0 * n * n;
        // The dense matrices may take nine tenths of what is available.
        let fits = |bytes: f64| available.is_none_or(|a| bytes <= (a / 10 * 9) as f64);
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
