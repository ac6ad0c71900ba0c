//! (f) The shield state machine.
//!
//! - `f1` (pure, model-checkable: Kani checks [`choose`], the selection `decide` evaluates, for
//!   any profiles; the twin [`decide`] itself): the decision `Shield::step` applies, over any
//!   sequence of candidates (fresh chunk or current path, any profile limits) and verification
//!   outcomes: every executed state lies on the last verified monitored trajectory, the stored
//!   failsafe changes only when a new candidate is verified, and if verification then fails
//!   forever the executed state is at rest (ṡ = s̈ = 0, fixed s) from the failsafe's settle time on.
//! - `f2` (pure): the occupancy intervals the verification checks are contiguous and cover the
//!   whole monitored trajectory `[0, stop]` (the last one ends at standstill).
//! - `f2_fine_pieces_cover` (pure): the fine verification's order ([`verify_fine`]: the last
//!   interval, the rest merged, the rest one by one only if the merged piece fails) verifies
//!   only when the pieces that passed cover `[0, stop]`, and always when every interval passes.
//! - `f3` (twin only: the real `Shield` is far too big for a model checker): random chunks and
//!   random measurements (none, stale, from the future, far away, on the robot) drive the real
//!   shield; every command equals the state of the shield's stored verified failsafe at its time,
//!   the failsafe changes only on verified steps, and once verification fails forever the robot
//!   is at rest by the reported stop time and stays there.

use crate::{Source, harness};
use pacs_motion::scaling::{PathState, SpeedProfile};
use pacs_shield::shield::{
    Candidate, FilterMode, OccupancyIntervals, Piece, VerifiedFailsafe, choose, decide, verify_fine,
};

/// Steps of the symbolic sequence in `f1` (the property is inductive; see README): under Kani
/// one step from any stored failsafe (the induction step; the base, `Shield::start`'s standing
/// still, is the twin's starting state), 3 from the start state in tests.
const STEPS: usize = if cfg!(kani) { 1 } else { 3 };

fn decide_induction<S: Source>(s: &mut S) {
    decide_induction_branch(s, None);
}

