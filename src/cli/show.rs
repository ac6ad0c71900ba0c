//! `pacs robot show` and `pacs human show`: built-in models as JSON.

use super::CliError;
use serde_json::Value;

/// Print a built-in robot's spec.
pub fn robot(name: &str) -> Result<Value, CliError> {
    let m = pacs_models::RobotModel::builtin(name)?;
    serde_json::to_value(m.spec()).map_err(|e| CliError::Internal(e.to_string()))
}

/// Print a built-in human model's spec.
pub fn human(name: &str) -> Result<Value, CliError> {
    let m = pacs_models::HumanModel::builtin(name)?;
    serde_json::to_value(m.spec()).map_err(|e| CliError::Internal(e.to_string()))
}
