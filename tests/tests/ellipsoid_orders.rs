//! Convergence orders on an ellipsoid with a manufactured solution: E = u - K u
//! with K u from the reference operator (tolerance 1e-14 on a fixed mesh).

use radcol_tests::{assert_orders, ellipsoid_manufactured};

fn check(r: usize, levels: std::ops::RangeInclusive<u32>) {
    assert_orders("ellipsoid", &ellipsoid_manufactured(), r, levels);
}

#[test]
fn ellipsoid_degree_1_at_alpha0() {
    check(1, 2..=4);
}

#[test]
fn ellipsoid_degree_2() {
    check(2, 2..=4);
}
