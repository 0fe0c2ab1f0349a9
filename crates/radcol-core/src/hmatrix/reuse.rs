//! Building a hierarchical matrix from the one of a set of rows and
//! columns that changed only locally (an adaptive step's refined mesh):
//! the cluster trees are the previous ones with the changed items put where
//! the items they replace were ([`ClusterTree::updated`]), so every block
//! whose row and column clusters the change did not touch is a block of
//! the previous matrix, with the same entries, decisions and leaf, and is
//! taken from it instead of being computed again.
//!
//! This rests on the [`super::Structure`] and [`super::Entries`] of an
//! untouched block being the same as before (for radiosity, the plan's
//! classes and integrals of pairs of unchanged elements, see
//! [`crate::assembly::plan::Unchanged`]).

use super::cluster::{Aabb, ClusterTree};
use super::leaf::Leaf;
use super::HMatrix;
use crate::assembly::plan::Unchanged;
use std::collections::HashMap;

/// One side (rows or columns) of a matrix whose items changed since the
/// previous matrix was built: new item i takes the place of old item
/// `near[i]`, and is that item unchanged when `same[i]`.
#[derive(Clone, Copy, Debug)]
pub struct Changed<'a> {
    /// For each new item, the old item it is, or replaces.
    pub near: &'a [usize],
    /// Whether it is that old item unchanged.
    pub same: &'a [bool],
}

/// What a build may take from the matrix of the previous rows and columns.
#[derive(Clone, Copy, Debug)]
pub struct Reuse<'a> {
    /// The previous matrix, built with the same options.
    pub previous: &'a HMatrix,
    /// How its rows changed.
    pub rows: Changed<'a>,
    /// How its columns changed.
    pub cols: Changed<'a>,
}

/// The cluster trees of a build, and for each of their clusters the
/// previous matrix's cluster it equals, if any.
pub(super) struct Trees {
    pub(super) rt: ClusterTree,
    pub(super) ct: ClusterTree,
    row_old: Vec<Option<usize>>,
    col_old: Vec<Option<usize>>,
}

/// `build` given what it may take from `previous`: the matrix of the mesh
/// a refined one was made from, whose rows and columns are both its
/// elements' unknowns (`offsets`: the old and the new discretization's
/// [`crate::discretization::Discretization::offsets`], [`element_items`]);
/// None when there is none, or when the new elements' parents are not
/// known.
pub(super) fn with_elements<T>(
    previous: Option<(&HMatrix, &Unchanged)>,
    offsets: Option<(&[usize], &[usize])>,
    build: impl FnOnce(Option<&Reuse<'_>>) -> T,
) -> T {
    let items = previous
        .zip(offsets)
        .and_then(|((h, u), (old, new))| Some((h, element_items(u, old, new)?)));
    let reuse = items.as_ref().map(|(h, (near, same))| Reuse {
        previous: h,
        rows: Changed { near, same },
        cols: Changed { near, same },
    });
    build(reuse.as_ref())
}

/// The items of a refined mesh whose element k holds items
/// `new[k]..new[k + 1]` (the old mesh's, `old`): for each, the old item it is or replaces
/// (the same item of the element it was split from, or that element's last
/// when it has fewer) and whether it is that item unchanged. None when
/// `unchanged` does not know the new elements' parents.
pub fn element_items(
    unchanged: &Unchanged,
    old: &[usize],
    new: &[usize],
) -> Option<(Vec<usize>, Vec<bool>)> {
    let mut near = Vec::with_capacity(new[unchanged.len()]);
    let mut same = Vec::with_capacity(near.capacity());
    for k in 0..unchanged.len() {
        let p = unchanged.parent(k)?;
        let (f, f_old) = (new[k + 1] - new[k], old[p + 1] - old[p]);
        near.extend((0..f).map(|l| old[p] + l.min(f_old - 1)));
        same.extend(std::iter::repeat_n(unchanged.old(k).is_some(), f));
    }
    Some((near, same))
}

impl Reuse<'_> {
    /// The updated trees for these boxes and leaf size; None when the sides
    /// do not match the previous matrix, or an old leaf would be left empty
    /// (then the build starts afresh).
    pub(super) fn trees(&self, rows: &[Aabb], cols: &[Aabb], leaf_size: usize) -> Option<Trees> {
        let p = self.previous;
        let fits = |c: &Changed<'_>, boxes: &[Aabb], old: &ClusterTree| {
            c.near.len() == boxes.len()
                && c.same.len() == boxes.len()
                && c.near.iter().all(|&o| o < old.order.len())
        };
        if !fits(&self.rows, rows, &p.rt) || !fits(&self.cols, cols, &p.ct) {
            return None;
        }
        let (rt, row_old) =
            p.rt.updated(rows, self.rows.near, self.rows.same, leaf_size)?;
        let (ct, col_old) =
            p.ct.updated(cols, self.cols.near, self.cols.same, leaf_size)?;
        Some(Trees {
            rt,
            ct,
            row_old,
            col_old,
        })
    }

    /// What the block-tree walk of `trees` needs to take whole subtrees
    /// of the previous matrix.
    pub(super) fn taken(&self, trees: &Trees) -> Taken<'_> {
        let new_of = |old: &[Option<usize>], n: usize| {
            let mut m = vec![None; n];
            for (k, o) in old.iter().enumerate() {
                if let Some(o) = *o {
                    m[o] = Some(k);
                }
            }
            m
        };
        let p = self.previous;
        Taken {
            previous: p,
            corner: (p.leaves.iter().enumerate())
                .map(|(k, l)| ((l.rows.start as u32, l.cols.start as u32), k))
                .collect(),
            row_new: new_of(&trees.row_old, p.rt.clusters.len()),
            col_new: new_of(&trees.col_old, p.ct.clusters.len()),
        }
    }

    /// Leaf `k` of the previous matrix as the leaf of clusters `r` and `c`
    /// of `trees`.
    pub(super) fn leaf(&self, k: usize, trees: &Trees, r: usize, c: usize) -> Leaf {
        let (rc, cc) = (&trees.rt.clusters[r], &trees.ct.clusters[c]);
        Leaf {
            rows: rc.start..rc.end,
            cols: cc.start..cc.end,
            block: (r as u32, c as u32),
            admissible: self.previous.leaves[k].admissible,
            data: self.previous.leaves[k].data.clone(),
        }
    }
}