/// [`decide_induction`] restricted to steps whose candidate was adopted (`Some(true)`) or not
/// (`Some(false)`): the two halves of the induction step, one Kani proof each.
fn decide_induction_branch<S: Source>(s: &mut S, branch: Option<bool>) {
    let alpha = s.f64_in(1e-4, 0.01);
    let (acc, jerk) = (s.f64_in(0.5, 20.0), s.f64_in(1.0, 500.0));
    let mut t = s.f64_in(0.0, 100.0);
    // `Shield::start`: at rest, standing still is the first verified failsafe.
    let mut stored = VerifiedFailsafe {
        slot: 0,
        profile: SpeedProfile::plan(PathState::rest(0.0), 0.0, 1.0, 1.0),
        t0: t,
    };
    if !cfg!(kani) {
        // The range the Kani stub of `plan` draws from covers this profile too (the later ones
        // are checked where they are planned).
        let p = &stored.profile;
        assert!(
            crate::profile_in_stub_range(p),
            "{p:?} outside the stub's range"
        );
    }
    let mut slot = 0;
    let mut path = PathState::rest(0.0);
    if cfg!(kani) {
        // Any stored failsafe (under Kani `plan` returns any profile), in either slot, started
        // at most 1 s ago.
        stored = VerifiedFailsafe {
            slot: s.index(2),
            profile: SpeedProfile::plan(path, 0.0, acc, jerk),
            t0: t - s.f64_in(0.0, 1.0),
        };
        slot = stored.slot;
    }
    for step in 0..STEPS {
        let candidate = any_candidate(s, (stored.slot, slot), path, (acc, jerk), alpha);
        // Kani checks the selection (`choose`: which profile, which time, which failsafe) for
        // any profiles and times; the twin also checks `decide`, its evaluation.
        let ch = choose(stored, candidate, FilterMode::Pacs, t, alpha);
        // (The restriction applies to the first step: the only one under Kani.)
        if let Some(want) = branch
            && step == 0
            && !s.assume(ch.adopted == want)
        {
            return;
        }
        if ch.adopted {
            // Executed: the verified monitored trajectory (go for α, then brake from t + α).
            let c = candidate.expect("adopted a candidate");
            assert!(c.verified, "adopted an unverified candidate");
            assert_eq!(ch.slot, c.slot);
            // Bitwise: the executed state is read from the verified go step at α (a NaN would
            // not compare equal to itself under `==`; the claim is that it is the same value).
            assert!(ch.profile.same_bits(&c.go) && ch.tau.to_bits() == alpha.to_bits());
            assert!(
                ch.failsafe.slot == c.slot
                    && ch.failsafe.profile.same_bits(&c.brake)
                    && ch.failsafe.t0.to_bits() == (t + alpha).to_bits()
            );
        } else {
            // Not verified (or no candidate): the stored failsafe is kept and continued.
            assert!(
                ch.failsafe.slot == stored.slot
                    && ch.failsafe.profile.same_bits(&stored.profile)
                    && ch.failsafe.t0.to_bits() == stored.t0.to_bits(),
                "failsafe abandoned without verification"
            );
            assert_eq!(ch.slot, stored.slot);
            assert!(
                ch.profile.same_bits(&stored.profile)
                    && ch.tau.to_bits() == (t + alpha - stored.t0).to_bits()
            );
        }
        if cfg!(kani) {
            // One step (the induction step); the evaluation is the twin's.
            return;
        }
        // `decide` is the choice evaluated: the executed state.
        let d = decide(stored, candidate, FilterMode::Pacs, t, alpha);
        assert!(
            d.slot == ch.slot
                && d.adopted == ch.adopted
                && d.path.same_bits(&ch.profile.eval(ch.tau))
                && d.failsafe.slot == ch.failsafe.slot
                && d.failsafe.profile.same_bits(&ch.failsafe.profile)
                && d.failsafe.t0.to_bits() == ch.failsafe.t0.to_bits()
        );
        if d.adopted {
            // Split (proofs/README.md): that the stored failsafe starts where the executed
            // state is (within rounding) is a property of the planner (`plan` from
            // `go.eval(α)`), the twin's and f3's.
            let b0 = d.failsafe.profile.eval(0.0);
            assert_eq!(b0.s, d.path.s);
            assert!((b0.sd - d.path.sd).abs() <= 1e-12 && (b0.sdd - d.path.sdd).abs() <= 1e-9);
        }
        stored = d.failsafe;
        slot = d.slot;
        path = d.path;
        t += alpha;
    }
    if cfg!(kani) {
        // Split (proofs/README.md): that a profile is at rest from its settle time on is e1's
        // claim (`e1_braking_profile`); the twin checks it here for the failsafe reached.
        return;
    }
    // Verification fails from now on: every later step continues `stored` (shown above), so
    // the executed state at any time after the settle time is the rest state.
    let settle_t = stored.t0 + stored.profile.settle_time();
    let later = s.f64_in(0.0, 10.0);
    let t_x = (settle_t - alpha).max(t) + later;
    // (Float rounding of the times: keep t_x with t_x + α − t0 ≥ settle time.)
    if !s.assume(t_x + alpha - stored.t0 >= stored.profile.settle_time()) {
        return;
    }
    let d = decide(stored, None, FilterMode::Pacs, t_x, alpha);
    assert_eq!(d.failsafe, stored);
    assert!(
        d.path.sd == 0.0 && d.path.sdd == 0.0,
        "not at rest after settling: {:?}",
        d.path
    );
    assert_eq!(d.path.s, stored.profile.settle_s());
}
/// A step's candidate, if any: a fresh chunk (the slot other than the stored failsafe's
/// (`slots.0`), from its start on the intended timing) or the current path (slot `slots.1`, at
/// `path`), planned with the limits `(acc, jerk)`, its brake from the go profile's state at
/// `alpha`; verified or not.
fn any_candidate<S: Source>(
    s: &mut S,
    (stored_slot, slot): (usize, usize),
    path: PathState,
    (acc, jerk): (f64, f64),
    alpha: f64,
) -> Option<Candidate> {
    if !s.bool() {
        return None;
    }
    // A fresh chunk (other slot, from its start on the intended timing) or the current path.
    let (cslot, start) = if s.bool() {
        (1 - stored_slot, PathState::intended(0.0))
    } else {
        (slot, path)
    };
    let go = if start.is_intended() {
        SpeedProfile::plan(start, 1.0, 0.0, 0.0)
    } else {
        SpeedProfile::plan(start, 1.0, acc, jerk)
    };
    // (Under Kani `plan` returns any profile whatever its start: no need to evaluate.)
    let brake_start = if cfg!(kani) { start } else { go.eval(alpha) };
    let brake = SpeedProfile::plan(brake_start, 0.0, acc, jerk);
    if !cfg!(kani) {
        // The range the Kani stub of `plan` draws from covers the planner's profiles.
        for p in [&go, &brake] {
            assert!(
                crate::profile_in_stub_range(p),
                "{p:?} outside the stub's range"
            );
        }
    }
    Some(Candidate {
        slot: cslot,
        go,
        brake,
        verified: s.bool(),
    })
}

