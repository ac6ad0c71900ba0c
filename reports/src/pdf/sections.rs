//! The report's sections, in the order `report` draws them: the front matter, the summary, the
//! evidence and the aggregate, per log its models, plots, episodes and inconclusive spans, then
//! the assumptions and the checks with the tests backing them.

use super::{Doc, Font};
use crate::svg::has_threshold;
use crate::{
    GIT_REVISION, ReportInput, TOOL_VERSION, aggregate, assumptions, check_backing, overall,
};
use pacs_audit::RunResult;
use serde_json::Value;

fn reg(s: impl Into<String>) -> (String, Font) {
    (s.into(), Font::Regular)
}

fn mono(s: impl Into<String>) -> (String, Font) {
    (s.into(), Font::Mono)
}

/// The text of the definition `k` ([`definitions`]), empty if there is none.
fn def(defs: &Value, k: &str) -> String {
    defs[k].as_str().unwrap_or("").to_string()
}

/// The title, the tool version, git revision and overall verdict, then the config file and the
/// effective settings.
pub(super) fn front_matter(d: &mut Doc, input: &ReportInput) {
    d.para("pacs audit certification report", 16.0, Font::Bold);
    d.gap(4.0);
    d.para(
        &format!(
            "Generated {} by pacs {TOOL_VERSION} (git {GIT_REVISION}). Overall verdict: {}.",
            input.generated(),
            format!("{:?}", overall(input.runs)).to_uppercase()
        ),
        9.5,
        Font::Regular,
    );
    d.heading("Settings", 12.0);
    d.para(
        &match &input.config {
            Some(c) => format!("Config {} (SHA-256 {}).", c.path, c.sha256),
            None => "Config: defaults.".into(),
        },
        8.5,
        Font::Regular,
    );
    let rows: Vec<Vec<(String, Font)>> = crate::settings_rows(&input.settings)
        .into_iter()
        .map(|(k, v)| vec![mono(k), reg(v)])
        .collect();
    d.table(&["setting", "value"], &[0.3, 0.7], &rows, 8.0);
}

/// One row per log ([`crate::summary_cells`]), with the footnotes on separation and safe success.
pub(super) fn summary_table(d: &mut Doc, input: &ReportInput, defs: &Value) {
    d.heading("Summary", 12.0);
    let rows: Vec<Vec<(String, Font)>> = input
        .runs
        .iter()
        .zip(&input.logs)
        .map(|(r, f)| crate::summary_cells(r, f).into_iter().map(reg).collect())
        .collect();
    d.table(
        &crate::SUMMARY_COLUMNS,
        &[0.24, 0.08, 0.08, 0.06, 0.07, 0.08, 0.13, 0.08, 0.08, 0.10],
        &rows,
        7.0,
    );
    d.para(
        &format!("(1) Separation: {}.", def(defs, "separation_m")),
        7.0,
        Font::Regular,
    );
    d.para(
        &format!("(2) Safe success: {}.", def(defs, "safe_success")),
        7.0,
        Font::Regular,
    );
}

/// What each log covers: its people, the audited span and whether it is the whole run.
pub(super) fn evidence_table(d: &mut Doc, runs: &[RunResult]) {
    d.heading("Evidence", 12.0);
    let rows: Vec<Vec<(String, Font)>> = runs
        .iter()
        .map(|r| crate::evidence_row(r).into_iter().map(reg).collect())
        .collect();
    d.table(
        &crate::EVIDENCE_COLUMNS,
        &[0.4, 0.2, 0.15, 0.25],
        &rows,
        7.0,
    );
}

/// Success and violation fraction per task, policy and filter ([`aggregate::aggregate`]).
pub(super) fn aggregate_table(d: &mut Doc, runs: &[RunResult]) {
    d.heading("Aggregate (impact of safeguarding)", 12.0);
    let rows: Vec<Vec<(String, Font)>> = aggregate::aggregate(runs)
        .into_iter()
        .map(|a| {
            let violation = aggregate::violation_cell(&a);
            vec![
                reg(a.task),
                reg(a.policy),
                reg(a.filter),
                reg(a.runs.to_string()),
                reg(aggregate::pct(a.success)),
                reg(aggregate::pct(a.safe_success)),
                reg(violation),
            ]
        })
        .collect();
    d.table(
        &[
            "task",
            "policy",
            "filter",
            "n (logs)",
            "success",
            "safe success",
            "violation fraction (mean ± std)",
        ],
        &[0.14, 0.14, 0.14, 0.1, 0.14, 0.14, 0.2],
        &rows,
        7.5,
    );
}

/// One log's section: verdict, models, the separation and energy plots, the contact note, the
/// violation episodes and the inconclusive spans.
pub(super) fn run_section(d: &mut Doc, r: &RunResult, defs: &Value) {
    d.heading(
        &format!("{}: {}", r.log, format!("{:?}", r.verdict).to_uppercase()),
        11.0,
    );
    models_table(d, r);
    d.plot(&r.series, false);
    if has_threshold(&r.series) {
        d.plot(&r.series, true);
    } else {
        d.para(
            "No PFL contact was possible in this run, so no energy limit applied; no energy plot.",
            8.0,
            Font::Regular,
        );
    }
    d.para(
        "Shading: green = robot at rest, red = violation possible, grey = inconclusive.",
        7.0,
        Font::Regular,
    );
    if let Some(note) = crate::contact_note(r) {
        d.para(
            &format!("Passed with a separation figure <= 0: {note}."),
            8.5,
            Font::Regular,
        );
    }
    episodes_table(d, r, defs);
    inconclusive_list(d, r);
}

