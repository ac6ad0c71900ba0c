//! The ROS 2 sqlite3 bag reader (`.db3`, bag directories with `metadata.yaml`). The bags are
//! written by an independent writer, the `rosbags` Python package, with
//! `python/tests/fixtures/make_db3_bags.py` (its docstring describes the run); the same run
//! written here as MCAP (`McapLogWriter`) gets the same result. Bad bags (made here with SQLite
//! from the fixtures) are errors naming the file and the problem, never a panic or a verdict.

mod audit_common;

use audit_common::{Q_READY, standing};
use pacs_audit::{AuditConfig, RunResult, Verdict, open_log};
use pacs_log::mcap::{McapConfig, McapLogWriter};
use pacs_log::{Header, LogError, ModelRef, PersonEntry, RobotRef};
use std::path::{Path, PathBuf};

const BASE_NS: i128 = 1_700_000_000 * 1_000_000_000;
const STEP_NS: i128 = 10_000_000;

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../python/tests/fixtures/db3")
}

fn header() -> Header {
    Header::new(
        RobotRef::Name("fr3".into()),
        ModelRef::Name("default".into()),
        ModelRef::Name("ssm".into()),
    )
}

fn audit(path: &Path, header: Option<&Header>) -> Result<RunResult, LogError> {
    let cfg = AuditConfig::default();
    let mut r = open_log(path, &cfg, header)?;
    pacs_audit::audit_reader(r.as_mut(), &cfg)
}

/// The fixtures' run (see make_db3_bags.py) written as MCAP with the library's writer, audited;
/// `people`: the two-person run (`op` far, `walker` stepping in at 0.6 s) with a v2 header.
fn mcap_twin(violation: bool) -> RunResult {
    twin(violation, false)
}

fn twin(violation: bool, people: bool) -> RunResult {
    let joints: Vec<String> = pacs_models::RobotModel::builtin("fr3")
        .unwrap()
        .joints()
        .iter()
        .map(|j| j.name.clone())
        .collect();
    let names: Vec<&str> = joints.iter().map(String::as_str).collect();
    let cfg = McapConfig::default();
    let h = if people {
        let person = |id: &str| PersonEntry {
            id: id.into(),
            human: ModelRef::Name("default".into()),
        };
        let mut h = Header::with_people(
            RobotRef::Name("fr3".into()),
            vec![person("op"), person("walker")],
            ModelRef::Name("ssm".into()),
        );
        h.end_event = false;
        h.start_event = false;
        h
    } else {
        header()
    };
    let mut w = McapLogWriter::new(
        std::io::Cursor::new(Vec::new()),
        mcap::WriteOptions::default(),
        &h,
        &cfg,
        &names,
    )
    .unwrap();
    for i in 0..=100i128 {
        let ns = i * STEP_NS;
        if i % 10 == 0 {
            let meas = (ns - 20_000_000).max(0);
            if people {
                w.write_person("op", BASE_NS + meas, BASE_NS + ns, &standing(2.5, 0.0))
                    .unwrap();
                let x = if i >= 60 { 0.45 } else { 2.5 };
                w.write_person("walker", BASE_NS + meas, BASE_NS + ns, &standing(x, 0.0))
                    .unwrap();
            } else {
                let x = if violation && i >= 50 { 0.45 } else { 2.5 };
                w.write_human(BASE_NS + meas, BASE_NS + ns, &standing(x, 0.0))
                    .unwrap();
            }
        }
        let mut q = Q_READY;
        q[0] = 0.005 * i as f64;
        let dq = [0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        let dq = (i % 2 == 0).then_some(&dq[..]);
        w.write_robot(BASE_NS + ns, BASE_NS + ns + 1_000_000, &q, dq)
            .unwrap();
    }
    w.write_event(BASE_NS + 100 * STEP_NS, "success").unwrap();
    let bytes = w.finish().unwrap().into_inner();
    let dir = tempdir();
    let p = dir.join("twin.mcap");
    std::fs::write(&p, bytes).unwrap();
    audit(&p, None).unwrap()
}

/// `a` and `b` equal but for the log's name and the time base's key.
fn same_result(a: &RunResult, b: &RunResult) {
    let mut a = a.clone();
    let mut b = b.clone();
    for r in [&mut a, &mut b] {
        r.log.clear();
        let base = r
            .meta
            .remove("db3_time_base_s")
            .or_else(|| r.meta.remove("mcap_time_base_s"));
        assert_eq!(base, Some(1_700_000_000.into()));
    }
    assert_eq!(a, b);
}

fn tempdir() -> pacs_testkit::ScratchDir {
    use std::sync::atomic::{AtomicUsize, Ordering};
    static N: AtomicUsize = AtomicUsize::new(0);
    pacs_testkit::ScratchDir::new("db3", &N.fetch_add(1, Ordering::Relaxed).to_string())
}

fn expect_err(r: Result<RunResult, LogError>, file: &str, words: &[&str]) -> String {
    let e = match r {
        Ok(run) => panic!("expected an error, got {:?}", run.verdict),
        Err(e) => e.to_string(),
    };
    assert!(e.starts_with(file), "{e} should name {file}");
    for w in words {
        assert!(e.contains(w), "{e} should contain {w:?}");
    }
    e
}

#[test]
fn clean_bag_passes_and_equals_the_same_run_as_mcap() {
    let r = audit(&fixtures().join("clean"), None).unwrap();
    assert_eq!(r.verdict, Verdict::Pass, "{r:?}");
    assert_eq!(r.metrics.samples, 101);
    assert_eq!(r.metrics.duration, 1.0);
    assert_eq!(r.metrics.success, Some(true));
    assert_eq!(r.meta["db3_time_base_s"], 1_700_000_000);
    assert!(r.violations.is_empty() && r.inconclusive.is_empty());
    assert_eq!(r.log, fixtures().join("clean").display().to_string());
    same_result(&r, &mcap_twin(false));
}

#[test]
fn violating_bag_fails_at_the_step_and_equals_mcap() {
    // JointState names reversed plus finger joints (mapped by name), an ignored `/tf` topic.
    let r = audit(&fixtures().join("violation"), None).unwrap();
    assert_eq!(r.verdict, Verdict::Fail);
    assert_eq!(r.metrics.samples, 101);
    assert_eq!(r.metrics.duration, 1.0);
    let first = r
        .violations
        .iter()
        .map(|v| v.t_start)
        .fold(f64::INFINITY, f64::min);
    assert_eq!(first, 0.5, "the person steps in at t = 0.5 s");
    // Intervals per (body part, link): the last two spans of each 0.1 s are cleared by the
    // record the camera took at their start, logged 20 ms later (its occupancy, tighter than the
    // older record's in use then, holds the person too).
    assert_eq!(r.violations.len(), 44);
    // The step from 2.5 m to 0.45 m is faster than the human model allows.
    assert_eq!(r.inconclusive.len(), 1);
    assert_eq!(
        (r.inconclusive[0].t_start, r.inconclusive[0].t_end),
        (0.38, 0.98)
    );
    same_result(&r, &mcap_twin(true));
}

/// `mcap.human_topics` naming someone the header does not declare is an input error naming
/// the id and the people (its topic would otherwise go unread without a word); naming the
/// header's people works.
#[test]
fn human_topics_must_name_the_headers_people() {
    let bag = fixtures().join("people");
    let with_topics = |topics: &[(&str, &str)]| {
        let mut cfg = AuditConfig::default();
        cfg.mcap.human_topics = topics
            .iter()
            .map(|(id, t)| (id.to_string(), t.to_string()))
            .collect();
        open_log(&bag, &cfg, None).and_then(|mut r| pacs_audit::audit_reader(r.as_mut(), &cfg))
    };
    let e = with_topics(&[("ghost", "/humans/ghost/keypoints")])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("mcap.human_topics: `ghost` is not a person of the header (people: op, walker)"),
        "{e}"
    );
    let r = with_topics(&[
        ("op", "/humans/op/keypoints"),
        ("walker", "/humans/walker/keypoints"),
    ])
    .unwrap();
    assert_eq!(r.verdict, Verdict::Fail);
    assert!(
        r.violations
            .iter()
            .all(|v| v.person.as_deref() == Some("walker"))
    );
}

