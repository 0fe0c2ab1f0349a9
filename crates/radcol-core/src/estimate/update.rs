//! The estimate of an adaptive step updated from the previous step's,
//! instead of computed afresh.
//!
//! Computing K u_n at every check point costs as much as assembling the
//! matrix (on the Cornell box to 3e-4, 15 of the last step's 20 s, with
//! two elements split), and a step that splits few elements changes u_n
//! little away from them. With the previous step's K u_old at its check
//! points and the change Δ = u_n - g, g the previous solution on the new
//! mesh (the adaptive loop's initial guess: u_old on unchanged elements,
//! the parent's polynomial on children),
//!
//! ```text
//! K u_n = K u_old + K Δ        at the check points of unchanged elements,
//! ```
//!
//! since ∫ over a parent of G u_old is the sum over its children of ∫ G g
//! (to the quadrature tolerance). K Δ is computed over the columns of new
//! elements and of unchanged elements where Δ is not small; the rest is
//! bounded, not computed: |∫_rest G V Δ / π| ≤ max_rest sup|Δ| (the form
//! factors from a point sum to at most 1), sup|Δ| on an element at most the
//! node set's Lebesgue constant times its largest nodal |Δ|. New elements'
//! check rows are computed whole. The bound accumulates over updates
//! (`ErrorEstimate::check_ku_drift`), and what it can move the figures is
//! reported (`ErrorEstimate::updated_within`), not added to them: added,
//! it raised every element by up to 4 % of the marking threshold at the
//! default allowance, and elements that would have stayed below it were
//! split (the Cornell box to 3e-4: 21 steps against 18, to 28 689 unknowns
//! against 27 132). Where the drift would pass what the caller allows, or
//! where the update would fill more than `UPDATE_SHARE` of the pairs a
//! fresh estimate fills, the caller computes afresh.

use super::{by_channel, contract, summaries, ChannelFields, ErrorEstimate};
use crate::assembly::AssemblyPlan;
use crate::discretization::Discretization;
use crate::nodes::NodeSet;
use rayon::prelude::*;

/// Above this share of a fresh estimate's pairs (the rows of new elements
/// against every column, the rest against the columns filled: new
/// elements and unchanged ones whose change is not small) an update is not
/// worth it: the estimate is computed afresh.
pub const UPDATE_SHARE: f64 = 0.8;

