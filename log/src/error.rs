//! Typed audit errors: every input error names the file, the line (or byte offset) and the problem.

use thiserror::Error;

/// Where in an input file a problem was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Location {
    /// The whole file (e.g. it cannot be opened, or it is empty).
    File,
    /// A 1-based line number (JSONL, CSV).
    Line(u64),
    /// A byte offset (MCAP).
    Offset(u64),
}

impl std::fmt::Display for Location {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Location::File => Ok(()),
            Location::Line(l) => write!(f, "line {l}: "),
            Location::Offset(o) => write!(f, "offset {o}: "),
        }
    }
}

/// Why a log or config could not be audited. Every variant is "invalid input" (CLI exit 3).
#[derive(Debug, Error)]
pub enum LogError {
    /// The file content is invalid at `location`; `problem` names the field and the value.
    #[error("{file}: {location}{problem}")]
    Input {
        /// File name as given.
        file: String,
        /// Line or offset.
        location: Location,
        /// What is wrong (field, value, expectation).
        problem: String,
    },
    /// The file could not be read.
    #[error("{file}: cannot read: {source}")]
    Io {
        /// File name as given.
        file: String,
        /// Underlying I/O error.
        #[source]
        source: std::io::Error,
    },
}

impl LogError {
    /// An input error at a location.
    pub fn input(file: &str, location: Location, problem: impl Into<String>) -> Self {
        LogError::Input {
            file: file.to_string(),
            location,
            problem: problem.into(),
        }
    }
}
