//! Shield scenarios with scripted humans: safety against the ground-truth human motion, path
//! consistency, progress when the human leaves, and the OFF baseline's violations.

use nalgebra::Point3;
use pacs_models::{ConstraintSpec, HumanModel, default_human, fr3};
use pacs_motion::chunk::{ActionKind, Chunk};
use pacs_reach::geometry::segment_distance_lower_bound;
use pacs_reach::human::HumanMeasurement;
use pacs_shield::shield::{EnvShape, FilterMode, Shield, ShieldConfig};

const Q0: [f64; 7] = fr3::Q_READY;

use pacs_testkit::true_separation;

fn chunk(delta: [f64; 7], h: usize) -> Chunk {
    Chunk {
        kind: ActionKind::Delta,
        actions: vec![delta.to_vec(); 16],
        execute: h,
        gripper: None,
    }
}

struct Run {
    qs: Vec<[f64; 7]>,
    moving_contact: usize,
    verified: usize,
    steps: usize,
}

/// Run `steps` safety steps; a new chunk every `every` steps; the human from `script(t)`.
/// The scripted motion must respect the human model (speed ≤ v_max per keypoint), otherwise the
/// shield's guarantee does not apply and the test would prove nothing.
fn assert_admissible(human: &HumanModel, script: &dyn Fn(f64) -> Vec<[f64; 3]>, t_end: f64) {
    let dt = 1e-3;
    let mut prev = script(-0.1);
    let mut t = -0.1 + dt;
    while t <= t_end {
        let cur = script(t);
        for (k, (a, b)) in prev.iter().zip(&cur).enumerate() {
            let v =
                ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt() / dt;
            assert!(
                v <= human.v_max()[k] * (1.0 + 1e-9),
                "script: keypoint {k} at {v} m/s at t = {t}"
            );
        }
        prev = cur;
        t += dt;
    }
}

fn run(
    mode: FilterMode,
    spec: &str,
    steps: usize,
    every: usize,
    delta: [f64; 7],
    script: &dyn Fn(f64) -> Vec<[f64; 3]>,
) -> Run {
    let robot = fr3::fr3();
    let human = default_human().with_uncertainty(0.01, 0.1, 0.02).unwrap();
    let spec = ConstraintSpec::builtin(spec).unwrap();
    let cfg = ShieldConfig {
        mode,
        ..ShieldConfig::default()
    };
    assert_admissible(&human, script, steps as f64 * cfg.safety_step);
    let mut sh = Shield::new(robot.clone(), Some((human.clone(), &spec)), vec![], cfg).unwrap();
    sh.start(0.0, &Q0).unwrap();
    let dt = cfg.safety_step;
    let mut out = Run {
        qs: vec![],
        moving_contact: 0,
        verified: 0,
        steps,
    };
    for k in 0..steps {
        let t = k as f64 * dt;
        if k % every == 0 {
            let _ = sh.set_chunk(&chunk(delta, 8));
        }
        // Camera: the true state at t - delay, stamped t (no noise here).
        let truth_then = script(t - human.delay());
        let m = HumanMeasurement::new(&human, t, &truth_then, None).unwrap();
        let cmd = sh.step(t, Some(&m)).expect("started");
        let mut q = [0.0; 7];
        q.copy_from_slice(cmd.q());
        let moving = cmd.dq().iter().any(|v| v.abs() > 1e-12);
        let sep = true_separation(&robot, &human, &q, &script(cmd.t));
        if moving && sep <= 0.0 {
            out.moving_contact += 1;
            if std::env::var("SHIELD_DEBUG").is_ok() {
                eprintln!(
                    "CONTACT t={t:.3} sep={sep:.4} dq={:.2e} verified={} fs={} sd={:.4} bind={:?}",
                    cmd.dq().iter().fold(0.0f64, |a, b| a.max(b.abs())),
                    cmd.diag.verified,
                    cmd.diag.on_failsafe,
                    cmd.diag.path_speed,
                    cmd.diag.binding
                );
            }
        }
        if cmd.diag.verified {
            out.verified += 1;
        }
        if std::env::var("SHIELD_DEBUG").is_ok() && k % 100 == 0 {
            eprintln!(
                "t={t:.3} q1={:.4} sd={:.3} verified={} fs={} bind={:?} sep_lb={:.3} true_sep={sep:.3} stop={:.3}",
                q[0],
                cmd.diag.path_speed,
                cmd.diag.verified,
                cmd.diag.on_failsafe,
                cmd.diag.binding,
                cmd.diag.min_separation,
                cmd.diag.stop_time
            );
        }
        out.qs.push(q);
    }
    out
}

