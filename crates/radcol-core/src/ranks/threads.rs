//! Ranks as threads of one process, exchanging through shared memory: the
//! distributed solve's code paths, tested without MPI.

use super::{Ranks, Reduce};
use std::sync::{Arc, Barrier, Mutex, PoisonError};
use std::time::Instant;

/// One of `size` ranks that are threads of this process
/// ([`Threads::new`] makes all of them; give one to each thread).
#[derive(Debug)]
pub struct Threads {
    rank: usize,
    shared: Arc<Shared>,
    nanos: std::sync::atomic::AtomicU64,
}

#[derive(Debug)]
struct Shared {
    barrier: Barrier,
    slots: Mutex<Vec<Vec<f64>>>,
}

impl Threads {
    /// `size` ranks (at least one), to be used from `size` threads that
    /// call the same collectives.
    pub fn new(size: usize) -> Vec<Threads> {
        let size = size.max(1);
        let shared = Arc::new(Shared {
            barrier: Barrier::new(size),
            slots: Mutex::new(vec![Vec::new(); size]),
        });
        (0..size)
            .map(|rank| Threads {
                rank,
                shared: shared.clone(),
                nanos: Default::default(),
            })
            .collect()
    }

    /// Every rank's `local`, in rank order, to every rank.
    fn exchange(&self, local: &[f64]) -> Vec<Vec<f64>> {
        let start = Instant::now();
        let lock = || {
            self.shared
                .slots
                .lock()
                .unwrap_or_else(PoisonError::into_inner)
        };
        lock()[self.rank] = local.to_vec();
        self.shared.barrier.wait();
        let all = lock().clone();
        // No rank writes its next contribution before every rank has read.
        self.shared.barrier.wait();
        let spent = start.elapsed().as_nanos() as u64;
        self.nanos
            .fetch_add(spent, std::sync::atomic::Ordering::Relaxed);
        all
    }
}

impl Reduce for Threads {
    /// Summed in rank order, so every rank gets the same bits.
    fn sum(&self, v: &mut [f64]) {
        let all = self.exchange(v);
        for (i, x) in v.iter_mut().enumerate() {
            *x = all.iter().map(|a| a[i]).sum();
        }
    }

    fn max(&self, v: &mut [f64]) {
        let all = self.exchange(v);
        for (i, x) in v.iter_mut().enumerate() {
            *x = all.iter().map(|a| a[i]).fold(f64::NEG_INFINITY, f64::max);
        }
    }
}

impl Ranks for Threads {
    fn rank(&self) -> usize {
        self.rank
    }

    fn size(&self) -> usize {
        self.shared.slots.lock().map_or(1, |s| s.len())
    }

    fn gather_all(&self, local: &[f64], counts: &[usize], all: &mut [f64]) {
        debug_assert_eq!(local.len(), counts[self.rank]);
        let parts = self.exchange(local);
        let mut at = 0;
        for part in parts {
            all[at..at + part.len()].copy_from_slice(&part);
            at += part.len();
        }
    }

    fn owns_its_process(&self) -> bool {
        false
    }

    fn seconds(&self) -> f64 {
        self.nanos.load(std::sync::atomic::Ordering::Relaxed) as f64 * 1e-9
    }
}
