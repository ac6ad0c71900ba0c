//! End-to-end tests of `pacs audit`: exit codes, `--json` output, reports.

use pacs_log::{Header, LogWriter, ModelRef};
use serde_json::Value;
use std::path::Path;
use std::process::{Command, Output};

const Q: [f64; 7] = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];

fn tmpdir(name: &str) -> pacs_testkit::ScratchDir {
    pacs_testkit::ScratchDir::new("cli-audit", name)
}

/// A 0.2 s log at 1 kHz, joint 1 moving at 0.3 rad/s, human at `x` (m) from the base.
/// `human` false: no human record (inconclusive).
fn write_log(path: &Path, x: f64, human: bool, meta: &[(&str, &str)], outcome: &str) {
    let mut h = Header::new(
        ModelRef::Name("fr3".into()),
        ModelRef::Name("default".into()),
        ModelRef::Name("ssm".into()),
    );
    for (k, v) in meta {
        h.meta.insert(k.to_string(), Value::String(v.to_string()));
    }
    let mut w = LogWriter::new(Vec::new());
    w.write_header(&h).unwrap();
    for i in 0..=200 {
        let t = i as f64 * 1e-3;
        if human && i % 10 == 0 {
            w.write_human(t, t, &pacs_testkit::keypoints_in_a_row(x))
                .unwrap();
        }
        let mut q = Q;
        q[0] = 0.3 * t;
        w.write_robot(t, &q, Some(&[0.3, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]))
            .unwrap();
    }
    w.write_event(0.2, outcome).unwrap();
    std::fs::write(path, w.finish().unwrap()).unwrap();
}

fn pacs(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pacs"))
        .args(args)
        .output()
        .expect("run pacs")
}

fn s(p: &Path) -> String {
    p.display().to_string()
}

struct Logs {
    dir: pacs_testkit::ScratchDir,
    pass: String,
    fail: String,
    inconclusive: String,
    bad: String,
}

fn logs(name: &str) -> Logs {
    let dir = tmpdir(name);
    let pass = dir.join("pass.jsonl");
    let fail = dir.join("fail.jsonl");
    let inc = dir.join("inconclusive.jsonl");
    let bad = dir.join("bad.jsonl");
    write_log(
        &pass,
        2.5,
        true,
        &[("task", "sorting"), ("policy", "act"), ("filter", "pacs")],
        "success",
    );
    write_log(
        &fail,
        0.3,
        true,
        &[("task", "sorting"), ("policy", "act"), ("filter", "none")],
        "success",
    );
    write_log(&inc, 2.5, false, &[], "failure");
    let mut text = std::fs::read_to_string(&pass).unwrap();
    text.push_str("{\"type\":\"robot\",\"t\":0.1,\"q\":[0,0,0,0,0,0,0]}\n");
    std::fs::write(&bad, text).unwrap();
    Logs {
        pass: s(&pass),
        fail: s(&fail),
        inconclusive: s(&inc),
        bad: s(&bad),
        dir,
    }
}

fn json(o: &Output) -> Value {
    serde_json::from_slice(&o.stdout).unwrap_or_else(|e| {
        panic!(
            "stdout is not JSON ({e}): {}",
            String::from_utf8_lossy(&o.stdout)
        )
    })
}

