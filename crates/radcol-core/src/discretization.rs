//! A mesh plus node sets: the collocation points v_{k,j} = m_k(q_j) (eq. 18).
//!
//! Each element has a node set, one for all (uniform) or one of a few by
//! element ([`Discretization::with_degrees`]: a degree per element). The
//! unknowns of element k are `range(k)`, consecutive and in element order,
//! so the columns of the collocation matrix and its rows share one
//! numbering; with one node set, unknown i = k · f_r + j is node j of
//! element k.

use crate::error::InputError;
use crate::mesh::{Mesh, SurfacePoint};
use crate::nodes::NodeSet;
use glam::DVec3;
use std::ops::Range;
use std::sync::Arc;

/// One collocation point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CollocationPoint {
    /// Element k.
    pub element: usize,
    /// Node j within the element.
    pub node: usize,
    /// Node coordinates (s, t) in σ.
    pub st: [f64; 2],
    /// Position v_{k,j}.
    pub position: DVec3,
    /// Inner unit normal at v_{k,j}.
    pub normal: DVec3,
}

/// The collocation discretization of one mesh with its node sets.
#[derive(Clone, Debug)]
pub struct Discretization {
    mesh: Arc<Mesh>,
    /// The distinct node sets (one when uniform).
    sets: Vec<NodeSet>,
    /// Per element, its node set's index in `sets` (empty when uniform).
    set_of: Vec<u8>,
    /// Per element, its first unknown; one more entry: N.
    offsets: Vec<usize>,
    points: Vec<CollocationPoint>,
}

impl Discretization {
    /// All collocation points of `mesh` for `nodes` on every element.
    pub fn new(mesh: Arc<Mesh>, nodes: NodeSet) -> Self {
        Self::build(mesh, vec![nodes], Vec::new())
    }

    /// A degree per element: element k takes the node set of `sets` whose
    /// degree is `degrees[k]`.
    ///
    /// # Errors
    /// When `degrees` does not have one entry per element, names a degree
    /// no set of `sets` has, or two sets share a degree.
    pub fn with_degrees(
        mesh: Arc<Mesh>,
        sets: Vec<NodeSet>,
        degrees: &[usize],
    ) -> Result<Self, InputError> {
        let bad = |message: String| Err(InputError::DegreePerElement { message });
        if degrees.len() != mesh.len() {
            return bad(format!(
                "{} degrees for {} elements",
                degrees.len(),
                mesh.len()
            ));
        }
        for (i, s) in sets.iter().enumerate() {
            if sets[..i].iter().any(|o| o.degree() == s.degree()) {
                return bad(format!("two node sets of degree {}", s.degree()));
            }
        }
        let mut set_of = Vec::with_capacity(degrees.len());
        for (k, &r) in degrees.iter().enumerate() {
            match sets.iter().position(|s| s.degree() == r) {
                Some(i) => set_of.push(i as u8),
                None => return bad(format!("element {k} has degree {r}, and no node set has")),
            }
        }
        // Only the sets used, in order of degree.
        let mut used: Vec<usize> = (0..sets.len())
            .filter(|&i| set_of.contains(&(i as u8)))
            .collect();
        used.sort_by_key(|&i| sets[i].degree());
        let renumber: Vec<u8> = (0..sets.len())
            .map(|i| used.iter().position(|&u| u == i).unwrap_or(0) as u8)
            .collect();
        let set_of: Vec<u8> = set_of.iter().map(|&i| renumber[i as usize]).collect();
        let sets: Vec<NodeSet> = used.iter().map(|&i| sets[i].clone()).collect();
        let set_of = if sets.len() > 1 { set_of } else { Vec::new() };
        if sets.is_empty() {
            // No element: any set will do.
            return Ok(Self::build(mesh, vec![NodeSet::new(0, 0.1)?], Vec::new()));
        }
        Ok(Self::build(mesh, sets, set_of))
    }

    fn build(mesh: Arc<Mesh>, sets: Vec<NodeSet>, set_of: Vec<u8>) -> Self {
        let set = |k: usize| &sets[set_of.get(k).map_or(0, |&i| i as usize)];
        let mut offsets = Vec::with_capacity(mesh.len() + 1);
        let mut points = Vec::new();
        for k in 0..mesh.len() {
            offsets.push(points.len());
            for (j, &[s, t]) in set(k).points().iter().enumerate() {
                let SurfacePoint {
                    position, normal, ..
                } = mesh.point(k, s, t);
                points.push(CollocationPoint {
                    element: k,
                    node: j,
                    st: [s, t],
                    position,
                    normal,
                });
            }
        }
        offsets.push(points.len());
        Self {
            mesh,
            sets,
            set_of,
            offsets,
            points,
        }
    }

    /// The mesh.
    pub fn mesh(&self) -> &Arc<Mesh> {
        &self.mesh
    }

    /// The node set of element `k`.
    #[inline]
    pub fn nodes_of(&self, k: usize) -> &NodeSet {
        &self.sets[self.set_of.get(k).map_or(0, |&i| i as usize)]
    }

