//! Interpolation nodes q_ij(α) on σ (eq. 13), their Lagrange basis (eq. 14), the
//! interpolatory weights ω_j (eq. 16) and the rule's degree of precision.
//!
//! The nodes are the uniform lattice of step 1/r on the shrunken triangle with
//! vertices (α, α), (1 - 2α, α), (α, 1 - 2α). In barycentric coordinates λ of that
//! triangle, the basis function of the node with lattice indices (i, j, r-i-j) is
//! the product formula
//!
//!   l_ij = P_i(λ_s) P_j(λ_t) P_{r-i-j}(λ_u),   P_m(λ) = Π_{k<m} (r λ - k)/(k + 1),
//!
//! which is exact, needs no linear solve and is stable for every r ≤ 6.

use crate::error::InputError;
use crate::quadrature::{collapsed::collapsed_rule, monomial_integral};

/// Largest polynomial degree supported.
pub const MAX_DEGREE: usize = 6;

/// 1/m for m = 1..=MAX_DEGREE (the basis recurrences multiply by it rather
/// than divide: they run at every rule point of the near and self pairs).
const INV_M: [f64; MAX_DEGREE + 1] = [0.0, 1.0, 0.5, 1.0 / 3.0, 0.25, 0.2, 1.0 / 6.0];

/// Lattice step 1/`LEBESGUE_GRID` of the samples that locate Λ's maximum.
const LEBESGUE_GRID: usize = 240;

/// Best samples refined by compass search.
const LEBESGUE_STARTS: usize = 12;

/// f_r = (r + 1)(r + 2) / 2: nodes per element at degree r.
pub const fn nodes_per_element(r: usize) -> usize {
    (r + 1) * (r + 2) / 2
}

/// `r` when radcol supports it (0..=`MAX_DEGREE`).
pub fn check_degree(r: usize) -> Result<usize, InputError> {
    if r > MAX_DEGREE {
        return Err(InputError::Degree { degree: r });
    }
    Ok(r)
}

/// The smallest α accepted: the unit sphere at level 1 gave NaN from α =
/// 1e-14 (nodes within rounding of the patch corners); 1e-9 keeps a margin
/// of 1e5 and already has a Lebesgue constant far beyond any useful one.
pub const MIN_ALPHA: f64 = 1e-9;

/// `alpha` when it lies in [`MIN_ALPHA`, 1/3) (every node interior, and
/// not within rounding of an element's corners).
pub fn check_alpha(alpha: f64) -> Result<f64, InputError> {
    if !(MIN_ALPHA..1.0 / 3.0).contains(&alpha) {
        return Err(InputError::Alpha { alpha });
    }
    Ok(alpha)
}

/// The collocation node set of degree `r` with parameter `alpha`.
#[derive(Clone, Debug, PartialEq)]
pub struct NodeSet {
    degree: usize,
    alpha: f64,
    /// Lattice indices (i, j): node q_ij.
    indices: Vec<(usize, usize)>,
    /// Node coordinates (s, t) in σ.
    points: Vec<[f64; 2]>,
    /// ω_j = ∫_σ l_j.
    weights: Vec<f64>,
}

impl NodeSet {
    /// Nodes of degree `r` ∈ 0..=6 and 0 < α < 1/3 (α is ignored for r = 0,
    /// whose single node is the centroid).
    pub fn new(r: usize, alpha: f64) -> Result<Self, InputError> {
        check_degree(r)?;
        if r > 0 {
            check_alpha(alpha)?;
        }
        let mut indices = Vec::new();
        // Order: i + j ascending rows, as (13) enumerates them.
        for j in 0..=r {
            for i in 0..=(r - j) {
                indices.push((i, j));
            }
        }
        let points = indices
            .iter()
            .map(|&(i, j)| {
                if r == 0 {
                    [1.0 / 3.0, 1.0 / 3.0]
                } else {
                    let rf = r as f64;
                    [
                        (i as f64 + (rf - 3.0 * i as f64) * alpha) / rf,
                        (j as f64 + (rf - 3.0 * j as f64) * alpha) / rf,
                    ]
                }
            })
            .collect();
        let mut set = Self {
            degree: r,
            alpha: if r == 0 { 0.0 } else { alpha },
            indices,
            points,
            weights: Vec::new(),
        };
        // ω_j = ∫ l_j, exactly: the basis has degree r.
        let rule = collapsed_rule(r);
        let f = set.len();
        let mut w = vec![0.0; f];
        let mut l = vec![0.0; f];
        for (&[s, t], &wq) in rule.points.iter().zip(&rule.weights) {
            set.eval_basis(s, t, &mut l);
            for (wj, lj) in w.iter_mut().zip(&l) {
                *wj += wq * lj;
            }
        }
        set.weights = w;
        Ok(set)
    }