#[test]
fn exit_codes_and_json_output() {
    let l = logs("codes");
    let o = pacs(&["audit", "--json", &l.pass]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let v = json(&o);
    assert_eq!(v["runs"][0]["verdict"], "pass");
    assert_eq!(v["runs"][0]["log"], l.pass.as_str());
    assert_eq!(v["runs"][0]["metrics"]["samples"], 201);
    assert_eq!(v["runs"][0]["metrics"]["success"], true);
    assert_eq!(v["runs"][0]["metrics"]["safe_success"], true);

    let o = pacs(&["audit", "--json", &l.fail]);
    assert_eq!(o.status.code(), Some(1));
    let v = json(&o);
    let run = &v["runs"][0];
    assert_eq!(run["verdict"], "fail");
    assert_eq!(run["metrics"]["safe_success"], false);
    assert!(run["metrics"]["violation_fraction"].as_f64().unwrap() > 0.0);
    // The episodes beside the intervals, each covering some of them.
    let episodes = run["episodes"].as_array().unwrap();
    assert!(!episodes.is_empty());
    let merged: u64 = episodes
        .iter()
        .map(|e| e["intervals"].as_u64().unwrap())
        .sum();
    assert_eq!(merged as usize, run["violations"].as_array().unwrap().len());
    let viol = &run["violations"][0];
    for k in [
        "t_start",
        "t_end",
        "constraint",
        "body_part",
        "link",
        "min_separation",
        "energy",
        "threshold",
        "certain",
    ] {
        assert!(viol.get(k).is_some(), "violation field {k} missing: {viol}");
    }
    assert_eq!(viol["constraint"], "ssm");

    let o = pacs(&["audit", "--json", &l.inconclusive]);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(json(&o)["runs"][0]["verdict"], "inconclusive");

    // Combinations: any fail → 1; inconclusive and no fail → 2; invalid input → 3.
    assert_eq!(
        pacs(&["audit", &l.pass, &l.fail, &l.inconclusive])
            .status
            .code(),
        Some(1)
    );
    assert_eq!(
        pacs(&["audit", &l.pass, &l.inconclusive]).status.code(),
        Some(2)
    );
    let o = pacs(&["audit", &l.pass, &l.bad]);
    assert_eq!(o.status.code(), Some(3));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains(&l.bad) && err.contains("line ") && err.contains("time goes backwards"),
        "{err}"
    );
}

#[test]
fn invalid_files_and_config_exit_3() {
    let l = logs("invalid");
    let missing = l.dir.join("missing.jsonl");
    let o = pacs(&["audit", &s(&missing)]);
    assert_eq!(o.status.code(), Some(3));
    assert!(String::from_utf8_lossy(&o.stderr).contains("missing.jsonl"));
    let cfg = l.dir.join("bad.toml");
    std::fs::write(&cfg, "max_gap = -1.0\n").unwrap();
    let o = pacs(&["audit", "--config", &s(&cfg), &l.pass]);
    assert_eq!(o.status.code(), Some(3));
    assert!(String::from_utf8_lossy(&o.stderr).contains("max_gap"));
    std::fs::write(&cfg, "no_such_setting = 1\n").unwrap();
    assert_eq!(
        pacs(&["audit", "--config", &s(&cfg), &l.pass])
            .status
            .code(),
        Some(3)
    );
    // A config that widens the allowed gap is applied.
    std::fs::write(&cfg, "max_gap = 0.5\nrest_speed = 0.01\n").unwrap();
    assert_eq!(
        pacs(&["audit", "--config", &s(&cfg), &l.pass])
            .status
            .code(),
        Some(0)
    );
}

