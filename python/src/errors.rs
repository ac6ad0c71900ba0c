//! Python exceptions: the classes live in `pacs.errors` (so that they can subclass both
//! `pacs.Error` and `ValueError`/`TypeError`); Rust raises them by name.

use pyo3::prelude::*;
use pyo3::types::PyType;

/// The kinds of `pacs.Error` the extension raises.
#[derive(Debug, Clone, Copy)]
pub enum Kind {
    /// `pacs.InputError(pacs.Error, ValueError)`: a value, shape or name that is invalid.
    Input,
    /// `pacs.ArgumentTypeError(pacs.Error, TypeError)`: an argument of the wrong type.
    Type,
    /// `pacs.NotStartedError(pacs.Error, RuntimeError)`: `start` first / loop running.
    State,
    /// `pacs.ChunkRejected(pacs.InputError)`: a chunk the planner refused.
    Chunk,
    /// `pacs.OutputError(pacs.Error, OSError)`: a file that cannot be written.
    Output,
}

impl Kind {
    fn class_name(self) -> &'static str {
        match self {
            Kind::Input => "InputError",
            Kind::Type => "ArgumentTypeError",
            Kind::State => "NotStartedError",
            Kind::Chunk => "ChunkRejected",
            Kind::Output => "OutputError",
        }
    }
}

/// A `pacs.errors` exception of `kind` with `msg`.
pub fn err(kind: Kind, msg: impl Into<String>) -> PyErr {
    let msg = msg.into();
    Python::attach(|py| {
        let class = py
            .import("pacs.errors")
            .and_then(|m| m.getattr(kind.class_name()))
            .and_then(|c| c.cast_into::<PyType>().map_err(PyErr::from));
        match class {
            Ok(c) => PyErr::from_type(c, msg),
            // The package is not importable (the extension used on its own): still an error
            // of the right Python family.
            Err(_) => match kind {
                Kind::Type => pyo3::exceptions::PyTypeError::new_err(msg),
                Kind::State => pyo3::exceptions::PyRuntimeError::new_err(msg),
                Kind::Output => pyo3::exceptions::PyOSError::new_err(msg),
                _ => pyo3::exceptions::PyValueError::new_err(msg),
            },
        }
    })
}

/// `pacs.InputError`.
pub fn input(msg: impl Into<String>) -> PyErr {
    err(Kind::Input, msg)
}

/// `pacs.ArgumentTypeError`.
pub fn type_err(msg: impl Into<String>) -> PyErr {
    err(Kind::Type, msg)
}
