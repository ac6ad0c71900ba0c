//! The audit catches injected violations (ground truth from exact geometry computed here) and
//! passes clean logs.

mod audit_common;

use audit_common::*;
use nalgebra::DVector;
use pacs_audit::{AuditConfig, ConstraintKind, Verdict};
use pacs_log::ModelRef;
use pacs_models::constraints::RegionSpec;
use pacs_models::{Constraint, ConstraintSpec, HumanModel};

fn gap_part(q: &[f64], kp: &[[f64; 3]], part: &str) -> f64 {
    let h = human_capsules(&human(), kp);
    let (_, hc) = h.iter().find(|(n, _)| n == part).unwrap();
    robot_capsules(&fr3(), q)
        .iter()
        .map(|(_, c)| capsule_gap(c, hc))
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn clean_log_passes_and_min_separation_is_a_lower_bound() {
    let robot = fr3();
    let h = human();
    let mut log = Log::new(ssm());
    let mut true_min = f64::INFINITY;
    let far = standing(2.0, 0.0);
    for i in 0..=500 {
        let t = i as f64 * 1e-3;
        if i % 10 == 0 {
            log.human(t, &far);
        }
        let q = q_at(0.4 * t.sin());
        true_min = true_min.min(min_gap(&robot, &q, &h, &far));
        log.robot(t, &q, Some(&[0.4 * t.cos(), 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]));
    }
    assert!(
        true_min > 0.5,
        "premise: human far from the robot ({true_min})"
    );
    let r = run(&log.text(), &AuditConfig::default()).unwrap();
    assert_eq!(r.verdict, Verdict::Pass, "{r:#?}");
    assert!(r.violations.is_empty() && r.inconclusive.is_empty());
    assert_eq!(r.metrics.samples, 501);
    assert_eq!(r.metrics.violation_fraction, 0.0);
    assert!((r.metrics.duration - 0.5).abs() < 1e-12);
    let lb = r.metrics.min_separation.unwrap();
    assert!(
        lb > 0.0 && lb <= true_min,
        "lower bound {lb} vs exact {true_min}"
    );
}

#[test]
fn violation_at_the_first_sample_is_caught_and_certain() {
    let robot = fr3();
    let h = human();
    let w = 0.5;
    let q0 = q_at(0.0);
    let touching = reaching(hand_contact(&q0, 0.02));
    assert!(
        min_gap(&robot, &q0, &h, &touching) < 0.0,
        "premise: contact at t = 0"
    );
    let far = standing(2.5, 0.0);
    let mut log = Log::new(ssm());
    log.human(0.0, &touching);
    for i in 0..=100 {
        let t = i as f64 * 1e-3;
        if i == 1 {
            log.human(0.0005, &far);
        }
        log.robot(t, &q_at(w * t), Some(&[w, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]));
    }
    let r = run(&log.text(), &AuditConfig::default()).unwrap();
    assert_eq!(r.verdict, Verdict::Fail);
    assert!(
        r.violations
            .iter()
            .all(|v| v.t_start == 0.0 && v.t_end == 0.001)
    );
    let v = r
        .violations
        .iter()
        .find(|v| v.body_part == "rHand")
        .unwrap();
    assert!(v.certain && v.constraint == ConstraintKind::Ssm);
    assert!(v.min_separation < 0.0);
    assert_eq!(r.metrics.violating_samples, 1);
    assert!((r.metrics.violation_fraction - 1.0 / 101.0).abs() < 1e-15);
}

#[test]
fn violation_at_the_last_sample_is_caught_and_certain() {
    let w = 1.0;
    let n = 300;
    let t_end = n as f64 * 1e-3;
    let kp = reaching(hand_contact(&q_at(w * t_end), 0.002));
    let mut log = Log::new(ssm());
    let mut first_contact = None;
    for i in 0..=n {
        let t = i as f64 * 1e-3;
        if i % 10 == 0 {
            log.human(t, &kp);
        }
        let q = q_at(w * t);
        if first_contact.is_none() && gap_part(&q, &kp, "rHand") < 0.0 {
            first_contact = Some(i);
        }
        log.robot(t, &q, Some(&[w, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]));
    }
    let first = first_contact.unwrap();
    assert!(
        first > 0 && first < n,
        "premise: contact only near the end ({first})"
    );
    let r = run(&log.text(), &AuditConfig::default()).unwrap();
    assert_eq!(r.verdict, Verdict::Fail);
    let v = r
        .violations
        .iter()
        .find(|v| v.body_part == "rHand" && v.link == "fr3_hand")
        .unwrap();
    assert_eq!(v.t_end, t_end);
    assert!(v.certain);
    // Every sample in exact contact is counted.
    assert!(r.metrics.violating_samples >= (n - first + 1) as u64);
}

#[test]
fn one_sample_human_spike_is_caught() {
    let robot = fr3();
    let h = human();
    let w = 0.5;
    let k = 50;
    let tk = k as f64 * 1e-3;
    let spike = reaching(hand_contact(&q_at(w * tk), 0.02));
    assert!(min_gap(&robot, &q_at(w * tk), &h, &spike) < 0.0);
    let far = standing(2.5, 0.0);
    let mut log = Log::new(ssm());
    for i in 0..=100 {
        let t = i as f64 * 1e-3;
        log.human(t, if i == k { &spike } else { &far });
        log.robot(t, &q_at(w * t), Some(&[w, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]));
    }
    let r = run(&log.text(), &AuditConfig::default()).unwrap();
    assert_eq!(r.verdict, Verdict::Fail);
    assert!(!r.violations.is_empty());
    for v in &r.violations {
        assert_eq!((v.t_start, v.t_end), (tk, tk + 1e-3));
    }
    assert!(
        r.violations
            .iter()
            .any(|v| v.body_part == "rHand" && v.certain)
    );
    assert_eq!(r.metrics.violating_samples, 1);
}

#[test]
fn robot_at_rest_in_contact_is_not_an_ssm_violation() {
    let q0 = q_at(0.0);
    let kp = reaching(hand_contact(&q0, 0.02));
    let mut log = Log::new(ssm());
    for i in 0..=100 {
        let t = i as f64 * 1e-3;
        log.human(t, &kp);
        log.robot(t, &q0, Some(&[0.0; 7]));
    }
    let r = run(&log.text(), &AuditConfig::default()).unwrap();
    assert_eq!(r.verdict, Verdict::Pass, "{:?}", r.violations);
}

fn slow_human_spec() -> pacs_models::HumanSpec {
    let mut s = human().spec().clone();
    s.v_max = vec![1e-3; s.keypoints.len()];
    s
}

#[test]
fn violation_only_between_samples_is_caught() {
    let robot = fr3();
    let h = HumanModel::new(slow_human_spec()).unwrap();
    let theta = 0.5;
    let dt = 0.4;
    let (qa, qm, qb) = (q_at(-theta), q_at(0.0), q_at(theta));
    let kp = reaching(hand_contact(&qm, 0.01));
    let ga = min_gap(&robot, &qa, &h, &kp);
    let gb = min_gap(&robot, &qb, &h, &kp);
    let gm = min_gap(&robot, &qm, &h, &kp);
    assert!(
        ga > 0.02 && gb > 0.02,
        "premise: samples clear ({ga}, {gb})"
    );
    assert!(gm < 0.0, "premise: midway configuration in contact ({gm})");
    // The midway configuration is reachable: joint 1 needs 2θ/Δt ≤ v_max.
    assert!(2.0 * theta / dt <= robot.limits().v_max()[0]);
    let mut log = Log::with_human(ModelRef::Spec(Box::new(slow_human_spec())), ssm());
    log.human(0.0, &kp);
    log.robot(0.0, &qa, None);
    log.robot(dt, &qb, None);
    let cfg = AuditConfig {
        max_gap: 1.0,
        ..AuditConfig::default()
    };
    let r = run(&log.text(), &cfg).unwrap();
    assert_eq!(r.verdict, Verdict::Fail);
    let v = r
        .violations
        .iter()
        .find(|v| v.body_part == "rHand")
        .unwrap();
    assert!(!v.certain, "not at a recorded sample");
    assert!(r.violations.iter().all(|v| !v.certain));
}

/// Task: every part PFL 100 J except the hands (thresholds given).
fn pfl_task(unconstrained: f64, constrained: f64) -> ConstraintSpec {
    ConstraintSpec {
        name: "test-pfl".into(),
        default: Constraint::Pfl {
            unconstrained: 100.0,
            constrained: 100.0,
        },
        regions: vec![RegionSpec {
            name: "hand".into(),
            body_parts: vec!["rHand".into()],
            constraint: Constraint::Pfl {
                unconstrained,
                constrained,
            },
        }],
    }
}

/// Exact nominal energy ½ q̇ᵀ M q̇ of the whole arm (frames 1..=7), from the mass matrix.
fn energy(q: &[f64], dq: &[f64]) -> f64 {
    let m = fr3().mass_matrix_upto(q, 7);
    let v = DVector::from_row_slice(dq);
    0.5 * v.dot(&(&m * &v))
}

/// Three samples 1 ms apart, joint 1 at constant speed `w`, right hand touching the gripper at
/// every sample; `left` places the left hand (None: far away).
fn pfl_log(task: ConstraintSpec, w: f64, left_on_right: bool) -> String {
    let mut log = Log::new(ModelRef::Spec(Box::new(task)));
    for i in 0..3 {
        let t = i as f64 * 1e-3;
        let q = q_at(w * t);
        let mut kp = reaching(hand_contact(&q, 0.01));
        if left_on_right {
            kp[L_HAND] = kp[R_HAND];
        }
        log.human(t, &kp);
        log.robot(t, &q, Some(&[w, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]));
    }
    log.text()
}

#[test]
fn pfl_energy_just_above_and_below_threshold() {
    let w = 0.8;
    let dq = [w, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    let e: Vec<f64> = (0..3)
        .map(|i| energy(&q_at(w * i as f64 * 1e-3), &dq))
        .collect();
    let (e_min, e_max) = (
        e.iter().cloned().fold(f64::INFINITY, f64::min),
        e.iter().cloned().fold(0.0, f64::max),
    );
    let kp = reaching(hand_contact(&q_at(0.0), 0.01));
    assert!(gap_part(&q_at(0.0), &kp, "rHand") < 0.0, "premise: contact");
    // Just above: 0.5 % below the exact energy at every sample → certain PFL violation.
    let r = run(
        &pfl_log(pfl_task(0.995 * e_min, 0.0), w, false),
        &AuditConfig::default(),
    )
    .unwrap();
    assert_eq!(r.verdict, Verdict::Fail);
    let v = r
        .violations
        .iter()
        .find(|v| v.body_part == "rHand" && v.link == "fr3_hand")
        .unwrap();
    assert!(
        v.certain && v.constraint == ConstraintKind::Pfl && !v.constrained,
        "{:?}",
        r.violations
    );
    assert!(v.energy >= e_max, "bound {} below exact {e_max}", v.energy);
    // Just below: 0.5 % above the exact energy → never a certain violation.
    let r = run(
        &pfl_log(pfl_task(1.005 * e_max, 0.0), w, false),
        &AuditConfig::default(),
    )
    .unwrap();
    assert!(
        r.violations.iter().all(|v| !v.certain),
        "{:?}",
        r.violations
    );
    // Above the bound's slack (measured ≈ 24 % here: interval dependency and the Gershgorin
    // inertia bound): pass.
    let r = run(
        &pfl_log(pfl_task(1.30 * e_max, 0.0), w, false),
        &AuditConfig::default(),
    )
    .unwrap();
    assert_eq!(r.verdict, Verdict::Pass, "{:?}", r.violations);
}

#[test]
fn pfl_constrained_vs_unconstrained() {
    let w = 0.8;
    let dq = [w, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    let e = energy(&q_at(0.0), &dq);
    // Independent clamping ground truth: with the left hand on the right hand, the two hand
    // capsules overlap (clampable pair); otherwise the left hand is far.
    let mut kp = reaching(hand_contact(&q_at(0.0), 0.01));
    let h = human_capsules(&human(), &kp);
    assert!(capsule_gap(&h[2].1, &h[5].1) > 1.0);
    kp[L_HAND] = kp[R_HAND];
    let h = human_capsules(&human(), &kp);
    assert!(capsule_gap(&h[2].1, &h[5].1) < 0.0);
    let task = pfl_task(10.0 * e, 0.5 * e);
    let free = run(&pfl_log(task.clone(), w, false), &AuditConfig::default()).unwrap();
    assert_eq!(free.verdict, Verdict::Pass, "{:?}", free.violations);
    let clamped = run(&pfl_log(task, w, true), &AuditConfig::default()).unwrap();
    assert_eq!(clamped.verdict, Verdict::Fail);
    let v = clamped
        .violations
        .iter()
        .find(|v| v.body_part == "rHand" && v.link == "fr3_hand")
        .unwrap();
    assert!(v.constrained && v.certain, "{:?}", clamped.violations);
    assert_eq!(v.threshold, 0.5 * e);
}

#[test]
fn environment_shape_makes_contact_constrained() {
    let w = 0.8;
    let e = energy(&q_at(0.0), &[w, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
    let task = pfl_task(10.0 * e, 0.5 * e);
    let text = pfl_log(task, w, false);
    // Add a wall (capsule) through the right hand's position to the header.
    let hand = hand_contact(&q_at(0.0), 0.01);
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let mut header: serde_json::Value = serde_json::from_str(&lines[0]).unwrap();
    header["environment"] =
        serde_json::json!([{"p1": hand, "p2": [hand[0], hand[1], hand[2] + 0.5], "radius": 0.05}]);
    lines[0] = header.to_string();
    let r = run(&(lines.join("\n") + "\n"), &AuditConfig::default()).unwrap();
    let v = r
        .violations
        .iter()
        .find(|v| v.body_part == "rHand" && v.link == "fr3_hand")
        .unwrap();
    assert!(v.constrained && v.certain, "{:?}", r.violations);
}

#[test]
fn gaps_missing_human_and_limit_violations_are_inconclusive() {
    let far = standing(2.5, 0.0);
    // No human record at all.
    let mut log = Log::new(ssm());
    log.robot(0.0, &Q_READY, None).robot(0.001, &Q_READY, None);
    let r = run(&log.text(), &AuditConfig::default()).unwrap();
    assert_eq!(r.verdict, Verdict::Inconclusive);
    assert_eq!(r.inconclusive[0].reason, "no_human");
    // A gap longer than max_gap.
    let mut log = Log::new(ssm());
    log.human(0.0, &far);
    log.robot(0.0, &Q_READY, None).robot(0.5, &Q_READY, None);
    let r = run(&log.text(), &AuditConfig::default()).unwrap();
    assert_eq!(r.verdict, Verdict::Inconclusive);
    assert_eq!(r.inconclusive[0].reason, "gap");
    assert_eq!(
        (r.inconclusive[0].t_start, r.inconclusive[0].t_end),
        (0.0, 0.5)
    );
    // Samples moving faster than v_max.
    let mut log = Log::new(ssm());
    log.human(0.0, &far);
    log.robot(0.0, &q_at(0.0), None)
        .robot(0.001, &q_at(0.1), None);
    let r = run(&log.text(), &AuditConfig::default()).unwrap();
    assert_eq!(r.verdict, Verdict::Inconclusive);
    assert_eq!(r.inconclusive[0].reason, "exceeds_limits");
    // A single robot sample covers no time.
    let mut log = Log::new(ssm());
    log.human(0.0, &far);
    log.robot(0.0, &Q_READY, None);
    let r = run(&log.text(), &AuditConfig::default()).unwrap();
    assert_eq!(r.verdict, Verdict::Inconclusive);
}

#[test]
fn success_events_give_safe_success() {
    let far = standing(2.5, 0.0);
    let mut log = Log::new(ssm());
    log.human(0.0, &far);
    log.robot(0.0, &Q_READY, None).robot(0.001, &Q_READY, None);
    log.w.write_event(0.001, "success").unwrap();
    let r = run(&log.text(), &AuditConfig::default()).unwrap();
    assert_eq!(r.verdict, Verdict::Pass);
    assert_eq!(r.metrics.success, Some(true));
    assert_eq!(r.metrics.safe_success, Some(true));
}

#[test]
fn human_record_after_the_last_robot_sample_is_never_pass() {
    // The human is far for the whole log, then a record stamped at the last sample's time (but
    // written after it) puts the hand on the tool: no span covers it, so the log must not pass.
    let w = 1.0;
    let n = 100;
    let t_end = n as f64 * 1e-3;
    let far = standing(2.0, 0.0);
    let mut log = Log::new(ssm());
    for i in 0..=n {
        let t = i as f64 * 1e-3;
        if i % 10 == 0 {
            log.human(t, &far);
        }
        log.robot(t, &q_at(w * t), Some(&[w, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]));
    }
    let kp = reaching(hand_contact(&q_at(w * t_end), 0.002));
    assert!(
        gap_part(&q_at(w * t_end), &kp, "rHand") < 0.0,
        "premise: contact at the last sample"
    );
    log.human(t_end, &kp);
    let r = run(&log.text(), &AuditConfig::default()).unwrap();
    assert_ne!(r.verdict, Verdict::Pass, "{r:#?}");
    // Without the late record the same log passes (the test is not vacuous).
    let mut clean = Log::new(ssm());
    for i in 0..=n {
        let t = i as f64 * 1e-3;
        if i % 10 == 0 {
            clean.human(t, &far);
        }
        clean.robot(t, &q_at(w * t), Some(&[w, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]));
    }
    assert_eq!(
        run(&clean.text(), &AuditConfig::default()).unwrap().verdict,
        Verdict::Pass
    );
}

/// The plot series tells the coarse far-range figure from the robot's occupancy: with the person
/// beyond the workspace ball, every bucket has `far_separation` (positive, and a lower bound of
/// the true distance at each sample), no `min_separation`; with the person within reach, buckets
/// have `min_separation` (a lower bound too) and no `far_separation`.
#[test]
fn far_and_near_separation_figures_are_drawn_apart() {
    let robot = fr3();
    let h = human();
    for (x, far) in [(3.0, true), (0.9, false)] {
        let kp = standing(x, 0.0);
        let mut log = Log::new(ssm());
        // The true distance at each sample (s, m).
        let mut truth: Vec<(f64, f64)> = Vec::new();
        for k in 0..=300 {
            let t = k as f64 * 1e-3;
            if k % 30 == 0 {
                log.human(t, &kp);
            }
            let q = q_at(0.2 * t);
            truth.push((t, min_gap(&robot, &q, &h, &kp)));
            log.robot(t, &q, None);
        }
        let r = run(&log.text(), &AuditConfig::default()).unwrap();
        let checked: Vec<_> = r.series.iter().filter(|p| !p.inconclusive).collect();
        assert!(checked.len() > 10, "x = {x}: {} buckets", checked.len());
        for p in checked {
            let (fig, other) = if far {
                (p.far_separation, p.min_separation)
            } else {
                (p.min_separation, p.far_separation)
            };
            let f = fig.unwrap_or_else(|| panic!("x = {x}: bucket at {} without its figure", p.t));
            assert!(other.is_none(), "x = {x}: both figures at {}", p.t);
            // A lower bound over the bucket's spans: at most the true distance at its samples.
            let here = truth
                .iter()
                .filter(|(t, _)| *t >= p.t && *t <= p.t_end)
                .map(|(_, d)| *d)
                .fold(f64::INFINITY, f64::min);
            assert!(
                f <= here,
                "x = {x}: {f} m above the true {here} m at {}",
                p.t
            );
            if far {
                assert!(f > 0.0, "x = {x}: far figure {f}");
            }
        }
        let m = r.metrics.min_separation.unwrap();
        let least = truth.iter().map(|(_, d)| *d).fold(f64::INFINITY, f64::min);
        assert!(
            m <= least,
            "x = {x}: run minimum {m} above the true {least}"
        );
    }
}

/// A person standing at `x` (m) in front of the arm (joint 1 turning at 0.05 rad/s from the
/// ready pose, SSM), measured every 10 ms with a model of 1 cm position error and 0.5 m/s;
/// record `i` (stamp `i`·10 ms) is moved by `offset(i)` (m, along x towards the arm and along
/// y), within the 2 cm that two records may differ by.
fn shifted_person_log(x: f64, offset: &dyn Fn(usize) -> (f64, f64)) -> String {
    let mut spec = human().spec().clone();
    spec.v_max = vec![0.5; spec.keypoints.len()];
    spec.measurement_error_pos = 0.01;
    let mut log = Log::with_human(ModelRef::Spec(Box::new(spec)), ssm());
    for k in 0..=200 {
        let t = k as f64 * 1e-3;
        if k % 10 == 0 {
            let (dx, dy) = offset(k / 10);
            log.human(t, &standing(x - dx, dy));
        }
        let mut q = Q_READY;
        q[0] += 0.05 * t;
        let mut dq = [0.0; 7];
        dq[0] = 0.05;
        log.robot(t, &q, Some(&dq));
    }
    log.text()
}

/// As for objects (`audit_objects::an_earlier_measurement_clears_a_span_the_newest_cannot`):
/// a (body part, link) pair that the occupancy of an earlier measurement still in use clears
/// is clear, even where the newest one, shifted within the measurement error, reaches the
/// arm; where every measurement still usable for a span reports a pair, the log fails.
#[test]
fn an_earlier_person_measurement_clears_a_span_the_newest_cannot() {
    let verdict = |x: f64, offset: &dyn Fn(usize) -> (f64, f64)| {
        let r = run(&shifted_person_log(x, offset), &AuditConfig::default()).unwrap();
        assert!(r.inconclusive.is_empty(), "x {x}: {:?}", r.inconclusive);
        r.verdict
    };
    let still = |_: usize| (0.0, 0.0);
    // The least distance that passes unshifted, to 0.25 mm.
    let (mut lo, mut hi) = (0.0, 2.5);
    assert_eq!(verdict(lo, &still), Verdict::Fail);
    assert_eq!(verdict(hi, &still), Verdict::Pass);
    while hi - lo > 2.5e-4 {
        let mid = 0.5 * (lo + hi);
        if verdict(mid, &still) == Verdict::Pass {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    // 7 mm more: the record 10 ms older than a span's newest reaches at most 5 mm further.
    let x = hi + 0.007;
    assert_eq!(verdict(x, &still), Verdict::Pass);
    // The record of 0.1 s 15 mm closer: the spans it is the newest for are cleared by the
    // record of 0.09 s.
    assert_eq!(
        verdict(x, &|i| if i == 10 { (0.015, 0.0) } else { (0.0, 0.0) }),
        Verdict::Pass
    );
    // Every record from 0.05 s on 15 mm closer, alternately 4 mm to either side (so that the
    // record before the one in use is not covered by it, and is tried): it reports the same
    // pairs, and the log fails.
    let zigzag = |i: usize| {
        if i >= 5 {
            (0.015, if i.is_multiple_of(2) { 0.004 } else { -0.004 })
        } else {
            (0.0, 0.0)
        }
    };
    assert_eq!(verdict(x, &zigzag), Verdict::Fail);
    assert_eq!(verdict(x, &|_| (0.015, 0.0)), Verdict::Fail);
}
