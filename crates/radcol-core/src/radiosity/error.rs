//! The one error type of the front door and the prelude.

use crate::query::QueryError;
use crate::render::RenderError;
use crate::scene::SceneError;

/// Every failure of [`super::Radiosity`] and of the prelude's calls: a solve's ([`crate::error::Error`],
/// bad input included), a scene file's, a render's, a point query's.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The solve (bad input, a solver or backend failure, cancellation).
    #[error(transparent)]
    Solve(#[from] crate::error::Error),
    /// A scene file.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// Rendering or tessellating a solution.
    #[error(transparent)]
    Render(#[from] RenderError),
    /// A point query.
    #[error(transparent)]
    Query(#[from] QueryError),
    /// Writing a file.
    #[cfg(feature = "export")]
    #[error(transparent)]
    Export(#[from] crate::export::ExportError),
}

impl From<crate::error::InputError> for Error {
    fn from(e: crate::error::InputError) -> Self {
        Error::Solve(e.into())
    }
}
