//! α0: the node parameter for which the interpolatory rule (28) of odd degree r
//! gains one degree of precision (Theorem 7, eq. 36).
//!
//! The defect of the rule on the degree-(r+1) monomials is a smooth function of
//! α on (0, 1/3). We bracket the sign changes of the defect on s^(r+1), bisect
//! each to full precision, and accept a root only if the defect vanishes on
//! *every* degree-(r+1) monomial there. The rule is invariant under the
//! symmetries of the triangle, so the defect lives on the symmetric polynomials
//! of degree r+1 modulo lower degree: one of them (e2) for r = 1, one (e2²) for
//! r = 3, but two (e2³, e3²) for r = 5 — two equations in one unknown, which
//! generically have no common root. When no α0 exists we report the α that
//! minimises the degree-(r+1) defect, with the defect left there as evidence.

use crate::nodes::NodeSet;
use crate::quadrature::monomial_integral;
use serde::Serialize;

/// What the search for α0 found for one degree r.
#[derive(Clone, Debug, Serialize)]
pub struct Alpha0Report {
    /// The polynomial degree r.
    pub degree: usize,
    /// α0 when it exists (odd r only).
    pub alpha0: Option<f64>,
    /// The α in (0, 1/3) minimising the largest relative degree-(r+1) defect
    /// (equal to α0 when α0 exists).
    pub best_alpha: f64,
    /// The largest relative defect on a degree-(r+1) monomial at `best_alpha`.
    pub best_defect: f64,
    /// Degree of precision of the rule at `best_alpha`.
    pub precision_at_best: usize,
    /// Roots of the defect on s^(r+1) that were rejected, with the largest
    /// relative defect on the other monomials there.
    pub rejected_roots: Vec<(f64, f64)>,
    /// Every α in (0, 1/3) at which the rule gains a degree of precision
    /// (all degree-(r+1) defects vanish), with the Lebesgue constant of its
    /// nodes: for odd r these are the α0 of Theorem 7; for even r they keep
    /// the one-triangle precision r + 1 that symmetric pairs would otherwise
    /// supply (Lemma 8), which matters on locally refined, unsymmetric meshes.
    pub roots: Vec<AlphaRoot>,
    /// One sentence saying what was found and why.
    pub reason: String,
}

/// An α that lifts the rule's precision, and how well its nodes interpolate.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct AlphaRoot {
    /// The node parameter.
    pub alpha: f64,
    /// The Lebesgue constant max_σ Σ_j |l_j| of its nodes.
    pub lebesgue: f64,
}

/// A defect this small (relative to the monomial's integral) counts as zero.
const ZERO_DEFECT: f64 = 1e-12;

