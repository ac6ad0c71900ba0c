//! `pacs demo` end to end: runs, prints JSON, PACS is safe in both scenarios, OFF violates SSM.

use std::process::Command;

#[test]
fn demo_runs_and_pacs_is_safe() {
    let out = Command::new(env!("CARGO_BIN_EXE_pacs"))
        .arg("demo")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let runs = v["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 4);
    for r in runs {
        if r["method"] == "pacs" {
            assert_eq!(r["safety_violation_fraction"].as_f64(), Some(0.0), "{r}");
            assert_eq!(r["success"], true, "{r}");
        }
    }
    let off_sorting = runs
        .iter()
        .find(|r| r["method"] == "off" && r["task"] == "sorting")
        .unwrap();
    assert!(off_sorting["safety_violation_fraction"].as_f64().unwrap() > 0.0);
}
