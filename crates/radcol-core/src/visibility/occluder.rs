//! One triangle of the scene that may occlude.

use glam::DVec3;

/// A triangle of the scene that may occlude, with its unit normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Occluder {
    /// Vertices.
    pub v: [DVec3; 3],
    /// Unit normal (b - a) × (c - a) / |…|.
    pub normal: DVec3,
}
