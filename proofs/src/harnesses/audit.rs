//! (h) The offline audit never returns `pass` when a recorded sample violates the constraint.
//!
//! A short log (FR3, default human, SSM everywhere) with random robot samples; at one sample the
//! robot moves (a joint speed above the rest threshold) while the human — standing still, measured
//! from the start (and optionally again at that sample) — has every keypoint on a point of a
//! moving link's capsule at that configuration: a recorded SSM violation by an admissible human.
//! The verdict must not be `pass`. (The human must be admissible: the audit's semantics assume
//! the human model, and a human record that teleports onto the robot at the *last* robot sample
//! covers no span — see README, "doubtful".)

use crate::{Source, harness};
use pacs_audit::{AuditConfig, Auditor, Verdict};
use pacs_log::LogModels;
use pacs_models::{ConstraintSpec, HumanModel, RobotModel};
use pacs_reach::JointBox;

/// Audit one random violating log; the verdict.
fn violating_log<S: Source>(s: &mut S) -> Verdict {
    let robot = RobotModel::builtin("fr3").expect("builtin");
    let human = HumanModel::builtin("default").expect("builtin");
    let models = LogModels {
        robot: robot.clone(),
        human: human.clone(),
        people: vec![("human".into(), human.clone())],
        constraints: ConstraintSpec::builtin("ssm").expect("preset"),
        environment: vec![],
        objects: vec![],
    };
    let cfg = AuditConfig::default();
    let mut auditor = Auditor::new(models, cfg.clone()).expect("valid models");
    let n = robot.dof();
    let samples = 2 + s.index(4);
    let k = s.index(samples); // the violating sample
    let dt = s.f64_in(0.001, 0.05);
    let lim = robot.limits();
    // Robot samples first (small motions consistent with the limits).
    let mut qs = vec![
        (0..n)
            .map(|i| s.f64_in(lim.q_min()[i] + 0.1, lim.q_max()[i] - 0.1))
            .collect::<Vec<f64>>(),
    ];
    let mut dqs = Vec::new();
    for i in 0..samples {
        let mut dq: Vec<f64> = (0..n).map(|_| s.f64_in(-0.5, 0.5)).collect();
        if i == k {
            // Moving at the violating sample: joint 0 clearly above the rest speed.
            dq[0] = if s.bool() { 1.0 } else { -1.0 } * s.f64_in(10.0 * cfg.rest_speed, 1.0);
        }
        let next: Vec<f64> = qs[i].iter().zip(&dq).map(|(q, v)| q + v * dt).collect();
        dqs.push(dq);
        qs.push(next);
    }
    // The human stands still with every keypoint on a point of a moving link capsule at q_k
    // (an admissible motion: measured at 0 and, optionally, again at t_k).
    let caps = robot.capsules_world(&qs[k]);
    let moving: Vec<_> = caps
        .iter()
        .filter(|(li, _)| robot.links()[*li].frame > 0)
        .map(|(_, c)| *c)
        .collect();
    let c = moving[s.index(moving.len())];
    let lambda = s.f64_in(0.0, 1.0);
    let p = c.p1() + (c.p2() - c.p1()) * lambda;
    let on_robot = vec![[p.x, p.y, p.z]; human.keypoint_count()];
    auditor.push_human(0.0, 0.0, &on_robot).expect("valid");
    let remeasure = s.bool();
    let with_dq = s.bool();
    for i in 0..samples {
        let t = i as f64 * dt;
        if i == k && remeasure {
            auditor.push_human(t, t, &on_robot).expect("valid");
        }
        let dq = (with_dq || i == k).then_some(&dqs[i][..]);
        auditor.push_robot(t, &qs[i], dq).expect("valid sample");
    }
    auditor.finish("harness", Default::default()).verdict
}

fn audit_violation<S: Source>(s: &mut S) {
    let verdict = violating_log(s);
    assert!(
        verdict != Verdict::Pass,
        "audit passed a log with a violating sample"
    );
}

/// Not vacuous: at least 90 % of the violating logs are judged `fail` (not just `inconclusive`).
#[cfg(test)]
#[test]
fn h1_violating_logs_mostly_fail() {
    let cases = 2000;
    let mut fails = 0;
    crate::run_cases("h1_violating_logs_mostly_fail", cases, |s| {
        if violating_log(s) == Verdict::Fail {
            fails += 1;
        }
    });
    assert!(
        fails * 10 >= cases * 9,
        "only {fails} of {cases} violating logs judged fail"
    );
}
harness!(
    h1_audit_never_passes_violation,
    twin_only,
    cases = crate::DEFAULT_CASES,
    audit_violation
);

// ---- Kani splits of h1 ----------------------------------------------------------------------
//
// h1 is the whole audit (parsing, span enclosures, occupancies, the rule, the bookkeeping): a
// property test only. Its parts are model-checked where a model checker can decide them: the
// span enclosure (h2's three splits), the rule (i1's two splits), the occupancies' arithmetic
// (a–c, f2) — and the two audit-specific steps below: the union of span boxes the block fast
// path checks instead of each span, and the verdict from the findings.

