//! Errors of a collocation solution against an exact u: at the nodes, over all
//! of S (a fixed lattice of interior and edge points of every element, not the
//! nodes) and in L².

use crate::problem::Field;
use crate::quadrature::RuleLadder;
use crate::solution::Solution;
use rayon::prelude::*;
use serde::Serialize;

/// Subdivisions of each element edge for the global-max lattice: the points
/// (a/M, b/M), a + b ≤ M, include vertices, edge points and interior points.
pub const LATTICE: usize = 8;

// The limiter's lattice holds this one: no point counted here is left negative.
const _: () = assert!(crate::solution::LIMITER_LATTICE.is_multiple_of(LATTICE));

/// Error norms of u - u_n.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ErrorNorms {
    /// max_i |u(v_i) - u_n(v_i)| over the collocation nodes.
    pub nodes_max: f64,
    /// max |u - u_n| over the lattice of every element.
    pub global_max: f64,
    /// (∫_S (u - u_n)²)^½.
    pub l2: f64,
}

/// Errors of `sol` against `exact`.
pub fn error_norms(sol: &Solution, exact: &Field) -> ErrorNorms {
    let disc = sol.discretization();
    let mesh = disc.mesh();
    let nodes_max = disc
        .points()
        .par_iter()
        .zip(sol.nodal())
        .map(|(p, &v)| (exact.eval(&mesh.site(p.element, p.st[0], p.st[1])) - v).abs())
        .reduce(|| 0.0, f64::max);
    // Squares are summed in units of max |u_n|: no overflow at u ~ 1e160.
    let unit = match sol.nodal().iter().fold(0.0f64, |m, u| m.max(u.abs())) {
        m if m > 0.0 => m,
        _ => 1.0,
    };
    let ladder = RuleLadder::new();
    let rule = ladder.rule(2 * disc.max_degree() + 8);
    let (global_max, l2sq) = (0..mesh.len())
        .into_par_iter()
        .map(|k| {
            let mut gmax: f64 = 0.0;
            for a in 0..=LATTICE {
                for b in 0..=(LATTICE - a) {
                    let (s, t) = (a as f64 / LATTICE as f64, b as f64 / LATTICE as f64);
                    let e = exact.eval(&mesh.site(k, s, t)) - sol.eval(k, s, t);
                    gmax = gmax.max(e.abs());
                }
            }
            let mut l2 = 0.0;
            for (&[s, t], &w) in rule.points.iter().zip(&rule.weights) {
                let site = mesh.site(k, s, t);
                let e = (exact.eval(&site) - sol.eval(k, s, t)) / unit;
                l2 += w * mesh.point(k, s, t).jacobian * e * e;
            }
            (gmax, l2)
        })
        .reduce(|| (0.0, 0.0), |a, b| (a.0.max(b.0), a.1 + b.1));
    ErrorNorms {
        nodes_max,
        global_max,
        l2: l2sq.sqrt() * unit,
    }
}