#[test]
fn two_people_on_their_topics_are_read_as_from_mcap() {
    // A v2 header in custom_data; /humans/op/keypoints and /humans/walker/keypoints.
    let r = audit(&fixtures().join("people"), None).unwrap();
    assert_eq!(r.verdict, Verdict::Fail);
    assert_eq!(r.metrics.samples, 101);
    assert!(!r.violations.is_empty());
    assert!(
        r.violations
            .iter()
            .all(|v| v.person.as_deref() == Some("walker"))
    );
    let first = r
        .violations
        .iter()
        .map(|v| v.t_start)
        .fold(f64::INFINITY, f64::min);
    assert_eq!(first, 0.6, "walker steps in at t = 0.6 s");
    assert_eq!(r.violations.len(), 35);
    same_result(&r, &twin(true, true));
}

#[test]
fn shuffled_insertion_is_read_in_timestamp_order() {
    let clean = audit(&fixtures().join("clean"), None).unwrap();
    let r = audit(&fixtures().join("shuffled.db3"), None).unwrap();
    assert_eq!(r.verdict, Verdict::Pass);
    same_result(&clean, &r);
}

/// `pacs_log::open_log` or `open_log_in_row_order`.
type OpenLog = fn(
    &Path,
    &McapConfig,
    &pacs_log::ModelOverrides,
    Option<&Header>,
) -> Result<Box<dyn pacs_log::RecordReader>, LogError>;

/// Every record of `path` read by `open` (formatted: records borrow the reader's buffers), and
/// how reading ended.
fn records(path: &Path, open: OpenLog) -> (Vec<String>, Result<(), LogError>) {
    let mut out = Vec::new();
    let mut r = match open(path, &McapConfig::default(), &Default::default(), None) {
        Ok(r) => r,
        Err(e) => return (out, Err(e)),
    };
    loop {
        match r.next_record() {
            Ok(Some(rec)) => out.push(format!("{rec:?}")),
            Ok(None) => return (out, Ok(())),
            Err(e) => return (out, Err(e)),
        }
    }
}

/// Bags whose rows are stored in time order (as `ros2 bag record` writes them) read in storage
/// order give exactly the records the time index gives, in the same order: one file, two
/// people, a bag split into two files, with and without topics that are not configured.
#[test]
fn row_order_reads_the_records_of_the_time_index() {
    for bag in ["clean", "violation", "people", "split"] {
        let path = fixtures().join(bag);
        let (by_index, end) = records(&path, pacs_log::open_log);
        end.unwrap();
        let (by_rows, end) = records(&path, pacs_log::open_log_in_row_order);
        end.unwrap_or_else(|e| panic!("{bag}: {e}"));
        assert!(by_index.len() > 100, "{bag}: {} records", by_index.len());
        assert_eq!(by_rows, by_index, "{bag}");
    }
}

/// Rows stored out of time order within what is held back at once (the shuffled bag: 113 rows
/// inserted in random order) are read in storage order as through the time index; a bag whose
/// rows are stored farther out of order (the clean bag's rows copied ten times, each copy two
/// seconds later than the one inserted after it) stops reading in storage order with the error
/// that asks for the time index (naming the file), and the audit then reads it through the time
/// index: the same result as the time index gives.
#[test]
fn rows_out_of_time_order_are_read_again_through_the_time_index() {
    let shuffled = fixtures().join("shuffled.db3");
    let (by_rows, end) = records(&shuffled, pacs_log::open_log_in_row_order);
    end.unwrap();
    let (clean, _) = records(&fixtures().join("clean"), pacs_log::open_log);
    assert_eq!(by_rows, clean);
    let cfg = AuditConfig::default();
    let r = pacs_audit::audit_file(&shuffled, &cfg).unwrap();
    assert_eq!(r.verdict, Verdict::Pass);
    same_result(
        &pacs_audit::audit_file(&fixtures().join("clean"), &cfg).unwrap(),
        &r,
    );

    let d = tempdir();
    let path = copy_clean(&d);
    sql(&path, pacs_testkit::DB3_ROW_STORED_LATE);
    let (_, end) = records(&path, pacs_log::open_log_in_row_order);
    match end {
        Err(LogError::RowsNotInTimeOrder { file }) => {
            assert_eq!(file, path.display().to_string())
        }
        other => panic!("expected RowsNotInTimeOrder, got {other:?}"),
    }
    let (by_index, end) = records(&path, pacs_log::open_log);
    end.unwrap();
    assert_eq!(by_index.len(), clean.len() + 1_001);
    same_result(
        &audit(&path, None).unwrap(),
        &pacs_audit::audit_file(&path, &cfg).unwrap(),
    );
}

/// Random bags: the clean bag's 113 rows and 1,000 to 1,200 copies of its first keypoints
/// message at random receive times within the run (more rows than one batch, so rows are held
/// back across batches), stored in the order of each row's receive time moved by a random
/// amount up to ±`jitter` (0 to 40 ms), with ids in that order. Read in storage order, every
/// bag gives exactly the records of the time index, or (only where the storage order is more
/// than the hold-back out of time order) the error that asks for the time index; within ±4 ms
/// it is never refused.
#[test]
fn random_storage_orders_read_as_the_time_index_or_are_refused() {
    let mut next = pacs_testkit::xorshift(0x9e37_79b9_7f4a_7c15);
    let d = tempdir();
    let (mut refused, mut read) = (0, 0);
    for case in 0..24 {
        let path = d.join(format!("case{case}.db3"));
        std::fs::copy(fixtures().join("clean/clean.db3"), &path).unwrap();
        let c = rusqlite::Connection::open(&path).unwrap();
        let mut rows: Vec<(i64, i64, Vec<u8>)> = c
            .prepare("SELECT topic_id, timestamp, data FROM messages ORDER BY id")
            .unwrap()
            .query_map([], |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?)))
            .unwrap()
            .map(Result::unwrap)
            .collect();
        let human: i64 = c
            .query_row(
                "SELECT id FROM topics WHERE name = '/human/keypoints'",
                [],
                |r| r.get(0),
            )
            .unwrap();
        let first = rows.iter().find(|r| r.0 == human).unwrap().2.clone();
        let extra = 1_000 + (next() % 201) as usize;
        for _ in 0..extra {
            let ts = 1_700_000_000_000_000_000 + (next() % 1_001_000_000) as i64;
            rows.push((human, ts, first.clone()));
        }
        let jitter = [0, 1, 4, 20, 40][case % 5] * 1_000_000i64;
        let mut keyed: Vec<(i64, usize)> = rows
            .iter()
            .enumerate()
            .map(|(i, r)| {
                let moved = if jitter > 0 {
                    (next() % (2 * jitter as u64 + 1)) as i64 - jitter
                } else {
                    0
                };
                (r.1 + moved, i)
            })
            .collect();
        keyed.sort_unstable();
        let tx = c.unchecked_transaction().unwrap();
        tx.execute("DELETE FROM messages", []).unwrap();
        for (id, (_, i)) in keyed.iter().enumerate() {
            let (topic, ts, data) = &rows[*i];
            tx.execute(
                "INSERT INTO messages (id, topic_id, timestamp, data) VALUES (?1, ?2, ?3, ?4)",
                rusqlite::params![id as i64 + 1, topic, ts, data],
            )
            .unwrap();
        }
        let n = rows.len();
        let humans = 11 + extra;
        tx.execute(
            &format!(
                "UPDATE metadata SET metadata = replace(replace(metadata, 'message_count: 113', \
                 'message_count: {n}'), 'message_count: 11\n', 'message_count: {humans}\n')"
            ),
            [],
        )
        .unwrap();
        tx.commit().unwrap();
        drop(c);
        let (by_index, end) = records(&path, pacs_log::open_log);
        end.unwrap_or_else(|e| panic!("case {case}: {e}"));
        assert_eq!(by_index.len(), n, "case {case}");
        match records(&path, pacs_log::open_log_in_row_order) {
            (by_rows, Ok(())) => {
                read += 1;
                assert_eq!(by_rows, by_index, "case {case} (jitter {jitter} ns)");
            }
            (_, Err(LogError::RowsNotInTimeOrder { .. })) => {
                refused += 1;
                assert!(jitter > 4_000_000, "case {case}: refused at ±{jitter} ns");
            }
            (_, Err(e)) => panic!("case {case}: {e}"),
        }
    }
    // Both outcomes occur (the test is not vacuous either way).
    assert!(read >= 10 && refused >= 1, "read {read}, refused {refused}");
}

