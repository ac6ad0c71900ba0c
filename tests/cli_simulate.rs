//! `pacs simulate` end to end: rollouts, logs that `pacs audit` accepts, tables, plots; bad
//! arguments exit 3.

mod common;

use common::{pacs, pacs_ok};

/// `pacs simulate ARGS --out DIR`, which must succeed (stderr shown if not).
fn simulate(args: &[&str], dir: &std::path::Path) -> std::process::Output {
    let args = std::iter::once("simulate")
        .chain(args.iter().copied())
        .map(std::ffi::OsStr::new)
        .chain([std::ffi::OsStr::new("--out"), dir.as_os_str()]);
    pacs_ok(args)
}

#[test]
fn simulate_writes_tables_plots_and_auditable_logs() {
    let dir = std::env::temp_dir().join(format!("pacs-sim-test-{}", std::process::id()));
    let out = simulate(
        &[
            "--task",
            "crowded",
            "--method",
            "off,pacs",
            "--rollouts",
            "1",
            // A seed where OFF meets the person or a sphere (OFF is fast and passes other seeds
            // by chance).
            "--seed",
            "6",
        ],
        &dir,
    );
    // The disk the logs may take is stated first: 2 rollouts × 20 s × 0.75 MB/s = 30 MB.
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("take up to 30 MB") && err.contains("--no-logs"),
        "{err}"
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 2);
    let pacs_row = rows.iter().find(|r| r["method"] == "pacs").unwrap();
    assert_eq!(pacs_row["safety_violation"]["mean"].as_f64(), Some(0.0));
    assert_eq!(pacs_row["constraints"], "ssm");
    let md = std::fs::read_to_string(dir.join("summary.md")).unwrap();
    assert!(md.contains("| crowded | pacs | SSM | 1 |"), "{md}");
    for plot in ["crowded-paths.svg", "crowded-separation.svg"] {
        let svg = std::fs::read_to_string(dir.join(plot)).unwrap();
        assert!(
            svg.starts_with("<svg") && svg.contains("<polyline"),
            "{plot}"
        );
    }
    let paths = std::fs::read_to_string(dir.join("crowded-paths.svg")).unwrap();
    assert!(paths.contains("<line"), "tool path segments drawn");
    // The PACS log passes the offline audit (from the measurements alone), and the OFF log, in
    // which a sphere or the person meets the moving robot, fails.
    let logs = dir.join("logs");
    let pacs_log = logs.join("crowded-pacs-0006.jsonl");
    let off_log = logs.join("crowded-off-0006.jsonl");
    // The header names the task (not its constraint preset, `sorting` for every SSM task): the
    // fleet report groups runs by it.
    let first = std::fs::read_to_string(&pacs_log).unwrap();
    let header: serde_json::Value = serde_json::from_str(first.lines().next().unwrap()).unwrap();
    assert_eq!(header["meta"]["task"], "crowded");
    let a = pacs().arg("audit").arg(&pacs_log).output().unwrap();
    assert_eq!(
        a.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&a.stdout)
    );
    let a = pacs().arg("audit").arg(&off_log).output().unwrap();
    assert_eq!(
        a.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&a.stdout)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The shield's own logs of every task pass the offline audit (PFL included: the logs
/// carry the commanded accelerations, which the audit uses with the jerk limit), and OFF logs
/// that truly violate the constraints fail.
#[test]
fn pacs_logs_of_every_task_pass_the_audit_and_violating_off_logs_fail() {
    let dir = std::env::temp_dir().join(format!("pacs-sim-all-{}", std::process::id()));
    simulate(
        &[
            "--task",
            "all",
            "--method",
            "pacs,off",
            "--rollouts",
            "1",
            "--seed",
            "5",
        ],
        &dir,
    );
    let logs = dir.join("logs");
    for task in ["sorting", "handover", "feeding", "sphere", "crowded"] {
        let log = logs.join(format!("{task}-pacs-0005.jsonl"));
        let a = pacs().arg("audit").arg(&log).output().unwrap();
        assert_eq!(
            a.status.code(),
            Some(0),
            "{task}: {}",
            String::from_utf8_lossy(&a.stdout)
        );
    }
    // Feeding OFF brings the fork to the head at full speed (true violations in every seed).
    let a = pacs()
        .arg("audit")
        .arg(logs.join("feeding-off-0005.jsonl"))
        .output()
        .unwrap();
    assert_eq!(
        a.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&a.stdout)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn simulate_rejects_unknown_task_and_method() {
    for args in [
        ["--task", "juggling"],
        ["--method", "pacs-magic"],
        ["--rollouts", "0"],
        ["--time-limit", "0"],
        ["--time-limit", "NaN"],
        ["--time-limit", "4000"],
        // Named twice, a task's or method's rollouts would count twice.
        ["--task", "sorting,sorting"],
        ["--method", "pacs,off,pacs"],
    ] {
        let out = pacs().arg("simulate").args(args).output().unwrap();
        assert_eq!(out.status.code(), Some(3), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(args[0]), "{args:?}: {err}");
    }
}

/// `--policy kernel`: the policy learned from the demonstrations runs the task (handover without
/// people, where it succeeds in all of seeds 1–10), the summary names it and every log header
/// says which policy produced the chunks.
#[test]
fn simulate_runs_the_learned_policy_and_says_so() {
    let dir = std::env::temp_dir().join(format!("pacs-sim-kernel-{}", std::process::id()));
    let out = simulate(
        &[
            "--task",
            "handover",
            "--method",
            "off",
            "--rollouts",
            "1",
            "--no-human",
            "--policy",
            "kernel",
        ],
        &dir,
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["policy"], "kernel");
    assert_eq!(v["rows"][0]["success"].as_f64(), Some(1.0), "{v}");
    let md = std::fs::read_to_string(dir.join("summary.md")).unwrap();
    assert!(md.contains("--no-human --policy kernel`"), "{md}");
    let log = std::fs::read_to_string(dir.join("logs/handover-off-0001.jsonl")).unwrap();
    let header: serde_json::Value = serde_json::from_str(log.lines().next().unwrap()).unwrap();
    assert_eq!(header["meta"]["policy"], "kernel-regression", "{header}");
    let _ = std::fs::remove_dir_all(&dir);
    // An unknown policy is an input error (exit 3, as an unknown task or method), naming it.
    let out = pacs()
        .args(["simulate", "--policy", "oracle"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(3));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--policy") && err.contains("oracle"), "{err}");
}

/// `--time-limit`: every rollout ends there (Sorting takes seconds: at 0.3 s nothing succeeds
/// and each duration is the limit).
#[test]
fn simulate_honours_the_time_limit() {
    let dir = std::env::temp_dir().join(format!("pacs-sim-limit-{}", std::process::id()));
    let out = simulate(
        &[
            "--task",
            "sorting",
            "--method",
            "off,pacs",
            "--rollouts",
            "2",
            "--time-limit",
            "0.3",
            "--no-logs",
        ],
        &dir,
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 2);
    for row in rows {
        assert_eq!(row["success"], 0.0, "{row}");
    }
    let text = std::fs::read_to_string(dir.join("rollouts.json")).unwrap();
    let rollouts: serde_json::Value = serde_json::from_str(&text).unwrap();
    let rollouts = rollouts.as_array().unwrap();
    assert_eq!(rollouts.len(), 4);
    for r in rollouts {
        assert_eq!(r["episode"]["duration"], 0.3, "{r}");
        assert_eq!(r["episode"]["success"], false, "{r}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
