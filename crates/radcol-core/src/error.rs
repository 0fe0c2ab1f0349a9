//! Typed errors of the library. Each names the value, element or node at fault.

use glam::DVec3;

/// Which of a problem's fields a value belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FieldKind {
    /// The reflectivity ρ.
    Reflectivity,
    /// The emission E.
    Emission,
    /// The exact solution u given to measure errors against.
    ExactSolution,
}

/// A field of a problem, of one colour channel or of a scalar problem, as
/// messages name it: "reflectivity", "emission R".
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FieldName {
    /// Which field.
    pub kind: FieldKind,
    /// The channel's name; None for a scalar problem (and the exact solution).
    pub channel: Option<String>,
}

impl std::fmt::Display for FieldName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self.kind {
            FieldKind::Reflectivity => "reflectivity",
            FieldKind::Emission => "emission",
            FieldKind::ExactSolution => "exact solution",
        })?;
        match &self.channel {
            Some(c) => write!(f, " {c}"),
            None => Ok(()),
        }
    }
}

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
    /// A degree per element that does not fit the mesh or the node sets.
    #[error("degree per element: {message}")]
    DegreePerElement {
        /// What does not fit.
        message: String,
    },
    /// Node parameter out of range.
    #[error("alpha = {alpha} must lie in [1e-9, 1/3): below 1/3 so that all nodes are interior, and at least 1e-9 because nodes within rounding of an element's corners coincide with its neighbours' and make the curved maps singular (the sphere failed at 1e-14)")]
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
        /// The reflectivity, of its channel when there are several.
        name: FieldName,
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
        what: FieldName,
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
    #[error("{}, but only {} of memory is available; use a coarser mesh or a lower degree", need(*unknowns, *bytes_matrix, *bytes_lu), gib(*bytes_available as f64))]
    TooLarge {
        /// Number of unknowns N (`u64::MAX` when counting stopped: more than
        /// any memory holds).
        unknowns: u64,
        /// Bytes for the geometric matrix (8 N²).
        bytes_matrix: f64,
        /// Extra bytes for a dense LU.
        bytes_lu: f64,
        /// Bytes available.
        bytes_available: u64,
    },
    /// The solve's peak, predicted once its plan is built, would not fit in
    /// the memory available ([`crate::run::MemoryUse`]).
    #[error("the solve would need {} more memory at its peak (matrix {}, then {} for the linear solver or {} for the error estimate, the larger), but {} is available; use a coarser mesh or a lower degree, or skip the estimate", gib(*to_come), gib(*matrix), gib(*solver), gib(*estimate), gib(*available as f64))]
    PeakTooLarge {
        /// Bytes still to be allocated at the peak.
        to_come: f64,
        /// Of which the geometric matrix.
        matrix: f64,
        /// The linear solver's working memory.
        solver: f64,
        /// The error estimate's working memory.
        estimate: f64,
        /// Bytes available.
        available: u64,
    },
    /// A relit problem on a surface other than the one assembled on.
    #[error("relighting solves on the operator assembled for '{assembled}'; the problem is on '{given}' (a different surface object): assemble it first")]
    OtherSurface {
        /// The surface the operator was assembled on.
        assembled: String,
        /// The surface of the problem given.
        given: String,
    },
    /// A maximum edge length that is not a positive finite number.
    #[error("max edge length {value} must be a positive finite number (scene units)")]
    MaxEdge {
        /// The length asked for.
        value: f64,
    },
    /// A grading exponent outside the accepted range.
    #[error("grading exponent {value} must lie in [{}, {}]: 1 is no grading, 2 suits degree 1, and beyond 3 the elements at each line multiply by a power of the mesh size", range.start(), range.end())]
    Grade {
        /// The exponent asked for.
        value: f64,
        /// The accepted range.
        range: std::ops::RangeInclusive<f64>,
    },
    /// A graded zone width that is not a positive finite number.
    #[error("graded zone width {value} must be a positive finite number (scene units)")]
    GradeZone {
        /// The width asked for.
        value: f64,
    },
    /// A quadrature tolerance that f64 cannot deliver (or outside (0, 1)).
    #[error("quadrature tolerance {value}: must lie in [{min:e}, 1); f64 sums carry a rounding error of about 1e-16, so a smaller tolerance only makes the adaptive rules subdivide every near pair to their depth limit")]
    QuadratureTolerance {
        /// The tolerance asked for.
        value: f64,
        /// The smallest accepted.
        min: f64,
    },
    /// A scene too small or too large for the kernel's f64 arithmetic.
    #[error("the scene is {extent:e} across (bounding-box diagonal): radcol works with scenes between {min:e} and {max:e} across, where the kernel's fourth powers of distances stay within double precision; the answer does not depend on the unit of length, so rescale the coordinates")]
    SceneExtent {
        /// The bounding box's diagonal.
        extent: f64,
        /// Smallest accepted.
        min: f64,
        /// Largest accepted.
        max: f64,
    },
    /// A target error outside [`crate::run::adapt::MIN_TARGET`], 1).
    #[error("target error {value} must lie in [1e-8, 1): it is the max error relative to the reflected light (or to max |u|), and the estimate's integrals are accurate to 1e-9")]
    TargetError {
        /// The target asked for.
        value: f64,
    },
    /// A visibility budget outside [0, 1).
    #[error("visibility budget {value} must lie in [0, 1): it is the unoccluded share of a point's view whose visibility may be approximated (0: none)")]
    VisibilityBudget {
        /// The budget asked for.
        value: f64,
    },
    /// A target error asked of a problem where nothing emits light.
    #[error("nothing emits light (the emission is zero in every channel): u = 0 everywhere, so a target error relative to max |u| cannot be measured; give the scene an emitter")]
    NoEmission,
    /// An adaptive size floor outside [0, 1).
    #[error("smallest element size {value} must lie in [0, 1): it is a fraction of the diagonal of the scene's bounding box")]
    MinSize {
        /// The floor asked for.
        value: f64,
    },
    /// A degree per element asked for with a backend that takes one node
    /// set per assembly.
    #[error("a degree per element (hp) needs the CPU backend: the {backend} backend's far-field shader takes one node set per assembly; assemble on the CPU (`CpuBackend`), or leave out hp (`AdaptOptions::hp`)")]
    HpBackend {
        /// The backend asked for.
        backend: String,
    },
    /// A compression tolerance outside (0, 1).
    #[error("compression tolerance {value} must lie in (0, 1): it is the relative error of each compressed block (Frobenius)")]
    CompressionTolerance {
        /// The tolerance asked for.
        value: f64,
    },
    /// The dense operator or LU asked for in a solve spread over ranks.
    #[error("a solve spread over {ranks} ranks stores the compressed operator and solves it with GMRES; the dense operator and LU run in one process (run without mpirun, or choose `--operator compressed` and `--solver gmres`)")]
    NotDistributed {
        /// The ranks of the solve.
        ranks: usize,
    },
    /// Fewer rows than ranks to share them.
    #[error("{unknowns} unknowns are too few to share among {ranks} ranks (each needs at least one row); use fewer ranks or a finer mesh")]
    TooFewRows {
        /// Unknowns of the mesh.
        unknowns: usize,
        /// The ranks of the solve.
        ranks: usize,
    },
    /// LU asked for with a compressed operator.
    #[error("LU factors the dense matrix, and the compressed operator does not store one: solve the compressed operator with GMRES (`SolverKind::Gmres`), or choose the dense operator (`OperatorChoice::Dense`)")]
    CompressedLu,
    /// The compressed operator, once built, leaves too little memory for
    /// the rest of the solve.
    #[error("the compressed operator takes {} ({:.3} of the dense matrix) and the rest of the solve would need {} more, but {} is available; use a coarser mesh or a lower degree, a larger compression tolerance, or skip the estimate", gib(*stored), fraction, gib(*to_come), gib(*available as f64))]
    CompressedTooLarge {
        /// Bytes of the built operator.
        stored: f64,
        /// Its stored numbers over the dense matrix's.
        fraction: f64,
        /// Bytes still to come (solver or estimate).
        to_come: f64,
        /// Bytes available.
        available: u64,
    },
    /// The compressed operator, predicted from the geometry before anything
    /// is computed (`crate::hmatrix::HMatrix::predict`), would not fit in
    /// memory with the plan's table of element pairs.
    #[error("{unknowns} unknowns need a compressed operator of {} {} ({} of it dense blocks near the diagonal, counted from the geometry), and {} for the table of their element pairs' classes, but only {} of memory is available; use a coarser mesh or a lower degree", if *complete { "about" } else { "more than" }, gib(*operator), gib(*near), gib(*pair_table), gib(*available as f64))]
    CompressedWontFit {
        /// Unknowns N.
        unknowns: u64,
        /// Predicted bytes of the operator (a lower count when the count
        /// stopped at the memory available).
        operator: f64,
        /// Of which dense leaves.
        near: f64,
        /// False when the count stopped (at four times the memory
        /// available) before the end.
        complete: bool,
        /// Expected bytes of pair classes
        /// ([`crate::assembly::pair_table_bytes`]).
        pair_table: f64,
        /// Bytes available.
        available: u64,
    },
    /// The plan's table of element pair classes would not fit in memory.
    #[error("{} need a table of their element pairs' classes of {} (kept by the assembly plan as runs of equal classes, about 44 n^1.5 bytes for n elements), but only {} of memory is available; use a coarser mesh", elements_text(*elements), gib(*bytes), gib(*available as f64))]
    PairTableTooLarge {
        /// Elements n.
        elements: u64,
        /// Its expected bytes ([`crate::assembly::pair_table_bytes`]).
        bytes: f64,
        /// Bytes available.
        available: u64,
    },
    /// The candidate occluders of the partly visible pairs, which the plan
    /// holds while the matrix is built, would not fit in memory (predicted
    /// from sampled row blocks: [`crate::run::AssemblyCost`]).
    #[error("{} in a scene that occludes have about {:.3e} partly visible pairs (± {:.0} %), whose candidate occluders the assembly plan would hold in about {} (predicted from {sampled} of their row blocks), but only {} of memory is available; use a coarser mesh (a scanned mesh's own triangles are elements already at level 0) or fewer occluding triangles", elements_text(*elements), partial_pairs, 100.0 * relative_error, gib(*bytes), gib(*available as f64))]
    VisibilityPlanTooLarge {
        /// Elements n.
        elements: u64,
        /// Partly visible (point × element) pairs, predicted.
        partial_pairs: f64,
        /// The predictions' relative standard error.
        relative_error: f64,
        /// Bytes of their candidate lists, predicted.
        bytes: f64,
        /// Row blocks sampled.
        sampled: usize,
        /// Bytes available.
        available: u64,
    },
    /// A curved surface that may occlude itself: radcol clips flat elements only.
    #[error("surface '{surface}': patch '{patch}' is curved and the surface is not known to bound a convex set; radcol models occlusion between flat triangles only (set Surface::convex_enclosure when the surface does bound a convex set)")]
    CurvedOcclusion {
        /// The surface's name.
        surface: String,
        /// The first curved patch.
        patch: String,
    },
    /// A refinement study of a problem without an exact solution.
    #[error("a study measures errors against the exact solution or estimates them, and this problem has no exact solution and the estimate is off")]
    NoExactSolution,
    /// A backend asked for a precision it does not compute in.
    #[error("the {backend} backend computes in {supported} only; {asked} needs the GPU backend")]
    Precision {
        /// The backend.
        backend: crate::backend_kind::BackendKind,
        /// What it computes in.
        supported: crate::backend_kind::Scalar,
        /// What was asked for.
        asked: crate::backend_kind::Scalar,
    },
}

