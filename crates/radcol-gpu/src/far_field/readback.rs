//! Reading tiles back: wait for a tile's submission, map its staging buffer,
//! widen it into the host matrix, and read its pass's timestamps.

use super::slot::Slot;
use crate::error::GpuError;
use crate::layout::GpuScalar;
use crate::tiling::Tile;
use rayon::prelude::*;
use std::mem::size_of;
use std::sync::mpsc;

/// A submitted tile awaiting read-back.
pub(super) struct Pending {
    pub(super) tile: Tile,
    pub(super) slot: usize,
    pub(super) bytes: u64,
    pub(super) submission: wgpu::SubmissionIndex,
}

/// What every read-back of one fill shares.
pub(super) struct ReadBack<'a> {
    pub(super) device: &'a wgpu::Device,
    pub(super) slots: &'a [Slot],
    pub(super) timestamps: bool,
    /// Nanoseconds per timestamp tick.
    pub(super) period_ns: f64,
    pub(super) n_dim: usize,
    pub(super) f: usize,
}

/// Reads back `pending` (when a tile is in flight) into `matrix`; returns
/// the device nanoseconds of its pass (0 without timestamps or tile).
pub(super) fn drain<S: GpuScalar>(
    r: &ReadBack<'_>,
    pending: Option<Pending>,
    matrix: &mut [f64],
) -> Result<f64, GpuError> {
    match pending {
        Some(p) => read_back::<S>(r, &p, matrix),
        None => Ok(0.0),
    }
}

/// Waits for tile `p`, copies it into `matrix` and returns the device
/// nanoseconds of its pass (0 without timestamps).
fn read_back<S: GpuScalar>(
    r: &ReadBack<'_>,
    p: &Pending,
    matrix: &mut [f64],
) -> Result<f64, GpuError> {
    let (device, slot, timestamps) = (r.device, &r.slots[p.slot], r.timestamps);
    let (period_ns, n_dim, f) = (r.period_ns, r.n_dim, r.f);
    let len = p.bytes + if timestamps { 16 } else { 0 };
    let (tx, rx) = mpsc::channel();
    slot.staging
        .map_async(wgpu::MapMode::Read, 0..len, move |r| {
            // The receiver outlives the poll below; a send error cannot happen.
            let _ = tx.send(r);
        });
    device
        .poll(wgpu::PollType::Wait {
            submission_index: Some(p.submission.clone()),
            timeout: None,
        })
        .map_err(|e| GpuError::Device {
            stage: "waiting for a tile",
            message: e.to_string(),
        })?;
    let mapped = rx.recv().map_err(|_| GpuError::Device {
        stage: "mapping a tile",
        message: "the map callback never ran".into(),
    })?;
    mapped.map_err(|e| GpuError::Device {
        stage: "mapping a tile",
        message: e.to_string(),
    })?;
    let mut ns = 0.0;
    {
        let view = slot
            .staging
            .get_mapped_range(0..len)
            .map_err(|e| GpuError::Device {
                stage: "reading a tile",
                message: e.to_string(),
            })?;
        let (data, ts) = view.split_at(p.bytes as usize);
        let tile = p.tile;
        let cols = tile.nk * f;
        let dst = &mut matrix[tile.row0 * n_dim..(tile.row0 + tile.rows) * n_dim];
        match bytemuck::try_cast_slice::<u8, S>(data) {
            Ok(src) => dst
                .par_chunks_exact_mut(n_dim)
                .zip(src.par_chunks_exact(cols))
                .for_each(|(row, src)| {
                    for (d, s) in row[tile.k0 * f..tile.k0 * f + cols].iter_mut().zip(src) {
                        *d = s.to_f64();
                    }
                }),
            // Mapped memory is page-aligned in practice; this path is for safety only.
            Err(_) => dst
                .par_chunks_exact_mut(n_dim)
                .zip(data.par_chunks_exact(cols * size_of::<S>()))
                .for_each(|(row, src)| {
                    for (d, s) in row[tile.k0 * f..tile.k0 * f + cols]
                        .iter_mut()
                        .zip(src.chunks_exact(size_of::<S>()))
                    {
                        *d = bytemuck::pod_read_unaligned::<S>(s).to_f64();
                    }
                }),
        }
        if timestamps {
            let begin: u64 = bytemuck::pod_read_unaligned(&ts[0..8]);
            let end: u64 = bytemuck::pod_read_unaligned(&ts[8..16]);
            ns = end.wrapping_sub(begin) as f64 * period_ns;
            if !(ns.is_finite() && ns >= 0.0 && end >= begin) {
                ns = 0.0;
            }
        }
    }
    slot.staging.unmap();
    Ok(ns)
}
