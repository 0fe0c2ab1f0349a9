//! The OBJ and MTL line scans' shared pieces: a scanned face, a syntax
//! error at a line, and a statement's text after its keyword.

use super::SceneError;

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