// Under Kani every planned profile is *any* profile (`stubs::any_speed_profile`, an
// over-approximation of `SpeedProfile::plan`: 1 to 4 phases, every field any finite `f64`):
// `choose` only copies the profiles it is given and the claims compare bit patterns, so they
// hold for every profile, planned or not, and every input at full width.
// The whole induction step verifies under Kani but over the 120 s budget (86.7–139.8 s before
// `choose` carried its contract): not in CI, where Kani checks its two halves below.
harness!(
    f1_shield_decision_induction,
    unwind = 6,
    bits = 52,
    stub = (pacs_motion::scaling::SpeedProfile::plan => crate::stubs::any_speed_profile),
    cases = crate::DEFAULT_CASES,
    decide_induction
);

fn decide_adopted<S: Source>(s: &mut S) {
    decide_induction_branch(s, Some(true));
}
fn decide_kept<S: Source>(s: &mut S) {
    decide_induction_branch(s, Some(false));
}
// The induction step where the candidate is adopted: it was verified, and the executed state and
// the new failsafe are the candidate's go and brake, bitwise.
harness!(
    f1_decision_adopted,
    unwind = 6,
    bits = 52,
    stub = (pacs_motion::scaling::SpeedProfile::plan => crate::stubs::any_speed_profile),
    cases = crate::DEFAULT_CASES,
    decide_adopted
);
// The induction step where it is not: the stored failsafe is kept and continued, bitwise.
harness!(
    f1_decision_kept,
    unwind = 6,
    bits = 52,
    stub = (pacs_motion::scaling::SpeedProfile::plan => crate::stubs::any_speed_profile),
    cases = crate::DEFAULT_CASES,
    decide_kept
);

fn intervals_cover<S: Source>(s: &mut S) {
    let alpha = s.f64_in(1e-4, 0.01);
    let stop = alpha + s.f64_in(0.0, 5.0);
    let first = s.f64_in(1e-4, 0.1);
    let max = 1 + s.index(12);
    let mut next_ta = 0.0;
    let mut count = 0;
    let mut last_tb = f64::NAN;
    for (k, ta, tb) in OccupancyIntervals::new(alpha, stop, first, max) {
        assert_eq!(k, count, "interval index");
        assert_eq!(ta, next_ta, "gap or overlap before interval {k}");
        assert!(ta <= tb, "empty interval {k}");
        if k == 0 {
            assert_eq!(tb, alpha, "first interval is the intended step");
        }
        count += 1;
        // Interval 0 is the intended step; at most max(max_intervals, 2) in all.
        assert!(count <= max.max(2), "more than max_intervals");
        next_ta = tb;
        last_tb = tb;
    }
    assert!(count >= 1);
    assert!(
        last_tb >= stop,
        "intervals end at {last_tb} before standstill {stop}"
    );
}
harness!(
    f2_occupancy_intervals_cover,
    unwind = 14,
    cases = crate::DEFAULT_CASES,
    intervals_cover
);

/// More than the most occupancy intervals (`max_intervals` ≤ 12, so at most 12).
const MAX_PIECES: usize = 14;

/// Any sequence of intervals `(k, t_a, t_b)`, `k = 0, 1, …` (Kani's stand-in for
/// [`OccupancyIntervals`], whose contiguity is `f2_occupancy_intervals_cover`'s claim).
#[derive(Clone)]
struct AnyIntervals {
    times: [(f64, f64); MAX_PIECES],
    n: usize,
    k: usize,
}

impl Iterator for AnyIntervals {
    type Item = (usize, f64, f64);
    fn next(&mut self) -> Option<(usize, f64, f64)> {
        if self.k >= self.n {
            return None;
        }
        let (k, (ta, tb)) = (self.k, self.times[self.k]);
        self.k += 1;
        Some((k, ta, tb))
    }
}

