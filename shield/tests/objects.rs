//! The shield with dynamic objects: a ball resting where the arm is going is never
//! touched (`no_contact`) and never touched while moving (`ssm`); a far ball does not slow the
//! robot; an object without a measurement keeps the robot at rest; bad measurements are errors.

use nalgebra::Point3;
use pacs_models::fr3;
use pacs_models::object::{ObjectContact, ObjectModel, ObjectSpec, ShapeSpec};
use pacs_motion::chunk::{ActionKind, Chunk};
use pacs_reach::geometry::segment_distance_lower_bound;
use pacs_reach::object::ObjectMeasurement;
use pacs_shield::shield::{Binding, Shield, ShieldConfig};

const Q0: [f64; 7] = fr3::Q_READY;
const DELTA: [f64; 7] = [0.04, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
const RADIUS: f64 = 0.05;

fn chunk() -> Chunk {
    Chunk {
        kind: ActionKind::Delta,
        actions: vec![DELTA.to_vec(); 16],
        execute: 8,
        gripper: None,
    }
}

fn ball() -> ObjectModel {
    ObjectModel::new(&ObjectSpec {
        name: "ball".into(),
        shape: ShapeSpec::Sphere { radius: RADIUS },
        max_acc: 2.0,
        acc_bias: [0.0; 3],
        acc_generators: vec![],
        max_speed: Some(1.0),
        measurement_error_pos: 0.005,
        measurement_error_vel: 0.02,
        delay: 0.02,
    })
    .unwrap()
}

/// Where the flange is after joint 1 turned by `dq1` from the ready pose (m).
fn flange_after(dq1: f64) -> [f64; 3] {
    let robot = fr3::fr3();
    let mut q = Q0;
    q[0] += dq1;
    let caps = robot.capsules_world(&q);
    let (_, last) = caps.last().unwrap();
    let p = last.p2();
    [p.x, p.y, p.z]
}

/// Exact distance between the robot's moving capsules at `q` and a ball at `c` (m).
fn separation(q: &[f64], c: [f64; 3]) -> f64 {
    let robot = fr3::fr3();
    let p = Point3::from(c);
    robot
        .capsules_world(q)
        .iter()
        .filter(|(li, _)| robot.links()[*li].frame != 0)
        .map(|(_, cap)| {
            segment_distance_lower_bound(&p, &p, &cap.p1(), &cap.p2()) - cap.radius() - RADIUS
        })
        .fold(f64::INFINITY, f64::min)
}

struct Outcome {
    min_separation: f64,
    moving_contact: usize,
    moved: f64,
    object_bindings: usize,
    verified: usize,
}

/// 1.5 s of a new chunk (joint 1 turning) every 0.4 s, the ball resting at `c`, measured every
/// step (true state at t − delay, stamped t).
fn run(c: [f64; 3], contact: ObjectContact, measure: bool) -> Outcome {
    run_rolling(c, [0.0; 3], contact, measure)
}

/// As [`run`], with the ball starting at `c` and rolling at constant velocity `v` (m/s),
/// measured with its velocity; separations are taken from the true ball at each command's time.
fn run_rolling(c: [f64; 3], v: [f64; 3], contact: ObjectContact, measure: bool) -> Outcome {
    let at = |t: f64| [0, 1, 2].map(|i| c[i] + v[i] * t);
    let cfg = ShieldConfig::default();
    let mut sh = Shield::new(fr3::fr3(), None, vec![], cfg).unwrap();
    let id = sh.add_object(ball(), contact).unwrap();
    sh.start(0.0, &Q0).unwrap();
    let mut out = Outcome {
        min_separation: f64::INFINITY,
        moving_contact: 0,
        moved: 0.0,
        object_bindings: 0,
        verified: 0,
    };
    for k in 0..1500 {
        let t = k as f64 * cfg.safety_step;
        if k % 400 == 0 {
            let _ = sh.set_chunk(&chunk());
        }
        if measure {
            // The true ball at t − delay (the measurement's age), stamped t.
            let m = ObjectMeasurement {
                time: t,
                position: at((t - ball().delay()).max(0.0)),
                velocity: Some(v),
            };
            sh.measure_object(id, &m).unwrap();
        }
        let cmd = sh.step(t, None).unwrap();
        let q = cmd.q();
        let sep = separation(q, at(cmd.t));
        out.min_separation = out.min_separation.min(sep);
        let moving = cmd.dq().iter().any(|v| v.abs() > 1e-12);
        if moving && sep <= 0.0 {
            out.moving_contact += 1;
        }
        if matches!(cmd.diag.binding, Binding::Object { object: 0, .. }) {
            out.object_bindings += 1;
        }
        out.verified += cmd.diag.verified as usize;
        out.moved = q[0] - Q0[0];
    }
    out
}

#[test]
fn a_ball_in_the_path_is_never_touched() {
    // Without the ball the arm turns joint 1 by ≈ 0.75 rad in 1.5 s (a_far_ball_…); the ball
    // sits where the flange would be after 0.9 rad, 7 cm from the folded arm at the start.
    let c = flange_after(0.9);
    assert!(
        separation(&Q0, c) > 0.05,
        "the ball starts clear of the arm"
    );
    let r = run(c, ObjectContact::NoContact, true);
    assert!(
        r.min_separation > 0.0,
        "touched: separation {}",
        r.min_separation
    );
    assert!(r.object_bindings > 0, "the object never bound a step");
    assert!(
        r.moved > 0.1,
        "the arm should approach the ball first (moved {} rad)",
        r.moved
    );
    assert!(
        r.moved < 0.6,
        "the ball did not stop the arm (moved {} rad)",
        r.moved
    );
    let r = run(c, ObjectContact::Ssm, true);
    assert_eq!(r.moving_contact, 0, "SSM: contact while moving");
}

#[test]
fn a_far_ball_does_not_slow_the_robot() {
    let free = run([3.0, 3.0, 0.5], ObjectContact::NoContact, true);
    assert!(free.moved > 0.7, "moved {} rad", free.moved);
    assert!(free.verified > 1400, "verified {} of 1500", free.verified);
    assert_eq!(free.object_bindings, 0);
}

#[test]
fn an_unmeasured_object_keeps_the_robot_at_rest() {
    let r = run([3.0, 3.0, 0.5], ObjectContact::NoContact, false);
    assert_eq!(r.verified, 0);
    assert_eq!(r.moved, 0.0);
}

#[test]
fn bad_object_input_is_an_error() {
    let mut sh = Shield::new(fr3::fr3(), None, vec![], ShieldConfig::default()).unwrap();
    let id = sh.add_object(ball(), ObjectContact::Ssm).unwrap();
    let m = ObjectMeasurement {
        time: 0.0,
        position: [f64::NAN, 0.0, 0.0],
        velocity: None,
    };
    assert!(sh.measure_object(id, &m).is_err());
    let ok = ObjectMeasurement {
        position: [0.0; 3],
        ..m
    };
    assert!(
        sh.measure_object(id + 1, &ok)
            .unwrap_err()
            .to_string()
            .contains("no such object")
    );
    let e = sh
        .add_object(ball(), ObjectContact::Pfl { threshold: -1.0 })
        .unwrap_err();
    assert!(e.to_string().contains("contact.pfl.threshold"), "{e}");
}

/// Two people: the first far away and measured through `step`, the second reaching
/// for the tool and measured through `measure_human(1, …)`. SSM: the arm never moves while the
/// second person's hand may touch it, the binding names human 1; with the second person far as
/// well, the arm moves freely.
#[test]
fn a_second_person_at_the_tool_stops_the_arm() {
    use pacs_models::{ConstraintSpec, default_human};
    use pacs_reach::human::HumanMeasurement;
    let human = default_human().with_uncertainty(0.01, 0.1, 0.02).unwrap();
    let spec = ConstraintSpec::builtin("sorting").unwrap();
    let far = pacs_testkit::human_reaching(3.0, 0.0, [2.8, -0.2, 1.0]);
    let run = |second: &[[f64; 3]]| {
        let cfg = ShieldConfig::default();
        let mut sh = Shield::new(fr3::fr3(), Some((human.clone(), &spec)), vec![], cfg).unwrap();
        assert_eq!(sh.add_human(human.clone(), &spec).unwrap(), 1);
        sh.start(0.0, &Q0).unwrap();
        let (mut moved, mut bound_by_second, mut verified) = (0.0, 0, 0);
        for k in 0..1000 {
            let t = k as f64 * cfg.safety_step;
            if k % 400 == 0 {
                let _ = sh.set_chunk(&chunk());
            }
            let m0 = HumanMeasurement::new(&human, t, &far, None).unwrap();
            let m1 = HumanMeasurement::new(&human, t, second, None).unwrap();
            sh.measure_human(1, &m1).unwrap();
            let cmd = sh.step(t, Some(&m0)).unwrap();
            if matches!(cmd.diag.binding, Binding::Ssm { human: 1, .. }) {
                bound_by_second += 1;
            }
            verified += cmd.diag.verified as usize;
            moved = cmd.state.q[0] - Q0[0];
        }
        (moved, bound_by_second, verified)
    };
    let (moved, bound, _) = run(&pacs_testkit::human_reaching(0.9, 0.3, [0.32, 0.12, 0.45]));
    assert!(bound > 0, "the second person never bound a step");
    assert!(
        moved.abs() < 1e-9,
        "the arm moved {moved} rad with a hand at the tool"
    );
    let (moved, bound, verified) = run(&far);
    assert_eq!(bound, 0);
    assert!(
        moved > 0.3 && verified > 900,
        "moved {moved}, verified {verified}"
    );
    // Errors: unknown index, a measurement of another keypoint count.
    let mut sh = Shield::new(
        fr3::fr3(),
        Some((human.clone(), &spec)),
        vec![],
        ShieldConfig::default(),
    )
    .unwrap();
    let m = HumanMeasurement::new(&human, 0.0, &far, None).unwrap();
    assert!(
        sh.measure_human(1, &m)
            .unwrap_err()
            .to_string()
            .contains("no such human")
    );
    sh.measure_human(0, &m).unwrap();
    assert_eq!(sh.human_count(), 1);
}

#[test]
fn the_arm_follows_a_ball_rolling_away_along_its_path() {
    // The ball starts 0.5 rad ahead along the flange's path (touching the resting arm) and rolls
    // away along the path's tangent at 0.25 m/s. The arm follows it, never touching it while
    // moving. Each step checks the ball's occupancy over the whole monitored trajectory first;
    // where that touches the robot the interval's own (later, farther) occupancy decides. If
    // the whole one decided (the recompute left out), the arm lags: 910 verified steps and
    // 0.45 rad instead of 1169 and 0.53 rad.
    let c = flange_after(0.5);
    let n = (c[0] * c[0] + c[1] * c[1]).sqrt();
    let v = [-c[1] / n * 0.25, c[0] / n * 0.25, 0.0];
    let r = run_rolling(c, v, ObjectContact::NoContact, true);
    assert_eq!(r.moving_contact, 0, "touched the ball while moving");
    assert!(r.verified >= 1050, "verified {} of 1500 steps", r.verified);
    assert!(r.moved > 0.49, "moved {} rad", r.moved);
}

/// A measurement of an object that contradicts the ones the shield trusts (positions farther
/// apart than the model allows, or a velocity the positions refute) verifies nothing until a
/// newer one agrees with them: a tracker glitch reporting a resting ball 2 m higher, or a
/// frozen tracker reporting it with a velocity of 0.99 m/s (under the 1 m/s bound) pointing
/// away, is not taken. Here the ball rests 2 m away, measured every step; from 0.3 s to 0.35 s the measurement is
/// (a) 2 m higher or (b) the true position with 0.99 m/s along x: those steps verify nothing
/// (binding `contradicted-object`), and verification resumes after.
#[test]
fn an_object_measurement_that_contradicts_the_trusted_ones_verifies_nothing() {
    let cfg = ShieldConfig::default();
    let c = [2.0, 0.0, 0.5];
    let glitches = [
        ("position", [2.0, 0.0, 2.5], Some([0.0; 3])),
        ("velocity", c, Some([0.99, 0.0, 0.0])),
    ];
    for (what, pos, vel) in glitches {
        let mut sh = Shield::new(fr3::fr3(), None, vec![], cfg).unwrap();
        let id = sh.add_object(ball(), ObjectContact::NoContact).unwrap();
        sh.start(0.0, &Q0).unwrap();
        let (mut during, mut after) = (0, 0);
        for k in 0..700 {
            let t = k as f64 * cfg.safety_step;
            if k % 200 == 0 {
                let _ = sh.set_chunk(&chunk());
            }
            let glitch = (0.3..0.35).contains(&t);
            let m = ObjectMeasurement {
                time: t,
                position: if glitch { pos } else { c },
                velocity: if glitch { vel } else { Some([0.0; 3]) },
            };
            sh.measure_object(id, &m).unwrap();
            let cmd = sh.step(t, None).unwrap();
            // (A velocity's direction shows after a few frames: from 0.31 s on.)
            if (0.31..0.35).contains(&t) {
                assert!(!cmd.diag.verified, "{what}: t = {t}");
                assert_eq!(
                    cmd.diag.binding,
                    Binding::ContradictedObject { object: 0 },
                    "{what}: t = {t}"
                );
                during += 1;
            }
            after += usize::from(t >= 0.4 && cmd.diag.verified);
        }
        assert!(during > 30, "{what}");
        assert!(after > 200, "{what}: {after}");
    }
}

/// A contradiction is cleared only by a measurement newer than the one that caused it: a ball
/// resting 2 m away, measured every 10 ms up to 0.3 s, then a glitch stamped 0.35 s (2 m
/// higher), then a measurement stamped 0.33 s at the true place (older than the glitch): the
/// shield keeps verifying nothing until one stamped after 0.35 s agrees (the older one never
/// clears it: a step verified against it would ignore the newest measurement).
#[test]
fn only_a_measurement_newer_than_the_contradicting_one_clears_it() {
    let cfg = ShieldConfig::default();
    let c = [2.0, 0.0, 0.5];
    let mut sh = Shield::new(fr3::fr3(), None, vec![], cfg).unwrap();
    let id = sh.add_object(ball(), ObjectContact::NoContact).unwrap();
    // (Every measurement below is stamped before the steps: none is from the future.)
    sh.start(0.4, &Q0).unwrap();
    let at = |time, position| ObjectMeasurement {
        time,
        position,
        velocity: Some([0.0; 3]),
    };
    let mut t = 0.4;
    for k in 0..=30 {
        sh.measure_object(id, &at(k as f64 * 0.01, c)).unwrap();
    }
    let _ = sh.set_chunk(&chunk());
    let mut step = |sh: &mut Shield| {
        let cmd = sh.step(t, None).unwrap();
        t += cfg.safety_step;
        cmd.diag
    };
    assert!(step(&mut sh).verified);
    sh.measure_object(id, &at(0.35, [2.0, 0.0, 2.5])).unwrap();
    assert_eq!(
        step(&mut sh).binding,
        Binding::ContradictedObject { object: 0 }
    );
    sh.measure_object(id, &at(0.33, c)).unwrap();
    let d = step(&mut sh);
    assert!(!d.verified);
    assert_eq!(d.binding, Binding::ContradictedObject { object: 0 });
    sh.measure_object(id, &at(0.36, c)).unwrap();
    assert!(step(&mut sh).verified);
}
