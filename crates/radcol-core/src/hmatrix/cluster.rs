//! Cluster trees: the indices of one side of the matrix (collocation points
//! for rows, basis functions for columns), ordered so that every cluster is a
//! contiguous range, split by geometric bisection of bounding boxes.

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
    pub fn root(&self) -> &Cluster {
        &self.clusters[0]
    }
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