fn fine_pieces_cover<S: Source>(s: &mut S) {
    // The intervals: under Kani any 1 to 12 of any times; in the twin the shield's own.
    let mut leaf = [(0.0, 0.0); MAX_PIECES];
    let mut leaves = 0;
    if cfg!(kani) {
        leaves = 1 + s.index(12);
        for l in &mut leaf[..leaves] {
            *l = (s.f64_in(0.0, 5.0), s.f64_in(0.0, 5.0));
        }
    } else {
        let alpha = s.f64_in(1e-4, 0.01);
        let stop = alpha + s.f64_in(0.0, 5.0);
        let (first, max) = (s.f64_in(1e-4, 0.1), 1 + s.index(12));
        for (k, ta, tb) in OccupancyIntervals::new(alpha, stop, first, max) {
            leaf[k] = (ta, tb);
            leaves = k + 1;
        }
    }
    let intervals = AnyIntervals {
        times: leaf,
        n: leaves,
        k: 0,
    };
    // Any verification outcome per interval (fixed per interval, as the shield's is) and for
    // the merged piece.
    let mut leaf_ok = [true; MAX_PIECES];
    for ok in &mut leaf_ok[..leaves] {
        *ok = s.bool();
    }
    let last = leaves - 1;
    let merged_ok = s.bool();
    // Which pieces were checked and passed; each piece's times are those it stands for.
    let mut passed = [false; MAX_PIECES];
    let mut merged_passed = false;
    let mut calls = 0;
    let ok = verify_fine(intervals, |piece, ta, tb| {
        calls += 1;
        match piece {
            Piece::Interval(k) => {
                assert!(
                    k < leaves && (ta, tb) == leaf[k],
                    "interval {k}: [{ta}, {tb}]"
                );
                passed[k] = leaf_ok[k];
                leaf_ok[k]
            }
            Piece::Before(k) => {
                // [0, t_a of the last interval] = the union of the intervals before it (when
                // they are contiguous from 0: f2_occupancy_intervals_cover).
                assert!(k == last && k > 0, "merged piece {k} of {leaves}");
                assert!(ta == 0.0 && tb == leaf[last].0, "merged piece [{ta}, {tb}]");
                merged_passed = merged_ok;
                merged_ok
            }
        }
    });
    assert!(calls <= leaves + 1, "{calls} checks for {leaves} intervals");
    let mut before_all = true;
    let mut all = leaf_ok[last];
    for k in 0..last {
        before_all &= passed[k];
        all &= leaf_ok[k];
    }
    if ok {
        // Covered: the last interval, and everything before it, merged or one by one.
        assert!(passed[last], "verified without the last interval");
        assert!(
            merged_passed || before_all,
            "verified without covering [0, t_a] of the last interval"
        );
    }
    if all {
        assert!(ok, "every interval verified, the fine verification did not");
    }
}
harness!(
    f2_fine_pieces_cover,
    unwind = 15,
    cases = crate::DEFAULT_CASES,
    fine_pieces_cover
);

/// `f3`: the real shield (property test only).
#[cfg(test)]
mod real {
    use crate::Source;
    use pacs_models::{ConstraintSpec, default_human, fr3};
    use pacs_motion::chunk::{ActionKind, Chunk};
    use pacs_reach::human::HumanMeasurement;
    use pacs_shield::shield::{Shield, ShieldConfig};

    /// Counters of the `f3` twin (steps, verified steps, failsafe changes): the test asserts that
    /// both outcomes occur, so the invariants are exercised on verified and unverified steps.
    static F3_STATS: [std::sync::atomic::AtomicUsize; 3] =
        [const { std::sync::atomic::AtomicUsize::new(0) }; 3];

    fn count(i: usize) {
        F3_STATS[i].fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    }