#[test]
fn a_bag_split_into_two_files_reads_both_in_order() {
    let one = audit(&fixtures().join("violation"), None).unwrap();
    let r = audit(&fixtures().join("split"), None).unwrap();
    same_result(&one, &r);
}

#[test]
fn a_lone_db3_finds_its_header_in_its_metadata_table_or_takes_one_given() {
    let dir = audit(&fixtures().join("clean"), None).unwrap();
    let file = fixtures().join("clean/clean.db3");
    same_result(&dir, &audit(&file, None).unwrap());
    // Detected by its magic bytes whatever its name.
    let d = tempdir();
    let renamed = d.join("run.bag");
    std::fs::copy(&file, &renamed).unwrap();
    same_result(&dir, &audit(&renamed, None).unwrap());
    // Without the metadata table: the header must be given.
    let bare = d.join("bare.db3");
    std::fs::copy(&file, &bare).unwrap();
    sql(&bare, "DROP TABLE metadata");
    let name = bare.display().to_string();
    expect_err(audit(&bare, None), &name, &["missing header", "--header"]);
    same_result(&dir, &audit(&bare, Some(&header())).unwrap());
    // One part of a split bag (its metadata lists another part) is refused: not the whole run.
    let part = d.join("part.db3");
    std::fs::copy(&file, &part).unwrap();
    sql(
        &part,
        "UPDATE metadata SET metadata = replace(metadata, \
         'relative_file_paths:' || char(10) || '- clean.db3' || char(10), \
         'relative_file_paths:' || char(10) || '- clean.db3' || char(10) || '- clean_1.db3' || char(10))",
    );
    let name = part.display().to_string();
    expect_err(
        audit(&part, None),
        &name,
        &[
            "one of 2 parts of a bag",
            "clean_1.db3",
            "audit the bag directory",
        ],
    );
    // A given header wins over the bag's.
    let mut pfl = header();
    pfl.constraints = ModelRef::Name("handover".into());
    let r = audit(&fixtures().join("clean"), Some(&pfl)).unwrap();
    assert_eq!(r.models.constraints, "handover");
}

#[test]
fn a_bag_in_humble_s_schema_reads_the_same() {
    // ROS 2 Humble's sqlite3 storage (schema version 3): `topics` without
    // `type_description_hash`, no `message_definitions`, no `metadata` table (so no custom_data:
    // the header is given), and a version 5 metadata.yaml without custom_data.
    let d = tempdir();
    let bag = d.join("humble");
    std::fs::create_dir_all(&bag).unwrap();
    let db = bag.join("humble_0.db3");
    std::fs::copy(fixtures().join("clean/clean.db3"), &db).unwrap();
    sql(
        &db,
        "DROP TABLE message_definitions; DROP TABLE metadata; \
         CREATE TABLE topics3(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, \
           serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL); \
         INSERT INTO topics3 SELECT id, name, type, serialization_format, offered_qos_profiles FROM topics; \
         DROP TABLE topics; ALTER TABLE topics3 RENAME TO topics; \
         UPDATE schema SET schema_version = 3, ros_distro = 'humble'; VACUUM;",
    );
    std::fs::write(
        bag.join("metadata.yaml"),
        "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: sqlite3\n  \
         duration:\n    nanoseconds: 1001000000\n  starting_time:\n    nanoseconds_since_epoch: 1700000000000000000\n  \
         message_count: 113\n  topics_with_message_count: []\n  compression_format: \"\"\n  \
         compression_mode: \"\"\n  relative_file_paths:\n    - humble_0.db3\n  files:\n    - path: humble_0.db3\n",
    )
    .unwrap();
    let name = bag.display().to_string();
    expect_err(audit(&bag, None), &name, &["missing header", "custom_data"]);
    let r = audit(&bag, Some(&header())).unwrap();
    same_result(&audit(&fixtures().join("clean"), None).unwrap(), &r);
}

// ---------------------------------------------------------------------------------------------
// Bad bags.

fn sql(path: &Path, stmt: &str) {
    let c = rusqlite::Connection::open(path).unwrap();
    c.execute_batch(stmt).unwrap();
}

fn copy_clean(d: &Path) -> PathBuf {
    let p = d.join("bad.db3");
    std::fs::copy(fixtures().join("clean/clean.db3"), &p).unwrap();
    p
}

#[test]
fn not_an_sqlite_file_is_an_error() {
    let d = tempdir();
    let p = d.join("run.db3");
    std::fs::write(&p, "{\"type\":\"header\"}\n").unwrap();
    let name = p.display().to_string();
    expect_err(audit(&p, None), &name, &["not an SQLite database"]);
    std::fs::write(&p, "").unwrap();
    expect_err(audit(&p, None), &name, &["not an SQLite database"]);
}

#[test]
fn missing_tables_are_errors() {
    for table in ["topics", "messages"] {
        let d = tempdir();
        let p = copy_clean(&d);
        sql(&p, &format!("DROP TABLE {table}"));
        let name = p.display().to_string();
        expect_err(
            audit(&p, None),
            &name,
            &[&format!("not a rosbag2 sqlite3 bag: no table `{table}`")],
        );
    }
}

