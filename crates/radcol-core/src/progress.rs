//! Progress observers for long stages (plan, assembly, solve), so that a
//! caller can draw a bar, and stop a solve: [`Progress::cancelled`] is asked
//! between stages, at every row block of the plan and the CPU assembly, and
//! at every GMRES iteration, and a solve it stops returns
//! [`crate::error::Error::Cancelled`]. A floor-level module: every stage may
//! report to it, and it imports nothing from the crate.

use std::sync::Arc;

/// Observer of a solve's progress, for progress bars. Called from worker
/// threads; must be cheap.
pub trait Progress: Send + Sync {
    /// A stage starts ("plan", "assembly", "estimate": row blocks; "solve":
    /// decades of the relative residual, `solve_decades` per channel);
    /// `total` units of work follow.
    fn start(&self, stage: &str, total: u64);
    /// `n` more units of the current stage are done.
    fn advance(&self, n: u64);
    /// True once the caller wants the solve stopped (asked often: must be
    /// cheap, an atomic load).
    fn cancelled(&self) -> bool {
        false
    }
}

/// Decades of the relative residual a channel's solve counts in the
/// "solve" stage: GMRES advances one per decade its residual falls (its
/// iterations per decade are roughly even, so the bar moves evenly), LU all
/// at once.
pub fn solve_decades(rel_tol: f64) -> u64 {
    if rel_tol > 0.0 && rel_tol < 1.0 {
        (-rel_tol.log10()).ceil().clamp(1.0, 20.0) as u64
    } else {
        1
    }
}

/// A shared [`Progress`] observer.
#[derive(Clone)]
pub struct ProgressHandle(pub Arc<dyn Progress>);

impl std::fmt::Debug for ProgressHandle {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("ProgressHandle")
    }
}

impl ProgressHandle {
    /// Starts a stage of `total` units.
    pub fn start(&self, stage: &str, total: u64) {
        self.0.start(stage, total)
    }
    /// Reports `n` more units done.
    pub fn advance(&self, n: u64) {
        self.0.advance(n)
    }
    /// Whether the caller wants the solve stopped.
    pub fn cancelled(&self) -> bool {
        self.0.cancelled()
    }
}

/// A [`Progress`] that draws nothing and stops a solve when asked:
/// [`Cancel::cancel`] from any thread, and the solve holding its handle
/// ([`Cancel::handle`]) returns [`crate::error::Error::Cancelled`] at its
/// next check (per row block, per GMRES iteration, between stages).
#[derive(Debug, Default)]
pub struct Cancel(std::sync::atomic::AtomicBool);

impl Cancel {
    /// A flag not yet set, shared.
    pub fn new() -> Arc<Self> {
        Arc::new(Self::default())
    }

    /// Asks the solve to stop.
    pub fn cancel(&self) {
        self.0.store(true, std::sync::atomic::Ordering::Relaxed);
    }

    /// The handle to give the solve.
    pub fn handle(self: &Arc<Self>) -> ProgressHandle {
        ProgressHandle(self.clone())
    }
}

impl Progress for Cancel {
    fn start(&self, _stage: &str, _total: u64) {}
    fn advance(&self, _n: u64) {}
    fn cancelled(&self) -> bool {
        self.0.load(std::sync::atomic::Ordering::Relaxed)
    }
}
