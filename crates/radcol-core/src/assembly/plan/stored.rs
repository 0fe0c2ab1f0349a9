//! The entries of partly visible pairs, kept for the plan of a refined mesh.
//!
//! A plan at other points than the nodes ([`AssemblyPlan::at_points`]: the
//! error estimate's check points) is filled one row block at a time and not
//! kept as a matrix, so the estimate of an adaptive step would clip every
//! partly visible pair again, although most of them are pairs of two
//! elements the step left unchanged, whose entries are the previous plan's
//! bit for bit (their classes and candidate occluders are: see
//! [`super::reuse`]). Clipping is nearly all of the cost of an occluded
//! scene's row block (the bunny room: 24 of a step's 37 s were the
//! estimate), while the entries of one pair are a few numbers (check points
//! of the row element times unknowns of the column element). So such a plan
//! keeps, per row block, the entries of its costliest partly visible pairs
//! (those whose shadows are merged: [`AssemblyPlan::kept`]), and the
//! plan of the refined mesh copies those of unchanged pairs instead of
//! clipping them again. It holds the previous plan's store weakly: the
//! chain of plans is not kept alive through it.

use super::AssemblyPlan;
use crate::visibility::clip;
use std::sync::{Arc, OnceLock, Weak};

/// The stored entries of every row block of a plan.
#[derive(Debug, Default)]
pub(crate) struct Stored {
    rows: Vec<OnceLock<RowEntries>>,
}

/// The entries of one row block's partly visible pairs: for each column
/// element (ascending) its rows × unknowns values, row-major.
#[derive(Debug)]
struct RowEntries {
    cols: Box<[u32]>,
    start: Box<[usize]>,
    values: Box<[f64]>,
}

impl RowEntries {
    fn get(&self, k: usize) -> Option<&[f64]> {
        let i = self.cols.binary_search(&(k as u32)).ok()?;
        Some(&self.values[self.start[i]..self.start[i + 1]])
    }

    fn heap_bytes(&self) -> usize {
        self.cols.len() * 4 + self.start.len() * 8 + self.values.len() * 8
    }
}

impl Stored {
    /// An empty store for `n` row blocks.
    pub(crate) fn new(n: usize) -> Self {
        Self {
            rows: (0..n).map(|_| OnceLock::new()).collect(),
        }
    }

    /// Bytes held on the heap.
    pub(crate) fn heap_bytes(&self) -> usize {
        let rows: usize = self
            .rows
            .iter()
            .filter_map(|r| r.get())
            .map(RowEntries::heap_bytes)
            .sum();
        rows + self.rows.len() * std::mem::size_of::<OnceLock<RowEntries>>()
    }
}

/// What the fill of one row block takes from the previous plan's store.
pub(super) struct StoredBefore {
    store: Option<Arc<Stored>>,
    old_row: usize,
}

impl StoredBefore {
    /// The stored entries of column element `k` (this plan's numbering) of
    /// the row block, when both elements are unchanged and the previous
    /// plan stored the pair.
    pub(super) fn get<'a>(&'a self, plan: &AssemblyPlan, k: usize) -> Option<&'a [f64]> {
        let row = self.store.as_ref()?.rows[self.old_row].get()?;
        row.get(plan.unchanged()?.old(k)?)
    }
}

impl AssemblyPlan {
    /// What the fill of row block `kp` may take from the previous plan's
    /// stored entries (nothing unless this plan reused a previous one that
    /// stored them, and `kp` is unchanged).
    pub(super) fn stored_previously(&self, kp: usize) -> StoredBefore {
        let old_row = self.unchanged().and_then(|u| u.old(kp));
        let store = old_row
            .and(self.previous_stored.as_ref())
            .and_then(Weak::upgrade);
        StoredBefore {
            store,
            old_row: old_row.unwrap_or(0),
        }
    }

    /// Stores the entries of row block `kp`'s partly visible pairs: taken
    /// from `previous` where it has them, else from `block` (rows × N,
    /// row-major), unless `filled(k)` says the fill left column element k
    /// out; then nothing is stored for the row.
    pub(super) fn store_row(
        &self,
        kp: usize,
        block: &[f64],
        previous: &StoredBefore,
        filled: impl Fn(usize) -> bool,
    ) {
        let Some(store) = &self.stored else {
            return;
        };
        if store.rows[kp].get().is_some() {
            return;
        }
        let disc = &*self.disc;
        let (ncols, f) = (disc.len(), self.rows().nodes_per(kp));
        let cols: Vec<u32> = self.kept(kp).map(|k| k as u32).collect();
        let mut start = Vec::with_capacity(cols.len() + 1);
        let mut values = Vec::new();
        for &k in &cols {
            let k = k as usize;
            start.push(values.len());
            if let Some(old) = previous.get(self, k) {
                values.extend_from_slice(old);
            } else if filled(k) {
                let cols = disc.range(k);
                for a in 0..f {
                    values.extend_from_slice(&block[a * ncols + cols.start..a * ncols + cols.end]);
                }
            } else {
                return;
            }
        }
        start.push(values.len());
        let _ = store.rows[kp].set(RowEntries {
            cols: cols.into_boxed_slice(),
            start: start.into_boxed_slice(),
            values: values.into_boxed_slice(),
        });
    }

    /// Copies into `block` (rows × N, row-major) the previous plan's
    /// entries of the partly visible pairs whose column element `take`s.
    pub(super) fn copy_previous(
        &self,
        kp: usize,
        block: &mut [f64],
        previous: &StoredBefore,
        take: impl Fn(usize) -> bool,
    ) {
        if previous.store.is_none() {
            return;
        }
        let disc = &*self.disc;
        let (ncols, f) = (disc.len(), self.rows().nodes_per(kp));
        for k in self.kept(kp) {
            if !take(k) {
                continue;
            }
            if let Some(old) = previous.get(self, k) {
                let cols = disc.range(k);
                let nk = cols.len();
                for a in 0..f {
                    block[a * ncols + cols.start..a * ncols + cols.end]
                        .copy_from_slice(&old[a * nk..(a + 1) * nk]);
                }
            }
        }
    }

    /// The column elements of row block `kp` whose entries are kept: the
    /// partly visible pairs with more than [`clip::MERGE_ABOVE`] candidate
    /// occluders, whose shadows are merged in a polygon overlay. On the
    /// bunny room they are a tenth of the pairs and about three quarters
    /// of the clipping time; keeping every pair's entries took 0.9 GB more
    /// at the peak of a solve to 1e-3 (8.5 GB against 7.6).
    fn kept(&self, kp: usize) -> impl Iterator<Item = usize> + '_ {
        let row = &self.partial[kp];
        (row.elements.iter())
            .map(|&k| k as usize)
            .filter(move |&k| row.candidates_of(k).len() > clip::MERGE_ABOVE)
    }

    /// Values a store of this plan's partly visible pairs would hold, with
    /// `rows_per(kp)` rows in row block kp (for a memory prediction).
    pub fn partial_entries(&self, rows_per: impl Fn(usize) -> usize) -> u64 {
        let disc = &*self.disc;
        (0..self.partial.len())
            .map(|kp| {
                let cols: usize = self.kept(kp).map(|k| disc.nodes_per(k)).sum();
                (rows_per(kp) * cols) as u64
            })
            .sum()
    }
}
