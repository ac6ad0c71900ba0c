//! `report.html`: one self-contained file (inline CSS and SVG, no scripts), readable when printed.

use crate::{
    GIT_REVISION, ReportInput, TOOL_VERSION, aggregate, assumptions, check_backing, overall, svg,
};
use pacs_audit::{RunResult, Verdict};
use std::fmt::Write;

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn verdict_cell(v: Verdict) -> String {
    let (c, t) = match v {
        Verdict::Pass => ("pass", "PASS"),
        Verdict::Fail => ("fail", "FAIL"),
        Verdict::Inconclusive => ("inconclusive", "INCONCLUSIVE"),
    };
    format!(r#"<span class="v {c}">{t}</span>"#)
}

/// The effective settings as a two-column table.
fn settings_table(s: &mut String, settings: &serde_json::Value) {
    s.push_str("<table><tr><th>setting</th><th>value</th></tr>");
    for (k, v) in crate::settings_rows(settings) {
        let _ = write!(
            s,
            "<tr><td><code>{}</code></td><td>{}</td></tr>",
            esc(&k),
            esc(&v)
        );
    }
    s.push_str("</table>");
}

/// A run's models with their parameters and hashes ([`crate::model_rows`]).
fn models_table(s: &mut String, r: &RunResult) {
    s.push_str("<table><tr><th>model</th><th>name</th><th>parameters</th><th>SHA-256 of the parameters</th></tr>");
    for [model, name, params, hash] in crate::model_rows(r) {
        let _ = write!(
            s,
            "<tr><td>{model}</td><td><code>{}</code></td><td>{}</td><td><code class=\"hash\">{hash}</code></td></tr>",
            esc(&name),
            esc(&params)
        );
    }
    s.push_str("</table>");
}

/// The document head: title and the inline stylesheet (screen and print).
const HEAD: &str = r#"<!DOCTYPE html><html lang="en"><head><meta charset="utf-8"><title>pacs audit report</title><style>
body{font-family:sans-serif;max-width:76em;margin:1em auto;padding:0 1em;color:#111;line-height:1.35}
table{border-collapse:collapse;margin:.5em 0;font-size:88%;width:100%;table-layout:auto}
th,td{border:1px solid #999;padding:2px 6px;text-align:left;vertical-align:top;overflow-wrap:break-word}
th{word-break:normal;hyphens:auto}
td.num,th.num{text-align:right;white-space:nowrap}table.episodes th.num{white-space:normal}
th{background:#eee}.v{font-weight:bold;padding:0 4px}.pass{color:#1b5e20}.fail{color:#b71c1c}.inconclusive{color:#e65100}
code{font-size:90%;overflow-wrap:anywhere}.hash{font-size:75%}.note{font-size:85%;color:#333}
section{page-break-inside:avoid;break-inside:avoid}svg{max-width:100%;height:auto}
@media print{body{max-width:none;font-size:10pt;margin:0}table{font-size:8pt}h2{break-after:avoid}tr{break-inside:avoid}a{color:inherit}}
</style></head><body>"#;

/// The HTML report.
pub fn report(input: &ReportInput) -> String {
    let mut s = String::new();
    s.push_str(HEAD);
    provenance(&mut s, input);
    summary_table(&mut s, input);
    evidence_table(&mut s, input.runs);
    if let Some(note) = crate::skipped_note(&input.skipped) {
        let _ = write!(s, "<p>{}</p>", esc(&note));
    }
    if input.runs.len() > 1 {
        aggregate_section(&mut s, input);
    }
    for r in input.runs {
        run_section(&mut s, r);
    }
    assumptions_section(&mut s, input.runs);
    check_backing_table(&mut s);
    s.push_str("</body></html>\n");
    s
}

/// The title with the tool version, git revision and overall verdict, then the config file and
/// the effective settings.
fn provenance(s: &mut String, input: &ReportInput) {
    let _ = write!(
        s,
        "<h1>pacs audit certification report</h1><p>Generated {} by pacs {} (git <code>{}</code>). Overall verdict: {}</p>",
        input.generated(),
        TOOL_VERSION,
        esc(GIT_REVISION),
        verdict_cell(overall(input.runs))
    );
    let _ = write!(
        s,
        "<h2>Settings</h2><p>Config: {}.</p>",
        input
            .config
            .as_ref()
            .map(|c| format!(
                "<code>{}</code> (SHA-256 <code class=\"hash\">{}</code>)",
                esc(&c.path),
                c.sha256
            ))
            .unwrap_or_else(|| "defaults".into()),
    );
    settings_table(s, &input.settings);
}

/// One row per log ([`crate::summary_cells`]), with the footnotes on separation and safe success.
fn summary_table(s: &mut String, input: &ReportInput) {
    s.push_str("<h2>Summary</h2><table><tr>");
    for (i, h) in crate::SUMMARY_COLUMNS.iter().enumerate() {
        let h = h.replace(" (1)", "¹").replace(" (2)", "²");
        let class = if (3..=7).contains(&i) {
            " class=\"num\""
        } else {
            ""
        };
        let _ = write!(s, "<th{class}>{h}</th>");
    }
    s.push_str("</tr>");
    for (r, f) in input.runs.iter().zip(&input.logs) {
        s.push_str("<tr>");
        for (i, c) in crate::summary_cells(r, f).iter().enumerate() {
            match i {
                0 => {
                    let _ = write!(
                        s,
                        "<td><code>{}</code><br><code class=\"hash\">{}</code></td>",
                        esc(&r.log),
                        f.sha256
                    );
                }
                2 => {
                    let _ = write!(s, "<td>{}</td>", verdict_cell(r.verdict));
                }
                // A separation with its note wraps like text.
                6 if crate::contact_note(r).is_some() => {
                    let _ = write!(s, "<td>{}</td>", esc(c));
                }
                3..=7 => {
                    let _ = write!(s, "<td class=\"num\">{}</td>", esc(c));
                }
                _ => {
                    let _ = write!(s, "<td>{}</td>", esc(c));
                }
            }
        }
        s.push_str("</tr>");
    }
    s.push_str("</table><p class=\"note\">¹ The separation figure: over the checked spans and robot/body-part capsule pairs, the least lower bound of the core-segment distance minus the radii; &gt; 0: the robot's and the human's occupancies are provably at least this far apart; ≤ 0: contact possible. ² Safe success: the task succeeded (last <code>success</code>/<code>failure</code> event) and the audit verdict is pass.</p>");
}

/// What each log covers: its people, the audited span (s) and whether the log is complete.
fn evidence_table(s: &mut String, runs: &[RunResult]) {
    s.push_str("<h2>Evidence</h2><table><tr><th>log</th><th>people</th><th>audited span (s)</th><th>log complete</th></tr>");
    for r in runs {
        let [log, people, span, complete] = crate::evidence_row(r);
        let _ = write!(
            s,
            "<tr><td><code>{}</code></td><td>{}</td><td>{}</td><td>{}</td></tr>",
            esc(&log),
            esc(&people),
            esc(&span),
            esc(&complete)
        );
    }
    s.push_str("</table>");
}

/// Success and violation fraction per task, policy and filter, then the fleet view (several
/// logs only).
fn aggregate_section(s: &mut String, input: &ReportInput) {
    s.push_str("<h2>Aggregate (impact of safeguarding)</h2><table><tr><th>task</th><th>policy</th><th>filter</th><th class=\"num\">n (logs)</th><th class=\"num\">success</th><th class=\"num\">safe success</th><th class=\"num\">violation fraction (mean ± std)</th></tr>");
    for row in aggregate::aggregate(input.runs) {
        let _ = write!(
            s,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td></tr>",
            esc(&row.task),
            esc(&row.policy),
            esc(&row.filter),
            row.runs,
            aggregate::pct(row.success),
            aggregate::pct(row.safe_success),
            aggregate::violation_cell(&row)
        );
    }
    s.push_str("</table>");
    s.push_str(&crate::fleet::html(&crate::fleet::of_input(input), esc));
}

/// One log's section: verdict, models, the separation and energy plots, the contact note, the
/// violation episodes and the inconclusive spans.
fn run_section(s: &mut String, r: &RunResult) {
    let _ = write!(
        s,
        "<section><h2><code>{}</code> {}</h2>",
        esc(&r.log),
        verdict_cell(r.verdict),
    );
    models_table(s, r);
    s.push_str(&svg::separation_plot(&r.series));
    if svg::has_threshold(&r.series) {
        s.push_str(&svg::energy_plot(&r.series));
    } else {
        s.push_str("<p class=\"note\">No PFL contact was possible in this run, so no energy limit applied (an SSM body part may only be touched by a robot at rest); no energy plot.</p>");
    }
    if let Some(note) = crate::contact_note(r) {
        let _ = write!(
            s,
            "<p class=\"contact-note\">Passed with a separation figure ≤ 0: {note}.</p>"
        );
    }
    episodes_table(s, r);
    inconclusive_list(s, r);
    s.push_str("</section>");
}

/// A log's violation intervals merged into episodes ([`crate::episodes`]), with the footnotes on
/// the separation and on certain violations; "No violations." if there are none.
fn episodes_table(s: &mut String, r: &RunResult) {
    let eps = crate::episodes::episodes(&r.violations);
    if eps.is_empty() {
        s.push_str("<p>No violations.</p>");
        return;
    }
    let _ = write!(
        s,
        "<p>{} violation episode(s) from {} violation interval(s) (the intervals: report.json and violations.csv).</p><table class=\"episodes\"><tr>",
        eps.len(),
        r.violations.len()
    );
    let num = |i: usize| matches!(i, 0 | 1 | 5 | 6 | 7 | 8);
    for (i, h) in crate::episodes::EPISODE_COLUMNS.iter().enumerate() {
        let mark = match i {
            6 => "³",
            9 => "⁴",
            _ => "",
        };
        let class = if num(i) { " class=\"num\"" } else { "" };
        let _ = write!(s, "<th{class}>{h}{mark}</th>");
    }
    s.push_str("</tr>");
    for e in &eps {
        s.push_str("<tr>");
        for (i, c) in crate::episodes::episode_cells(e).iter().enumerate() {
            let class = if num(i) { " class=\"num\"" } else { "" };
            let _ = write!(s, "<td{class}>{}</td>", esc(c));
        }
        s.push_str("</tr>");
    }
    s.push_str("</table><p class=\"note\">³ Signed separation of the logged robot capsules and the measured body part or object (negative: they overlap as logged); a violation can be possible at a positive value because the person may have moved since the measurement. ⁴ Certain: the logged robot and the measured person themselves violate the constraint; possible: some motion the models allow does. An episode merges the intervals of one person or object, link and constraint less than 0.1 s apart.</p>");
}

/// A log's inconclusive spans with their times (s), reasons and span counts (nothing if none).
fn inconclusive_list(s: &mut String, r: &RunResult) {
    if r.inconclusive.is_empty() {
        return;
    }
    s.push_str("<p>Inconclusive spans:</p><ul>");
    for i in &r.inconclusive {
        let _ = write!(
            s,
            "<li>{:.4}–{:.4} s: {} ({} spans)</li>",
            i.t_start,
            i.t_end,
            esc(&crate::inconclusive_what(
                i.reason.as_str(),
                i.person.as_deref(),
                i.object.as_deref()
            )),
            i.spans
        );
    }
    s.push_str("</ul>");
}

/// The modelling assumptions, then the model values the user gave ([`crate::user_values`]).
fn assumptions_section(s: &mut String, runs: &[RunResult]) {
    s.push_str("<h2>Assumptions</h2><ul>");
    for a in assumptions() {
        let _ = write!(s, "<li>{}</li>", esc(a));
    }
    s.push_str("</ul>");
    let user = crate::user_values(runs);
    if !user.is_empty() {
        let _ = write!(
            s,
            "<p>{}:</p><ul class=\"user-values\">",
            esc(crate::USER_VALUES_HEADING)
        );
        for v in &user {
            let _ = write!(s, "<li>{}</li>", esc(v));
        }
        s.push_str("</ul>");
    }
}

/// Each check the audit makes with the tests and harnesses backing it ([`check_backing`]).
fn check_backing_table(s: &mut String) {
    s.push_str("<h2>Checks and the tests backing them</h2><table><tr><th>check</th><th>backed by</th></tr>");
    if let Some(arr) = check_backing().as_array() {
        for c in arr {
            let _ = write!(
                s,
                "<tr><td>{}</td><td>{}</td></tr>",
                esc(c["check"].as_str().unwrap_or("")),
                c["backed_by"]
                    .as_array()
                    .map(|v| v
                        .iter()
                        .filter_map(|x| x.as_str())
                        .map(esc)
                        .collect::<Vec<_>>()
                        .join("<br>"))
                    .unwrap_or_default()
            );
        }
    }
    s.push_str("</table>");
}
