//! `pacs reach robot` and `pacs reach human`.

use super::CliError;
use serde_json::Value;
use std::path::Path;

/// Run `pacs reach robot --input F`.
pub fn run_robot(_path: &Path) -> Result<Value, CliError> {
    Err(CliError::Internal("pacs reach robot: not built yet".into()))
}

/// Run `pacs reach human --input F`.
pub fn run_human(_path: &Path) -> Result<Value, CliError> {
    Err(CliError::Internal("pacs reach human: not built yet".into()))
}