/// The estimate of every channel on the mesh of `check` (a plan
/// [`AssemblyPlan::at_points`] updated from the previous step's, so that it
/// knows which elements are unchanged), updated from `previous` (the
/// previous step's estimates, channel by channel) with `change` (per
/// channel, u_n - g at the nodes: g the previous solution on this mesh).
/// `within` is how far (relative to max |u_n| of each channel) the figures
/// may be from the computed ones. None where that cannot be kept, or where
/// the update would fill more than `UPDATE_SHARE` of the pairs.
pub fn estimate_updated(
    check: &AssemblyPlan,
    channels: &[ChannelFields<'_>],
    previous: &[&ErrorEstimate],
    change: &[Vec<f64>],
    within: f64,
) -> Option<Vec<ErrorEstimate>> {
    let unchanged = check.unchanged()?;
    if previous.len() != channels.len() || change.len() != channels.len() {
        return None;
    }
    let disc = check.discretization();
    let n = disc.mesh().len();
    let lebesgue = max_lebesgue(disc);
    let lebesgue_check = max_lebesgue(check.rows());
    let old_rows = check.previous_row_offsets()?;
    // Per channel: the drift allowed in K u_n, and what this update may add.
    let mut budgets = Vec::with_capacity(channels.len());
    for ((ch, prev), delta) in channels.iter().zip(previous).zip(change) {
        let scale = ch
            .solution
            .nodal()
            .iter()
            .fold(0.0f64, |m, u| m.max(u.abs()));
        let rho = ch.rho.iter().fold(0.0f64, |m, r| m.max(r.abs()));
        if prev.check_ku.len() != old_rows[unchanged.old_len()] || delta.len() != disc.len() {
            return None;
        }
        // |η - η_computed| ≤ Λ_c ρ drift at every point of an element.
        let allowed = if rho > 0.0 {
            within * scale / (lebesgue_check * rho)
        } else {
            f64::INFINITY
        };
        let left = allowed - prev.check_ku_drift;
        if left.is_nan() || left <= 0.0 {
            return None;
        }
        budgets.push((left / 2.0, lebesgue_check * rho));
    }
    // The columns filled: new elements, and unchanged ones whose change in
    // some channel exceeds half what that channel has left; the others'
    // largest change is what this update adds.
    let mut wanted = vec![false; n];
    let mut added = vec![0.0f64; channels.len()];
    for (k, w) in wanted.iter_mut().enumerate() {
        if unchanged.old(k).is_none() {
            *w = true;
            continue;
        }
        let sups: Vec<f64> = change
            .iter()
            .map(|delta| {
                let nodal = delta[disc.range(k)].iter();
                lebesgue * nodal.fold(0.0f64, |m, d| m.max(d.abs()))
            })
            .collect();
        *w = sups.iter().zip(&budgets).any(|(s, b)| *s > b.0);
        if !*w {
            for (a, s) in added.iter_mut().zip(&sups) {
                *a = a.max(*s);
            }
        }
    }
    let filled = wanted.iter().filter(|&&w| w).count() as f64;
    let new = (0..n).filter(|&k| unchanged.old(k).is_none()).count() as f64;
    let n = n as f64;
    if (n - new) * filled + new * n > UPDATE_SHARE * n * n {
        return None;
    }
    let ku = updated_ku(check, channels, previous, change, &wanted);
    let mut estimates = summaries(check, channels, ku);
    // Quadrature: a parent's integral against its children's, both to the
    // check rows' tolerance relative to a row that sums to at most 1.
    let quad = check.options().tol;
    for (c, e) in estimates.iter_mut().enumerate() {
        let scale = channels[c]
            .solution
            .nodal()
            .iter()
            .fold(0.0f64, |m, u| m.max(u.abs()));
        e.check_ku_drift = previous[c].check_ku_drift + added[c] + 2.0 * quad * scale;
        e.updated_within = Some(budgets[c].1 * e.check_ku_drift);
    }
    Some(estimates)
}

/// K u_n at every check point, per channel: new elements' rows computed
/// whole; unchanged elements' from the previous value plus K Δ over the
/// `wanted` columns.
fn updated_ku(
    check: &AssemblyPlan,
    channels: &[ChannelFields<'_>],
    previous: &[&ErrorEstimate],
    change: &[Vec<f64>],
    wanted: &[bool],
) -> Vec<Vec<f64>> {
    let unchanged = check.unchanged().expect("checked by the caller");
    let old_rows = check.previous_row_offsets().expect("with unchanged");
    let n = wanted.len();
    let disc = check.discretization();
    let ncols = check.dim();
    let columns: Vec<usize> = (0..n).filter(|&k| wanted[k]).collect();
    let blocks = (0..n)
        .into_par_iter()
        .map_init(Vec::new, |block, kp| {
            let fc = check.rows().nodes_per(kp);
            block.resize(fc * ncols, 0.0);
            let block = &mut block[..fc * ncols];
            match unchanged.old(kp) {
                None => {
                    check.fill_block(kp, block, crate::assembly::FillMode::All);
                    contract(block, fc, ncols, channels)
                }
                Some(op) => {
                    check.fill_columns(kp, block, wanted);
                    let mut out = Vec::with_capacity(channels.len() * fc);
                    for (prev, delta) in previous.iter().zip(change) {
                        for a in 0..fc {
                            let row = &block[a * ncols..(a + 1) * ncols];
                            let kd: f64 = columns
                                .iter()
                                .flat_map(|&k| disc.range(k))
                                .map(|j| row[j] * delta[j])
                                .sum();
                            out.push(prev.check_ku[old_rows[op] + a] + kd);
                        }
                    }
                    out
                }
            }
        })
        .collect();
    by_channel(blocks, channels.len())
}

/// The largest Lebesgue constant of `disc`'s node sets.
fn max_lebesgue(disc: &Discretization) -> f64 {
    disc.node_sets()
        .iter()
        .map(NodeSet::lebesgue_constant)
        .fold(0.0, f64::max)
}
