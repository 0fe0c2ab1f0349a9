//! Quadrature on the unit simplex σ = {(s, t) : s, t ≥ 0, s + t ≤ 1}.
//!
//! * [`symmetric`]: fully symmetric published rules, the cheapest per degree.
//! * [`collapsed`]: conical-product rules of any degree (and square rules for
//!   vertex-collapsed integrands).
//! * [`RuleLadder`]: one rule per degree 1..=[`MAX_RULE_DEGREE`], the menu the
//!   assembly plan picks far-pair rules from.

pub mod collapsed;
pub mod gauss;
pub mod symmetric;

/// The highest degree of precision in the `RuleLadder`.
pub const MAX_RULE_DEGREE: usize = 30;

/// A quadrature rule on the unit simplex σ: `∫_σ f ≈ Σ_q weights[q] · f(points[q])`.
///
/// Weights sum to 1/2 (the area of σ); `degree` is the degree of precision
/// (every polynomial of total degree ≤ `degree` is integrated exactly).
#[derive(Clone, Debug, PartialEq)]
pub struct TriangleRule {
    /// Degree of precision.
    pub degree: usize,
    /// Points `(s, t)` in σ.
    pub points: Vec<[f64; 2]>,
    /// Weights, one per point, summing to 1/2.
    pub weights: Vec<f64>,
}

impl TriangleRule {
    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True when the rule has no points.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }
}

/// The cheapest positive interior rule of each degree 1..=[`MAX_RULE_DEGREE`]:
/// the symmetric table where it has one, else the collapsed rule.
#[derive(Clone, Debug)]
pub struct RuleLadder {
    rules: Vec<TriangleRule>,
}

impl Default for RuleLadder {
    fn default() -> Self {
        Self::new()
    }
}

impl RuleLadder {
    /// Builds all rules (microseconds).
    pub fn new() -> Self {
        let rules = (0..=MAX_RULE_DEGREE)
            .map(|d| {
                let collapsed = collapsed::collapsed_rule(d);
                match symmetric::symmetric_rule(d) {
                    Some(s) if s.len() <= collapsed.len() => s,
                    _ => collapsed,
                }
            })
            .collect();
        Self { rules }
    }

    /// The rule for degree `d` (clamped to [`MAX_RULE_DEGREE`]); `d = 0` gives the
    /// cheapest rule of degree ≥ 0.
    pub fn rule(&self, d: usize) -> &TriangleRule {
        &self.rules[d.min(MAX_RULE_DEGREE)]
    }
}

/// ∫_σ s^a t^b = a! b! / (a + b + 2)!.
pub fn monomial_integral(a: usize, b: usize) -> f64 {
    let mut v = 1.0;
    // a! b! / (a+b+2)! = 1 / [(a+b+2)! / (a! b!)], computed as a product of ratios.
    for i in 1..=b {
        v *= i as f64 / (a + i) as f64;
    }
    // now v = a! b! / (a+b)!
    v / ((a + b + 1) as f64 * (a + b + 2) as f64)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Every monomial of degree ≤ d is integrated to 1e-14 relative.
    pub(crate) fn assert_exact_to_degree(rule: &TriangleRule, d: usize) {
        let total: f64 = rule.weights.iter().sum();
        crate::assert_close!(total, 0.5, 1e-14, "weights sum to {total}");
        assert!(rule.weights.iter().all(|&w| w > 0.0));
        assert!(rule
            .points
            .iter()
            .all(|&[s, t]| s > 0.0 && t > 0.0 && s + t < 1.0));
        for deg in 0..=d {
            for a in 0..=deg {
                let b = deg - a;
                let q: f64 = rule
                    .points
                    .iter()
                    .zip(&rule.weights)
                    .map(|(&[s, t], w)| w * s.powi(a as i32) * t.powi(b as i32))
                    .sum();
                let exact = monomial_integral(a, b);
                assert!(
                    (q - exact).abs() <= 1e-14 * exact.max(1e-3),
                    "degree {d} rule: s^{a} t^{b}: {q} vs {exact}"
                );
            }
        }
    }

    #[test]
    fn monomial_integrals() {
        crate::assert_close!(monomial_integral(0, 0), 0.5, 1e-16);
        crate::assert_close!(monomial_integral(1, 0), 1.0 / 6.0, 1e-16);
        crate::assert_close!(monomial_integral(1, 1), 1.0 / 24.0, 1e-16);
        crate::assert_close!(monomial_integral(2, 3), 2.0 * 6.0 / 5040.0, 1e-18);
    }

    #[test]
    fn ladder_rules_reach_their_degree() {
        let ladder = RuleLadder::new();
        for d in 0..=MAX_RULE_DEGREE {
            let r = ladder.rule(d);
            assert!(r.degree >= d);
            assert_exact_to_degree(r, d);
        }
    }
}
