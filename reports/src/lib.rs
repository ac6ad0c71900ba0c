//! # pacs-reports
//!
//! Certification reports from `pacs audit` results: `report.json` (provenance, SHA-256 of every
//! input, models and assumptions, verdicts, violations, metrics, and the tests backing each check),
//! a self-contained `report.html` (inline SVG plots, print-friendly), `report.pdf`, `report.md`,
//! and `violations.csv` (every violation interval). HTML, PDF and Markdown show violation
//! *episodes* ([`episodes`]); the intervals are in report.json and the CSV. Several logs add an
//! aggregate table grouped by the logs' `meta` (`task`, `policy`, `filter`: the filter that ran)
//! and the fleet table per robot, scene and day ([`fleet`]).

pub mod aggregate;
pub mod episodes;
pub mod fleet;
pub mod html;
pub mod markdown;
pub mod pdf;
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
    /// SHA-256 of the file's bytes, lowercase hex. For a directory (a ROS 2 bag): the SHA-256 of
    /// the `sha256sum`-style listing (`{sha256}  {name}\n`) of its files in name order.
    pub sha256: String,
    /// Size (bytes).
    pub bytes: u64,
}

/// The first two logs among `logs` that hold the same bytes (equal SHA-256), if any: one run
/// given twice under two names (a copy, not a link: [`fleet::refuse_twice`] catches those) would
/// count twice in a report's runs, verdict counts and audited time. The CLI and Python refuse
/// such a report. Test `reports/tests/fleet.rs::a_copy_of_a_log_is_one_run_given_twice`.
pub fn same_bytes(logs: &[InputFile]) -> Option<(&InputFile, &InputFile)> {
    let mut seen: std::collections::HashMap<&str, usize> = std::collections::HashMap::new();
    for (i, f) in logs.iter().enumerate() {
        if let Some(&first) = seen.get(f.sha256.as_str()) {
            return Some((&logs[first], f));
        }
        seen.insert(&f.sha256, i);
    }
    None
}

/// The error text of [`same_bytes`]'s finding.
pub fn same_bytes_message(a: &InputFile, b: &InputFile) -> String {
    format!(
        "{} holds the same bytes as {} (sha256 {}): one run given twice would count twice in the report; audit one copy",
        b.path, a.path, a.sha256
    )
}

impl InputFile {
    /// Hash a file by streaming it (memory stays flat); a directory (a ROS 2 bag) by its files
    /// (see [`InputFile::sha256`]; subdirectories are not part of a bag and are left out).
    pub fn hash(path: &Path) -> Result<Self, ReportError> {
        let io = |e| ReportError::Io {
            path: path.to_path_buf(),
            source: e,
        };
        if path.is_dir() {
            let mut files = Vec::new();
            for e in std::fs::read_dir(path).map_err(io)? {
                let e = e.map_err(io)?;
                if e.file_type().map_err(io)?.is_file() {
                    files.push(e.file_name());
                }
            }
            files.sort();
            let mut listing = String::new();
            let mut bytes = 0u64;
            for f in files {
                let one = Self::hash(&path.join(&f))?;
                bytes += one.bytes;
                listing.push_str(&format!("{}  {}\n", one.sha256, f.to_string_lossy()));
            }
            return Ok(Self {
                path: path.display().to_string(),
                sha256: hex(&Sha256::digest(listing.as_bytes())),
                bytes,
            });
        }
        // Never open a FIFO, socket or device: opening a FIFO waits for a writer.
        if !std::fs::metadata(path).map_err(io)?.is_file() {
            return Err(io(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "not a regular file (a FIFO, socket or device)",
            )));
        }
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

/// SHA-256 (lowercase hex) of a model's parameters as compact JSON (object keys sorted, as
/// `serde_json` orders them): equal parameters give equal hashes, across logs and runs.
pub fn model_sha256(spec: &Value) -> String {
    let bytes = serde_json::to_vec(spec).unwrap_or_default();
    hex(&Sha256::digest(&bytes))
}

/// The models of a run with their parameters and SHA-256: `{"robot": {"sha256", "spec"}, ...}`.
pub fn model_specs(r: &RunResult) -> Value {
    let mut out = serde_json::Map::new();
    if let Some(m) = r.models.specs.as_object() {
        for (k, v) in m {
            out.insert(k.clone(), json!({"sha256": model_sha256(v), "spec": v}));
        }
    }
    Value::Object(out)
}

/// What an inconclusive span is about, as the reports print it: its reason, and the person it
/// names where there is one (`no_human, person `B``).
pub(crate) fn inconclusive_what(
    reason: &str,
    person: Option<&str>,
    object: Option<&str>,
) -> String {
    match (person, object) {
        (Some(p), _) => format!("{reason}, person `{p}`"),
        (None, Some(o)) => format!("{reason}, object `{o}`"),
        (None, None) => reason.to_string(),
    }
}

/// The current time as ISO 8601 UTC (`2026-11-25T15:30:00Z`), from the system clock.
pub fn utc_now() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    utc(secs)
}

