//! The fleet report (`pacs_reports::fleet`): groups per robot / scene / day, verdict counts,
//! violation time as the union of intervals, worst runs, where each day comes from.

use pacs_audit::ConstraintKind;
use pacs_audit::verdict::{Metrics, ModelNames, RunResult, Verdict, Violation};
use pacs_reports::fleet::{self, expand_logs};
use serde_json::{Value, json};

fn run(log: &str, meta: Value, verdict: Verdict, violations: &[(f64, f64)]) -> RunResult {
    RunResult {
        log: log.into(),
        verdict,
        violations: violations
            .iter()
            .map(|&(a, b)| Violation {
                t_start: a,
                t_end: b,
                constraint: ConstraintKind::Ssm,
                person: None,
                body_part: "rHand".into(),
                link: "fr3_link7".into(),
                min_separation: -0.01,
                energy: 0.0,
                threshold: 0.0,
                constrained: false,
                certain: true,
                spans: 1,
                first_span: 0,
            })
            .collect(),
        inconclusive: vec![],
        metrics: Metrics {
            samples: 1001,
            human_records: 10,
            duration: 1.0,
            violation_fraction: violations.len() as f64 * 0.1,
            violating_samples: 0,
            certain_violating_samples: 0,
            // An inconclusive log left a quarter of its time unchecked.
            inconclusive_duration: if verdict == Verdict::Inconclusive {
                0.25
            } else {
                0.0
            },
            min_separation: None,
            success: None,
            safe_success: None,
        },
        evidence: pacs_audit::Evidence {
            t_start: 0.0,
            t_end: 1.0,
            completeness: pacs_audit::Completeness::Complete,
        },
        people: vec!["human".into()],
        meta: meta.as_object().cloned().unwrap_or_default(),
        models: ModelNames {
            robot: "fr3".into(),
            human: "default".into(),
            constraints: "ssm".into(),
            robot_v_max: vec![],
            robot_a_max: vec![],
            human_v_max: vec![],
            human_measurement_error_pos: 0.0,
            human_delay: 0.0,
            environment_shapes: 0,
            people: Vec::new(),
            specs: Value::Null,
        },
        series: vec![],
    }
}

#[test]
fn violation_time_is_the_union_of_the_intervals() {
    let r = run(
        "a",
        json!({}),
        Verdict::Fail,
        &[(0.5, 2.0), (0.0, 1.0), (3.0, 4.0), (3.25, 3.5)],
    );
    assert_eq!(fleet::violation_time(&r), 3.0);
    assert_eq!(
        fleet::violation_time(&run("b", json!({}), Verdict::Pass, &[])),
        0.0
    );
}

#[test]
fn days_come_from_meta_date_start_time_time_base_then_mtime() {
    let mtime = Some(1_795_824_000); // 2026-11-28T00:00:00Z
    let day = |meta: Value| fleet::day(&run("x", meta, Verdict::Pass, &[]), mtime);
    let d = |a: &str, b: &str| (a.to_string(), b.to_string());
    assert_eq!(
        day(json!({"date": "2026-01-02", "start_time": 0})),
        d("2026-01-02", "meta.date")
    );
    assert_eq!(
        day(json!({"start_time": "2026-11-28T23:30:00-05:00"})),
        d("2026-11-29", "meta.start_time")
    );
    assert_eq!(
        day(json!({"start_time": 1_700_000_000.5})),
        d("2023-11-14", "meta.start_time")
    );
    assert_eq!(
        day(json!({"mcap_time_base_s": 1_700_000_000})),
        d("2023-11-14", "meta.mcap_time_base_s")
    );
    // A sqlite3 bag's first message time, as MCAP's.
    assert_eq!(
        day(json!({"db3_time_base_s": 1_700_000_000})),
        d("2023-11-14", "meta.db3_time_base_s")
    );
    assert_eq!(
        day(json!({"db3_time_base_s": 12})),
        d("2026-11-28", "file_mtime")
    );
    // A simulated clock's time base is not a date: the file's mtime is used.
    assert_eq!(
        day(json!({"mcap_time_base_s": 12})),
        d("2026-11-28", "file_mtime")
    );
    assert_eq!(day(json!({})), d("2026-11-28", "file_mtime"));
    assert_eq!(
        fleet::day(&run("x", json!({}), Verdict::Pass, &[]), None).0,
        "unknown"
    );
    // A stated date that cannot be read is not replaced by a guess.
    let (day_, why) = day(json!({"date": "28.11.2026"}));
    assert_eq!(day_, "invalid");
    assert!(
        why.contains("meta.date") && why.contains("28.11.2026"),
        "{why}"
    );
    let (day_, why) = day(json!({"start_time": "yesterday"}));
    assert_eq!(day_, "invalid");
    assert!(
        why.contains("meta.start_time") && why.contains("yesterday"),
        "{why}"
    );
}

