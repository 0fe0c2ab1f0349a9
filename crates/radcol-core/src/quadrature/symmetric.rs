//! Fully symmetric quadrature rules on the unit simplex σ, degrees 1..=[`MAX_DEGREE`].
//!
//! # What
//!
//! [`symmetric_rule`] returns a rule on σ = {(s, t) : s, t ≥ 0, s + t ≤ 1} that is
//! invariant under all six permutations of the barycentric coordinates
//! (λ1, λ2, λ3) = (1 − s − t, s, t), has **all weights positive** and **all points
//! strictly inside** σ ("PI" rules), and integrates every polynomial of total
//! degree ≤ its `degree` exactly. Weights sum to 1/2, the area of σ.
//!
//! # Why symmetric rules
//!
//! For a given degree, fully symmetric rules are among the cheapest known PI
//! rules on the triangle (79 points for degree 20 against 121 for the 11 × 11
//! conical product), and because the point set does not depend on how the
//! vertices of a mesh triangle are numbered, the quadrature error does not
//! either — the assembled matrices keep the symmetries of the mesh.
//!
//! # Source
//!
//! H. Xiao and Z. Gimbutas, "A numerical algorithm for the construction of
//! efficient quadrature rules in two and higher dimensions", *Computers &
//! Mathematics with Applications* **59**(2) (2010) 663–676,
//! doi:10.1016/j.camwa.2009.10.027. Their triangle rules are fully symmetric
//! with positive weights and interior nodes for every degree. Their tables are
//! distributed in machine-readable form by J. Burkardt (TRIANGLE_SYMQ_RULE); the
//! numbers here (16–17 significant digits: the IEEE doubles of the tables) were
//! transcribed from the copy in FEniCS/basix, `cpp/basix/quadrature.cpp`
//! (`make_xiao_gimbutas_quadrature`, MIT licence), and are stored in our own
//! orbit form in `symmetric_data.rs`; see that file for the layout.
//!
//! Point counts, degrees 1–30: 1, 3, 6, 6, 7, 12, 15, 16, 19, 25, 28, 33, 37,
//! 42, 49, 55, 60, 67, 73, 79, 87, 96, 103, 112, 120, 130, 141, 150, 159, 171.
//! The degree-3 entry of the tables is the 6-point degree-4 rule, so
//! `symmetric_rule(3)` returns that rule with `degree == 4`; every other degree
//! 1..=30 gets the rule of exactly that degree, and degree 0 the 1-point
//! centroid rule (degree 1).
//!
//! # Verification
//!
//! The tests below check, for every rule: every monomial s^a t^b with
//! a + b ≤ degree against the closed form a! b! / (a + b + 2)! to 1e-14 relative
//! — this catches a mistyped digit down to about the 13th decimal place (a
//! change of 1e-13 in one coordinate of the degree-20 rule already gives a
//! moment error of 8e-14); that some monomial of degree `degree + 1` is *not*
//! integrated exactly (the stated degree is the true one); positivity, strict
//! interiority and the weight sum; closure of the point set under the six
//! barycentric permutations with matching weights; and the point counts against
//! the published ones.
//!
//! The last digits, below the resolution of a double-precision moment test, were
//! checked once offline in 50-digit arithmetic: every table's moment equations
//! (all monomials of degree ≤ its degree) have full column rank in the orbit
//! parameters, so each rule is locally unique, and the minimum-norm Newton
//! correction towards the exact rule is at most 2.1e-16 in any orbit
//! coordinate or weight (a few ulps) — the stored doubles are the exact rules
//! to within the accuracy of the published tables.

#[path = "symmetric_data.rs"]
mod symmetric_data;

use super::TriangleRule;
use std::sync::OnceLock;
use symmetric_data::{OrbitRule, RULES};

/// The highest degree available.
pub const MAX_DEGREE: usize = 30;

/// The fully symmetric PI rule (Xiao–Gimbutas) of degree of precision `degree`,
/// or `None` if `degree > MAX_DEGREE`.
///
/// Returns the cheapest stored rule whose degree is ≥ `degree`, with
/// [`TriangleRule::degree`] set to its true degree of precision. That is the rule
/// of exactly `degree` for every `degree` in 1..=30 except 3, for which the
/// published 6-point rule is the degree-4 rule (so `degree == 4` is reported);
/// `degree == 0` gives the 1-point centroid rule (degree 1).
pub fn symmetric_rule(degree: usize) -> Option<TriangleRule> {
    if degree > MAX_DEGREE {
        return None;
    }
    table().iter().find(|r| r.degree >= degree).cloned()
}

