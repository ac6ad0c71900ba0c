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
    /// The `id` of a row in a rosbag2 sqlite3 bag's `messages` table (db3).
    Message(i64),
}

impl std::fmt::Display for Location {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Location::File => Ok(()),
            Location::Line(l) => write!(f, "line {l}: "),
            Location::Offset(o) => write!(f, "offset {o}: "),
            Location::Message(id) => write!(f, "message id {id}: "),
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
    /// A sqlite3 bag read in storage order ([`crate::open_log_in_row_order`]) whose rows are
    /// not stored in time order: read it again with [`crate::open_log`], through its time index.
    #[error("{file}: rows not stored in time order (read the bag through its time index)")]
    RowsNotInTimeOrder {
        /// File name as given.
        file: String,
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

/// What is wrong with a log header (its first record, an MCAP metadata record or a side file),
/// before a file and location are attached (`LogError::Input` carries its message).
#[derive(Debug, Error)]
pub enum HeaderError {
    /// The first record is not a header.
    #[error("first record: type `{0}`, expected `header`")]
    NotHeader(String),
    /// A header object without `"type": "header"`.
    #[error("missing header: the header must have \"type\": \"header\"")]
    MissingType,
    /// Unsupported `format`.
    #[error("header.format: `{0}`, expected `{format}`", format = crate::format::FORMAT)]
    Format(String),
    /// Unsupported `version`.
    #[error("header.version: {0} is not supported (expected 1 or 2)")]
    Version(u32),
    /// The text is not JSON.
    #[error("invalid JSON: {0}")]
    Json(String),
    /// The JSON does not have the header's fields and types.
    #[error("invalid header: {0}")]
    Fields(String),
    /// A model the header names or specifies is invalid; `field` is its header field.
    #[error("{field}: {source}")]
    Model {
        /// Header field (`header.robot`, `header.environment[2]`, …).
        field: String,
        /// The model's own error.
        #[source]
        source: pacs_models::ModelError,
    },
}

/// An invalid MCAP reader setting (`[mcap]` of an audit config, or the CLI's topic flags).
#[derive(Debug, Clone, PartialEq, Error)]
pub enum McapConfigError {
    /// `mcap.reorder_window` is negative or not finite (s).
    #[error("mcap.reorder_window: {0} must be finite and ≥ 0")]
    ReorderWindow(f64),
    /// A topic is empty.
    #[error("{0}: empty topic")]
    EmptyTopic(&'static str),
    /// Two settings name the same topic.
    #[error("{field}: topic `{topic}` is also {other}")]
    DuplicateTopic {
        /// The setting.
        field: &'static str,
        /// The topic.
        topic: String,
        /// The earlier setting with the same topic.
        other: &'static str,
    },
}
