//! # pacs-reports
//!
//! Certification reports from `pacs audit` results: `report.json` (provenance, SHA-256 of every
//! input, models and assumptions, verdicts, violations, metrics, and the tests backing each check),
//! a self-contained `report.html` (inline SVG plots, print-friendly) and `report.md`. Several logs
//! add an aggregate table grouped by the logs' `meta` (`task`, `policy`, `filter`).

pub mod aggregate;
pub mod html;
pub mod markdown;
pub mod svg;

use pacs_audit::{RunResult, Verdict};
use serde::Serialize;
use serde_json::{Value, json};
use sha2::{Digest, Sha256};
use std::io::Read;
use std::path::{Path, PathBuf};

/// Errors writing a report: the path and the cause.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// Reading an input or writing an output failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Cause.
        #[source]
        source: std::io::Error,
    },
}

/// The tool version (crate version) recorded in reports.
pub const TOOL_VERSION: &str = env!("CARGO_PKG_VERSION");
/// The git revision the tool was built from (`-dirty` if the tree had changes), or "unknown".
pub const GIT_REVISION: &str = env!("PACS_GIT_REV");

/// An input file with its SHA-256 (lowercase hex).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct InputFile {
    /// Path as given.
    pub path: String,
    /// SHA-256 of the file's bytes, lowercase hex.
    pub sha256: String,
    /// Size (bytes).
    pub bytes: u64,
}

impl InputFile {
    /// Hash a file by streaming it (memory stays flat).
    pub fn hash(path: &Path) -> Result<Self, ReportError> {
        let io = |e| ReportError::Io {
            path: path.to_path_buf(),
            source: e,
        };
        let mut f = std::fs::File::open(path).map_err(io)?;
        let mut h = Sha256::new();
        let mut buf = vec![0u8; 1 << 16];
        let mut bytes = 0u64;
        loop {
            let n = f.read(&mut buf).map_err(io)?;
            if n == 0 {
                break;
            }
            bytes += n as u64;
            h.update(&buf[..n]);
        }
        Ok(Self {
            path: path.display().to_string(),
            sha256: hex(&h.finalize()),
            bytes,
        })
    }
}

fn hex(b: &[u8]) -> String {
    b.iter().map(|x| format!("{x:02x}")).collect()
}

/// Everything a report is built from.
#[derive(Debug, Clone)]
pub struct ReportInput<'a> {
    /// One result per log, in the order given.
    pub runs: &'a [RunResult],
    /// The logs, hashed.
    pub logs: Vec<InputFile>,
    /// The config file, hashed (None: defaults).
    pub config: Option<InputFile>,
    /// The effective audit settings (serialized `AuditConfig`).
    pub settings: Value,
}

/// Which checks the audit makes, and the tests and harnesses that back each
/// ([`pacs_audit::claims::CHECKS`], the one list).
pub fn check_backing() -> Value {
    serde_json::to_value(pacs_audit::claims::CHECKS).unwrap_or(Value::Null)
}

/// The modelling assumptions the verdicts rest on ([`pacs_audit::claims::ASSUMPTIONS`]).
pub fn assumptions() -> Vec<&'static str> {
    pacs_audit::claims::ASSUMPTIONS.to_vec()
}

/// Overall verdict of the runs.
pub fn overall(runs: &[RunResult]) -> Verdict {
    Verdict::combine(runs.iter().map(|r| r.verdict))
}

/// The `report.json` document.
pub fn report_json(input: &ReportInput) -> Value {
    let runs: Vec<Value> = input
        .runs
        .iter()
        .zip(&input.logs)
        .map(|(r, f)| {
            json!({
                "log": r.log,
                "sha256": f.sha256,
                "bytes": f.bytes,
                "verdict": r.verdict,
                "models": r.models,
                "meta": r.meta,
                "violations": r.violations,
                "inconclusive": r.inconclusive,
                "metrics": r.metrics,
            })
        })
        .collect();
    json!({
        "report": "pacs-audit-certification",
        "tool": {"name": "pacs", "version": TOOL_VERSION, "git_revision": GIT_REVISION},
        "inputs": {"logs": input.logs, "config": input.config},
        "settings": input.settings,
        "assumptions": assumptions(),
        "checks": check_backing(),
        "verdict": overall(input.runs),
        "runs": runs,
        "aggregate": aggregate::aggregate(input.runs),
    })
}

/// Write `report.json`, `report.md` and `report.html` into `dir` (created if missing).
pub fn write_reports(dir: &Path, input: &ReportInput) -> Result<(), ReportError> {
    let io = |p: &Path| {
        let p = p.to_path_buf();
        move |e| ReportError::Io { path: p, source: e }
    };
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    let j = dir.join("report.json");
    let text = serde_json::to_string_pretty(&report_json(input)).map_err(|e| ReportError::Io {
        path: j.clone(),
        source: e.into(),
    })?;
    std::fs::write(&j, text + "\n").map_err(io(&j))?;
    let m = dir.join("report.md");
    std::fs::write(&m, markdown::report(input)).map_err(io(&m))?;
    let h = dir.join("report.html");
    std::fs::write(&h, html::report(input)).map_err(io(&h))?;
    Ok(())
}