    /// The node set of every element, when they share one.
    pub fn uniform_nodes(&self) -> Option<&NodeSet> {
        (self.sets.len() == 1).then(|| &self.sets[0])
    }

    /// The distinct node sets, by increasing degree (one when uniform).
    pub fn node_sets(&self) -> &[NodeSet] {
        &self.sets
    }

    /// Element `k`'s index in [`Discretization::node_sets`].
    #[inline]
    pub fn set_index(&self, k: usize) -> usize {
        self.set_of.get(k).map_or(0, |&i| i as usize)
    }

    /// The degree of element `k`.
    #[inline]
    pub fn degree(&self, k: usize) -> usize {
        self.nodes_of(k).degree()
    }

    /// The largest degree of any element.
    pub fn max_degree(&self) -> usize {
        self.sets.iter().map(NodeSet::degree).max().unwrap_or(0)
    }

    /// How many elements have each degree (index: the degree, up to
    /// [`Self::max_degree`]).
    pub fn elements_per_degree(&self) -> Vec<usize> {
        let mut counts = vec![0; self.max_degree() + 1];
        for k in 0..self.mesh.len() {
            counts[self.degree(k)] += 1;
        }
        counts
    }

    /// The unknowns (and collocation points) of element `k`.
    #[inline]
    pub fn range(&self, k: usize) -> Range<usize> {
        self.offsets[k]..self.offsets[k + 1]
    }

    /// The unknowns of elements `elements` (consecutive).
    #[inline]
    pub fn range_of(&self, elements: Range<usize>) -> Range<usize> {
        self.offsets[elements.start]..self.offsets[elements.end]
    }

    /// Per element, its first unknown, and N last (length n + 1).
    pub fn offsets(&self) -> &[usize] {
        &self.offsets
    }

    /// Element `k`'s first unknown.
    #[inline]
    pub fn offset(&self, k: usize) -> usize {
        self.offsets[k]
    }

    /// Nodes of element `k` (f_r of its degree).
    #[inline]
    pub fn nodes_per(&self, k: usize) -> usize {
        self.offsets[k + 1] - self.offsets[k]
    }

    /// The most nodes of any element.
    pub fn max_nodes_per_element(&self) -> usize {
        self.sets.iter().map(NodeSet::len).max().unwrap_or(0)
    }

    /// `elements` cut into runs of consecutive elements with one node set.
    pub fn runs_of_one_set(
        &self,
        elements: Range<usize>,
    ) -> impl Iterator<Item = Range<usize>> + '_ {
        let mut start = elements.start;
        std::iter::from_fn(move || {
            if start >= elements.end {
                return None;
            }
            let set = self.set_index(start);
            let mut end = start + 1;
            while end < elements.end && self.set_index(end) == set {
                end += 1;
            }
            let run = start..end;
            start = end;
            Some(run)
        })
    }

    /// The element of unknown `i`.
    #[inline]
    pub fn element_of(&self, i: usize) -> usize {
        self.points[i].element
    }

    /// Collocation points, length N, ordered like the unknowns.
    pub fn points(&self) -> &[CollocationPoint] {
        &self.points
    }

    /// Number of unknowns N.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True when there is no unknown.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::shapes::sphere;

    /// A degree per element numbers each element's unknowns consecutively,
    /// with its own node set, and refuses degrees it has no set for.
    #[test]
    fn a_degree_per_element() {
        let mesh = Arc::new(Mesh::new(Arc::new(sphere(1.0)), 1));
        let sets = vec![NodeSet::new(3, 0.1).unwrap(), NodeSet::new(1, 0.2).unwrap()];
        let degrees: Vec<usize> = (0..mesh.len())
            .map(|k| if k % 3 == 0 { 1 } else { 3 })
            .collect();
        let d = Discretization::with_degrees(mesh.clone(), sets.clone(), &degrees).unwrap();
        assert_eq!(d.node_sets().len(), 2);
        assert_eq!(d.node_sets()[0].degree(), 1, "sets by increasing degree");
        let mut next = 0;
        for (k, &r) in degrees.iter().enumerate() {
            assert_eq!(d.degree(k), r);
            assert_eq!(d.range(k).start, next);
            assert_eq!(d.nodes_per(k), (r + 1) * (r + 2) / 2);
            for (j, i) in d.range(k).enumerate() {
                let p = &d.points()[i];
                assert_eq!((p.element, p.node, p.st), (k, j, d.nodes_of(k).points()[j]));
                assert_eq!(d.element_of(i), k);
            }
            next = d.range(k).end;
        }
        assert_eq!(next, d.len());
        assert_eq!(d.max_nodes_per_element(), 10);
        assert!(d.uniform_nodes().is_none());
        // One degree used: uniform.
        let u = Discretization::with_degrees(mesh.clone(), sets.clone(), &vec![3; mesh.len()]);
        assert!(u.unwrap().uniform_nodes().is_some_and(|n| n.degree() == 3));
        let e = Discretization::with_degrees(mesh.clone(), sets, &vec![2; mesh.len()]).unwrap_err();
        assert!(e.to_string().contains("element 0 has degree 2"), "{e}");
    }
}
