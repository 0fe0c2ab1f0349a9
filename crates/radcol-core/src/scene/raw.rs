//! What a loader hands to the shared checks ([`super::validate`]): raw
//! triangles with their origin, the raw scene, and capped warning lists.

use super::{Material, TriangleOrigin, MAX_WARNINGS_PER_KIND};
use crate::camera::Camera;
use glam::DVec3;
use std::path::PathBuf;

/// One input triangle before checks.
#[derive(Clone, Debug)]
pub(crate) struct RawTriangle {
    /// Group (OBJ `g`/`o`, builder mesh name).
    pub group: String,
    /// Index into the scene's materials.
    pub material: usize,
    /// World positions, front face counter-clockwise.
    pub vertices: [DVec3; 3],
    /// Where it came from, for messages ("a.obj:12", "mesh 'floor' face 3").
    pub at: String,
    /// Texture coordinates of the vertices (OBJ `vt`, glTF TEXCOORD_n), v
    /// down from the image's top edge as in glTF.
    pub uv: Option<[[f64; 2]; 3]>,
    /// The input triangle it is, or a piece of.
    pub origin: TriangleOrigin,
}

/// Everything a loader gathered, before the shared checks.
#[derive(Debug)]
pub(crate) struct RawScene {
    pub name: String,
    pub materials: Vec<Material>,
    pub triangles: Vec<RawTriangle>,
    pub camera: Option<Camera>,
    pub warnings: Vec<String>,
    pub source: Option<PathBuf>,
    /// Duplicate triangles the loader dropped while reading.
    pub duplicates: Dropped,
}

/// Duplicate triangles a loader dropped while reading, so that a file of
/// one triangle repeated millions of times is not held in memory first:
/// the first [`MAX_WARNINGS_PER_KIND`] messages, and how many more. The
/// shared checks drop the rest and warn about all of them together.
#[derive(Debug, Default)]
pub(crate) struct Dropped {
    pub listed: Vec<String>,
    pub more: usize,
}

impl Dropped {
    /// Notes one more dropped copy (its message formatted only while
    /// listed).
    pub(crate) fn note(&mut self, message: impl FnOnce() -> String) {
        if self.listed.len() < MAX_WARNINGS_PER_KIND {
            self.listed.push(message());
        } else {
            self.more += 1;
        }
    }
}

/// The warning for a triangle at `at` dropped as a copy of the one at
/// `first`.
pub(crate) fn duplicate_message(at: &str, first: &str) -> String {
    format!("{at}: duplicate of the triangle at {first} (same vertices, same orientation) dropped")
}

/// Collects warnings of one kind, listing the first few and counting the rest.
pub(crate) struct Capped<'a> {
    out: &'a mut Vec<String>,
    kind: &'static str,
    count: usize,
}

impl<'a> Capped<'a> {
    pub(crate) fn new(out: &'a mut Vec<String>, kind: &'static str) -> Self {
        Self {
            out,
            kind,
            count: 0,
        }
    }
    pub(crate) fn push(&mut self, message: String) {
        if self.count < MAX_WARNINGS_PER_KIND {
            self.out.push(message);
        }
        self.count += 1;
    }

    /// Counts `n` more warnings without listing them.
    pub(crate) fn count_more(&mut self, n: usize) {
        self.count += n;
    }
}

impl Drop for Capped<'_> {
    fn drop(&mut self) {
        if self.count > MAX_WARNINGS_PER_KIND {
            self.out.push(format!(
                "... and {} more {} warnings",
                self.count - MAX_WARNINGS_PER_KIND,
                self.kind
            ));
        }
    }
}
