//! `pacs audit DIR --out`: a directory stands for its log files, sorted; report.json gains the
//! fleet section (per robot, scene and day), report.md and report.html the fleet table.

use pacs_log::{Header, LogWriter, ModelRef};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

const Q: [f64; 7] = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];

fn tmpdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("pacs-cli-fleet-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A 0.2 s log at 1 kHz of joint 1 turning at 0.3 rad/s, a person `x` m from the base
/// (`None`: never measured, inconclusive), with `meta`.
fn write_log(path: &Path, x: Option<f64>, meta: Value) {
    let mut h = Header::new(
        ModelRef::Name("fr3".into()),
        ModelRef::Name("default".into()),
        ModelRef::Name("ssm".into()),
    );
    h.meta = meta.as_object().cloned().unwrap();
    let mut w = LogWriter::new(Vec::new());
    w.write_header(&h).unwrap();
    for i in 0..=200 {
        let t = i as f64 * 1e-3;
        if let Some(x) = x
            && i % 10 == 0
        {
            w.write_human(t, t, &pacs_testkit::keypoints_in_a_row(x))
                .unwrap();
        }
        let mut q = Q;
        q[0] = 0.3 * t;
        w.write_robot(t, &q, Some(&[0.3, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]))
            .unwrap();
    }
    std::fs::write(path, w.finish().unwrap()).unwrap();
}

fn pacs(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_pacs"))
        .args(args)
        .output()
        .expect("run pacs")
}

#[test]
fn an_archive_directory_is_audited_in_path_order_with_a_fleet_report() {
    let d = tmpdir("archive");
    let a = d.join("archive");
    std::fs::create_dir_all(a.join("2026-11-27")).unwrap();
    let arm1 = serde_json::json!({"robot_id": "arm-1", "task": "sorting", "date": "2026-11-27"});
    write_log(
        &a.join("2026-11-27/arm1-pass.jsonl"),
        Some(2.5),
        arm1.clone(),
    );
    write_log(&a.join("2026-11-27/arm1-fail.jsonl"), Some(0.3), arm1);
    write_log(
        &a.join("arm2-fail.jsonl"),
        Some(0.3),
        serde_json::json!({"robot_id": "arm-2", "task": "packing", "start_time": "2026-11-28T23:30:00-05:00"}),
    );
    let inc = a.join("arm2-inconclusive.jsonl");
    write_log(
        &inc,
        None,
        serde_json::json!({"robot_id": "arm-2", "task": "packing"}),
    );
    // No date in its header: the day is the file's modification time (2026-11-28T12:00:00Z).
    std::fs::File::options()
        .write(true)
        .open(&inc)
        .unwrap()
        .set_modified(std::time::UNIX_EPOCH + std::time::Duration::from_secs(1_795_867_200))
        .unwrap();
    std::fs::write(a.join("notes.txt"), "not a log").unwrap();
    std::fs::write(a.join("header.json"), "{}").unwrap();
    let out = d.join("report");
    let archive = a.display().to_string();
    let o = pacs(&[
        "audit",
        &archive,
        "--json",
        "--out",
        &out.display().to_string(),
    ]);
    assert_eq!(
        o.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let stdout: Value = serde_json::from_slice(&o.stdout).unwrap();
    let logs: Vec<&str> = stdout["runs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["log"].as_str().unwrap())
        .collect();
    let want: Vec<String> = [
        "2026-11-27/arm1-fail.jsonl",
        "2026-11-27/arm1-pass.jsonl",
        "arm2-fail.jsonl",
        "arm2-inconclusive.jsonl",
    ]
    .iter()
    .map(|f| a.join(f).display().to_string())
    .collect();
    assert_eq!(logs, want);
    let report: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let fleet = &report["fleet"];
    let groups: Vec<(String, String, String, u64, u64, u64, u64)> = fleet["groups"]
        .as_array()
        .unwrap()
        .iter()
        .map(|g| {
            (
                g["robot"].as_str().unwrap().into(),
                g["scene"].as_str().unwrap().into(),
                g["day"].as_str().unwrap().into(),
                g["runs"].as_u64().unwrap(),
                g["pass"].as_u64().unwrap(),
                g["fail"].as_u64().unwrap(),
                g["inconclusive"].as_u64().unwrap(),
            )
        })
        .collect();
    let g = |r: &str, s: &str, d: &str, n, p, f, i| (r.into(), s.into(), d.into(), n, p, f, i);
    assert_eq!(
        groups,
        [
            g("arm-1", "sorting", "2026-11-27", 2, 1, 1, 0),
            g("arm-2", "packing", "2026-11-28", 1, 0, 0, 1),
            g("arm-2", "packing", "2026-11-29", 1, 0, 1, 0),
        ]
    );
    let sources: Vec<&str> = fleet["runs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["day_source"].as_str().unwrap())
        .collect();
    assert_eq!(
        sources,
        ["meta.date", "meta.date", "meta.start_time", "file_mtime"]
    );
    // Violation time: the union of the failing log's violation intervals, from its own rows.
    let runs = report["runs"].as_array().unwrap();
    let mut iv: Vec<(f64, f64)> = runs[0]["violations"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| (v["t_start"].as_f64().unwrap(), v["t_end"].as_f64().unwrap()))
        .collect();
    iv.sort_by(|x, y| x.0.total_cmp(&y.0));
    let mut union = 0.0;
    let mut cur = iv[0];
    for &(s, e) in &iv[1..] {
        if s <= cur.1 {
            cur.1 = cur.1.max(e);
        } else {
            union += cur.1 - cur.0;
            cur = (s, e);
        }
    }
    union += cur.1 - cur.0;
    assert!(union > 0.0);
    assert_eq!(fleet["runs"][0]["violation_time_s"].as_f64(), Some(union));
    assert_eq!(
        fleet["groups"][0]["worst"][0]["log"].as_str(),
        Some(want[0].as_str())
    );
    assert_eq!(fleet["groups"][0]["worst"].as_array().unwrap().len(), 1);
    assert_eq!(fleet["total"]["runs"].as_u64(), Some(4));
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(md.contains("## Fleet (per robot, scene and day)"), "{md}");
    assert!(
        md.contains("| arm-2 | packing | 2026-11-28 | 1 | 0 | 0 | 1 |"),
        "{md}"
    );
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(html.contains("<h2>Fleet (per robot, scene and day)</h2>"));
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn an_empty_or_missing_directory_is_invalid_input_naming_it() {
    let d = tmpdir("empty");
    std::fs::create_dir_all(d.join("empty/sub")).unwrap();
    std::fs::write(d.join("empty/readme.txt"), "no logs").unwrap();
    let empty = d.join("empty").display().to_string();
    let o = pacs(&["audit", &empty]);
    assert_eq!(o.status.code(), Some(3));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains(&empty) && err.contains("without log files"),
        "{err}"
    );
    let missing = d.join("missing").display().to_string();
    let o = pacs(&["audit", &missing]);
    assert_eq!(o.status.code(), Some(3));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains(&missing), "{err}");
    let _ = std::fs::remove_dir_all(&d);
}

/// An archive mixing a ROS recording without a pacs header (the shipped MCAP, as a Humble bag
/// would be) and JSON Lines logs: `--header` is for the recording, the JSON Lines logs keep their
/// own; one JSON Lines log alone with `--header` stays an input error. A log given twice, and an
/// entry with a log's name that cannot be read (a dangling link), are input errors naming them.
#[test]
fn header_for_an_archives_recordings_and_bad_entries_named() {
    let d = tmpdir("mixed");
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let logs = root.join("examples/logs");
    std::fs::copy(logs.join("clean_sorting.mcap"), d.join("a.mcap")).unwrap();
    std::fs::copy(logs.join("close_sorting.jsonl"), d.join("b.jsonl")).unwrap();
    let header = logs.join("clean_sorting_header.json").display().to_string();
    let dir = d.display().to_string();
    let o = pacs(&["audit", &dir, "--header", &header, "--json"]);
    let v: Value = serde_json::from_slice(&o.stdout).unwrap_or(Value::Null);
    assert_eq!(
        o.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let verdicts: Vec<_> = v["runs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["verdict"].as_str().unwrap().to_string())
        .collect();
    assert_eq!(verdicts, ["pass", "fail"]);
    let one = d.join("b.jsonl").display().to_string();
    let o = pacs(&["audit", &one, "--header", &header]);
    assert_eq!(o.status.code(), Some(3));
    // Given twice: refused, both paths named.
    let o = pacs(&["audit", &dir, &one, "--header", &header]);
    assert_eq!(o.status.code(), Some(3));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("given twice") && err.contains(&one), "{err}");
    // A dangling `*.jsonl` link is named, not skipped.
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink(d.join("gone.jsonl"), d.join("c.jsonl")).unwrap();
        let o = pacs(&["audit", &dir, "--header", &header]);
        assert_eq!(o.status.code(), Some(3));
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains("c.jsonl"), "{err}");
    }
    let _ = std::fs::remove_dir_all(&d);
}
