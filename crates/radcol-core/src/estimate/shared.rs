//! The estimate over the ranks of a distributed solve: each rank fills
//! the check rows of the elements it owns, and K u_n at the check points is
//! gathered whole before the summaries.

use super::{by_channel, contract, summaries, ChannelFields, ErrorEstimate};
use crate::assembly::{AssemblyPlan, FillMode};
use crate::ranks::Ranks;
use rayon::prelude::*;

/// The estimate (`estimate`), its check rows spread over ranks when `share` gives them
/// and each element's rank: each rank fills and contracts the check rows
/// of its own elements (which its plan `check` classifies), and K u_n at
/// the check points is gathered whole on every rank before the summaries,
/// which every rank computes alike. Every rank calls it together.
pub fn estimate_shared(
    check: &AssemblyPlan,
    channels: &[ChannelFields<'_>],
    share: Option<(&dyn Ranks, &[u32])>,
) -> Vec<ErrorEstimate> {
    let rows = check.rows();
    let ncols = check.dim();
    let n = rows.mesh().len();
    let owner = |k: usize| share.map_or(0, |(_, o)| o[k] as usize);
    let rank = share.map_or(0, |(r, _)| r.rank());
    let mine: Vec<usize> = (0..n).filter(|&k| owner(k) == rank).collect();
    let blocks = mine
        .into_par_iter()
        .map_init(Vec::new, |block, kp| {
            let fc = rows.nodes_per(kp);
            block.resize(fc * ncols, 0.0);
            check.fill_block(kp, &mut block[..fc * ncols], FillMode::All);
            contract(&block[..fc * ncols], fc, ncols, channels)
        })
        .collect();
    let mut ku = by_channel(blocks, channels.len());
    if let Some((ranks, _)) = share.filter(|(r, _)| r.size() > 1) {
        // Every rank's rows, one rank after the other, then put back in
        // element order.
        let mut counts = vec![0; ranks.size()];
        let mut order: Vec<Vec<usize>> = vec![Vec::new(); ranks.size()];
        for k in 0..n {
            counts[owner(k)] += rows.nodes_per(k);
            order[owner(k)].push(k);
        }
        for local in &mut ku {
            let mut all = vec![0.0; rows.len()];
            ranks.gather_all(local, &counts, &mut all);
            *local = vec![0.0; rows.len()];
            let mut at = 0;
            for k in order.iter().flatten() {
                let r = rows.range(*k);
                local[r.clone()].copy_from_slice(&all[at..at + r.len()]);
                at += r.len();
            }
        }
    }
    summaries(check, channels, ku)
}
