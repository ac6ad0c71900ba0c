//! Typed errors of model loading and validation.

use thiserror::Error;

/// Why a model could not be built: each variant names the field and the offending value.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ModelError {
    /// A numeric field is NaN, infinite, or outside its admissible range.
    #[error("invalid value for `{field}`: {value} ({reason})")]
    InvalidValue {
        /// Dotted path of the field, e.g. `joints[3].limits.v_max`.
        field: String,
        /// The offending value.
        value: f64,
        /// What was expected.
        reason: &'static str,
    },
    /// Two lists that must have equal lengths do not.
    #[error("length mismatch for `{field}`: expected {expected}, found {found}")]
    LengthMismatch {
        /// Dotted path of the field.
        field: String,
        /// Required length.
        expected: usize,
        /// Actual length.
        found: usize,
    },
    /// A name refers to something that does not exist.
    #[error("unknown {kind} `{name}` in `{field}`")]
    UnknownName {
        /// What kind of name (keypoint, body part, link, robot, ...).
        kind: &'static str,
        /// The unknown name.
        name: String,
        /// Where it was referenced.
        field: String,
    },
    /// A name is used twice where names must be unique.
    #[error("duplicate {kind} `{name}`")]
    DuplicateName {
        /// What kind of name.
        kind: &'static str,
        /// The repeated name.
        name: String,
    },
    /// Links whose collision geometry includes a mesh, without side-file capsules: pacs cannot
    /// bound a mesh, and ignoring it would make the checks vacuous for those bodies.
    #[error(
        "links with mesh collision geometry and no capsules: {} (give capsules for them in the side file)",
        links.iter().map(|l| format!("`{l}`")).collect::<Vec<_>>().join(", ")
    )]
    MeshCollision {
        /// The link names.
        links: Vec<String>,
    },
    /// A robot model that would make a PFL check vacuous: moving links with collision geometry
    /// but no mass or no inertia.
    #[error(
        "task `{task}` has PFL constraints, but robot `{robot}` has moving links without mass or inertia: {} (their kinetic energy would be ignored)",
        links.iter().map(|l| format!("`{l}`")).collect::<Vec<_>>().join(", ")
    )]
    MasslessLinks {
        /// Task name.
        task: String,
        /// Robot name.
        robot: String,
        /// The link names.
        links: Vec<String>,
    },
    /// Moving links with mass and no capsules, not marked `frame`: no contact with them could
    /// ever be found, so SSM and PFL would pass whatever they hit.
    #[error(
        "robot `{robot}`: moving links with mass and no capsules: {} (no contact with them could ever be found; give them capsules — `pacs robot capsules` fits them to meshes — or, if a link has no body outside other links' capsules, mark it `\"frame\": true` in the model or `frame = true` under its `[links.NAME]` in the side file)",
        links.iter().map(|(l, m)| format!("`{l}` ({m} kg)")).collect::<Vec<_>>().join(", ")
    )]
    UncoveredLinks {
        /// Robot name.
        robot: String,
        /// The link names with their masses (kg).
        links: Vec<(String, f64)>,
    },
    /// A structural problem that is not a single value (empty chain, bad index...).
    #[error("invalid model: {0}")]
    Invalid(String),
    /// The text could not be parsed.
    #[error("cannot parse {format}: {message}")]
    Parse {
        /// "JSON", "TOML" or "URDF".
        format: &'static str,
        /// Parser message (with line/column where the parser gives one).
        message: String,
    },
}

/// Check that `value` is finite, naming `field` otherwise.
pub(crate) fn finite(field: impl FnOnce() -> String, value: f64) -> Result<f64, ModelError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(ModelError::InvalidValue {
            field: field(),
            value,
            reason: "must be finite",
        })
    }
}

/// Check that `value` is finite and `>= 0`.
pub(crate) fn non_negative(field: impl FnOnce() -> String, value: f64) -> Result<f64, ModelError> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(ModelError::InvalidValue {
            field: field(),
            value,
            reason: "must be finite and >= 0",
        })
    }
}

/// Check that `value` is finite and `> 0`.
pub(crate) fn positive(field: impl FnOnce() -> String, value: f64) -> Result<f64, ModelError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(ModelError::InvalidValue {
            field: field(),
            value,
            reason: "must be finite and > 0",
        })
    }
}

/// Parse a spec from JSON text (errors: [`ModelError::Parse`]).
pub(crate) fn parse_json<T: serde::de::DeserializeOwned>(text: &str) -> Result<T, ModelError> {
    serde_json::from_str(text).map_err(|e| ModelError::Parse {
        format: "JSON",
        message: crate::json_path::describe_json_error(text, &e),
    })
}

/// Parse a spec from TOML text (errors: [`ModelError::Parse`]).
pub(crate) fn parse_toml<T: serde::de::DeserializeOwned>(text: &str) -> Result<T, ModelError> {
    toml::from_str(text).map_err(|e| ModelError::Parse {
        format: "TOML",
        message: e.to_string(),
    })
}
