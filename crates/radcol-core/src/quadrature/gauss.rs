//! Gauss–Legendre rules on [0, 1], computed by Newton's method on the
//! three-term recurrence (nodes and weights to within a few ulps).

/// The n-point Gauss–Legendre rule on [0, 1]: (nodes, weights), nodes ascending,
/// weights summing to 1. Exact for polynomials of degree ≤ 2n - 1.
pub fn gauss_legendre01(n: usize) -> (Vec<f64>, Vec<f64>) {
    assert!(n > 0, "a Gauss rule needs at least one point");
    let mut x = vec![0.0; n];
    let mut w = vec![0.0; n];
    for i in 0..n.div_ceil(2) {
        // Tricomi's initial guess for the i-th largest root on [-1, 1].
        let theta = std::f64::consts::PI * (4 * i + 3) as f64 / (4 * n + 2) as f64;
        let mut z = theta.cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (p, d) = legendre_and_derivative(n, z);
            dp = d;
            let dz = p / d;
            z -= dz;
            if dz.abs() <= 1e-16 * z.abs().max(1.0) {
                break;
            }
        }
        let (_, d) = legendre_and_derivative(n, z);
        dp = if d != 0.0 { d } else { dp };
        let weight = 2.0 / ((1.0 - z * z) * dp * dp);
        // Map [-1, 1] -> [0, 1].
        x[n - 1 - i] = 0.5 * (1.0 + z);
        x[i] = 0.5 * (1.0 - z);
        w[n - 1 - i] = 0.5 * weight;
        w[i] = 0.5 * weight;
    }
    (x, w)
}

/// (P_n(z), P_n'(z)) by the Bonnet recurrence.
fn legendre_and_derivative(n: usize, z: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, z);
    for k in 2..=n {
        let k = k as f64;
        let p2 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
    }
    if n == 0 {
        return (1.0, 0.0);
    }
    let d = n as f64 * (z * p1 - p0) / (z * z - 1.0);
    (p1, d)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ∫_0^1 x^k = 1/(k+1) exactly up to degree 2n-1, and not at degree 2n.
    #[test]
    fn exact_to_degree_2n_minus_1() {
        for n in 1..=30 {
            let (x, w) = gauss_legendre01(n);
            for k in 0..2 * n {
                let q: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(k as i32)).sum();
                let exact = 1.0 / (k as f64 + 1.0);
                crate::assert_close!(q, exact, 2e-15, "n={n} k={k}: {q} vs {exact}");
            }
            // At degree 2n the error is the closed form (n!)^4 / ((2n+1) ((2n)!)^2) > 0.
            if n <= 8 {
                let k = 2 * n;
                let q: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(k as i32)).sum();
                let fact = |m: usize| (1..=m).map(|v| v as f64).product::<f64>();
                let err = fact(n).powi(4) / ((2 * n + 1) as f64 * fact(2 * n).powi(2));
                let got = 1.0 / (k as f64 + 1.0) - q;
                assert!(
                    (got - err).abs() < 1e-3 * err + 2e-16,
                    "n={n}: {got} vs {err}"
                );
            }
            assert!(x.windows(2).all(|p| p[0] < p[1]) && x[0] > 0.0 && x[n - 1] < 1.0);
        }
    }
}
