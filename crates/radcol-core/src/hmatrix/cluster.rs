//! Cluster trees: the indices of one side of the matrix (collocation points
//! for rows, basis functions for columns), ordered so that every cluster is a
//! contiguous range, split by geometric bisection of bounding boxes.

use crate::discretization::Discretization;
use glam::DVec3;

/// An axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Smallest corner.
    pub lo: DVec3,
    /// Largest corner.
    pub hi: DVec3,
}

impl Aabb {
    /// The empty box (the identity of [`Aabb::union`]).
    pub const EMPTY: Self = Self {
        lo: DVec3::INFINITY,
        hi: DVec3::NEG_INFINITY,
    };

    /// The smallest box holding both.
    pub fn union(self, o: Self) -> Self {
        Self {
            lo: self.lo.min(o.lo),
            hi: self.hi.max(o.hi),
        }
    }

    /// The diagonal's length.
    pub fn diameter(&self) -> f64 {
        (self.hi - self.lo).max(DVec3::ZERO).length()
    }

    /// The Euclidean distance between two boxes (0 when they overlap).
    pub fn distance(&self, o: &Self) -> f64 {
        let gap = (self.lo - o.hi).max(o.lo - self.hi).max(DVec3::ZERO);
        gap.length()
    }

    /// The centre.
    pub fn center(&self) -> DVec3 {
        0.5 * (self.lo + self.hi)
    }

    /// The eight corners.
    pub fn corners(&self) -> [DVec3; 8] {
        let (a, b) = (self.lo, self.hi);
        std::array::from_fn(|i| {
            DVec3::new(
                if i & 1 == 0 { a.x } else { b.x },
                if i & 2 == 0 { a.y } else { b.y },
                if i & 4 == 0 { a.z } else { b.z },
            )
        })
    }
}

/// One cluster: the range `start..end` of [`ClusterTree::order`], its box
/// and its two children (none for a leaf).
#[derive(Clone, Debug)]
pub struct Cluster {
    /// First position in the tree's order.
    pub start: usize,
    /// One past the last.
    pub end: usize,
    /// The union of its items' boxes.
    pub bbox: Aabb,
    /// Indices of the two children in [`ClusterTree::clusters`].
    pub children: Option<[usize; 2]>,
}

impl Cluster {
    /// Number of indices.
    pub fn len(&self) -> usize {
        self.end - self.start
    }

    /// True when it holds no index.
    #[cfg(feature = "internals")]
    pub fn is_empty(&self) -> bool {
        self.end == self.start
    }
}

/// A binary cluster tree; the root is cluster 0.
#[derive(Clone, Debug)]
pub struct ClusterTree {
    /// All clusters, parents before children.
    pub clusters: Vec<Cluster>,
    /// `order[p]`: the original index at position p.
    pub order: Vec<usize>,
}

impl ClusterTree {
    /// Builds the tree over items with these boxes: a cluster of more than
    /// `leaf_size` items is split at the median of its items' centres along
    /// the longest side of its box. Items with equal boxes stay together only
    /// as long as the median allows, so the depth is about log2(n / leaf_size).
    pub fn new(boxes: &[Aabb], leaf_size: usize) -> Self {
        let mut tree = Self {
            clusters: Vec::new(),
            order: (0..boxes.len()).collect(),
        };
        tree.split(boxes, 0, boxes.len(), leaf_size.max(1));
        tree
    }

    fn split(&mut self, boxes: &[Aabb], start: usize, end: usize, leaf: usize) -> usize {
        let bbox = self.order[start..end]
            .iter()
            .fold(Aabb::EMPTY, |b, &i| b.union(boxes[i]));
        let id = self.clusters.len();
        self.clusters.push(Cluster {
            start,
            end,
            bbox,
            children: None,
        });
        if end - start <= leaf {
            return id;
        }
        let extent = bbox.hi - bbox.lo;
        let axis = if extent.x >= extent.y && extent.x >= extent.z {
            0
        } else if extent.y >= extent.z {
            1
        } else {
            2
        };
        let mid = start + (end - start) / 2;
        let key = |i: &usize| boxes[*i].center()[axis];
        self.order[start..end]
            .select_nth_unstable_by(mid - start, |a, b| key(a).total_cmp(&key(b)));
        let left = self.split(boxes, start, mid, leaf);
        let right = self.split(boxes, mid, end, leaf);
        self.clusters[id].children = Some([left, right]);
        id
    }

    /// The root cluster.
    #[cfg(any(test, feature = "internals"))]
    pub fn root(&self) -> &Cluster {
        &self.clusters[0]
    }