#[test]
fn a_configured_topic_must_be_cdr_of_the_expected_type() {
    let d = tempdir();
    let p = copy_clean(&d);
    sql(
        &p,
        "UPDATE topics SET serialization_format = 'json' WHERE name = '/joint_states'",
    );
    let name = p.display().to_string();
    expect_err(
        audit(&p, None),
        &name,
        &[
            "topic `/joint_states`",
            "serialization format `json` is not supported (expected `cdr`)",
        ],
    );
    let scratch = tempdir();
    let p = copy_clean(&scratch);
    sql(
        &p,
        "UPDATE topics SET type = 'sensor_msgs/msg/Imu' WHERE name = '/joint_states'",
    );
    expect_err(
        audit(&p, None),
        &p.display().to_string(),
        &["type `sensor_msgs/msg/Imu`, expected `sensor_msgs/msg/JointState` for this topic"],
    );
    // A configured topic the metadata counts but the file has no connection for: its count
    // (not 0) tells, as for MCAP bags.
    let scratch = tempdir();
    let p = copy_clean(&scratch);
    sql(
        &p,
        "UPDATE topics SET name = '/other' WHERE name = '/pacs/events'",
    );
    expect_err(
        audit(&p, None),
        &format!("{} (table `metadata`)", p.display()),
        &["`/pacs/events` has message_count 1", "hold 0"],
    );
    // A topic that is not configured may be anything.
    let scratch = tempdir();
    let p = copy_clean(&scratch);
    sql(
        &p,
        "UPDATE topics SET serialization_format = 'json', type = 'x', name = '/other' WHERE name = '/pacs/events'; \
         UPDATE metadata SET metadata = replace(metadata, 'name: /pacs/events', 'name: /other')",
    );
    let r = audit(&p, None).unwrap();
    assert_eq!(r.verdict, Verdict::Pass);
    assert_eq!(
        r.metrics.success, None,
        "events are not read from a json topic"
    );
}

#[test]
fn bad_messages_are_errors_naming_the_message() {
    let cases: [(&str, &[&str]); 4] = [
        (
            "UPDATE messages SET data = x'000100000000' WHERE id = (SELECT min(m.id) FROM messages m JOIN topics t ON m.topic_id = t.id WHERE t.name = '/joint_states')",
            &[
                "message id ",
                "on `/joint_states`",
                "JointState",
                "truncated",
            ],
        ),
        (
            "UPDATE messages SET data = 'text' WHERE id = (SELECT min(m.id) FROM messages m JOIN topics t ON m.topic_id = t.id WHERE t.name = '/joint_states')",
            &["message id ", "messages.data: expected a blob, found Text"],
        ),
        (
            "UPDATE messages SET timestamp = -5 WHERE id = (SELECT min(m.id) FROM messages m JOIN topics t ON m.topic_id = t.id WHERE t.name = '/human/keypoints')",
            &[
                "message id ",
                "on `/human/keypoints` (timestamp -5 ns): negative timestamp",
            ],
        ),
        (
            "UPDATE messages SET data = x'28b52ffd00' WHERE id = (SELECT min(m.id) FROM messages m JOIN topics t ON m.topic_id = t.id WHERE t.name = '/human/keypoints')",
            &["PoseArray", "zstd-compressed"],
        ),
    ];
    for (stmt, words) in cases {
        let scratch = tempdir();
        let p = copy_clean(&scratch);
        sql(&p, stmt);
        expect_err(audit(&p, None), &p.display().to_string(), words);
    }
}

#[test]
fn a_bad_message_in_a_split_bag_names_the_part_it_is_in() {
    // One damaged `JointState` in either part of a two-file bag: the error names that part's
    // file, not the bag directory nor the other part.
    for damaged in ["split_0.db3", "split_1.db3"] {
        let d = tempdir();
        for f in ["metadata.yaml", "split_0.db3", "split_1.db3"] {
            std::fs::copy(fixtures().join("split").join(f), d.join(f)).unwrap();
        }
        let part = d.join(damaged);
        sql(
            &part,
            "UPDATE messages SET data = x'000100000000' WHERE id = (SELECT min(m.id) FROM messages m JOIN topics t ON m.topic_id = t.id WHERE t.name = '/joint_states')",
        );
        expect_err(
            audit(&d, None),
            &part.display().to_string(),
            &[
                "message id ",
                "on `/joint_states`",
                "JointState",
                "truncated",
            ],
        );
    }
}

#[test]
fn truncated_files_are_errors_at_every_length() {
    let full = std::fs::read(fixtures().join("clean/clean.db3")).unwrap();
    let d = tempdir();
    let p = d.join("cut.db3");
    let name = p.display().to_string();
    let mut lengths: Vec<usize> = (0..full.len()).step_by(4096).collect();
    lengths.extend([1, 15, 16, 99, 100, 101, 4097, full.len() - 1]);
    for n in lengths {
        std::fs::write(&p, &full[..n]).unwrap();
        let e = expect_err(audit(&p, None), &name, &[]);
        assert!(
            e.contains("truncated") || e.contains("not an SQLite database"),
            "{n} bytes: {e}"
        );
    }
}

#[test]
fn bag_directory_errors_name_metadata_yaml() {
    let meta = std::fs::read_to_string(fixtures().join("clean/metadata.yaml")).unwrap();
    let db = fixtures().join("clean/clean.db3");
    let cases: Vec<(String, &[&str])> = vec![
        (
            meta.replace("compression_mode: ''", "compression_mode: file")
                .replace("compression_format: ''", "compression_format: zstd"),
            &["compressed bags are not supported", "`file`", "`zstd`"],
        ),
        (
            meta.replace("storage_identifier: sqlite3", "storage_identifier: mcap"),
            &[
                "relative_file_paths[0]",
                "clean.db3` is not an MCAP file",
                "storage_identifier is `mcap`",
            ],
        ),
        (
            // The file listed is not the file the metadata's `files` describe.
            meta.replace("- clean.db3", "- missing.db3"),
            &[
                "contradicts itself",
                "files[0].path `clean.db3` is not in relative_file_paths (missing.db3)",
            ],
        ),
        (
            meta.replace("- clean.db3", "- missing.db3")
                .replace("path: clean.db3", "path: missing.db3"),
            &["relative_file_paths[0]", "missing.db3", "is not a file"],
        ),
        (
            meta.replace("- clean.db3", "- clean.db3\n  - clean.db3"),
            &["relative_file_paths[1] `clean.db3` is relative_file_paths[0] again"],
        ),
        (
            // One file under two spellings.
            meta.replace("- clean.db3", "- clean.db3\n  - ./clean.db3"),
            &["relative_file_paths[1] `./clean.db3` is relative_file_paths[0] again"],
        ),
        (
            "a: &x [1, 2]\nb: *x\n".into(),
            &["line 2: YAML aliases are not supported"],
        ),
        ("rosbag2_bagfile_information: [\n".into(), &["invalid YAML"]),
        (
            "other: 1\n".into(),
            &["no mapping `rosbag2_bagfile_information`"],
        ),
    ];
    for (text, words) in cases {
        let d = tempdir();
        std::fs::copy(&db, d.join("clean.db3")).unwrap();
        std::fs::write(d.join("metadata.yaml"), text).unwrap();
        let name = d.join("metadata.yaml").display().to_string();
        expect_err(audit(&d, None), &name, words);
    }
    // A directory without metadata.yaml is not a bag.
    let d = tempdir();
    let name = d.display().to_string();
    expect_err(
        audit(&d, None),
        &name,
        &["a directory without metadata.yaml: not a ROS 2 bag"],
    );
}

