//! Logged values that other logged values contradict are never trusted, the PFL energy
//! is the whole robot's, pinches between adjacent links count, trailing human records count.
//! Each case here is a log that an audit without the check under test would pass (exit 0).

use pacs_audit::enclosure::{Sample, span_boxes};
use pacs_audit::{AuditConfig, ConstraintKind, RunResult, Verdict, audit_reader};
use pacs_log::jsonl::JsonlReader;
use pacs_models::{HumanModel, MAX_DOF, RobotModel};

fn run(text: &str) -> RunResult {
    let mut r = JsonlReader::new("t.jsonl", std::io::Cursor::new(text.as_bytes())).unwrap();
    audit_reader(&mut r, &AuditConfig::default()).unwrap()
}

fn reasons(r: &RunResult) -> Vec<&str> {
    r.inconclusive.iter().map(|s| s.reason.as_str()).collect()
}

/// The issue's log: joint 1 turns at 2.4 rad/s while both samples claim `dq = 0`, and the right
/// hand overlaps the gripper by 3 cm.
const HUMAN: &str = r#"{"type":"human","t":0.0,"positions":[[2.6,0,1],[2.6,0.1,1],[2.6,0.2,1],[0.9017,0.5819,0.6393],[0.7169,0.4626,0.6393],[0.4816,0.3108,0.6393],[2.6,0.6,1],[2.6,0.7,1],[2.6,0.8,1]]}"#;
const ROBOT: &str = r#"{"type":"robot","t":0.0,"q":[0.3,-0.5,0.2,-2.0,0.1,1.8,0.6],"dq":[0,0,0,0,0,0,0]}
{"type":"robot","t":0.001,"q":[0.3024,-0.5,0.2,-2.0,0.1,1.8,0.6],"dq":[0,0,0,0,0,0,0]}"#;

fn header(constraints: &str) -> String {
    format!(
        r#"{{"type":"header","format":"pacs-log","version":1,"robot":"fr3","human":"default","constraints":"{constraints}"}}"#
    )
}

/// The default human's nine keypoints in a column at x = 2.6 + `dx` (m), 0.1 m apart in y.
fn person_at(dx: f64) -> String {
    let x = 2.6 + dx;
    let kp: Vec<String> = (0..9)
        .map(|i| format!("[{x},{},1]", i as f64 / 10.0))
        .collect();
    format!("[{}]", kp.join(","))
}

/// A human record logged at `t`, stamped `t_meas` (default `t`), with keypoints `kp` (JSON).
fn human_record(t: f64, t_meas: Option<f64>, kp: &str) -> String {
    match t_meas {
        Some(tm) => {
            format!("{{\"type\":\"human\",\"t\":{t},\"t_meas\":{tm},\"positions\":{kp}}}\n")
        }
        None => format!("{{\"type\":\"human\",\"t\":{t},\"positions\":{kp}}}\n"),
    }
}

/// The audit of a log under `head`: 21 robot samples 10 ms apart at the joint positions `q`
/// (rad, comma-separated), each preceded by the human records `humans(k, t)` returns.
fn rest_log(head: &str, q: &str, humans: impl Fn(usize, f64) -> String) -> RunResult {
    let mut text = format!("{head}\n");
    for k in 0..=20 {
        let t = k as f64 * 0.01;
        text += &humans(k, t);
        text += &format!("{{\"type\":\"robot\",\"t\":{t},\"q\":[{q}]}}\n");
    }
    run(&text)
}

/// The joint positions of the logs at rest (rad).
const AT_REST: &str = "0.3,-0.5,0.2,-2.0,0.1,1.8,0.6";

#[test]
fn velocities_contradicting_positions_never_pass_ssm() {
    let r = run(&format!("{}\n{HUMAN}\n{ROBOT}\n", header("ssm")));
    assert_eq!(r.verdict, Verdict::Fail, "{r:?}");
    assert_eq!(reasons(&r), ["exceeds_limits"]);
    let v = &r.violations[0];
    assert_eq!(v.constraint, ConstraintKind::Ssm);
    assert_eq!(v.body_part, "rHand");
}

