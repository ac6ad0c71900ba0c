//! `pacs robot show`, `pacs human show` and `pacs object show`: built-in models as JSON.

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

/// Print a built-in object's spec.
pub fn object(name: &str) -> Result<Value, CliError> {
    let spec = pacs_models::object::builtin_object(name).ok_or_else(|| {
        CliError::Input(format!(
            "unknown built-in object `{name}` (built-in: {})",
            pacs_models::object::BUILTIN_OBJECTS.join(", ")
        ))
    })?;
    serde_json::to_value(spec).map_err(|e| CliError::Internal(e.to_string()))
}