/// A run's models with their parameters and hashes ([`crate::model_rows`]).
fn models_table(d: &mut Doc, r: &RunResult) {
    let rows: Vec<Vec<(String, Font)>> = crate::model_rows(r)
        .into_iter()
        .map(|[model, name, params, hash]| vec![reg(model), reg(name), reg(params), mono(hash)])
        .collect();
    d.table(
        &[
            "model",
            "name",
            "parameters (all in report.json)",
            "SHA-256 of the parameters",
        ],
        &[0.1, 0.12, 0.43, 0.35],
        &rows,
        7.0,
    );
}

/// A log's violation intervals merged into episodes ([`crate::episodes`]), the first 60 shown,
/// with the footnotes on the separation and on certain violations; "No violations." if none.
fn episodes_table(d: &mut Doc, r: &RunResult, defs: &Value) {
    let eps = crate::episodes::episodes(&r.violations);
    if eps.is_empty() {
        d.para("No violations.", 9.0, Font::Regular);
        return;
    }
    const SHOWN: usize = 60;
    d.para(
        &format!(
            "{} violation episode(s) from {} violation interval(s) (the intervals: report.json and violations.csv).",
            eps.len(),
            r.violations.len()
        ),
        8.5,
        Font::Regular,
    );
    let rows: Vec<Vec<(String, Font)>> = eps
        .iter()
        .take(SHOWN)
        .map(|e| {
            crate::episodes::episode_cells(e)
                .into_iter()
                .map(reg)
                .collect()
        })
        .collect();
    let mut heads = crate::episodes::EPISODE_COLUMNS;
    heads[6] = "worst separation (m) (3)";
    heads[9] = "certain (4)";
    d.table(
        &heads,
        &[0.07, 0.07, 0.18, 0.1, 0.14, 0.1, 0.09, 0.08, 0.09, 0.08],
        &rows,
        7.0,
    );
    if eps.len() > SHOWN {
        d.para(
            &format!("... {} more episodes in report.json.", eps.len() - SHOWN),
            7.5,
            Font::Regular,
        );
    }
    d.para(
        &format!(
            "(3) {}. (4) Certain: the logged robot and the measured person themselves violate the constraint; possible: some motion the models allow does. An episode merges the intervals of one person or object, link and constraint less than 0.1 s apart.",
            def(defs, "violation_separation_m")
        ),
        7.0,
        Font::Regular,
    );
}

/// The first 40 of a log's inconclusive spans with their times (s), reasons and span counts
/// (nothing if none).
fn inconclusive_list(d: &mut Doc, r: &RunResult) {
    if r.inconclusive.is_empty() {
        return;
    }
    d.para("Inconclusive spans:", 8.5, Font::Bold);
    for i in r.inconclusive.iter().take(40) {
        d.para(
            &format!(
                "- {:.4}-{:.4} s: {} ({} spans)",
                i.t_start,
                i.t_end,
                crate::inconclusive_what(
                    i.reason.as_str(),
                    i.person.as_deref(),
                    i.object.as_deref(),
                ),
                i.spans
            ),
            8.0,
            Font::Regular,
        );
    }
}

/// The modelling assumptions, then the model values the user gave ([`crate::user_values`]).
pub(super) fn assumptions_section(d: &mut Doc, runs: &[RunResult]) {
    d.heading("Assumptions", 12.0);
    for a in assumptions() {
        d.para(&format!("- {a}"), 8.0, Font::Regular);
    }
    let user = crate::user_values(runs);
    if !user.is_empty() {
        d.para(&format!("{}:", crate::USER_VALUES_HEADING), 8.0, Font::Bold);
        for v in &user {
            d.para(&format!("- {v}"), 8.0, Font::Regular);
        }
    }
}

/// Each check the audit makes with the tests and harnesses backing it ([`check_backing`]).
pub(super) fn check_backing_table(d: &mut Doc) {
    d.heading("Checks and the tests backing them", 12.0);
    let rows: Vec<Vec<(String, Font)>> = check_backing()
        .as_array()
        .map(|arr| {
            arr.iter()
                .map(|c| {
                    vec![
                        reg(c["check"].as_str().unwrap_or("").to_string()),
                        mono(
                            c["backed_by"]
                                .as_array()
                                .map(|v| {
                                    v.iter()
                                        .filter_map(|x| x.as_str())
                                        .collect::<Vec<_>>()
                                        .join("; ")
                                })
                                .unwrap_or_default(),
                        ),
                    ]
                })
                .collect()
        })
        .unwrap_or_default();
    d.table(&["check", "backed by"], &[0.45, 0.55], &rows, 6.5);
}