/// Seconds since the Unix epoch as ISO 8601 UTC (proleptic Gregorian calendar).
pub fn utc(secs: u64) -> String {
    let days = (secs / 86_400) as i64;
    let rem = secs % 86_400;
    // Civil date from days since 1970-01-01 (Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}Z",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    )
}

/// The report's `inputs`: the logs, and the config file only when one was given (no `null`:
/// an absent `config` means the documented defaults).
fn inputs_json(logs: &[InputFile], config: Option<&InputFile>) -> Value {
    let mut inputs = serde_json::json!({ "logs": logs });
    if let Some(c) = config {
        inputs["config"] = serde_json::json!(c);
    }
    inputs
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
    /// When the report is generated (ISO 8601 UTC, [`utc_now`]): one time for all its files.
    pub generated: String,
    /// Entries under the given directories that are not logs, not audited
    /// ([`fleet::Listing::skipped`]): listed in the report.
    pub skipped: Vec<String>,
}

impl ReportInput<'_> {
    /// When the report is generated (ISO 8601 UTC).
    pub fn generated(&self) -> String {
        self.generated.clone()
    }
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

/// The model values the user gave rather than the robot description (the robot spec's
/// `user_values`, written by the URDF loader from the side file), one line per value and robot,
/// over all runs without repeats: `robot `NAME`: a_max = 10 rad/s² for every joint`.
pub fn user_values(runs: &[RunResult]) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for r in runs {
        let spec = &r.models.specs["robot"];
        let name = spec["name"].as_str().unwrap_or(&r.models.robot);
        for v in spec["user_values"].as_array().into_iter().flatten() {
            if let Some(v) = v.as_str() {
                let line = format!("robot `{name}`: {v}");
                if !out.contains(&line) {
                    out.push(line);
                }
            }
        }
    }
    out
}

/// The heading of the [`user_values`] list.
pub const USER_VALUES_HEADING: &str = "Values the user gave, not the robot description (side file): the verdicts hold only if they are right";

/// Why a passing run may show a separation ≤ 0 (contact possible) without a violation: the rule
/// allows contact while the robot is at rest (SSM) and, with PFL, below the energy limit.
/// `None` unless the run passed with a separation figure ≤ 0.
pub fn contact_note(r: &RunResult) -> Option<&'static str> {
    let contact = r.metrics.min_separation.is_some_and(|s| s <= 0.0);
    if r.verdict != Verdict::Pass || !contact {
        return None;
    }
    let moving_contact = r
        .series
        .iter()
        .any(|p| p.min_separation.is_some_and(|s| s <= 0.0) && !p.at_rest);
    Some(if svg::has_threshold(&r.series) && moving_contact {
        "contact possible only below the energy limit (PFL allows) or while at rest (SSM allows)"
    } else {
        "contact while at rest (SSM allows)"
    })
}

/// The column heads of [`summary_cells`] (HTML, PDF and Markdown print the same columns).
pub const SUMMARY_COLUMNS: [&str; 10] = [
    "log (SHA-256)",
    "constraints",
    "verdict",
    "samples",
    "duration (s)",
    "violation fraction",
    "separation (m) (1)",
    "violation episodes",
    "success",
    "safe success (2)",
];