/// Bytes as GiB with three significant digits (scientific beyond 10⁶ GiB).
fn gib(bytes: f64) -> String {
    let g = bytes / 1073741824.0;
    if g < 1e6 {
        format!("{g:.2} GiB")
    } else {
        format!("{g:.3e} GiB")
    }
}

impl InputError {
    /// A refusal for the peak memory of a solve whose operator was (or
    /// would be) admitted: the dense peak, the compressed operator's rest,
    /// or the compressed operator's pair table.
    pub fn is_peak_refusal(&self) -> bool {
        matches!(
            self,
            Self::PeakTooLarge { .. }
                | Self::CompressedTooLarge { .. }
                | Self::CompressedWontFit { .. }
                | Self::PairTableTooLarge { .. }
                | Self::VisibilityPlanTooLarge { .. }
        )
    }
}

/// n elements; `u64::MAX` is where counting stopped.
fn elements_text(elements: u64) -> String {
    if elements == u64::MAX {
        "more than 4 million elements (counting stopped there)".into()
    } else {
        format!("{elements} elements")
    }
}

/// What N unknowns need; `u64::MAX` is where counting stopped (more than
/// 4 million elements).
fn need(unknowns: u64, matrix: f64, lu: f64) -> String {
    if unknowns == u64::MAX {
        "more than 4 million unknowns (counting stopped there) need a dense matrix of more than 100 TiB".into()
    } else {
        let lu = if lu > 0.0 {
            format!(" (plus {} for an LU copy)", gib(lu))
        } else {
            String::new()
        };
        format!(
            "{unknowns} unknowns need a dense matrix of {}{lu}",
            gib(matrix)
        )
    }
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
    #[error("assembly backend '{backend}': {source}")]
    Backend {
        /// Which backend.
        backend: crate::backend_kind::BackendKind,
        /// The backend's own typed error.
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// The progress observer asked for the solve to stop
    /// ([`crate::progress::Progress::cancelled`]).
    #[error("cancelled during the {stage}")]
    Cancelled {
        /// The stage that noticed: "plan", "assembly", "solve", "estimate".
        stage: &'static str,
    },
}

impl Error {
    /// [`Error::Cancelled`] in `stage` when `progress` asks for it.
    pub(crate) fn if_cancelled(
        progress: Option<&crate::progress::ProgressHandle>,
        stage: &'static str,
    ) -> Result<(), Error> {
        match progress {
            Some(p) if p.cancelled() => Err(Error::Cancelled { stage }),
            _ => Ok(()),
        }
    }
}