fn relative_defects(r: usize, alpha: f64) -> Vec<f64> {
    let set = NodeSet::new(r, alpha).expect("alpha inside (0, 1/3)");
    set.defects(r + 1)
        .iter()
        .enumerate()
        .map(|(a, e)| e / monomial_integral(a, r + 1 - a))
        .collect()
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

/// Searches (0, 1/3) for α0 of degree `r` (0 ≤ r ≤ 6).
pub fn find_alpha0(r: usize) -> Alpha0Report {
    if r == 0 {
        return Alpha0Report {
            degree: 0,
            alpha0: None,
            best_alpha: 0.0,
            best_defect: 0.0,
            precision_at_best: 1,
            rejected_roots: vec![],
            roots: vec![],
            reason: "r = 0 has the single centroid node, which does not depend on α (its rule already has degree 1 = r + 1).".into(),
        };
    }
    const SAMPLES: usize = 600;
    let lo = 1e-6;
    let hi = 1.0 / 3.0 - 1e-6;
    let grid: Vec<f64> = (0..=SAMPLES)
        .map(|i| lo + (hi - lo) * i as f64 / SAMPLES as f64)
        .collect();
    let lead = |a: f64| relative_defects(r, a)[r + 1]; // monomial s^(r+1)
    let values: Vec<f64> = grid.iter().map(|&a| lead(a)).collect();

    let mut accepted = Vec::new();
    let mut rejected_roots = Vec::new();
    for i in 0..SAMPLES {
        let (fa, fb) = (values[i], values[i + 1]);
        if fa == 0.0 || fa.signum() != fb.signum() {
            let root = bisect(&lead, grid[i], grid[i + 1]);
            let defect = max_abs(&relative_defects(r, root));
            if defect <= ZERO_DEFECT {
                accepted.push((root, defect));
            } else {
                rejected_roots.push((root, defect));
            }
        }
    }

    // The minimiser of the full defect (also catches a double root).
    let norm = |a: f64| max_abs(&relative_defects(r, a));
    let (ibest, _) =
        grid.iter()
            .map(|&a| norm(a))
            .enumerate()
            .fold(
                (0, f64::INFINITY),
                |b, (i, v)| if v < b.1 { (i, v) } else { b },
            );
    let (mut best_alpha, mut best_defect) = golden_section(
        &norm,
        grid[ibest.saturating_sub(1)],
        grid[(ibest + 1).min(SAMPLES)],
    );
    if accepted.is_empty() && best_defect <= ZERO_DEFECT {
        accepted.push((best_alpha, best_defect));
    }
    let lebesgue = |a: f64| {
        NodeSet::new(r, a)
            .map(|s| s.lebesgue_constant())
            .unwrap_or(f64::INFINITY)
    };
    let mut roots: Vec<AlphaRoot> = accepted
        .iter()
        .map(|&(alpha, _)| AlphaRoot {
            alpha,
            lebesgue: lebesgue(alpha),
        })
        .collect();
    // The best conditioned root first: it is the one "auto" takes.
    roots.sort_by(|a, b| a.lebesgue.total_cmp(&b.lebesgue));
    if let Some(first) = roots.first() {
        best_alpha = first.alpha;
        best_defect = max_abs(&relative_defects(r, best_alpha));
    }
    let precision_at_best = NodeSet::new(r, best_alpha)
        .map(|s| s.precision())
        .unwrap_or(r);

    let (alpha0, reason) = verdict(
        r,
        &roots,
        &rejected_roots,
        best_alpha,
        best_defect,
        precision_at_best,
    );
    Alpha0Report {
        degree: r,
        alpha0,
        best_alpha,
        best_defect,
        precision_at_best,
        rejected_roots,
        roots,
        reason,
    }
}

/// α0 and the sentence that says what the search found: for even r the
/// precision-lifting roots (none is an α0); for odd r the best conditioned
/// accepted root; else the rejected roots as evidence.
fn verdict(
    r: usize,
    roots: &[AlphaRoot],
    rejected_roots: &[(f64, f64)],
    best_alpha: f64,
    best_defect: f64,
    precision_at_best: usize,
) -> (Option<f64>, String) {
    let listed = roots
        .iter()
        .map(|x| format!("α = {:.12} (Lebesgue constant {:.2})", x.alpha, x.lebesgue))
        .collect::<Vec<_>>()
        .join(", ");
    if r.is_multiple_of(2) {
        let lifted = if roots.is_empty() {
            format!(
                "the α minimising the degree-{} defect is {best_alpha:.15}, leaving a relative defect of {best_defect:.3e}",
                r + 1
            )
        } else {
            format!(
                "the rule reaches degree {} on one triangle at {listed}; auto takes the first, the best conditioned",
                r + 1
            )
        };
        (
            None,
            format!(
                "α0 is defined for odd r (Theorem 7); for even r = {r} the node error is O(h^{}) for every α on symmetric meshes (Theorem 9); {lifted}.",
                r + 2,
            ),
        )
    } else if let Some(first) = roots.first() {
        let others = if roots.len() > 1 {
            format!(" Roots: {listed}; auto takes the best conditioned.")
        } else {
            String::new()
        };
        (
            Some(first.alpha),
            format!(
                "At α0 = {:.16} the interpolatory rule integrates every monomial of degree {} to a relative defect of {best_defect:.1e}: its degree of precision rises from {r} to {precision_at_best}.{others}",
                first.alpha,
                r + 1
            ),
        )
    } else {
        let evidence = rejected_roots
            .iter()
            .map(|(a, d)| format!("at α = {a:.12} the defect on s^{} vanishes but another degree-{} monomial keeps a relative defect of {d:.3e}", r + 1, r + 1))
            .collect::<Vec<_>>()
            .join("; ");
        (
            None,
            format!(
                "No α in (0, 1/3) makes the rule exact for all degree-{} monomials: {}{}the smallest achievable relative defect is {best_defect:.3e}, at α = {best_alpha:.15}.",
                r + 1,
                evidence,
                if evidence.is_empty() { "" } else { "; " }
            ),
        )
    }
}

impl Alpha0Report {
    /// The α that "auto" uses: of the α that lift the rule's precision (α0
    /// for odd r), the one whose nodes have the smallest Lebesgue constant;
    /// else the defect minimiser (for r = 0 any α; we return 0.1, which the
    /// centroid node ignores).
    pub fn auto_alpha(&self) -> f64 {
        if self.degree == 0 {
            return 0.1;
        }
        self.roots.first().map_or(self.best_alpha, |x| x.alpha)
    }
}

/// [`Alpha0Report::auto_alpha`] of degree `r`: the search runs once per
/// degree and process (degrees up to `crate::nodes::MAX_DEGREE`; callers
/// that also need the report should call [`find_alpha0`] once and keep it).
pub fn auto_alpha(r: usize) -> f64 {
    use std::sync::OnceLock;
    static AUTO: [OnceLock<f64>; crate::nodes::MAX_DEGREE + 1] =
        [const { OnceLock::new() }; crate::nodes::MAX_DEGREE + 1];
    if r == 0 {
        return 0.1;
    }
    match AUTO.get(r) {
        Some(cell) => *cell.get_or_init(|| find_alpha0(r).auto_alpha()),
        None => find_alpha0(r).auto_alpha(),
    }
}

/// Bisection to full double precision on a bracket with a sign change.
fn bisect(f: &dyn Fn(f64) -> f64, mut a: f64, mut b: f64) -> f64 {
    let mut fa = f(a);
    if fa == 0.0 {
        return a;
    }
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        if m <= a || m >= b {
            break;
        }
        let fm = f(m);
        if fm == 0.0 {
            return m;
        }
        if fm.signum() == fa.signum() {
            a = m;
            fa = fm;
        } else {
            b = m;
        }
    }
    // Of the two final bracket ends, the one with the smaller |f|.
    if f(a).abs() <= f(b).abs() {
        a
    } else {
        b
    }
}

