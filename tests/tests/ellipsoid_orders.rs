//! Convergence orders on an ellipsoid with a manufactured solution: E = u - K u
//! with K u from the reference operator (tolerance 1e-14 on a fixed mesh).

use radcol_core::geometry::shapes::ellipsoid;
use radcol_core::problem::{Field, Problem, ReferenceOperator};
use radcol_tests::assert_orders;
use std::sync::Arc;

fn check(r: usize, levels: std::ops::RangeInclusive<u32>) {
    let surface = Arc::new(ellipsoid(1.0, 1.3, 0.8));
    let problem = Problem::manufactured(
        surface.clone(),
        Field::parse("0.4 + 0.1*x - 0.1*z").unwrap(),
        Field::parse("exp(0.3*x + 0.5*y + 0.8*z)").unwrap(),
        ReferenceOperator::new(surface, 2),
    );
    assert_orders("ellipsoid", &problem, r, levels);
}

#[test]
fn ellipsoid_degree_1_at_alpha0() {
    check(1, 2..=4);
}

#[test]
fn ellipsoid_degree_2() {
    check(2, 2..=4);
}