#[test]
fn groups_count_verdicts_and_list_the_worst_runs_whatever_the_input_order() {
    let a1 = json!({"robot_id": "arm-1", "task": "sorting", "date": "2026-11-27"});
    let a2 = json!({"robot_id": "arm-2", "scene": "cell-b", "date": "2026-11-27"});
    let runs = vec![
        run("l0", a1.clone(), Verdict::Pass, &[]),
        run("l1", a1.clone(), Verdict::Fail, &[(0.0, 0.25)]),
        run("l2", a1.clone(), Verdict::Fail, &[(0.0, 0.5)]),
        run("l3", a1.clone(), Verdict::Inconclusive, &[]),
        run("l4", a1, Verdict::Fail, &[(0.0, 0.25), (0.5, 0.75)]),
        run("l5", a2, Verdict::Fail, &[(0.0, 0.125)]),
        // No robot id or scene: the robot model's name and "-".
        run("l6", json!({"date": "2026-11-28"}), Verdict::Pass, &[]),
    ];
    let f = fleet::fleet(&runs, &[None; 7]);
    let keys: Vec<(&str, &str, &str)> = f
        .groups
        .iter()
        .map(|g| (g.robot.as_str(), g.scene.as_str(), g.day.as_str()))
        .collect();
    assert_eq!(
        keys,
        [
            ("arm-1", "sorting", "2026-11-27"),
            ("arm-2", "cell-b", "2026-11-27"),
            ("fr3", "-", "2026-11-28")
        ]
    );
    let g = &f.groups[0];
    assert_eq!(
        (
            g.counts.runs,
            g.counts.pass,
            g.counts.fail,
            g.counts.inconclusive
        ),
        (5, 1, 3, 1)
    );
    assert_eq!(g.counts.violation_time_s, 1.25);
    assert_eq!(g.counts.duration_s, 5.0);
    // l2 and l4 both 0.5 s; l4 has two intervals, so the higher fraction: first. Then l2, l1.
    let worst: Vec<&str> = g.worst.iter().map(|w| w.log.as_str()).collect();
    assert_eq!(worst, ["l4", "l2", "l1"]);
    assert_eq!(f.total.runs, 7);
    assert_eq!(
        (f.total.pass, f.total.fail, f.total.inconclusive),
        (2, 4, 1)
    );
    assert_eq!(f.total.violation_time_s, 1.375);
    let all_worst: Vec<&str> = f.worst.iter().map(|w| w.log.as_str()).collect();
    assert_eq!(all_worst, ["l4", "l2", "l1", "l5"]);
    assert!(f.groups[2].worst.is_empty());
    // The runs keep the log order; groups and worst runs do not depend on it.
    let mut reversed = runs.clone();
    reversed.reverse();
    let r = fleet::fleet(&reversed, &[None; 7]);
    assert_eq!(
        r.runs.iter().map(|x| x.log.as_str()).collect::<Vec<_>>(),
        ["l6", "l5", "l4", "l3", "l2", "l1", "l0"]
    );
    assert_eq!(r.worst, f.worst);
    for (a, b) in r.groups.iter().zip(&f.groups) {
        assert_eq!(
            (&a.robot, &a.scene, &a.day, &a.worst),
            (&b.robot, &b.scene, &b.day, &b.worst)
        );
        assert_eq!(
            (
                a.counts.runs,
                a.counts.pass,
                a.counts.fail,
                a.counts.inconclusive
            ),
            (
                b.counts.runs,
                b.counts.pass,
                b.counts.fail,
                b.counts.inconclusive
            )
        );
    }
    let md = fleet::markdown(&f);
    assert!(md.contains("| arm-1 | sorting | 2026-11-27 | 5 | 1 | 3 | 1 | 5.000 | 0.250 | 1.250 | l4 (0.500); l2 (0.500); l1 (0.250) |"), "{md}");
    assert!(md.contains("Days from meta.date: 7"), "{md}");
}

