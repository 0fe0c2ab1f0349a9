//! Convergence orders on the unit sphere against closed-form solutions.
//!
//! On the unit sphere with inner normals G ≡ 1/4 (Lemma 1d), so
//! K u(P) = ρ(P)/(4π) ∫_S u. With E = exp(a·P) and ρ = 0.5 + 0.2 x:
//! ∫_S E = 4π sinh|a|/|a| and ∫_S ρ = 2π, so I = ∫ u = ∫E / (1 - ∫ρ/4π) = 2∫E
//! and u = E + ρ I/(4π) = E + 2ρ sinh|a|/|a| exactly.
//!
//! Theory: global error O(h^{r+1}) (eq. 23); at the nodes O(h^{r+3} log h) for odd
//! r at α0 (36) and O(h^{r+2}) for even r (39). The node bounds are upper bounds:
//! on a closed surface the leading term largely cancels (only the patch seams of
//! the octahedral parametrisation contribute) and the observed node orders are
//! higher, so they are checked as lower bounds; global orders are checked within
//! 0.3 of r + 1 over three levels in the asymptotic range.

use radcol_tests::{assert_orders, sphere_closed_form};

fn check(r: usize, levels: std::ops::RangeInclusive<u32>) {
    assert_orders("sphere", &sphere_closed_form(), r, levels);
}

#[test]
fn sphere_degree_1_at_alpha0() {
    check(1, 2..=4);
}

#[test]
fn sphere_degree_2() {
    // Levels 2..4: at α = 0.109 (auto, the best conditioned root) level 1 is
    // not yet asymptotic (global order 2.7 from level 1 to 2), though its errors
    // are smaller than at α = 0.232 on every level (3.5e-4 against 6.4e-4 at level 4).
    check(2, 2..=4);
}

#[test]
fn sphere_degree_3_at_alpha0() {
    check(3, 2..=4);
}
