//! Bad input: every case is an error naming the file, the line and the problem; never a pass.

mod audit_common;

use audit_common::*;
use pacs_audit::AuditConfig;
use pacs_log::WriteError;
use pacs_log::{Location, LogError, LogWriter};

const HEADER: &str = r#"{"type":"header","format":"pacs-log","version":1,"robot":"fr3","human":"default","constraints":"ssm"}"#;
const HUMAN: &str = r#"{"type":"human","t":0.0,"positions":[[2,0,1],[2,0,1],[2,0,1],[2,0,1],[2,0,1],[2,0,1],[2,0,1],[2,0,1],[2,0,1]]}"#;
const ROBOT0: &str = r#"{"type":"robot","t":0.0,"q":[0,-0.785,0,-2.356,0,1.571,0.785]}"#;
const ROBOT1: &str = r#"{"type":"robot","t":0.001,"q":[0,-0.785,0,-2.356,0,1.571,0.785]}"#;

fn lines(ls: &[&str]) -> String {
    ls.iter().map(|l| format!("{l}\n")).collect()
}

/// The error for `text`, asserting it is an input error at `line` whose message contains `what`.
fn expect_error(text: &str, line: Option<u64>, what: &str) {
    let e = run(text, &AuditConfig::default()).expect_err("must be rejected");
    let msg = e.to_string();
    match &e {
        LogError::Input { file, location, .. } => {
            assert_eq!(file, "test.jsonl");
            if let Some(l) = line {
                assert_eq!(*location, Location::Line(l), "{msg}");
            }
        }
        other => panic!("unexpected error {other:?}"),
    }
    assert!(msg.starts_with("test.jsonl: "), "{msg}");
    assert!(msg.contains(what), "`{msg}` should mention `{what}`");
}

#[test]
fn valid_baseline_passes() {
    let r = run(
        &lines(&[HEADER, HUMAN, ROBOT0, ROBOT1]),
        &AuditConfig::default(),
    )
    .unwrap();
    assert_eq!(r.verdict, pacs_audit::Verdict::Pass);
}

#[test]
fn truncated_last_line() {
    let mut text = lines(&[HEADER, HUMAN, ROBOT0]);
    text.push_str(&ROBOT1[..ROBOT1.len() - 10]);
    expect_error(&text, Some(4), "truncated line");
    // A complete-looking last line without its newline is also rejected.
    let mut text = lines(&[HEADER, HUMAN, ROBOT0]);
    text.push_str(ROBOT1);
    expect_error(&text, Some(4), "truncated line");
}

