//! Kani harnesses of the shield's induction step (claim C8, proofs/README.md § C8) on the real
//! step, [`run_step`] (the body of [`Shield::step`]), and the proofs of the contract of
//! [`choose`] it uses.
//!
//! `f3_shield_step_induction` runs `run_step` from *any* state of the induction invariant — any
//! stored failsafe (any finite profile, either slot, started up to 1 s before the step), the
//! command on its slot at any path state, a fresh chunk or none in the other slot, any chunk
//! serials and offer state — with any measurement of the person (none, older, newer, from the
//! future), a waiting offer taken over or not, in any mode, at any step time in [0, 100] s and
//! any α_s in [1e-4, 0.01] s. Its environment ([`StepEnv`]) is a model whose operations return
//! *any* result the shield's could:
//! - `verify`: any verdict, recorded with what it was asked and the measurement in use (the
//!   soundness of a `true` verdict is claim C7's, not the step's: the step must hold whatever the
//!   verification answers);
//! - `candidate`: any pair of finite go and brake profiles, or none (the planner);
//! - `take_offer`: the shield's own slot choice ([`StepState::take_over_slot`]) when the offer
//!   is taken over, else nothing;
//! - `take_measurement`: the newest-stamp rule of the shield (`stamped::supersedes`);
//! - `at_rest`: any answer.
//!
//! [`choose`] is replaced by its verified contract [`chosen_by_rule`] (`stub_verified`), and
//! [`SpeedProfile::eval`] (the executed state read from the chosen profile) by its verified
//! contract (a path speed ≥ 0, `f3_eval_contract`): the harnesses assert nothing of the executed
//! state's values, and evaluating a symbolic cubic was most of their solver time.
//!
//! It proves the induction step: after the step the command follows the new stored failsafe's
//! slot and no fresh chunk is left; in PACS and single-action modes the failsafe changes only to
//! the brake of a candidate whose last verification returned `true` (no unverified intended
//! step is executed); every verification saw the newest measurement delivered at or before `t`;
//! otherwise the stored failsafe, its slot and the trajectory it lives on (its chunk serial) are
//! kept. Mutants `x67_step_adopts_before_verify` and `x68_step_verifies_stale_measurement` make
//! it fail. In CI it runs as three parts that together cover every step (each within the
//! budget): `f3_step_kept` (the step keeps the stored failsafe), `f3_adopt_pacs`,
//! `f3_adopt_single_action` and `f3_adopt_off` (it adopts its candidate, in each mode).

#![allow(dead_code)] // The harnesses are entry points of `cargo kani` only.

use super::decision::Choice;
use super::step::{StepEnv, StepState, run_step};
use super::*;

/// What the model's `verify` saw in one step: how often it was called, and the last call.
#[derive(Clone, Copy)]
struct Spy {
    calls: usize,
    last: Option<Seen>,
}

/// One verification: what it was asked, its verdict and the measurement in use.
#[derive(Clone, Copy)]
struct Seen {
    slot: usize,
    brake: SpeedProfile,
    t: f64,
    ok: bool,
    meas: Option<f64>,
}

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
    let phase = || {
        (
            any_finite(),
            any_finite(),
            any_finite(),
            any_finite(),
            any_finite(),
        )
    };
    SpeedProfile::from_parts(
        [phase(), phase(), phase(), phase()],
        n,
        any_finite(),
        any_finite(),
        any_finite(),
        any_finite(),
    )
}

/// A measurement of the model: its stamp (s).
struct Stamp(f64);

/// The model environment of `f3_shield_step_induction` (module docs).
struct Model {
    st: StepState,
    alpha: f64,
    mode: FilterMode,
    /// Stamp of person 0's measurement in use, if any.
    meas: Option<f64>,
    /// A chunk is waiting for its handover; the step takes it over when `take_it`.
    offer: bool,
    take_it: bool,
    accepted: u64,
    spy: Spy,
}

impl StepEnv for Model {
    type Measurement = Stamp;
    fn st(&mut self) -> &mut StepState {
        &mut self.st
    }
    fn safety_step(&self) -> f64 {
        self.alpha
    }
    fn mode(&self) -> FilterMode {
        self.mode
    }
    fn take_measurement(&mut self, m: Option<&Stamp>, t: f64) {
        if let Some(m) = m
            && m.0 <= t
            && self.meas.is_none_or(|c| m.0 > c)
        {
            self.meas = Some(m.0);
        }
    }
    fn take_offer(&mut self, _t: f64) {
        if self.offer && self.take_it {
            self.offer = false;
            self.accepted += 1;
            self.st.take_over_slot(self.accepted);
        }
    }
    fn at_rest(&self) -> bool {
        kani::any()
    }
    fn candidate(&self, _slot: usize, _start: PathState) -> Option<(SpeedProfile, SpeedProfile)> {
        if kani::any() {
            Some((any_profile(), any_profile()))
        } else {
            None
        }
    }
    fn verify(
        &mut self,
        slot: usize,
        _go: &SpeedProfile,
        brake: &SpeedProfile,
        t: f64,
        _diag: &mut Diagnostics,
    ) -> bool {
        let ok: bool = kani::any();
        self.spy.calls += 1;
        self.spy.last = Some(Seen {
            slot,
            brake: *brake,
            t,
            ok,
            meas: self.meas,
        });
        ok
    }
    fn command_state(&self) -> JointState {
        JointState::default()
    }
    fn dof(&self) -> usize {
        1
    }
}