    /// The polynomial degree r.
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// The node parameter α (0 for r = 0).
    pub fn alpha(&self) -> f64 {
        self.alpha
    }

    /// Number of nodes f_r = (r + 1)(r + 2)/2.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Always false: every node set has at least one node.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Node coordinates (s, t), length f_r.
    pub fn points(&self) -> &[[f64; 2]] {
        &self.points
    }

    /// Lattice indices (i, j) of the nodes, length f_r.
    pub fn indices(&self) -> &[(usize, usize)] {
        &self.indices
    }

    /// Interpolatory weights ω_j = ∫_σ l_j (eq. 16), length f_r, summing to 1/2.
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// Writes l_j(s, t) for every node j into `out` (length f_r).
    pub fn eval_basis(&self, s: f64, t: f64, out: &mut [f64]) {
        // One copy per degree, with the recurrences unrolled: this runs at
        // every rule point of the near and self pairs.
        match self.degree {
            0 => out[0] = 1.0,
            1 => self.eval_basis_of::<1>(s, t, out),
            2 => self.eval_basis_of::<2>(s, t, out),
            3 => self.eval_basis_of::<3>(s, t, out),
            4 => self.eval_basis_of::<4>(s, t, out),
            5 => self.eval_basis_of::<5>(s, t, out),
            _ => self.eval_basis_of::<MAX_DEGREE>(s, t, out),
        }
    }

    /// [`eval_basis`](Self::eval_basis) at degree `R` (= `self.degree`).
    fn eval_basis_of<const R: usize>(&self, s: f64, t: f64, out: &mut [f64]) {
        let scale = R as f64 / (1.0 - 3.0 * self.alpha);
        let ls = (s - self.alpha) * scale;
        let lt = (t - self.alpha) * scale;
        let lu = R as f64 - ls - lt;
        // P_m(λ) for m = 0..=R at the three (scaled) coordinates.
        let table = |x: f64| {
            let mut p = [0.0; MAX_DEGREE + 1];
            p[0] = 1.0;
            for m in 1..=R {
                p[m] = p[m - 1] * (x - (m - 1) as f64) * INV_M[m];
            }
            p
        };
        let (ps, pt, pu) = (table(ls), table(lt), table(lu));
        for (o, &(i, j)) in out.iter_mut().zip(&self.indices) {
            *o = ps[i] * pt[j] * pu[R - i - j];
        }
    }

    /// [`eval_basis`](Self::eval_basis) at each (`s[i]`, `t[i]`): l_j at
    /// point i into `out[j * stride + i]` (`stride` ≥ the number of points),
    /// in loops over the points that the compiler vectorizes.
    pub fn eval_basis_batch(&self, s: &[f64], t: &[f64], out: &mut [f64], stride: usize) {
        match self.degree {
            0 => out[..s.len()].fill(1.0),
            1 => self.eval_basis_batch_of::<1, 2>(s, t, out, stride),
            2 => self.eval_basis_batch_of::<2, 3>(s, t, out, stride),
            3 => self.eval_basis_batch_of::<3, 4>(s, t, out, stride),
            4 => self.eval_basis_batch_of::<4, 5>(s, t, out, stride),
            5 => self.eval_basis_batch_of::<5, 6>(s, t, out, stride),
            _ => self.eval_basis_batch_of::<MAX_DEGREE, { MAX_DEGREE + 1 }>(s, t, out, stride),
        }
    }

