//! Bounded approximate visibility of the bounce pairs.
//!
//! A partly visible pair (row point P, element e) whose element emits
//! nothing may have its visibility V(P, ·) on e replaced by a constant
//! Ṽ ∈ [0, 1] (the fraction of a few rays from P to points of e that no
//! candidate blocks; [`visible_fraction`]). The entries of e's columns in
//! P's row then change by at most the pair's unoccluded mass
//! m(P, e) = (1/π) ∫_e G(P, Q) dQ times max |u| on e, whatever V is, since
//! |V − Ṽ| ≤ 1. Per row point the masses of the approximated pairs add up to
//! at most a budget τ ([`choose`]: the smallest first), so the residual of
//! the approximate solution differs from the exact-visibility one by at most
//! ρ(P) τ max|u| at every row point (the emitters' columns, the direct
//! light, keep exact visibility), and the solution by at most
//! ρ_max τ max|u| / (1 − ρ_max) (the operator's rows sum to at most ρ_max):
//! what the estimate adds ([`crate::estimate::ErrorEstimate::visibility_bound`]).
//!
//! The masses are bounded, not integrated ([`mass_bound`]), so the budget
//! holds however close the element is; pairs whose bound exceeds τ stay
//! exact. Measured on the bunny room at r = 1 on its own triangles
//! (`cargo run --release -p radcol-benches --example partial_mass`, masses
//! integrated and weighted by ρ), most partly visible pairs have small
//! masses: a budget of 1e-3 per point would cover 61 % of them with the
//! whole bunny, 1e-2 87 %; with these bounds and unweighted masses, 1e-3
//! covers 36 % (docs/visibility.md).

use super::Plane;
use super::{clip, Occluders};
use glam::DVec3;

/// What a plan may approximate.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Bounce<'a> {
    /// Per row point, the most unoccluded mass of approximated pairs.
    pub(crate) budget: f64,
    /// Per element: whether its pairs may be approximated (it emits
    /// nothing).
    pub(crate) columns: &'a [bool],
    /// Per row point, what pairs taken from a previous plan already spend
    /// (empty: nothing).
    pub(crate) spent: &'a [f64],
}

/// The relative tolerance of an approximated pair's unoccluded integral:
/// its error, at most this share of the pair's mass, is far below the mass
/// that bounds the visibility's (the plan's bound adds it).
pub(crate) const APPROX_TOL: f64 = 1e-6;

/// Pieces per edge of [`mass_bound`]'s split of an element.
const BOUND_PIECES: usize = 4;

/// An upper bound of m(P, e) = (1/π) ∫_e G(P, Q) dQ over the flat element
/// e = (vertices, unit normal), from the point `p` with unit normal `n_p`.
/// On e, (P − Q)·n_e = h is constant and (Q − P)·n_P is linear in Q, so on
/// each of [`BOUND_PIECES`]² pieces of e, G = h [(Q − P)·n_P]⁺ / |P − Q|⁴ ≤
/// h max over the piece's corners of [(v − P)·n_P]⁺ / d⁴ with d the distance
/// from P to the piece's bounding ball; infinite when P lies in one.
pub(crate) fn mass_bound(p: DVec3, n_p: DVec3, (v, n_e): Plane) -> f64 {
    let h = (p - v[0]).dot(n_e);
    if h <= 0.0 || v.iter().all(|&x| (x - p).dot(n_p) <= 0.0) {
        return 0.0;
    }
    let m = BOUND_PIECES;
    let step = 1.0 / m as f64;
    let at = |s: f64, t: f64| v[0] + (v[1] - v[0]) * s + (v[2] - v[0]) * t;
    let area = 0.5 * (v[1] - v[0]).cross(v[2] - v[0]).length() * step * step;
    let piece = |c: [DVec3; 3]| {
        let lift = c.iter().map(|&x| (x - p).dot(n_p)).fold(0.0, f64::max);
        let mid = (c[0] + c[1] + c[2]) / 3.0;
        let radius = c.iter().map(|&x| (x - mid).length()).fold(0.0, f64::max);
        let d = (p - mid).length() - radius;
        match (lift > 0.0, d > 0.0) {
            (false, _) => 0.0,
            (true, false) => f64::INFINITY,
            (true, true) => area * h * lift / d.powi(4),
        }
    };
    let mut sum = 0.0;
    for i in 0..m {
        for j in 0..m - i {
            let (s, t) = (i as f64 * step, j as f64 * step);
            sum += piece([at(s, t), at(s + step, t), at(s, t + step)]);
            if i + j + 1 < m {
                sum += piece([at(s + step, t), at(s + step, t + step), at(s, t + step)]);
            }
        }
    }
    sum / std::f64::consts::PI
}

/// A partly visible pair set aside for [`choose`]: the element, its
/// candidate occluders and its mass bound at each row point.
#[derive(Debug)]
pub(crate) struct Deferred {
    pub(crate) k: u32,
    pub(crate) cands: Vec<u32>,
    pub(crate) mass: Vec<f64>,
}