fn any_mode() -> FilterMode {
    match kani::any::<u8>() % 3 {
        0 => FilterMode::Pacs,
        1 => FilterMode::Off,
        _ => FilterMode::SingleAction,
    }
}

#[kani::proof]
#[kani::unwind(6)]
#[kani::stub_verified(choose)]
#[kani::stub_verified(SpeedProfile::eval)]
fn f3_shield_step_induction() {
    step_induction(None, None);
}

/// The induction step where the candidate is adopted in PACS mode (with `f3_adopt_off`,
/// `f3_adopt_single_action` and `f3_step_kept`: the whole step, split by outcome and by mode, to
/// fit the budget).
#[kani::proof]
#[kani::unwind(6)]
#[kani::stub_verified(choose)]
#[kani::stub_verified(SpeedProfile::eval)]
fn f3_adopt_pacs() {
    step_induction(Some(true), Some(FilterMode::Pacs));
}

/// The induction step where the candidate is adopted in OFF mode (the policy's step executed
/// unfiltered; the step's bookkeeping must still hold).
#[kani::proof]
#[kani::unwind(6)]
#[kani::stub_verified(choose)]
#[kani::stub_verified(SpeedProfile::eval)]
fn f3_adopt_off() {
    step_induction(Some(true), Some(FilterMode::Off));
}

/// The induction step where the candidate is adopted in single-action mode.
#[kani::proof]
#[kani::unwind(6)]
#[kani::stub_verified(choose)]
#[kani::stub_verified(SpeedProfile::eval)]
fn f3_adopt_single_action() {
    step_induction(Some(true), Some(FilterMode::SingleAction));
}

/// The induction step where the stored failsafe is kept.
#[kani::proof]
#[kani::unwind(6)]
#[kani::stub_verified(choose)]
#[kani::stub_verified(SpeedProfile::eval)]
fn f3_step_kept() {
    step_induction(Some(false), None);
}

/// The body of the f3 harnesses: one step of `run_step` from any state of the invariant (module
/// docs); `outcome`, if given, restricts the proof to steps that adopt (`true`) or keep;
/// `mode`, if given, to that mode (else any).
fn step_induction(outcome: Option<bool>, mode: Option<FilterMode>) {
    let t = any_in(0.0, 100.0);
    let alpha = any_in(1e-4, 0.01);
    let mode = mode.unwrap_or_else(any_mode);
    // Any state of the invariant: a failsafe on either slot, the command on its slot, a fresh
    // chunk (if any) on the other.
    let f = VerifiedFailsafe {
        slot: usize::from(kani::any::<bool>()),
        profile: any_profile(),
        t0: t - any_in(0.0, 1.0),
    };
    let serials: [u64; 2] = [kani::any(), kani::any()];
    let mut env = Model {
        st: StepState {
            started: true,
            time: t,
            slot: f.slot,
            path: PathState {
                s: any_finite(),
                sd: any_finite(),
                sdd: any_finite(),
            },
            fresh: kani::any::<bool>().then_some(1 - f.slot),
            failsafe: Some(f),
            last_verified: kani::any(),
            offer_state: OfferState::Waiting,
            chunk_serial: serials,
        },
        alpha,
        mode,
        meas: kani::any::<bool>().then(|| any_in(-10.0, 100.0)),
        offer: kani::any(),
        take_it: kani::any(),
        // Chunks accepted so far: any count that leaves room for one more (a take-over writes
        // serial `accepted + 1`, into the slot the failsafe does not use).
        accepted: serials[0].max(serials[1]) % (u64::MAX / 2),
        spy: Spy {
            calls: 0,
            last: None,
        },
    };
    let old_meas = env.meas;
    // This step's measurement: none, or one stamped at any time (older, newer, from the future).
    let given = Stamp(any_in(-10.0, 110.0));
    let given = kani::any::<bool>().then_some(&given);

    let cmd = run_step(&mut env, t, given).expect("started");

    let st = env.st;
    let nf = st.failsafe.expect("a failsafe after every step");
    let adopted = !cmd.diag.on_failsafe;
    if let Some(o) = outcome {
        kani::assume(adopted == o);
    }
    // The command follows the stored failsafe's slot; the fresh chunk had its one try.
    assert!(st.slot == nf.slot, "the command left the failsafe's slot");
    assert!(st.fresh.is_none(), "a fresh chunk survived its one try");
    assert!(
        st.time.to_bits() == (t + alpha).to_bits(),
        "the step's time"
    );
    // Every verification saw the newest measurement delivered at or before t.
    if let Some(seen) = env.spy.last {
        let newest = match given {
            Some(m) if m.0 <= t && old_meas.is_none_or(|c| m.0 > c) => Some(m.0),
            _ => old_meas,
        };
        assert!(
            seen.meas.map(f64::to_bits) == newest.map(f64::to_bits),
            "verified against a stale measurement"
        );
        assert!(seen.t.to_bits() == t.to_bits(), "verified for another time");
    }
    assert!(
        env.spy.calls <= 2,
        "more than two verifications in one step"
    );
    if adopted && mode != FilterMode::Off {
        // No unverified intended step is executed: the last verification of this step returned
        // true, on the candidate whose brake is the new failsafe from t + α.
        let seen = env.spy.last.expect("adopted without a verification");
        assert!(seen.ok, "adopted an unverified candidate");
        assert!(
            nf.slot == seen.slot
                && nf.profile.same_bits(&seen.brake)
                && nf.t0.to_bits() == (t + alpha).to_bits(),
            "the new failsafe is not the verified brake"
        );
        assert!(cmd.diag.verified, "an adopted step not reported verified");
    }
    if !adopted {
        // Kept: the stored failsafe, its slot and the trajectory it lives on.
        assert!(
            nf.slot == f.slot
                && nf.profile.same_bits(&f.profile)
                && nf.t0.to_bits() == f.t0.to_bits(),
            "the stored failsafe changed without a verified candidate"
        );
        assert!(
            st.chunk_serial[f.slot] == serials[f.slot],
            "the failsafe's trajectory was replaced"
        );
    }
}

