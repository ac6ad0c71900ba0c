//! End-to-end tests of `pacs audit` on ROS 2 sqlite3 bags written by `rosbags`
//! (python/tests/fixtures/db3, made by make_db3_bags.py): exit codes, `--header`, topic flags,
//! a report on a bag directory, and bad bags exiting 3 with the file and the problem on stderr.

mod common;

use common::{pacs, pacs_ok};
use serde_json::Value;
use std::path::{Path, PathBuf};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("python/tests/fixtures/db3")
}

fn tmpdir(name: &str) -> pacs_testkit::ScratchDir {
    pacs_testkit::ScratchDir::new("cli-db3", name)
}

fn s(p: &Path) -> String {
    p.display().to_string()
}

#[test]
fn bags_are_audited_with_their_exit_codes() {
    let f = fixtures();
    let o = pacs_ok(["audit", &s(&f.join("clean")), "--json"]);
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["runs"][0]["verdict"], "pass");
    assert_eq!(v["runs"][0]["metrics"]["samples"], 101);
    assert_eq!(v["runs"][0]["meta"]["db3_time_base_s"], 1_700_000_000);
    for bag in ["violation", "split"] {
        let o = pacs().args(["audit", &s(&f.join(bag))]).output().unwrap();
        assert_eq!(o.status.code(), Some(1), "{bag}");
    }
    let o = pacs()
        .args(["audit", &s(&f.join("shuffled.db3"))])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0));
}

#[test]
fn header_and_topic_flags_apply_to_bags() {
    let f = fixtures();
    let d = tmpdir("flags");
    let h = d.join("header.json");
    std::fs::write(
        &h,
        r#"{"type":"header","format":"pacs-log","version":1,"robot":"fr3","human":"default","constraints":"handover"}"#,
    )
    .unwrap();
    let o = pacs()
        .args(["audit", &s(&f.join("clean")), "--header", &s(&h), "--json"])
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["runs"][0]["models"]["constraints"], "handover");
    // No robot samples on the configured topic: nothing was checked, never a pass.
    let o = pacs()
        .args(["audit", &s(&f.join("clean")), "--robot-topic", "/other"])
        .output()
        .unwrap();
    assert_ne!(o.status.code(), Some(0));
}

#[test]
fn a_report_on_a_bag_directory_hashes_its_files() {
    let d = tmpdir("report");
    let out = d.join("report");
    let bag = fixtures().join("clean");
    let o = pacs()
        .args(["audit", &s(&bag), "--out", &s(&out)])
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let r: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let text = r.to_string();
    assert!(text.contains(&s(&bag)), "the report names the bag");
    let sizes: u64 = ["clean.db3", "metadata.yaml"]
        .iter()
        .map(|f| std::fs::metadata(bag.join(f)).unwrap().len())
        .sum();
    assert!(text.contains(&format!("\"bytes\":{sizes}")), "{text}");
}

#[test]
fn bad_bags_exit_3_naming_the_file_and_the_problem() {
    let d = tmpdir("bad");
    let full = std::fs::read(fixtures().join("clean/clean.db3")).unwrap();
    let cut = d.join("cut.db3");
    std::fs::write(&cut, &full[..full.len() / 2]).unwrap();
    let text = d.join("text.db3");
    std::fs::write(&text, "not a database\n").unwrap();
    let no_topics = d.join("no_topics.db3");
    std::fs::write(&no_topics, &full).unwrap();
    let c = rusqlite::Connection::open(&no_topics).unwrap();
    c.execute_batch("DROP TABLE topics").unwrap();
    drop(c);
    let json = d.join("json.db3");
    std::fs::write(&json, &full).unwrap();
    let c = rusqlite::Connection::open(&json).unwrap();
    c.execute_batch("UPDATE topics SET serialization_format = 'json'")
        .unwrap();
    drop(c);
    let empty_dir = d.join("empty");
    std::fs::create_dir_all(&empty_dir).unwrap();
    for (p, words) in [
        (&cut, "truncated file"),
        (&text, "not an SQLite database"),
        (&no_topics, "no table `topics`"),
        (&json, "serialization format `json` is not supported"),
        (&empty_dir, "a directory without log files"),
    ] {
        let o = pacs().args(["audit", &s(p)]).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(3), "{}: {err}", s(p));
        assert!(err.contains(&s(p)) && err.contains(words), "{err}");
        assert!(!err.contains("panicked"), "{err}");
    }
}

/// `--scene` reads a bag as the audit does: in the table's own order, and again through the time
/// index where the rows are stored too far out of time order (here a keypoints row stored 0.8 s
/// late after 1,000 others); the scene is written either way, from the whole bag.
#[test]
fn scenes_of_bags_stored_in_and_out_of_time_order_are_written() {
    let d = tmpdir("scene-order");
    let bag = d.join("late.db3");
    std::fs::copy(fixtures().join("clean/clean.db3"), &bag).unwrap();
    let c = rusqlite::Connection::open(&bag).unwrap();
    c.execute_batch(pacs_testkit::DB3_ROW_STORED_LATE).unwrap();
    drop(c);
    for (log, name) in [(fixtures().join("clean"), "clean"), (bag, "late")] {
        let scene = d.join(format!("{name}.mcap"));
        let o = pacs()
            .args(["audit", &s(&log), "--scene", &s(&scene)])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(matches!(o.status.code(), Some(0 | 1)), "{name}: {err}");
        assert!(!err.contains("error"), "{name}: {err}");
        let bytes = std::fs::read(&scene).unwrap();
        assert!(
            bytes.starts_with(b"\x89MCAP0\r\n") && bytes.len() > 10_000,
            "{name}"
        );
    }
}
