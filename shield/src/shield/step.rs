//! One safety step of the shield: the latest measurement, the candidate (go, then brake) and the
//! decision between it and the stored failsafe.

use super::{
    Binding, Candidate, Command, Diagnostics, FilterMode, OfferState, Shield, ShieldError,
    VerifiedFailsafe, decide,
};
use pacs_motion::scaling::{PathState, SpeedProfile, admissible};
use pacs_motion::trajectory::JointState;
use pacs_reach::human::HumanMeasurement;

impl Shield {
    /// Take the first human's measurement `m` (`HumanSlot::take`: it replaces the one in use if it
    /// is newer and agrees with the trusted ones; one that contradicts them stops verification;
    /// ones from the future and ones for another model's keypoint count are ignored).
    fn take_measurement(&mut self, m: Option<&HumanMeasurement>, t: f64) {
        let Some(m) = m else { return };
        if m.time() > t {
            return; // from the future: ignore
        }
        if let Some(h) = self.humans.first_mut()
            && m.positions().len() == h.reach.model().keypoint_count()
        {
            h.take(m);
        }
    }

    /// One safety step at time `t` (s; must follow the previous step by α_s) with the newest
    /// measurement of every person ([`Shield::measure_human`]) and object. `measurement`, if
    /// given, is a measurement of person 0 taken now (the same as `measure_human(0, m)` before
    /// the step, except that one stamped after `t` is ignored). Returns the command for time
    /// t + α_s; before [`Shield::start`] there is no command to give
    /// ([`ShieldError::NotStarted`]).
    ///
    /// # Soundness
    /// Claim C8 (induction): the step is [`run_step`] on this shield; harness
    /// `f3_shield_step_induction` (Kani) proves its induction step, property test
    /// `f3_real_shield_commands_on_verified_failsafe` runs it with the real planner and
    /// verification.
    pub fn step(
        &mut self,
        t: f64,
        measurement: Option<&HumanMeasurement>,
    ) -> Result<Command, ShieldError> {
        run_step(self, t, measurement)
    }

    /// Whether the commanded joint velocity and acceleration are exactly zero (a chunk planned
    /// from the current state then stays valid until a step verifies the old path).
    pub fn at_rest(&self) -> bool {
        let st = self.state();
        st.dq[..self.dof]
            .iter()
            .chain(&st.ddq[..self.dof])
            .all(|&x| x == 0.0)
    }

    /// The go-profile (toward ṡ = 1 for one step) and the brake profile after it, both admissible.
    pub(super) fn candidate(
        &self,
        slot: usize,
        start: PathState,
    ) -> Option<(SpeedProfile, SpeedProfile)> {
        let tr = self.traj(slot);
        let alpha = self.config.safety_step;
        let go = if start.is_intended() {
            SpeedProfile::plan(start, 1.0, 0.0, 0.0)
        } else {
            admissible(tr, &self.hw, start, 1.0, Some(alpha))?
        };
        let after = go.eval(alpha);
        let brake = if after.sd == 0.0 && after.sdd == 0.0 {
            SpeedProfile::plan(after, 0.0, 0.0, 0.0)
        } else {
            admissible(tr, &self.hw, after, 0.0, None)?
        };
        Some((go, brake))
    }
}

/// What one shield step reads and changes: the state the induction is about. The rest of the
/// shield (models, trajectories, measurements, occupancy buffers) is reached through
/// [`StepEnv`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct StepState {
    /// Set by [`Shield::start`]; no command before.
    pub(super) started: bool,
    /// Time (s) of the next step (the commanded state's time).
    pub(super) time: f64,
    /// Slot of the trajectory the command follows.
    pub(super) slot: usize,
    /// Path state of the command on it at `time`.
    pub(super) path: PathState,
    /// Slot of a chunk planned from the current state, not yet tried by a step.
    pub(super) fresh: Option<usize>,
    /// The last verified failsafe (after `start`).
    pub(super) failsafe: Option<VerifiedFailsafe>,
    /// Whether the latest step adopted its candidate ([`Shield::last_verified`]).
    pub(super) last_verified: bool,
    /// What became of the latest offer.
    pub(super) offer_state: OfferState,
    /// Serial number of the chunk each slot holds (0: the start's standstill; the n-th
    /// accepted chunk is n).
    pub(super) chunk_serial: [u64; 2],
}