    /// Random steps of the real shield, then verification failing forever.
    fn real_shield<S: Source>(s: &mut S) {
        let robot = fr3::fr3();
        let human = default_human()
            .with_uncertainty(0.01, 0.1, 0.02)
            .expect("valid");
        let spec = ConstraintSpec::builtin("ssm").expect("preset");
        let cfg = ShieldConfig {
            safety_step: [0.001, 0.002, 0.004][s.index(3)],
            ..ShieldConfig::default()
        };
        let alpha = cfg.safety_step;
        let mut sh = Shield::new(robot, Some((human.clone(), &spec)), vec![], cfg).expect("valid");
        let q0 = fr3::Q_READY;
        sh.start(0.0, &q0).expect("at rest in limits");
        let far = pacs_testkit::human_reaching(3.0, 0.0, [2.8, -0.3, 1.2]);
        // The hand on the robot's flange region (it never moves more than a few cm here).
        let near = pacs_testkit::human_reaching(0.6, 0.0, [0.3, 0.0, 0.5]);
        let mut t = 0.0;
        let random_steps = 3 + s.index(12);
        let mut fail_forever = false;
        let mut at_rest_since: Option<[f64; 7]> = None;
        for step in 0..4000 {
            if step == random_steps {
                fail_forever = true;
            }
            if !fail_forever && s.index(3) == 0 {
                let delta: Vec<f64> = (0..7).map(|_| s.f64_in(-0.02, 0.02)).collect();
                let _ = sh.set_chunk(&Chunk {
                    kind: ActionKind::Delta,
                    actions: vec![delta; 8],
                    execute: 1 + s.index(8),
                    gripper: None,
                });
            }
            let kp = if fail_forever || s.bool() {
                &near
            } else {
                &far
            };
            let stamp = match if fail_forever { 0 } else { s.index(4) } {
                0 => Some(t),
                1 => Some(t - 0.05),
                2 => Some(t + 0.01), // from the future: ignored
                _ => None,
            };
            let m = stamp.map(|st| HumanMeasurement::new(&human, st, kp, None).expect("finite"));
            let before = sh.verified_failsafe().expect("started");
            let cmd = sh.step(t, m.as_ref()).expect("started");
            let after = sh.verified_failsafe().expect("started");
            count(0);
            if cmd.diag.verified {
                count(1);
            }
            if after != before {
                count(2);
            }
            // The failsafe is only abandoned for a newly verified one.
            if after != before {
                assert!(cmd.diag.verified, "failsafe changed on an unverified step");
                assert_eq!(after.t0, cmd.t);
            }
            if fail_forever {
                assert!(!cmd.diag.verified, "verified with the human on the robot");
            }
            // The command lies on the stored verified failsafe (the last verified monitored
            // trajectory; at its start the go-step and the brake meet).
            let on = sh.failsafe_state_at(cmd.t).expect("started");
            for i in 0..7 {
                assert!(
                    (cmd.state.q[i] - on.q[i]).abs() <= 1e-12,
                    "q off the verified failsafe"
                );
                assert!(
                    (cmd.state.dq[i] - on.dq[i]).abs() <= 1e-9,
                    "q̇ off the verified failsafe"
                );
            }
            // Failing forever: at rest after the reported stop time, and it stays there.
            if fail_forever && cmd.t >= cmd.diag.stop_time + alpha {
                assert!(cmd.dq().iter().all(|v| *v == 0.0), "moving after stop time");
                let q: [f64; 7] = std::array::from_fn(|i| cmd.state.q[i]);
                match at_rest_since {
                    None => at_rest_since = Some(q),
                    Some(q_rest) => {
                        assert_eq!(q, q_rest, "moved after reaching rest");
                        return;
                    }
                }
            }
            t += alpha;
        }
        panic!("did not reach rest within 4000 steps");
    }

    #[test]
    fn f3_real_shield_commands_on_verified_failsafe() {
        crate::run_cases("f3_real_shield", crate::DEFAULT_CASES, real_shield);
        let [steps, verified, changes] = F3_STATS
            .each_ref()
            .map(|c| c.load(std::sync::atomic::Ordering::Relaxed));
        eprintln!("f3: {steps} steps, {verified} verified, {changes} failsafe changes");
        assert!(
            verified * 20 >= steps / 10 && verified < steps,
            "f3 must exercise both outcomes"
        );
    }
}