    /// The tree of a changed set of items (with these `boxes`) made from
    /// this one, so that the clusters the change did not touch stay as
    /// they were: new item i takes the place of old item `near[i]` (itself
    /// when `same[i]`; for an item of a refined element, an item of the
    /// element it was split from). Each old leaf holds the items placed in
    /// it, in the old order; a leaf grown past `leaf_size` is split as in
    /// [`ClusterTree::new`]. Returns the tree and, for each of its
    /// clusters, the old cluster with the same items in the same order
    /// (hence the same box), if there is one; None when an old leaf would
    /// be left empty.
    pub fn updated(
        &self,
        boxes: &[Aabb],
        near: &[usize],
        same: &[bool],
        leaf_size: usize,
    ) -> Option<(Self, Vec<Option<usize>>)> {
        let old_n = self.order.len();
        let mut position = vec![0; old_n];
        for (p, &i) in self.order.iter().enumerate() {
            position[i] = p;
        }
        // Where each old item went: kept as itself, and how many new items
        // were placed at its position.
        let mut kept = vec![false; old_n];
        let mut placed = vec![0usize; old_n];
        for (i, (&o, &s)) in near.iter().zip(same).enumerate() {
            assert!(o < old_n, "new item {i} placed at old item {o} of {old_n}");
            kept[o] |= s;
            placed[o] += 1;
        }
        let mut order: Vec<usize> = (0..boxes.len()).collect();
        order.sort_by_key(|&i| (position[near[i]], !same[i], i));
        let mut tree = Self {
            clusters: Vec::new(),
            order,
        };
        let mut old_of = Vec::new();
        let mut at = 0;
        let walk = Walk {
            old: self,
            boxes,
            kept: &kept,
            placed: &placed,
            leaf: leaf_size.max(1),
        };
        walk.rebuild(0, &mut tree, &mut old_of, &mut at)?;
        old_of.resize(tree.clusters.len(), None);
        Some((tree, old_of))
    }
}

/// What [`ClusterTree::updated`] walks the old tree with.
struct Walk<'a> {
    old: &'a ClusterTree,
    boxes: &'a [Aabb],
    kept: &'a [bool],
    placed: &'a [usize],
    leaf: usize,
}

impl Walk<'_> {
    /// Rebuilds old cluster `c` into `tree` (its items from position `at`
    /// of the new order on), recording in `old_of` which new clusters equal
    /// old ones; returns the new cluster's index, None when a leaf is left
    /// empty.
    fn rebuild(
        &self,
        c: usize,
        tree: &mut ClusterTree,
        old_of: &mut Vec<Option<usize>>,
        at: &mut usize,
    ) -> Option<usize> {
        let old = &self.old.clusters[c];
        let Some([l, r]) = old.children else {
            let items = &self.old.order[old.start..old.end];
            let n: usize = items.iter().map(|&o| self.placed[o]).sum();
            if n == 0 {
                return None;
            }
            let start = *at;
            *at += n;
            let id = tree.split(self.boxes, start, *at, self.leaf);
            let same = n == items.len() && items.iter().all(|&o| self.kept[o]);
            old_of.resize(tree.clusters.len(), None);
            old_of[id] = same.then_some(c);
            return Some(id);
        };
        let id = tree.clusters.len();
        tree.clusters.push(Cluster {
            start: *at,
            end: *at,
            bbox: Aabb::EMPTY,
            children: None,
        });
        old_of.resize(tree.clusters.len(), None);
        let left = self.rebuild(l, tree, old_of, at)?;
        let right = self.rebuild(r, tree, old_of, at)?;
        let (a, b) = (&tree.clusters[left], &tree.clusters[right]);
        let (end, bbox) = (b.end, a.bbox.union(b.bbox));
        tree.clusters[id] = Cluster {
            start: a.start,
            end,
            bbox,
            children: Some([left, right]),
        };
        let same = old_of[left] == Some(l) && old_of[right] == Some(r);
        old_of[id] = same.then_some(c);
        Some(id)
    }
}