    /// [`eval_basis_batch`](Self::eval_basis_batch) at degree `R` (`R1` =
    /// R + 1 tabulated polynomials), in chunks of 32 points.
    fn eval_basis_batch_of<const R: usize, const R1: usize>(
        &self,
        s: &[f64],
        t: &[f64],
        out: &mut [f64],
        stride: usize,
    ) {
        const CHUNK: usize = 32;
        let scale = R as f64 / (1.0 - 3.0 * self.alpha);
        // P_m(λ) for m = 0..=R at the three scaled coordinates of each point.
        let mut tables = [[[0.0f64; CHUNK]; R1]; 3];
        for (c, (s, t)) in s.chunks(CHUNK).zip(t.chunks(CHUNK)).enumerate() {
            let n = s.len();
            for i in 0..n {
                let (ls, lt) = ((s[i] - self.alpha) * scale, (t[i] - self.alpha) * scale);
                (tables[0][0][i], tables[1][0][i], tables[2][0][i]) = (1.0, 1.0, 1.0);
                (tables[0][1][i], tables[1][1][i]) = (ls, lt);
                tables[2][1][i] = R as f64 - ls - lt;
            }
            for table in &mut tables {
                // P_m = P_{m-1} (λ - (m - 1)) / m, with P_1 = λ.
                for m in 2..=R {
                    let (lo, hi) = table.split_at_mut(m);
                    for i in 0..n {
                        hi[0][i] = lo[m - 1][i] * (lo[1][i] - (m - 1) as f64) * INV_M[m];
                    }
                }
            }
            for (j, &(a, b)) in self.indices.iter().enumerate() {
                let (ps, pt, pu) = (&tables[0][a], &tables[1][b], &tables[2][R - a - b]);
                let o = &mut out[j * stride + c * CHUNK..][..n];
                for i in 0..n {
                    o[i] = ps[i] * pt[i] * pu[i];
                }
            }
        }
    }

    /// Σ_j ω_j g(q_j): the interpolatory rule (16)/(28) applied to `g`.
    pub fn integrate<F: Fn(f64, f64) -> f64>(&self, g: F) -> f64 {
        self.points
            .iter()
            .zip(&self.weights)
            .map(|(&[s, t], w)| w * g(s, t))
            .sum()
    }

    /// Defects ∫_σ m - Σ ω_j m(q_j) of the rule on the monomials s^a t^b, a + b = d.
    pub fn defects(&self, d: usize) -> Vec<f64> {
        (0..=d)
            .map(|a| {
                let b = d - a;
                monomial_integral(a, b) - self.integrate(|s, t| s.powi(a as i32) * t.powi(b as i32))
            })
            .collect()
    }

    /// The Lebesgue constant Λ = max over σ of Σ_j |l_j(s, t)|: the factor
    /// by which interpolation at these nodes can amplify data (‖I_n u‖∞ ≤
    /// Λ ‖u‖∞ on each element). Found by sampling σ on a lattice of step
    /// 1/`LEBESGUE_GRID` and refining the best samples by compass search;
    /// exact (to rounding) where the maximum sits at a vertex of σ, as it
    /// does for r ≤ 1.
    pub fn lebesgue_constant(&self) -> f64 {
        let mut l = vec![0.0; self.len()];
        let mut value = |s: f64, t: f64| {
            self.eval_basis(s, t, &mut l);
            l.iter().map(|v| v.abs()).sum::<f64>()
        };
        let m = LEBESGUE_GRID;
        let mut samples: Vec<(f64, f64, f64)> = Vec::with_capacity((m + 1) * (m + 2) / 2);
        for i in 0..=m {
            for j in 0..=(m - i) {
                let (s, t) = (i as f64 / m as f64, j as f64 / m as f64);
                samples.push((value(s, t), s, t));
            }
        }
        samples.sort_by(|a, b| b.0.total_cmp(&a.0));
        let mut best = samples[0].0;
        for &(v0, s0, t0) in samples.iter().take(LEBESGUE_STARTS) {
            let (mut v, mut s, mut t) = (v0, s0, t0);
            let mut h = 1.0 / m as f64;
            while h > 1e-13 {
                let mut moved = false;
                for (ds, dt) in [(h, 0.0), (-h, 0.0), (0.0, h), (0.0, -h), (h, -h), (-h, h)] {
                    let (s1, t1) = (s + ds, t + dt);
                    if s1 < 0.0 || t1 < 0.0 || s1 + t1 > 1.0 {
                        continue;
                    }
                    let v1 = value(s1, t1);
                    if v1 > v {
                        (v, s, t, moved) = (v1, s1, t1, true);
                    }
                }
                if !moved {
                    h *= 0.5;
                }
            }
            best = best.max(v);
        }
        best
    }