/// A joint box of two joints in [−10, 10] (rad or rad/s), lower end at most the upper.
fn two_joint_box<S: Source>(s: &mut S) -> Option<JointBox> {
    let (a, b) = (s.f64_in(-10.0, 10.0), s.f64_in(-10.0, 10.0));
    let (c, d) = (s.f64_in(-10.0, 10.0), s.f64_in(-10.0, 10.0));
    if !s.assume(a <= b && c <= d) {
        return None;
    }
    JointBox::new(&[a, c], &[b, d]).ok()
}

/// (h1, the block fast path) The audit checks a block of spans at once on the hull of their
/// boxes (`SpanBoxes::hull`, i.e. `JointBox::hull` of the position and velocity boxes): "no
/// violation possible on the hull" implies it for each span only if every joint state of either
/// box lies in the hull. Any two boxes of two joints (the loop is per joint), any state of
/// either. Catches mutant `x28_joint_box_hull_keeps_first` (the hull keeps the first box's lower
/// ends). The hull runs over all `MAX_DOF` lanes when the counts agree (unwind 17).
fn block_hull<S: Source>(s: &mut S) {
    let (Some(a), Some(b)) = (two_joint_box(s), two_joint_box(s)) else {
        return;
    };
    let h = a.hull(&b);
    let from = if s.bool() { a } else { b };
    let q = [
        s.f64_in(from.lo()[0], from.hi()[0]),
        s.f64_in(from.lo()[1], from.hi()[1]),
    ];
    assert!(
        h.contains(&q),
        "{q:?} in {from:?} but not in the hull {h:?} of {a:?} and {b:?}"
    );
}
harness!(
    h1_block_hull_contains,
    unwind = 17,
    cases = crate::DEFAULT_CASES,
    block_hull
);

/// (h1, the verdict) A log's verdict (`Verdict::of_findings`, what `Auditor::finish` returns) is
/// `fail` whenever a violation was recorded and never `pass` with an unchecked span; the verdict
/// over several logs (`Verdict::combine`, the CLI's exit code) is `pass` only if every log
/// passed and `fail` if any failed. Any findings, any sequence of up to three verdicts.
fn verdict_of_findings<S: Source>(s: &mut S) {
    let (violation, unchecked) = (s.bool(), s.bool());
    let v = Verdict::of_findings(violation, unchecked);
    assert!(!violation || v == Verdict::Fail, "a violation is not fail");
    assert!(
        v != Verdict::Pass || (!violation && !unchecked),
        "pass with findings"
    );
    assert!(
        violation || unchecked || v == Verdict::Pass,
        "a clean log is not pass"
    );
    let all = [Verdict::Pass, Verdict::Fail, Verdict::Inconclusive];
    let n = s.index(4);
    let logs = [all[s.index(3)], all[s.index(3)], all[s.index(3)]];
    let c = Verdict::combine(logs[..n].iter().copied());
    let any_fail = logs[..n].contains(&Verdict::Fail);
    let all_pass = logs[..n].iter().all(|v| *v == Verdict::Pass);
    assert!(!any_fail || c == Verdict::Fail, "a failing log is hidden");
    assert!(
        (c == Verdict::Pass) == all_pass,
        "pass iff every log passed"
    );
}
harness!(
    h1_verdict_never_hides_findings,
    unwind = 5,
    cases = crate::DEFAULT_CASES,
    verdict_of_findings
);

/// The rest-speed cap of the one rule (claim C9 and C8′: SSM allows contact only while every
/// joint speed is at most `rest_speed`, so a larger setting would let SSM pass a moving robot):
/// for any float `r` (NaN and ±∞ included), `check_rest_speed(r)` — which the rule's
/// constructors and the audit's [`AuditConfig::validate`] call — accepts `r` only within
/// `[0, MAX_REST_SPEED]`, and an audit config with `rest_speed = r` validates only then too.
/// Mutant `x58` (the cap lifted) fails it.
fn rest_speed_capped<S: Source>(s: &mut S) {
    use pacs_verify::iso15066::{MAX_REST_SPEED, check_rest_speed};
    let r = match s.index(3) {
        0 => s.f64_full(-1.0, 1.0),
        // Near the cap (in the twin; any float of the range under Kani).
        1 => s.f64_full(0.9 * MAX_REST_SPEED, 1.1 * MAX_REST_SPEED),
        // Any bit pattern: NaN, ±∞, every magnitude.
        _ => f64::from_bits(s.index(usize::MAX) as u64),
    };
    let within = (0.0..=MAX_REST_SPEED).contains(&r);
    if check_rest_speed(r).is_ok() {
        assert!(within, "rest speed {r} rad/s accepted above the cap");
    }
    let cfg = AuditConfig {
        rest_speed: r,
        ..AuditConfig::default()
    };
    if cfg.validate().is_ok() {
        assert!(
            within,
            "an audit config with rest speed {r} rad/s validated"
        );
    }
}
harness!(
    h3_rest_speed_capped,
    unwind = 8,
    bits = 52,
    cases = pacs_proof_kit::DEFAULT_CASES,
    rest_speed_capped
);
