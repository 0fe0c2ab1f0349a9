//! Test support: one shared context per test binary, and the skip-or-fail rule.
//!
//! A GPU test calls [`test_context`]: without an adapter it prints why and the
//! test returns early (skips), so CPU-only machines still pass; with
//! `RADCOL_REQUIRE_GPU=1` (CI with lavapipe installed) a missing adapter fails
//! the test instead.

use crate::context::{AdapterFilter, GpuContext};
use std::sync::{Arc, OnceLock};

/// Environment variable that turns "no adapter" from a skip into a failure.
pub const REQUIRE_GPU_ENV: &str = "RADCOL_REQUIRE_GPU";

/// True when `RADCOL_REQUIRE_GPU` is set to something other than "" or "0".
pub fn gpu_required() -> bool {
    std::env::var(REQUIRE_GPU_ENV).is_ok_and(|v| !v.is_empty() && v != "0")
}

/// The shared context (any adapter, lavapipe included), or `None` after
/// printing why `test` is skipped.
///
/// # Panics
/// When no adapter exists and [`gpu_required`], or when an adapter exists but
/// its device or pipelines fail (a real failure, never a skip).
pub fn test_context(test: &str) -> Option<Arc<GpuContext>> {
    static CTX: OnceLock<Result<Arc<GpuContext>, (bool, String)>> = OnceLock::new();
    let ctx = CTX.get_or_init(|| {
        GpuContext::new(AdapterFilter::Any)
            .map(Arc::new)
            .map_err(|e| (e.is_no_adapter(), e.to_string()))
    });
    match ctx {
        Ok(c) => Some(c.clone()),
        Err((true, msg)) if !gpu_required() => {
            println!("SKIPPED {test}: {msg}");
            None
        }
        Err((true, msg)) => panic!("{test}: {REQUIRE_GPU_ENV} is set but {msg}"),
        Err((false, msg)) => panic!("{test}: the GPU adapter exists but failed: {msg}"),
    }
}