impl StepState {
    /// Install chunk number `serial` as the fresh chunk: in the slot the verified failsafe does
    /// not live on (so the failsafe's trajectory is never replaced), which is returned for its
    /// trajectory.
    pub(super) fn take_over_slot(&mut self, serial: u64) -> usize {
        let keep = self.failsafe.map(|f| f.slot).unwrap_or(self.slot);
        let slot = if keep == 0 { 1 } else { 0 };
        self.chunk_serial[slot] = serial;
        self.fresh = Some(slot);
        self.offer_state = OfferState::Taken(serial);
        slot
    }
}

/// The operations one step uses besides its [`StepState`]: implemented by [`Shield`] (the
/// models, planner and verification) and, in the Kani harness `f3_shield_step_induction`, by a
/// model whose operations return any result the shield's could.
pub(super) trait StepEnv {
    /// Person 0's measurement ([`HumanMeasurement`] in the shield).
    type Measurement;
    /// The step state.
    fn st(&mut self) -> &mut StepState;
    /// Safety step α_s (s).
    fn safety_step(&self) -> f64;
    /// PACS, OFF or single-action.
    fn mode(&self) -> FilterMode;
    /// Take person 0's measurement `m` if newer and not stamped after `t`.
    fn take_measurement(&mut self, m: Option<&Self::Measurement>, t: f64);
    /// Take a waiting offer over at its handover (it becomes the fresh chunk), or drop it.
    fn take_offer(&mut self, t: f64);
    /// Whether the commanded joint velocity and acceleration are exactly zero.
    fn at_rest(&self) -> bool;
    /// The go and brake profiles on `slot` from `start` ([`Shield::candidate`]).
    fn candidate(&self, slot: usize, start: PathState) -> Option<(SpeedProfile, SpeedProfile)>;
    /// Verify the monitored trajectory (go for α_s from `t`, then brake) on `slot`.
    fn verify(
        &mut self,
        slot: usize,
        go: &SpeedProfile,
        brake: &SpeedProfile,
        t: f64,
        diag: &mut Diagnostics,
    ) -> bool;
    /// The commanded joint state (of `st().path` on `st().slot`).
    fn command_state(&self) -> JointState;
    /// Degrees of freedom.
    fn dof(&self) -> usize;
}

impl StepEnv for Shield {
    type Measurement = HumanMeasurement;
    fn st(&mut self) -> &mut StepState {
        &mut self.st
    }
    fn safety_step(&self) -> f64 {
        self.config.safety_step
    }
    fn mode(&self) -> FilterMode {
        self.config.mode
    }
    fn take_measurement(&mut self, m: Option<&HumanMeasurement>, t: f64) {
        Shield::take_measurement(self, m, t);
    }
    fn take_offer(&mut self, t: f64) {
        Shield::take_offer(self, t);
    }
    fn at_rest(&self) -> bool {
        Shield::at_rest(self)
    }
    fn candidate(&self, slot: usize, start: PathState) -> Option<(SpeedProfile, SpeedProfile)> {
        Shield::candidate(self, slot, start)
    }
    fn verify(
        &mut self,
        slot: usize,
        go: &SpeedProfile,
        brake: &SpeedProfile,
        t: f64,
        diag: &mut Diagnostics,
    ) -> bool {
        Shield::verify(self, slot, go, brake, t, diag)
    }
    fn command_state(&self) -> JointState {
        self.state()
    }
    fn dof(&self) -> usize {
        self.dof
    }
}

