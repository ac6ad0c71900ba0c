//! Log format v2: several people in one audited run, the end-event promise (a log cut short is
//! never a pass), exact duplicates, and evidence that covers no time or cannot resolve it.

#[path = "audit_common/mod.rs"]
mod audit_common;

use audit_common::*;
use pacs_audit::{AuditConfig, Completeness, InconclusiveReason, Verdict};
use pacs_log::{Header, LogWriter, ModelRef, PersonEntry};

const W: f64 = 0.5; // rad/s of joint 1

fn people(ids: &[&str]) -> Vec<PersonEntry> {
    ids.iter()
        .map(|id| PersonEntry {
            id: id.to_string(),
            human: ModelRef::Name("default".into()),
        })
        .collect()
}

/// A v2 log of 101 samples (0.1 s) of the FR3 turning joint 1 at `W`, with the people `ids`;
/// `measure(i, t)` gives person i's keypoints at t (None: no record). Ends with the `end` event.
fn two_person_log(ids: &[&str], measure: impl Fn(usize, f64) -> Option<Vec<[f64; 3]>>) -> String {
    let mut w = LogWriter::new(Vec::new());
    let h = Header::with_people(
        ModelRef::Name("fr3".into()),
        people(ids),
        ModelRef::Name("ssm".into()),
    );
    w.write_header(&h).unwrap();
    let dq = [W, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    for i in 0..=100 {
        let t = i as f64 * 1e-3;
        if i % 10 == 0 {
            for (k, id) in ids.iter().enumerate() {
                if let Some(kp) = measure(k, t) {
                    w.write_person(t, t, Some(id), &kp).unwrap();
                }
            }
        }
        w.write_robot(t, &q_at(W * t), Some(&dq)).unwrap();
    }
    w.write_event(0.1, pacs_log::END_EVENT).unwrap();
    String::from_utf8(w.finish().unwrap()).unwrap()
}

fn audit(text: &str) -> pacs_audit::RunResult {
    run(text, &AuditConfig::default()).unwrap()
}

/// The operator far, the visitor's hand on the gripper at t = 0: a failing run whose violations
/// name the visitor; the same run with the roles swapped names the operator. Either person
/// alone near the robot makes the run fail: the audit checks every person, not the first.
#[test]
fn every_person_is_checked_and_violations_name_the_person() {
    let touching = reaching(hand_contact(&q_at(0.0), 0.02));
    let far = standing(2.5, 0.0);
    for near in [0usize, 1] {
        let text = two_person_log(&["operator", "visitor"], |k, t| {
            Some(if k == near && t == 0.0 {
                touching.clone()
            } else {
                far.clone()
            })
        });
        let r = audit(&text);
        assert_eq!(r.verdict, Verdict::Fail, "near = {near}");
        assert_eq!(r.people, vec!["operator", "visitor"]);
        let name = ["operator", "visitor"][near];
        assert!(!r.violations.is_empty());
        assert!(
            r.violations
                .iter()
                .all(|v| v.person.as_deref() == Some(name)),
            "{:?}",
            r.violations
        );
        assert_eq!(r.evidence.completeness, Completeness::Complete);
        // Spans of 1 ms until the next measurement (10 ms later) use the touching one.
        assert!(r.metrics.violating_samples >= 1);
        assert_eq!(r.metrics.human_records, 22);
    }
    // Both far: pass, over the whole 0.1 s.
    let text = two_person_log(&["operator", "visitor"], |_, _| Some(far.clone()));
    let r = audit(&text);
    assert_eq!(r.verdict, Verdict::Pass, "{:?}", r.inconclusive);
    assert_eq!((r.evidence.t_start, r.evidence.t_end), (0.0, 0.1));
}

/// Both people touching at t = 0: the violating samples are counted once (the union), not once
/// per person.
#[test]
fn violating_samples_are_counted_once_across_people() {
    let touching = reaching(hand_contact(&q_at(0.0), 0.02));
    let far = standing(2.5, 0.0);
    let one = audit(&two_person_log(&["a", "b"], |k, t| {
        Some(if k == 0 && t == 0.0 {
            touching.clone()
        } else {
            far.clone()
        })
    }));
    let both = audit(&two_person_log(&["a", "b"], |_, t| {
        Some(if t == 0.0 {
            touching.clone()
        } else {
            far.clone()
        })
    }));
    assert_eq!(
        both.metrics.violating_samples,
        one.metrics.violating_samples
    );
    assert!(
        both.violations
            .iter()
            .any(|v| v.person.as_deref() == Some("a"))
    );
    assert!(
        both.violations
            .iter()
            .any(|v| v.person.as_deref() == Some("b"))
    );
}

/// A person who is never measured leaves every span unchecked for that person: inconclusive,
/// reason `no_human` naming the person.
#[test]
fn a_person_never_measured_is_inconclusive_and_named() {
    let far = standing(2.5, 0.0);
    let r = audit(&two_person_log(&["operator", "visitor"], |k, _| {
        (k == 0).then(|| far.clone())
    }));
    assert_eq!(r.verdict, Verdict::Inconclusive);
    assert!(
        r.inconclusive
            .iter()
            .all(|s| s.reason == InconclusiveReason::NoHuman
                && s.person.as_deref() == Some("visitor"))
    );
    assert!(!r.inconclusive.is_empty());
}

/// Bad people: an undeclared id, a record without id among several people, two people with
/// one id, a v1 header with `humans` — each a clear error naming the problem.
#[test]
fn bad_person_ids_are_errors() {
    let far = standing(2.5, 0.0);
    let text = two_person_log(&["operator", "visitor"], |_, _| Some(far.clone()));
    // Edit the records, not the header (line 1).
    let in_records = |from: &str, to: &str| {
        let (head, rest) = text.split_once('\n').unwrap();
        format!("{head}\n{}", rest.replace(from, to))
    };
    let undeclared = in_records("\"id\":\"visitor\"", "\"id\":\"stranger\"");
    let e = run(&undeclared, &AuditConfig::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("id `stranger` is not a person of the header")
            && e.contains("operator, visitor"),
        "{e}"
    );
    let no_id = in_records("\"id\":\"visitor\",", "");
    let e = run(&no_id, &AuditConfig::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("no `id`") && e.contains("several people"), "{e}");
    let twice = text.replacen("\"id\":\"visitor\"", "\"id\":\"operator\"", 1);
    let e = run(&twice, &AuditConfig::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("line 1")
            && e.contains("header.humans[1].id")
            && e.contains("two people with one id"),
        "{e}"
    );
    let v1 = text.replacen("\"version\":2", "\"version\":1", 1);
    let e = run(&v1, &AuditConfig::default()).unwrap_err().to_string();
    assert!(e.contains("header.human"), "{e}");
}

/// A log whose writer promised the end event: complete, it passes; cut at any line boundary
/// before its end (or with the end event removed), it is `incomplete_log`, never `pass`.
#[test]
fn a_log_cut_short_is_never_a_pass() {
    let far = standing(2.5, 0.0);
    let text = two_person_log(&["operator"], |_, _| Some(far.clone()));
    let full = audit(&text);
    assert_eq!(full.verdict, Verdict::Pass, "{:?}", full.inconclusive);
    assert_eq!(full.evidence.completeness, Completeness::Complete);
    let lines: Vec<&str> = text.lines().collect();
    for keep in [3, 20, lines.len() / 2, lines.len() - 1] {
        let cut: String = lines[..keep].iter().map(|l| format!("{l}\n")).collect();
        let r = audit(&cut);
        assert_ne!(r.verdict, Verdict::Pass, "cut after {keep} lines");
        assert_eq!(r.evidence.completeness, Completeness::Incomplete);
        assert!(
            r.inconclusive
                .iter()
                .any(|s| s.reason == InconclusiveReason::IncompleteLog),
            "cut after {keep} lines: {:?}",
            r.inconclusive
        );
    }
    // The end event present but the samples stop before it.
    let early = text.replace(
        "{\"type\":\"event\",\"t\":0.1,\"name\":\"end\"}",
        "{\"type\":\"event\",\"t\":0.2,\"name\":\"end\"}",
    );
    let r = audit(&early);
    assert_eq!(r.verdict, Verdict::Inconclusive);
    let s = r
        .inconclusive
        .iter()
        .find(|s| s.reason == InconclusiveReason::IncompleteLog)
        .unwrap();
    assert_eq!((s.t_start, s.t_end), (0.1, 0.2));
    // A record after the end event is an error.
    let after = format!("{text}{{\"type\":\"event\",\"t\":0.3,\"name\":\"late\"}}\n");
    let e = run(&after, &AuditConfig::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("after the `end` event"), "{e}");
    // A v1 log promises nothing: its completeness is not promised, and it passes as before.
    let mut log = Log::new(ssm());
    log.human(0.0, &far);
    for i in 0..=10 {
        log.robot(i as f64 * 1e-3, &Q_READY, None);
    }
    let r = audit(&log.text());
    assert_eq!(r.verdict, Verdict::Pass);
    assert_eq!(r.evidence.completeness, Completeness::NotPromised);
}

/// An exact duplicate of a measurement record (same stamps, same values) is no contradiction;
/// one that differs beyond the model still is.
#[test]
fn exact_duplicates_are_not_contradictions() {
    let far = standing(2.5, 0.0);
    let text = two_person_log(&["operator"], |_, _| Some(far.clone()));
    let first_human = text.lines().nth(1).unwrap();
    assert!(first_human.contains("\"type\":\"human\""));
    let doubled = text.replacen(first_human, &format!("{first_human}\n{first_human}"), 1);
    let r = audit(&doubled);
    assert_eq!(r.verdict, Verdict::Pass, "{:?}", r.inconclusive);
    // Moved at the same stamp: contradicts the model (no measurement error, no time to move).
    // 1 m contradicts the neighbours in time as well; 1 cm only the record at the same stamp
    // (10 ms later the model allows 2 cm), so only the equal-stamp check can flag it.
    for shifted in ["[3.5,", "[2.51,"] {
        let moved = first_human.replace("[2.5,", shifted);
        let r = audit(&text.replacen(first_human, &format!("{first_human}\n{moved}"), 1));
        assert!(
            r.inconclusive
                .iter()
                .any(|s| s.reason == InconclusiveReason::HumanExceedsModel),
            "{shifted}: {:?}",
            r.inconclusive
        );
    }
}

/// The 20-sample log that fails from t = 0 does not pass from t = 10¹⁶ s, where doubles are 2 s
/// apart and cannot resolve its 50 ms steps.
#[test]
fn stamps_that_cannot_resolve_the_samples_are_not_evidence() {
    let touching = reaching(hand_contact(&q_at(0.0), 0.02));
    let log_from = |t0: f64| {
        let mut log = Log::new(ssm());
        log.human(t0, &touching);
        for i in 0..20 {
            let t = t0 + i as f64 * 0.05;
            log.robot(t, &q_at(0.01 * i as f64), None);
        }
        log.text()
    };
    assert_eq!(audit(&log_from(0.0)).verdict, Verdict::Fail);
    let r = audit(&log_from(1e16));
    assert_ne!(r.verdict, Verdict::Pass, "{:?}", r);
}

/// 10⁴ samples of a moving robot at one time stamp cover no time: not a pass.
#[test]
fn a_log_that_covers_no_time_is_not_a_pass() {
    let far = standing(2.5, 0.0);
    let mut log = Log::new(ssm());
    log.human(1.0, &far);
    let dq = [0.3, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    for _ in 0..10_000 {
        log.robot(1.0, &Q_READY, Some(&dq));
    }
    let r = audit(&log.text());
    assert_ne!(r.verdict, Verdict::Pass);
    assert!(
        r.inconclusive
            .iter()
            .any(|s| s.reason == InconclusiveReason::NoTimeCovered)
    );
}

/// Records of one time stamp are held in bounded memory: more than `MAX_EQUAL_TIME` of them is
/// an input error, not gigabytes.
#[test]
fn equal_time_records_are_capped() {
    let mut text = String::from(
        "{\"type\":\"header\",\"format\":\"pacs-log\",\"version\":1,\"robot\":\"fr3\",\"human\":\"default\",\"constraints\":\"ssm\"}\n",
    );
    let line = "{\"type\":\"event\",\"t\":0.5,\"name\":\"x\"}\n";
    text.push_str(&line.repeat(pacs_log::MAX_EQUAL_TIME + 1));
    let e = run(&text, &AuditConfig::default()).unwrap_err().to_string();
    assert!(
        e.contains(&format!("line {}", pacs_log::MAX_EQUAL_TIME + 2))
            && e.contains("records at one time stamp"),
        "{e}"
    );
}

/// The fuzzers' seeds are valid logs that reach the audit (and pass): the fuzzers start from
/// inputs that exercise the checks, not only the parsers (v1 and v2, JSON Lines and CSV).
#[test]
fn the_fuzz_seeds_reach_the_audit_and_pass() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz/corpus");
    for (dir, n_min) in [("jsonl", 1), ("csv", 2)] {
        let mut n = 0;
        for e in std::fs::read_dir(root.join(dir)).unwrap() {
            let p = e.unwrap().path();
            if p.file_name()
                .unwrap()
                .to_string_lossy()
                .starts_with("close_")
            {
                continue; // a near-miss seed, not meant to pass
            }
            let r = pacs_audit::audit_file(&p, &AuditConfig::default())
                .unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            assert_eq!(
                r.verdict,
                Verdict::Pass,
                "{}: {:?}",
                p.display(),
                r.inconclusive
            );
            n += 1;
        }
        assert!(n >= n_min, "{dir}: {n} seeds");
    }
}