#[test]
fn a_directory_expands_to_its_sorted_log_files() {
    let d = std::env::temp_dir().join(format!("pacs-reports-fleet-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(d.join("b/c")).unwrap();
    for f in [
        "z.jsonl",
        "a.CSV",
        "b/c/m.mcap",
        "b/x.jsonl",
        "notes.txt",
        "h.json",
    ] {
        std::fs::write(d.join(f), "").unwrap();
    }
    let single = d.join("notes.txt");
    let got = expand_logs(&[single.clone(), d.clone()]).unwrap();
    let want: Vec<_> = [
        single,
        d.join("a.CSV"),
        d.join("b/c/m.mcap"),
        d.join("b/x.jsonl"),
        d.join("z.jsonl"),
    ]
    .into();
    assert_eq!(got, want);
    // What is passed over is said: other names, and a symbolic link to a directory (not
    // followed; it holds a log here).
    #[cfg(unix)]
    std::os::unix::fs::symlink(d.join("b"), d.join("linked")).unwrap();
    let listing = fleet::list_logs(&[d.join("notes.txt"), d.clone()]).unwrap();
    assert_eq!(listing.logs, want);
    let mut skipped = vec![d.join("h.json"), d.join("notes.txt")];
    #[cfg(unix)]
    skipped.insert(1, d.join("linked"));
    assert_eq!(listing.skipped, skipped);
    let names: Vec<String> = skipped.iter().map(|p| p.display().to_string()).collect();
    let note = pacs_reports::skipped_note(&names).unwrap();
    assert!(
        note.starts_with(&format!("Not audited: {} entries", names.len()))
            && names.iter().all(|n| note.contains(n.as_str())),
        "{note}"
    );
    assert_eq!(pacs_reports::skipped_note(&[]), None);
    std::fs::create_dir_all(d.join("empty/sub")).unwrap();
    let e = expand_logs(&[d.join("empty")]).unwrap_err().to_string();
    assert!(
        e.contains(&d.join("empty").display().to_string()) && e.contains("without log files"),
        "{e}"
    );
    let e = expand_logs(&[d.join("missing")]).unwrap_err().to_string();
    assert!(e.contains("missing") && e.contains("cannot read"), "{e}");
    // A log named twice (the directory and a file in it; one file by two spellings) is refused,
    // naming both paths: it would count twice in the fleet report.
    let e = expand_logs(&[d.clone(), d.join("b/x.jsonl")])
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with(&d.join("b/x.jsonl").display().to_string())
            && e.contains(&format!("same log as {}", d.join("b/x.jsonl").display()))
            && e.contains("given twice"),
        "{e}"
    );
    let e = expand_logs(&[d.join("z.jsonl"), d.join("b/../z.jsonl")])
        .unwrap_err()
        .to_string();
    assert!(e.contains("given twice"), "{e}");
    // A hard link is the same log under another name.
    std::fs::hard_link(d.join("z.jsonl"), d.join("y.jsonl")).unwrap();
    let e = expand_logs(&[d.join("z.jsonl"), d.join("y.jsonl")])
        .unwrap_err()
        .to_string();
    assert!(e.contains("given twice"), "{e}");
    std::fs::remove_file(d.join("y.jsonl")).unwrap();
    let _ = std::fs::remove_dir_all(&d);
}

/// A bag directory is made of its parts: the directory and its own `.db3` given together, and
/// two bag directories whose parts are hard links of one file, are one log given twice. Two
/// different bags, and a bag beside a log of its own, are not.
#[test]
fn a_bag_and_its_own_part_are_one_log() {
    let d = std::env::temp_dir().join(format!("pacs-fleet-bagparts-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    for bag in ["bag1", "bag2", "bag3"] {
        std::fs::create_dir_all(d.join(bag)).unwrap();
        std::fs::write(
            d.join(bag).join("metadata.yaml"),
            "rosbag2_bagfile_information: {}\n",
        )
        .unwrap();
    }
    std::fs::write(d.join("bag1/run.db3"), b"SQLite format 3\0").unwrap();
    std::fs::write(d.join("bag2/run.db3"), b"SQLite format 3\0 other").unwrap();
    std::fs::hard_link(d.join("bag1/run.db3"), d.join("bag3/run_0.db3")).unwrap();
    std::fs::write(d.join("other.jsonl"), "{}\n").unwrap();
    let twice =
        |a: &str, b: &str| fleet::refuse_twice(&[d.join(a), d.join(b)]).map_err(|e| e.to_string());
    let e = twice("bag1", "bag1/run.db3").unwrap_err();
    assert!(
        e.starts_with(&d.join("bag1/run.db3").display().to_string())
            && e.contains(&format!("same log as {}", d.join("bag1").display()))
            && e.contains("given twice"),
        "{e}"
    );
    let e = twice("bag1/run.db3", "bag1").unwrap_err();
    assert!(e.contains("given twice"), "{e}");
    let e = twice("bag1", "bag3").unwrap_err();
    assert!(e.contains("given twice"), "{e}");
    let e = twice("bag1", "bag1").unwrap_err();
    assert!(e.contains("given twice"), "{e}");
    twice("bag1", "bag2").unwrap();
    twice("bag2", "other.jsonl").unwrap();
    twice("bag2/run.db3", "bag1/run.db3").unwrap();
    let _ = std::fs::remove_dir_all(&d);
}

/// An entry with a log's name that cannot be read (a dangling link) is listed, so that its audit
/// fails naming it, instead of leaving the archive unmentioned.
#[cfg(unix)]
#[test]
fn an_unreadable_log_in_a_directory_is_listed_not_skipped() {
    let d = std::env::temp_dir().join(format!("pacs-reports-dangling-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    std::fs::write(d.join("a.jsonl"), "").unwrap();
    std::os::unix::fs::symlink(d.join("gone.jsonl"), d.join("b.jsonl")).unwrap();
    let got = expand_logs(std::slice::from_ref(&d)).unwrap();
    assert_eq!(got, vec![d.join("a.jsonl"), d.join("b.jsonl")]);
    // A FIFO with a log's name is refused before anything opens it (opening would block).
    let fifo = d.join("c.jsonl");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .is_ok_and(|s| s.success());
    if made {
        for given in [d.clone(), fifo.clone()] {
            let e = expand_logs(std::slice::from_ref(&given))
                .unwrap_err()
                .to_string();
            assert!(
                e.contains("c.jsonl") && e.contains("not a regular file"),
                "{e}"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// Hashing a log for the report never opens a FIFO (opening one waits for a writer).
#[cfg(unix)]
#[test]
fn a_fifo_is_not_hashed() {
    let d = std::env::temp_dir().join(format!("pacs-reports-fifo-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    let fifo = d.join("x.jsonl");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap();
    assert!(made.success());
    let e = pacs_reports::InputFile::hash(&fifo)
        .unwrap_err()
        .to_string();
    assert!(e.contains("not a regular file"), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}

/// Two logs that hold the same bytes under two names (a copy, not a link) are one run given
/// twice: `same_bytes` finds them (a report is then refused, naming both), and nothing else.
#[test]
fn a_copy_of_a_log_is_one_run_given_twice() {
    let f = |path: &str, sha: &str| pacs_reports::InputFile {
        path: path.into(),
        sha256: sha.into(),
        bytes: 1,
    };
    let logs = [
        f("a/run.jsonl", "aa"),
        f("c.jsonl", "cc"),
        f("b/run.jsonl", "aa"),
    ];
    let (a, b) = pacs_reports::same_bytes(&logs).unwrap();
    assert_eq!(
        (a.path.as_str(), b.path.as_str()),
        ("a/run.jsonl", "b/run.jsonl")
    );
    let msg = pacs_reports::same_bytes_message(a, b);
    assert!(
        msg.starts_with("b/run.jsonl holds the same bytes as a/run.jsonl (sha256 aa)"),
        "{msg}"
    );
    assert!(pacs_reports::same_bytes(&logs[..2]).is_none());
}
