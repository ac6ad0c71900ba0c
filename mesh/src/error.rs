//! Errors of mesh reading and capsule fitting: each names the file and, where it applies, the
//! line, element or value.

use std::path::PathBuf;
use thiserror::Error;

/// What went wrong with a mesh or a URDF's mesh collision.
#[derive(Debug, Error)]
pub enum MeshError {
    /// The file cannot be read.
    #[error("{path}: cannot read: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    /// The file's content is not what its format requires.
    #[error("{path}: {what}")]
    Parse { path: PathBuf, what: String },
    /// A format or construct this reader does not handle (rather than guessing geometry).
    #[error("{path}: unsupported: {what}")]
    Unsupported { path: PathBuf, what: String },
    /// No vertices (nothing to fit).
    #[error("{path}: the mesh has no vertices")]
    Empty { path: PathBuf },
    /// A mesh file name that cannot be resolved to a file.
    #[error("{what}")]
    Resolve { what: String },
    /// The URDF (or side file) is invalid.
    #[error("{0}")]
    Model(#[from] pacs_models::ModelError),
}