/// A run as summary cells ([`SUMMARY_COLUMNS`]): n/a where the log says nothing (no success
/// event, no span checked); the separation with [`contact_note`] where it applies.
pub fn summary_cells(r: &RunResult, f: &InputFile) -> [String; 10] {
    let m = &r.metrics;
    let yes_no = |b: Option<bool>| {
        b.map_or("n/a", |b| if b { "yes" } else { "no" })
            .to_string()
    };
    [
        format!("{} ({})", r.log, f.sha256),
        r.models.constraints.clone(),
        format!("{:?}", r.verdict).to_uppercase(),
        m.samples.to_string(),
        format!("{:.3}", m.duration),
        format!("{:.4}", m.violation_fraction),
        match (m.min_separation, contact_note(r)) {
            (Some(x), Some(note)) => format!("{x:.4}: {note}"),
            (Some(x), None) => format!("{x:.4}"),
            (None, _) => "n/a".into(),
        },
        episodes::episodes(&r.violations).len().to_string(),
        yes_no(m.success),
        yes_no(m.safe_success),
    ]
}

/// The report's figures, defined once (report.json `definitions`; the HTML and Markdown print
/// them under the tables).
pub fn definitions() -> Value {
    json!({
        "separation_m": "the separation figure: over the checked spans and robot/body-part capsule pairs, the least (lower bound of the core-segment distance) - (sum of radii), rounded down; > 0: the occupancies are provably at least this far apart; <= 0: contact possible (magnitude: radius overlap at the bound)",
        "violation_separation_m": "of a violation interval: the signed separation of the logged robot capsules and the measured body part (negative: they overlap as logged); positive values occur when the person may have moved since the measurement",
        "safe_success": "the task succeeded (last success/failure event) and no violation occurred, with the audit verdict pass as the evidence",
        "violation_fraction": "violating robot samples / robot samples",
        "episode": "violation intervals of one person (any body part) or object, one robot link and one constraint, less than 0.1 s apart, merged: from-to, the time they cover, the worst separation and energy bound; the intervals themselves are in report.json (runs[].violations) and violations.csv",
        "far_separation_m": "plot only (dotted grey): where every person and object was outside the robot's workspace ball, the distance to that ball, a coarse lower bound (> 0) of the separation, far below the distance to the arm",
        "at_rest": "plot shading: every logged joint speed (or sample difference) <= rest_speed over the bucket",
    })
}

/// The effective settings as (name, value) rows for the report tables: nested tables as
/// `table.key`, unset model overrides as "from the log header".
pub fn settings_rows(settings: &Value) -> Vec<(String, String)> {
    fn rows(prefix: &str, v: &Value, out: &mut Vec<(String, String)>) {
        match v {
            Value::Object(m) => {
                for (k, x) in m {
                    let key = if prefix.is_empty() {
                        k.clone()
                    } else {
                        format!("{prefix}.{k}")
                    };
                    rows(&key, x, out);
                }
            }
            Value::Null => out.push((prefix.into(), "from the log header".into())),
            other => out.push((
                prefix.into(),
                other.to_string().trim_matches('"').to_string(),
            )),
        }
    }
    let mut out = Vec::new();
    rows("", settings, &mut out);
    // The model overrides are left out of the settings when unset (no `null` in report.json).
    for k in ["robot", "human", "constraints"] {
        let set = out.iter().any(|(name, _)| {
            name == k
                || name
                    .strip_prefix(k)
                    .is_some_and(|rest| rest.starts_with('.'))
        });
        if settings.is_object() && !set {
            out.push((k.into(), "from the log header".into()));
        }
    }
    out
}

/// A constraint kind as assessors write it.
pub fn constraint_name(k: pacs_audit::ConstraintKind) -> String {
    let what = match k {
        pacs_audit::ConstraintKind::Ssm => "no contact while moving",
        pacs_audit::ConstraintKind::Pfl => "energy limit",
        pacs_audit::ConstraintKind::NoContact => "never touched",
    };
    format!("{} ({what})", k.label())
}