#[test]
fn a_bag_directory_must_be_the_whole_recording() {
    let meta = std::fs::read_to_string(fixtures().join("clean/metadata.yaml")).unwrap();
    let db = fixtures().join("clean/clean.db3");
    let bag = |text: &str| {
        let d = tempdir();
        std::fs::copy(&db, d.join("clean.db3")).unwrap();
        std::fs::write(d.join("metadata.yaml"), text).unwrap();
        d
    };
    // The untouched bag passes (the counts agree).
    assert_eq!(audit(&bag(&meta), None).unwrap().verdict, Verdict::Pass);
    // A .db3 in the directory that the metadata does not list would go unread.
    let d = bag(&meta);
    std::fs::copy(&db, d.join("clean_1.db3")).unwrap();
    let name = d.join("metadata.yaml").display().to_string();
    expect_err(
        audit(&d, None),
        &name,
        &[
            "clean_1.db3",
            "not in rosbag2_bagfile_information.relative_file_paths",
        ],
    );
    // The recorder counted more messages than the files hold: cut short.
    assert!(meta.contains("- message_count: 101\n    topic_metadata:\n      name: /joint_states"));
    let d = bag(&meta.replace("- message_count: 101", "- message_count: 102"));
    let name = d.join("metadata.yaml").display().to_string();
    expect_err(
        audit(&d, None),
        &name,
        &[
            "`/joint_states` has message_count 102",
            "hold 101",
            "cut short",
        ],
    );
    // Rows deleted from the file (the metadata unchanged): the file's count contradicts it.
    let d = bag(&meta);
    sql(
        &d.join("clean.db3"),
        "DELETE FROM messages WHERE id IN (SELECT id FROM messages ORDER BY timestamp DESC LIMIT 30);",
    );
    expect_err(
        audit(&d, None),
        &d.join("clean.db3").display().to_string(),
        &[
            "counts 113 messages in this file",
            "it holds 83",
            "rows cut or added",
        ],
    );
    // More messages than counted: the metadata is not this recording's.
    let d = bag(&meta.replace("- message_count: 101", "- message_count: 100"));
    expect_err(
        audit(&d, None),
        &name_of(&d),
        &[
            "has message_count 100",
            "hold 101",
            "does not describe these files",
        ],
    );
}

fn name_of(bag: &Path) -> String {
    bag.join("metadata.yaml").display().to_string()
}

#[test]
fn the_header_in_custom_data_is_checked() {
    let meta = std::fs::read_to_string(fixtures().join("clean/metadata.yaml")).unwrap();
    let d = tempdir();
    std::fs::copy(fixtures().join("clean/clean.db3"), d.join("clean.db3")).unwrap();
    std::fs::write(
        d.join("metadata.yaml"),
        meta.replace("\"version\": 1", "\"version\": 7"),
    )
    .unwrap();
    let name = d.join("metadata.yaml").display().to_string();
    expect_err(
        audit(&d, None),
        &name,
        &["custom_data.pacs_header: header.version: 7 is not supported"],
    );
}

#[test]
fn corrupted_bytes_are_an_error_or_a_result_never_a_panic() {
    // Deterministic corruptions of the clean bag: a run of bytes overwritten at many places
    // (SQLite's structure and the message payloads alike).
    let full = std::fs::read(fixtures().join("clean/clean.db3")).unwrap();
    let d = tempdir();
    let p = d.join("bad.db3");
    let mut x: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut errors = 0;
    for k in 0..300 {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        let mut b = full.clone();
        let at = (x as usize) % b.len();
        let len = 1 + (x >> 32) as usize % 16;
        for (i, v) in b.iter_mut().skip(at).take(len).enumerate() {
            *v = (x >> (i % 8 * 8)) as u8 ^ (k as u8);
        }
        std::fs::write(&p, &b).unwrap();
        if audit(&p, None).is_err() {
            errors += 1;
        }
    }
    assert!(errors > 0);
}

/// `bag`'s `.db3` file `db` with its free list damaged (the header names page 2, in use, as a
/// free-list trunk with one leaf): SQLite's `quick_check` complains, the rows read as before.
fn damage_free_list(db: &Path) {
    let mut b = std::fs::read(db).unwrap();
    b[32..36].copy_from_slice(&2u32.to_be_bytes());
    b[36..40].copy_from_slice(&1u32.to_be_bytes());
    std::fs::write(db, b).unwrap();
}

#[test]
fn rows_that_account_for_the_metadata_s_count_need_no_structural_check() {
    // Every row 1..=113 read once, the metadata counting 113 for the file: the file is read
    // whole, so damage outside the rows read (here the free list) does not stop the audit.
    let d = tempdir();
    for f in ["clean.db3", "metadata.yaml"] {
        std::fs::copy(fixtures().join("clean").join(f), d.join(f)).unwrap();
    }
    damage_free_list(&d.join("clean.db3"));
    let clean = audit(&fixtures().join("clean"), None).unwrap();
    let cfg = AuditConfig::default();
    // Through the time index and in the table's own order (the audit's `audit_file`) alike.
    let file = |p: &Path, h: Option<&Header>| pacs_audit::audit_file_with_header(p, &cfg, h);
    same_result(&clean, &audit(&d, None).unwrap());
    same_result(&clean, &file(&d, None).unwrap());
    // The lone file keeps its count in its `metadata` table: the same.
    same_result(&clean, &audit(&d.join("clean.db3"), None).unwrap());
    same_result(&clean, &file(&d.join("clean.db3"), None).unwrap());
    // Without a count (no `metadata` table) the structural check runs before reading, and
    // refuses the damaged file.
    let lone = d.join("lone.db3");
    std::fs::copy(fixtures().join("clean/clean.db3"), &lone).unwrap();
    sql(&lone, "DROP TABLE metadata; VACUUM;");
    same_result(&clean, &audit(&lone, Some(&header())).unwrap());
    same_result(&clean, &file(&lone, Some(&header())).unwrap());
    damage_free_list(&lone);
    for r in [audit(&lone, Some(&header())), file(&lone, Some(&header()))] {
        expect_err(
            r,
            &lone.display().to_string(),
            &["damaged SQLite file (PRAGMA quick_check:", "freelist"],
        );
    }
}

