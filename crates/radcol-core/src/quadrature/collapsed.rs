//! Conical-product (collapsed Gauss) rules on σ of any degree: Gauss–Legendre in
//! both directions of the Duffy map (x, y) ↦ (x, (1 - x) y). Positive weights,
//! interior points, exact to the requested degree; used where no cheaper
//! symmetric rule exists (the node weights, and the ladder's fallback).

use super::gauss::gauss_legendre01;
use super::TriangleRule;

/// A rule on σ exact for polynomials of total degree ≤ `degree`.
///
/// ∫_σ f = ∫_0^1 ∫_0^1 f(x, (1-x) y) (1-x) dy dx: the x-integrand has degree
/// `degree + 1`, the y-integrand degree `degree`.
pub fn collapsed_rule(degree: usize) -> TriangleRule {
    let nx = (degree + 2).div_ceil(2);
    let ny = (degree + 1).div_ceil(2).max(1);
    let (xs, wxs) = gauss_legendre01(nx);
    let (ys, wys) = gauss_legendre01(ny);
    let mut points = Vec::with_capacity(nx * ny);
    let mut weights = Vec::with_capacity(nx * ny);
    for (&x, &wx) in xs.iter().zip(&wxs) {
        for (&y, &wy) in ys.iter().zip(&wys) {
            // s = x collapses to the vertex (1, 0) as x → 1.
            points.push([x, (1.0 - x) * y]);
            weights.push(wx * wy * (1.0 - x));
        }
    }
    TriangleRule {
        degree,
        points,
        weights,
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::assert_exact_to_degree;
    use super::*;

    #[test]
    fn collapsed_rules_are_exact() {
        for d in 0..=30 {
            assert_exact_to_degree(&collapsed_rule(d), d);
        }
    }
}
