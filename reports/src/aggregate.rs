//! Aggregate table over several logs, grouped by `meta.task`, `meta.policy`, `meta.filter` (the
//! paper's "Impact of safeguarding"): Success, Safe Success, Safety Viol. as mean ± std (the
//! std n/a for a single log). `meta.filter` is the filter that ran (`pacs shield` writes its
//! configured mode, `pacs simulate` its method), so PACS and OFF runs are never averaged together.

use pacs_audit::RunResult;
use serde::Serialize;

/// One group of runs with equal (task, policy, filter).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Row {
    /// `meta.task` (or "-").
    pub task: String,
    /// `meta.policy` (or "-").
    pub policy: String,
    /// `meta.filter` (or "-").
    pub filter: String,
    /// Number of logs.
    pub runs: usize,
    /// Mean and sample std of success (0/1) over logs with an outcome (None if none; the std
    /// None for one log). In JSON `{"mean": m, "std": s}`, `std` left out for one log and the
    /// whole field for none (no `null`).
    #[serde(
        skip_serializing_if = "Option::is_none",
        serialize_with = "mean_std_json_opt"
    )]
    pub success: Option<(f64, Option<f64>)>,
    /// Mean and std of safe success (0/1) over logs with an outcome (JSON as `success`).
    #[serde(
        skip_serializing_if = "Option::is_none",
        serialize_with = "mean_std_json_opt"
    )]
    pub safe_success: Option<(f64, Option<f64>)>,
    /// Mean and std of the violation fraction over the logs with a verdict (pass or fail; JSON
    /// as `success`, left out when every log is inconclusive): an inconclusive log's fraction
    /// counts only what was checked, and would pass unchecked time off as free of violations.
    #[serde(
        skip_serializing_if = "Option::is_none",
        serialize_with = "mean_std_json_opt"
    )]
    pub safety_violation: Option<(f64, Option<f64>)>,
    /// Logs left out of `safety_violation`: inconclusive.
    pub inconclusive: usize,
}

/// `{"mean": m, "std": s}`, `std` left out when there is none (one log).
fn mean_std_json<S: serde::Serializer>(v: &(f64, Option<f64>), s: S) -> Result<S::Ok, S::Error> {
    use serde::ser::SerializeMap;
    let mut m = s.serialize_map(None)?;
    m.serialize_entry("mean", &v.0)?;
    if let Some(std) = v.1 {
        m.serialize_entry("std", &std)?;
    }
    m.end()
}

/// [`mean_std_json`] of a present value (the field is skipped when absent).
fn mean_std_json_opt<S: serde::Serializer>(
    v: &Option<(f64, Option<f64>)>,
    s: S,
) -> Result<S::Ok, S::Error> {
    match v {
        Some(v) => mean_std_json(v, s),
        None => s.serialize_none(),
    }
}

fn meta_str(r: &RunResult, k: &str) -> String {
    match r.meta.get(k) {
        Some(serde_json::Value::String(s)) => s.clone(),
        Some(v) => v.to_string(),
        None => "-".into(),
    }
}

/// Mean and sample standard deviation (None for a single value: no spread to measure); None if
/// empty.
pub fn mean_std(xs: &[f64]) -> Option<(f64, Option<f64>)> {
    if xs.is_empty() {
        return None;
    }
    let n = xs.len() as f64;
    let mean = xs.iter().sum::<f64>() / n;
    let std = (xs.len() > 1)
        .then(|| (xs.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1.0)).sqrt());
    Some((mean, std))
}

/// The filter a run used: `meta.filter`, with the mode of `meta.shield_config` where the log
/// has one (the Python `Shield` records its settings there and `"filter": "pacs-shield
/// (python)"` whatever the mode; a missing `mode` is the default, `pacs`).
pub fn filter_of(r: &RunResult) -> String {
    let f = meta_str(r, "filter");
    match r.meta.get("shield_config") {
        Some(c) => format!(
            "{f}, mode {}",
            c.get("mode").and_then(|m| m.as_str()).unwrap_or("pacs")
        ),
        None => f,
    }
}

/// Rows in order of first appearance.
pub fn aggregate(runs: &[RunResult]) -> Vec<Row> {
    let mut keys: Vec<(String, String, String)> = Vec::new();
    for r in runs {
        let k = (meta_str(r, "task"), meta_str(r, "policy"), filter_of(r));
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    keys.into_iter()
        .map(|k| {
            let group: Vec<&RunResult> = runs
                .iter()
                .filter(|r| (meta_str(r, "task"), meta_str(r, "policy"), filter_of(r)) == k)
                .collect();
            let b = |x: bool| if x { 1.0 } else { 0.0 };
            let succ: Vec<f64> = group
                .iter()
                .filter_map(|r| r.metrics.success.map(b))
                .collect();
            let safe: Vec<f64> = group
                .iter()
                .filter_map(|r| r.metrics.safe_success.map(b))
                .collect();
            let conclusive = |r: &&&RunResult| r.verdict != pacs_audit::Verdict::Inconclusive;
            let viol: Vec<f64> = group
                .iter()
                .filter(conclusive)
                .map(|r| r.metrics.violation_fraction)
                .collect();
            Row {
                task: k.0,
                policy: k.1,
                filter: k.2,
                runs: group.len(),
                success: mean_std(&succ),
                safe_success: mean_std(&safe),
                safety_violation: mean_std(&viol),
                inconclusive: group.len() - viol.len(),
            }
        })
        .collect()
}

/// The safety-violation cell: [`pct`] of the logs with a verdict, and how many inconclusive
/// logs were left out ("n/a" when every log is).
pub fn violation_cell(row: &Row) -> String {
    match row.inconclusive {
        0 => pct(row.safety_violation),
        k => format!("{} ({k} inconclusive left out)", pct(row.safety_violation)),
    }
}

/// "m ± s %" with percentages; "m % ± n/a" for one log, "n/a" for none.
pub fn pct(v: Option<(f64, Option<f64>)>) -> String {
    match v {
        Some((m, Some(s))) => format!("{:.1} ± {:.1} %", 100.0 * m, 100.0 * s),
        Some((m, None)) => format!("{:.1} % ± n/a", 100.0 * m),
        None => "n/a".into(),
    }
}
