//! What a hierarchical matrix will store, from its block tree alone: no
//! entry is computed, so a matrix that cannot fit is refused before the
//! hours its entries would take.

use super::cluster::Aabb;
use super::{dense_leaf_numbers, index_bytes, partition, HMatrix, HOptions, Leaf, Structure};
use serde::Serialize;
use std::ops::ControlFlow;

/// The bytes a hierarchical matrix will take: its dense leaves exactly
/// (those the structure does not prove zero, without the rows and columns
/// it proves zero), its low-rank leaves at rank 1
/// (at least that; most are higher), and its orders and leaf records.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct HPrediction {
    /// Bytes of the dense leaves: 8 m n each, or less where the structure
    /// proves rows and columns zero.
    pub near_bytes: f64,
    /// Bytes of the admissible leaves at rank 1: 8 (m + n) each.
    pub far_min_bytes: f64,
    /// Bytes of the row and column orders and of the leaf records.
    pub index_bytes: f64,
    /// False when the count stopped at its limit (the figures are then
    /// those reached: the matrix takes more).
    pub complete: bool,
}

impl HPrediction {
    /// All of it.
    pub fn bytes(&self) -> f64 {
        self.near_bytes + self.far_min_bytes + self.index_bytes
    }
}

impl HMatrix {
    /// What [`HMatrix::build`] with these boxes, `structure` and `opts` will
    /// store, counted over its block tree without computing an entry
    /// (equal to its [`HMatrix::heap_bytes`] when every low-rank block has
    /// rank 1 and no cross grows into a dense block), stopping once the
    /// count passes `limit` bytes.
    pub fn predict(
        row_boxes: &[Aabb],
        col_boxes: &[Aabb],
        structure: &dyn Structure,
        opts: &HOptions,
        limit: f64,
    ) -> HPrediction {
        let mut p = HPrediction {
            near_bytes: 0.0,
            far_min_bytes: 0.0,
            index_bytes: 0.0,
            complete: true,
        };
        let (mut leaves, record) = (0, std::mem::size_of::<Leaf>() as f64);
        let (rt, ct, flow) = partition(
            row_boxes,
            col_boxes,
            structure,
            opts,
            &mut |rt, ct, r, c, admissible| {
                let (rc, cc) = (&rt.clusters[r], &ct.clusters[c]);
                let (m, n) = (rc.len() as f64, cc.len() as f64);
                leaves += 1;
                p.index_bytes += record;
                if admissible {
                    p.far_min_bytes += 8.0 * (m + n);
                } else if !structure.is_zero(
                    &rt.order[rc.start..rc.end],
                    &rc.bbox,
                    &ct.order[cc.start..cc.end],
                    &cc.bbox,
                ) {
                    p.near_bytes +=
                        8.0 * dense_leaf_numbers(&rt.order, rc, &ct.order, cc, structure) as f64;
                }
                if p.bytes() > limit {
                    ControlFlow::Break(())
                } else {
                    ControlFlow::Continue(())
                }
            },
        );
        p.index_bytes = index_bytes(&rt, &ct, leaves) as f64;
        p.complete = flow.is_continue();
        p
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::matrix::DenseMatrix;
    use glam::DVec3;

    /// Points on the helix.
    const HELIX: usize = 700;

    /// The boxes of `HELIX` points on a helix.
    fn helix() -> Vec<Aabb> {
        (0..HELIX)
            .map(|k| {
                let t = k as f64 * 0.05;
                let p = DVec3::new(t.cos(), t.sin(), 0.1 * t);
                Aabb { lo: p, hi: p }
            })
            .collect()
    }

    /// The factors a_i of a rank-1 matrix a_i a_(j+3).
    fn a(i: usize) -> f64 {
        1.0 + (i as f64 * 0.37).sin().abs()
    }

    /// Points on a helix, and the rank-1 matrix a_i b_j over them: every
    /// admissible block has rank 1 exactly, so the prediction is the
    /// built matrix's size to the byte; a limit stops the count past it.
    #[test]
    fn a_rank_one_matrix_is_predicted_exactly() {
        let (n, boxes) = (HELIX, helix());
        let data = (0..n * n).map(|k| a(k / n) * a(k % n + 3)).collect();
        let m = DenseMatrix::from_row_major(n, n, data);
        let opts = HOptions::default();
        let h = HMatrix::build(&boxes, &boxes, &m, &opts);
        assert!(h.stats().low_rank_blocks > 10, "{:?}", h.stats());
        assert_eq!(h.stats().max_rank, 1);
        let p = HMatrix::predict(&boxes, &boxes, &m, &opts, f64::INFINITY);
        assert!(p.complete);
        assert_eq!(p.bytes(), h.heap_bytes() as f64, "{p:?}");
        let stopped = HMatrix::predict(&boxes, &boxes, &m, &opts, 0.5 * p.bytes());
        assert!(!stopped.complete);
        assert!(stopped.bytes() > 0.5 * p.bytes() && stopped.bytes() < p.bytes());
    }

    /// The rank-1 matrix above with every fifth row and every seventh
    /// column zero, which its structure says: dense leaves store the other
    /// lines only, the product is the dense one's, the prediction is still
    /// exact, and less is stored than when the structure says nothing.
    #[test]
    fn rows_and_columns_proved_zero_are_not_stored() {
        struct Lines(DenseMatrix, bool);
        impl Structure for Lines {
            fn zero_lines(&self, rows: &[usize], cols: &[usize]) -> (Vec<bool>, Vec<bool>) {
                let said = self.1;
                (
                    rows.iter().map(|&i| said && i % 5 == 0).collect(),
                    cols.iter().map(|&j| said && j % 7 == 0).collect(),
                )
            }
        }
        impl crate::hmatrix::Entries for Lines {
            fn block(&self, rows: &[usize], cols: &[usize], out: &mut [f64]) {
                self.0.block(rows, cols, out)
            }
        }
        let (n, boxes) = (HELIX, helix());
        let data = (0..n * n)
            .map(|k| {
                let (i, j) = (k / n, k % n);
                if i % 5 == 0 || j % 7 == 0 {
                    0.0
                } else {
                    a(i) * a(j + 3)
                }
            })
            .collect();
        let opts = HOptions::default();
        let said = Lines(DenseMatrix::from_row_major(n, n, data), true);
        let h = HMatrix::build(&boxes, &boxes, &said, &opts);
        let p = HMatrix::predict(&boxes, &boxes, &said, &opts, f64::INFINITY);
        assert_eq!(p.bytes(), h.heap_bytes() as f64, "{p:?}");
        let unsaid = Lines(said.0.clone(), false);
        let whole = HMatrix::build(&boxes, &boxes, &unsaid, &opts);
        let s = h.stats();
        assert!(s.dense_blocks > 10, "{s:?}");
        assert!(
            (s.stored as f64) < 0.8 * whole.stats().stored as f64,
            "{s:?} against {:?}",
            whole.stats()
        );
        let x: Vec<f64> = (0..n).map(|k| (k as f64 * 0.61).cos()).collect();
        let (mut y, mut exact) = (vec![0.0; n], vec![0.0; n]);
        h.matvec(&x, &mut y);
        crate::solve::LinearOperator::apply(&said.0, &x, &mut exact);
        let scale = exact.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (u, v) in y.iter().zip(&exact) {
            assert!((u - v).abs() <= 1e-12 * scale, "{u} against {v}");
        }
    }
}
