//! How the N × N matrix is cut into tiles that the device can bind.
//!
//! A tile is `rows` consecutive matrix rows × the columns of `nk` consecutive
//! elements (`nk · f` columns). Three buffers grow with it and each must fit in
//! one storage binding (`max_storage_buffer_binding_size`, 128 MiB on lavapipe)
//! and one buffer (`max_buffer_size`):
//!
//! * the tile itself: `rows · nk · f` scalars;
//! * the far points of its elements: `nk · stride` point records;
//! * its class codes: about `(rows / f + 1) · nk` bytes (smaller than the tile).
//!
//! Dispatches are `ceil(nk / 64) × rows` workgroups, each dimension capped at
//! `max_compute_workgroups_per_dimension` (65535). Column tiles are outermost so
//! each element's far points are uploaded once; most problems need one.

use crate::error::GpuError;

/// Invocations per workgroup along x (elements); must match the shader.
pub const WORKGROUP_X: u32 = 64;

/// Tile size limits, from the device (and optionally tightened by the caller).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TileLimits {
    /// Largest storage binding, bytes.
    pub max_binding_bytes: u64,
    /// Largest buffer, bytes.
    pub max_buffer_bytes: u64,
    /// Workgroups per dispatch dimension.
    pub max_workgroups: u32,
    /// Preferred upper bound on one tile's bytes: smaller tiles let the host
    /// copy one tile while the device fills the next, and keep each dispatch
    /// short (desktop drivers reset GPUs that hang for ~2 s).
    pub target_tile_bytes: u64,
}

impl TileLimits {
    /// Default target tile size: 32 MiB.
    pub const DEFAULT_TARGET_TILE_BYTES: u64 = 32 << 20;

    /// The limits of a device, with the default target tile size.
    pub fn from_device_limits(l: &wgpu::Limits) -> Self {
        Self {
            max_binding_bytes: l.max_storage_buffer_binding_size,
            max_buffer_bytes: l.max_buffer_size,
            max_workgroups: l.max_compute_workgroups_per_dimension,
            target_tile_bytes: Self::DEFAULT_TARGET_TILE_BYTES,
        }
    }

    /// Bytes one binding may hold: the smaller of the two limits, rounded down
    /// to a multiple of 256 (any record size and copy alignment divides it).
    pub fn binding_bytes(&self) -> u64 {
        self.max_binding_bytes.min(self.max_buffer_bytes) / 256 * 256
    }
}

/// One tile: matrix rows `row0..row0 + rows`, elements `k0..k0 + nk`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tile {
    /// First row.
    pub row0: usize,
    /// Rows.
    pub rows: usize,
    /// First element (column block).
    pub k0: usize,
    /// Elements.
    pub nk: usize,
}

/// The tiles of one assembly, column tiles outermost.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TilePlan {
    /// Column tiles: `(k0, nk)`.
    pub columns: Vec<(usize, usize)>,
    /// Rows per tile (the last tile of each column may have fewer).
    pub rows_per_tile: usize,
    /// Matrix dimension N.
    pub dim: usize,
}

impl TilePlan {
    /// Tiles for an `n_elems · f`-square matrix whose far-point records per
    /// element take `stride · point_bytes` bytes and whose entries take
    /// `scalar_bytes` each on the device.
    pub fn new(
        n_elems: usize,
        f: usize,
        stride: usize,
        point_bytes: usize,
        scalar_bytes: usize,
        limits: &TileLimits,
    ) -> Result<Self, GpuError> {
        let dim = n_elems * f;
        let bind = limits.binding_bytes();
        let too_large = |what: String| GpuError::TooLarge { message: what };
        if dim == 0 {
            return Ok(Self {
                columns: Vec::new(),
                rows_per_tile: 0,
                dim,
            });
        }
        let max_wg = limits.max_workgroups.max(1) as u64;
        let row_bytes_per_elem = (f * scalar_bytes) as u64;
        let rec_bytes = (stride.max(1) * point_bytes) as u64;
        // Elements per column tile: their far points fit one binding, one row of
        // them fits the tile and the x dispatch stays under the cap.
        let nk_max = (bind / rec_bytes)
            .min(bind / row_bytes_per_elem)
            .min(max_wg * WORKGROUP_X as u64)
            .min(u32::MAX as u64 / 2) as usize;
        if nk_max == 0 {
            return Err(too_large(format!(
                "one element's far points take {rec_bytes} bytes, more than one storage binding ({bind} bytes)"
            )));
        }
        let n_col_tiles = n_elems.div_ceil(nk_max);
        let base = n_elems / n_col_tiles;
        let extra = n_elems % n_col_tiles;
        let mut columns = Vec::with_capacity(n_col_tiles);
        let mut k0 = 0;
        for t in 0..n_col_tiles {
            let nk = base + usize::from(t < extra);
            columns.push((k0, nk));
            k0 += nk;
        }
        let widest = base + usize::from(extra > 0);
        let row_bytes = widest as u64 * row_bytes_per_elem;
        let target = limits
            .target_tile_bytes
            .clamp(row_bytes, bind.max(row_bytes));
        let rows_per_tile = (target / row_bytes)
            .min(bind / row_bytes)
            .min(max_wg)
            .min(dim as u64)
            .max(1) as usize;
        Ok(Self {
            columns,
            rows_per_tile,
            dim,
        })
    }

