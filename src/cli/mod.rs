//! The `pacs` command line: one module per subcommand, shared error type and JSON I/O helpers.

pub mod audit;
pub mod bench;
pub mod bench_audit;
pub mod capsules;
pub mod demo;
pub mod fk;
pub mod reach;
pub mod shield;
pub mod show;
pub mod simulate;
pub mod trajectory;

use std::path::Path;

/// Exit code for invalid input (bad file, bad JSON, invalid model or values).
pub const EXIT_INVALID_INPUT: i32 = 3;
/// Exit code for an internal failure (a bug: please report).
pub const EXIT_INTERNAL: i32 = 70;
/// Exit code when an output (file, directory, stdout) cannot be written (`EX_IOERR` of
/// sysexits.h): nothing is wrong with the input, the destination refused.
pub const EXIT_CANNOT_WRITE: i32 = 74;

/// A CLI failure with the exit code it maps to.
#[derive(Debug)]
pub enum CliError {
    /// Invalid input: exit 3.
    Input(String),
    /// An output cannot be written: exit 74.
    Output(String),
    /// Anything else: exit 70.
    Internal(String),
}

impl CliError {
    /// Exit code of this error.
    pub fn code(&self) -> i32 {
        match self {
            CliError::Input(_) => EXIT_INVALID_INPUT,
            CliError::Output(_) => EXIT_CANNOT_WRITE,
            CliError::Internal(_) => EXIT_INTERNAL,
        }
    }
    /// Human-readable message.
    pub fn message(&self) -> &str {
        match self {
            CliError::Input(m) | CliError::Output(m) | CliError::Internal(m) => m,
        }
    }
}

impl From<pacs_models::ModelError> for CliError {
    fn from(e: pacs_models::ModelError) -> Self {
        CliError::Input(e.to_string())
    }
}

/// Read a whole input file, naming it in the error.
pub fn read_file(path: &Path) -> Result<String, CliError> {
    std::fs::read_to_string(path)
        .map_err(|e| CliError::Input(format!("cannot read {}: {e}", path.display())))
}

/// Parse JSON input into `T`, naming the file, line and column on error.
pub fn parse_json<T: serde::de::DeserializeOwned>(path: &Path, text: &str) -> Result<T, CliError> {
    serde_json::from_str(text).map_err(|e| {
        CliError::Input(format!(
            "{}: invalid input: {}",
            path.display(),
            pacs_models::describe_json_error(text, &e)
        ))
    })
}

/// Read and parse a JSON input file.
pub fn read_json<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T, CliError> {
    let text = read_file(path)?;
    parse_json(path, &text)
}

/// A robot given by built-in name, `{"urdf": ..., "side": ...}` or inline spec: the one reader
/// shared with log headers and audit configs.
pub use pacs_log::RobotRef;

/// Load the robot an input file names: `{urdf, side}` paths relative to that file (`input`; the
/// working directory for built-in examples).
pub fn load_robot(
    robot: &RobotRef,
    input: Option<&Path>,
) -> Result<pacs_models::RobotModel, CliError> {
    let mut r = robot.clone();
    if let Some(p) = input {
        r.rebase(&pacs_log::dir_of(p));
    }
    r.load().map_err(|e| CliError::Input(format!("robot: {e}")))
}

/// A human model given by built-in name (`"default"`) or inline (read by its shape, like
/// [`pacs_log::ModelRef`], so a faulty inline spec reports its own field).
#[derive(Debug, Clone, serde::Deserialize)]
#[serde(transparent)]
pub struct HumanRef(pub pacs_log::ModelRef<pacs_models::HumanSpec>);

impl HumanRef {
    /// Resolve to a validated model.
    pub fn load(&self) -> Result<pacs_models::HumanModel, CliError> {
        use pacs_log::ModelRef;
        Ok(match &self.0 {
            ModelRef::Name(n) => pacs_models::HumanModel::builtin(n)?,
            ModelRef::Spec(s) => pacs_models::HumanModel::new((**s).clone())
                .map_err(|e| CliError::Input(format!("human: {e}")))?,
        })
    }
}

/// Check that a vector has the expected length and finite entries.
pub fn check_vec(field: &str, v: &[f64], n: usize) -> Result<(), CliError> {
    if v.len() != n {
        return Err(CliError::Input(format!(
            "{field}: expected {n} values, found {}",
            v.len()
        )));
    }
    if let Some((i, x)) = v.iter().enumerate().find(|(_, x)| !x.is_finite()) {
        return Err(CliError::Input(format!(
            "{field}[{i}]: value {x} is not finite"
        )));
    }
    Ok(())
}