/// Inputs of `choose` in its precondition (`choose_in_proven_range`): any finite `t`, `α` and
/// failsafe start, any candidate, any mode; finite profiles (with NaN fields Bitwuzla refutes the bit-for-bit copy: its
/// floating-point theory has one NaN, whose bit pattern the encoding leaves free).
fn choose_inputs() -> (VerifiedFailsafe, Option<Candidate>, FilterMode, f64, f64) {
    let t = any_finite();
    let alpha = any_finite();
    let stored = VerifiedFailsafe {
        slot: usize::from(kani::any::<bool>()),
        profile: any_profile(),
        t0: any_finite(),
    };
    let candidate = kani::any::<bool>().then(|| Candidate {
        slot: usize::from(kani::any::<bool>()),
        go: any_profile(),
        brake: any_profile(),
        verified: kani::any(),
    });
    (stored, candidate, any_mode(), t, alpha)
}

/// The contract of [`SpeedProfile::eval`] (the path speed is never negative) on the real
/// function, for any finite profile of 1 to 4 phases and any `tau` its precondition admits
/// (up to 10²⁸⁰ s, NaN and −∞ included).
#[kani::proof_for_contract(SpeedProfile::eval)]
#[kani::unwind(5)]
fn f3_eval_contract() {
    let p = any_profile();
    let tau: f64 = kani::any();
    let _ = p.eval(tau);
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

/// The contract of [`interval_end`] (claim C7) on the real function, for any interval index and
/// limit and any `ta`, `dur`, `α_s`, `stop` its precondition admits (`dur = +∞` included).
#[kani::proof_for_contract(interval_end)]
fn f2_interval_end_contract() {
    let (k, ta, dur, alpha, stop, max) = (
        kani::any(),
        kani::any(),
        kani::any(),
        kani::any(),
        kani::any(),
        kani::any(),
    );
    let _: f64 = interval_end(k, ta, dur, alpha, stop, max);
}

/// The occupancy intervals cover the monitored trajectory (claim C7) given only [`interval_end`]'s
/// contract: for any finite `0 < α_s ≤ stop`, any finite first duration > 0 and any `max_intervals` in
/// 1..=12, [`OccupancyIntervals`] yields intervals `0, 1, …` that are contiguous from 0, start
/// with `[0, α_s]`, number at most `max(max, 2)` and end at `stop`. `interval_end` is replaced by
/// its verified contract (every call's precondition is checked here), so the iterator's own
/// bookkeeping (the start of each interval, `done`, the limit) is what is proven.
#[kani::proof]
#[kani::stub_verified(interval_end)]
#[kani::unwind(15)]
fn f2_intervals_cover_by_contract() {
    let alpha = any_finite();
    let stop = any_finite();
    kani::assume(alpha > 0.0 && alpha <= stop);
    // The shield's validated `first_interval` (positive, finite).
    let first = any_finite();
    kani::assume(first > 0.0);
    let max: usize = kani::any();
    kani::assume((1..=12).contains(&max));
    let (mut next_ta, mut count, mut last_tb) = (0.0, 0usize, f64::NAN);
    for (k, ta, tb) in OccupancyIntervals::new(alpha, stop, first, max) {
        assert!(k == count, "interval index");
        assert!(ta == next_ta, "a gap or overlap");
        assert!(ta <= tb, "an empty interval");
        assert!(k > 0 || tb == alpha, "interval 0 is the intended step");
        count += 1;
        assert!(count <= max.max(2), "more than max_intervals");
        next_ta = tb;
        last_tb = tb;
    }
    assert!(count >= 1, "no interval");
    assert!(last_tb == stop, "the intervals end before standstill");
}
