//! How far an adaptive step may refine within the memory available and
//! the unknowns budget.

use super::{AdaptOptions, StopReason};
use crate::run::size::available_memory;
use crate::run::SolveConfig;

/// While a step assembles, solves and estimates, the previous step's matrix
/// and plans are still held (they count as used in the memory available when
/// the step is planned), and the step's matrix, its linear solver's working
/// memory (an LU factorisation: one more matrix) comes on top. Those may
/// take at most this fraction of the memory available. (While the estimate
/// kept its check rows for the next step, they counted too: the Cornell
/// box to 1e-4 once planned a step of 10.2 GiB whose check rows needed
/// 22.8 GiB more, which the step's own peak check then refused; such a
/// refusal still ends the loop with the previous step's answer.)
const STEP_MEMORY_FRACTION: f64 = 0.8;

/// How many of the marked elements may be split, worst first, or why none
/// may, on a mesh of `elements` elements and `unknowns` unknowns. Each
/// marked element adds at most 3 elements and `growth[i]` unknowns (3 f_r
/// for a split at its degree r; with a degree per element a split that
/// lowers the degree or a raise adds fewer).
pub(super) fn budget(
    opts: &AdaptOptions,
    cfg: &SolveConfig,
    (elements, unknowns): (usize, usize),
    growth: &[usize],
) -> Result<usize, StopReason> {
    let marked = growth.len();
    let mut after = Vec::with_capacity(marked + 1);
    after.push(unknowns as u64);
    for &g in growth {
        after.push(after[after.len() - 1] + g as u64);
    }
    let available = available_memory();
    let solver = match cfg.solver {
        crate::run::SolverKind::Gmres => 0.0,
        crate::run::SolverKind::Lu => 1.0,
    };
    // Where the pipeline may compress (GMRES, not --operator dense), a step
    // whose dense matrix does not fit is solved compressed; the plan's pair
    // table (as expected: pair_table_bytes) is what is known to be needed, and
    // the step's own check after the build ends the loop when the
    // compressed operator leaves too little.
    let may_compress = cfg.solver == crate::run::SolverKind::Gmres
        && cfg.operator != crate::run::OperatorChoice::Dense;
    let fits_memory = |n: u64, elements: usize| {
        if may_compress {
            let pairs = crate::assembly::pair_table_bytes(elements as f64);
            return !cfg.check_memory
                || available.is_none_or(|a| pairs <= STEP_MEMORY_FRACTION * a as f64);
        }
        let bytes = (1.0 + solver) * crate::run::dense_bytes(n);
        !cfg.check_memory || available.is_none_or(|a| bytes <= STEP_MEMORY_FRACTION * a as f64)
    };
    let unknowns = |split: usize| after[split];
    let allowed = |split: usize| {
        opts.max_unknowns.is_none_or(|m| unknowns(split) <= m)
            && fits_memory(unknowns(split), elements + 3 * split)
    };
    if marked == 0 || allowed(marked) {
        return Ok(marked);
    }
    // The largest count that fits (the worst elements first).
    let (mut lo, mut hi) = (0, marked);
    while lo < hi {
        let mid = (lo + hi).div_ceil(2);
        if allowed(mid) {
            lo = mid;
        } else {
            hi = mid - 1;
        }
    }
    if lo > 0 {
        return Ok(lo);
    }
    Err(if opts.max_unknowns.is_some_and(|m| unknowns(1) > m) {
        StopReason::MaxUnknowns
    } else {
        StopReason::Memory
    })
}
