//! Ranks over MPI's world communicator (the `mpi` crate, rsmpi).

use super::{Ranks, Reduce};
use mpi::collective::SystemOperation;
use mpi::datatype::PartitionMut;
use mpi::environment::Universe;
use mpi::topology::SimpleCommunicator;
use mpi::traits::{Communicator, CommunicatorCollectives};
use mpi::Threading;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// MPI, initialised for as long as it lives (dropped: finalised), and this
/// process's place in the world communicator.
pub struct MpiSession {
    _universe: Universe,
    world: std::sync::Arc<Mpi>,
    local: usize,
}

impl std::fmt::Debug for MpiSession {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MpiSession")
            .field("world", &self.world)
            .field("local", &self.local)
            .finish_non_exhaustive()
    }
}

impl MpiSession {
    /// Initialises MPI (once per process), asking that any thread may call
    /// it as long as calls do not overlap (`Threading::Serialized`). A
    /// process started without `mpirun` is a world of one.
    ///
    /// # Errors
    /// One line when MPI was initialised already, or cannot give that
    /// level of thread support.
    pub fn start() -> Result<Self, String> {
        let (universe, level) = mpi::initialize_with_threading(Threading::Serialized)
            .ok_or("MPI was initialised already in this process")?;
        if level < Threading::Serialized {
            return Err(format!(
                "the MPI library offers thread support {level:?}; radcol needs Serialized"
            ));
        }
        let world = Mpi::world();
        Ok(Self {
            _universe: universe,
            local: world.local,
            world: std::sync::Arc::new(world),
        })
    }

    /// This process among the world's ranks.
    pub fn world(&self) -> std::sync::Arc<Mpi> {
        self.world.clone()
    }

    /// Ranks on this machine (sharing its memory and cores), this one
    /// included.
    pub fn local_size(&self) -> usize {
        self.local
    }

    /// Whether every rank of the world reaches this call within `wait`
    /// (a non-blocking barrier, polled): when all fail alike (bad input
    /// is the same on every rank), each can end by itself; when one fails
    /// alone, the others are elsewhere and it must end them
    /// ([`MpiSession::abort`]).
    pub fn all_here(&self, wait: std::time::Duration) -> bool {
        let start = Instant::now();
        let mut request = SimpleCommunicator::world().immediate_barrier();
        loop {
            match request.test() {
                Ok(_) => return true,
                Err(pending) if start.elapsed() < wait => {
                    request = pending;
                    std::thread::sleep(std::time::Duration::from_millis(5));
                }
                Err(pending) => {
                    // Never completed: the process is about to abort, and
                    // dropping an incomplete request panics.
                    std::mem::forget(pending);
                    return false;
                }
            }
        }
    }

    /// Ends every rank of the world at once with `code` (MPI_Abort): what a
    /// rank that fails alone does, so that the others, waiting for it in a
    /// collective operation, do not hang.
    pub fn abort(&self, code: i32) -> ! {
        SimpleCommunicator::world().abort(code)
    }
}

/// This process among MPI's world communicator. MPI must have been
/// initialised (`mpi::initialize_with_threading`, at least
/// `Threading::Serialized`: radcol calls MPI from one thread at a time,
/// not always the main one) and not yet finalised while it is used.
#[derive(Debug)]
pub struct Mpi {
    rank: usize,
    size: usize,
    local: usize,
    nanos: AtomicU64,
}

impl Mpi {
    /// This process in the world communicator (every rank calls it
    /// together: finding the ranks on this machine is collective).
    pub fn world() -> Self {
        let w = SimpleCommunicator::world();
        Self {
            rank: w.rank() as usize,
            size: w.size() as usize,
            local: w.split_shared(0).size() as usize,
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

    fn local_size(&self) -> usize {
        self.local
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