#[test]
fn reports_are_written_with_plots_hashes_and_aggregate() {
    let l = logs("report");
    let out = l.dir.join("out");
    let cfg = l.dir.join("task.toml");
    std::fs::write(&cfg, "max_gap = 0.05\n").unwrap();
    let o = pacs(&[
        "audit",
        "--config",
        &s(&cfg),
        "--out",
        &s(&out),
        &l.pass,
        &l.fail,
    ]);
    assert_eq!(
        o.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    // It says where the report went, and why the exit code is 1.
    let err = String::from_utf8_lossy(&o.stderr);
    let d = out.display();
    assert!(
        err.contains(&format!(
            "pacs: report written: {d}/report.html, {d}/report.pdf, {d}/report.md, {d}/report.json, {d}/violations.csv (overall verdict FAIL: exit 1)"
        )),
        "{err}"
    );
    let csv = std::fs::read_to_string(out.join("violations.csv")).unwrap();
    assert!(
        csv.starts_with("log,t_start_s,t_end_s,constraint,"),
        "{csv}"
    );
    assert!(
        csv.lines().count() > 1,
        "the failing log's intervals: {csv}"
    );
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(html.starts_with("<!DOCTYPE html>"));
    // SSM logs: the separation plot; no energy plot (no PFL threshold applies).
    assert_eq!(html.matches("<svg").count(), 2, "one plot per SSM log");
    assert!(html.contains("class=\"separation\""));
    assert!(html.contains("no energy limit applied"));
    assert!(
        html.contains("class=\"violation\""),
        "violation spans shaded"
    );
    assert!(!html.contains("<script"), "self-contained, no scripts");
    assert!(html.contains("n (logs)"));
    let pdf = std::fs::read(out.join("report.pdf")).unwrap();
    assert!(pdf.starts_with(b"%PDF-1.4") && pdf.ends_with(b"%%EOF\n"));
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        md.contains("| sorting | act | pacs | 1 |") && md.contains("| sorting | act | none | 1 |"),
        "{md}"
    );
    let rep: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(rep["verdict"], "fail");
    assert!(rep["tool"]["git_revision"].is_string());
    assert!(rep["checks"].as_array().unwrap().len() >= 5);
    assert_eq!(rep["runs"].as_array().unwrap().len(), 2);
    assert_eq!(rep["settings"]["max_gap"], 0.05);
    let logs_in = rep["inputs"]["logs"].as_array().unwrap();
    // Independent SHA-256 (coreutils), when available.
    if let Ok(o) = Command::new("sha256sum").arg(&l.pass).arg(&cfg).output()
        && o.status.success()
    {
        let text = String::from_utf8_lossy(&o.stdout).to_string();
        let mut it = text
            .lines()
            .map(|line| line.split_whitespace().next().unwrap().to_string());
        assert_eq!(logs_in[0]["sha256"], it.next().unwrap());
        assert_eq!(rep["inputs"]["config"]["sha256"], it.next().unwrap());
    }
}

/// Paths of `null` anywhere in `v` (report.json promises none).
fn nulls(v: &Value, at: &str, out: &mut Vec<String>) {
    match v {
        Value::Null => out.push(at.to_string()),
        Value::Array(a) => a
            .iter()
            .enumerate()
            .for_each(|(i, x)| nulls(x, &format!("{at}[{i}]"), out)),
        Value::Object(m) => m
            .iter()
            .for_each(|(k, x)| nulls(x, &format!("{at}.{k}"), out)),
        _ => {}
    }
}

/// `dir/report.json`, asserted to hold no `null` anywhere.
fn report_json_without_null(dir: &Path) -> Value {
    let rep: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap();
    let mut found = Vec::new();
    nulls(&rep, "report", &mut found);
    assert!(found.is_empty(), "null at {found:?}");
    rep
}

