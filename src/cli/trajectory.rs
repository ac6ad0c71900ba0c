//! `pacs trajectory`: intended trajectory from an action chunk, optionally with a failsafe.

use super::CliError;
use serde_json::Value;
use std::path::Path;

/// Run `pacs trajectory --input F [--brake-at t]`.
pub fn run(_path: &Path, _brake_at: Option<f64>) -> Result<Value, CliError> {
    Err(CliError::Internal("pacs trajectory: not built yet".into()))
}
