//! `report.html`: one self-contained file (inline CSS and SVG, no scripts), readable when printed.

use crate::{
    GIT_REVISION, ReportInput, TOOL_VERSION, aggregate, assumptions, check_backing, overall, svg,
};
use pacs_audit::Verdict;
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

fn opt(v: Option<f64>, unit: &str) -> String {
    v.map(|x| format!("{x:.4} {unit}"))
        .unwrap_or_else(|| "n/a".into())
}

/// The HTML report.
pub fn report(input: &ReportInput) -> String {
    let mut s = String::new();
    s.push_str(r#"<!DOCTYPE html><html lang="en"><head><meta charset="utf-8"><title>pacs audit report</title><style>
body{font-family:sans-serif;max-width:60em;margin:1em auto;color:#111}
table{border-collapse:collapse;margin:.5em 0;font-size:90%}th,td{border:1px solid #999;padding:2px 6px;text-align:left}
th{background:#eee}.v{font-weight:bold;padding:0 4px}.pass{color:#1b5e20}.fail{color:#b71c1c}.inconclusive{color:#e65100}
code{font-size:90%}section{page-break-inside:avoid}svg{max-width:100%}
@media print{body{max-width:none}a{color:inherit}}
</style></head><body>"#);
    let _ = write!(
        s,
        "<h1>pacs audit certification report</h1><p>Tool: pacs {} (git <code>{}</code>). Overall verdict: {}</p>",
        TOOL_VERSION,
        esc(GIT_REVISION),
        verdict_cell(overall(input.runs))
    );
    let _ = write!(
        s,
        "<p>Config: {}. Settings: <code>{}</code></p>",
        input
            .config
            .as_ref()
            .map(|c| format!(
                "<code>{}</code> (SHA-256 <code>{}</code>)",
                esc(&c.path),
                c.sha256
            ))
            .unwrap_or_else(|| "defaults".into()),
        esc(&serde_json::to_string(&input.settings).unwrap_or_default())
    );
    s.push_str("<h2>Summary</h2><table><tr><th>log</th><th>SHA-256</th><th>task</th><th>verdict</th><th>samples</th><th>duration (s)</th><th>violation fraction</th><th>min separation</th><th>violations</th><th>success</th><th>safe success</th></tr>");
    for (r, f) in input.runs.iter().zip(&input.logs) {
        let m = &r.metrics;
        let _ = write!(
            s,
            "<tr><td><code>{}</code></td><td><code>{}</code></td><td>{}</td><td>{}</td><td>{}</td><td>{:.3}</td><td>{:.4}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            esc(&r.log),
            f.sha256,
            esc(&r.models.constraints),
            verdict_cell(r.verdict),
            m.samples,
            m.duration,
            m.violation_fraction,
            opt(m.min_separation, "m"),
            r.violations.len(),
            m.success.map(|b| b.to_string()).unwrap_or("n/a".into()),
            m.safe_success
                .map(|b| b.to_string())
                .unwrap_or("n/a".into()),
        );
    }
    s.push_str("</table>");
    if input.runs.len() > 1 {
        s.push_str("<h2>Aggregate (impact of safeguarding)</h2><table><tr><th>task</th><th>policy</th><th>filter</th><th>logs</th><th>Success</th><th>Safe Success</th><th>Safety Viol.</th></tr>");
        for row in aggregate::aggregate(input.runs) {
            let _ = write!(
                s,
                "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
                esc(&row.task),
                esc(&row.policy),
                esc(&row.filter),
                row.runs,
                aggregate::pct(row.success),
                aggregate::pct(row.safe_success),
                aggregate::pct(Some(row.safety_violation))
            );
        }
        s.push_str("</table>");
    }
    for r in input.runs {
        let _ = write!(
            s,
            "<section><h2><code>{}</code> {}</h2><p>Robot <code>{}</code>, human <code>{}</code>, constraints <code>{}</code>.</p>",
            esc(&r.log),
            verdict_cell(r.verdict),
            esc(&r.models.robot),
            esc(&r.models.human),
            esc(&r.models.constraints)
        );
        s.push_str(&svg::separation_plot(&r.series));
        s.push_str(&svg::energy_plot(&r.series));
        if r.violations.is_empty() {
            s.push_str("<p>No violations.</p>");
        } else {
            s.push_str("<table><tr><th>t_start (s)</th><th>t_end (s)</th><th>constraint</th><th>body part</th><th>link</th><th>min separation (m)</th><th>energy (J)</th><th>threshold (J)</th><th>constrained</th><th>certain</th></tr>");
            for v in &r.violations {
                let _ = write!(
                    s,
                    "<tr><td>{:.4}</td><td>{:.4}</td><td>{:?}</td><td>{}</td><td>{}</td><td>{:.4}</td><td>{:.4}</td><td>{:.4}</td><td>{}</td><td>{}</td></tr>",
                    v.t_start,
                    v.t_end,
                    v.constraint,
                    esc(&v.body_part),
                    esc(&v.link),
                    v.min_separation,
                    v.energy,
                    v.threshold,
                    v.constrained,
                    v.certain
                );
            }
            s.push_str("</table>");
        }
        if !r.inconclusive.is_empty() {
            s.push_str("<p>Inconclusive spans:</p><ul>");
            for i in &r.inconclusive {
                let _ = write!(
                    s,
                    "<li>{:.4}–{:.4} s: {} ({} spans)</li>",
                    i.t_start,
                    i.t_end,
                    esc(i.reason.as_str()),
                    i.spans
                );
            }
            s.push_str("</ul>");
        }
        s.push_str("</section>");
    }
    s.push_str("<h2>Assumptions</h2><ul>");
    for a in assumptions() {
        let _ = write!(s, "<li>{}</li>", esc(a));
    }
    s.push_str("</ul><h2>Checks and the tests backing them</h2><table><tr><th>check</th><th>backed by</th></tr>");
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
    s.push_str("</table></body></html>\n");
    s
}
