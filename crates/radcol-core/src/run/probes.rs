//! Shadow probes of the error estimate: points inside a shadow of the
//! direct light that falls on an element between its check points.
//!
//! The estimate samples the residual η = E + ρ K u_n − u_n at each
//! element's check points. A small occluder can cast a shadow that falls
//! wholly between them (an object far smaller than the floor triangle it
//! stands on): η is large there, u_n being interpolated from nodes in the
//! light, and neither the element's figure nor the maximum saw it, so an
//! adaptive solve stopped with the shadow missing. Here, for every pair of
//! an element with an emitting element whose visible part is clipped
//! exactly, the shadows that the pair's candidate occluders cast from the
//! emitting element's centroid are found on the element
//! ([`clip::shadow_pieces`]). When none of them holds a check point, the
//! largest pieces (not holding an earlier probe) get a probe at their
//! centroid, where η is evaluated with the row of K at that point
//! ([`PointEvaluator::row`]) and raises the element's figure and the
//! maximum ([`ErrorEstimate::add_probe`]); the adaptive loop then splits
//! the element until check points fall in the shadow.

use super::ChannelResult;
use crate::assembly::point::PointEvaluator;
use crate::assembly::{AssemblyPlan, QuadratureOptions};
use crate::discretization::Discretization;
use crate::estimate::ErrorEstimate;
use crate::mesh::Located;
use crate::problem::Problem;
use crate::visibility::{clip, VisibilityAnalysis};
use rayon::prelude::*;
use std::sync::Arc;

/// At most so many probes per pair of an element and an emitting element,
/// the largest pieces first.
const PER_PAIR: usize = 2;

/// At most so many probes per element.
const PER_ELEMENT: usize = 8;

/// A point where η is evaluated besides the check points.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Probe {
    pub(crate) element: usize,
    pub(crate) st: [f64; 2],
}

/// The probes of the elements of `square`'s discretization (the solve's
/// plan), with `check` its check points and `emitting` which elements emit;
/// of the elements `owned` alone when given (a rank's, whose rows its plan
/// classified: [`gather`] collects every rank's).
pub(crate) fn find(
    square: &AssemblyPlan,
    check: &Discretization,
    emitting: &[bool],
    owned: Option<&[bool]>,
) -> Vec<Probe> {
    let Some(occ) = square.occluders() else {
        return Vec::new();
    };
    let mesh = square.discretization().mesh();
    (0..mesh.len())
        .into_par_iter()
        .flat_map_iter(|b| {
            let mut taken: Vec<[f64; 2]> = Vec::new();
            if mesh.is_flat(b) && owned.is_none_or(|o| o[b]) {
                let v = mesh.vertices(b);
                let checks: Vec<[f64; 2]> = check.points()[check.range(b)]
                    .iter()
                    .map(|p| p.st)
                    .collect();
                for (c, cands) in square.clipped_pairs(b) {
                    if !emitting[c] || cands.is_empty() || taken.len() >= PER_ELEMENT {
                        continue;
                    }
                    let light = mesh.point(c, 1.0 / 3.0, 1.0 / 3.0);
                    let mut pieces =
                        clip::shadow_pieces(light.position, light.normal, &v, occ, cands);
                    // A shadow that holds a check point is seen by the
                    // check points already.
                    let in_shadow = |q: &[f64; 2]| pieces.iter().any(|x| clip::contains(x, *q));
                    if checks.iter().any(in_shadow) {
                        continue;
                    }
                    pieces.sort_by(|x, y| clip::area(y).total_cmp(&clip::area(x)));
                    let mut added = 0;
                    for piece in &pieces {
                        if added == PER_PAIR || taken.len() == PER_ELEMENT {
                            break;
                        }
                        if !taken.iter().any(|q| clip::contains(piece, *q)) {
                            taken.push(clip::centroid(piece));
                            added += 1;
                        }
                    }
                }
            }
            taken.into_iter().map(move |st| Probe { element: b, st })
        })
        .collect()
}

/// Every rank's probes ([`find`] of the elements it owns) with their η per
/// channel ([`etas`]), on every rank, in element order as one process
/// finds them.
pub(crate) fn gather(
    ranks: &dyn crate::ranks::Ranks,
    (mine, etas): (&[Probe], &[Vec<f64>]),
    channels: usize,
) -> (Vec<Probe>, Vec<Vec<f64>>) {
    let width = 3 + channels;
    let flat: Vec<f64> = mine
        .iter()
        .zip(etas)
        .flat_map(|(p, eta)| {
            [p.element as f64, p.st[0], p.st[1]]
                .into_iter()
                .chain(eta.iter().copied())
        })
        .collect();
    let counts: Vec<usize> = ranks
        .gather_each(flat.len() as f64)
        .into_iter()
        .map(|c| c as usize)
        .collect();
    let mut all = vec![0.0; counts.iter().sum()];
    ranks.gather_all(&flat, &counts, &mut all);
    let mut found: Vec<(Probe, Vec<f64>)> = all
        .chunks_exact(width)
        .map(|p| {
            let probe = Probe {
                element: p[0] as usize,
                st: [p[1], p[2]],
            };
            (probe, p[3..].to_vec())
        })
        .collect();
    // Each element's probes come from one rank, in the order found.
    found.sort_by_key(|(p, _)| p.element);
    found.into_iter().unzip()
}

/// Adds η at each probe (per channel, [`etas`]) to its channel's estimate.
pub(crate) fn add(probes: &[Probe], etas: &[Vec<f64>], estimates: &mut [ErrorEstimate]) {
    for (pr, eta) in probes.iter().zip(etas) {
        for (est, &eta) in estimates.iter_mut().zip(eta) {
            est.add_probe(pr.element, eta);
        }
    }
}

/// |η| of every channel at each of `probes` (one vector per probe).
pub(crate) fn etas(
    probes: &[Probe],
    (disc, quad, visibility): (
        &Arc<Discretization>,
        &QuadratureOptions,
        &VisibilityAnalysis,
    ),
    problem: &Problem,
    channels: &[ChannelResult],
) -> Vec<Vec<f64>> {
    if probes.is_empty() {
        return Vec::new();
    }
    let eval = PointEvaluator::new(disc.clone(), quad.clone(), visibility);
    let mesh = disc.mesh();
    probes
        .par_iter()
        .map(|pr| {
            let ([s, t], k) = (pr.st, pr.element);
            let point = mesh.point(k, s, t);
            let at = Located {
                element: k,
                st: pr.st,
                position: point.position,
                normal: point.normal,
                distance: 0.0,
            };
            let (row, _) = eval.row(&at);
            let site = mesh.site(k, s, t);
            channels
                .iter()
                .zip(&problem.channels)
                .map(|(ch, fields)| {
                    let nodal = ch.solution.nodal();
                    let ku: f64 = row.iter().zip(nodal).map(|(a, b)| a * b).sum();
                    let (rho, e) = (fields.rho.eval(&site), fields.emission.eval(&site));
                    (e + rho * ku - ch.solution.eval(k, s, t)).abs()
                })
                .collect()
        })
        .collect()
}

/// Which elements emit: E > 0 at one of their nodes in some channel.
pub(crate) fn emitting(disc: &Discretization, channels: &[ChannelResult]) -> Vec<bool> {
    (0..disc.mesh().len())
        .map(|k| {
            let r = disc.range(k);
            channels
                .iter()
                .any(|ch| ch.emission[r.clone()].iter().any(|&e| e > 0.0))
        })
        .collect()
}