/// Splits `deferred` into the pairs to approximate and the rest (each
/// ascending by element): the pairs with the smallest largest mass first,
/// each taken while every row point's sum, from what is `spent` already
/// (empty: nothing), stays within `budget`.
pub(crate) fn choose(
    mut deferred: Vec<Deferred>,
    spent: &[f64],
    budget: f64,
) -> (Vec<Deferred>, Vec<Deferred>) {
    let largest = |d: &Deferred| d.mass.iter().copied().fold(0.0, f64::max);
    deferred.sort_by(|a, b| largest(a).total_cmp(&largest(b)));
    let rows = deferred.first().map_or(0, |d| d.mass.len());
    let mut sums = match spent.is_empty() {
        true => vec![0.0; rows],
        false => spent.to_vec(),
    };
    let (mut chosen, mut rest) = (Vec::new(), Vec::new());
    for d in deferred {
        if sums.iter().zip(&d.mass).all(|(s, m)| s + m <= budget) {
            sums.iter_mut().zip(&d.mass).for_each(|(s, m)| *s += m);
            chosen.push(d);
        } else {
            rest.push(d);
        }
    }
    chosen.sort_by_key(|d| d.k);
    rest.sort_by_key(|d| d.k);
    (chosen, rest)
}

/// The fraction of four rays from `p` to points of the triangle `v` (its
/// centroid and the midpoints between it and each vertex:
/// [`clip::ray_targets`]) that none of the occluders `cands` blocks.
pub(crate) fn visible_fraction(p: DVec3, v: &[DVec3; 3], occ: &Occluders, cands: &[u32]) -> f64 {
    let targets = clip::ray_targets(v);
    let seen = targets
        .iter()
        .filter(|&&q| !cands.iter().any(|&i| clip::blocks(p, q, occ.get(i))))
        .count();
    seen as f64 / targets.len() as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The mass bound is at least the mass, integrated independently with a
    /// fine midpoint rule, for random triangles and points in front of them
    /// (near and far), and zero when either side faces away.
    #[test]
    fn the_mass_bound_bounds_the_mass() {
        let mut unit = crate::testing::uniform(0x6a09e667f3bcc909);
        let mut rnd = || unit() - 0.5;
        let mut tight = 0usize;
        for case in 0..400 {
            let v = [0, 1, 2].map(|_| DVec3::new(rnd(), rnd(), 0.2 * rnd()));
            let n_e = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
            let far = if case % 2 == 0 { 1.0 } else { 8.0 };
            let p =
                (v[0] + v[1] + v[2]) / 3.0 + far * (n_e + 0.5 * DVec3::new(rnd(), rnd(), rnd()));
            let n_p = DVec3::new(rnd(), rnd(), rnd()).normalize();
            let exact = midpoint_mass(p, n_p, &v, n_e);
            let bound = mass_bound(p, n_p, (v, n_e));
            assert!(bound >= exact * (1.0 - 1e-12), "{case}: {bound} < {exact}");
            if exact > 0.0 && bound < 3.0 * exact {
                tight += 1;
            }
        }
        // Not vacuous: within 3x of the mass in many cases (the far ones).
        assert!(tight > 100, "{tight}");
        let v = [DVec3::ZERO, DVec3::X, DVec3::Y];
        let above = DVec3::new(0.2, 0.2, 3.0);
        assert_eq!(mass_bound(above, DVec3::Z, (v, DVec3::Z)), 0.0);
        assert_eq!(mass_bound(-above, DVec3::Z, (v, DVec3::Z)), 0.0);
        assert!(mass_bound(above, -DVec3::Z, (v, DVec3::Z)) > 0.0);
    }

    /// (1/π) ∫ G over triangle v by the midpoint rule on 256² pieces.
    fn midpoint_mass(p: DVec3, n_p: DVec3, v: &[DVec3; 3], n_e: DVec3) -> f64 {
        let m = 256;
        let h = 1.0 / m as f64;
        let piece = 0.5 * (v[1] - v[0]).cross(v[2] - v[0]).length() * h * h;
        let mut sum = 0.0;
        for i in 0..m {
            for j in 0..m - i {
                let mut at = vec![(i as f64 * h + h / 3.0, j as f64 * h + h / 3.0)];
                if i + j + 1 < m {
                    at.push((i as f64 * h + 2.0 * h / 3.0, j as f64 * h + 2.0 * h / 3.0));
                }
                for (s, t) in at {
                    let q = v[0] + (v[1] - v[0]) * s + (v[2] - v[0]) * t;
                    sum += crate::kernel::g(p, n_p, q, n_e) * piece;
                }
            }
        }
        sum / std::f64::consts::PI
    }

    /// Pairs are taken smallest first while every row point's sum fits.
    #[test]
    fn choose_takes_the_smallest_within_the_budget() {
        let d = |k: u32, mass: [f64; 2]| Deferred {
            k,
            cands: vec![k],
            mass: mass.to_vec(),
        };
        let all = vec![
            d(3, [0.4, 0.1]),
            d(1, [0.1, 0.5]),
            d(2, [0.05, 0.05]),
            d(0, [0.6, 0.0]),
        ];
        let (chosen, rest) = choose(all, &[], 0.6);
        let ks = |v: &[Deferred]| v.iter().map(|d| d.k).collect::<Vec<_>>();
        // 2 (0.05), then 3 (0.4: sums 0.45, 0.15), then 1 (0.5: 0.55, 0.65 > 0.6) no, 0 no.
        assert_eq!(ks(&chosen), [2, 3]);
        assert_eq!(ks(&rest), [0, 1]);
        // What a previous plan spent counts: with 0.5 spent at the first
        // point only 2 (0.05) fits there.
        let again = vec![d(3, [0.4, 0.1]), d(2, [0.05, 0.05])];
        let (chosen, _) = choose(again, &[0.5, 0.0], 0.6);
        assert_eq!(ks(&chosen), [2]);
    }
}
