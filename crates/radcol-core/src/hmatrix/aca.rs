//! Low-rank blocks: adaptive cross approximation with the reference row and
//! column of ACA+ (Grasedyck 2005; Börm, Grasedyck and Hackbusch's lecture
//! notes), which samples only the rows and columns it pivots on, then
//! recompression of the cross to the tolerance by QR and SVD (faer).
//!
//! Radiosity blocks often have rows and columns that are exactly zero (a
//! point that faces away from a whole cluster, or sees it through an
//! occluder). Plain partial pivoting can then stop on a zero row while the
//! rest of the block is not; ACA+ keeps a reference row and column whose
//! residuals must vanish too, and replaces a reference that has become
//! exactly zero by an unused one.

use faer::Mat;

/// A ≈ U Vᵀ with U (m × k) and V (n × k), column-major.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LowRank {
    /// Rows m.
    pub m: usize,
    /// Columns n.
    pub n: usize,
    /// `u[l * m + i]`: column l of U.
    pub u: Vec<f64>,
    /// `v[l * n + j]`: column l of V.
    pub v: Vec<f64>,
}

impl LowRank {
    /// This block of the rows `at_rows` (of `m`) and columns `at_cols`
    /// (of `n`) of a larger one that is zero elsewhere.
    pub fn padded(&self, m: usize, at_rows: &[usize], n: usize, at_cols: &[usize]) -> Self {
        if (m, n) == (self.m, self.n) {
            return self.clone();
        }
        let k = self.rank();
        let (mut u, mut v) = (vec![0.0; k * m], vec![0.0; k * n]);
        for l in 0..k {
            for (a, &i) in at_rows.iter().enumerate() {
                u[l * m + i] = self.u[l * self.m + a];
            }
            for (b, &j) in at_cols.iter().enumerate() {
                v[l * n + j] = self.v[l * self.n + b];
            }
        }
        Self { m, n, u, v }
    }

    /// The rank k.
    pub fn rank(&self) -> usize {
        self.u.len().checked_div(self.m).unwrap_or(0)
    }

    /// y += U (Vᵀ x).
    pub fn apply_add(&self, x: &[f64], y: &mut [f64]) {
        for l in 0..self.rank() {
            let v = &self.v[l * self.n..(l + 1) * self.n];
            let c: f64 = v.iter().zip(x).map(|(a, b)| a * b).sum();
            if c != 0.0 {
                let u = &self.u[l * self.m..(l + 1) * self.m];
                for (yi, ui) in y.iter_mut().zip(u) {
                    *yi += c * ui;
                }
            }
        }
    }

    /// ‖S + u vᵀ‖²_F − ‖S‖²_F = 2 Σ_l (u·u_l)(v·v_l) + ‖u‖²‖v‖² for S = U Vᵀ.
    fn norm2_increment(&self, u: &[f64], v: &[f64]) -> f64 {
        let (m, n) = (self.m, self.n);
        let cross: f64 = (0..self.rank())
            .map(|l| dot(u, &self.u[l * m..(l + 1) * m]) * dot(v, &self.v[l * n..(l + 1) * n]))
            .sum();
        2.0 * cross + norm2(u) * norm2(v)
    }

    /// Row i of A − U Vᵀ into `out`.
    fn residual_row(&self, i: usize, row: &mut dyn FnMut(usize, &mut [f64]), out: &mut [f64]) {
        row(i, out);
        residual(
            out,
            (0..self.rank()).map(|l| self.u[l * self.m + i]),
            &self.v,
        );
    }

    /// Column j of A − U Vᵀ into `out`.
    fn residual_col(&self, j: usize, col: &mut dyn FnMut(usize, &mut [f64]), out: &mut [f64]) {
        col(j, out);
        residual(
            out,
            (0..self.rank()).map(|l| self.v[l * self.n + j]),
            &self.u,
        );
    }