/// The models of a run as report rows: model, name, the parameters an assessor checks first,
/// and the SHA-256 of the model's full parameters ([`model_specs`]). HTML, PDF and Markdown
/// print these.
pub fn model_rows(r: &RunResult) -> Vec<[String; 4]> {
    let specs = model_specs(r);
    let hash = |k: &str| specs[k]["sha256"].as_str().unwrap_or("-").to_string();
    let m = &r.models;
    let list = |v: &[f64]| {
        v.iter()
            .map(|x| format!("{x}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let human = |v: &[f64], e: f64, d: f64| {
        format!(
            "keypoint speeds (m/s): {}; position error {e} m; delay {d} s",
            list(v)
        )
    };
    let mut rows = vec![[
        "robot".into(),
        m.robot.clone(),
        format!(
            "v_max (rad/s): {}; a_max (rad/s²): {}",
            list(&m.robot_v_max),
            list(&m.robot_a_max)
        ),
        hash("robot"),
    ]];
    if m.people.is_empty() {
        rows.push([
            "human".into(),
            m.human.clone(),
            human(&m.human_v_max, m.human_measurement_error_pos, m.human_delay),
            hash("human"),
        ]);
    } else {
        // Several people: a row per person, each with its own model's parameters and hash.
        let all = specs["humans"]["spec"].clone();
        for p in &m.people {
            rows.push([
                format!("human `{}`", p.id),
                p.human.clone(),
                human(&p.human_v_max, p.human_measurement_error_pos, p.human_delay),
                all.get(&p.id).map_or_else(|| "-".to_string(), model_sha256),
            ]);
        }
    }
    rows.push([
        "constraints".into(),
        m.constraints.clone(),
        format!("{} environment capsule(s)", m.environment_shapes),
        hash("constraints"),
    ]);
    rows
}

/// The column heads of [`violation_cells`].
pub const VIOLATION_COLUMNS: [&str; 10] = [
    "from (s)",
    "to (s)",
    "constraint",
    "person: body part",
    "link",
    "nominal separation (m)",
    "energy bound (J)",
    "threshold (J)",
    "clamped",
    "certain",
];

/// A violation interval as report cells ([`VIOLATION_COLUMNS`]): energies only for PFL (`-`
/// otherwise), the nominal separation (`-` when not computed), certain or possible.
pub fn violation_cells(v: &pacs_audit::Violation) -> [String; 10] {
    let pfl = v.constraint == pacs_audit::ConstraintKind::Pfl;
    let num = |x: f64| {
        if pfl && x.is_finite() {
            format!("{x:.4}")
        } else {
            "-".into()
        }
    };
    [
        format!("{:.4}", v.t_start),
        format!("{:.4}", v.t_end),
        constraint_name(v.constraint),
        match &v.person {
            Some(p) => format!("{p}: {}", v.body_part),
            None => v.body_part.clone(),
        },
        v.link.clone(),
        if v.min_separation.is_finite() {
            format!("{:.4}", v.min_separation)
        } else {
            "-".into()
        },
        num(v.energy),
        num(v.threshold),
        if v.constrained { "yes" } else { "no" }.into(),
        if v.certain { "yes" } else { "possible" }.into(),
    ]
}

/// Overall verdict of the runs.
pub fn overall(runs: &[RunResult]) -> Verdict {
    Verdict::combine(runs.iter().map(|r| r.verdict))
}

/// The column heads of [`evidence_row`] (HTML, PDF and Markdown).
pub const EVIDENCE_COLUMNS: [&str; 4] = ["log", "people", "audited span (s)", "log complete"];

/// What a run's log covers, for the reports: the people, the audited time span (s) and whether
/// the log is the whole run (`complete`: its writer promised a `start` and an `end` event and
/// the samples run from one to the other; `end only`: the end is reached, no start was
/// promised; `incomplete`: cut short at either end; `not promised`: the writer promised nothing,
/// as ROS bags and v1 logs, so only the span is stated).
pub fn evidence_row(r: &RunResult) -> [String; 4] {
    let e = &r.evidence;
    let completeness = match e.completeness {
        pacs_audit::Completeness::Complete => "complete (start and end events reached)",
        pacs_audit::Completeness::EndOnly => {
            "end event reached; no start promised (a cut at the beginning cannot be told)"
        }
        pacs_audit::Completeness::Incomplete => "INCOMPLETE (cut short: never a pass)",
        pacs_audit::Completeness::NotPromised => "not promised by the writer (span only)",
    };
    // The header the verdict rests on, where it was given with `--header`, and whether it
    // replaced the log's own (whose `start`/`end` promises it keeps).
    let text = |k: &str| r.meta.get(k).and_then(|v| v.as_str());
    let mut completeness = completeness.to_string();
    if let Some(f) = text("header_file") {
        let sha = text("header_file_sha256").unwrap_or("?");
        completeness.push_str(&format!("; header from `--header {f}` (sha256 {sha})"));
        if r.meta.get("own_header_replaced") == Some(&Value::Bool(true)) {
            completeness.push_str(", in place of the log's own (its start/end promises kept)");
        }
    }
    // A ROS recording's stamps count from its time base (s since the Unix epoch).
    let base = ["mcap_time_base_s", "db3_time_base_s"]
        .iter()
        .find_map(|k| r.meta.get(*k).and_then(Value::as_f64));
    [
        r.log.clone(),
        if r.people.is_empty() {
            "—".into()
        } else {
            r.people.join(", ")
        },
        if r.metrics.samples == 0 {
            "no robot samples".into()
        } else {
            match base {
                Some(b) => format!(
                    "{:.3} – {:.3} after the recording's time base {b} s",
                    e.t_start, e.t_end
                ),
                None => format!("{:.3} – {:.3}", e.t_start, e.t_end),
            }
        },
        completeness,
    ]
}

/// The sentence on entries under the given directories that were not audited (not logs), for
/// every form of the report; `None` when there are none. At most ten are named.
pub fn skipped_note(skipped: &[String]) -> Option<String> {
    if skipped.is_empty() {
        return None;
    }
    let named: Vec<&str> = skipped.iter().take(10).map(String::as_str).collect();
    let more = skipped.len().saturating_sub(named.len());
    Some(format!(
        "Not audited: {} entr{} under the given directories {} not a log (not *.{}, or a symbolic link to a directory, which is not followed): {}{}.",
        skipped.len(),
        if skipped.len() == 1 { "y" } else { "ies" },
        if skipped.len() == 1 { "is" } else { "are" },
        pacs_log::db3::LOG_EXTENSIONS.join(", *."),
        named.join(", "),
        if more > 0 {
            format!(" and {more} more (report.json lists all)")
        } else {
            String::new()
        }
    ))
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
                "model_parameters": model_specs(r),
                "meta": r.meta,
                "episodes": episodes::episodes(&r.violations),
                "violations": r.violations,
                "inconclusive": r.inconclusive,
                "metrics": r.metrics,
                "evidence": r.evidence,
                "people": r.people,
            })
        })
        .collect();
    json!({
        "report": "pacs-audit-certification",
        "tool": {"name": "pacs", "version": TOOL_VERSION, "git_revision": GIT_REVISION},
        "generated_utc": input.generated(),
        "definitions": definitions(),
        "inputs": inputs_json(&input.logs, input.config.as_ref()),
        "settings": input.settings,
        "assumptions": assumptions(),
        "user_values": user_values(input.runs),
        "checks": check_backing(),
        "verdict": overall(input.runs),
        "runs": runs,
        "skipped": input.skipped,
        "aggregate": aggregate::aggregate(input.runs),
        "fleet": fleet::of_input(input),
    })
}

/// Write `report.json`, `violations.csv`, `report.md`, `report.html` and `report.pdf` into `dir`
/// (created if missing).
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
    let c = dir.join("violations.csv");
    std::fs::write(&c, episodes::violations_csv(input.runs)).map_err(io(&c))?;
    let m = dir.join("report.md");
    std::fs::write(&m, markdown::report(input)).map_err(io(&m))?;
    let h = dir.join("report.html");
    std::fs::write(&h, html::report(input)).map_err(io(&h))?;
    let p = dir.join("report.pdf");
    std::fs::write(&p, pdf::report(input)).map_err(io(&p))?;
    Ok(())
}
