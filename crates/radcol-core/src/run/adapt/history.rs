//! What refinement has done to each element, and where it stopped helping.
//!
//! At a point where u has a direction-dependent limit (the foot of a block's
//! corner on a floor: walls, floor and the penumbra wedges of the block's
//! vertical edges meet there, and the configuration is self-similar), the
//! element touching the point keeps its max error under every split: its
//! child touching the point sees the same range of directions. Elsewhere a
//! split divides the max error by about 2^(r+1) where u is smooth, and by
//! about 2 next to a concave edge (u ~ x log x) or along a kink, on
//! average: along a kink the factor of one split varies with where the
//! line crosses the child (on the shadow family's line x = 0.2 at r = 3 the
//! element on it went 4.3e-3, 3.6e-3, 2.5e-3, 3.3e-3, then 3.9e-4: flat for
//! three splits, then tenfold). So an element
//! whose estimate fell by less than [`STALL_RATIO`] per split on average
//! over its last `stall_generations` splits is not split again (nor is one
//! at the size floor, `AdaptOptions::min_size`), and the elements left
//! above the target that way are gathered into the [`SingularPoint`]s the
//! report names, with how many of them are at the floor.

use crate::mesh::Mesh;
use serde::Serialize;

/// Splits "stall" when the estimate fell by less than this factor per
/// split, on average over them (a smooth u gives 1/4 at r = 1, an x log x
/// edge or a kink about 1/2, a self-similar point about 1). Judged split by
/// split at 0.7 over 3 splits, as before, and averaged over 3, a kink's
/// uneven factors froze elements on the shadow family's kinks once the
/// estimate followed them closely; averaged over 4 (the default
/// `stall_generations`) they did not.
pub const STALL_RATIO: f64 = 0.85;

/// Per element of the current mesh: the estimates of its ancestors when
/// they were split, the parent's first (NaN beyond the starting mesh).
#[derive(Clone, Debug)]
pub(super) struct History {
    /// Ancestors kept per element.
    depth: usize,
    /// Row-major, `depth` per element.
    ancestors: Vec<f64>,
}

impl History {
    /// The starting mesh of `n` elements, keeping `depth` ancestors.
    pub fn new(n: usize, depth: usize) -> Self {
        Self {
            depth,
            ancestors: vec![f64::NAN; n * depth],
        }
    }

    fn of(&self, k: usize) -> &[f64] {
        &self.ancestors[k * self.depth..(k + 1) * self.depth]
    }

    /// Per element, over how many of its last splits (up to the depth kept)
    /// the estimate fell by less than [`STALL_RATIO`] per split on average,
    /// counted from the last split back while that holds, given the current
    /// `indicator`.
    pub fn stalls(&self, indicator: &[f64]) -> Vec<u32> {
        indicator
            .iter()
            .enumerate()
            .map(|(k, &e)| {
                let mut bound = 1.0;
                let held = self.of(k).iter().take_while(|&&a| {
                    bound *= STALL_RATIO;
                    a.is_finite() && e > bound * a
                });
                held.count() as u32
            })
            .collect()
    }

    /// Whether element k is no longer split: its estimate stalled over
    /// `stall_generations` splits (0: never), given `stalls`.
    pub fn stalled(k: usize, stalls: &[u32], stall_generations: u32) -> bool {
        stall_generations > 0 && stalls[k] >= stall_generations
    }

    /// The history of the refined mesh whose element i came from `parents[i]`
    /// (split when `split[parents[i]]`), given this mesh's `indicator`.
    pub fn refined(&self, parents: &[usize], split: &[bool], indicator: &[f64]) -> Self {
        let mut next = Self::new(parents.len(), self.depth);
        if self.depth == 0 {
            return next;
        }
        for (i, &p) in parents.iter().enumerate() {
            let row = &mut next.ancestors[i * self.depth..(i + 1) * self.depth];
            if split[p] {
                row[0] = indicator[p];
                row[1..].copy_from_slice(&self.of(p)[..self.depth - 1]);
            } else {
                row.copy_from_slice(self.of(p));
            }
        }
        next
    }
}

impl History {
    /// Element `k` starts afresh: its degree was lowered, so its estimate
    /// is not comparable with its ancestors'.
    pub fn forget(&mut self, k: usize) {
        let d = self.depth;
        self.ancestors[k * d..(k + 1) * d].fill(f64::NAN);
    }
}

/// A neighbourhood where refinement stopped reducing the error.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SingularPoint {
    /// Centre of the elements left above the target there (scene units).
    pub position: [f64; 3],
    /// Radius of the ball about `position` that holds them.
    pub radius: f64,
    /// How many elements.
    pub elements: usize,
    /// How many of them are at the size floor rather than stalled (there
    /// the error may still fall under refinement: a kink along a line
    /// halves it per split; lower `AdaptOptions::min_size` to go on).
    pub smallest: usize,
    /// Their largest estimate (relative to max |u_n|, worst channel).
    pub estimate: f64,
}