#[test]
fn rows_that_do_not_account_for_the_count_are_checked_after_reading() {
    // Rows deleted (ids missing from 1..=113) and the free list damaged: the rows do not
    // account, so SQLite's structural check runs at the end of the file and refuses it.
    let d = tempdir();
    for f in ["clean.db3", "metadata.yaml"] {
        std::fs::copy(fixtures().join("clean").join(f), d.join(f)).unwrap();
    }
    sql(
        &d.join("clean.db3"),
        "DELETE FROM messages WHERE id IN (SELECT id FROM messages ORDER BY timestamp LIMIT 30 OFFSET 40);",
    );
    damage_free_list(&d.join("clean.db3"));
    let cfg = AuditConfig::default();
    for r in [audit(&d, None), pacs_audit::audit_file(&d, &cfg)] {
        expect_err(
            r,
            &d.join("clean.db3").display().to_string(),
            &[
                "damaged SQLite file (its rows are not the ids 1 to the metadata's message_count",
                "freelist",
            ],
        );
    }
    // A row of the time index lost (the index's root swapped for one built without row 41):
    // through the index the rows read do not account, and the structural check names the
    // index; the audit reads the table in its own order, so every row is read, they account,
    // and the index is not read at all: the clean bag's result.
    let d = tempdir();
    for f in ["clean.db3", "metadata.yaml"] {
        std::fs::copy(fixtures().join("clean").join(f), d.join(f)).unwrap();
    }
    let db = d.join("clean.db3");
    sql(
        &db,
        "CREATE TABLE m2(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, \
           timestamp INTEGER NOT NULL, data BLOB NOT NULL); \
         INSERT INTO m2 SELECT * FROM messages WHERE id != 41; \
         CREATE INDEX i2 ON m2 (timestamp ASC);",
    );
    let c = rusqlite::Connection::open(&db).unwrap();
    let root = |n: &str| -> i64 {
        c.query_row(
            "SELECT rootpage FROM sqlite_master WHERE name = ?1",
            [n],
            |r| r.get(0),
        )
        .unwrap()
    };
    let (a, b) = (root("timestamp_idx"), root("i2"));
    c.execute_batch(&format!(
        "PRAGMA writable_schema = ON; \
         UPDATE sqlite_master SET rootpage = {b} WHERE name = 'timestamp_idx'; \
         UPDATE sqlite_master SET rootpage = {a} WHERE name = 'i2'; \
         PRAGMA writable_schema = OFF;"
    ))
    .unwrap();
    drop(c);
    expect_err(
        audit(&d, None),
        &db.display().to_string(),
        &[
            "damaged SQLite file (its rows are not the ids 1 to the metadata's message_count",
            "wrong # of entries in index",
        ],
    );
    same_result(
        &audit(&fixtures().join("clean"), None).unwrap(),
        &pacs_audit::audit_file(&d, &cfg).unwrap(),
    );
}

/// The bag directories of `python/tests/fixtures/mcap_bags` (the same runs, written by `rosbags`
/// in the MCAP storage, `storage_identifier: mcap`).
fn mcap_bags() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../python/tests/fixtures/mcap_bags")
}

/// Replace `from` by `to` in the bag's `metadata.yaml` (which must contain `from`).
fn edit_metadata(bag: &Path, from: &str, to: &str) {
    let p = bag.join("metadata.yaml");
    let text = std::fs::read_to_string(&p).unwrap();
    assert!(text.contains(from), "{} lacks {from:?}", p.display());
    std::fs::write(&p, text.replace(from, to)).unwrap();
}

/// Copy the bag directory `from` into `d` (as `name`).
fn copy_bag(from: &Path, d: &Path, name: &str) -> PathBuf {
    let to = d.join(name);
    std::fs::create_dir_all(&to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
    }
    to
}

/// A rosbag2 bag in the MCAP storage (ROS 2 Iron's and Jazzy's default) is audited as its
/// directory: its `.mcap` parts in the metadata's order, one log, the header from the
/// metadata's `custom_data`; the result is that of the same run's sqlite3 bag (one file, or
/// two parts split at 0.5 s), named by the directory.
#[test]
fn mcap_bags_audit_as_their_db3_twins() {
    let cfg = AuditConfig::default();
    for (name, verdict) in [
        ("clean", Verdict::Pass),
        ("violation", Verdict::Fail),
        ("split", Verdict::Fail),
    ] {
        let bag = mcap_bags().join(name);
        let r = pacs_audit::audit_file(&bag, &cfg).unwrap();
        assert_eq!(r.verdict, verdict, "{name}");
        assert_eq!(r.log, bag.display().to_string());
        same_result(
            &pacs_audit::audit_file(&fixtures().join(name), &cfg).unwrap(),
            &r,
        );
    }
    // The split bag's parts read as one log equal the one-file bag of the same run.
    same_result(
        &audit(&mcap_bags().join("violation"), None).unwrap(),
        &audit(&mcap_bags().join("split"), None).unwrap(),
    );
}

/// What an MCAP bag directory must be: every listed part there and no unlisted `.mcap` part
/// (either would leave part of the recording unread), parts listed in time order (the second
/// part first is put back in order within the reordering window, refused beyond it, never
/// reordered silently), each part complete (a part
/// cut short is refused), no compression, and a header (custom_data or `--header`).
#[test]
fn mcap_bags_that_do_not_describe_the_recording_are_refused() {
    let d = tempdir();
    let split = mcap_bags().join("split");
    let meta = |bag: &Path| std::fs::read_to_string(bag.join("metadata.yaml")).unwrap();
    // A listed part missing.
    let bag = copy_bag(&split, &d, "missing");
    std::fs::remove_file(bag.join("split_1.mcap")).unwrap();
    expect_err(
        audit(&bag, None),
        &name_of(&bag),
        &["relative_file_paths[1]", "is not a file"],
    );
    // A part not listed (its `files` entry left: the metadata contradicts itself).
    let bag = copy_bag(&split, &d, "unlisted");
    edit_metadata(&bag, "  - split_1.mcap\n", "");
    expect_err(
        audit(&bag, None),
        &name_of(&bag),
        &[
            "contradicts itself",
            "files[1].path `split_1.mcap` is not in relative_file_paths (split_0.mcap)",
        ],
    );
    // The parts listed in the wrong order.
    let bag = copy_bag(&split, &d, "reversed");
    edit_metadata(
        &bag,
        "  - split_0.mcap\n  - split_1.mcap\n",
        "  - split_1.mcap\n  - split_0.mcap\n",
    );
    // Within the reordering window (the whole 1 s run) the messages are put back in order...
    same_result(&audit(&split, None).unwrap(), &audit(&bag, None).unwrap());
    // ... beyond it (a 0.1 s window), time going backwards is refused.
    let mut cfg = AuditConfig::default();
    cfg.mcap.reorder_window = 0.1;
    let mut r = open_log(&bag, &cfg, None).unwrap();
    expect_err(
        pacs_audit::audit_reader(r.as_mut(), &cfg),
        &bag.join("split_0.mcap").display().to_string(),
        &["out of time order"],
    );
    // The second part cut short.
    let bag = copy_bag(&split, &d, "cut");
    let part = bag.join("split_1.mcap");
    let bytes = std::fs::read(&part).unwrap();
    std::fs::write(&part, &bytes[..bytes.len() / 2]).unwrap();
    expect_err(
        audit(&bag, None),
        &bag.join("split_1.mcap").display().to_string(),
        &["truncated file"],
    );
    // A part missing together with its listing: the recorder's counts tell.
    let bag = copy_bag(&split, &d, "dropped");
    std::fs::remove_file(bag.join("split_1.mcap")).unwrap();
    edit_metadata(&bag, "  - split_1.mcap\n", "");
    // Its `files` entry left: the metadata contradicts itself.
    expect_err(
        audit(&bag, None),
        &name_of(&bag),
        &["contradicts itself", "files[1].path `split_1.mcap`"],
    );
    // Its `files` entry removed too (the counts per file then add up to less than the bag's).
    let text = meta(&bag);
    let entry = text.find("  - duration:\n").and_then(|first| {
        text[first + 1..]
            .find("  - duration:\n")
            .map(|second| first + 1 + second)
    });
    let start = entry.expect("the fixture lists two files");
    // Up to the bag's own count (indented two spaces, the entries' four).
    let end = text[start..]
        .find("\n  message_count:")
        .map_or(text.len(), |e| start + e + 1);
    std::fs::write(
        bag.join("metadata.yaml"),
        format!("{}{}", &text[..start], &text[end..]),
    )
    .unwrap();
    let e = expect_err(audit(&bag, None), &name_of(&bag), &["message_count"]);
    assert!(
        e.contains("add up to") || e.contains("a part is missing"),
        "{e}"
    );
    // A custom_data header whose robot model does not exist: the error names the metadata.
    let bag = copy_bag(&mcap_bags().join("clean"), &d, "bad_robot");
    edit_metadata(&bag, "\"fr3\"", "\"fr9\"");
    expect_err(audit(&bag, None), &name_of(&bag), &["fr9"]);
    // A watched topic the metadata counts but no file has a channel for (the part holding it
    // dropped with its listing): its count (not 0) tells.
    let bag = copy_bag(&mcap_bags().join("clean"), &d, "ghost");
    edit_metadata(
        &bag,
        "topics_with_message_count:\n",
        "topics_with_message_count:\n  - message_count: 5\n    topic_metadata:\n      name: /humans/ghost/keypoints\n",
    );
    expect_err(
        audit(&bag, None),
        &name_of(&bag),
        &["`/humans/ghost/keypoints` has message_count 5", "hold 0"],
    );
    // Compressed (rosbag2's file compression).
    let bag = copy_bag(&split, &d, "compressed");
    edit_metadata(&bag, "compression_mode: ''", "compression_mode: FILE");
    expect_err(
        audit(&bag, None),
        &name_of(&bag),
        &["compressed bags are not supported"],
    );
    // No header in the metadata: an error, unless one is given.
    let bag = copy_bag(&mcap_bags().join("clean"), &d, "no_header");
    let text: String = meta(&bag)
        .lines()
        .filter(|l| {
            !l.contains("custom_data") && !l.contains("pacs_header") && !l.contains("\"fr3\"")
        })
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(bag.join("metadata.yaml"), text).unwrap();
    expect_err(
        audit(&bag, None),
        &bag.join("clean.mcap").display().to_string(),
        &["missing header"],
    );
    assert_eq!(audit(&bag, Some(&header())).unwrap().verdict, Verdict::Pass);
}

