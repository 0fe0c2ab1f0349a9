//! A mesh plus a node set: the collocation points v_{k,j} = m_k(q_j) (eq. 18).
//!
//! Unknown i = k · f_r + j belongs to node j of element k, so the columns of the
//! collocation matrix and its rows share one numbering.

use crate::mesh::{Mesh, SurfacePoint};
use crate::nodes::NodeSet;
use glam::DVec3;
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

/// The collocation discretization of one mesh with one node set.
#[derive(Clone, Debug)]
pub struct Discretization {
    mesh: Arc<Mesh>,
    nodes: NodeSet,
    points: Vec<CollocationPoint>,
}

impl Discretization {
    /// All collocation points of `mesh` for `nodes`.
    pub fn new(mesh: Arc<Mesh>, nodes: NodeSet) -> Self {
        let mut points = Vec::with_capacity(mesh.len() * nodes.len());
        for k in 0..mesh.len() {
            for (j, &[s, t]) in nodes.points().iter().enumerate() {
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
        Self {
            mesh,
            nodes,
            points,
        }
    }

    /// The mesh.
    pub fn mesh(&self) -> &Arc<Mesh> {
        &self.mesh
    }

    /// The node set.
    pub fn nodes(&self) -> &NodeSet {
        &self.nodes
    }

    /// Collocation points, length N = n · f_r.
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

    /// Nodes per element f_r.
    pub fn nodes_per_element(&self) -> usize {
        self.nodes.len()
    }
}