/// An object whose inline model has no speed bound: report.json's echo of its spec leaves the
/// bound out (no `null`).
#[test]
fn an_object_without_a_speed_bound_leaves_no_null_in_the_report() {
    let dir = tmpdir("report-object-no-speed");
    let log = dir.join("ball.jsonl");
    let mut text = String::from(
        r#"{"type":"header","format":"pacs-log","version":2,"robot":"fr3","constraints":"sorting","humans":[{"id":"op","human":"default"}],"end_event":true,"objects":[{"id":"b1","object":{"shape":{"sphere":{"radius":0.04}},"max_acc":3.0,"name":"ns"},"contact":"no_contact"}]}"#,
    );
    text.push('\n');
    let person = "[[1.8,0.2,1.4],[1.8,0.2,1.1],[1.8,0.2,0.9],[1.8,-0.2,1.4],[1.8,-0.2,1.1],[1.8,-0.2,0.9],[1.8,0,1.45],[1.8,0,0.9],[1.8,0,1.65]]";
    for k in 0..=100 {
        let t = f64::from(k) * 0.001;
        text += &format!(
            "{{\"type\":\"human\",\"t\":{t},\"id\":\"op\",\"positions\":{person}}}\n{{\"type\":\"object\",\"t\":{t},\"id\":\"b1\",\"position\":[1.5,1.5,0.5],\"velocity\":[0,0,0]}}\n{{\"type\":\"robot\",\"t\":{t},\"q\":[0,-0.785,0,-2.356,0,1.571,0.785],\"dq\":[0,0,0,0,0,0,0]}}\n"
        );
    }
    text += "{\"type\":\"event\",\"t\":0.1,\"name\":\"end\"}\n";
    std::fs::write(&log, text).unwrap();
    let out = dir.join("report");
    let o = pacs(&["audit", &s(&log), "--out", &s(&out)]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    let rep = report_json_without_null(&out);
    let spec = &rep["runs"][0]["model_parameters"]["objects"]["spec"][0];
    assert!(spec.get("max_speed").is_none(), "{spec}");
    assert_eq!(spec["max_acc"], 3.0, "{spec}");
}

#[test]
fn report_json_without_a_config_has_no_null() {
    let l = logs("report-no-null");
    let out = l.dir.join("report");
    let o = pacs(&[
        "audit",
        &l.pass,
        &l.fail,
        &l.inconclusive,
        "--out",
        &s(&out),
    ]);
    assert_eq!(
        o.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let rep = report_json_without_null(&out);
    assert!(rep["inputs"].get("config").is_none(), "no config given");
    assert!(rep["settings"].get("robot").is_none());
    // The tables still say where the models come from.
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(md.contains("| `robot` | from the log header |"), "{md}");
}

#[test]
fn csv_logs_are_audited_by_extension() {
    let dir = tmpdir("csv");
    let header = r#"#{"type":"header","format":"pacs-log","version":1,"robot":"fr3","human":"default","constraints":"ssm"}"#;
    let human = "human,0,0,2.5,0,1,2.5,0,1,2.5,0,1,2.5,0,1,2.5,0,1,2.5,0,1,2.5,0,1,2.5,0,1,2.5,0,1";
    let good = dir.join("good.csv");
    std::fs::write(
        &good,
        format!("{header}\n{human}\nrobot,0,7,0,-0.785,0,-2.356,0,1.571,0.785\nrobot,0.001,7,0,-0.785,0,-2.356,0,1.571,0.785\n"),
    )
    .unwrap();
    let o = pacs(&["audit", "--json", &s(&good)]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert_eq!(json(&o)["runs"][0]["metrics"]["samples"], 2);
    let bad = dir.join("bad.csv");
    std::fs::write(
        &bad,
        format!("{header}\n{human}\nrobot,0,7,NaN,-0.785,0,-2.356,0,1.571,0.785\n"),
    )
    .unwrap();
    let o = pacs(&["audit", &s(&bad)]);
    assert_eq!(o.status.code(), Some(3));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("bad.csv: line 3: q[0]"), "{err}");
}

/// A PFL task with a robot whose moving link has capsules but no mass, or a robot with
/// a massless moving body, is refused (exit 3) naming the link; the same robot is accepted for an
/// SSM-only task (no energy involved).
#[test]
fn massless_moving_link_is_refused_for_pfl() {
    let mut spec = pacs_models::RobotModel::builtin("fr3")
        .unwrap()
        .spec()
        .clone();
    let l4 = spec
        .links
        .iter_mut()
        .find(|l| l.name == "fr3_link4")
        .unwrap();
    l4.inertial = None;
    let d = tmpdir("massless");
    for (constraints, code) in [("handover", 3), ("ssm", 0)] {
        let h = Header::new(
            ModelRef::Spec(Box::new(spec.clone())),
            ModelRef::Name("default".into()),
            ModelRef::Name(constraints.into()),
        );
        let mut w = LogWriter::new(Vec::new());
        w.write_header(&h).unwrap();
        w.write_human(0.0, 0.0, &pacs_testkit::keypoints_in_a_row(2.5))
            .unwrap();
        w.write_robot(0.0, &Q, None).unwrap();
        w.write_robot(0.001, &Q, None).unwrap();
        let path = d.join(format!("{constraints}.jsonl"));
        std::fs::write(&path, w.finish().unwrap()).unwrap();
        let o = pacs(&["audit", &s(&path)]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(code), "{constraints}: {err}");
        if code == 3 {
            assert!(
                err.contains("`fr3_link4`") && err.contains("without mass"),
                "{err}"
            );
            assert!(err.contains("line 1"), "names the header line: {err}");
        }
    }
}

/// A header robot whose moving link has mass but no capsules could never be found touching
/// anyone (it would audit PASS): refused with exit 3, naming the link, under SSM too.
#[test]
fn uncovered_moving_link_in_the_header_is_refused() {
    let mut spec = pacs_models::RobotModel::builtin("fr3")
        .unwrap()
        .spec()
        .clone();
    for l in spec.links.iter_mut().filter(|l| l.name == "fr3_hand") {
        l.capsules.clear();
    }
    let d = tmpdir("uncovered");
    let h = Header::new(
        ModelRef::Spec(Box::new(spec)),
        ModelRef::Name("default".into()),
        ModelRef::Name("ssm".into()),
    );
    let mut w = LogWriter::new(Vec::new());
    w.write_header(&h).unwrap();
    w.write_human(0.0, 0.0, &pacs_testkit::keypoints_in_a_row(2.5))
        .unwrap();
    w.write_robot(0.0, &Q, None).unwrap();
    w.write_robot(0.001, &Q, None).unwrap();
    let path = d.join("uncovered.jsonl");
    std::fs::write(&path, w.finish().unwrap()).unwrap();
    let o = pacs(&["audit", &s(&path)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{err}");
    assert!(
        err.contains("moving links with mass and no capsules: `fr3_hand` (0.6544 kg)"),
        "{err}"
    );
    assert!(err.contains("line 1"), "names the header line: {err}");
}

/// A header robot with finite but astronomical offsets would overflow the checker (a panic in
/// debug builds; in release an inconclusive run with `"min_separation": null` and the contact
/// at the base unreported). The model is refused: exit 3 naming the header line and the field.
#[test]
fn astronomical_robot_in_the_header_is_refused() {
    let mut spec = pacs_models::RobotModel::builtin("fr3")
        .unwrap()
        .spec()
        .clone();
    spec.joints[1].origin.xyz = [1.7e308, 0.0, 0.0];
    spec.joints[2].origin.xyz = [1.7e308, 0.0, 0.0];
    let d = tmpdir("astronomical");
    let h = Header::new(
        ModelRef::Spec(Box::new(spec)),
        ModelRef::Name("default".into()),
        ModelRef::Name("ssm".into()),
    );
    let mut w = LogWriter::new(Vec::new());
    w.write_header(&h).unwrap();
    // The human at the base: a certain SSM contact while joint 1 turns.
    w.write_human(0.0, 0.0, &[[0.0, 0.0, 0.2]; 9]).unwrap();
    let mut q = Q;
    for k in 0..3 {
        q[0] = 0.5e-3 * k as f64;
        let dq = [0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        w.write_robot(1e-3 * k as f64, &q, Some(&dq)).unwrap();
    }
    let path = d.join("astronomical.jsonl");
    std::fs::write(&path, w.finish().unwrap()).unwrap();
    let o = pacs(&["audit", "--json", &s(&path)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{err}");
    assert!(
        err.contains(
            "astronomical.jsonl: line 1: header.robot: invalid value for `joints[1].origin.xyz`"
        ) && err.contains("must be at most 1e6 m"),
        "{err}"
    );
    assert!(o.stdout.is_empty());
}

/// `1e400` or `NaN` in a log names the record's field (and the file line), not only
/// a JSON column.
#[test]
fn non_finite_numbers_in_a_log_name_the_field() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/logs/clean_sorting.jsonl");
    let text = std::fs::read_to_string(src).unwrap();
    let d = tmpdir("nonfinite");
    for (name, from, to, want) in [
        (
            "huge",
            "\"q\": [0.0, -0.785, 0, -2.356,",
            "\"q\": [0.0, -0.785, 1e400, -2.356,",
            "line 4: invalid JSON record: q[2]: number out of range at line 1 column 52 (numbers must be finite: |x| ≤ 1.8e308)",
        ),
        (
            "nan",
            "\"dq\": [0.3, 0,",
            "\"dq\": [NaN, 0,",
            "line 4: invalid JSON record: dq[0]: expected value at line 1 column 84 (NaN and Infinity are not JSON: numbers must be finite)",
        ),
    ] {
        assert!(text.contains(from), "{name}");
        let path = d.join(format!("{name}.jsonl"));
        std::fs::write(&path, text.replacen(from, to, 1)).unwrap();
        let o = pacs(&["audit", &s(&path)]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(3), "{name}: {err}");
        assert!(err.contains(want), "{name}: {err}");
    }
}