/// Golden-section search for the minimum of a unimodal `f` on [a, b]: (x, f(x)).
fn golden_section(f: &dyn Fn(f64) -> f64, mut a: f64, mut b: f64) -> (f64, f64) {
    let g = (5f64.sqrt() - 1.0) / 2.0;
    let mut c = b - g * (b - a);
    let mut d = a + g * (b - a);
    let (mut fc, mut fd) = (f(c), f(d));
    for _ in 0..200 {
        if (b - a).abs() < 1e-16 {
            break;
        }
        if fc < fd {
            b = d;
            d = c;
            fd = fc;
            c = b - g * (b - a);
            fc = f(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + g * (b - a);
            fd = f(d);
        }
    }
    let x = 0.5 * (a + b);
    (x, f(x))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// α0(1) = 1/6 exactly (the three-point rule at (1/6, 1/6), (2/3, 1/6), (1/6, 2/3)).
    #[test]
    fn alpha0_of_degree_one_is_one_sixth() {
        let rep = find_alpha0(1);
        let a = rep.alpha0.expect("α0(1) exists");
        crate::assert_close!(a, 1.0 / 6.0, 1e-15, "{a}");
        assert_eq!(rep.precision_at_best, 2);
    }

    /// r = 3: α0 exists and lifts the 10-node rule to degree 4 (checked on the
    /// monomials independently of the search).
    #[test]
    fn alpha0_of_degree_three_lifts_precision() {
        let rep = find_alpha0(3);
        let a = rep.alpha0.expect("α0(3) exists");
        assert!(a > 0.0 && a < 1.0 / 3.0);
        let set = NodeSet::new(3, a).unwrap();
        assert_eq!(set.precision(), 4);
        // Away from α0 the rule has degree 3 only.
        assert_eq!(NodeSet::new(3, a + 0.01).unwrap().precision(), 3);
    }

    /// r = 2: the rule gains degree 3 at two α; auto takes the one whose nodes
    /// interpolate better (Lebesgue constant ≈ 4.4 against ≈ 32), and every
    /// reported root lifts the precision (checked on the monomials).
    #[test]
    fn auto_alpha_of_degree_two_is_the_best_conditioned_root() {
        let rep = find_alpha0(2);
        assert!(rep.roots.len() >= 2, "{:?}", rep.roots);
        for root in &rep.roots {
            assert_eq!(NodeSet::new(2, root.alpha).unwrap().precision(), 3);
            let lambda = NodeSet::new(2, root.alpha).unwrap().lebesgue_constant();
            crate::assert_close!(root.lebesgue, lambda, 1e-12);
        }
        let auto = rep.auto_alpha();
        let min = rep
            .roots
            .iter()
            .min_by(|a, b| a.lebesgue.total_cmp(&b.lebesgue))
            .unwrap();
        assert_eq!(auto, min.alpha);
        assert!(min.lebesgue < 5.0 && auto < 0.15, "{min:?}");
        assert!(rep.alpha0.is_none(), "no α0 for even r");
    }

    /// r = 5: two symmetric invariants of degree 6 must vanish at once; the report
    /// states the outcome with the defect left at the best α as evidence.
    #[test]
    fn alpha0_of_degree_five_reports_evidence() {
        let rep = find_alpha0(5);
        match rep.alpha0 {
            Some(a) => assert_eq!(NodeSet::new(5, a).unwrap().precision(), 6),
            None => {
                assert!(rep.best_defect > ZERO_DEFECT);
                assert!(rep.reason.contains("No α"));
                assert_eq!(NodeSet::new(5, rep.best_alpha).unwrap().precision(), 5);
            }
        }
    }

    #[test]
    fn even_degrees_have_no_alpha0() {
        assert!(find_alpha0(2).alpha0.is_none());
        assert!(find_alpha0(0).alpha0.is_none());
    }
}