    fn push(&mut self, u: &[f64], v: &[f64]) {
        self.u.extend_from_slice(u);
        self.v.extend_from_slice(v);
    }

    /// Entry (i, j) of U Vᵀ.
    #[cfg(any(test, feature = "internals"))]
    pub fn entry(&self, i: usize, j: usize) -> f64 {
        (0..self.rank())
            .map(|l| self.u[l * self.m + i] * self.v[l * self.n + j])
            .sum()
    }
}

/// What ACA+ ended with.
#[derive(Debug)]
pub enum Cross {
    /// A cross of rank k within the tolerance (not yet recompressed).
    LowRank(LowRank),
    /// The rank grew past the point where storing the cross costs as much as
    /// the block: the caller should store it dense.
    Dense,
}

fn argmax_abs(v: &[f64], skip: &[bool]) -> Option<usize> {
    v.iter()
        .enumerate()
        .filter(|(i, _)| !skip[*i])
        .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
        .map(|(i, _)| i)
}

fn norm2(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum()
}

/// The residual row i (or column j, with the roles of U and V swapped):
/// `out = A(i, :) − Σ_l u_l(i) v_l`.
fn residual(out: &mut [f64], coeffs: impl Iterator<Item = f64>, basis: &[f64]) {
    let n = out.len();
    for (l, c) in coeffs.enumerate() {
        if c != 0.0 {
            for (o, b) in out.iter_mut().zip(&basis[l * n..(l + 1) * n]) {
                *o -= c * b;
            }
        }
    }
}

