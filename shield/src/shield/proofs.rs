//! Kani harnesses of the shield's induction step on the real [`Shield::step`] (claim C8,
//! proofs/README.md § C8), and the proofs of the contract of [`choose`] it uses.
//!
//! `f3_shield_step_induction` runs the real `Shield::step` of a real shield (one joint, one
//! link; a person of two keypoints; SSM) from *any* state of the induction invariant — any stored failsafe (any finite
//! profile, either slot, started up to 1 s before the step), any path state, a fresh chunk or
//! none in the other slot, any chunk serials — with any measurement of the person (older, newer,
//! from the future, or none) and any step time in [0, 100] s. What it replaces:
//! - [`choose`] by its verified contract [`chosen_by_rule`] (`stub_verified`);
//! - `Shield::verify` by a spy that returns *any* verdict and records what it was asked and the
//!   measurement in use (the soundness of a `true` verdict is claim C7's, not this step's: the
//!   step must hold whatever the verification answers);
//! - `Shield::candidate` by *any* pair of finite go and brake profiles, or none (the planner);
//! - `SpeedProfile::plan` by any finite profile (the start's standstill);
//! - the formatting machinery (`core::fmt::write`) by writing nothing (the error paths of the
//!   scene's construction format; the claims read no text).
//!
//! It proves the induction step: after the step the command follows the new stored failsafe's
//! slot, the failsafe changes only to the brake of a candidate whose last verification returned
//! `true` (no unverified intended step is executed), that verification saw the newest
//! measurement delivered at or before `t`, and otherwise the stored failsafe, its slot and the
//! trajectory it lives on are kept. Mutants `x67_step_adopts_before_verify` and
//! `x68_step_verifies_stale_measurement` make it fail.

#![allow(dead_code)] // The harnesses are entry points of `cargo kani` only.

use super::decision::Choice;
use super::*;
use pacs_models::human::BodyPartSpec;
use pacs_models::robot::{InertialSpec, JointLimitSpec, JointSpec, LinkSpec, PoseSpec};
use pacs_models::shape::CapsuleSpec;
use pacs_models::{HumanSpec, RobotSpec};

/// What the stand-in of `Shield::verify` saw in one step (its last two calls).
#[derive(Clone, Copy)]
struct Spy {
    calls: usize,
    last: Option<Seen>,
}

/// One verification: what it was asked, its verdict and the person's measurement in use.
#[derive(Clone, Copy)]
struct Seen {
    slot: usize,
    brake: SpeedProfile,
    t: f64,
    ok: bool,
    has_meas: bool,
    meas_time: f64,
}

static mut SPY: Spy = Spy {
    calls: 0,
    last: None,
};

fn any_finite() -> f64 {
    let x: f64 = kani::any();
    kani::assume(x.is_finite());
    x
}

fn any_in(lo: f64, hi: f64) -> f64 {
    let x: f64 = kani::any();
    kani::assume(x >= lo && x <= hi);
    x
}

/// Any finite profile of 1 to 4 phases (over-approximates the planner, as in `f1`).
fn any_profile() -> SpeedProfile {
    let n: usize = kani::any();
    kani::assume((1..=4).contains(&n));
    let phase = || (any_finite(), any_finite(), any_finite(), any_finite(), any_finite());
    SpeedProfile::from_parts(
        [phase(), phase(), phase(), phase()],
        n,
        any_finite(),
        any_finite(),
        any_finite(),
        any_finite(),
    )
}

fn any_plan(_start: PathState, _target: f64, _acc: f64, _jerk: f64) -> SpeedProfile {
    any_profile()
}

/// Stand-in of `Shield::verify`: any verdict, recorded with the measurement in use.
fn verify_spy(
    sh: &mut Shield,
    slot: usize,
    _go: &SpeedProfile,
    brake: &SpeedProfile,
    t: f64,
    _diag: &mut Diagnostics,
) -> bool {
    let ok: bool = kani::any();
    let h = &sh.humans[0];
    // Copied in and out: no reference to the static.
    let mut spy = unsafe { SPY };
    spy.calls += 1;
    spy.last = Some(Seen {
        slot,
        brake: *brake,
        t,
        ok,
        has_meas: h.has_meas,
        meas_time: h.meas.time(),
    });
    unsafe { SPY = spy };
    ok
}

/// Stand-in of `Shield::candidate`: any finite go and brake profiles, or none.
fn candidate_any(_sh: &Shield, _slot: usize, _start: PathState) -> Option<(SpeedProfile, SpeedProfile)> {
    if kani::any() {
        Some((any_profile(), any_profile()))
    } else {
        None
    }
}

