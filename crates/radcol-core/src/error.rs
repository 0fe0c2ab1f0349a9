//! Typed errors of the library. Each names the value, element or node at fault.

use glam::DVec3;

/// Bad input: every variant says what was wrong and where.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum InputError {
    /// Polynomial degree out of range.
    #[error("degree r = {degree} is not supported (radcol supports r = 0..=6)")]
    Degree {
        /// The degree asked for.
        degree: usize,
    },
    /// Node parameter out of range.
    #[error("alpha = {alpha} must lie strictly between 0 and 1/3 so that all nodes are interior")]
    Alpha {
        /// The α asked for.
        alpha: f64,
    },
    /// An expression failed to parse or uses an unknown variable.
    #[error("expression '{expr}': {message}")]
    Expression {
        /// The expression text.
        expr: String,
        /// What is wrong with it.
        message: String,
    },
    /// rho outside [0, 1) at a collocation point.
    #[error("{name} = {value} at element {element}, node {node} (x, y, z = {:.6}, {:.6}, {:.6}) lies outside [0, 1)", position.x, position.y, position.z)]
    Reflectivity {
        /// "reflectivity" or "reflectivity R" (the channel).
        name: String,
        /// The offending value.
        value: f64,
        /// Element index.
        element: usize,
        /// Node index within the element.
        node: usize,
        /// Where.
        position: DVec3,
    },
    /// A field evaluated to NaN or infinity (or a negative emission).
    #[error("{what} = {value} at element {element}, node {node} (x, y, z = {:.6}, {:.6}, {:.6}) is not a valid value", position.x, position.y, position.z)]
    InvalidValue {
        /// Which field ("emission R", "exact solution").
        what: String,
        /// The offending value.
        value: f64,
        /// Element index.
        element: usize,
        /// Node index within the element.
        node: usize,
        /// Where.
        position: DVec3,
    },
    /// The dense matrix would not fit in memory.
    #[error("{unknowns} unknowns need a dense {unknowns}×{unknowns} matrix: {:.2} GiB for the matrix (plus {:.2} GiB for an LU copy), but only {:.2} GiB of memory is available; lower --level or --degree", *bytes_matrix as f64 / 1073741824.0, *bytes_lu as f64 / 1073741824.0, *bytes_available as f64 / 1073741824.0)]
    TooLarge {
        /// Number of unknowns N.
        unknowns: usize,
        /// Bytes for the geometric matrix.
        bytes_matrix: u64,
        /// Extra bytes for a dense LU.
        bytes_lu: u64,
        /// Bytes available.
        bytes_available: u64,
    },
    /// Anything else about the problem set-up.
    #[error("{0}")]
    Other(String),
}

/// Every error the library returns.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Bad input.
    #[error(transparent)]
    Input(#[from] InputError),
    /// A linear solver failed.
    #[error(transparent)]
    Solve(#[from] crate::solve::SolveError),
    /// An assembly backend failed (GPU device lost, validation error, …).
    #[error("assembly backend '{backend}': {message}")]
    Backend {
        /// Backend name.
        backend: String,
        /// What happened.
        message: String,
    },
}
