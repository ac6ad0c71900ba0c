//! `pacs demo` end to end: simulates, logs, audits and reports. PACS runs are safe against the
//! ground truth and their logs audit `pass`; the OFF sorting run violates SSM and audits `fail`.

mod common;

#[test]
fn demo_runs_audits_and_reports() {
    let out_dir = std::env::temp_dir().join(format!("pacs-demo-test-{}", std::process::id()));
    let out = common::pacs_ok([
        std::ffi::OsStr::new("demo"),
        "--out".as_ref(),
        out_dir.as_ref(),
    ]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let runs = v["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 4);
    for r in runs {
        if r["method"] == "pacs" {
            assert_eq!(r["safety_violation_fraction"].as_f64(), Some(0.0), "{r}");
            assert_eq!(r["success"], true, "{r}");
            assert_eq!(r["audit_verdict"], "pass", "{r}");
        } else {
            assert_eq!(r["audit_verdict"], "fail", "{r}");
        }
    }
    let off_sorting = runs
        .iter()
        .find(|r| r["method"] == "off" && r["task"] == "sorting")
        .unwrap();
    assert!(off_sorting["safety_violation_fraction"].as_f64().unwrap() > 0.0);
    for f in [
        "report.html",
        "report.json",
        "report.md",
        "sorting-pacs.jsonl",
        "handover-off.jsonl",
    ] {
        assert!(out_dir.join(f).is_file(), "{f} missing");
    }
    let html = std::fs::read_to_string(out_dir.join("report.html")).unwrap();
    assert!(html.contains("<svg"), "report has plots");
    // The sentences on stderr are read off the rows: one per run, never "hits the
    // person" above a row with 0.0 % violations.
    let err = String::from_utf8_lossy(&out.stderr);
    for r in runs {
        let (task, method) = (r["task"].as_str().unwrap(), r["method"].as_str().unwrap());
        let f = r["safety_violation_fraction"].as_f64().unwrap();
        let c = if task == "handover" { "PFL" } else { "SSM" };
        let want = if f > 0.0 {
            format!(
                "  {task}, {}: {:.1} % of its steps violate {c} against the true human motion.",
                method.to_uppercase(),
                100.0 * f
            )
        } else {
            format!(
                "  {task}, {}: no step violates {c} against the true human motion",
                method.to_uppercase()
            )
        };
        assert!(err.contains(&want), "{want} not in {err}");
    }
    assert!(!err.contains("hits the person"), "{err}");
    // The report's aggregate groups by the filter that ran: PACS and OFF apart.
    let rep: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("report.json")).unwrap())
            .unwrap();
    let filters: Vec<&str> = rep["aggregate"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a["filter"].as_str().unwrap())
        .collect();
    assert_eq!(filters, ["pacs", "off", "pacs", "off"]);
    assert!(out_dir.join("violations.csv").is_file());
    let _ = std::fs::remove_dir_all(&out_dir);
}
