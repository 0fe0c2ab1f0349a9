//! The true relative residual of a computed solution, independent of how
//! the solver measured its own.

use super::LinearOperator;

/// ‖b - A x‖ / ‖b‖ (‖A x‖-free: 0 when b = 0 and x = 0).
pub fn true_residual(op: &dyn LinearOperator, x: &[f64], b: &[f64]) -> f64 {
    // Relative residuals do not change when x and b are scaled together; at
    // max |b_i| = 1 the sums of squares neither overflow nor underflow.
    let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let scale = if scale > 0.0 { scale } else { 1.0 };
    let xs: Vec<f64> = x.iter().map(|v| v / scale).collect();
    let mut ax = vec![0.0; b.len()];
    op.apply(&xs, &mut ax);
    let num: f64 = ax
        .iter()
        .zip(b)
        .map(|(a, b)| (b / scale - a) * (b / scale - a))
        .sum::<f64>()
        .sqrt();
    let den: f64 = b
        .iter()
        .map(|v| (v / scale) * (v / scale))
        .sum::<f64>()
        .sqrt();
    if den > 0.0 {
        num / den
    } else {
        num
    }
}
