//! The uniform tessellation of the unit simplex σ into n² sub-triangles, shared
//! by the BVH (curved elements) and the per-vertex read-back.
//!
//! Vertices are the lattice points (i/n, j/n), i + j ≤ n, ordered by j then i.
//! Every sub-triangle is listed counter-clockwise in (s, t), so its mapped normal
//! has the orientation of D_s m × D_t m (the side light leaves from).

/// Number of lattice vertices of the level-`n` tessellation: (n + 1)(n + 2)/2.
pub fn tessellation_vertex_count(n: u32) -> usize {
    let n = n as usize;
    (n + 1) * (n + 2) / 2
}

/// The (s, t) of the lattice vertices (i/n, j/n), i + j ≤ n, j-major
/// (n = 0 is treated as 1).
pub fn tessellation_points(n: u32) -> Vec<[f64; 2]> {
    let n = n.max(1);
    let nf = n as f64;
    let mut out = Vec::with_capacity(tessellation_vertex_count(n));
    for j in 0..=n {
        for i in 0..=n - j {
            out.push([i as f64 / nf, j as f64 / nf]);
        }
    }
    out
}

/// The n² sub-triangles as indices into [`tessellation_points`], counter-clockwise
/// in (s, t) (n = 0 is treated as 1).
pub fn tessellation_triangles(n: u32) -> Vec<[u32; 3]> {
    let n = n.max(1);
    // Rows below j hold (n + 1) + n + … + (n + 2 - j) = j (n + 1) - j (j - 1)/2 points.
    let idx = |i: u32, j: u32| j * (n + 1) - j * j.saturating_sub(1) / 2 + i;
    let mut out = Vec::with_capacity((n * n) as usize);
    for j in 0..n {
        for i in 0..n - j {
            out.push([idx(i, j), idx(i + 1, j), idx(i, j + 1)]);
            if i + j + 1 < n {
                out.push([idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)]);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every index points at the lattice point it claims, there are n² triangles,
    /// all counter-clockwise, and their areas sum to |σ| = 1/2.
    #[test]
    fn lattice_and_triangles() {
        for n in 1..=7u32 {
            let p = tessellation_points(n);
            assert_eq!(p.len(), tessellation_vertex_count(n));
            let tris = tessellation_triangles(n);
            assert_eq!(tris.len(), (n * n) as usize);
            let mut area = 0.0;
            for t in &tris {
                let [a, b, c] = t.map(|i| p[i as usize]);
                let cross = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
                // Each sub-triangle has area 1/(2 n²), positively oriented.
                assert!(
                    (cross - 1.0 / (n * n) as f64).abs() < 1e-14,
                    "n = {n}: {cross}"
                );
                area += 0.5 * cross;
            }
            crate::assert_close!(area, 0.5, 1e-13);
            // Lattice points are distinct and exact multiples of 1/n.
            for (k, &[s, t]) in p.iter().enumerate() {
                let (i, j) = ((s * n as f64).round(), (t * n as f64).round());
                assert_eq!([i / n as f64, j / n as f64], [s, t]);
                assert!(p[..k].iter().all(|q| *q != [s, t]));
            }
        }
    }
}