/// The boxes of `disc`'s rows (its collocation points) and columns (each
/// basis function's element, by its bounding ball).
pub(super) fn boxes(disc: &Discretization) -> (Vec<Aabb>, Vec<Aabb>) {
    let rows = disc
        .points()
        .iter()
        .map(|p| Aabb {
            lo: p.position,
            hi: p.position,
        })
        .collect();
    let mesh = disc.mesh();
    let cols = (0..mesh.len())
        .flat_map(|k| {
            // A flat element's own corners: the cube of its bounding ball
            // reaches through the planes of the faces it meets, so a wall's
            // elements along the floor cut the floor's plane, and every
            // block of floor rows against them was split to its leaves
            // (the room's near field grew like N^1.4).
            let b = if mesh.is_flat(k) {
                let v = mesh.vertices(k);
                Aabb {
                    lo: v[0].min(v[1]).min(v[2]),
                    hi: v[0].max(v[1]).max(v[2]),
                }
            } else {
                let (c, r) = mesh.bounding_ball(k);
                Aabb {
                    lo: c - DVec3::splat(r),
                    hi: c + DVec3::splat(r),
                }
            };
            std::iter::repeat_n(b, disc.nodes_per(k))
        })
        .collect();
    (rows, cols)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(x: f64, y: f64, z: f64) -> Aabb {
        let p = DVec3::new(x, y, z);
        Aabb { lo: p, hi: p }
    }

    #[test]
    fn clusters_are_contiguous_nested_and_bounded() {
        let boxes: Vec<Aabb> = (0..1000)
            .map(|i| {
                let t = i as f64 * 0.618_033_988_75;
                point(t.fract(), (t * 7.3).fract() * 0.1, (t * 3.1).fract())
            })
            .collect();
        let tree = ClusterTree::new(&boxes, 16);
        let mut sorted = tree.order.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..1000).collect::<Vec<_>>(), "a permutation");
        for c in &tree.clusters {
            for &i in &tree.order[c.start..c.end] {
                let b = boxes[i];
                assert!(c.bbox.lo.cmple(b.lo).all() && c.bbox.hi.cmpge(b.hi).all());
            }
            match c.children {
                Some([l, r]) => {
                    let (l, r) = (&tree.clusters[l], &tree.clusters[r]);
                    assert_eq!((l.start, l.end, r.end), (c.start, r.start, c.end));
                    assert!(l.len().abs_diff(r.len()) <= 1);
                }
                None => assert!(c.len() <= 16),
            }
        }
        // The first split is along x, the longest side.
        let [l, r] = tree.root().children.unwrap();
        assert!(tree.clusters[l].bbox.hi.x <= tree.clusters[r].bbox.lo.x);
    }

    /// A tree updated after a few items are each replaced by four nearby
    /// ones is a valid cluster tree, and the clusters away from them are the
    /// old ones: the same items in the same order with the same box.
    #[test]
    fn an_updated_tree_keeps_the_clusters_a_change_did_not_touch() {
        let at = |i: usize| {
            let t = i as f64 * 0.618_033_988_75;
            point(t.fract(), (t * 7.3).fract() * 0.1, (t * 3.1).fract())
        };
        let old_boxes: Vec<Aabb> = (0..1000).map(at).collect();
        let old = ClusterTree::new(&old_boxes, 16);
        let replaced = [3, 500, 501, 977];
        let (mut boxes, mut near, mut same) = (Vec::new(), Vec::new(), Vec::new());
        for (o, b) in old_boxes.iter().enumerate() {
            let children = if replaced.contains(&o) { 4 } else { 1 };
            for k in 0..children {
                let d = if children == 1 {
                    0.0
                } else {
                    1e-3 * (k as f64 - 1.5)
                };
                boxes.push(Aabb {
                    lo: b.lo + DVec3::new(d, -d, d),
                    hi: b.hi + DVec3::new(d, -d, d),
                });
                near.push(o);
                same.push(children == 1);
            }
        }
        let (tree, old_of) = old
            .updated(&boxes, &near, &same, 16)
            .expect("no leaf emptied");
        let mut sorted = tree.order.clone();
        sorted.sort_unstable();
        assert_eq!(
            sorted,
            (0..boxes.len()).collect::<Vec<_>>(),
            "a permutation"
        );
        let mut kept = 0;
        for (c, o) in tree.clusters.iter().zip(&old_of) {
            let items = &tree.order[c.start..c.end];
            let hull = items.iter().fold(Aabb::EMPTY, |b, &i| b.union(boxes[i]));
            assert_eq!(c.bbox, hull);
            match c.children {
                Some([l, r]) => {
                    let (l, r) = (&tree.clusters[l], &tree.clusters[r]);
                    assert_eq!((l.start, l.end, r.end), (c.start, r.start, c.end));
                }
                None => assert!(c.len() <= 16),
            }
            if let Some(o) = *o {
                assert!(items.iter().all(|&i| same[i]), "kept, so untouched");
                let oc = &old.clusters[o];
                let mapped: Vec<usize> = items.iter().map(|&i| near[i]).collect();
                assert_eq!(mapped, old.order[oc.start..oc.end]);
                assert_eq!(c.bbox, oc.bbox);
                kept += 1;
            }
        }
        // Every old cluster without a replaced item is kept.
        let untouched = old
            .clusters
            .iter()
            .filter(|c| {
                !old.order[c.start..c.end]
                    .iter()
                    .any(|o| replaced.contains(o))
            })
            .count();
        assert_eq!(kept, untouched);
        assert!(
            kept + 4 * 8 >= old.clusters.len(),
            "{kept} of {}",
            old.clusters.len()
        );
        // An old leaf left empty is refused.
        let leaf = old.clusters.iter().find(|c| c.children.is_none()).unwrap();
        let left: Vec<usize> = (0..1000)
            .filter(|o| !old.order[leaf.start..leaf.end].contains(o))
            .collect();
        let boxes: Vec<Aabb> = left.iter().map(|&o| old_boxes[o]).collect();
        assert!(old
            .updated(&boxes, &left, &vec![true; left.len()], 16)
            .is_none());
    }

    #[test]
    fn box_distances() {
        let a = Aabb {
            lo: DVec3::ZERO,
            hi: DVec3::ONE,
        };
        let b = Aabb {
            lo: DVec3::new(4.0, 5.0, 0.5),
            hi: DVec3::new(6.0, 6.0, 2.0),
        };
        assert_eq!(a.distance(&b), 5.0);
        assert_eq!(a.distance(&a), 0.0);
        assert!((a.diameter() - 3f64.sqrt()).abs() < 1e-15);
    }
}