#[test]
fn non_json_line() {
    expect_error(
        &lines(&[HEADER, HUMAN, "hello", ROBOT1]),
        Some(3),
        "invalid JSON",
    );
    expect_error(
        &lines(&[HEADER, HUMAN, r#"{"type":"robot","t":0.0,"q":[1,2"#, ROBOT1]),
        Some(3),
        "invalid JSON",
    );
}

#[test]
fn nan_and_infinity() {
    let nan = r#"{"type":"robot","t":0.0,"q":[NaN,-0.785,0,-2.356,0,1.571,0.785]}"#;
    expect_error(
        &lines(&[HEADER, HUMAN, nan, ROBOT1]),
        Some(3),
        "invalid JSON",
    );
    let inf = r#"{"type":"robot","t":0.0,"q":[1e999,-0.785,0,-2.356,0,1.571,0.785]}"#;
    expect_error(
        &lines(&[HEADER, HUMAN, inf, ROBOT1]),
        Some(3),
        "invalid JSON",
    );
    let inf_t = r#"{"type":"human","t":1e400,"positions":[]}"#;
    expect_error(&lines(&[HEADER, inf_t]), Some(2), "invalid JSON");
}

#[test]
fn time_going_backwards() {
    let back = r#"{"type":"robot","t":-0.5,"q":[0,-0.785,0,-2.356,0,1.571,0.785]}"#;
    expect_error(
        &lines(&[HEADER, HUMAN, ROBOT0, back]),
        Some(4),
        "time goes backwards",
    );
}

#[test]
fn wrong_joint_and_keypoint_counts() {
    let six = r#"{"type":"robot","t":0.0,"q":[0,-0.785,0,-2.356,0,1.571]}"#;
    expect_error(
        &lines(&[HEADER, HUMAN, six]),
        Some(3),
        "expected 7 joint positions",
    );
    let dq = r#"{"type":"robot","t":0.0,"q":[0,-0.785,0,-2.356,0,1.571,0.785],"dq":[0]}"#;
    expect_error(
        &lines(&[HEADER, HUMAN, dq]),
        Some(3),
        "expected 7 joint velocities",
    );
    let kp = r#"{"type":"human","t":0.0,"positions":[[2,0,1]]}"#;
    expect_error(&lines(&[HEADER, kp]), Some(2), "expected 9 keypoints");
}

#[test]
fn missing_or_bad_header() {
    expect_error(&lines(&[HUMAN, ROBOT0]), Some(1), "missing header");
    expect_error("", None, "missing header");
    let v2 = HEADER.replace("\"version\":1", "\"version\":2");
    expect_error(&lines(&[&v2, HUMAN]), Some(1), "version");
    let robot = HEADER.replace("\"fr3\"", "\"ur5\"");
    expect_error(&lines(&[&robot, HUMAN]), Some(1), "header.robot");
    expect_error(&lines(&[HEADER, HUMAN, HEADER]), Some(3), "second header");
}

/// An inline model with a missing or unknown field names that field, never
/// "did not match any variant of untagged enum".
#[test]
fn inline_models_name_their_missing_or_unknown_field() {
    // The built-in human, inline, without `keypoints`; then with an unknown field.
    let human = pacs_models::default_human().spec().clone();
    let mut v = serde_json::to_value(&human).unwrap();
    v.as_object_mut().unwrap().remove("keypoints");
    let h = HEADER.replace("\"human\":\"default\"", &format!("\"human\":{v}"));
    expect_error(&lines(&[&h, HUMAN]), Some(1), "missing field `keypoints`");
    let mut v = serde_json::to_value(&human).unwrap();
    v.as_object_mut()
        .unwrap()
        .insert("v_maximum".into(), serde_json::json!(2.0));
    let h = HEADER.replace("\"human\":\"default\"", &format!("\"human\":{v}"));
    expect_error(&lines(&[&h, HUMAN]), Some(1), "unknown field `v_maximum`");
    // A number where a model belongs says what is expected.
    let h = HEADER.replace("\"robot\":\"fr3\"", "\"robot\":7");
    expect_error(&lines(&[&h, HUMAN]), Some(1), "built-in model name");
    let bad = HEADER.replace("\"robot\":\"fr3\"", "\"robot\":{\"name\":\"x\"}");
    let e = run(&lines(&[&bad, HUMAN]), &AuditConfig::default()).unwrap_err();
    assert!(!e.to_string().contains("untagged"), "{e}");
    assert!(e.to_string().contains("missing field"), "{e}");
}

#[test]
fn unknown_record_type_and_fields() {
    expect_error(
        &lines(&[HEADER, r#"{"type":"lidar","t":0.0}"#]),
        Some(2),
        "unknown record type `lidar`",
    );
    expect_error(&lines(&[HEADER, r#"{"t":0.0}"#]), Some(2), "no `type`");
    let extra = r#"{"type":"robot","t":0.0,"q":[0,-0.785,0,-2.356,0,1.571,0.785],"qq":1}"#;
    expect_error(&lines(&[HEADER, extra]), Some(2), "unknown field `qq`");
    let no_t = r#"{"type":"robot","q":[0,-0.785,0,-2.356,0,1.571,0.785]}"#;
    expect_error(&lines(&[HEADER, no_t]), Some(2), "no `t`");
    // Shield diagnostics may carry anything.
    let shield = r#"{"type":"shield","t":0.0,"anything":{"x":[1,2]}}"#;
    assert!(
        run(
            &lines(&[HEADER, HUMAN, shield, ROBOT0, ROBOT1]),
            &AuditConfig::default()
        )
        .is_ok()
    );
}

#[test]
fn measurement_from_the_future() {
    let fut = r#"{"type":"human","t":0.0,"t_meas":0.1,"positions":[[2,0,1],[2,0,1],[2,0,1],[2,0,1],[2,0,1],[2,0,1],[2,0,1],[2,0,1],[2,0,1]]}"#;
    expect_error(&lines(&[HEADER, fut]), Some(2), "t_meas");
}

#[test]
fn writer_rejects_what_the_reader_would_reject() {
    let mut w = LogWriter::new(Vec::new());
    assert!(w.write_robot(0.0, &[0.0], None).is_err(), "header first");
    let h = pacs_log::Header::new(
        pacs_log::ModelRef::Name("fr3".into()),
        pacs_log::ModelRef::Name("default".into()),
        ssm(),
    );
    w.write_header(&h).unwrap();
    assert!(matches!(
        w.write_robot(f64::NAN, &[0.0], None),
        Err(WriteError::NotFinite { .. })
    ));
    assert!(matches!(
        w.write_robot(1.0, &[f64::INFINITY], None),
        Err(WriteError::NotFinite { .. })
    ));
    w.write_robot(1.0, &[0.0], None).unwrap();
    assert!(w.write_robot(0.5, &[0.0], None).is_err(), "time backwards");
    // Accelerations without velocities: refused (the reader would reject the line), never
    // dropped silently.
    let e = w
        .write_robot_with_acc(1.0, &[0.0], None, Some(&[0.0]))
        .unwrap_err();
    assert!(
        matches!(e, WriteError::AccelerationsWithoutVelocities),
        "{e:?}"
    );
    assert_eq!(
        e.to_string(),
        "ddq: accelerations are written only together with velocities (dq)"
    );
    w.write_robot_with_acc(1.0, &[0.0], Some(&[0.0]), Some(&[0.5]))
        .unwrap();
    let text = String::from_utf8(w.finish().unwrap()).unwrap();
    assert!(
        text.ends_with(
            "{\"type\":\"robot\",\"t\":1.0,\"q\":[0.0]}\n{\"type\":\"robot\",\"t\":1.0,\"q\":[0.0],\"dq\":[0.0],\"ddq\":[0.5]}\n"
        ),
        "{text}"
    );
}

/// Dynamic objects: the log format carries them (header `objects`, `object` records,
/// written by `LogWriter::write_object` and read back); an object record without a declared
/// object is an error; a malformed one names its field.
#[test]
fn object_records_are_read_and_checked_for_errors() {
    let header_objects = r#"{"type":"header","format":"pacs-log","version":1,"robot":"fr3","human":"default","constraints":"ssm","objects":[{"id":"b1","object":"ball","contact":"no_contact"}]}"#;
    let object = r#"{"type":"object","t":0.0,"t_meas":0.0,"id":"b1","position":[0.5,0.0,0.04],"velocity":[0.0,0.1,0.0]}"#;
    // (Audited: `audit_objects.rs`.) An object far from the arm: the log passes.
    let r = run(
        &lines(&[header_objects, HUMAN, object, ROBOT0, ROBOT1]),
        &AuditConfig::default(),
    )
    .unwrap();
    assert_eq!(r.verdict, pacs_audit::Verdict::Pass);
    // Undeclared object: an error at its line.
    expect_error(
        &lines(&[HEADER, HUMAN, object, ROBOT0, ROBOT1]),
        Some(3),
        "id `b1` is not declared",
    );
    // Malformed records name the field.
    let short = r#"{"type":"object","t":0.0,"id":"b1","position":[0.5,0.0]}"#;
    expect_error(
        &lines(&[HEADER, short]),
        Some(2),
        "`position` needs 3 values",
    );
    let no_id = r#"{"type":"object","t":0.0,"position":[0.5,0.0,0.0]}"#;
    expect_error(
        &lines(&[HEADER, no_id]),
        Some(2),
        "object record has no `id` field",
    );
    let bad_header = r#"{"type":"header","format":"pacs-log","version":1,"robot":"fr3","human":"default","constraints":"ssm","objects":[{"id":"b1","object":"rock","contact":"ssm"}]}"#;
    expect_error(
        &lines(&[bad_header, HUMAN, ROBOT0]),
        Some(1),
        "header.objects[0].object",
    );
    // A person and an object with one id: violations and reports could not tell them apart.
    let same_id = r#"{"type":"header","format":"pacs-log","version":2,"robot":"fr3","humans":[{"id":"b1","human":"default"}],"constraints":"ssm","objects":[{"id":"b1","object":"ball","contact":"ssm"}]}"#;
    expect_error(
        &lines(&[same_id, ROBOT0]),
        Some(1),
        "header.objects[0].id: \"b1\" is also the id of a person (header.humans[0])",
    );
    // The writer's output reads back as the same record.
    let mut w = LogWriter::new(Vec::new());
    let mut h = pacs_log::Header::new(
        pacs_log::ModelRef::Name("fr3".into()),
        pacs_log::ModelRef::Name("default".into()),
        pacs_log::ModelRef::Name("ssm".into()),
    );
    h.objects.push(pacs_log::ObjectEntry {
        id: "b1".into(),
        object: pacs_log::ModelRef::Name("ball".into()),
        contact: pacs_models::object::ObjectContact::Pfl { threshold: 2.0 },
    });
    w.write_header(&h).unwrap();
    w.write_object(0.5, 0.49, "b1", [0.1, 0.2, 0.3], None)
        .unwrap();
    let text = String::from_utf8(w.finish().unwrap()).unwrap();
    let mut r = pacs_log::jsonl::JsonlReader::new("w.jsonl", text.as_bytes()).unwrap();
    use pacs_log::RecordReader;
    assert_eq!(r.header().objects, h.objects);
    match r.next_record().unwrap() {
        Some(pacs_log::Record::Object {
            t,
            t_meas,
            id,
            position,
            velocity,
        }) => {
            assert_eq!(
                (t, t_meas, id, position, velocity),
                (0.5, 0.49, "b1", [0.1, 0.2, 0.3], None)
            );
        }
        other => panic!("{other:?}"),
    }
}