/// The previous matrix's leaves by their first row and column (leaves
/// partition the matrix, so each pair starts one), and its clusters in the
/// new trees where untouched.
pub(super) struct Taken<'a> {
    previous: &'a HMatrix,
    corner: HashMap<(u32, u32), usize>,
    row_new: Vec<Option<usize>>,
    col_new: Vec<Option<usize>>,
}

impl Taken<'_> {
    /// When clusters `r` and `c` of `trees` are both untouched and were a
    /// node of the previous block tree: pushes that node's leaves onto
    /// `out` (as leaves of the new clusters, with their previous index) and
    /// returns true. The node's decisions and its subtree's depend on its
    /// two clusters alone, so they are the previous ones. Its leaves are
    /// consecutive in the previous matrix (block-tree order) from the one
    /// at its first row and column; when that one does not lie within both
    /// clusters, the pair was no node (an ancestor was a leaf), and nothing
    /// is taken.
    pub(super) fn subtree(&self, trees: &Trees, r: usize, c: usize, out: &mut Found) -> bool {
        let (Some(or), Some(oc)) = (trees.row_old[r], trees.col_old[c]) else {
            return false;
        };
        let p = self.previous;
        let (rc, cc) = (&p.rt.clusters[or], &p.ct.clusters[oc]);
        let inside = |l: &Leaf| {
            rc.start <= l.rows.start
                && l.rows.end <= rc.end
                && cc.start <= l.cols.start
                && l.cols.end <= cc.end
        };
        let Some(&first) = self.corner.get(&(rc.start as u32, cc.start as u32)) else {
            return false;
        };
        if !inside(&p.leaves[first]) {
            return false;
        }
        for (k, l) in p.leaves.iter().enumerate().skip(first) {
            if !inside(l) {
                break;
            }
            let (lr, lc) = (l.block.0 as usize, l.block.1 as usize);
            let (nr, nc) = (self.row_new[lr], self.col_new[lc]);
            let (nr, nc) = (nr.expect("untouched"), nc.expect("untouched"));
            out.push(((nr, nc, l.admissible), Some(k)));
        }
        true
    }
}

/// Leaves found by a block-tree walk, in its order: (row cluster, column
/// cluster, admissible), and the previous leaf each is, if taken.
pub(super) type Found = Vec<((usize, usize, bool), Option<usize>)>;

