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

/// Which checks the audit makes, and the tests and harnesses that back each (paths in the repo).
pub fn check_backing() -> Value {
    json!([
        {"check": "robot occupancy over a span (joint box from v_max, outward-rounded)",
         "backed_by": ["reach/tests/robot_occupancy.rs (proptest: sampled link points stay in the box occupancy)",
                       "audit/tests/audit_checks.rs::violation_only_between_samples_is_caught"]},
        {"check": "human occupancy since the measurement (vel/pos/combined models)",
         "backed_by": ["reach/tests/human_occupancy.rs (proptest soundness of every model)"]},
        {"check": "conservative capsule separation / intersection",
         "backed_by": ["reach/tests/geometry.rs (lower bound never above exact distance; touching never disjoint)"]},
        {"check": "span enclosures and consistency of logged positions, velocities and accelerations",
         "backed_by": ["proofs: h2_span_enclosure_sound (Kani harness + property twin)",
                       "audit/tests/audit_consistency.rs"]},
        {"check": "whole-robot kinetic-energy upper bound over the boxes",
         "backed_by": ["reach/tests/energy.rs (proptest: bound covers every sampled state)",
                       "audit/tests/audit_checks.rs::pfl_energy_just_above_and_below_threshold",
                       "audit/tests/audit_consistency.rs::pfl_uses_the_whole_robot_energy"]},
        {"check": "the one ISO/TS 15066 rule (SSM, PFL, clamping) shared with the shield",
         "backed_by": ["proofs: i1_rule_sound (Kani harness + property twin)",
                       "proofs/mutants: x9, x10 caught"]},
        {"check": "SSM violation detection (first, last sample, one-sample spike, between samples)",
         "backed_by": ["audit/tests/audit_checks.rs"]},
        {"check": "PFL constrained vs unconstrained contact",
         "backed_by": ["audit/tests/audit_checks.rs::pfl_constrained_vs_unconstrained"]},
        {"check": "bad input rejected (exit 3), never pass",
         "backed_by": ["audit/tests/audit_input.rs", "tests/cli_audit.rs", "fuzz/ (cargo fuzz target jsonl)"]}
    ])
}

/// The modelling assumptions the verdicts rest on (see `docs/audit.md`).
pub fn assumptions() -> Vec<&'static str> {
    vec![
        "Recorded joint positions, velocities and accelerations are exact at their time stamps (up to 1 ulp of decimal parsing).",
        "Between samples every joint obeys |dq| <= v_max, |ddq| <= a_max and |dddq| <= j_max of the robot model; samples contradicting this or each other (positions vs velocities under a_max, velocities vs accelerations under j_max) make the span inconclusive, with boxes covering what the positions imply.",
        "The human moves within the human model's speed bound since each measurement; positions are within measurement_error_pos of the truth; a measurement stamped t_meas describes the state at t_meas - delay.",
        "Robot link geometry is the model's capsules enlarged by tracking_error; human body parts are the model's capsules.",
        "SSM: any possible contact while the robot is not provably at rest (all joint speeds <= rest_speed) is a violation; contact with the fixed base link counts.",
        "PFL: a possible contact is a violation if the sound upper bound of the whole robot's kinetic energy (which bounds the energy transferable at any contact point) exceeds the threshold; constrained (the lower threshold) if clamping is possible: the environment, robot links on two different frames (adjacent links included), or a clampable body part.",
        "With human_model = pos: each extremity's keypoints stay within its length + thickness/2 of its base keypoint; a measurement contradicting this by more than 2 measurement_error_pos is not trusted (that extremity uses the speed-bounded occupancy).",
        "Spans longer than max_gap, before the first human record, or with a human measurement older than max_human_age are inconclusive.",
    ]
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