/// One revolute joint and one link (a capsule with a mass): the smallest robot the shield takes.
/// The step's decision does not depend on the robot beyond its trajectories (stubbed profiles
/// over a standstill), so the smallest keeps the model checker's formula small.
fn one_joint_robot() -> RobotModel {
    let spec = RobotSpec {
        name: "one".into(),
        base: PoseSpec::default(),
        joints: vec![JointSpec {
            name: "j1".into(),
            origin: PoseSpec::default(),
            axis: [0.0, 0.0, 1.0],
            limits: JointLimitSpec {
                q_min: -1.0,
                q_max: 1.0,
                v_max: 1.0,
                a_max: 10.0,
                j_max: 1000.0,
            },
        }],
        links: vec![LinkSpec {
            name: "l1".into(),
            parent: "j1".into(),
            origin: PoseSpec::default(),
            capsules: vec![CapsuleSpec {
                p1: [0.0, 0.0, 0.0],
                p2: [0.5, 0.0, 0.0],
                radius: 0.05,
            }],
            inertial: Some(InertialSpec {
                mass: 1.0,
                com: [0.25, 0.0, 0.0],
                inertia: [0.01, 0.0, 0.0, 0.01, 0.0, 0.01],
            }),
            frame: false,
        }],
        user_values: vec![],
    };
    RobotModel::new(spec).expect("a valid robot")
}

/// Two keypoints and one body part between them: the smallest person.
fn two_point_human() -> HumanModel {
    HumanModel::new(HumanSpec {
        name: "two".into(),
        keypoints: vec!["a".into(), "b".into()],
        v_max: vec![2.0, 2.0],
        a_max: vec![20.0, 20.0],
        body_parts: vec![BodyPartSpec {
            name: "arm".into(),
            from: "a".into(),
            to: "b".into(),
            thickness: 0.1,
        }],
        measurement_error_pos: 0.0,
        measurement_error_vel: 0.1,
        delay: 0.0,
        extremities: vec![],
        clamping_pairs: vec![],
    })
    .expect("a valid human")
}

/// A measurement of `h` at `time` (keypoints at the origin: the step only
/// compares stamps).
fn measurement(h: &HumanModel, time: f64) -> HumanMeasurement {
    let zeros = vec![[0.0; 3]; h.keypoint_count()];
    HumanMeasurement::new(h, time, &zeros, None).expect("a valid measurement")
}

/// Stand-in of the formatting machinery (`format!`, `write!`): writes nothing (field paths and messages built while the scene is
/// constructed; the step's claims do not read them, and the formatting machinery is far beyond
/// the model checker).
fn no_format(_out: &mut dyn std::fmt::Write, _args: std::fmt::Arguments<'_>) -> std::fmt::Result {
    Ok(())
}

