//! Progress observers for long stages (plan, assembly, solve), so that a
//! caller can draw a bar. A floor-level module: every stage may report to it,
//! and it imports nothing from the crate.

use std::sync::Arc;

/// Observer of a solve's progress, for progress bars. Called from worker
/// threads; must be cheap.
pub trait Progress: Send + Sync {
    /// A stage starts ("plan", "assembly", "estimate": row blocks, "solve": channels);
    /// `total` units of work follow.
    fn start(&self, stage: &str, total: u64);
    /// `n` more units of the current stage are done.
    fn advance(&self, n: u64);
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
}
