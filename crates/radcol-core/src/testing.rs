//! Test support shared by the tests of every crate (compiled for core's own
//! tests and with the `conformance` feature): the one tolerance check, which
//! names what differs, both values, the difference and the tolerance.

/// Panics unless |got - want| ≤ tol, naming `label`, both values, the
/// difference, the tolerance and the optional `context`.
#[track_caller]
pub fn check_close(label: &str, got: f64, want: f64, tol: f64, context: Option<String>) {
    let diff = (got - want).abs();
    assert!(
        diff <= tol,
        "{label}: got {got:.17e}, want {want:.17e}, |diff| = {diff:.3e} > tol {tol:.3e}{}",
        context.map(|c| format!(" ({c})")).unwrap_or_default()
    );
}

/// Panics unless |got - want| ≤ tol at element `index` of a sequence.
#[track_caller]
pub fn assert_close(label: &str, index: usize, got: f64, want: f64, tol: f64) {
    check_close(&format!("{label}[{index}]"), got, want, tol, None);
}

/// A number the tolerance check reads as f64 (f64, f32 and references to them).
pub trait Number: Copy {
    /// The value as f64.
    fn to_f64(self) -> f64;
}

impl Number for f64 {
    fn to_f64(self) -> f64 {
        self
    }
}

impl Number for f32 {
    fn to_f64(self) -> f64 {
        self as f64
    }
}

impl<T: Number> Number for &T {
    fn to_f64(self) -> f64 {
        (*self).to_f64()
    }
}

/// `assert_close!(got, want, tol)` or `assert_close!(got, want, tol, "fmt", args..)`:
/// [`check_close`] labelled with the expression of `got`.
#[macro_export]
macro_rules! assert_close {
    ($got:expr, $want:expr, $tol:expr $(,)?) => {
        $crate::testing::check_close(
            stringify!($got),
            $crate::testing::Number::to_f64($got),
            $crate::testing::Number::to_f64($want),
            $tol,
            None,
        )
    };
    ($got:expr, $want:expr, $tol:expr, $($fmt:tt)+) => {
        $crate::testing::check_close(
            stringify!($got),
            $crate::testing::Number::to_f64($got),
            $crate::testing::Number::to_f64($want),
            $tol,
            Some(format!($($fmt)+)),
        )
    };
}

/// A reproducible stream of numbers in [0, 1) (xorshift64, 53 bits) for
/// random test configurations: the same `seed` gives the same stream.
pub fn uniform(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed;
    move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn close_values_pass_and_far_ones_name_the_difference() {
        check_close("x", 1.0, 1.0 + 1e-13, 1e-12, None);
        crate::assert_close!(2.0_f64.sqrt(), std::f64::consts::SQRT_2, 0.0);
        let err = std::panic::catch_unwind(|| check_close("x", 1.0, 2.0, 0.5, Some("at P".into())))
            .unwrap_err();
        let msg = err.downcast_ref::<String>().unwrap();
        assert!(
            msg.contains("x: got") && msg.contains("> tol") && msg.contains("(at P)"),
            "{msg}"
        );
    }
}