/// A bag with rosbag2's message compression (`compression_mode: message`, `compression_format:
/// zstd`, written by `rosbags`: `violation_zstd`) reads each payload decompressed and gives the
/// uncompressed bag's result. A payload that is not a zstd frame stating its size, or whose frame
/// does not hold what it states, is an error naming the message; file compression is still
/// refused.
#[test]
fn message_compressed_bags_read_as_their_uncompressed_twins() {
    let zstd = fixtures().join("violation_zstd");
    let meta = std::fs::read_to_string(zstd.join("metadata.yaml")).unwrap();
    assert!(meta.contains("compression_mode: message"), "{meta}");
    let r = audit(&zstd, None).unwrap();
    assert_eq!(r.verdict, Verdict::Fail);
    same_result(&audit(&fixtures().join("violation"), None).unwrap(), &r);
    same_result(
        &pacs_audit::audit_file(&zstd, &AuditConfig::default()).unwrap(),
        &r,
    );
    let d = tempdir();
    let bag = copy_bag(&zstd, &d, "damaged");
    let db = bag.join("violation_zstd.db3");
    let first_pose = "(SELECT min(m.id) FROM messages m JOIN topics t ON m.topic_id = t.id WHERE t.name = '/human/keypoints')";
    for (data, words) in [
        // Not a zstd frame.
        ("x'00010000'", &["is not a zstd frame"][..]),
        // A frame header without its content size (single segment off, no size field).
        ("x'28b52ffd0058'", &["does not state its size"][..]),
    ] {
        sql(
            &db,
            &format!("UPDATE messages SET data = {data} WHERE id = {first_pose}"),
        );
        let e = expect_err(audit(&bag, None), &db.display().to_string(), words);
        assert!(
            e.contains("message id ") && e.contains("/human/keypoints"),
            "{e}"
        );
    }
    // A frame stating more bytes than it holds: cut the first pose message's frame short.
    let bag = copy_bag(&zstd, &d, "cut");
    let db = bag.join("violation_zstd.db3");
    sql(
        &db,
        &format!(
            "UPDATE messages SET data = substr(data, 1, length(data) - 4) WHERE id = {first_pose}"
        ),
    );
    let e = expect_err(
        audit(&bag, None),
        &db.display().to_string(),
        &["zstd frame"],
    );
    assert!(e.contains("/human/keypoints"), "{e}");
    // File compression: refused.
    let bag = copy_bag(&zstd, &d, "file");
    std::fs::write(
        bag.join("metadata.yaml"),
        meta.replace("compression_mode: message", "compression_mode: file"),
    )
    .unwrap();
    expect_err(
        audit(&bag, None),
        &name_of(&bag),
        &["compressed bags are not supported", "`file`"],
    );
}

/// A part of a split bag given alone beside a `metadata.yaml` that cannot be read — a
/// directory, or a dangling link — is refused (whether it is the whole recording cannot be
/// told), and so is the directory as a bag; never audited as a whole run.
#[cfg(unix)]
#[test]
fn a_part_beside_unreadable_metadata_is_refused() {
    let split = fixtures().join("split");
    for (case, make) in [
        (
            "dir",
            &(|m: &Path| std::fs::create_dir(m).unwrap()) as &dyn Fn(&Path),
        ),
        ("dangling", &|m: &Path| {
            std::os::unix::fs::symlink("/nonexistent/metadata.yaml", m).unwrap()
        }),
    ] {
        let d = tempdir();
        for f in ["split_0.db3", "split_1.db3"] {
            std::fs::copy(split.join(f), d.join(f)).unwrap();
        }
        make(&d.join("metadata.yaml"));
        let part = d.join("split_0.db3");
        let e = audit(&part, None).unwrap_err().to_string();
        assert!(
            e.contains("cannot be read as a bag's metadata"),
            "{case}: {e}"
        );
        assert!(audit(&d, None).is_err(), "{case}: the directory as a bag");
    }
}

/// A topic recorded on two connections (publishers with different QoS) is listed twice in
/// `topics_with_message_count`, each entry with its connection's count: the topic's messages
/// are compared with the sum. Entries of 60 and 41 describe the 101 `/joint_states` messages
/// (a pass); 60 and 42 count one more than the files hold (cut short), and one entry of 60
/// alone fewer (not these files).
#[test]
fn a_topic_listed_once_per_connection_is_compared_by_its_total() {
    let meta = std::fs::read_to_string(fixtures().join("clean/metadata.yaml")).unwrap();
    let db = fixtures().join("clean/clean.db3");
    let entry = "  - message_count: 101\n    topic_metadata:\n      name: /joint_states\n";
    assert!(meta.contains(entry));
    let split = |a: u64, b: u64| {
        let two = format!(
            "  - message_count: {a}\n    topic_metadata:\n      name: /joint_states\n      type: sensor_msgs/msg/JointState\n  - message_count: {b}\n    topic_metadata:\n      name: /joint_states\n"
        );
        let d = tempdir();
        std::fs::copy(&db, d.join("clean.db3")).unwrap();
        std::fs::write(d.join("metadata.yaml"), meta.replace(entry, &two)).unwrap();
        d
    };
    let d = split(60, 41);
    assert_eq!(audit(&d, None).unwrap().verdict, Verdict::Pass);
    let d = split(60, 42);
    expect_err(
        audit(&d, None),
        &name_of(&d),
        &[
            "`/joint_states` has message_count 102",
            "hold 101",
            "cut short",
        ],
    );
    let d = split(60, 0);
    expect_err(
        audit(&d, None),
        &name_of(&d),
        &["has message_count 60", "does not describe these files"],
    );
}