    /// The degree of precision of the interpolatory rule (16): the largest d such
    /// that all monomials of degree ≤ d are integrated to 1e-13 relative.
    pub fn precision(&self) -> usize {
        let mut d = 0;
        while d < 4 * MAX_DEGREE {
            let ok = self
                .defects(d + 1)
                .iter()
                .enumerate()
                .all(|(a, e)| e.abs() <= 1e-13 * monomial_integral(a, d + 1 - a));
            if !ok {
                break;
            }
            d += 1;
        }
        d
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// r = 1: Σ|λ_i| is convex and piecewise linear, so Λ sits at a vertex of
    /// σ, whose barycentric coordinates relative to the shrunken node
    /// triangle (scaled by k = 1 - 3α about the centroid) are 1/3 + 2/(3k)
    /// and twice 1/3 - 1/(3k): Λ = 4/(3k) - 1/3, 7/3 at α0 = 1/6.
    #[test]
    fn lebesgue_constant_of_degree_one_is_the_closed_form() {
        for alpha in [0.02, 0.1, 1.0 / 6.0, 0.25, 0.3] {
            let k = 1.0 - 3.0 * alpha;
            let want = 4.0 / (3.0 * k) - 1.0 / 3.0;
            let got = NodeSet::new(1, alpha).unwrap().lebesgue_constant();
            crate::assert_close!(got, want, 1e-13 * want, "alpha = {alpha}");
        }
        assert_eq!(NodeSet::new(0, 0.1).unwrap().lebesgue_constant(), 1.0);
    }

    /// Higher degrees against an independent brute-force maximum over a
    /// lattice ten times finer: the search never finds less, and the two
    /// agree to the lattice's resolution.
    #[test]
    fn lebesgue_constant_matches_a_fine_lattice() {
        for (r, alpha) in [(2, 0.2319), (2, 0.109), (3, 0.0779365403436462), (5, 0.05)] {
            let set = NodeSet::new(r, alpha).unwrap();
            let mut l = vec![0.0; set.len()];
            let m = 2400;
            let mut brute = 0.0f64;
            for i in 0..=m {
                for j in 0..=(m - i) {
                    set.eval_basis(i as f64 / m as f64, j as f64 / m as f64, &mut l);
                    brute = brute.max(l.iter().map(|v| v.abs()).sum());
                }
            }
            let got = set.lebesgue_constant();
            println!("r = {r}, alpha = {alpha}: Λ = {got:.6} (lattice 1/{m}: {brute:.6})");
            assert!(got >= brute * (1.0 - 1e-12), "r = {r}: {got} < {brute}");
            crate::assert_close!(got, brute, 1e-5 * brute, "r = {r}, alpha = {alpha}");
        }
    }

    #[test]
    fn basis_is_cardinal_and_partition_of_unity() {
        for r in 0..=MAX_DEGREE {
            let set = NodeSet::new(r, 0.1).unwrap();
            assert_eq!(set.len(), (r + 1) * (r + 2) / 2);
            let mut l = vec![0.0; set.len()];
            for (k, &[s, t]) in set.points().iter().enumerate() {
                set.eval_basis(s, t, &mut l);
                for (j, v) in l.iter().enumerate() {
                    let want = if j == k { 1.0 } else { 0.0 };
                    crate::assert_close!(v, want, 1e-13, "r={r} node {k} basis {j}: {v}");
                }
            }
            set.eval_basis(0.77, 0.05, &mut l);
            crate::assert_close!(l.iter().sum::<f64>(), 1.0, 1e-12);
        }
    }

    /// The batched basis on more points than one chunk, some of them the
    /// nodes: cardinal at the nodes, every polynomial of degree ≤ r
    /// reproduced, and the point-by-point values to rounding.
    #[test]
    fn batched_basis_is_the_basis() {
        for r in 0..=MAX_DEGREE {
            let set = NodeSet::new(r, 0.07).unwrap();
            let f = set.len();
            let mut pts: Vec<[f64; 2]> = set.points().to_vec();
            pts.extend((0..50).map(|i| {
                let x = (i as f64 * 0.618_034) % 1.0;
                let y = (i as f64 * 0.414_214) % 1.0;
                if x + y <= 1.0 {
                    [x, y]
                } else {
                    [1.0 - x, 1.0 - y]
                }
            }));
            let n = pts.len();
            let (s, t): (Vec<f64>, Vec<f64>) = pts.iter().map(|&[s, t]| (s, t)).unzip();
            let stride = n + 3;
            let mut out = vec![f64::NAN; f * stride];
            set.eval_basis_batch(&s, &t, &mut out, stride);
            let p = |s: f64, t: f64| (1.0 + 2.0 * s - t).powi(r as i32) + s.powi(r as i32 - 1) * t;
            let vals: Vec<f64> = set.points().iter().map(|&[s, t]| p(s, t)).collect();
            let mut one = vec![0.0; f];
            for (i, &[si, ti]) in pts.iter().enumerate() {
                let l: Vec<f64> = (0..f).map(|j| out[j * stride + i]).collect();
                if i < f {
                    for (j, v) in l.iter().enumerate() {
                        let want = if j == i { 1.0 } else { 0.0 };
                        crate::assert_close!(v, want, 1e-13, "r={r} node {i} basis {j}");
                    }
                }
                if r > 0 {
                    let interp: f64 = l.iter().zip(&vals).map(|(a, b)| a * b).sum();
                    crate::assert_close!(interp, p(si, ti), 1e-10, "r={r} at {si}, {ti}");
                }
                set.eval_basis(si, ti, &mut one);
                for (a, b) in l.iter().zip(&one) {
                    crate::assert_close!(a, b, 1e-14, "r={r} at {si}, {ti}");
                }
            }
        }
    }

    /// Interpolation reproduces every polynomial of degree ≤ r.
    #[test]
    fn basis_reproduces_polynomials() {
        for r in 1..=MAX_DEGREE {
            let set = NodeSet::new(r, 0.07).unwrap();
            let p = |s: f64, t: f64| (1.0 + 2.0 * s - t).powi(r as i32) + s.powi(r as i32 - 1) * t;
            let vals: Vec<f64> = set.points().iter().map(|&[s, t]| p(s, t)).collect();
            let mut l = vec![0.0; set.len()];
            for &(s, t) in &[(0.0, 0.0), (1.0, 0.0), (0.2, 0.7), (0.4, 0.1)] {
                set.eval_basis(s, t, &mut l);
                let interp: f64 = l.iter().zip(&vals).map(|(a, b)| a * b).sum();
                crate::assert_close!(interp, p(s, t), 1e-10, "r={r}");
            }
        }
    }

    #[test]
    fn nodes_are_interior_and_match_equation_13() {
        let set = NodeSet::new(3, 0.1).unwrap();
        // q_{1,0} = ((1 + 0·α)/3, (0 + 3α)/3) = (1/3, α).
        let k = set.indices().iter().position(|&ij| ij == (1, 0)).unwrap();
        let [s, t] = set.points()[k];
        crate::assert_close!(s, 1.0 / 3.0, 1e-16);
        crate::assert_close!(t, 0.1, 1e-16);
        assert!(set
            .points()
            .iter()
            .all(|&[s, t]| s > 0.0 && t > 0.0 && s + t < 1.0));
        crate::assert_close!(set.weights().iter().sum::<f64>(), 0.5, 1e-15);
    }

    #[test]
    fn precision_is_at_least_r() {
        for r in 0..=MAX_DEGREE {
            let p = NodeSet::new(r, 0.13).unwrap().precision();
            assert!(p >= r, "r={r}: precision {p}");
        }
        // The centroid rule has degree 1; the 3-node rule at α = 1/6 has degree 2.
        assert_eq!(NodeSet::new(0, 0.1).unwrap().precision(), 1);
        assert_eq!(NodeSet::new(1, 1.0 / 6.0).unwrap().precision(), 2);
        assert_eq!(NodeSet::new(1, 0.1).unwrap().precision(), 1);
    }

    #[test]
    fn rejects_bad_input() {
        assert!(NodeSet::new(7, 0.1).is_err());
        assert!(NodeSet::new(2, 0.0).is_err());
        assert!(NodeSet::new(2, 1.0 / 3.0).is_err());
        assert!(NodeSet::new(2, f64::NAN).is_err());
    }
}