/// A pool of intended trajectories for f5: the first anchor chunks of the FR3 (the motion
/// crate's demonstration-like chunks), planned once, each with its own Moving or AtRest end.
fn trajectory_pool() -> &'static [pacs_motion::Trajectory] {
    use pacs_motion::anchors::anchor_set;
    use pacs_motion::{EndCondition, JointState, Limits, OutOfLimits, Planner, PlannerConfig};
    static POOL: std::sync::OnceLock<Vec<pacs_motion::Trajectory>> = std::sync::OnceLock::new();
    POOL.get_or_init(|| {
        let robot = pacs_models::RobotModel::builtin("fr3").expect("built-in fr3");
        let plan = Limits::from_joint_limits(robot.limits()).with_uniform_acc_jerk(10.0, 400.0);
        anchor_set(robot.limits(), 8, 11)
            .iter()
            .enumerate()
            .filter_map(|(k, p)| {
                let wp = p
                    .chunk
                    .waypoints(&p.q0, robot.limits(), OutOfLimits::Reject)
                    .ok()?;
                let end = if k % 2 == 0 {
                    EndCondition::Moving
                } else {
                    EndCondition::AtRest
                };
                let mut pl = Planner::new(
                    plan,
                    PlannerConfig {
                        end,
                        ..Default::default()
                    },
                );
                pl.plan(&JointState::at_rest(&p.q0), &wp).ok()
            })
            .collect()
    })
}

/// The joint boxes of one occupancy interval (claim C7, `monitored_joint_boxes`, the shield's
/// own computation) contain the executed joint state at every instant of the interval: random
/// intended trajectories (the pool), a go profile from a random consistent path state for α,
/// the brake planned from where it ends (as the shield does), a random interval `[ta, tb]`
/// around α, and sampled instants τ in it (biased to the ends); the executed state is
/// `q(s(τ))`, `q′(s(τ))·ṡ(τ)` with `(s, ṡ)` from `go.eval(τ)` before α and
/// `brake.eval(τ − α)` from α on.
fn joint_boxes<S: Source>(s: &mut S) {
    let pool = trajectory_pool();
    let tr = &pool[s.index(pool.len())];
    let alpha = [0.001, 0.002, 0.004][s.index(3)];
    let (acc, jerk) = (s.f64_in(0.5, 20.0), s.f64_in(1.0, 500.0));
    let sdd = s.f64_in(-acc, acc);
    let sd = s.f64_in(0.0, 1.5);
    if !s.assume(sdd >= 0.0 || sd >= sdd * sdd / (2.0 * jerk)) {
        return;
    }
    let start = PathState {
        s: s.f64_in(0.0, tr.rest_time()),
        sd,
        sdd,
    };
    let target = if s.bool() { 1.0 } else { s.f64_in(0.0, 1.5) };
    let go = SpeedProfile::plan(start, target, acc, jerk);
    let brake = SpeedProfile::plan(go.eval(alpha), 0.0, acc, jerk);
    let horizon = alpha + brake.settle_time() + 0.01;
    let ta = if s.bool() {
        0.0
    } else {
        s.f64_in(0.0, horizon)
    };
    let tb = if s.bool() {
        alpha.max(ta)
    } else {
        s.f64_in(ta, horizon)
    };
    let n = tr.dof();
    let (mut q_lo, mut q_hi, mut v_lo, mut v_hi) = ([0.0; 7], [0.0; 7], [0.0; 7], [0.0; 7]);
    pacs_shield::shield::monitored_joint_boxes(
        tr,
        &go,
        &brake,
        alpha,
        (ta, tb),
        (&mut q_lo[..n], &mut q_hi[..n]),
        (&mut v_lo[..n], &mut v_hi[..n]),
    );
    for _ in 0..4 {
        let tau = s.f64_in(ta, tb);
        // At τ = α the executed state is where the go step ends (the brake is planned from it).
        let e = if tau <= alpha {
            go.eval(tau)
        } else {
            brake.eval(tau - alpha)
        };
        for i in 0..n {
            let (q, dq, _) = tr.joint_at(i, e.s);
            let v = dq * e.sd;
            assert!(
                q_lo[i] <= q && q <= q_hi[i],
                "joint {i}: q = {q} ∉ [{}, {}] at τ = {tau} in [{ta}, {tb}]",
                q_lo[i],
                q_hi[i]
            );
            // q′·ṡ in floating point is within one rounding of the exact product, which the
            // box's outward rounding (one ulp each way) already covers.
            assert!(
                v_lo[i] <= v && v <= v_hi[i],
                "joint {i}: q̇ = {v} ∉ [{}, {}] at τ = {tau} in [{ta}, {tb}] (ṡ = {})",
                v_lo[i],
                v_hi[i],
                e.sd
            );
        }
    }
}
harness!(
    f5_joint_boxes_enclose,
    twin_only,
    cases = crate::DEFAULT_CASES,
    joint_boxes
);
