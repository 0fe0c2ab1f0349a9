//! Ranks over MPI's world communicator (the `mpi` crate, rsmpi).

use super::{Ranks, Reduce};
use mpi::collective::SystemOperation;
use mpi::datatype::PartitionMut;
use mpi::topology::SimpleCommunicator;
use mpi::traits::{Communicator, CommunicatorCollectives};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// This process among MPI's world communicator. MPI must have been
/// initialised (`mpi::initialize_with_threading`, at least
/// `Threading::Serialized`: radcol calls MPI from one thread at a time,
/// not always the main one) and not yet finalised while it is used.
#[derive(Debug)]
pub struct Mpi {
    rank: usize,
    size: usize,
    nanos: AtomicU64,
}

impl Mpi {
    /// This process in the world communicator.
    pub fn world() -> Self {
        let w = SimpleCommunicator::world();
        Self {
            rank: w.rank() as usize,
            size: w.size() as usize,
            nanos: AtomicU64::new(0),
        }
    }

    /// Runs `f` on the world communicator, counting its time.
    fn timed<T>(&self, f: impl FnOnce(&SimpleCommunicator) -> T) -> T {
        let start = Instant::now();
        let out = f(&SimpleCommunicator::world());
        self.nanos
            .fetch_add(start.elapsed().as_nanos() as u64, Ordering::Relaxed);
        out
    }
}

impl Reduce for Mpi {
    fn sum(&self, v: &mut [f64]) {
        let local = v.to_vec();
        self.timed(|w| w.all_reduce_into(&local[..], v, SystemOperation::sum()));
    }

    fn max(&self, v: &mut [f64]) {
        let local = v.to_vec();
        self.timed(|w| w.all_reduce_into(&local[..], v, SystemOperation::max()));
    }
}

impl Ranks for Mpi {
    fn rank(&self) -> usize {
        self.rank
    }

    fn size(&self) -> usize {
        self.size
    }

    fn gather_all(&self, local: &[f64], counts: &[usize], all: &mut [f64]) {
        let counts: Vec<i32> = counts.iter().map(|&c| c as i32).collect();
        let displs: Vec<i32> = counts
            .iter()
            .scan(0, |at, &c| {
                let d = *at;
                *at += c;
                Some(d)
            })
            .collect();
        self.timed(|w| {
            let mut part = PartitionMut::new(all, &counts[..], &displs[..]);
            w.all_gather_varcount_into(local, &mut part);
        });
    }

    fn seconds(&self) -> f64 {
        self.nanos.load(Ordering::Relaxed) as f64 * 1e-9
    }
}