const DELTA: [f64; 7] = [0.01, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
/// Faster actions for the PFL scenarios (joint 1 reaches ~1 rad/s): OFF exceeds the thresholds.
const FAST: [f64; 7] = [0.08, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];

#[test]
fn free_motion_completes_without_a_human_nearby() {
    let far = |_t: f64| pacs_testkit::human_reaching(3.0, 0.0, [2.8, -0.2, 1.0]);
    let r = run(FilterMode::Pacs, "sorting", 1500, 400, DELTA, &far);
    assert_eq!(r.moving_contact, 0);
    assert!(
        r.verified > r.steps * 9 / 10,
        "verified {} of {}",
        r.verified,
        r.steps
    );
    let moved = r.qs.last().unwrap()[0] - Q0[0];
    assert!(moved > 0.2, "joint 1 moved only {moved} rad");
}

#[test]
fn ssm_never_moves_into_a_person_standing_at_the_tool() {
    let close = |_t: f64| pacs_testkit::human_reaching(0.9, 0.3, [0.32, 0.12, 0.45]);
    let r = run(FilterMode::Pacs, "sorting", 1000, 400, DELTA, &close);
    assert_eq!(r.moving_contact, 0, "robot moved while in contact");
    let off = run(FilterMode::Off, "sorting", 1000, 400, DELTA, &close);
    assert!(
        off.moving_contact > 0,
        "OFF should collide in this scenario"
    );
    // OFF executes every step but reports which ones verified: not those moving into the
    // person (an executed step is not therefore `verified`).
    assert!(
        off.verified < off.steps / 2,
        "OFF reports {} of {} steps verified while moving into the person",
        off.verified,
        off.steps
    );
}

#[test]
fn person_walks_in_and_leaves_robot_resumes_on_the_same_path() {
    // Approach over 1 s (hand ≤ 1.3 m/s, within the model's 2 m/s), stay, leave over 1 s.
    let script = |t: f64| {
        let far = [1.6, 0.2, 1.0];
        let near = [0.45, 0.15, 0.5];
        let w = if t < 0.3 {
            0.0
        } else if t < 1.3 {
            t - 0.3
        } else if t < 2.0 {
            1.0
        } else if t < 3.0 {
            1.0 - (t - 2.0)
        } else {
            0.0
        };
        let hand = [
            far[0] + w * (near[0] - far[0]),
            far[1] + w * (near[1] - far[1]),
            far[2] + w * (near[2] - far[2]),
        ];
        pacs_testkit::human_reaching(1.4 - 0.3 * w, 0.2, hand)
    };
    let r = run(FilterMode::Pacs, "sorting", 4000, 400, DELTA, &script);
    assert_eq!(r.moving_contact, 0);
    let q_at = |k: usize| r.qs[k][0];
    assert!(
        q_at(3999) > q_at(3100) + 0.01,
        "no progress after the person left: {} -> {}",
        q_at(3100),
        q_at(3999)
    );
    for w in r.qs.windows(2) {
        assert!(w[1][0] >= w[0][0] - 1e-12, "moved backwards on the path");
        for i in 1..7 {
            assert!(
                (w[1][i] - Q0[i]).abs() < 1e-9,
                "joint {i} left the path: {}",
                w[1][i]
            );
        }
    }
}

/// Moving contacts of a PFL run, with the nominal energy of the whole moving robot at contact.
fn pfl_contacts(
    spec: &str,
    script: &dyn Fn(f64) -> Vec<[f64; 3]>,
    mode: FilterMode,
    steps: usize,
    env: Vec<EnvShape>,
    clamped: bool,
) -> (usize, f64, f64) {
    let robot = fr3::fr3();
    let human = default_human().with_uncertainty(0.01, 0.1, 0.02).unwrap();
    let cs = ConstraintSpec::builtin(spec).unwrap();
    let tc = cs.resolve(&human).unwrap();
    let cfg = ShieldConfig {
        mode,
        ..ShieldConfig::default()
    };
    assert_admissible(&human, script, steps as f64 * cfg.safety_step);
    let mut sh = Shield::new(robot.clone(), Some((human.clone(), &cs)), env, cfg).unwrap();
    sh.start(0.0, &Q0).unwrap();
    let (mut contacts, mut worst_ratio, mut progress) = (0, 0.0f64, 0.0);
    for k in 0..steps {
        let t = k as f64 * cfg.safety_step;
        if k % 400 == 0 {
            let _ = sh.set_chunk(&chunk(FAST, 8));
        }
        let m = HumanMeasurement::new(&human, t, &script(t - human.delay()), None).unwrap();
        let cmd = sh.step(t, Some(&m)).expect("started");
        let q = cmd.q();
        let dq = cmd.dq();
        progress = q[0] - Q0[0];
        // Ground truth: any body part in contact with a moving link?
        let kp = script(cmd.t);
        let caps = robot.capsules_world(q);
        let mut e = [0.0; 8];
        robot.subchain_energies_into(q, dq, &mut e);
        for (b, bp) in human.body_parts().iter().enumerate() {
            let (a, bb) = (Point3::from(kp[bp.from]), Point3::from(kp[bp.to]));
            for (li, c) in &caps {
                let frame = robot.links()[*li].frame;
                if frame == 0 {
                    continue;
                }
                let d = segment_distance_lower_bound(&a, &bb, &c.p1(), &c.p2())
                    - c.radius()
                    - bp.thickness / 2.0;
                if d <= 0.0 && e[frame] > 0.0 {
                    contacts += 1;
                    // Ground truth contact type is known by construction of the scenario.
                    let thr = tc.per_part[b].threshold(clamped).max(1e-12);
                    worst_ratio = worst_ratio.max(e[frame] / thr);
                }
            }
        }
    }
    (contacts, worst_ratio, progress)
}

#[test]
fn handover_pfl_contact_energy_stays_below_threshold() {
    // The right hand comes to the gripper's path and stays there.
    let script = |t: f64| {
        let w = ((t - 0.2) / 0.6).clamp(0.0, 1.0);
        let hand = [1.2 - w * (1.2 - 0.33), 0.1, 1.0 - w * (1.0 - 0.45)];
        pacs_testkit::human_reaching(1.4, 0.2, hand)
    };
    let (contacts, ratio, progress) =
        pfl_contacts("handover", &script, FilterMode::Pacs, 2000, vec![], false);
    assert!(
        ratio <= 1.0,
        "PACS: contact energy {ratio}× the unconstrained threshold"
    );
    let (off_contacts, off_ratio, _) =
        pfl_contacts("handover", &script, FilterMode::Off, 2000, vec![], false);
    assert!(
        off_contacts > 0 && off_ratio > 1.0,
        "OFF should exceed the threshold: {off_contacts} contacts, {off_ratio}×"
    );
    // PFL lets the robot keep moving slowly near the hand instead of stopping far away.
    assert!(progress > 0.0, "no progress at all ({contacts} contacts)");
}

#[test]
fn feeding_pfl_head_approach_is_safe() {
    // The head leans toward the tool (fork) at 0.3 m/s.
    let script = |t: f64| {
        let w = ((t - 0.1) / 1.0).clamp(0.0, 1.0);
        let x = 1.0 - 0.45 * w;
        let mut kp = pacs_testkit::human_reaching(x + 0.1, 0.0, [x, -0.3, 1.0]);
        kp[8] = [x - 0.05, 0.05, 0.62]; // head low, in front of the robot
        kp[6] = [x + 0.05, 0.0, 0.75];
        kp
    };
    let (_, ratio, _) = pfl_contacts("feeding", &script, FilterMode::Pacs, 2000, vec![], false);
    assert!(ratio <= 1.0, "PACS: head contact energy {ratio}× threshold");
}

#[test]
fn hand_resting_on_the_table_gets_the_constrained_threshold() {
    // The hand lies on a table top (z = 0.36 m) under the gripper's path: clamping is possible.
    let table = EnvShape::Box {
        min: [0.1, -0.6, 0.0],
        max: [1.0, 0.6, 0.36],
    };
    let script = |t: f64| {
        let w = ((t - 0.2) / 0.6).clamp(0.0, 1.0);
        let hand = [1.2 - w * (1.2 - 0.33), 0.1, 0.45];
        pacs_testkit::human_reaching(1.4, 0.2, hand)
    };
    let (_, ratio, _) = pfl_contacts(
        "handover",
        &script,
        FilterMode::Pacs,
        2000,
        vec![table],
        true,
    );
    assert!(
        ratio <= 1.0,
        "PACS: clamped contact energy {ratio}× the constrained threshold"
    );
    let (_, off_ratio, _) = pfl_contacts(
        "handover",
        &script,
        FilterMode::Off,
        2000,
        vec![table],
        true,
    );
    assert!(
        off_ratio > 1.0,
        "OFF should exceed the constrained threshold ({off_ratio}×)"
    );
}

#[test]
fn step_before_start_carries_no_joint_targets() {
    let human = default_human();
    let spec = ConstraintSpec::builtin("sorting").unwrap();
    let mut sh = Shield::new(
        fr3::fr3(),
        Some((human, &spec)),
        vec![],
        ShieldConfig::default(),
    )
    .unwrap();
    assert_eq!(
        sh.step(0.0, None),
        Err(pacs_shield::shield::ShieldError::NotStarted),
        "a not-started shield must not hand out joint targets"
    );
    assert!(sh.set_chunk(&chunk(DELTA, 8)).is_err());
}

/// The PFL energy bound includes the controller's velocity tracking error: a robot commanded to
/// stay at rest with the hand on its gripper verifies under the handover thresholds with the
/// default margin, but not with a margin whose kinetic energy alone exceeds the hand's threshold.
#[test]
fn velocity_tracking_margin_enters_the_pfl_energy_bound() {
    let robot = fr3::fr3();
    let human = default_human().with_uncertainty(0.01, 0.1, 0.02).unwrap();
    let spec = ConstraintSpec::builtin("handover").unwrap();
    let tool = {
        let f = robot.frames(&Q0);
        (f[7] * fr3::tcp_in_joint7()).translation.vector
    };
    // The right hand on the tool, the person 0.8 m in front.
    let kp = pacs_testkit::human_reaching(tool.x + 0.8, tool.y, [tool.x + 0.05, tool.y, tool.z]);
    let step_once = |margin: f64| {
        let cfg = ShieldConfig {
            velocity_tracking_error: margin,
            ..ShieldConfig::default()
        };
        let mut sh = Shield::new(robot.clone(), Some((human.clone(), &spec)), vec![], cfg).unwrap();
        sh.start(0.0, &Q0).unwrap();
        let m = HumanMeasurement::new(&human, 0.0, &kp, None).unwrap();
        sh.step(0.0, Some(&m)).expect("started").diag
    };
    let small = step_once(0.004);
    assert!(small.verified, "{small:?}");
    assert!(
        small.contact_energy > 0.0,
        "contact possible, margin energy > 0: {small:?}"
    );
    assert!(small.contact_energy <= small.contact_threshold);
    let large = step_once(2.0);
    assert!(!large.verified, "{large:?}");
    assert!(large.contact_energy > large.contact_threshold, "{large:?}");
    let invalid = ShieldConfig {
        velocity_tracking_error: f64::NAN,
        ..ShieldConfig::default()
    };
    assert!(Shield::new(robot.clone(), Some((human.clone(), &spec)), vec![], invalid).is_err());
}

/// Continuous chunk motion ([`ChunkMotion::Continuous`]) with nobody near: each chunk is handed
/// over as the robot reaches its last waypoint, and the robot keeps moving across hand-overs
/// (it never stops between chunks once it has ramped up), verifies ≥ 97 % of its steps, never
/// moves backwards along the path, and covers more distance than stopping at every chunk.
#[test]
fn continuous_chunks_never_stop_without_a_human() {
    use pacs_shield::ChunkMotion;
    let robot = fr3::fr3();
    let human = default_human().with_uncertainty(0.01, 0.1, 0.02).unwrap();
    let spec = ConstraintSpec::builtin("sorting").unwrap();
    let far = pacs_testkit::human_reaching(3.0, 0.0, [2.8, -0.2, 1.0]);
    let run = |motion: ChunkMotion| {
        let mut cfg = ShieldConfig::default();
        motion.apply(&mut cfg);
        let dt = cfg.safety_step;
        let mut sh = Shield::new(robot.clone(), Some((human.clone(), &spec)), vec![], cfg).unwrap();
        sh.start(0.0, &Q0).unwrap();
        let (mut since, mut verified, mut handovers) = (usize::MAX, 0usize, 0usize);
        let mut qs = Vec::new();
        let mut speeds = Vec::new();
        for k in 0..1500 {
            let t = k as f64 * dt;
            let due = match motion {
                ChunkMotion::Stop => since >= 264,
                ChunkMotion::Continuous => {
                    since >= 264 || (since >= 33 && sh.remaining().unwrap() < 1.5 * dt)
                }
            };
            if due {
                sh.set_chunk(&chunk(DELTA, 8)).unwrap();
                since = 0;
                handovers += 1;
            }
            since += 1;
            let m = HumanMeasurement::new(&human, t, &far, None).unwrap();
            let cmd = sh.step(t, Some(&m)).unwrap();
            verified += cmd.diag.verified as usize;
            qs.push(cmd.state.q[0]);
            speeds.push(cmd.state.dq[0]);
        }
        (qs, speeds, verified, handovers)
    };
    let (qs, speeds, verified, handovers) = run(ChunkMotion::Continuous);
    assert!(verified * 100 >= 97 * 1500, "verified {verified} of 1500");
    assert!(
        handovers > 1500 / 264 + 1,
        "{handovers} hand-overs: no faster than the clock"
    );
    let slowest = speeds[300..].iter().fold(f64::INFINITY, |m, v| m.min(*v));
    assert!(
        slowest > 0.05,
        "joint 1 slowed to {slowest} rad/s between chunks"
    );
    for w in qs.windows(2) {
        assert!(
            w[1] >= w[0] - 1e-12,
            "moved backwards: {} -> {}",
            w[0],
            w[1]
        );
    }
    let (qs_stop, speeds_stop, _, _) = run(ChunkMotion::Stop);
    let slowest_stop = speeds_stop[300..]
        .iter()
        .fold(f64::INFINITY, |m, v| m.min(*v));
    eprintln!("slowest: continuous {slowest} rad/s, stopping {slowest_stop} rad/s");
    assert!(
        slowest_stop < 0.5 * slowest,
        "the stop mode slows down between chunks (else this comparison proves nothing)"
    );
    let (moved, moved_stop) = (qs[1499] - Q0[0], qs_stop[1499] - Q0[0]);
    assert!(
        moved > 1.2 * moved_stop,
        "continuous {moved} rad vs stopping {moved_stop} rad"
    );
}

/// A refused start names the joint, the value and the limits, not only `start: configuration
/// outside the joint position limits`.
#[test]
fn a_refused_start_names_the_joint_the_value_and_the_limit() {
    let spec = ConstraintSpec::builtin("sorting").unwrap();
    let mut sh = Shield::new(
        fr3::fr3(),
        Some((default_human(), &spec)),
        vec![],
        ShieldConfig::default(),
    )
    .unwrap();
    let msg = |q: &[f64], t: f64| {
        let mut sh2 = sh.clone();
        sh2.start(t, q).unwrap_err().to_string()
    };
    let mut q = Q0;
    q[3] = 0.5;
    assert_eq!(
        msg(&q, 0.0),
        "start[3] (joint `fr3_joint4`): 0.5 rad is outside the joint position limits [-3.0421, -0.1518] rad"
    );
    q[3] = f64::NAN;
    assert_eq!(
        msg(&q, 0.0),
        "start[3] (joint `fr3_joint4`): NaN is not a finite angle (rad)"
    );
    assert_eq!(
        msg(&Q0[..6], 0.0),
        "start: 6 joint values given, the robot has 7 joints"
    );
    assert_eq!(
        msg(&Q0, f64::INFINITY),
        "start: the time inf s is not finite"
    );
    sh.start(0.0, &Q0).unwrap();
}

/// A person "measured" beyond any robot's reach (a tracker's lost-track value, 10⁷ m or
/// FLT_MAX) is no measurement of anyone in the cell: the shield verifies nothing against it and
/// the robot stays on its failsafe (at rest), as with no measurement at all. The audit's rule
/// for the same record is `human_reach_error` (one rule, `HumanReach::occupancy_into`).
#[test]
fn a_person_measured_beyond_any_reach_is_not_verified_against() {
    for far in [1e7, f32::MAX as f64] {
        let lost = move |_t: f64| vec![[far, 0.0, 1.0]; 9];
        let r = run(FilterMode::Pacs, "sorting", 300, 100, DELTA, &lost);
        assert_eq!(r.verified, 0, "at {far} m");
        assert!(r.qs.iter().all(|q| *q == Q0), "at {far} m the robot moved");
    }
}

/// A measurement that contradicts the one the shield trusts (a keypoint moved farther than
/// `v_max·Δt + 2·e_pos` since it) verifies nothing: one of the two is wrong (a tracker glitch
/// putting the person metres away for a few frames must not let the arm move). Here the person stands 2.5 m from the base,
/// measured every step; from 0.3 s to 0.33 s the tracker reports them 3.5 m farther: those steps
/// are not verified (binding `contradicted-measurement`), and verification resumes with the next
/// measurement that agrees with the trusted one. A person who truly moved 2 m is accepted once
/// the model allows that move since the trusted measurement (v_max 2 m/s: after about 1 s).
#[test]
fn a_measurement_that_contradicts_the_trusted_one_verifies_nothing() {
    use pacs_shield::shield::Binding;
    let robot = fr3::fr3();
    let human = default_human().with_uncertainty(0.01, 0.1, 0.02).unwrap();
    let spec = ConstraintSpec::builtin("sorting").unwrap();
    let cfg = ShieldConfig::default();
    let run = |at: &dyn Fn(f64) -> f64| {
        let mut sh = Shield::new(robot.clone(), Some((human.clone(), &spec)), vec![], cfg).unwrap();
        sh.start(0.0, &Q0).unwrap();
        let mut out = Vec::new();
        for k in 0..2000 {
            let t = k as f64 * cfg.safety_step;
            if k % 100 == 0 {
                let _ = sh.set_chunk(&chunk(DELTA, 8));
            }
            let kp = pacs_testkit::standing_arms_forward(at(t));
            let m = HumanMeasurement::new(&human, t, &kp, None).unwrap();
            let cmd = sh.step(t, Some(&m)).expect("started");
            out.push((t, cmd.diag.verified, cmd.diag.binding));
        }
        out
    };
    let glitch = run(&|t| if (0.3..0.33).contains(&t) { 6.0 } else { 2.5 });
    for &(t, verified, binding) in &glitch {
        if (0.3..0.33).contains(&t) {
            assert!(!verified, "t = {t}");
            assert_eq!(
                binding,
                Binding::ContradictedMeasurement { human: 0 },
                "t = {t}"
            );
        }
    }
    let verified_in = |r: &[(f64, bool, Binding)], a: f64, b: f64| {
        r.iter()
            .filter(|(t, v, _)| *v && (a..b).contains(t))
            .count()
    };
    assert!(verified_in(&glitch, 0.0, 0.3) > 200);
    assert!(verified_in(&glitch, 0.34, 0.5) > 100);
    // A drift: from 0.3 s each measurement 15 mm farther than the one before (each within the
    // model's allowance of it, 2·e_pos = 20 mm plus v_max·1 ms, but 15 m/s in all): held
    // against the recent trusted ones, it is contradicted within a few frames of the first
    // one 20 ms back, and nothing verifies while it goes on (until 0.45 s).
    let drift = run(&|t| {
        if (0.3..0.45).contains(&t) {
            2.5 + 15.0 * (t - 0.3)
        } else {
            2.5
        }
    });
    assert_eq!(verified_in(&drift, 0.33, 0.45), 0);
    assert!(verified_in(&drift, 0.47, 0.7) > 100);
    // A true move of 2 m at 0.5 s: contradicted until the model allows it (2 m at 2 m/s within
    // 2·e_pos: ≈ 0.99 s after the last trusted measurement), then trusted again.
    let moved = run(&|t| if t < 0.5 { 2.5 } else { 4.5 });
    assert_eq!(verified_in(&moved, 0.5, 1.45), 0);
    assert!(verified_in(&moved, 1.55, 2.0) > 300);
}

/// Through a session, every measurement of person 0 is held against the trusted ones, not only
/// the newest of a step: a newer agreeing one and an older contradicting one (4 m away)
/// delivered at the same step leave the person contradicted, as for people 1 and up and
/// objects.
#[test]
fn every_measurement_of_the_first_person_is_checked_in_a_session() {
    use pacs_shield::session::Session;
    use pacs_shield::shield::Binding;
    let human = default_human().with_uncertainty(0.01, 0.1, 0.02).unwrap();
    let cs = ConstraintSpec::builtin("sorting").unwrap();
    let sh = Shield::builder(fr3::fr3())
        .person(human.clone(), &cs)
        .build()
        .unwrap();
    let mut s: Session<std::io::Sink> = Session::new(sh, vec![]);
    s.start(0.0, &Q0).unwrap();
    let at = |t: f64, x: f64| {
        HumanMeasurement::new(&human, t, &pacs_testkit::standing_arms_forward(x), None).unwrap()
    };
    for k in 0..10 {
        let t = k as f64 * 0.001;
        s.measure_person(0, at(t, 2.5)).unwrap();
        s.step(t).unwrap();
    }
    // At 0.010 s: the newer (0.010) agrees, the older (0.0095) puts the person 4 m farther.
    s.measure_person_at(0.01, 0, at(0.01, 2.5)).unwrap();
    s.measure_person_at(0.01, 0, at(0.0095, 6.5)).unwrap();
    let cmd = s.step(0.01).unwrap();
    assert!(!cmd.diag.verified);
    assert_eq!(
        cmd.diag.binding,
        Binding::ContradictedMeasurement { human: 0 }
    );
}