#[test]
fn velocities_contradicting_positions_never_pass_pfl() {
    let r = run(&format!("{}\n{HUMAN}\n{ROBOT}\n", header("handover")));
    assert_eq!(r.verdict, Verdict::Fail, "{r:?}");
    assert_eq!(reasons(&r), ["exceeds_limits"]);
    let v = r
        .violations
        .iter()
        .find(|v| v.body_part == "rHand")
        .expect("a PFL violation at the right hand");
    assert_eq!(v.constraint, ConstraintKind::Pfl);
    // The velocity box covers what Δq implies (2.4 rad/s on joint 1): the true whole-robot
    // energy at 2.4 rad/s is about 2.2 J.
    let robot = RobotModel::builtin("fr3").unwrap();
    let q = [0.3012, -0.5, 0.2, -2.0, 0.1, 1.8, 0.6];
    let truth = robot.kinetic_energy(&q, &[2.4, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
    assert!(truth > 1.5, "{truth}");
    assert!(
        v.energy >= truth,
        "bound {} < true energy {truth}",
        v.energy
    );
}

#[test]
fn consistent_zero_velocities_at_rest_are_not_flagged() {
    // The same contact with the robot truly at rest: SSM allows it, nothing is inconclusive.
    let still = ROBOT.replace("0.3024", "0.3");
    let r = run(&format!("{}\n{HUMAN}\n{still}\n", header("ssm")));
    assert_eq!(r.verdict, Verdict::Pass, "{r:?}");
}

/// A joint accelerating at 5 rad/s² from rest, its velocity logged by a filter lagging 50 ms.
#[test]
fn lagging_velocity_filter_is_inconclusive_or_fails() {
    let mut text = header("handover");
    text.push('\n');
    text.push_str(HUMAN);
    text.push('\n');
    for k in 0..=200 {
        let t = k as f64 * 0.001;
        let q0 = 0.3 + 2.5 * t * t;
        let lagged = 5.0 * (t - 0.05).max(0.0);
        text.push_str(&format!(
            r#"{{"type":"robot","t":{t},"q":[{q0},-0.5,0.2,-2.0,0.1,1.8,0.6],"dq":[{lagged},0,0,0,0,0,0]}}"#
        ));
        text.push('\n');
    }
    let r = run(&text);
    assert_ne!(r.verdict, Verdict::Pass);
    assert!(reasons(&r).contains(&"exceeds_limits"), "{:?}", reasons(&r));
}

/// The jerk limit narrows the velocity box only where a motion within all the limits joins the
/// samples. A span (Δ = 4 ms, `q̇` 0 then 0.038 rad/s, `q̈ = A` at both ends, the
/// positions 0.2 µrad short of `AΔ²/2`) passes every consistency test, and the quintic through
/// it stays within the jerk limit, but it exceeds `A` (its jerk is positive where `q̈₀ = A`):
/// no motion within both joins the samples, while one within `A` alone reaches 0.0385 rad/s.
/// The box keeps the acceleration limit's bound, above that. A motion within
/// all the limits (constant velocity) still gets the narrowed box.
#[test]
fn the_jerk_limit_narrows_a_box_only_where_all_the_limits_are_met() {
    let lim = RobotModel::builtin("fr3").unwrap().limits().clone();
    let (a, dt) = (10.0, 0.004);
    let mut s0 = Sample {
        t: 1.0,
        q: [0.0; MAX_DOF],
        dq: [0.0; MAX_DOF],
        ddq: [0.0; MAX_DOF],
        has_dq: true,
        has_ddq: true,
    };
    s0.ddq[0] = a;
    let mut s1 = Sample { t: 1.0 + dt, ..s0 };
    s1.q[0] = a * dt * dt / 2.0 - 2e-7;
    s1.dq[0] = a * dt - 2e-3;
    let enc = span_boxes(&lim, &s0, &s1, 1e-9);
    assert!(enc.consistent);
    let hi = enc.boxes.unwrap().dq.bounds(0).1;
    assert!(hi >= 0.0385, "{hi}");
    // Constant velocity 0.5 rad/s: within every limit, the box within JΔ²/8 of it.
    let (mut s0, mut s1) = (s0, s1);
    s0.ddq[0] = 0.0;
    s1.ddq[0] = 0.0;
    s0.dq[0] = 0.5;
    s1.dq[0] = 0.5;
    s1.q[0] = 0.5 * dt;
    let b = span_boxes(&lim, &s0, &s1, 1e-9).boxes.unwrap();
    let (lo, hi) = b.dq.bounds(0);
    let j = 5000.0 * dt * dt / 8.0;
    assert!(hi <= 0.5 + j + 1e-9 && lo >= 0.5 - j - 1e-9, "{lo} {hi}");
}

/// A lone acceleration (logged on one end of a span with velocities at both) must agree with
/// the positions too: from its end, `|Δq − q̇Δ − q̈Δ²/2| ≤ JΔ³/6`. A span (Δ = 1 ms,
/// `q̇ = 0` then 0.0075 rad/s, `q̈₀ = 10` rad/s² alone, Δq = 3.75 µrad) meets every other test
/// but misses this one by 1.25 µrad against 0.83 µrad allowed; with Δq = 4.5 µrad it agrees.
#[test]
fn a_lone_acceleration_must_agree_with_the_positions() {
    let lim = RobotModel::builtin("fr3").unwrap().limits().clone();
    let mut s0 = Sample {
        t: 0.0,
        q: [0.0; MAX_DOF],
        dq: [0.0; MAX_DOF],
        ddq: [0.0; MAX_DOF],
        has_dq: true,
        has_ddq: true,
    };
    s0.ddq[0] = 10.0;
    let mut s1 = Sample {
        t: 0.001,
        has_ddq: false,
        ddq: [0.0; MAX_DOF],
        ..s0
    };
    s1.dq[0] = 0.0075;
    s1.q[0] = 3.75e-6;
    assert!(!span_boxes(&lim, &s0, &s1, 0.0).consistent);
    s1.q[0] = 4.5e-6;
    assert!(span_boxes(&lim, &s0, &s1, 0.0).consistent);
}

#[test]
fn a_contradiction_within_limits_is_flagged_by_the_displacement_test_alone() {
    // |Δq| ≤ v_max·Δ, |Δq̇| ≤ A·Δ, |q̇| ≤ v_max: only the displacement-vs-velocities test sees it.
    let lim = RobotModel::builtin("fr3").unwrap().limits().clone();
    let a = lim.a_max()[0];
    let dt = 0.01;
    let s0 = Sample {
        t: 0.0,
        q: [0.0; MAX_DOF],
        dq: [0.0; MAX_DOF],
        ddq: [0.0; MAX_DOF],
        has_dq: true,
        has_ddq: false,
    };
    let mut s1 = Sample { t: dt, ..s0 };
    // The most a joint starting and ending at rest can travel: A·Δ²/4 (bang-bang).
    s1.q[0] = a * dt * dt / 4.0 * 0.999;
    assert!(span_boxes(&lim, &s0, &s1, 1e-9).consistent);
    s1.q[0] = a * dt * dt / 4.0 * 1.01;
    let enc = span_boxes(&lim, &s0, &s1, 1e-9);
    assert!(!enc.consistent);
    // The velocity box then covers the mean velocity Δq/Δ.
    let b = enc.boxes.expect("finite samples have boxes");
    assert!(b.dq.bounds(0).1 >= s1.q[0] / dt);
}

/// Only joint 4 (the elbow) moves; the right hand touches link 2. The sub-chain up to link 2 has
/// no kinetic energy, the whole robot has: PFL must use the whole robot's.
#[test]
fn pfl_uses_the_whole_robot_energy() {
    let robot = RobotModel::builtin("fr3").unwrap();
    let human = HumanModel::builtin("default").unwrap();
    let q = [0.0, -0.3, 0.0, -2.0, 0.0, 1.8, 0.6];
    let caps = robot.capsules_world(&q);
    let link2 = robot.link_index("fr3_link2").unwrap();
    let (_, c) = caps.iter().find(|(l, _)| *l == link2).unwrap();
    let mid = nalgebra::center(&c.p1(), &c.p2());
    let hand_r = human.body_parts()[5].thickness / 2.0;
    // The hand touches the link's capsule side facing +y, forearm pointing away.
    let hand = [mid.x, mid.y + c.radius() + hand_r - 0.01, mid.z];
    let mut kp = vec![[2.6, 0.0, 1.0]; 9];
    kp[5] = hand;
    kp[4] = [hand[0], hand[1] + 0.3, hand[2]];
    kp[3] = [hand[0], hand[1] + 0.6, hand[2]];
    let kp_json = serde_json::to_string(&kp).unwrap();
    let dq = [0.0, 0.0, 0.0, 1.5, 0.0, 0.0, 0.0];
    let mut e = vec![0.0; 8];
    robot.subchain_energies_into(&q, &dq, &mut e);
    assert_eq!(e[2], 0.0);
    let whole = robot.kinetic_energy(&q, &dq);
    assert!(whole > 0.265, "{whole}");
    let mut text = header("handover");
    text.push_str(&format!(
        "\n{{\"type\":\"human\",\"t\":0.0,\"positions\":{kp_json}}}\n"
    ));
    let mut qk = q;
    for k in 0..=4 {
        let t = k as f64 * 0.001;
        qk[3] = q[3] + 1.5 * t;
        text.push_str(&format!(
            "{{\"type\":\"robot\",\"t\":{t},\"q\":{},\"dq\":{}}}\n",
            serde_json::to_string(&qk).unwrap(),
            serde_json::to_string(&dq).unwrap()
        ));
    }
    let r = run(&text);
    assert_eq!(r.verdict, Verdict::Fail, "{r:?}");
    let v = r
        .violations
        .iter()
        .find(|v| v.body_part == "rHand" && v.link == "fr3_link2")
        .expect("violation at link 2");
    assert!(
        v.certain,
        "the nominal whole-robot energy exceeds the threshold at the samples"
    );
    assert!(v.energy >= whole);
}

/// Two human records after the last robot sample: the first, measured inside the logged time,
/// shows contact; only the second was remembered before.
#[test]
fn every_trailing_human_record_counts() {
    let far = person_at(0.0);
    let contact = r#"[[2.6,0,1],[2.6,0.1,1],[2.6,0.2,1],[0.9017,0.5819,0.6393],[0.7169,0.4626,0.6393],[0.4816,0.3108,0.6393],[2.6,0.6,1],[2.6,0.7,1],[2.6,0.8,1]]"#;
    let robots: String = (0..=10)
        .map(|k| {
            format!(
                "{{\"type\":\"robot\",\"t\":{},\"q\":[0.3,-0.5,0.2,-2.0,0.1,1.8,0.6]}}\n",
                k as f64 * 0.05
            )
        })
        .collect();
    let text = format!(
        "{}\n{{\"type\":\"human\",\"t\":0.0,\"positions\":{far}}}\n\
         {robots}\
         {{\"type\":\"human\",\"t\":0.6,\"t_meas\":0.4,\"positions\":{contact}}}\n\
         {{\"type\":\"human\",\"t\":0.7,\"t_meas\":0.7,\"positions\":{far}}}\n",
        header("ssm")
    );
    let r = run(&text);
    assert_eq!(r.verdict, Verdict::Inconclusive, "{r:?}");
    // The hand also jumps 2 m within 0.4 s between the records (the model allows 0.8 m).
    assert_eq!(
        reasons(&r),
        [
            "human_record_after_last_robot_sample",
            "human_exceeds_model"
        ]
    );
}

/// A person who moves faster than the model allows between two measurements makes the log
/// inconclusive where it would otherwise pass: the occupancies checked with the earlier
/// measurement assumed the model (a spike of one record 1.5 m away from the others, 10 ms apart,
/// is such a contradiction; a 1.5 cm one, 1.5 m/s, is not).
#[test]
fn a_human_faster_than_the_model_is_inconclusive_not_a_pass() {
    let far = person_at(0.0);
    // One record displaced by `dx` (m) along x, 10 ms after and before its neighbours.
    let log = |dx: f64| {
        let spike = person_at(dx);
        rest_log(&header("ssm"), AT_REST, |k, t| {
            human_record(t, None, if k == 10 { &spike } else { &far })
        })
    };
    let fast = log(1.5);
    assert_eq!(
        fast.verdict,
        Verdict::Inconclusive,
        "{:?}",
        fast.inconclusive
    );
    assert_eq!(reasons(&fast), ["human_exceeds_model"]);
    // From the record before the spike to the last one the spike contradicts: every record up
    // to 0.2 s is within 0.2 m of the others and 1.5 m from the spike (each is checked against
    // every kept record, not only against the one logged before it, which would give 0.09–0.11).
    let span = &fast.inconclusive[0];
    assert_eq!((span.t_start, span.t_end), (0.09, 0.2));
    let slow = log(0.015);
    assert_eq!(slow.verdict, Verdict::Pass, "{:?}", slow.inconclusive);
}

/// A clean log (robot at rest, the human far away) written robot-then-human or human-then-robot
/// at every time stamp, in JSON Lines and CSV: the same verdict, PASS, in all four forms.
#[test]
fn equal_times_follow_one_order_in_jsonl_and_csv() {
    let q = "0.3,-0.5,0.2,-2.0,0.1,1.8,0.6";
    let kp: Vec<String> = (0..9)
        .map(|i| format!("2.6,{},1", i as f64 * 0.1))
        .collect();
    let kp_csv = kp.join(",");
    let kp_json = format!(
        "[{}]",
        kp.iter()
            .map(|p| format!("[{p}]"))
            .collect::<Vec<_>>()
            .join(",")
    );
    let head = header("ssm");
    for robot_first in [true, false] {
        let (mut jsonl, mut csv) = (format!("{head}\n"), format!("#{head}\n"));
        for k in 0..=20 {
            let t = k as f64 * 0.01;
            let rj = format!("{{\"type\":\"robot\",\"t\":{t},\"q\":[{q}]}}\n");
            let hj = format!("{{\"type\":\"human\",\"t\":{t},\"positions\":{kp_json}}}\n");
            let rc = format!("robot,{t},7,{q}\n");
            let hc = format!("human,{t},{t},{kp_csv}\n");
            if robot_first {
                jsonl.push_str(&(rj + &hj));
                csv.push_str(&(rc + &hc));
            } else {
                jsonl.push_str(&(hj + &rj));
                csv.push_str(&(hc + &rc));
            }
        }
        let r = run(&jsonl);
        assert_eq!(
            r.verdict,
            Verdict::Pass,
            "jsonl, robot first {robot_first}: {r:?}"
        );
        let mut reader =
            pacs_log::csv::CsvReader::new("t.csv", std::io::Cursor::new(csv.as_bytes())).unwrap();
        let r = audit_reader(&mut reader, &AuditConfig::default()).unwrap();
        assert_eq!(
            r.verdict,
            Verdict::Pass,
            "csv, robot first {robot_first}: {r:?}"
        );
        assert_eq!(r.metrics.samples, 21);
        assert_eq!(r.metrics.human_records, 21);
    }
}

/// `human_model = "pos"` must not trust the extremity length when the measurement contradicts it:
/// the right shoulder measured 1.4 m from the hand with a 1.0 m arm, the hand on the moving
/// gripper. Before: PASS with `pos` (FAIL with the default model).
#[test]
fn pos_model_does_not_trust_a_contradicted_extremity_length() {
    let human = r#"{"type":"human","t":0.0,"positions":[[2.6,0,1],[2.6,0.1,1],[2.6,0.2,1],[1.8816,0.3108,0.6393],[1.1816,0.3108,0.6393],[0.4816,0.3108,0.6393],[2.6,0.6,1],[2.6,0.7,1],[2.6,0.8,1]]}"#;
    let robot = r#"{"type":"robot","t":0.0,"q":[0.3,-0.5,0.2,-2.0,0.1,1.8,0.6],"dq":[0.5,0,0,0,0,0,0]}
{"type":"robot","t":0.001,"q":[0.3005,-0.5,0.2,-2.0,0.1,1.8,0.6],"dq":[0.5,0,0,0,0,0,0]}"#;
    let text = format!("{}\n{human}\n{robot}\n", header("ssm"));
    let audit = |model: &str| {
        let cfg: AuditConfig = toml::from_str(&format!("human_model = \"{model}\"")).unwrap();
        let mut r = JsonlReader::new("t.jsonl", std::io::Cursor::new(text.as_bytes())).unwrap();
        audit_reader(&mut r, &cfg).unwrap()
    };
    for model in ["combined", "vel", "pos"] {
        let r = audit(model);
        assert_eq!(r.verdict, Verdict::Fail, "{model}: {r:?}");
        assert!(
            r.violations.iter().any(|v| v.body_part == "rHand"),
            "{model}: {:?}",
            r.violations
        );
    }
}

/// `ddq` is accepted in JSON Lines and CSV (3n values), only together with `dq`; the same data
/// gets the same verdict in both forms.
#[test]
fn accelerations_in_jsonl_and_csv() {
    let q = "0.3,-0.5,0.2,-2.0,0.1,1.8,0.6";
    let zeros = "0,0,0,0,0,0,0";
    let kp: Vec<String> = (0..9)
        .map(|i| format!("2.6,{},1", i as f64 * 0.1))
        .collect();
    let head = header("handover");
    let mut jsonl = format!(
        "{head}\n{{\"type\":\"human\",\"t\":0,\"positions\":[{}]}}\n",
        kp.iter()
            .map(|p| format!("[{p}]"))
            .collect::<Vec<_>>()
            .join(",")
    );
    let mut csv = format!("#{head}\nhuman,0,0,{}\n", kp.join(","));
    for k in 0..=10 {
        let t = k as f64 * 0.001;
        jsonl.push_str(&format!(
            "{{\"type\":\"robot\",\"t\":{t},\"q\":[{q}],\"dq\":[{zeros}],\"ddq\":[{zeros}]}}\n"
        ));
        csv.push_str(&format!("robot,{t},7,{q},{zeros},{zeros}\n"));
    }
    let r = run(&jsonl);
    assert_eq!(r.verdict, Verdict::Pass, "{r:?}");
    let mut reader =
        pacs_log::csv::CsvReader::new("t.csv", std::io::Cursor::new(csv.as_bytes())).unwrap();
    let c = audit_reader(&mut reader, &AuditConfig::default()).unwrap();
    assert_eq!(c.verdict, Verdict::Pass);
    assert_eq!(c.metrics.samples, r.metrics.samples);
    // Accelerations without velocities: an input error naming the field and the line.
    let bad = format!(
        "{head}\n{{\"type\":\"robot\",\"t\":0,\"q\":[{q}],\"ddq\":[{zeros}]}}\n{{\"type\":\"robot\",\"t\":0.001,\"q\":[{q}]}}\n"
    );
    let mut reader = JsonlReader::new("t.jsonl", std::io::Cursor::new(bad.as_bytes())).unwrap();
    let err = audit_reader(&mut reader, &AuditConfig::default())
        .unwrap_err()
        .to_string();
    assert!(err.contains("ddq") && err.contains("line 2"), "{err}");
}

/// A human record arriving late (logged at 0.2 s, stamped 0.095 s) is checked against its
/// neighbours in time (0.09 and 0.10 s), not only against the newest record (0.2 s), and it
/// does not replace the newest as the measurement in use (the shield keeps the newest too). A
/// spike 5 ms from its neighbours that the model forbids there but allows over the 105 ms to
/// the newest (so a check against the latest record logged only would let the log pass) makes
/// the log inconclusive; the same record without the spike passes.
#[test]
fn a_late_human_record_is_checked_against_its_neighbours_in_time() {
    let far = person_at(0.0);
    let model = HumanModel::builtin("default").unwrap();
    let v = model.v_max().iter().cloned().fold(f64::INFINITY, f64::min);
    let e = model.measurement_error_pos();
    // Beyond the model against both neighbours (5 ms), within it against the newest (105 ms).
    let (near, newest) = (v * 0.005 + 2.0 * e, v * 0.105 + 2.0 * e);
    let dx_spike = 0.5 * (near + newest);
    let log = |dx: f64| {
        let late = person_at(dx);
        rest_log(&header("ssm"), AT_REST, |k, t| {
            let mut r = human_record(t, None, &far);
            if k == 20 {
                r += &human_record(t, Some(0.095), &late);
            }
            r
        })
    };
    assert!(newest - near > 0.1, "v {v}, e {e}");
    let spike = log(dx_spike);
    assert_eq!(
        spike.verdict,
        Verdict::Inconclusive,
        "{:?}",
        spike.inconclusive
    );
    assert_eq!(reasons(&spike), ["human_exceeds_model"]);
    let span = &spike.inconclusive[0];
    assert_eq!((span.t_start, span.t_end), (0.09, 0.1));
    assert_eq!(spike.metrics.human_records, 22);
    let calm = log(0.0);
    assert_eq!(calm.verdict, Verdict::Pass, "{:?}", calm.inconclusive);
}

/// Records with one stamp, each 1.5·e_pos from the one before (within the `2·e_pos` that equal
/// stamps allow) but drifting away from the first, contradict the model once the drift exceeds
/// `2·e_pos`: each record is checked against every kept one, not only against its neighbour in
/// time (the records 50 ms before and after allow far more). One step of 1.5·e_pos passes; a
/// chain of three (4.5·e_pos from the first) is flagged.
#[test]
fn a_chain_of_equal_stamp_records_cannot_drift_from_the_first() {
    let e = 0.01;
    let mut spec = serde_json::to_value(HumanModel::builtin("default").unwrap().spec()).unwrap();
    spec["measurement_error_pos"] = serde_json::json!(e);
    let head = format!(
        r#"{{"type":"header","format":"pacs-log","version":1,"robot":"fr3","human":{spec},"constraints":"ssm"}}"#
    );
    let log = |links: usize| {
        rest_log(&head, AT_REST, |k, t| {
            let copies = match k {
                10 => links + 1,
                _ if k % 5 == 0 => 1,
                _ => 0,
            };
            (0..copies)
                .map(|c| human_record(t, None, &person_at(1.5 * e * c as f64)))
                .collect()
        })
    };
    let one = log(1);
    assert_eq!(one.verdict, Verdict::Pass, "{:?}", one.inconclusive);
    let chain = log(3);
    assert_eq!(
        chain.verdict,
        Verdict::Inconclusive,
        "{:?}",
        chain.inconclusive
    );
    assert_eq!(reasons(&chain), ["human_exceeds_model"]);
}

/// The audit keeps the latest 64 records of a person; the ones let go still bound later ones
/// (per keypoint and axis). A log (e_pos 0.05 m, so two
/// records may differ by 0.1 m beyond `v·Δt`, v = 2 m/s): a record at 0 m, then 64 records at
/// `2t + 0.095` m, each within the allowance of every other, then one at `2t + 0.19` m
/// (t = 0.065 s): within the allowance of the 64 kept ones, but 0.32 m from the first where
/// 0.23 m is allowed. It is `human_exceeds_model`. A person walking at 1.9 m/s for
/// 0.3 s (300 records, most let go) agrees with its model and passes.
#[test]
fn records_drifting_from_one_let_go_break_the_model() {
    let mut spec = serde_json::to_value(HumanModel::builtin("default").unwrap().spec()).unwrap();
    spec["measurement_error_pos"] = serde_json::json!(0.05);
    let head = format!(
        r#"{{"type":"header","format":"pacs-log","version":1,"robot":"fr3","human":{spec},"constraints":"ssm"}}"#
    );
    let log_from = |t0: f64, n: usize, dx: &dyn Fn(usize, f64) -> f64| {
        let mut text = format!("{head}\n");
        for j in 0..n {
            let s = j as f64 * 0.001;
            let t = t0 + s;
            text += &human_record(t, None, &person_at(dx(j, s)));
            text += &format!("{{\"type\":\"robot\",\"t\":{t},\"q\":[{AT_REST}]}}\n");
        }
        run(&text)
    };
    let log = |n: usize, dx: &dyn Fn(usize, f64) -> f64| log_from(0.0, n, dx);
    let r = log(66, &|j, t| match j {
        0 => 0.0,
        65 => 2.0 * t + 0.19,
        _ => 2.0 * t + 0.095,
    });
    assert_ne!(r.verdict, Verdict::Pass);
    assert_eq!(reasons(&r), ["human_exceeds_model"]);
    let r = log(300, &|_, t| 1.9 * t);
    assert_eq!(r.verdict, Verdict::Pass, "{:?}", reasons(&r));
    // 2 mm beyond the allowance, also at Unix-time stamps (1.7·10⁹ s, where `v·t` is 3.4·10⁹ m:
    // the let-go bounds count time from the first record let go).
    for t0 in [0.0, 1.7e9] {
        let r = log_from(t0, 66, &|j, s| match j {
            0 => 0.0,
            65 => 2.0 * s + 0.102,
            _ => 2.0 * s + 0.095,
        });
        assert_eq!(reasons(&r), ["human_exceeds_model"], "t0 {t0}");
        let r = log_from(t0, 300, &|_, s| 1.9 * s);
        assert_eq!(r.verdict, Verdict::Pass, "t0 {t0}: {:?}", reasons(&r));
    }
}

/// A report names a model by its name only where the spec is that built-in's: an inline robot
/// spec called "fr3" with other capsule radii, or a human spec called "default" with another
/// measurement error, is labelled as a custom spec, so that an assessor never reads a modified
/// model under a built-in's name.
#[test]
fn an_inline_spec_under_a_built_in_name_is_labelled_custom() {
    let mut robot = serde_json::to_value(RobotModel::builtin("fr3").unwrap().spec()).unwrap();
    let mut human = serde_json::to_value(HumanModel::builtin("default").unwrap().spec()).unwrap();
    let body = format!("{HUMAN}\n{ROBOT}\n");
    let names = |robot: &serde_json::Value, human: &serde_json::Value| {
        let head = format!(
            r#"{{"type":"header","format":"pacs-log","version":1,"robot":{robot},"human":{human},"constraints":"ssm"}}"#
        );
        let r = run(&format!("{head}\n{body}"));
        (
            r.models.robot.clone(),
            r.models.human.clone(),
            r.models.constraints.clone(),
        )
    };
    // The built-ins' own specs inline: their names.
    assert_eq!(
        names(&robot, &human),
        ("fr3".into(), "default".into(), "ssm".into())
    );
    robot["links"][1]["capsules"][0]["radius"] = serde_json::json!(0.0);
    human["measurement_error_pos"] = serde_json::json!(0.05);
    let (r, h, _) = names(&robot, &human);
    assert_eq!(r, "fr3 (custom spec, not the built-in fr3)");
    assert_eq!(h, "default (custom spec, not the built-in default)");
    robot["name"] = serde_json::json!("my-arm");
    assert_eq!(names(&robot, &human).0, "my-arm (custom spec)");
}

/// Joint positions outside the robot's position limits contradict the robot model: the spans
/// they bound are `exceeds_limits` (checked, never passed), as for samples moving faster than
/// the limits. The same log within the limits passes.
#[test]
fn positions_outside_the_joint_limits_are_inconclusive_not_a_pass() {
    let far = person_at(0.0);
    let log = |q3: f64| {
        let q = format!("0.3,-0.5,0.2,{q3},0.1,1.8,0.6");
        rest_log(&header("ssm"), &q, |_, t| human_record(t, None, &far))
    };
    // FR3 joint 4 lies in [-3.0421, -0.1518] rad.
    let outside = log(1.0);
    assert_eq!(
        outside.verdict,
        Verdict::Inconclusive,
        "{:?}",
        outside.inconclusive
    );
    assert_eq!(reasons(&outside), ["exceeds_limits"]);
    assert_eq!(log(-2.0).verdict, Verdict::Pass);
}

/// The contact of [`HUMAN`] with joint 1 moving from [`ROBOT`]'s first positions at `w` rad/s
/// (positions only), 1 kHz, `dq` logged on one sample only (joint 1: `dq1` rad/s; at 5 ms, or
/// at the last sample with `at_end`, after a last person record) and `ddq` there too if given;
/// with `all_dq` every other sample logs `dq` (joint 1 at `w`).
fn lone_derivative_log(
    w: f64,
    dq1: f64,
    ddq1: Option<f64>,
    all_dq: bool,
    at_end: bool,
) -> RunResult {
    let mut text = format!("{}\n{HUMAN}\n", header("ssm"));
    let lone = if at_end { 10 } else { 5 };
    for k in 0..=10 {
        let t = k as f64 * 0.001;
        let derivs = if k == lone {
            let d = format!(",\"dq\":[{dq1},0,0,0,0,0,0]");
            match ddq1 {
                Some(a) => format!("{d},\"ddq\":[{a},0,0,0,0,0,0]"),
                None => d,
            }
        } else if all_dq {
            format!(",\"dq\":[{w},0,0,0,0,0,0]")
        } else {
            String::new()
        };
        if at_end && k == 10 {
            text += &HUMAN.replace("\"t\":0.0", "\"t\":0.01");
            text.push('\n');
        }
        let q0 = 0.3 + w * t;
        text += &format!(
            "{{\"type\":\"robot\",\"t\":{t},\"q\":[{q0},-0.5,0.2,-2.0,0.1,1.8,0.6]{derivs}}}\n"
        );
    }
    run(&text)
}

/// Samples at `dt` (s) apart, joint 1 at `0.3 + step·k` (rad) with `dq = dq` and the
/// accelerations `ddq(k)` on every sample, the hand of [`HUMAN`] overlapping the gripper (SSM).
fn ddq_log(samples: usize, dt: f64, step: f64, dq: f64, ddq: impl Fn(usize) -> f64) -> RunResult {
    let mut text = format!("{}\n{HUMAN}\n", header("ssm"));
    for k in 0..samples {
        let t = k as f64 * dt;
        let q0 = 0.3 + step * k as f64;
        let a = ddq(k);
        text += &format!(
            "{{\"type\":\"robot\",\"t\":{t},\"q\":[{q0},-0.5,0.2,-2.0,0.1,1.8,0.6],\"dq\":[{dq},0,0,0,0,0,0],\"ddq\":[{a},0,0,0,0,0,0]}}\n"
        );
    }
    run(&text)
}

/// With accelerations logged, the jerk limit tightens the velocity box to within `JΔ²/8` of
/// the logged velocities; the positions must then be reachable under that limit too. Logs
/// with the hand of [`HUMAN`] on the gripper (SSM's rest speed 0.02 rad/s):
/// at 1 kHz joint 1 logs `dq = 0.019`, `ddq = 0` while its positions advance 21.475 µrad per
/// step (a mean of 0.021475 rad/s, which the joint reaches at some instant of every span: moving,
/// touching); two samples 5 ms apart log `dq = 0.0199` and `ddq = ∓8` while the joint covers
/// 161.375 µrad (0.0323 rad/s on average). The jerk-narrowed box ([0.0184, 0.0196] at 1 kHz)
/// would call them at rest, but `|Δq − Δ(q̇₀ + q̇₁)/2 − Δ²(q̈₀ − q̈₁)/8| ≤ JΔ³/24` (0.21 µrad at
/// 1 kHz) fails:
/// `exceeds_limits` and the hull boxes, which reach the mean velocity, fail the contact. Positions
/// that agree (19 µrad per step at 0.019 rad/s) still pass: at rest, touching.
#[test]
fn accelerations_must_agree_with_the_positions_under_the_jerk_limit() {
    for r in [
        ddq_log(101, 0.001, 2.1475e-5, 0.019, |_| 0.0),
        ddq_log(2, 0.005, 1.61375e-4, 0.0199, |k| {
            if k == 0 { -8.0 } else { 8.0 }
        }),
    ] {
        assert_eq!(r.verdict, Verdict::Fail, "{:?}", reasons(&r));
        assert!(reasons(&r).contains(&"exceeds_limits"), "{:?}", reasons(&r));
    }
    let r = ddq_log(101, 0.001, 1.9e-5, 0.019, |_| 0.0);
    assert_eq!(r.verdict, Verdict::Pass, "{:?}", reasons(&r));
    // Within that bound, but beyond what a motion within J reaches: at rest at both ends of a
    // 5 ms span (`dq = ddq = 0`), the joint moves at most JΔ³/32 = 19.5 µrad (bang-bang jerk);
    // logged 22.3 µrad (JΔ³/28). No motion within the jerk limit joins the samples, so the
    // limit does not narrow the velocity box (±JΔ²/8 = ±0.016 rad/s, "at rest"): the box the
    // acceleration limit gives (±AΔ/2 = ±0.025 rad/s) fails the contact, as the same log
    // without `ddq` does. The test of a motion within J is sufficient,
    // not exact (the quintic through the samples: its jerk 60·Δq/Δ³ here, within J up to
    // JΔ³/60), so between JΔ³/60 and JΔ³/32 the box is the wider one too.
    let j_dt3 = 5000.0 * 0.005f64.powi(3);
    let r = ddq_log(2, 0.005, j_dt3 / 28.0, 0.0, |_| 0.0);
    assert_eq!(r.verdict, Verdict::Fail, "{:?}", reasons(&r));
    // Samples the quintic joins within J (a tenth of the largest displacement) narrow the box:
    // at rest, they pass.
    let r = ddq_log(2, 0.005, j_dt3 / 600.0, 0.0, |_| 0.0);
    assert_eq!(r.verdict, Verdict::Pass, "{:?}", reasons(&r));
    // The same positions with their true velocity logged: consistent, and moving.
    let r = ddq_log(101, 0.001, 2.1475e-5, 0.021475, |_| 0.0);
    assert_eq!(r.verdict, Verdict::Fail);
    assert!(reasons(&r).is_empty(), "{:?}", reasons(&r));
}

/// Robot samples 1 ms apart without velocities, joint 1 at `0.3 + q(k)` (rad), the hand of
/// [`HUMAN`] overlapping the gripper (SSM).
fn positions_log(samples: usize, q: impl Fn(usize) -> f64) -> RunResult {
    let mut text = format!("{}\n{HUMAN}\n", header("ssm"));
    for k in 0..samples {
        let t = k as f64 * 0.001;
        let q0 = 0.3 + q(k);
        text +=
            &format!("{{\"type\":\"robot\",\"t\":{t},\"q\":[{q0},-0.5,0.2,-2.0,0.1,1.8,0.6]}}\n");
    }
    run(&text)
}

/// Robot samples `(t (s), joint 1 (rad), dq of joint 1 (rad/s) if logged)` after the hand of
/// [`HUMAN`] measured at 1 s, overlapping the gripper (SSM).
fn stamped_log(samples: &[(f64, f64, Option<f64>)]) -> RunResult {
    let mut text = format!(
        "{}\n{}\n",
        header("ssm"),
        HUMAN.replace("\"t\":0.0", "\"t\":1.0")
    );
    for &(t, q0, dq) in samples {
        let dq = dq.map_or(String::new(), |c| format!(",\"dq\":[{c},0,0,0,0,0,0]"));
        text += &format!(
            "{{\"type\":\"robot\",\"t\":{t},\"q\":[{q0},-0.5,0.2,-2.0,0.1,1.8,0.6]{dq}}}\n"
        );
    }
    run(&text)
}

/// Without logged velocities each span's box is its mean velocity ± AΔ, which holds for any
/// motion within the acceleration limit A over that span; adjacent spans must then agree at
/// their shared sample, where one velocity is within `AΔ/2` of both means: `|m₁ − m₀| ≤
/// A(Δ₀ + Δ₁)/2` (0.01 rad/s at 1 kHz, A = 10 rad/s²). Logs with each span
/// within the limits alone and "at rest" (box within the rest speed 0.02 rad/s), the hand on
/// the gripper: joint 1 still, then one step of 50 µrad (0.05 rad/s), then still again (at the
/// step's end the joint moves at ≥ 0.045 rad/s, which the next span's box ±0.01 excludes); a
/// zig-zag of ±9 µrad per step (means ±0.009 rad/s, 0.018 apart). Each is
/// `exceeds_limits`. A zig-zag of ±4 µrad (0.008 apart) agrees, and still passes.
#[test]
fn adjacent_spans_must_agree_at_their_shared_sample() {
    for r in [
        positions_log(12, |k| if k >= 6 { 5e-5 } else { 0.0 }),
        positions_log(12, |k| if k % 2 == 1 { 9e-6 } else { 0.0 }),
    ] {
        assert_ne!(r.verdict, Verdict::Pass, "{:?}", reasons(&r));
        assert!(reasons(&r).contains(&"exceeds_limits"), "{:?}", reasons(&r));
    }
    let r = positions_log(12, |k| if k % 2 == 1 { 4e-6 } else { 0.0 });
    assert_eq!(r.verdict, Verdict::Pass, "{:?}", reasons(&r));
    // Across a span of no length: a log moves joint 1 by 1 mrad in the first
    // millisecond (≥ 0.995 rad/s at its end), then logs the same stamp again with `dq = 0`
    // and keeps still, the next span "at rest" beside the hand. The velocity logged at the
    // repeated stamp must agree with the span before it (|c − m₀| ≤ AΔ₀/2).
    let r = stamped_log(&[
        (1.0, 0.3, None),
        (1.001, 0.301, None),
        (1.001, 0.301, Some(0.0)),
        (1.002, 0.301, Some(0.0)),
    ]);
    assert_ne!(r.verdict, Verdict::Pass, "{:?}", reasons(&r));
    assert!(reasons(&r).contains(&"exceeds_limits"), "{:?}", reasons(&r));
    // Where only the logged velocity contradicts the span before: means 0.0135 then 0.0045
    // rad/s (0.009 apart, within A(Δ₀ + Δ₁)/2 = 0.01), the repeated stamp logging `dq = 0`
    // (within AΔ/2 of the later span's mean, but 0.0135 from the earlier one's, where 0.005 is
    // allowed).
    let r = stamped_log(&[
        (1.0, 0.3, None),
        (1.001, 0.3000135, None),
        (1.001, 0.3000135, Some(0.0)),
        (1.002, 0.300018, None),
    ]);
    assert!(reasons(&r).contains(&"exceeds_limits"), "{:?}", reasons(&r));
    // With a velocity at both ends of the earlier span but a sample without one between (of the
    // later stamp): 1 rad/s logged at the start and agreeing with the positions, then the
    // repeated stamp's `dq = 0`, which nothing but this test holds against the earlier span.
    let r = stamped_log(&[
        (1.0, 0.3, Some(1.0)),
        (1.001, 0.301, None),
        (1.001, 0.301, Some(0.0)),
        (1.002, 0.301, Some(0.0)),
    ]);
    assert!(reasons(&r).contains(&"exceeds_limits"), "{:?}", reasons(&r));
}

/// A velocity or acceleration logged on one sample only, beside samples without it, is checked
/// against the spans it ends or starts. At 1 kHz with A = 10 rad/s², a lone `q̇ = c` must keep
/// `|Δq − cΔ| ≤ AΔ²/2 = 5 µrad`: on a joint that does not move, 1 rad/s (or 50, or −0.009)
/// contradicts the positions, 0.004 does not; on a joint moving 28 µrad per step, a last sample
/// claiming 0.019 rad/s (below the rest speed 0.02 rad/s, which the final instant would have
/// used to pass the hand's contact) contradicts them too. A lone `q̈` beyond 100·A, or (with
/// velocities at every sample, constant) beyond `JΔ/3 ≈ 1.67 rad/s²` (the positions from its
/// end, `|Δq − q̇Δ − q̈Δ²/2| ≤ JΔ³/6`; the velocities' change allows `JΔ/2`) contradicts them. A log that
/// contradicts itself so is never a pass.
#[test]
fn a_derivative_logged_on_one_sample_only_must_agree_with_its_spans() {
    let contradicted = |r: &RunResult| reasons(r).contains(&"exceeds_limits");
    for dq1 in [1.0, 50.0, -0.009, 0.006] {
        let r = lone_derivative_log(0.0, dq1, None, false, false);
        assert_ne!(r.verdict, Verdict::Pass, "lone dq {dq1}");
        assert!(contradicted(&r), "lone dq {dq1}: {:?}", reasons(&r));
    }
    // The contradicted spans' boxes cover what the lone velocity claims: the hand's contact with
    // a robot that sample says is moving fails SSM.
    let r = lone_derivative_log(0.0, 1.0, None, false, false);
    assert_eq!(r.verdict, Verdict::Fail, "{:?}", r.violations);
    // Within the band: nothing contradicted, the contact at rest passes.
    for dq1 in [0.0, 0.004, -0.0045] {
        let r = lone_derivative_log(0.0, dq1, None, false, false);
        assert_eq!(r.verdict, Verdict::Pass, "lone dq {dq1}: {:?}", reasons(&r));
    }
    // At the last sample, checked with a touching person record: 0.019 contradicts 28 µrad/ms.
    let r = lone_derivative_log(0.028, 0.019, None, false, true);
    assert_ne!(r.verdict, Verdict::Pass);
    assert!(contradicted(&r), "{:?}", reasons(&r));
    let r = lone_derivative_log(0.028, 0.028, None, false, true);
    assert!(!contradicted(&r), "{:?}", reasons(&r));
    assert_eq!(
        r.verdict,
        Verdict::Fail,
        "moving at the final instant, touching"
    );
    // A lone acceleration far beyond the limit, with or without velocities elsewhere.
    for all_dq in [false, true] {
        let r = lone_derivative_log(0.0, 0.0, Some(1000.0), all_dq, false);
        assert_ne!(r.verdict, Verdict::Pass);
        assert!(contradicted(&r), "{:?}", reasons(&r));
    }
    // Within A but beyond JΔ/2 of the velocities' change (none); or within it but beyond the
    // positions' `|Δq − q̇Δ − q̈Δ²/2| ≤ JΔ³/6` from its end (q̈ up to JΔ/3 ≈ 1.67 rad/s²).
    for a in [2.6, -3.0, 2.4, -2.4, 1.7] {
        let r = lone_derivative_log(0.0, 0.0, Some(a), true, false);
        assert!(contradicted(&r), "lone ddq {a}: {:?}", reasons(&r));
    }
    for a in [0.0, 1.6, -1.6] {
        let r = lone_derivative_log(0.0, 0.0, Some(a), true, false);
        assert_eq!(r.verdict, Verdict::Pass, "lone ddq {a}: {:?}", reasons(&r));
    }
}

/// A robot at rest 0.2 s at 1 kHz, the person measured far away every 1 ms; at 150 ms one more
/// record stamped `stamp` with keypoints `late` (JSON).
fn late_record_log(stamp: f64, late: &str) -> RunResult {
    let far = person_at(0.0);
    let mut text = format!("{}\n", header("ssm"));
    for k in 0..=200 {
        let t = k as f64 * 0.001;
        text += &human_record(t, None, &far);
        if k == 150 {
            text += &human_record(t, Some(stamp), late);
        }
        text += &format!("{{\"type\":\"robot\",\"t\":{t},\"q\":[{AT_REST}]}}\n");
    }
    run(&text)
}

/// The audit checks each human record against the latest 64 it keeps. A record arriving after
/// those have moved past its stamp (logged at 150 ms, stamped 10 ms, 140 records later) cannot
/// be checked against its neighbours in time: `human_record_too_late` (never a pass), whatever
/// it shows (here also a person touching the robot, which the kept records, 77 ms and more
/// away, would allow); so does one stamped as the oldest kept record (87 ms: its older
/// neighbour is gone) unless it copies that record. Stamped 140 ms (within the kept records) it is checked against its
/// neighbours: far, it passes; touching, it contradicts them.
#[test]
fn a_record_too_late_to_check_against_its_neighbours_is_not_evidence() {
    for late in [person_at(0.0), person_at(-2.0)] {
        let r = late_record_log(0.01, &late);
        assert_eq!(r.verdict, Verdict::Inconclusive, "{:?}", r.inconclusive);
        let s = r
            .inconclusive
            .iter()
            .find(|s| s.reason == "human_record_too_late")
            .expect("human_record_too_late");
        // From its stamp to the oldest kept record's (the 64 latest by stamp at 150 ms).
        assert_eq!((s.t_start, s.t_end), (0.01, 87.0 * 0.001), "{s:?}");
    }
    // Stamped as the oldest kept record (87 ms) and 1 mm off it, its older neighbour (86 ms) is
    // gone too; an exact copy of the kept record is checked as that record was.
    let oldest = 87.0 * 0.001;
    assert_eq!(
        late_record_log(oldest, &person_at(0.0)).verdict,
        Verdict::Pass
    );
    let r = late_record_log(oldest, &person_at(0.001));
    // (The default human's measurement error is 0: it contradicts the kept record too.)
    assert_eq!(
        reasons(&r),
        ["human_exceeds_model", "human_record_too_late"]
    );
    assert_eq!(
        (r.inconclusive[0].t_start, r.inconclusive[0].t_end),
        (oldest, oldest)
    );
    assert_eq!(
        late_record_log(0.14, &person_at(0.0)).verdict,
        Verdict::Pass
    );
    let r = late_record_log(0.14, &person_at(-2.0));
    assert_eq!(reasons(&r), ["human_exceeds_model"]);
}

/// A 10 Hz tracker logged at 1 kHz: each measurement's stamp is repeated 100 times, more than
/// the 64 records the audit keeps. The repeats are checked against the kept ones of their
/// stamp, not taken as too late: the log passes.
#[test]
fn a_stamp_repeated_more_often_than_the_records_kept_is_not_too_late() {
    let far = person_at(0.0);
    let mut text = format!("{}\n", header("ssm"));
    for k in 0..=300 {
        let t = k as f64 * 0.001;
        text += &human_record(t, Some((k / 100) as f64 / 10.0), &far);
        text += &format!("{{\"type\":\"robot\",\"t\":{t},\"q\":[{AT_REST}]}}\n");
    }
    let r = run(&text);
    assert_eq!(r.verdict, Verdict::Pass, "{:?}", reasons(&r));
}

/// A 10 Hz logger writes its stamps as `0.0`, `0.1`, …, `1.5`: in doubles some steps are longer
/// than 0.1 s by a rounding (`1.1 − 1.0 = 0.10000000000000009`), which is no gap at the default
/// `max_gap` (0.1 s). A step of 0.1 s + 1 µs is one.
#[test]
fn a_10_hz_logger_leaves_no_gap_at_the_default_max_gap() {
    let log = |stamp: &dyn Fn(usize) -> f64| {
        let mut text = format!("{}\n", header("ssm"));
        for k in 0..=15 {
            let t = stamp(k);
            text += &human_record(t, None, &person_at(0.0));
            text += &format!("{{\"type\":\"robot\",\"t\":{t},\"q\":[{AT_REST}]}}\n");
        }
        run(&text)
    };
    let (a, b): (f64, f64) = ("1.0".parse().unwrap(), "1.1".parse().unwrap());
    assert!(
        b - a > 0.1,
        "the stamps' difference exceeds the step by a rounding"
    );
    let r = log(&|k| format!("{}", k as f64 / 10.0).parse().unwrap());
    assert_eq!(r.verdict, Verdict::Pass, "{:?}", r.inconclusive);
    let r = log(&|k| k as f64 * 0.100001);
    assert_eq!(r.verdict, Verdict::Inconclusive);
    assert!(reasons(&r).iter().all(|s| *s == "gap"), "{:?}", reasons(&r));
}
