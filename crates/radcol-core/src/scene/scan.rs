//! The OBJ and MTL line scans' shared pieces: a scanned face, a syntax
//! error at a line, and a statement's text after its keyword.

use super::raw::{duplicate_message, Dropped};
use super::validate::{degenerate_why, oriented_key};
use super::SceneError;
use glam::DVec3;
use std::collections::hash_map::Entry;
use std::collections::HashMap;

/// A face as the line scan read it.
#[derive(Debug)]
pub(super) struct ScanFace {
    pub(super) line: usize,
    pub(super) group: String,
    pub(super) material: usize,
    pub(super) vertices: Vec<usize>,
    /// The texture coordinates of its vertices (v down), when all have them.
    pub(super) uvs: Option<Vec<[f64; 2]>>,
}

/// A syntax error at `at`.
pub(super) fn syntax(at: String, message: impl Into<String>) -> SceneError {
    SceneError::Syntax {
        at,
        message: message.into(),
    }
}

/// The rest of a statement after its keyword, trimmed.
pub(super) fn rest<'a>(line: &'a str, keyword: &str) -> &'a str {
    line[keyword.len()..].trim()
}

/// The triangle faces read so far, to drop copies while scanning: by
/// position triple (same cyclic order) the line of the first, and the
/// copies dropped.
#[derive(Default)]
pub(super) struct Copies {
    seen: HashMap<[[u64; 3]; 3], usize>,
    dropped: Dropped,
}

impl Copies {
    /// Pushes `face` to `faces` unless it is a copy of an earlier triangle
    /// face (same positions in the same cyclic order; degenerate triangles
    /// are left to the shared checks), which is noted instead; `at(line)`
    /// names a line. Returns whether the face was kept.
    pub(super) fn keep(
        &mut self,
        face: ScanFace,
        positions: &[DVec3],
        faces: &mut Vec<ScanFace>,
        at: &dyn Fn(usize) -> String,
    ) -> bool {
        if let [a, b, c] = face.vertices[..] {
            let t = [positions[a], positions[b], positions[c]];
            if degenerate_why(t).is_none() {
                match self.seen.entry(oriented_key(&t)) {
                    Entry::Occupied(e) => {
                        let first = *e.get();
                        let line = face.line;
                        self.dropped
                            .note(|| duplicate_message(&at(line), &at(first)));
                        return false;
                    }
                    Entry::Vacant(e) => {
                        e.insert(face.line);
                    }
                }
            }
        }
        faces.push(face);
        true
    }

    /// The copies dropped (the positions seen are let go).
    pub(super) fn dropped(self) -> Dropped {
        self.dropped
    }
}