impl Trees {
    /// Fresh trees (nothing to take from a previous matrix).
    pub(super) fn new(rows: &[Aabb], cols: &[Aabb], leaf_size: usize) -> Self {
        let (rt, ct) = (
            ClusterTree::new(rows, leaf_size),
            ClusterTree::new(cols, leaf_size),
        );
        let (row_old, col_old) = (vec![None; rt.clusters.len()], vec![None; ct.clusters.len()]);
        Self {
            rt,
            ct,
            row_old,
            col_old,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hmatrix::{Entries, HOptions, Structure};
    use glam::DVec3;
    use std::sync::atomic::{AtomicU64, Ordering};

    /// The kernel 1 / (ε + r²) between points, counting its entries.
    struct Kernel {
        pts: Vec<DVec3>,
        asked: AtomicU64,
    }

    impl Structure for Kernel {}

    impl Entries for Kernel {
        fn block(&self, rows: &[usize], cols: &[usize], out: &mut [f64]) {
            self.asked
                .fetch_add((rows.len() * cols.len()) as u64, Ordering::Relaxed);
            for (a, &i) in rows.iter().enumerate() {
                for (b, &j) in cols.iter().enumerate() {
                    let r2 = self.pts[i].distance_squared(self.pts[j]);
                    out[a * cols.len() + b] = 1.0 / (1e-3 + r2);
                }
            }
        }
    }

    fn boxes(pts: &[DVec3]) -> Vec<Aabb> {
        pts.iter().map(|&p| Aabb { lo: p, hi: p }).collect()
    }

    fn build(k: &Kernel, opts: &HOptions, reuse: Option<&Reuse<'_>>) -> HMatrix {
        let b = boxes(&k.pts);
        let built = HMatrix::build_checked(&b, &b, k, opts, reuse, |_| Ok::<(), ()>(()));
        built.unwrap().0
    }

    /// y = A x for a fixed x, and ‖y − y_exact‖ / ‖y_exact‖ against the
    /// kernel's exact rows.
    fn product_error(h: &HMatrix, k: &Kernel) -> f64 {
        let n = k.pts.len();
        let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        let mut y = vec![0.0; n];
        h.matvec(&x, &mut y);
        let all: Vec<usize> = (0..n).collect();
        let (mut num, mut den) = (0.0, 0.0);
        let mut row = vec![0.0; n];
        for i in 0..n {
            k.block(&[i], &all, &mut row);
            let exact: f64 = row.iter().zip(&x).map(|(a, b)| a * b).sum();
            (num, den) = (num + (y[i] - exact).powi(2), den + exact * exact);
        }
        (num / den).sqrt()
    }

    /// A sheet of points of which three are each replaced by four nearby
    /// ones (a local refinement): the matrix built from the previous one
    /// takes most of its blocks from it, asks for a fraction of the
    /// entries, and equals, leaf for leaf, the matrix computed afresh on
    /// the same updated trees; both are within the tolerance of the exact
    /// product.
    #[test]
    fn untouched_blocks_are_taken_and_equal_computed_ones() {
        let side = 40;
        let at = |x: f64, y: f64| DVec3::new(x, y, 0.3 * (3.0 * x).sin() * y);
        let old_pts: Vec<DVec3> = (0..side * side)
            .map(|k| {
                at(
                    (k % side) as f64 / side as f64,
                    (k / side) as f64 / side as f64,
                )
            })
            .collect();
        let opts = HOptions {
            tol: 1e-8,
            ..Default::default()
        };
        let old = Kernel {
            pts: old_pts.clone(),
            asked: AtomicU64::new(0),
        };
        let previous = build(&old, &opts, None);
        let replaced = [17, 800, 1555];
        let (mut pts, mut near, mut same) = (Vec::new(), Vec::new(), Vec::new());
        for (o, p) in old_pts.iter().enumerate() {
            let children: &[f64] = if replaced.contains(&o) {
                &[-0.3, -0.1, 0.1, 0.3]
            } else {
                &[0.0]
            };
            for d in children {
                pts.push(at(p.x + d / side as f64, p.y - d / side as f64));
                near.push(o);
                same.push(children.len() == 1);
            }
        }
        let kernel = |pts: &[DVec3]| Kernel {
            pts: pts.to_vec(),
            asked: AtomicU64::new(0),
        };
        let changed = Changed {
            near: &near,
            same: &same,
        };
        let reuse = Reuse {
            previous: &previous,
            rows: changed,
            cols: changed,
        };
        let (taken, fresh) = (kernel(&pts), kernel(&pts));
        let h = build(&taken, &opts, Some(&reuse));
        // The same trees with nothing to take: the previous leaves removed.
        let bare = HMatrix {
            leaves: Vec::new(),
            ..previous.clone()
        };
        let computed = build(
            &fresh,
            &opts,
            Some(&Reuse {
                previous: &bare,
                ..reuse
            }),
        );
        let (s, c) = (h.stats(), computed.stats());
        println!(
            "{s:?}\n{} of {} entries asked",
            taken.asked.load(Ordering::Relaxed),
            fresh.asked.load(Ordering::Relaxed)
        );
        assert_eq!(c.reused_blocks, 0);
        assert!(
            s.reused_blocks * 10 >= s.low_rank_blocks + s.dense_blocks,
            "{s:?}"
        );
        let (asked, all) = (
            taken.asked.load(Ordering::Relaxed),
            fresh.asked.load(Ordering::Relaxed),
        );
        assert!(asked * 3 < all, "{asked} of {all} entries asked");
        assert_eq!(h.leaves.len(), computed.leaves.len());
        for (a, b) in h.leaves.iter().zip(&computed.leaves) {
            assert_eq!((&a.rows, &a.cols, a.block), (&b.rows, &b.cols, b.block));
            assert_eq!(
                format!("{:?}", a.data),
                format!("{:?}", b.data),
                "{:?}",
                a.block
            );
        }
        assert_eq!(h.rt.order, computed.rt.order);
        assert_eq!(h.heap_bytes(), computed.heap_bytes());
        for m in [&h, &computed, &previous] {
            let k = if std::ptr::eq(m, &previous) {
                &old
            } else {
                &taken
            };
            let e = product_error(m, k);
            assert!(e < 1e-7, "product error {e}");
        }
    }
}
