//! `report.md`: the same content as the HTML report, without plots.

use crate::{
    GIT_REVISION, ReportInput, TOOL_VERSION, aggregate, assumptions, definitions, overall,
};
use std::fmt::Write;

/// Text from a log (file names, `meta` values, model names) as one Markdown table cell: `|`
/// escaped and control characters (a newline would end the row) shown as spaces.
pub fn md_cell(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '|' => out.push_str("\\|"),
            c if c.is_control() => out.push(' '),
            c => out.push(c),
        }
    }
    out
}

/// Text from a log on a line of its own (a heading, a list item): control characters (a
/// newline would start another line, perhaps a heading) shown as spaces.
pub fn md_line(text: &str) -> String {
    text.chars()
        .map(|c| if c.is_control() { ' ' } else { c })
        .collect()
}

/// One table row of cells, each through [`md_cell`].
fn md_row<S: AsRef<str>>(cells: &[S]) -> String {
    let cells: Vec<String> = cells.iter().map(|c| md_cell(c.as_ref())).collect();
    format!("| {} |", cells.join(" | "))
}

/// The Markdown report.
pub fn report(input: &ReportInput) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# pacs audit certification report\n");
    let _ = writeln!(
        s,
        "- Generated: {}\n- Tool: pacs {TOOL_VERSION} (git {GIT_REVISION})\n- Overall verdict: **{:?}**",
        input.generated(),
        overall(input.runs)
    );
    if let Some(c) = &input.config {
        let _ = writeln!(
            s,
            "- Config: `{}` (SHA-256 `{}`)",
            md_line(&c.path),
            c.sha256
        );
    } else {
        let _ = writeln!(s, "- Config: defaults");
    }
    let _ = writeln!(s, "\n| setting | value |\n|---|---|");
    for (k, v) in crate::settings_rows(&input.settings) {
        let _ = writeln!(s, "{}", md_row(&[format!("`{k}`"), v]));
    }
    let _ = writeln!(s);
    let _ = writeln!(s, "## Summary\n");
    let _ = writeln!(
        s,
        "| {} |\n|{}",
        crate::SUMMARY_COLUMNS.join(" | "),
        "---|".repeat(crate::SUMMARY_COLUMNS.len())
    );
    for (r, f) in input.runs.iter().zip(&input.logs) {
        let mut cells = crate::summary_cells(r, f);
        cells[0] = format!("`{}` (`{}…`)", r.log, &f.sha256[..16.min(f.sha256.len())]);
        cells[2] = format!("**{}**", cells[2]);
        let _ = writeln!(s, "{}", md_row(&cells));
    }
    s.push_str(
        "\n### Evidence\n\n| log | people | audited span (s) | log complete |\n|---|---|---|---|\n",
    );
    for r in input.runs {
        let [log, people, span, complete] = crate::evidence_row(r);
        let _ = writeln!(
            s,
            "{}",
            md_row(&[format!("`{log}`"), people, span, complete])
        );
    }
    if let Some(note) = crate::skipped_note(&input.skipped) {
        let _ = writeln!(s, "\n{}", md_cell(&note));
    }
    let d = definitions();
    let _ = writeln!(
        s,
        "\n(1) Separation: {}. (2) Safe success: {}.",
        d["separation_m"].as_str().unwrap_or(""),
        d["safe_success"].as_str().unwrap_or("")
    );
    if input.runs.len() > 1 {
        let _ = writeln!(
            s,
            "\n## Aggregate (impact of safeguarding)\n\n| task | policy | filter | n (logs) | success | safe success | violation fraction (mean ± std) |\n|---|---|---|---|---|---|---|"
        );
        for row in aggregate::aggregate(input.runs) {
            let violation = aggregate::violation_cell(&row);
            let cells = [
                row.task,
                row.policy,
                row.filter,
                row.runs.to_string(),
                aggregate::pct(row.success),
                aggregate::pct(row.safe_success),
                violation,
            ];
            let _ = writeln!(s, "{}", md_row(&cells));
        }
        s.push_str(&crate::fleet::markdown(&crate::fleet::of_input(input)));
    }
    for r in input.runs {
        let _ = writeln!(s, "\n## `{}` — {:?}\n", md_line(&r.log), r.verdict);
        let _ = writeln!(
            s,
            "| model | name | parameters (all in report.json) | SHA-256 of the parameters |\n|---|---|---|---|"
        );
        for [model, name, params, hash] in crate::model_rows(r) {
            let _ = writeln!(
                s,
                "{}",
                md_row(&[model, format!("`{name}`"), params, format!("`{hash}`")])
            );
        }
        let _ = writeln!(s);
        if let Some(note) = crate::contact_note(r) {
            let _ = writeln!(s, "Passed with a separation figure ≤ 0: {note}.\n");
        }
        let eps = crate::episodes::episodes(&r.violations);
        if eps.is_empty() {
            let _ = writeln!(s, "No violations.");
        } else {
            let _ = writeln!(
                s,
                "{} violation episode(s) from {} violation interval(s) (the intervals: report.json and violations.csv).\n",
                eps.len(),
                r.violations.len()
            );
            let _ = writeln!(
                s,
                "| {} |\n|{}",
                crate::episodes::EPISODE_COLUMNS.join(" | "),
                "---|".repeat(crate::episodes::EPISODE_COLUMNS.len())
            );
            for e in &eps {
                let _ = writeln!(s, "{}", md_row(&crate::episodes::episode_cells(e)));
            }
            let _ = writeln!(
                s,
                "\nWorst separation: {}. Episode: {}.",
                d["violation_separation_m"].as_str().unwrap_or(""),
                d["episode"].as_str().unwrap_or("")
            );
        }
        if !r.inconclusive.is_empty() {
            let _ = writeln!(s, "\nInconclusive spans:\n");
            for i in &r.inconclusive {
                let _ = writeln!(
                    s,
                    "- {:.4}–{:.4} s: {} ({} spans)",
                    i.t_start,
                    i.t_end,
                    crate::inconclusive_what(
                        i.reason.as_str(),
                        i.person.as_deref(),
                        i.object.as_deref(),
                    ),
                    i.spans
                );
            }
        }
    }
    let _ = writeln!(s, "\n## Assumptions\n");
    for a in assumptions() {
        let _ = writeln!(s, "- {a}");
    }
    let user = crate::user_values(input.runs);
    if !user.is_empty() {
        let _ = writeln!(s, "\n{}:\n", crate::USER_VALUES_HEADING);
        for v in &user {
            let _ = writeln!(s, "- {}", md_line(v));
        }
    }
    s
}
