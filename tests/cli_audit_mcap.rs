//! End-to-end tests of `pacs audit` on MCAP logs (ROS 2 recordings): detection, exit codes,
//! `--header`, topic flags, and the same verdict and violations as the JSON Lines form.

use pacs_log::mcap::{McapConfig, McapLogWriter};
use pacs_log::{Header, LogWriter, ModelRef};
use serde_json::Value;
use std::io::Cursor;
use std::path::Path;
use std::process::{Command, Output};

const Q: [f64; 7] = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];
const JOINTS: [&str; 7] = [
    "fr3_joint1",
    "fr3_joint2",
    "fr3_joint3",
    "fr3_joint4",
    "fr3_joint5",
    "fr3_joint6",
    "fr3_joint7",
];

fn tmpdir(name: &str) -> pacs_testkit::ScratchDir {
    pacs_testkit::ScratchDir::new("cli-mcap", name)
}

fn header() -> Header {
    Header::new(
        ModelRef::Name("fr3".into()),
        ModelRef::Name("default".into()),
        ModelRef::Name("ssm".into()),
    )
}

/// A 0.2 s run at 1 kHz (joint 1 at 0.3 rad/s), human at `x` m, written as JSON Lines to
/// `jsonl` and as MCAP (robot topic `robot_topic`) to `mcap`; `with_header`: the `pacs` metadata
/// record is written (the MCAP writer always writes it; without, it is stripped by writing
/// through a header-less copy).
fn write_run(jsonl: &Path, mcap: &Path, x: f64, robot_topic: &str) {
    let mut j = LogWriter::new(Vec::new());
    j.write_header(&header()).unwrap();
    let cfg = McapConfig {
        robot_topic: robot_topic.into(),
        ..McapConfig::default()
    };
    let mut m = McapLogWriter::new(
        Cursor::new(Vec::new()),
        mcap::WriteOptions::new(),
        &header(),
        &cfg,
        &JOINTS,
    )
    .unwrap();
    for i in 0..=200i128 {
        let ns = i * 1_000_000;
        let t = ns as f64 / 1e9;
        if i % 10 == 0 {
            j.write_human(t, t, &pacs_testkit::keypoints_in_a_row(x))
                .unwrap();
            m.write_human(ns, ns, &pacs_testkit::keypoints_in_a_row(x))
                .unwrap();
        }
        let mut q = Q;
        q[0] = 0.3 * t;
        let dq = [0.3, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        j.write_robot(t, &q, Some(&dq)).unwrap();
        m.write_robot(ns, ns, &q, Some(&dq)).unwrap();
    }
    j.write_event(0.2, "success").unwrap();
    m.write_event(200_000_000, "success").unwrap();
    std::fs::write(jsonl, j.finish().unwrap()).unwrap();
    std::fs::write(mcap, m.finish().unwrap().into_inner()).unwrap();
}

/// A copy of an MCAP file without its `pacs` metadata record.
fn strip_header(src: &Path, dst: &Path) {
    let bytes = std::fs::read(src).unwrap();
    let mut out = mcap::Writer::new(Cursor::new(Vec::new())).unwrap();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        out.write(&m.unwrap()).unwrap();
    }
    out.finish().unwrap();
    std::fs::write(dst, out.into_inner().into_inner()).unwrap();
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

fn json(o: &Output) -> Value {
    serde_json::from_slice(&o.stdout).expect("JSON on stdout")
}

#[test]
fn mcap_logs_are_detected_and_audited_like_jsonl() {
    let d = tmpdir("detect");
    let (pj, pm) = (d.join("pass.jsonl"), d.join("pass.mcap"));
    let (fj, fm) = (d.join("fail.jsonl"), d.join("fail.mcap"));
    write_run(&pj, &pm, 2.5, "/joint_states");
    write_run(&fj, &fm, 0.3, "/joint_states");
    let o = pacs(&["audit", &s(&pm), "--json"]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert_eq!(json(&o)["runs"][0]["verdict"], "pass");
    // Detected by its magic bytes whatever the name.
    let other = d.join("recording.bin");
    std::fs::copy(&fm, &other).unwrap();
    let a = pacs(&["audit", &s(&fj), "--json"]);
    let b = pacs(&["audit", &s(&other), "--json"]);
    assert_eq!(a.status.code(), Some(1));
    assert_eq!(
        b.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&b.stderr)
    );
    let (a, b) = (json(&a), json(&b));
    assert_eq!(a["runs"][0]["verdict"], b["runs"][0]["verdict"]);
    assert_eq!(a["runs"][0]["violations"], b["runs"][0]["violations"]);
    assert_eq!(a["runs"][0]["metrics"], b["runs"][0]["metrics"]);
    assert_eq!(b["runs"][0]["meta"]["mcap_time_base_s"], 0);
    // Mixed with JSON Lines logs and a report.
    let out = d.join("report");
    let o = pacs(&["audit", &s(&pj), &s(&pm), &s(&fm), "--out", &s(&out)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(out.join("report.html").exists());
}

#[test]
fn header_flag_and_topic_flags() {
    let d = tmpdir("header");
    let (j, m) = (d.join("run.jsonl"), d.join("run.mcap"));
    write_run(&j, &m, 2.5, "/fr3/joint_states");
    // The robot topic is not the default: nothing to audit → inconclusive (exit 2), never pass.
    let o = pacs(&["audit", &s(&m)]);
    assert_eq!(o.status.code(), Some(2));
    let o = pacs(&["audit", &s(&m), "--robot-topic", "/fr3/joint_states"]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    // Same through the config's [mcap] table.
    let cfg = d.join("task.toml");
    std::fs::write(&cfg, "[mcap]\nrobot_topic = \"/fr3/joint_states\"\n").unwrap();
    assert_eq!(
        pacs(&["audit", &s(&m), "--config", &s(&cfg)]).status.code(),
        Some(0)
    );
    // Without the metadata record: exit 3 naming the file, unless --header gives it.
    let bare = d.join("bare.mcap");
    strip_header(&m, &bare);
    let o = pacs(&["audit", &s(&bare), "--robot-topic", "/fr3/joint_states"]);
    assert_eq!(o.status.code(), Some(3));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("bare.mcap") && err.contains("missing header"),
        "{err}"
    );
    let hj = d.join("header.json");
    std::fs::write(&hj, serde_json::to_string(&header()).unwrap()).unwrap();
    let o = pacs(&[
        "audit",
        &s(&bare),
        "--robot-topic",
        "/fr3/joint_states",
        "--header",
        &s(&hj),
    ]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let ht = d.join("header.toml");
    std::fs::write(
        &ht,
        "type = \"header\"\nformat = \"pacs-log\"\nversion = 1\nrobot = \"fr3\"\nhuman = \"default\"\nconstraints = \"ssm\"\n[meta]\ntask = \"sorting\"\n",
    )
    .unwrap();
    let o = pacs(&[
        "audit",
        &s(&bare),
        "--robot-topic",
        "/fr3/joint_states",
        "--header",
        &s(&ht),
        "--json",
    ]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert_eq!(json(&o)["runs"][0]["meta"]["task"], "sorting");
    // A bad header file, and --header with a JSON Lines log: exit 3.
    std::fs::write(&hj, "{\"type\": \"header\"}").unwrap();
    let o = pacs(&["audit", &s(&bare), "--header", &s(&hj)]);
    assert_eq!(o.status.code(), Some(3));
    assert!(String::from_utf8_lossy(&o.stderr).contains("header.json"));
    std::fs::write(&hj, serde_json::to_string(&header()).unwrap()).unwrap();
    let o = pacs(&["audit", &s(&j), "--header", &s(&hj)]);
    assert_eq!(o.status.code(), Some(3));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("applies to MCAP logs and ROS 2 bags only")
    );
}

#[test]
fn bad_mcap_input_exits_3_naming_file_offset_and_problem() {
    let d = tmpdir("bad");
    let (j, m) = (d.join("run.jsonl"), d.join("run.mcap"));
    write_run(&j, &m, 2.5, "/joint_states");
    let bytes = std::fs::read(&m).unwrap();
    let cut = d.join("cut.mcap");
    std::fs::write(&cut, &bytes[..bytes.len() * 2 / 3]).unwrap();
    let o = pacs(&["audit", &s(&cut)]);
    assert_eq!(o.status.code(), Some(3));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("cut.mcap: offset ") && err.contains("truncated"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
    let junk = d.join("junk.mcap");
    std::fs::write(&junk, b"{\"type\": \"header\"}\n").unwrap();
    let o = pacs(&["audit", &s(&junk)]);
    assert_eq!(o.status.code(), Some(3));
    assert!(String::from_utf8_lossy(&o.stderr).contains("junk.mcap"));
    // A wrong joint count on the robot topic.
    let mut w = McapLogWriter::new(
        Cursor::new(Vec::new()),
        mcap::WriteOptions::new(),
        &header(),
        &McapConfig::default(),
        &JOINTS[..6],
    )
    .unwrap();
    w.write_human(0, 0, &pacs_testkit::keypoints_in_a_row(2.5))
        .unwrap();
    w.write_robot(0, 0, &Q[..6], None).unwrap();
    let six = d.join("six.mcap");
    std::fs::write(&six, w.finish().unwrap().into_inner()).unwrap();
    let o = pacs(&["audit", &s(&six)]);
    assert_eq!(o.status.code(), Some(3));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("six.mcap: offset ") && err.contains("fr3_joint7"),
        "{err}"
    );
}

/// The shipped MCAP example (`examples/logs/clean_sorting.mcap`: the JSON Lines example as a
/// ROS 2 recording — JointState on `/joint_states`, PoseArray on `/human/keypoints`, CDR — with
/// its pacs header in `examples/logs/clean_sorting_header.json`, not in the file). Rewrite it
/// with `cargo test --test cli_audit_mcap -- --ignored regenerate`.
fn shipped_mcap() -> Vec<u8> {
    use pacs_log::RecordReader;
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let path = root.join("examples/logs/clean_sorting.jsonl");
    let mut reader = pacs_log::jsonl::JsonlReader::new(
        "clean_sorting.jsonl",
        std::io::BufReader::new(std::fs::File::open(&path).unwrap()),
    )
    .unwrap();
    let header = reader.header().clone();
    let mut m = McapLogWriter::new(
        Cursor::new(Vec::new()),
        mcap::WriteOptions::new(),
        &header,
        &McapConfig::default(),
        &JOINTS,
    )
    .unwrap();
    while let Some(rec) = reader.next_record().unwrap() {
        m.write_record(&rec).unwrap();
    }
    let with_header = m.finish().unwrap().into_inner();
    // Ship it without the metadata record: the header comes from --header, as for a recording
    // made by a ROS 2 stack that knows nothing of pacs.
    let mut out = mcap::Writer::new(Cursor::new(Vec::new())).unwrap();
    for msg in mcap::MessageStream::new(&with_header).unwrap() {
        out.write(&msg.unwrap()).unwrap();
    }
    out.finish().unwrap();
    out.into_inner().into_inner()
}

#[test]
#[ignore = "rewrites the shipped example"]
fn regenerate_the_shipped_mcap_example() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    std::fs::write(
        root.join("examples/logs/clean_sorting.mcap"),
        shipped_mcap(),
    )
    .unwrap();
    let text = std::fs::read_to_string(root.join("examples/logs/clean_sorting.jsonl")).unwrap();
    let header: Value = serde_json::from_str(text.lines().next().unwrap()).unwrap();
    std::fs::write(
        root.join("examples/logs/clean_sorting_header.json"),
        serde_json::to_string_pretty(&header).unwrap() + "\n",
    )
    .unwrap();
}

/// The shipped MCAP example is what the generator makes, carries no header of its own, and
/// audits with its header file exactly as the JSON Lines example does (pass).
#[test]
fn the_shipped_mcap_example_audits_like_its_jsonl_twin() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let shipped = std::fs::read(root.join("examples/logs/clean_sorting.mcap")).unwrap();
    assert_eq!(
        shipped.len(),
        shipped_mcap().len(),
        "regenerate the example"
    );
    let o = pacs(&["audit", "examples/logs/clean_sorting.mcap"]);
    assert_eq!(
        o.status.code(),
        Some(3),
        "no header in the file: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let o = pacs(&[
        "audit",
        "examples/logs/clean_sorting.mcap",
        "--header",
        "examples/logs/clean_sorting_header.json",
        "--json",
    ]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let m: Value = serde_json::from_slice(&o.stdout).unwrap();
    let o = pacs(&["audit", "examples/logs/clean_sorting.jsonl", "--json"]);
    let j: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(m["runs"][0]["verdict"], "pass");
    assert_eq!(m["runs"][0]["verdict"], j["runs"][0]["verdict"]);
    for k in [
        "samples",
        "human_records",
        "violation_fraction",
        "min_separation",
    ] {
        let (a, b) = (&m["runs"][0]["metrics"][k], &j["runs"][0]["metrics"][k]);
        assert!(a.is_number(), "{k} missing: {m}");
        assert_eq!(a, b, "{k}");
    }
}
