//! The processes of a distributed solve ("ranks"): who this process is,
//! how many there are, and the few collective operations a distributed
//! solve needs. Every rank holds the scene, the mesh and the cluster trees
//! (replicated, built deterministically); each assembles and stores only
//! its share of the compressed operator's block rows
//! (`crate::run::RowShare`), and GMRES runs on every rank's rows at
//! once, its dot products summed over the ranks.
//!
//! `Mpi` (feature `mpi`) runs over MPI's world communicator through the
//! `mpi` crate (rsmpi). [`Threads`] runs the same collectives between
//! threads of one process, so that the distributed code paths are tested
//! without an MPI installation.

#[cfg(feature = "mpi")]
mod mpi;
mod threads;

#[cfg(feature = "mpi")]
pub use self::mpi::{Mpi, MpiSession};
pub use threads::Threads;

pub use crate::solve::{Alone, Reduce};

/// The ranks of a distributed solve, seen from one of them. Every rank
/// must call the same collective operations in the same order.
pub trait Ranks: Reduce + Send + Sync + std::fmt::Debug {
    /// This process's rank, 0-based.
    fn rank(&self) -> usize;
    /// How many ranks take part.
    fn size(&self) -> usize;
    /// How many of them share this machine's memory, this one included
    /// (each plans for its part of the memory available).
    fn local_size(&self) -> usize {
        self.size()
    }
    /// Every rank's `local` (rank p's of length `counts[p]`), one after
    /// the other in rank order, into `all` (of length the sum of `counts`).
    fn gather_all(&self, local: &[f64], counts: &[usize], all: &mut [f64]);
    /// Seconds this rank has spent in collective operations so far,
    /// waiting for the other ranks included.
    fn seconds(&self) -> f64;
    /// Whether this rank is a process of its own, so that the process's
    /// CPU seconds are this rank's (`RankFigures::work_cpu_s`); false for
    /// ranks that share one process.
    fn owns_its_process(&self) -> bool {
        true
    }
}

/// CPU seconds this process has run so far, all its threads together
/// (Linux: the sum of `/proc/self/task/*/schedstat`'s run times, in
/// nanoseconds); None where the platform does not say. Unlike wall time,
/// it does not grow while ranks sharing a core wait for it, so it measures
/// a rank's own work when ranks outnumber cores.
pub(crate) fn cpu_seconds() -> Option<f64> {
    let tasks = std::fs::read_dir("/proc/self/task").ok()?;
    let mut nanos = 0u64;
    for task in tasks.flatten() {
        let text = std::fs::read_to_string(task.path().join("schedstat")).ok()?;
        nanos += text.split_whitespace().next()?.parse::<u64>().ok()?;
    }
    Some(nanos as f64 * 1e-9)
}

impl dyn Ranks + '_ {
    /// One number from every rank, in rank order.
    pub fn gather_each(&self, value: f64) -> Vec<f64> {
        let mut all = vec![0.0; self.size()];
        self.gather_all(&[value], &vec![1; self.size()], &mut all);
        all
    }
}