/// A log inside a bag directory that is not one of the bag's files — another form (JSON Lines,
/// MCAP in an sqlite3 bag) or one in a subdirectory — is refused, naming it: read as the bag, it
/// would go unaudited (also in a fleet's archive, whose walk takes the bag directory as one log).
#[test]
fn a_log_inside_a_bag_directory_that_is_not_the_bag_is_refused() {
    let src = fixtures().join("clean");
    for (rel, body) in [
        ("notes.jsonl", "{}\n"),
        ("other.mcap", ""),
        ("rerun/x.db3", ""),
        ("a/b/c.csv", ""),
    ] {
        let d = tempdir();
        for f in ["clean.db3", "metadata.yaml"] {
            std::fs::copy(src.join(f), d.join(f)).unwrap();
        }
        let p = d.join(rel);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(&p, body).unwrap();
        expect_err(
            audit(&d, None),
            &name_of(&d),
            &[&p.display().to_string(), "not one of the bag's files"],
        );
    }
    // Other files (notes, scripts) are no logs: the bag passes.
    let d = tempdir();
    for f in ["clean.db3", "metadata.yaml"] {
        std::fs::copy(src.join(f), d.join(f)).unwrap();
    }
    std::fs::write(d.join("README.txt"), "recorded on cell 3\n").unwrap();
    assert_eq!(audit(&d, None).unwrap().verdict, Verdict::Pass);
}

/// A `.db3` given alone whose `metadata.yaml` beside it lists it as the bag's only part is read as
/// that bag: in Humble's layout (no `metadata` table in the file) its header comes from the
/// metadata's `custom_data` (none given), and rows deleted from it are refused by the metadata's
/// counts, as when the directory is given.
#[test]
fn a_lone_db3_described_by_the_metadata_beside_it_is_read_as_its_bag() {
    let src = fixtures().join("clean");
    let d = tempdir();
    for f in ["clean.db3", "metadata.yaml"] {
        std::fs::copy(src.join(f), d.join(f)).unwrap();
    }
    let file = d.join("clean.db3");
    sql(&file, "DROP TABLE metadata; VACUUM;");
    let whole = audit(&file, None).unwrap();
    assert_eq!(whole.verdict, Verdict::Pass);
    same_result(&whole, &audit(&d, None).unwrap());
    sql(
        &file,
        "DELETE FROM messages WHERE id IN (SELECT id FROM messages ORDER BY timestamp DESC LIMIT 5);",
    );
    let by_dir = audit(&d, None).unwrap_err().to_string();
    let by_file = audit(&file, None).unwrap_err().to_string();
    assert_eq!(by_file, by_dir);
    assert!(by_file.contains("it holds 108"), "{by_file}");
}

/// An MCAP-storage bag with rosbag2's per-message zstd compression (read for sqlite3 bags) is
/// refused with a message that says so, not one that calls that form supported.
#[test]
fn an_mcap_bag_with_message_compression_is_refused_saying_why() {
    let d = tempdir();
    let bag = copy_bag(&mcap_bags().join("clean"), &d, "zstd");
    edit_metadata(&bag, "compression_mode: ''", "compression_mode: message");
    edit_metadata(&bag, "compression_format: ''", "compression_format: zstd");
    expect_err(
        audit(&bag, None),
        &name_of(&bag),
        &[
            "`message`",
            "`zstd`",
            "sqlite3 bags only",
            "not in the MCAP storage",
        ],
    );
}

/// An MCAP file whose own Statistics record counts more (or fewer) messages on a configured
/// topic's channel than the file holds contradicts itself (messages cut out, or added): refused,
/// naming the channel and topic. The file given alone (away from its bag's metadata), with the
/// header given: untouched it passes.
#[test]
fn an_mcap_file_whose_statistics_disagree_with_its_messages_is_refused() {
    let src = std::fs::read(mcap_bags().join("clean/clean.mcap")).unwrap();
    let u64_at = |b: &[u8], i: usize| u64::from_le_bytes(b[i..i + 8].try_into().unwrap());
    // The footer: opcode, length, summary start, summary offset start, summary CRC (4 bytes).
    let footer = src.len() - 8 - (1 + 8 + 20);
    assert_eq!(src[footer], 0x02);
    let summary = u64_at(&src, footer + 9) as usize;
    // The Statistics record's channel_message_counts entries (u16 id, u64 count).
    let mut at = summary;
    let mut entries = None;
    while at < footer {
        let len = u64_at(&src, at + 1) as usize;
        if src[at] == 0x0b {
            entries = Some(at + 9 + 42 + 4);
        }
        at += 9 + len;
    }
    let first = entries.expect("a Statistics record");
    // Entry 1 is `/joint_states` (channel 2, 101 messages).
    let count_at = first + 10 + 2;
    assert_eq!(u64_at(&src, count_at), 101);
    let d = tempdir();
    let write = |k: u64| {
        let mut b = src.clone();
        b[count_at..count_at + 8].copy_from_slice(&k.to_le_bytes());
        // Summary CRC 0: not checked (MCAP spec), so the edited summary reads.
        b[footer + 9 + 16..footer + 9 + 20].copy_from_slice(&0u32.to_le_bytes());
        let p = d.join(format!("stats_{k}.mcap"));
        std::fs::write(&p, b).unwrap();
        p
    };
    assert_eq!(
        audit(&write(101), Some(&header())).unwrap().verdict,
        Verdict::Pass
    );
    for (k, why) in [(102, "messages were cut out"), (100, "messages were added")] {
        let p = write(k);
        expect_err(
            audit(&p, Some(&header())),
            &p.display().to_string(),
            &[
                &format!("Statistics record counts {k} messages on channel 2 (`/joint_states`)"),
                "the file holds 101",
                why,
            ],
        );
    }
}

/// A header given in place of a bag's own (`--header`) keeps the `start` and `end` events the
/// bag's `custom_data` header promises, in both storages: the bag, promising events it does not
/// hold (as if cut short), is `incomplete_log` whether its own header or a given one without
/// promises is used, and never passes.
#[test]
fn a_given_header_keeps_a_bags_own_promises() {
    let d = tempdir();
    let given = Header::new(
        ModelRef::Name("fr3".into()),
        ModelRef::Name("default".into()),
        ModelRef::Name("ssm".into()),
    );
    for (from, name) in [
        (fixtures().join("clean"), "db3"),
        (mcap_bags().join("clean"), "mcap"),
    ] {
        let bag = copy_bag(&from, &d, name);
        edit_metadata(
            &bag,
            "\"version\": 1, \"robot\":\n      \"fr3\", \"human\": \"default\", \"constraints\": \"ssm\"}'",
            "\"version\": 2, \"robot\": \"fr3\", \"humans\": [{\"id\": \"human\", \"human\": \"default\"}], \"end_event\": true, \"start_event\": true, \"constraints\": \"ssm\"}'",
        );
        for h in [None, Some(&given)] {
            let r = audit(&bag, h).unwrap();
            assert_eq!(
                r.evidence.completeness,
                pacs_audit::Completeness::Incomplete,
                "{name}, given: {}",
                h.is_some()
            );
            assert_ne!(r.verdict, Verdict::Pass, "{name}");
            assert_eq!(
                r.meta.get("own_header_replaced"),
                h.is_some().then_some(&serde_json::Value::Bool(true)),
                "{name}"
            );
        }
    }
}
