//! `report.md`: the same content as the HTML report, without plots.

use crate::{
    GIT_REVISION, ReportInput, TOOL_VERSION, aggregate, assumptions, definitions, overall,
};
use std::fmt::Write;

fn opt(v: Option<f64>, unit: &str) -> String {
    v.map(|x| format!("{x:.4} {unit}"))
        .unwrap_or_else(|| "n/a".into())
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
        let _ = writeln!(s, "- Config: `{}` (SHA-256 `{}`)", c.path, c.sha256);
    } else {
        let _ = writeln!(s, "- Config: defaults");
    }
    let _ = writeln!(s, "\n| setting | value |\n|---|---|");
    for (k, v) in crate::settings_rows(&input.settings) {
        let _ = writeln!(s, "| `{k}` | {v} |");
    }
    let _ = writeln!(s);
    let _ = writeln!(s, "## Summary\n");
    let _ = writeln!(
        s,
        "| log | SHA-256 | constraints | verdict | samples | duration (s) | violation fraction | separation (m) | violations | success | safe success |\n|---|---|---|---|---|---|---|---|---|---|---|"
    );
    for (r, f) in input.runs.iter().zip(&input.logs) {
        let m = &r.metrics;
        let _ = writeln!(
            s,
            "| `{}` | `{}…` | {} | **{:?}** | {} | {:.3} | {:.4} | {} | {} | {} | {} |",
            r.log,
            &f.sha256[..16.min(f.sha256.len())],
            r.models.constraints,
            r.verdict,
            m.samples,
            m.duration,
            m.violation_fraction,
            opt(m.min_separation, ""),
            r.violations.len(),
            m.success.map(|b| b.to_string()).unwrap_or("n/a".into()),
            m.safe_success
                .map(|b| b.to_string())
                .unwrap_or("n/a".into()),
        );
    }
    s.push_str(
        "\n### Evidence\n\n| log | people | audited span (s) | log complete |\n|---|---|---|---|\n",
    );
    for r in input.runs {
        let [log, people, span, complete] = crate::evidence_row(r);
        let _ = writeln!(s, "| `{log}` | {people} | {span} | {complete} |");
    }
    let d = definitions();
    let _ = writeln!(
        s,
        "\nSeparation: {}. Safe success: {}.",
        d["separation_m"].as_str().unwrap_or(""),
        d["safe_success"].as_str().unwrap_or("")
    );
    if input.runs.len() > 1 {
        let _ = writeln!(
            s,
            "\n## Aggregate (impact of safeguarding)\n\n| task | policy | filter | n (logs) | success | safe success | violation fraction (mean ± std) |\n|---|---|---|---|---|---|---|"
        );
        for row in aggregate::aggregate(input.runs) {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} | {} |",
                row.task,
                row.policy,
                row.filter,
                row.runs,
                aggregate::pct(row.success),
                aggregate::pct(row.safe_success),
                aggregate::pct(Some(row.safety_violation))
            );
        }
        s.push_str(&crate::fleet::markdown(&crate::fleet::of_input(input)));
    }
    for r in input.runs {
        let _ = writeln!(s, "\n## `{}` — {:?}\n", r.log, r.verdict);
        let _ = writeln!(
            s,
            "| model | name | parameters (all in report.json) | SHA-256 of the parameters |\n|---|---|---|---|"
        );
        for [model, name, params, hash] in crate::model_rows(r) {
            let _ = writeln!(s, "| {model} | `{name}` | {params} | `{hash}` |");
        }
        let _ = writeln!(s);
        if r.violations.is_empty() {
            let _ = writeln!(s, "No violations.");
        } else {
            let _ = writeln!(
                s,
                "| {} |\n|{}",
                crate::VIOLATION_COLUMNS.join(" | "),
                "---|".repeat(crate::VIOLATION_COLUMNS.len())
            );
            for v in &r.violations {
                let _ = writeln!(s, "| {} |", crate::violation_cells(v).join(" | "));
            }
            let _ = writeln!(
                s,
                "\nNominal separation: {}.",
                d["violation_separation_m"].as_str().unwrap_or("")
            );
        }
        if !r.inconclusive.is_empty() {
            let _ = writeln!(s, "\nInconclusive spans:\n");
            for i in &r.inconclusive {
                let _ = writeln!(
                    s,
                    "- {:.4}–{:.4} s: {} ({} spans)",
                    i.t_start, i.t_end, i.reason, i.spans
                );
            }
        }
    }
    let _ = writeln!(s, "\n## Assumptions\n");
    for a in assumptions() {
        let _ = writeln!(s, "- {a}");
    }
    s
}
