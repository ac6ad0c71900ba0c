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
    people_log(ids, ModelRef::Name("ssm".into()), measure)
}

/// [`two_person_log`] with the task's `constraints`.
fn people_log(
    ids: &[&str],
    constraints: ModelRef<pacs_models::ConstraintSpec>,
    measure: impl Fn(usize, f64) -> Option<Vec<[f64; 3]>>,
) -> String {
    let mut w = LogWriter::new(Vec::new());
    let h = Header::with_people(ModelRef::Name("fr3".into()), people(ids), constraints);
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

/// PFL with a free-contact limit no robot reaches (1 MJ) and a clamping limit any moving robot
/// exceeds (1 nJ): the operator's hand on the gripper alone is a free contact (pass); with a
/// visitor anywhere in the cell the hand may be pressed against them, so the same contact is
/// judged as a pinch and fails, naming the operator, clamped (the shield's rule likewise).
#[test]
fn a_second_person_makes_a_pfl_contact_a_possible_pinch() {
    let pfl = || {
        ModelRef::Spec(Box::new(pacs_models::ConstraintSpec {
            name: "pinch".into(),
            default: pacs_models::Constraint::Pfl {
                unconstrained: 1e6,
                constrained: 1e-9,
            },
            regions: vec![],
        }))
    };
    let touching = reaching(hand_contact(&q_at(0.0), 0.02));
    let far = standing(2.5, 3.0);
    let alone = audit(&people_log(&["operator"], pfl(), |_, _| {
        Some(touching.clone())
    }));
    assert_eq!(alone.verdict, Verdict::Pass, "{:?}", alone.violations);
    let shared = audit(&people_log(&["operator", "visitor"], pfl(), |k, _| {
        Some(if k == 0 {
            touching.clone()
        } else {
            far.clone()
        })
    }));
    assert_eq!(shared.verdict, Verdict::Fail);
    assert!(!shared.violations.is_empty());
    assert!(
        shared.violations.iter().all(|v| v.constrained
            && v.threshold == 1e-9
            && v.person.as_deref() == Some("operator")),
        "{:?}",
        shared.violations
    );
}

/// Each person's human model is in the result (and so in the report): the operator's built-in
/// `default`, the visitor's inline `fast` (5 m/s keypoints); `models.human` names both, the
/// specs carry both under `humans`.
#[test]
fn the_result_names_every_persons_model() {
    let mut fast = pacs_models::HumanModel::builtin("default")
        .unwrap()
        .spec()
        .clone();
    fast.name = "fast".into();
    fast.v_max = vec![5.0; fast.v_max.len()];
    let people = vec![
        PersonEntry {
            id: "operator".into(),
            human: ModelRef::Name("default".into()),
        },
        PersonEntry {
            id: "visitor".into(),
            human: ModelRef::Spec(Box::new(fast)),
        },
    ];
    let mut w = LogWriter::new(Vec::new());
    w.write_header(&Header::with_people(
        ModelRef::Name("fr3".into()),
        people,
        ModelRef::Name("ssm".into()),
    ))
    .unwrap();
    let far = standing(2.5, 0.0);
    for i in 0..=10 {
        let t = i as f64 * 1e-3;
        if i == 0 {
            w.write_person(t, t, Some("operator"), &far).unwrap();
            w.write_person(t, t, Some("visitor"), &far).unwrap();
        }
        w.write_robot(t, &q_at(0.0), Some(&[0.0; 7])).unwrap();
    }
    w.write_event(0.01, pacs_log::END_EVENT).unwrap();
    let r = audit(&String::from_utf8(w.finish().unwrap()).unwrap());
    assert_eq!(r.verdict, Verdict::Pass, "{:?}", r.inconclusive);
    let m = &r.models;
    // (An inline spec is labelled as such: never presented as a built-in.)
    assert_eq!(m.human, "operator: default; visitor: fast (custom spec)");
    let ids: Vec<_> = m
        .people
        .iter()
        .map(|p| (p.id.as_str(), p.human.as_str()))
        .collect();
    assert_eq!(
        ids,
        [("operator", "default"), ("visitor", "fast (custom spec)")]
    );
    assert!(m.people[1].human_v_max.iter().all(|&v| v == 5.0));
    assert!(m.people[0].human_v_max.iter().all(|&v| v < 5.0));
    assert_eq!(m.specs["humans"]["visitor"]["name"], "fast");
    assert_eq!(m.specs["humans"]["operator"]["name"], "default");
}

/// A ball inside the robot's hand from 1.5 s to 2 s, while person A's measurement is stale and B's
/// fresh (and, in the second pair, B never measured): the object's contact fails the log whatever
/// the order of the people in the header (every pass checks the objects; an object's violations
/// are kept once). Logs written by hand (tests/data, `people_object_*`).
#[test]
fn an_objects_contact_fails_whatever_the_order_of_the_people() {
    let logs = [
        (
            include_str!("data/people_object_a_stale.jsonl"),
            include_str!("data/people_object_a_stale_b_first.jsonl"),
        ),
        (
            include_str!("data/people_object_b_never.jsonl"),
            include_str!("data/people_object_b_never_b_first.jsonl"),
        ),
    ];
    for (a_first, b_first) in logs {
        let (x, y) = (audit(a_first), audit(b_first));
        assert_eq!(x.verdict, Verdict::Fail, "{:?}", x.inconclusive);
        assert_eq!(y.verdict, Verdict::Fail, "{:?}", y.inconclusive);
        let objects = |r: &pacs_audit::RunResult| {
            let mut v: Vec<_> = r
                .violations
                .iter()
                .filter(|v| v.person.is_none())
                .map(|v| (v.t_start.to_bits(), v.t_end.to_bits(), v.link.clone()))
                .collect();
            v.sort();
            v
        };
        assert!(!objects(&x).is_empty());
        assert_eq!(objects(&x), objects(&y));
        // Kept once: no two object violations alike.
        let o = objects(&x);
        assert!(o.windows(2).all(|w| w[0] != w[1]), "{o:?}");
        assert_eq!(x.metrics.violating_samples, y.metrics.violating_samples);
    }
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
    // A malformed person entry, `end_event` or `version`: the field is named, with the value.
    let cases = [
        (
            text.replacen("{\"id\":\"visitor\",", "{", 1),
            "header.humans[1]: missing field `id`",
        ),
        (
            text.replacen("\"id\":\"visitor\"", "\"id\":5", 1),
            "header.humans[1]: invalid type: integer `5`",
        ),
        (
            text.replacen(
                "{\"id\":\"visitor\",",
                "{\"id\":\"visitor\",\"extra\":1,",
                1,
            ),
            "header.humans[1]: unknown field `extra`",
        ),
        (
            text.replacen("\"end_event\":true", "\"end_event\":\"yes\"", 1),
            "header.end_event: expected true or false, found \"yes\"",
        ),
        (
            text.replacen("\"version\":2", "\"version\":2.0", 1),
            "header.version: expected 1 or 2 (an integer), found 2.0",
        ),
    ];
    for (bad, want) in cases {
        assert_ne!(bad, text, "{want}: the edit must apply");
        let e = run(&bad, &AuditConfig::default()).unwrap_err().to_string();
        assert!(e.contains("line 1") && e.contains(want), "{want}: {e}");
    }
}

/// A log whose writer promised the start and end events: complete, it passes; cut at any line
/// boundary before its end (or with the end event removed), or cut at its beginning (the header
/// kept), it is `incomplete_log`, never `pass`.
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
    // Cut at its beginning: the header kept, the lines after it up to a robot sample dropped
    // (with the `start` event, or after it), the samples begin after the start.
    // (The `start` event comes just before the first robot sample, after the first records of
    // the people.)
    let start = lines.iter().position(|l| l.contains("\"start\"")).unwrap();
    assert!(
        lines[start + 1].contains("\"robot\""),
        "{}",
        lines[start + 1]
    );
    for from in [start + 2, 30, lines.len() / 2] {
        let from = from
            + lines[from..]
                .iter()
                .position(|l| l.contains("robot"))
                .unwrap();
        for keep_start in [false, true] {
            let head = if keep_start {
                vec![lines[0], lines[start]]
            } else {
                vec![lines[0]]
            };
            let cut: String = head
                .iter()
                .chain(&lines[from..])
                .map(|l| format!("{l}\n"))
                .collect();
            let r = audit(&cut);
            assert_ne!(
                r.verdict,
                Verdict::Pass,
                "cut {from} lines, start {keep_start}"
            );
            assert_eq!(r.evidence.completeness, Completeness::Incomplete);
            let s = r
                .inconclusive
                .iter()
                .find(|s| s.reason == InconclusiveReason::IncompleteLog)
                .unwrap();
            // From the start event (or, without it, the first sample) to the first sample.
            assert_eq!(s.t_end, r.evidence.t_start);
            assert_eq!(s.t_start, if keep_start { 0.0 } else { s.t_end });
        }
    }
    // A `start` event after the first robot sample: samples before the run's start (a log
    // glued from two) are not a complete run.
    let mut moved: Vec<&str> = lines
        .iter()
        .copied()
        .filter(|l| !l.contains("\"start\""))
        .collect();
    let at = moved
        .iter()
        .position(|l| l.contains("\"robot\"") && l.contains("\"t\":0.05,"))
        .unwrap();
    moved.insert(at + 1, "{\"type\":\"event\",\"t\":0.05,\"name\":\"start\"}");
    let late_start: String = moved.iter().map(|l| format!("{l}\n")).collect();
    let r = audit(&late_start);
    assert_eq!(r.evidence.completeness, Completeness::Incomplete);
    assert_ne!(r.verdict, Verdict::Pass);
    // A second `start` event is an error (two runs in one log).
    let twice = text.replacen(
        "{\"type\":\"event\",\"t\":0.1,\"name\":\"end\"}",
        "{\"type\":\"event\",\"t\":0.1,\"name\":\"start\"}\n{\"type\":\"event\",\"t\":0.1,\"name\":\"end\"}",
        1,
    );
    let e = run(&twice, &AuditConfig::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("a second `start` event at t = 0.1 s"), "{e}");
    // A writer that promised its end and not its start (logs of pacs before the start
    // promise): complete at its end, a cut at its beginning cannot be told.
    let end_only = text.replacen(",\"start_event\":true", "", 1).replacen(
        "{\"type\":\"event\",\"t\":0.0,\"name\":\"start\"}\n",
        "",
        1,
    );
    assert_ne!(end_only, text);
    let r = audit(&end_only);
    assert_eq!(r.verdict, Verdict::Pass, "{:?}", r.inconclusive);
    assert_eq!(r.evidence.completeness, Completeness::EndOnly);
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

/// A log of two people and an object resting on the gripper (no contact allowed) for 2 s at
/// 100 Hz: `a` and `b` give the times (s) each person is measured (far away).
fn object_on_gripper_log(a: &[f64], b: &[f64]) -> String {
    let far = |x: f64| {
        (0..9)
            .map(|i| format!("[{x}, {}, 1.0]", 0.1 * i as f64 - 0.4))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let mut s = String::from(
        r#"{"type": "header", "format": "pacs-log", "version": 2, "robot": "fr3", "constraints": "ssm", "humans": [{"id": "A", "human": "default"}, {"id": "B", "human": "default"}], "end_event": true, "objects": [{"id": "b1", "object": "ball", "contact": "no_contact"}]}"#,
    );
    s.push('\n');
    for i in 0..=200 {
        let t = f64::from(i) * 0.01;
        if i % 10 == 0 {
            for (id, times, x) in [("A", a, 3.0), ("B", b, -3.0)] {
                if times.iter().any(|m| (m - t).abs() < 1e-9) {
                    s.push_str(&format!(
                        "{{\"type\": \"human\", \"t\": {t}, \"id\": \"{id}\", \"positions\": [{}]}}\n",
                        far(x)
                    ));
                }
            }
            s.push_str(&format!(
                "{{\"type\": \"object\", \"t\": {t}, \"id\": \"b1\", \"position\": [0.307, 0.0, 0.52], \"velocity\": [0, 0, 0]}}\n"
            ));
        }
        s.push_str(&format!(
            "{{\"type\": \"robot\", \"t\": {t}, \"q\": [0.0, -0.785, 0, -2.356, 0, 1.571, 0.785], \"dq\": [0, 0, 0, 0, 0, 0, 0]}}\n"
        ));
    }
    s.push_str("{\"type\": \"event\", \"t\": 2.0, \"name\": \"end\"}\n");
    s
}

/// Each pass checks an object only where its own person lets it check the span: person A is
/// measured until 0.6 s (stale after 1.6 s), person B from 0.8 s on, so A's pass sees the
/// object's contact on [0, 1.6] and B's on [0.8, 2.0]. The result lists the contact once per
/// link, as the one interval [0, 2] that a person measured throughout gives — not
/// as two overlapping intervals.
#[test]
fn an_objects_interval_seen_in_parts_by_the_passes_is_listed_once() {
    let until = |a: f64, b: f64| -> Vec<f64> {
        (0..=20)
            .map(|i| f64::from(i) * 0.1)
            .filter(|t| *t >= a - 1e-9 && *t <= b + 1e-9)
            .collect()
    };
    let parts = audit(&object_on_gripper_log(&until(0.0, 0.6), &until(0.8, 2.0)));
    let whole = audit(&object_on_gripper_log(&until(0.0, 2.0), &[]));
    assert_eq!(parts.verdict, Verdict::Fail);
    let objects = |r: &pacs_audit::RunResult| {
        let mut v: Vec<_> = r
            .violations
            .iter()
            .filter(|v| v.person.is_none())
            .map(|v| (v.link.clone(), v.t_start, v.t_end, v.spans, v.certain))
            .collect();
        v.sort_by(|a, b| a.0.cmp(&b.0));
        v
    };
    let (p, w) = (objects(&parts), objects(&whole));
    assert!(!w.is_empty());
    assert!(
        // 200 spans and the last sample's instant (checked with the last object record).
        w.iter().all(|v| v.1 == 0.0 && v.2 == 2.0 && v.3 == 201),
        "{w:?}"
    );
    assert_eq!(p, w, "joined across the passes as one person sees it");
}

/// Joint 1 turns at `W` next to a person's hand while the logger writes `dq = 0`. With the
/// default slack and at `MAX_LIMIT_SLACK` the positions contradict the logged velocities (never a
/// pass); a slack above the cap (at 1000 the samples would be judged consistent and the robot at
/// rest) is refused.
#[test]
fn a_limit_slack_that_would_hide_a_logger_zero_velocity_is_refused() {
    let text = touching_log(W, Some([0.0; 7]), 1);
    for slack in [
        AuditConfig::default().limit_slack,
        pacs_audit::config::MAX_LIMIT_SLACK,
    ] {
        let cfg = AuditConfig {
            limit_slack: slack,
            ..AuditConfig::default()
        };
        let r = run(&text, &cfg).unwrap();
        assert_ne!(r.verdict, Verdict::Pass, "limit_slack {slack}");
        assert!(
            r.inconclusive
                .iter()
                .any(|s| s.reason == InconclusiveReason::ExceedsLimits),
            "limit_slack {slack}: the zero velocities contradict the positions"
        );
    }
    for slack in [2e-6, 1.0, 1000.0] {
        let cfg = AuditConfig {
            limit_slack: slack,
            ..AuditConfig::default()
        };
        let e = run(&text, &cfg).unwrap_err().to_string();
        assert!(e.contains("limit_slack") && e.contains("1e-6"), "{e}");
    }
}

/// A person "measured" at a tracker's lost-track value (FLT_MAX, or 10⁷ m) is no measurement of
/// anyone in the cell: the spans that use it are `human_reach_error` (never a pass), as for an
/// object beyond 10⁶ m (taken as a measurement, the person would count as far away).
#[test]
fn a_person_measured_beyond_any_reach_is_not_evidence() {
    for far in [f32::MAX as f64, 1e7, -2e6] {
        let text = two_person_log(&["op"], |_, _| Some(vec![[far, 0.0, 1.0]; 9]));
        let r = audit(&text);
        assert_eq!(r.verdict, Verdict::Inconclusive, "at {far} m");
        assert!(
            r.inconclusive
                .iter()
                .all(|s| s.reason == InconclusiveReason::HumanReachError
                    && s.person.as_deref() == Some("op")),
            "at {far} m: {:?}",
            r.inconclusive
        );
    }
    // At 10⁶ m exactly (the bound), and standing 2.5 m away: measurements of a person, passed.
    for kp in [vec![[1e6, 0.0, 1.0]; 9], standing(2.5, 0.0)] {
        let text = two_person_log(&["op"], |_, _| Some(kp.clone()));
        assert_eq!(audit(&text).verdict, Verdict::Pass);
    }
}

/// A log of `W`-turning (or resting, `w = 0`) joint 1 next to a touching hand, 1 kHz, with the
/// logged velocities `dq` (or none); each robot sample written `copies` times (a recorder that
/// wrote every message twice). With `at_end`, a person record also just before the last sample
/// (the final instant is then checked with it, as a zero-length span).
fn touching_log_ending(w_joint: f64, dq: Option<[f64; 7]>, copies: usize, at_end: bool) -> String {
    let touching = reaching(hand_contact(&q_at(0.0), 0.02));
    let mut w = LogWriter::new(Vec::new());
    let h = Header::with_people(ModelRef::Name("fr3".into()), people(&["op"]), ssm());
    w.write_header(&h).unwrap();
    for i in 0..=100 {
        let t = i as f64 * 1e-3;
        if i % 10 == 0 && (i < 100 || at_end) {
            w.write_person(t, t, Some("op"), &touching).unwrap();
        }
        for _ in 0..copies {
            w.write_robot(t, &q_at(w_joint * t), dq.as_ref().map(|v| &v[..]))
                .unwrap();
        }
    }
    w.write_event(0.1, pacs_log::END_EVENT).unwrap();
    String::from_utf8(w.finish().unwrap()).unwrap()
}

/// [`touching_log_ending`] without a person record at the last sample.
fn touching_log(w_joint: f64, dq: Option<[f64; 7]>, copies: usize) -> String {
    touching_log_ending(w_joint, dq, copies, false)
}

/// The last sample's instant, checked with a person record that arrived just before it, in a log
/// without velocities: its velocity box is the one of the span ending there. A robot at rest
/// touched by a hand (allowed under SSM) passes as it does without that record (the limits alone,
/// `[−v_max, v_max]`, would make that instant a possible violation); a turning joint fails at that instant
/// too.
#[test]
fn the_final_instant_without_velocities_is_bounded_by_the_last_span() {
    for w_joint in [0.0, W] {
        let without = audit(&touching_log(w_joint, None, 1));
        let with = audit(&touching_log_ending(w_joint, None, 1, true));
        if w_joint == 0.0 {
            assert_eq!(without.verdict, Verdict::Pass);
            assert_eq!(with.verdict, Verdict::Pass, "{:?}", with.violations);
        } else {
            assert_eq!(without.verdict, Verdict::Fail);
            assert_eq!(with.verdict, Verdict::Fail);
            // The violation runs to the last sample, whose instant is checked with the record.
            assert!(
                with.violations.iter().any(|v| v.t_end == 0.1),
                "{:?}",
                with.violations
            );
        }
    }
}

/// An exact copy of a robot sample (same stamp, same values) adds no evidence: the run audits as
/// if it were written once. Checked, without `dq` each copy would open a zero-length span whose
/// velocity box is `[−v_max, v_max]`, and a robot at rest touched by a hand (allowed under SSM)
/// would fail. A moving robot's run fails alike with or without copies.
#[test]
fn an_exact_copy_of_a_robot_sample_changes_nothing() {
    for w_joint in [0.0, W] {
        let once = audit(&touching_log(w_joint, None, 1));
        let twice = audit(&touching_log(w_joint, None, 2));
        let expect = if w_joint == 0.0 {
            Verdict::Pass
        } else {
            Verdict::Fail
        };
        assert_eq!(once.verdict, expect, "w = {w_joint}");
        assert_eq!(twice.verdict, once.verdict, "w = {w_joint}");
        assert_eq!(twice.metrics.samples, once.metrics.samples);
        assert_eq!(twice.violations, once.violations);
        assert_eq!(twice.inconclusive, once.inconclusive);
    }
}

/// `text` without its object records (the object declared, never measured).
fn without_object_records(text: &str) -> String {
    text.lines()
        .filter(|l| !l.contains("\"type\": \"object\""))
        .map(|l| format!("{l}\n"))
        .collect()
}

/// An object never measured, person A never measured, person B throughout: A's pass stops at
/// `no_human` before it reaches the objects, B's finds `no_object`. Both are reported, and the
/// object's spans name the object, whichever pass found them; a span both passes find is listed
/// once.
#[test]
fn an_objects_finding_of_any_pass_is_reported_and_names_the_object() {
    let all: Vec<f64> = (0..=20).map(|i| f64::from(i) * 0.1).collect();
    let text = without_object_records(&object_on_gripper_log(&[], &all));
    let r = audit(&text);
    assert_eq!(r.verdict, Verdict::Inconclusive);
    let about = |reason: InconclusiveReason| {
        r.inconclusive
            .iter()
            .filter(|s| s.reason == reason)
            .collect::<Vec<_>>()
    };
    let (no_human, no_object) = (
        about(InconclusiveReason::NoHuman),
        about(InconclusiveReason::NoObject),
    );
    assert!(
        !no_human.is_empty() && no_human.iter().all(|s| s.person.as_deref() == Some("A")),
        "{:?}",
        r.inconclusive
    );
    assert!(
        no_object.len() == 1
            && no_object[0].object.as_deref() == Some("b1")
            && no_object[0].person.is_none()
            // 200 spans and the last sample's instant (B's record at 2.0 s).
            && no_object[0].spans == 201,
        "{:?}",
        r.inconclusive
    );
    // Both people measured throughout: both passes find the same `no_object` span, listed once.
    let text = without_object_records(&object_on_gripper_log(&all, &all));
    let r = audit(&text);
    assert_eq!(r.verdict, Verdict::Inconclusive);
    let reasons: Vec<_> = r.inconclusive.iter().map(|s| s.reason).collect();
    assert_eq!(
        reasons,
        [InconclusiveReason::NoObject],
        "{:?}",
        r.inconclusive
    );
}

/// [`touching_log_ending`]'s run (joint 1 turning at `w_joint`, the operator's hand on the
/// gripper from t = 0, measured every 10 ms) with a ball declared far away (2.5 m, no contact
/// allowed): measured at `ball_times` (s) only, and with the operator measured until
/// `op_until` (s) only. The ball is stale 1 s after its last record, the operator likewise.
fn touching_with_ball(w_joint: f64, ball_times: &[f64], op_until: f64) -> String {
    let touching = reaching(hand_contact(&q_at(0.0), 0.02));
    let mut w = LogWriter::new(Vec::new());
    let mut h = Header::with_people(ModelRef::Name("fr3".into()), people(&["op"]), ssm());
    h.objects.push(pacs_log::ObjectEntry {
        id: "b1".into(),
        object: ModelRef::Name("ball".into()),
        contact: pacs_models::object::ObjectContact::NoContact,
    });
    w.write_header(&h).unwrap();
    for i in 0..=2000 {
        let t = i as f64 * 1e-3;
        if i % 10 == 0 && i < 2000 && t <= op_until + 1e-9 {
            w.write_person(t, t, Some("op"), &touching).unwrap();
        }
        if ball_times.iter().any(|b| (b - t).abs() < 1e-9) {
            w.write_object(t, t, "b1", [2.5, 0.0, 0.5], Some([0.0; 3]))
                .unwrap();
        }
        w.write_robot(t, &q_at(w_joint * t), None).unwrap();
    }
    w.write_event(2.0, pacs_log::END_EVENT).unwrap();
    String::from_utf8(w.finish().unwrap()).unwrap()
}

/// A person's certain contact is a violation whatever the objects' measurements: with the
/// far ball measured once at t = 0 (stale from 1 s on) or never, the slowly turning joint's
/// contact with the hand (0.15 rad/s: the hand stays on the gripper for the whole 2 s) still
/// fails the log, with the same violations as with the ball measured throughout — certain up
/// to the end of the run — and the spans the ball cannot be checked on are inconclusive as
/// well (`stale_object`, `no_object`).
#[test]
fn an_object_that_cannot_be_checked_hides_no_persons_contact() {
    const SLOW: f64 = 0.15;
    let every: Vec<f64> = (0..200).map(|i| f64::from(i) * 0.01).collect();
    let throughout = audit(&touching_with_ball(SLOW, &every, 2.0));
    assert_eq!(throughout.verdict, Verdict::Fail);
    assert!(
        throughout
            .violations
            .iter()
            .any(|v| v.t_end >= 1.99 && v.certain && v.person.as_deref() == Some("op")),
        "{:?}",
        throughout.violations
    );
    for (balls, reason) in [
        (&[0.0][..], InconclusiveReason::StaleObject),
        (&[][..], InconclusiveReason::NoObject),
    ] {
        let r = audit(&touching_with_ball(SLOW, balls, 2.0));
        assert_eq!(r.verdict, Verdict::Fail, "{reason:?}: {:?}", r.inconclusive);
        assert_eq!(r.violations, throughout.violations, "{reason:?}");
        assert!(
            r.inconclusive
                .iter()
                .any(|s| s.reason == reason && s.object.as_deref() == Some("b1")),
            "{:?}",
            r.inconclusive
        );
    }
    // At rest the hand on the gripper is allowed (SSM): the log is inconclusive for the ball,
    // never a pass, and reports no violation.
    let r = audit(&touching_with_ball(0.0, &[0.0], 2.0));
    assert_eq!(r.verdict, Verdict::Inconclusive);
    assert!(r.violations.is_empty(), "{:?}", r.violations);
}

/// The object's certain contact is a violation whatever the people's measurements: the ball
/// resting on the gripper (no contact allowed), measured throughout, while the only person is
/// measured until 0.5 s (stale from 1.5 s on): the ball's contact is reported over the whole
/// run, the person's stale stretch inconclusive as well.
#[test]
fn a_person_who_cannot_be_checked_hides_no_objects_contact() {
    let every: Vec<f64> = (0..200).map(|i| f64::from(i) * 0.01).collect();
    let on_gripper = |text: String| text.replace("[2.5,0.0,0.5]", "[0.307,0.0,0.52]");
    let text = on_gripper(touching_with_ball(0.0, &every, 0.5));
    assert!(text.contains("[0.307,0.0,0.52]"));
    let r = audit(&text);
    assert_eq!(r.verdict, Verdict::Fail, "{:?}", r.inconclusive);
    let ball: Vec<_> = r.violations.iter().filter(|v| v.person.is_none()).collect();
    assert!(
        ball.iter().any(|v| v.t_start <= 1.5 && v.t_end >= 1.99),
        "{ball:?}"
    );
    assert!(
        r.inconclusive
            .iter()
            .any(|s| s.reason == InconclusiveReason::StaleHuman && s.t_end >= 1.99),
        "{:?}",
        r.inconclusive
    );
}

/// A log whose robot samples before some time were cut out and whose `start` event was moved to
/// its new first sample still holds the shield's diagnostics of the samples cut (the shield
/// logs one after each sample): one stamped before the start shows the cut, and the log is
/// `incomplete_log`, never complete. The same log with those
/// diagnostics cut out too is indistinguishable from a run that began there (complete).
#[test]
fn shield_diagnostics_before_the_start_show_a_cut() {
    let far = standing(2.5, 0.0);
    let text = two_person_log(&["operator"], |_, _| Some(far.clone()));
    // A diagnostics record after every robot sample, as the shield writes them.
    let mut with_diag = String::new();
    for l in text.lines() {
        with_diag.push_str(l);
        with_diag.push('\n');
        let v: serde_json::Value = serde_json::from_str(l).unwrap();
        if v["type"] == "robot" {
            let t = v["t"].as_f64().unwrap();
            with_diag.push_str(&format!(
                "{{\"type\":\"shield\",\"t\":{t},\"verified\":true,\"on_failsafe\":false}}\n"
            ));
        }
    }
    let full = audit(&with_diag);
    assert_eq!(full.verdict, Verdict::Pass, "{:?}", full.inconclusive);
    assert_eq!(full.evidence.completeness, Completeness::Complete);
    // Robot samples (and the start event) before 0.05 s dropped, the start put at 0.05 s.
    let cut = |drop_diag: bool| -> String {
        let mut out = String::new();
        for l in with_diag.lines() {
            let v: serde_json::Value = serde_json::from_str(l).unwrap();
            let t = v["t"].as_f64().unwrap_or(0.0);
            let early = t < 0.05 - 1e-12;
            let drop = match v["type"].as_str() {
                Some("robot") => early,
                Some("shield") => early && drop_diag,
                Some("event") => v["name"] == "start",
                _ => false,
            };
            if v["type"] == "robot" && (t - 0.05).abs() < 1e-12 {
                out.push_str("{\"type\":\"event\",\"t\":0.05,\"name\":\"start\"}\n");
            }
            if !drop {
                out.push_str(l);
                out.push('\n');
            }
        }
        out
    };
    let r = audit(&cut(false));
    assert_ne!(r.verdict, Verdict::Pass);
    assert_eq!(r.evidence.completeness, Completeness::Incomplete);
    let s = r
        .inconclusive
        .iter()
        .find(|s| s.reason == InconclusiveReason::IncompleteLog)
        .expect("incomplete_log");
    assert_eq!((s.t_start, s.t_end), (0.0, 0.05));
    let r = audit(&cut(true));
    assert_eq!(r.verdict, Verdict::Pass, "{:?}", r.inconclusive);
    assert_eq!(r.evidence.completeness, Completeness::Complete);
}

/// A reason that lasts while another comes and goes is listed as one stretch: the ball never
/// measured (`no_object` over the whole run) while the person goes stale between 1.0 and 1.3 s
/// (no record from 0 to 1.3 s). The time counts once either way.
#[test]
fn a_lasting_reason_is_one_stretch_while_another_comes_and_goes() {
    let text: String = touching_with_ball(0.0, &[], 2.0)
        .lines()
        .filter(|l| {
            let v: serde_json::Value = serde_json::from_str(l).unwrap();
            let t = v["t"].as_f64().unwrap_or(0.0);
            !(v["type"] == "human" && t > 1e-9 && t < 1.3 - 1e-9)
        })
        .map(|l| format!("{l}\n"))
        .collect();
    let r = audit(&text);
    assert_eq!(r.verdict, Verdict::Inconclusive);
    let no_object: Vec<_> = r
        .inconclusive
        .iter()
        .filter(|s| s.reason == InconclusiveReason::NoObject)
        .collect();
    assert_eq!(no_object.len(), 1, "{:?}", r.inconclusive);
    assert_eq!((no_object[0].t_start, no_object[0].t_end), (0.0, 2.0));
    assert!(
        r.inconclusive
            .iter()
            .any(|s| s.reason == InconclusiveReason::StaleHuman),
        "{:?}",
        r.inconclusive
    );
    assert!((r.metrics.inconclusive_duration - 2.0).abs() < 1e-9);
}