#[kani::proof]
#[kani::stub(core::fmt::write, no_format)]
#[kani::stub(SpeedProfile::plan, any_plan)]
#[kani::stub(Shield::verify, verify_spy)]
#[kani::stub(Shield::candidate, candidate_any)]
#[kani::stub_verified(choose)]
fn f3_shield_step_induction() {
    let robot = one_joint_robot();
    let human = two_point_human();
    let spec = ConstraintSpec::builtin("ssm").expect("built-in preset");
    let mut sh = Shield::new(robot, Some((human.clone(), &spec)), vec![], ShieldConfig::default())
        .expect("a valid shield");
    let l = sh.robot.limits();
    let q0: Vec<f64> = (0..sh.dof).map(|j| 0.5 * (l.q_min()[j] + l.q_max()[j])).collect();
    sh.start(0.0, &q0).expect("starts at rest");
    let alpha = sh.config.safety_step;

    // Any state of the invariant: a failsafe on either slot, the command on its slot, the other
    // slot holding a trajectory (a fresh chunk, or an older one), any path state.
    let t = any_in(0.0, 100.0);
    let f_slot = usize::from(kani::any::<bool>());
    let f = VerifiedFailsafe {
        slot: f_slot,
        profile: any_profile(),
        t0: t - any_in(0.0, 1.0),
    };
    sh.trajs = [Some(Trajectory::standstill(&q0)), Some(Trajectory::standstill(&q0))];
    sh.failsafe = Some(f);
    sh.slot = f_slot;
    sh.path = PathState {
        s: any_finite(),
        sd: any_finite(),
        sdd: any_finite(),
    };
    sh.time = t;
    sh.fresh = if kani::any() { Some(1 - f_slot) } else { None };
    sh.chunk_serial = [kani::any(), kani::any()];
    let serial_kept = sh.chunk_serial[f_slot];
    // The person: measured before (at any time up to t) or not yet.
    if kani::any() {
        let before = measurement(&human, any_in(-10.0, 100.0));
        sh.measure_human(0, &before).expect("the model's keypoints");
    }
    let (had_meas, old_time) = (sh.humans[0].has_meas, sh.humans[0].meas.time());
    // This step's measurement: none, or one at any time (older, newer, from the future).
    let new_meas = measurement(&human, any_in(-10.0, 110.0));
    let given = kani::any::<bool>().then_some(&new_meas);

    let cmd = sh.step(t, given).expect("started");

    let spy = unsafe { SPY };
    let nf = sh.failsafe.expect("a failsafe after every step");
    let adopted = !cmd.diag.on_failsafe;
    // The command follows the stored failsafe's slot; a fresh chunk never sits on it.
    assert!(sh.slot == nf.slot, "the command left the failsafe's slot");
    assert!(sh.fresh.is_none(), "a fresh chunk survived its one try");
    assert!(sh.trajs[nf.slot].is_some(), "the failsafe's trajectory is gone");
    // The measurement every verification saw: the newest delivered at or before t.
    if let Some(seen) = spy.last {
        let newer = new_meas.time() <= t && (!had_meas || new_meas.time() > old_time);
        if given.is_some() && newer {
            assert!(
                seen.has_meas && seen.meas_time.to_bits() == new_meas.time().to_bits(),
                "verified against a stale measurement"
            );
        }
        assert!(seen.t.to_bits() == t.to_bits(), "verified for another time");
    }
    if adopted {
        // No unverified intended step is executed: the last verification of this step returned
        // true, on the candidate whose brake is the new failsafe from t + α.
        let seen = spy.last.expect("adopted without a verification");
        assert!(seen.ok, "adopted an unverified candidate");
        assert!(
            nf.slot == seen.slot
                && nf.profile.same_bits(&seen.brake)
                && nf.t0.to_bits() == (t + alpha).to_bits(),
            "the new failsafe is not the verified brake"
        );
        assert!(cmd.diag.verified, "an adopted PACS step not reported verified");
    } else {
        // Kept: the stored failsafe, its slot and the trajectory it lives on.
        assert!(
            nf.slot == f.slot && nf.profile.same_bits(&f.profile) && nf.t0.to_bits() == f.t0.to_bits(),
            "the stored failsafe changed without a verified candidate"
        );
        assert!(sh.chunk_serial[f.slot] == serial_kept, "the failsafe's trajectory was replaced");
    }
    assert!(spy.calls <= 2, "more than two verifications in one step");
}

/// Inputs of `choose` in `f1`'s ranges: any stored failsafe started up to 1 s before `t`, any
/// candidate (finite profiles), any mode.
fn choose_inputs() -> (VerifiedFailsafe, Option<Candidate>, FilterMode, f64, f64) {
    let t = any_in(0.0, 100.0);
    let alpha = any_in(1e-4, 0.01);
    let stored = VerifiedFailsafe {
        slot: usize::from(kani::any::<bool>()),
        profile: any_profile(),
        t0: t - any_in(0.0, 1.0),
    };
    let candidate = kani::any::<bool>().then(|| Candidate {
        slot: usize::from(kani::any::<bool>()),
        go: any_profile(),
        brake: any_profile(),
        verified: kani::any(),
    });
    let mode = match kani::any::<u8>() % 3 {
        0 => FilterMode::Pacs,
        1 => FilterMode::Off,
        _ => FilterMode::SingleAction,
    };
    (stored, candidate, mode, t, alpha)
}

/// `choose`'s contract where the candidate is adopted.
#[kani::proof_for_contract(choose)]
fn f3_choose_contract_adopted() {
    let (stored, candidate, mode, t, alpha) = choose_inputs();
    kani::assume(candidate.is_some_and(|c| c.verified || mode == FilterMode::Off));
    let _: Choice = choose(stored, candidate, mode, t, alpha);
}

/// `choose`'s contract where the stored failsafe is kept.
#[kani::proof_for_contract(choose)]
fn f3_choose_contract_kept() {
    let (stored, candidate, mode, t, alpha) = choose_inputs();
    kani::assume(!candidate.is_some_and(|c| c.verified || mode == FilterMode::Off));
    let _: Choice = choose(stored, candidate, mode, t, alpha);
}

/// Any choice (every field any value): `stub_verified(choose)` draws the result from here and
/// keeps those its contract allows.
impl kani::Arbitrary for Choice {
    fn any() -> Self {
        Choice {
            slot: kani::any(),
            profile: any_profile(),
            tau: kani::any(),
            failsafe: VerifiedFailsafe {
                slot: kani::any(),
                profile: any_profile(),
                t0: kani::any(),
            },
            adopted: kani::any(),
        }
    }
}