    /// All tiles, column tiles outermost.
    pub fn tiles(&self) -> impl Iterator<Item = Tile> + '_ {
        let rows = self.rows_per_tile;
        let dim = self.dim;
        self.columns.iter().flat_map(move |&(k0, nk)| {
            (0..dim.div_ceil(rows.max(1))).map(move |t| Tile {
                row0: t * rows,
                rows: rows.min(dim - t * rows),
                k0,
                nk,
            })
        })
    }

    /// Number of tiles.
    pub fn len(&self) -> usize {
        if self.dim == 0 {
            0
        } else {
            self.columns.len() * self.dim.div_ceil(self.rows_per_tile)
        }
    }

    /// No tiles (an empty problem).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Widest column tile, elements.
    pub fn max_nk(&self) -> usize {
        self.columns.iter().map(|c| c.1).max().unwrap_or(0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lavapipe() -> TileLimits {
        TileLimits {
            max_binding_bytes: 128 << 20,
            max_buffer_bytes: u64::MAX,
            max_workgroups: 65535,
            target_tile_bytes: TileLimits::DEFAULT_TARGET_TILE_BYTES,
        }
    }

    /// Every entry is covered exactly once and every tile respects the limits.
    fn check(
        plan: &TilePlan,
        n: usize,
        f: usize,
        stride: usize,
        pb: usize,
        sb: usize,
        l: &TileLimits,
    ) {
        let dim = n * f;
        let mut seen = vec![0u8; dim * n];
        for t in plan.tiles() {
            assert!(t.rows >= 1 && t.nk >= 1);
            assert!((t.rows * t.nk * f * sb) as u64 <= l.binding_bytes());
            assert!((t.nk * stride * pb) as u64 <= l.binding_bytes());
            assert!(t.rows as u64 <= l.max_workgroups as u64);
            assert!(t.nk.div_ceil(WORKGROUP_X as usize) as u64 <= l.max_workgroups as u64);
            for r in t.row0..t.row0 + t.rows {
                for k in t.k0..t.k0 + t.nk {
                    seen[r * n + k] += 1;
                }
            }
        }
        assert!(seen.iter().all(|&c| c == 1));
        assert_eq!(plan.tiles().count(), plan.len());
    }

    #[test]
    fn small_problem_is_one_tile() {
        let l = lavapipe();
        let p = TilePlan::new(128, 3, 40, 64, 8, &l).unwrap();
        assert_eq!(p.len(), 1);
        check(&p, 128, 3, 40, 64, 8, &l);
    }

    #[test]
    fn tight_limits_split_rows_and_columns() {
        let l = TileLimits {
            max_binding_bytes: 4096,
            max_buffer_bytes: 1 << 40,
            max_workgroups: 7,
            target_tile_bytes: 1 << 20,
        };
        for (n, f, stride) in [(50, 3, 12), (33, 1, 7), (20, 6, 3)] {
            let p = TilePlan::new(n, f, stride, 64, 8, &l).unwrap();
            assert!(p.columns.len() > 1 || p.rows_per_tile < n * f, "{p:?}");
            check(&p, n, f, stride, 64, 8, &l);
        }
    }

    /// The largest matrix the core accepts on a 24 GiB machine (N ≈ 50 000,
    /// 9/10 of memory) still tiles within lavapipe's 128 MiB bindings.
    #[test]
    fn largest_problem_tiles_within_lavapipe_limits() {
        let l = lavapipe();
        let n = 50_000;
        let p = TilePlan::new(n, 1, 1500, 64, 8, &l).unwrap();
        assert!(p.columns.len() > 1);
        for t in p.tiles().take(3) {
            assert!((t.rows * t.nk * 8) as u64 <= l.binding_bytes());
            assert!((t.nk * 1500 * 64) as u64 <= l.binding_bytes());
        }
        let covered: usize = p.columns.iter().map(|c| c.1).sum();
        assert_eq!(covered, n);
    }

    #[test]
    fn a_record_larger_than_a_binding_is_an_error() {
        let l = TileLimits {
            max_binding_bytes: 256,
            ..lavapipe()
        };
        assert!(matches!(
            TilePlan::new(10, 1, 100, 64, 8, &l),
            Err(GpuError::TooLarge { .. })
        ));
    }
}