/// The elements `left` (above the target, not split any more) of `mesh`,
/// gathered into neighbourhoods: elements whose bounding balls touch belong
/// to one; largest estimate first. `smallest(k)`: element k is at the size
/// floor.
pub fn singular_points(
    mesh: &Mesh,
    left: &[usize],
    indicator: &[f64],
    smallest: &dyn Fn(usize) -> bool,
) -> Vec<SingularPoint> {
    let balls: Vec<_> = left.iter().map(|&k| mesh.bounding_ball(k)).collect();
    // Union-find over touching balls (a few hundred elements at most: the
    // quadratic pass costs nothing next to a solve).
    let mut root: Vec<usize> = (0..left.len()).collect();
    fn find(root: &mut [usize], mut i: usize) -> usize {
        while root[i] != i {
            root[i] = root[root[i]];
            i = root[i];
        }
        i
    }
    for a in 0..left.len() {
        for b in a + 1..left.len() {
            let ((ca, ra), (cb, rb)) = (balls[a], balls[b]);
            if (ca - cb).length() <= 1.01 * (ra + rb) {
                let (x, y) = (find(&mut root, a), find(&mut root, b));
                root[x] = y;
            }
        }
    }
    let mut groups: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
    for i in 0..left.len() {
        let r = find(&mut root, i);
        groups.entry(r).or_default().push(i);
    }
    let mut points: Vec<SingularPoint> = groups
        .into_values()
        .map(|members| {
            let centre =
                members.iter().map(|&i| balls[i].0).sum::<glam::DVec3>() / members.len() as f64;
            let radius = members
                .iter()
                .map(|&i| (balls[i].0 - centre).length() + balls[i].1)
                .fold(0.0, f64::max);
            SingularPoint {
                position: centre.to_array(),
                radius,
                elements: members.len(),
                smallest: members.iter().filter(|&&i| smallest(left[i])).count(),
                estimate: members
                    .iter()
                    .map(|&i| indicator[left[i]])
                    .fold(0.0, f64::max),
            }
        })
        .collect();
    points.sort_by(|a, b| b.estimate.total_cmp(&a.estimate));
    points
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::shapes::box_room;
    use std::sync::Arc;

    /// Stalls count the splits back from the last over which the estimate
    /// fell by less than STALL_RATIO per split on average: a split that
    /// halves it ends the run, one uneven factor between halvings does not
    /// make one.
    #[test]
    fn stalls_count_splits_whose_average_factor_is_near_one() {
        let h = History::new(2, 3);
        // Nothing to compare with on the starting mesh.
        assert_eq!(h.stalls(&[1.0, 1.0]), vec![0, 0]);
        let h = h.refined(&[0, 0, 0, 0, 1], &[true, false], &[1.0, 1.0]);
        // Children of element 0 at 0.9 (stalled) and 0.2 (fell); element 1 unsplit.
        let ind = [0.9, 0.2, 0.2, 0.2, 1.0];
        let s = h.stalls(&ind);
        assert_eq!(s, vec![1, 0, 0, 0, 0]);
        let h = h.refined(
            &[0, 0, 0, 0, 1, 2, 3, 4],
            &[true, false, false, false, false],
            &ind,
        );
        let s2 = h.stalls(&[0.8, 0.1, 0.1, 0.1, 0.2, 0.2, 0.2, 1.0]);
        assert_eq!(s2[0], 2);
        assert!(History::stalled(0, &s2, 2) && !History::stalled(0, &s2, 3));
        assert!(!History::stalled(0, &s2, 0) && !History::stalled(1, &s2, 2));
        // A split that lowers the estimate ends the run.
        assert_eq!(h.stalls(&[0.5, 0.1, 0.1, 0.1, 0.2, 0.2, 0.2, 1.0])[0], 0);
        // The element on the shadow family's kink x = 0.2 at r = 3, split
        // after split: 3.9e-2, 4.3e-3, 3.6e-3, 2.5e-3, 3.3e-3, then 3.9e-4.
        // Flat over three splits (stalled, were three the limit), not over
        // four; the next split ends the run.
        let chain = |ancestors: Vec<f64>| History {
            depth: 4,
            ancestors,
        };
        let kink = chain(vec![2.503e-3, 3.615e-3, 4.277e-3, 3.855e-2]);
        let s = kink.stalls(&[3.272e-3]);
        assert_eq!(s, vec![3]);
        assert!(History::stalled(0, &s, 3) && !History::stalled(0, &s, 4));
        let next = chain(vec![3.272e-3, 2.503e-3, 3.615e-3, 4.277e-3]);
        assert_eq!(next.stalls(&[3.932e-4]), vec![0]);
        // A self-similar point: flat within 5 % over four splits.
        let flat = chain(vec![1.02, 0.97, 1.0, 1.04]);
        assert_eq!(flat.stalls(&[1.0]), vec![4]);
    }

    /// Touching elements gather into one neighbourhood, far ones into others.
    #[test]
    fn neighbourhoods_gather_touching_elements() {
        let mesh = crate::mesh::Mesh::new(Arc::new(box_room(1.0, 1.0, 1.0)), 2);
        // Two elements sharing a vertex with element 0 (its first children's
        // neighbours in the refinement order) and one on another wall.
        let far = mesh.len() - 1;
        let ind: Vec<f64> = (0..mesh.len()).map(|k| k as f64).collect();
        let pts = singular_points(&mesh, &[0, 1, far], &ind, &|k| k == 1);
        assert_eq!(pts.len(), 2, "{pts:?}");
        assert_eq!((pts[0].elements, pts[0].smallest), (1, 0));
        assert_eq!((pts[1].elements, pts[1].smallest), (2, 1));
        assert_eq!(pts[0].estimate, far as f64);
        assert_eq!(pts[1].elements, 2);
        let (c, r) = mesh.bounding_ball(far);
        crate::assert_close!(pts[0].radius, r, 1e-15);
        assert!((glam::DVec3::from_array(pts[0].position) - c).length() < 1e-15);
    }
}
