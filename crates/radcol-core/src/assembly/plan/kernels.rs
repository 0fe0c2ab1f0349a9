//! The far-field hot loop: G·w·J/π over a run of rule points, then a
//! register contraction with the transposed basis. Written over slices so
//! that the compiler vectorises it.

/// Elements per run at most (bounds the kernel buffer).
pub(super) const RUN_CHUNK: usize = 64;

/// out[e * f + j] = Σ_q g[e * nq + q] · basis_t[q * f + j] for every element e
/// of a run: one small product per element, accumulated in registers for the
/// node counts of r = 0..=6 (no horizontal reductions).
#[inline]
pub(super) fn contract(g: &[f64], basis_t: &[f64], nq: usize, f: usize, out: &mut [f64]) {
    match f {
        1 => contract_fixed::<1>(g, basis_t, nq, out),
        3 => contract_fixed::<3>(g, basis_t, nq, out),
        6 => contract_fixed::<6>(g, basis_t, nq, out),
        10 => contract_fixed::<10>(g, basis_t, nq, out),
        15 => contract_fixed::<15>(g, basis_t, nq, out),
        21 => contract_fixed::<21>(g, basis_t, nq, out),
        28 => contract_fixed::<28>(g, basis_t, nq, out),
        _ => {
            for (ge, oe) in g.chunks_exact(nq).zip(out.chunks_exact_mut(f)) {
                oe.fill(0.0);
                for (gq, bq) in ge.iter().zip(basis_t.chunks_exact(f)) {
                    for (o, b) in oe.iter_mut().zip(bq) {
                        *o += gq * b;
                    }
                }
            }
        }
    }
}

#[inline]
fn contract_fixed<const F: usize>(g: &[f64], basis_t: &[f64], nq: usize, out: &mut [f64]) {
    let basis_t = &basis_t[..nq * F];
    for (ge, oe) in g.chunks_exact(nq).zip(out.chunks_exact_mut(F)) {
        // Four independent accumulators hide the latency of the additions.
        let mut acc = [[0.0f64; F]; 4];
        let mut gc = ge.chunks_exact(4);
        let mut bc = basis_t.chunks_exact(4 * F);
        for (g4, b4) in (&mut gc).zip(&mut bc) {
            for u in 0..4 {
                for j in 0..F {
                    acc[u][j] += g4[u] * b4[u * F + j];
                }
            }
        }
        for (gq, bq) in gc.remainder().iter().zip(bc.remainder().chunks_exact(F)) {
            for j in 0..F {
                acc[0][j] += gq * bq[j];
            }
        }
        for j in 0..F {
            oe[j] = (acc[0][j] + acc[1][j]) + (acc[2][j] + acc[3][j]);
        }
    }
}

/// `g[q] = G(P, Q_q) · wj[q]` for one collocation point against one element's rule
/// points: the hot loop of far assembly, written over slices so it vectorises.
#[inline]
pub fn far_kernel_row(
    p: glam::DVec3,
    n_p: glam::DVec3,
    px: &[f64],
    py: &[f64],
    pz: &[f64],
    nx: &[f64],
    ny: &[f64],
    nz: &[f64],
    wj: &[f64],
    g: &mut [f64],
) {
    let nq = g.len();
    let (px, py, pz) = (&px[..nq], &py[..nq], &pz[..nq]);
    let (nx, ny, nz, wj) = (&nx[..nq], &ny[..nq], &nz[..nq], &wj[..nq]);
    for q in 0..nq {
        let dx = px[q] - p.x;
        let dy = py[q] - p.y;
        let dz = pz[q] - p.z;
        let a = (dx * n_p.x + dy * n_p.y + dz * n_p.z).max(0.0);
        let b = (-(dx * nx[q] + dy * ny[q] + dz * nz[q])).max(0.0);
        let r2 = dx * dx + dy * dy + dz * dz;
        g[q] = a * b / (r2 * r2) * wj[q];
    }
}

/// [`far_kernel_row`] against one flat element (`e`'s map, rule points
/// `s`, `t` with weights / π `w`), from the element's geometry alone: on a
/// flat element the cosine at Q is the constant (P − o)·n_Q / |P − Q|,
/// the cosine at P and |P − Q|² are a linear and a quadratic polynomial
/// in (s, t), so a point costs a few multiply-adds and no table is read.
#[inline]
pub(super) fn far_kernel_flat(
    p: glam::DVec3,
    n_p: glam::DVec3,
    e: &super::tables::FlatElement,
    [s, t, w]: [&[f64]; 3],
    g: &mut [f64],
) {
    let nq = g.len();
    let (s, t, w) = (&s[..nq], &t[..nq], &w[..nq]);
    let d0 = e.origin - p;
    // a = d·n_P, b = −d·n_Q, r² = |d|², d = d0 + s e1 + t e2.
    let (a0, a1, a2) = (d0.dot(n_p), e.e1.dot(n_p), e.e2.dot(n_p));
    let b = (-d0.dot(e.normal)).max(0.0) * e.jacobian;
    let (c0, c1, c2) = (d0.dot(d0), 2.0 * d0.dot(e.e1), 2.0 * d0.dot(e.e2));
    let (c3, c4, c5) = (e.e1.dot(e.e1), 2.0 * e.e1.dot(e.e2), e.e2.dot(e.e2));
    for q in 0..nq {
        let (sq, tq) = (s[q], t[q]);
        let a = (a0 + sq * a1 + tq * a2).max(0.0);
        let r2 = c0 + sq * (c1 + sq * c3 + tq * c4) + tq * (c2 + tq * c5);
        g[q] = a * b / (r2 * r2) * w[q];
    }
}