/// ACA+ on the m × n block whose rows and columns `row(i, out)` and
/// `col(j, out)` write: stops when the newest cross ‖u‖‖v‖ and the residual
/// reference row and column are within `tol` of the approximation's
/// Frobenius norm, or returns [`Cross::Dense`] when the rank reaches
/// `m n / (m + n)` (a cross that large costs more than the block).
pub fn aca_plus(
    m: usize,
    n: usize,
    tol: f64,
    row: &mut dyn FnMut(usize, &mut [f64]),
    col: &mut dyn FnMut(usize, &mut [f64]),
) -> Cross {
    let mut lr = LowRank {
        m,
        n,
        ..Default::default()
    };
    let max_rank = (m * n) / (m + n).max(1);
    let (mut used_rows, mut used_cols) = (vec![false; m], vec![false; n]);
    let (mut r_buf, mut c_buf) = (vec![0.0; n], vec![0.0; m]);
    let mut norm_s2 = 0.0f64;
    // Reference column and row, with their residuals.
    let mut j_ref = 0usize;
    let mut c_ref = vec![0.0; m];
    col(j_ref, &mut c_ref);
    let mut i_ref = argmin_nonzero(&c_ref).unwrap_or(0);
    let mut r_ref = vec![0.0; n];
    row(i_ref, &mut r_ref);
    loop {
        if lr.rank() >= max_rank {
            return Cross::Dense;
        }
        let ci = argmax_abs(&c_ref, &used_rows);
        let rj = argmax_abs(&r_ref, &used_cols);
        let (cmax, rmax) = (
            ci.map_or(0.0, |i| c_ref[i].abs()),
            rj.map_or(0.0, |j| r_ref[j].abs()),
        );
        if cmax == 0.0 && rmax == 0.0 {
            let refs = exhausted(
                &lr,
                (&mut used_rows, &mut used_cols),
                tol,
                norm_s2,
                row,
                col,
            );
            match refs {
                None => return Cross::LowRank(lr),
                Some(r) => (i_ref, r_ref, j_ref, c_ref) = r,
            }
            continue;
        }
        // Pivot on the larger reference entry.
        let (i, j) = if cmax >= rmax {
            let i = ci.expect("cmax > 0");
            lr.residual_row(i, row, &mut r_buf);
            let Some(j) = argmax_abs(&r_buf, &used_cols) else {
                return Cross::LowRank(lr);
            };
            lr.residual_col(j, col, &mut c_buf);
            (i, j)
        } else {
            let j = rj.expect("rmax > 0");
            lr.residual_col(j, col, &mut c_buf);
            let Some(i) = argmax_abs(&c_buf, &used_rows) else {
                return Cross::LowRank(lr);
            };
            lr.residual_row(i, row, &mut r_buf);
            (i, j)
        };
        used_rows[i] = true;
        used_cols[j] = true;
        let pivot = r_buf[j];
        if pivot == 0.0 {
            // The residual row (or column) is zero where it is largest: it is
            // zero, and both indices, now marked used, are not chosen again.
            continue;
        }
        let u: Vec<f64> = c_buf.iter().map(|x| x / pivot).collect();
        let v = r_buf.clone();
        let (nu, nv) = (norm2(&u), norm2(&v));
        norm_s2 = (norm_s2 + lr.norm2_increment(&u, &v)).max(0.0);
        // Update the references' residuals by the new cross.
        let (vj, ui) = (v[j_ref], u[i_ref]);
        c_ref.iter_mut().zip(&u).for_each(|(c, x)| *c -= x * vj);
        r_ref.iter_mut().zip(&v).for_each(|(r, x)| *r -= x * ui);
        lr.push(&u, &v);
        if used_rows[i_ref] || used_cols[j_ref] {
            // A reference that became a pivot carries no more news.
            if let Some((i, ri, jj, cj)) = fresh_references(&lr, &used_rows, &used_cols, row, col) {
                (i_ref, r_ref, j_ref, c_ref) = (i, ri, jj, cj);
            }
        }
        let eps2 = tol * tol * norm_s2;
        let refs_small = norm2(&c_ref) * n as f64 <= eps2 && norm2(&r_ref) * m as f64 <= eps2;
        if nu * nv <= eps2 && refs_small {
            return Cross::LowRank(lr);
        }
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The index of the smallest nonzero |entry| (a row unlike the pivots to
/// come), if any.
fn argmin_nonzero(v: &[f64]) -> Option<usize> {
    v.iter()
        .enumerate()
        .filter(|(_, x)| **x != 0.0)
        .min_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
        .map(|(i, _)| i)
}

type References = (usize, Vec<f64>, usize, Vec<f64>);

/// Both references are exhausted among the unused rows and columns: fresh
/// ones, or None when the cross is done. Once the approximation is nonzero,
/// a fresh pair within the tolerance confirms it; a pair with nothing left
/// among the unused is consumed, so this ends after at most min(m, n)
/// samples (an unproved zero block costs what its dense fill would).
fn exhausted(
    lr: &LowRank,
    (used_rows, used_cols): (&mut [bool], &mut [bool]),
    tol: f64,
    norm_s2: f64,
    row: &mut dyn FnMut(usize, &mut [f64]),
    col: &mut dyn FnMut(usize, &mut [f64]),
) -> Option<References> {
    let (i, ri, j, cj) = fresh_references(lr, used_rows, used_cols, row, col)?;
    let eps2 = tol * tol * norm_s2;
    if norm_s2 > 0.0 && norm2(&cj) * lr.n as f64 <= eps2 && norm2(&ri) * lr.m as f64 <= eps2 {
        return None;
    }
    let live = |v: &[f64], used: &[bool]| v.iter().zip(used).any(|(x, &u)| !u && *x != 0.0);
    if !live(&ri, used_cols) && !live(&cj, used_rows) {
        used_rows[i] = true;
        used_cols[j] = true;
    }
    Some((i, ri, j, cj))
}

/// New reference row and column among the unused, with their residuals:
/// the next unused column, and the unused row where that column's residual
/// is smallest but nonzero (else the next unused row). None when every row
/// or every column is used.
fn fresh_references(
    lr: &LowRank,
    used_rows: &[bool],
    used_cols: &[bool],
    row: &mut dyn FnMut(usize, &mut [f64]),
    col: &mut dyn FnMut(usize, &mut [f64]),
) -> Option<References> {
    let (m, n) = (lr.m, lr.n);
    let j = (0..n).find(|&j| !used_cols[j])?;
    let mut c = vec![0.0; m];
    lr.residual_col(j, col, &mut c);
    let unused: Vec<f64> = c
        .iter()
        .zip(used_rows)
        .map(|(x, &u)| if u { 0.0 } else { *x })
        .collect();
    let i = argmin_nonzero(&unused).or_else(|| (0..m).find(|&i| !used_rows[i]))?;
    let mut r = vec![0.0; n];
    lr.residual_row(i, row, &mut r);
    Some((i, r, j, c))
}

/// The cross recompressed to the smallest rank k' with
/// ‖U Vᵀ − U' V'ᵀ‖_F ≤ tol ‖U Vᵀ‖_F: U = Q_u R_u, V = Q_v R_v, then the SVD
/// of the k × k matrix R_u R_vᵀ, truncated.
pub fn recompress(lr: &LowRank, tol: f64) -> LowRank {
    let (m, n, k) = (lr.m, lr.n, lr.rank());
    if k == 0 {
        return lr.clone();
    }
    let u = Mat::from_fn(m, k, |i, l| lr.u[l * m + i]);
    let v = Mat::from_fn(n, k, |j, l| lr.v[l * n + j]);
    let (qu, qv) = (u.qr(), v.qr());
    let (ru, rv) = (qu.thin_R(), qv.thin_R());
    let core = ru * rv.transpose();
    let Ok(svd) = core.thin_svd() else {
        return lr.clone();
    };
    let s = svd.S().column_vector();
    let s: Vec<f64> = (0..s.nrows()).map(|i| s[i]).collect();
    let keep = kept(&s, tol);
    if keep == 0 {
        return LowRank {
            m,
            n,
            ..Default::default()
        };
    }
    let (qu, qv) = (qu.compute_thin_Q(), qv.compute_thin_Q());
    let (w, z) = (svd.U(), svd.V());
    let mut out = LowRank {
        m,
        n,
        u: Vec::with_capacity(m * keep),
        v: Vec::with_capacity(n * keep),
    };
    for l in 0..keep {
        let ucol = (&qu * w.col(l)) * s[l];
        let vcol = &qv * z.col(l);
        out.u.extend((0..m).map(|i| ucol[i]));
        out.v.extend((0..n).map(|j| vcol[j]));
    }
    out
}

/// The fewest leading singular values `s` (descending) whose tail is within
/// `tol` of the whole, in the Frobenius norm. The tail is summed from the
/// smallest value up: subtracting from the total instead loses every tail
/// below about ε of it, so tolerances under 1e-8 truncated on rounding
/// noise (a block kept at 3e-9 for a tolerance of 1e-10).
fn kept(s: &[f64], tol: f64) -> usize {
    let total: f64 = s.iter().map(|x| x * x).sum();
    let mut tail = 0.0;
    let mut keep = s.len();
    while keep > 0 && tail + s[keep - 1] * s[keep - 1] <= tol * tol * total {
        tail += s[keep - 1] * s[keep - 1];
        keep -= 1;
    }
    keep
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth kernel block between two separated point sets: numerically
    /// low rank, its singular values falling geometrically.
    fn kernel_block(m: usize, n: usize) -> Vec<f64> {
        let mut a = vec![0.0; m * n];
        for i in 0..m {
            for j in 0..n {
                let x = i as f64 / m as f64;
                let y = 3.0 + j as f64 / n as f64;
                a[i * n + j] = 1.0 / ((x - y) * (x - y) + 0.5);
            }
        }
        a
    }

    /// Recompression keeps the tolerance down to 1e-12: a full-rank
    /// representation of a smooth block (U = A, V = I) truncated to tol is
    /// within tol of it. With the tail subtracted from the total, tails
    /// under about ε of it were rounding noise (3.3e-9 kept for 1e-10).
    #[test]
    fn recompression_keeps_tight_tolerances() {
        let (m, n) = (30, 24);
        let a = kernel_block(m, n);
        let full = LowRank {
            m,
            n,
            u: (0..n)
                .flat_map(|j| (0..m).map(move |i| (i, j)))
                .map(|(i, j)| a[i * n + j])
                .collect(),
            v: (0..n)
                .flat_map(|l| (0..n).map(move |j| (l == j) as u8 as f64))
                .collect(),
        };
        for tol in [1e-3, 1e-6, 1e-10, 1e-12] {
            let lr = recompress(&full, tol);
            let (d, t) = frob_diff(&a, n, &lr);
            assert!(d <= tol * t, "tol {tol}: {d} of {t}");
            assert!(lr.rank() < n / 2, "tol {tol}: rank {}", lr.rank());
        }
    }

    fn frob_diff(a: &[f64], n: usize, lr: &LowRank) -> (f64, f64) {
        let mut d = 0.0;
        let mut t = 0.0;
        for (idx, x) in a.iter().enumerate() {
            let (i, j) = (idx / n, idx % n);
            let e = x - lr.entry(i, j);
            d += e * e;
            t += x * x;
        }
        (d.sqrt(), t.sqrt())
    }

    fn run(a: &[f64], m: usize, n: usize, tol: f64) -> Cross {
        aca_plus(
            m,
            n,
            tol,
            &mut |i, out| out.copy_from_slice(&a[i * n..(i + 1) * n]),
            &mut |j, out| {
                out.iter_mut()
                    .enumerate()
                    .for_each(|(i, o)| *o = a[i * n + j])
            },
        )
    }

    #[test]
    fn error_tracks_the_tolerance_and_recompression_keeps_it() {
        let (m, n) = (120, 90);
        let a = kernel_block(m, n);
        let mut last_rank = 0;
        for tol in [1e-3, 1e-6, 1e-9, 1e-12] {
            let Cross::LowRank(lr) = run(&a, m, n, tol) else {
                panic!("a smooth block is low rank");
            };
            let (d, t) = frob_diff(&a, n, &lr);
            assert!(d <= 10.0 * tol * t, "tol {tol}: error {:.2e}", d / t);
            let re = recompress(&lr, tol);
            let (d2, _) = frob_diff(&a, n, &re);
            assert!(
                d2 <= 20.0 * tol * t,
                "recompressed, tol {tol}: {:.2e}",
                d2 / t
            );
            assert!(re.rank() <= lr.rank() && re.rank() >= last_rank);
            last_rank = re.rank();
        }
        assert!(last_rank < 30, "rank {last_rank} at 1e-12");
    }

    /// Rows that are zero (a point facing away) and a block that is zero
    /// except for a few rows: the references find them.
    #[test]
    fn zero_rows_do_not_stop_it_early() {
        let (m, n) = (60, 50);
        let mut a = kernel_block(m, n);
        for i in 0..m {
            if i % 7 != 3 {
                a[i * n..(i + 1) * n].iter_mut().for_each(|x| *x = 0.0);
            }
        }
        let Cross::LowRank(lr) = run(&a, m, n, 1e-10) else {
            panic!("low rank");
        };
        let (d, t) = frob_diff(&a, n, &lr);
        assert!(d <= 1e-9 * t, "error {:.2e}", d / t);
        let zero = vec![0.0; m * n];
        let Cross::LowRank(lr) = run(&zero, m, n, 1e-10) else {
            panic!("low rank");
        };
        assert_eq!(lr.rank(), 0);
    }

    #[test]
    fn a_full_rank_block_is_left_dense() {
        let n = 40;
        let a: Vec<f64> = (0..n * n)
            .map(|k| if k / n == k % n { 1.0 + k as f64 } else { 0.0 })
            .collect();
        assert!(matches!(run(&a, n, n, 1e-8), Cross::Dense));
    }
}