/// One safety step (paper Algorithm 1) on `env` at time `t` with person 0's `measurement`: the
/// body of [`Shield::step`]. Take the newest measurement and a waiting offer; build the
/// candidate (a fresh chunk from its start, else the current path) and verify its monitored
/// trajectory; [`decide`] between it and the stored failsafe; record the fresh chunk's fate.
///
/// # Soundness
/// Claim C8: from any state of the induction invariant and any measurement, offer, candidate
/// and verdict, the command follows the stored failsafe's slot, the failsafe changes only to
/// the brake of a candidate whose last verification (against the newest measurement) returned
/// true, and is kept otherwise. Kani: `f3_shield_step_induction` (this function, with `decide`'s
/// `choose` and `SpeedProfile::eval` replaced by their verified contracts), in CI as its parts
/// `f3_step_kept`, `f3_adopt_pacs`, `f3_adopt_single_action` and `f3_adopt_off`; mutants `x67`,
/// `x68` caught.
pub(super) fn run_step<E: StepEnv>(
    env: &mut E,
    t: f64,
    measurement: Option<&E::Measurement>,
) -> Result<Command, ShieldError> {
    let (alpha, mode) = (env.safety_step(), env.mode());
    if !env.st().started {
        return Err(ShieldError::NotStarted);
    }
    env.take_measurement(measurement, t);
    env.take_offer(t);
    env.st().time = t;
    // Candidate: a fresh chunk starting at the current state, else the current path.
    let tried = env.st().fresh.take();
    let (cand_slot, cand_start, ramp) = match tried {
        Some(s) if env.at_rest() => {
            // At rest the robot is at the new trajectory's start q(0), where q̇ = q̈ = 0 as
            // well: it can take the intended timing at once (tried first), or adopt the new
            // path at path speed 0 (standing still is verified on either path) and
            // accelerate along it as fast as verification allows (if the intended timing
            // does not verify).
            env.st().slot = s;
            env.st().path = PathState::rest(0.0);
            (s, PathState::intended(0.0), true)
        }
        Some(s) => (s, PathState::intended(0.0), false),
        None => (env.st().slot, env.st().path, false),
    };
    let mut diag = Diagnostics::unbound(t);
    let mut outcome = env.candidate(cand_slot, cand_start).map(|(go, brake)| {
        let result = env.verify(cand_slot, &go, &brake, t, &mut diag);
        (go, brake, result)
    });
    if ramp && !outcome.is_some_and(|(_, _, ok)| ok) {
        outcome = env
            .candidate(cand_slot, PathState::rest(0.0))
            .map(|(go, brake)| {
                let result = env.verify(cand_slot, &go, &brake, t, &mut diag);
                (go, brake, result)
            });
    }
    if outcome.is_none() {
        diag.binding = Binding::NoProfile;
    }
    let stored = env
        .st()
        .failsafe
        .expect("a verified failsafe exists once started");
    let cand = outcome.map(|(go, brake, ok)| Candidate {
        slot: cand_slot,
        go,
        brake,
        verified: ok,
    });
    let next = decide(stored, cand, mode, t, alpha);
    env.st().slot = next.slot;
    env.st().path = next.path;
    env.st().failsafe = Some(next.failsafe);
    // Adopted: the candidate runs (verified; in OFF mode any candidate).
    let adopted = next.adopted;
    env.st().last_verified = adopted;
    if let Some(s) = tried {
        // The fresh chunk had its one try: record its fate for the caller that handed it in.
        let n = env.st().chunk_serial[s];
        if env.st().offer_state == OfferState::Taken(n) {
            env.st().offer_state = if adopted {
                OfferState::Followed(n)
            } else {
                OfferState::Dropped(n)
            };
        }
    }
    diag.on_failsafe = !adopted;
    diag.stop_time = next.failsafe.t0 + next.failsafe.profile.settle_time();
    // Verified and executed: in OFF mode a candidate runs whether or not it verified, and
    // the flag says which (a diagnostic that never claims a check that failed).
    diag.verified = adopted && cand.is_some_and(|c| c.verified);
    diag.path_speed = env.st().path.sd;
    env.st().time = t + alpha;
    Ok(Command {
        t: t + alpha,
        state: env.command_state(),
        dof: env.dof(),
        diag,
    })
}