/// All stored rules, expanded once, by increasing degree.
fn table() -> &'static [TriangleRule] {
    static TABLE: OnceLock<Vec<TriangleRule>> = OnceLock::new();
    TABLE.get_or_init(|| RULES.iter().map(expand).collect())
}

/// Expands one orbit-form rule into points `(s, t) = (λ2, λ3)`.
fn expand(rule: &OrbitRule) -> TriangleRule {
    let mut points = Vec::with_capacity(rule.points);
    let mut weights = Vec::with_capacity(rule.points);
    if let Some(w) = rule.centroid {
        points.push([1.0 / 3.0, 1.0 / 3.0]);
        weights.push(w);
    }
    for &[a, w] in rule.s21 {
        let b = 1.0 - 2.0 * a;
        // (λ1, λ2, λ3) ∈ {(a, a, b), (a, b, a), (b, a, a)}.
        for p in [[a, b], [b, a], [a, a]] {
            points.push(p);
            weights.push(w);
        }
    }
    for &[a, b, w] in rule.s111 {
        let c = 1.0 - a - b;
        // All six orderings of (a, b, c) as (λ2, λ3); λ1 is the remaining one.
        for p in [[a, b], [b, a], [a, c], [c, a], [b, c], [c, b]] {
            points.push(p);
            weights.push(w);
        }
    }
    debug_assert_eq!(points.len(), rule.points);
    TriangleRule {
        degree: rule.degree,
        points,
        weights,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Published point counts of the Xiao–Gimbutas triangle rules, degrees 1..=30.
    const PUBLISHED_COUNTS: [usize; 30] = [
        1, 3, 6, 6, 7, 12, 15, 16, 19, 25, 28, 33, 37, 42, 49, 55, 60, 67, 73, 79, 87, 96, 103,
        112, 120, 130, 141, 150, 159, 171,
    ];

    /// ∫_σ s^a t^b = a! b! / (a + b + 2)! = 1 / (C(a+b, a) (a+b+1) (a+b+2)),
    /// with the integer denominator formed exactly (it is < 2^53 for a + b ≤ 31),
    /// independently of the crate's own `monomial_integral`.
    fn exact_moment(a: usize, b: usize) -> f64 {
        let n = (a + b) as u128;
        let mut binom: u128 = 1;
        for i in 0..a as u128 {
            binom = binom * (n - i) / (i + 1);
        }
        let den = binom * (n + 1) * (n + 2);
        assert!(den < (1u128 << 53));
        1.0 / den as f64
    }

    fn moment(rule: &TriangleRule, a: usize, b: usize) -> f64 {
        rule.points
            .iter()
            .zip(&rule.weights)
            .map(|(&[s, t], &w)| w * s.powi(a as i32) * t.powi(b as i32))
            .sum()
    }

    /// Relative error of the rule on s^a t^b.
    fn moment_error(rule: &TriangleRule, a: usize, b: usize) -> f64 {
        let exact = exact_moment(a, b);
        (moment(rule, a, b) - exact).abs() / exact
    }

    /// The worst relative moment error over all monomials of degree ≤ `d`.
    fn worst_error_to_degree(rule: &TriangleRule, d: usize) -> (f64, usize, usize) {
        let mut worst = (0.0, 0, 0);
        for deg in 0..=d {
            for a in 0..=deg {
                let e = moment_error(rule, a, deg - a);
                if e > worst.0 {
                    worst = (e, a, deg - a);
                }
            }
        }
        worst
    }

    fn all_rules() -> Vec<TriangleRule> {
        (1..=MAX_DEGREE)
            .map(|d| symmetric_rule(d).expect("rule exists"))
            .collect()
    }

    #[test]
    fn every_monomial_up_to_the_degree_is_exact() {
        for rule in all_rules() {
            let (e, a, b) = worst_error_to_degree(&rule, rule.degree);
            assert!(
                e <= 1e-14,
                "degree {} rule: s^{a} t^{b} has relative error {e:e}",
                rule.degree
            );
        }
    }

    #[test]
    fn degree_is_not_understated() {
        for rule in all_rules() {
            let d = rule.degree + 1;
            let worst = (0..=d)
                .map(|a| moment_error(&rule, a, d - a))
                .fold(0.0, f64::max);
            assert!(
                // 100× the exactness tolerance: the degree-29 rule comes closest,
                // with a worst degree-30 error of about 1e-9.
                worst > 1e-12,
                "degree {} rule is also exact for degree {d} (worst {worst:e})",
                rule.degree
            );
        }
    }

    #[test]
    fn positive_weights_interior_points_unit_area() {
        for rule in all_rules() {
            assert_eq!(rule.points.len(), rule.weights.len());
            assert!(
                rule.weights.iter().all(|&w| w > 0.0),
                "degree {}",
                rule.degree
            );
            for &[s, t] in &rule.points {
                assert!(
                    s > 0.0 && t > 0.0 && s + t < 1.0 && 1.0 - s - t > 0.0,
                    "degree {}: point ({s}, {t}) not strictly inside",
                    rule.degree
                );
            }
            let total: f64 = rule.weights.iter().sum();
            assert!(
                (total - 0.5).abs() < 1e-15,
                "degree {}: weights sum to {total}",
                rule.degree
            );
        }
    }

    #[test]
    fn point_set_is_closed_under_barycentric_permutations() {
        const PERMS: [[usize; 3]; 6] = [
            [0, 1, 2],
            [0, 2, 1],
            [1, 0, 2],
            [1, 2, 0],
            [2, 0, 1],
            [2, 1, 0],
        ];
        for rule in all_rules() {
            for (&[s, t], &w) in rule.points.iter().zip(&rule.weights) {
                let lam = [1.0 - s - t, s, t];
                for p in PERMS {
                    let (ps, pt) = (lam[p[1]], lam[p[2]]);
                    let matches = rule
                        .points
                        .iter()
                        .zip(&rule.weights)
                        .filter(|(&[u, v], _)| (u - ps).abs() < 1e-14 && (v - pt).abs() < 1e-14)
                        .collect::<Vec<_>>();
                    assert_eq!(
                        matches.len(),
                        1,
                        "degree {}: image ({ps}, {pt}) of ({s}, {t}) found {} times",
                        rule.degree,
                        matches.len()
                    );
                    assert!(
                        (matches[0].1 - w).abs() <= 1e-16 * w,
                        "degree {}: weight mismatch at ({ps}, {pt})",
                        rule.degree
                    );
                }
            }
        }
    }

    #[test]
    fn point_counts_match_the_published_ones() {
        for d in 1..=MAX_DEGREE {
            let rule = symmetric_rule(d).unwrap();
            if d == 3 {
                // The published degree-3 rule is the 6-point degree-4 rule.
                assert_eq!(rule.degree, 4);
            } else {
                assert_eq!(rule.degree, d);
            }
            assert_eq!(rule.len(), PUBLISHED_COUNTS[d - 1], "degree {d}");
        }
        // The orbit tables agree with their own stated counts.
        for r in RULES {
            let n = usize::from(r.centroid.is_some()) + 3 * r.s21.len() + 6 * r.s111.len();
            assert_eq!(n, r.points, "degree {}", r.degree);
        }
    }

    #[test]
    fn degree_zero_and_out_of_range() {
        let r0 = symmetric_rule(0).unwrap();
        assert_eq!(r0.degree, 1);
        assert_eq!(r0.points, vec![[1.0 / 3.0, 1.0 / 3.0]]);
        assert_eq!(r0.weights, vec![0.5]);
        assert!(symmetric_rule(MAX_DEGREE).is_some());
        assert!(symmetric_rule(MAX_DEGREE + 1).is_none());
        assert!(symmetric_rule(usize::MAX).is_none());
    }

    #[test]
    fn rules_are_sorted_and_cheapest_first() {
        for pair in RULES.windows(2) {
            assert!(pair[0].degree < pair[1].degree);
            assert!(pair[0].points <= pair[1].points);
        }
        assert_eq!(RULES.last().unwrap().degree, MAX_DEGREE);
    }

    /// The exactness check is sharp enough to catch a single wrong digit: perturb
    /// one orbit coordinate or weight in the 10th decimal place and it must fail.
    #[test]
    fn exactness_check_detects_a_mistyped_digit() {
        for d in [6, 13, 20, 30] {
            let good = symmetric_rule(d).unwrap();
            // Perturb the points of the last 6-point orbit ...
            let mut bad = good.clone();
            let k = bad.points.len() - 6;
            for p in &mut bad.points[k..] {
                for x in p.iter_mut() {
                    *x += 1e-10 * x.signum();
                }
            }
            assert!(worst_error_to_degree(&bad, d).0 > 1e-14, "degree {d}");
            // ... or one weight of one orbit.
            let mut bad = good.clone();
            for w in &mut bad.weights[k..] {
                *w *= 1.0 + 1e-10;
            }
            assert!(worst_error_to_degree(&bad, d).0 > 1e-14, "degree {d}");
        }
    }
}
