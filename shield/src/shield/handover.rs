//! Chunks planned off the control loop: the shield predicts where its commands will be a few
//! safety steps ahead ([`Shield::handover`]), a [`ChunkPlanner`] plans the chunk from that state
//! on another thread (no lock on the shield), and [`Shield::offer`] hands the plan back. The
//! step takes the plan over only if the commanded state at the handover is *bitwise* the state
//! it was planned from — exactly the invariant of [`Shield::set_chunk`] (a fresh trajectory
//! starts at the current commanded state), so the safety argument (C8) is the same: the fresh
//! trajectory still runs only once one of its monitored steps is verified. If the commands went
//! elsewhere (a step was not verified, another chunk came first), the plan is dropped
//! ([`OfferState::Stale`]) and the caller plans again from a new handover.
//!
//! Planning a chunk (the spline's passes) takes too long to fit in a 1 ms step beside the
//! verification (measured in `docs/performance.md#chunk-planning-time`); a 1 kHz loop that
//! planned in its own step would miss its deadline. With this split the loop's share is a comparison of two joint
//! states and a move of the trajectory into a slot (no allocation: the trajectory it replaces
//! is kept until the next [`Shield::offer`], which drops it outside the step).

use super::{Candidate, FilterMode, Shield, ShieldError, decide};
use pacs_models::JointLimits;
use pacs_motion::chunk::{Chunk, OutOfLimits};
use pacs_motion::intended::Planner;
use pacs_motion::scaling::PathState;
use pacs_motion::trajectory::{JointState, Trajectory};

/// Where and when a chunk planned off the loop takes over: the commanded state the shield
/// predicts at its step at time `t`, provided every step until then is verified.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Handover {
    /// Time (s) of the step at which the plan can take over.
    pub t: f64,
    /// The commanded joint state at `t` if every step until then is verified.
    pub start: JointState,
}

/// Plans chunks for a shield without holding it: a copy of the shield's planner, the robot's
/// joint limits and the chunk settings ([`Shield::chunk_planner`]). One implementation serves
/// [`Shield::set_chunk`] (planning from the current state) and [`Shield::offer`] (planning from
/// a [`Handover`]).
#[derive(Clone)]
pub struct ChunkPlanner {
    planner: Planner,
    /// The same planner with the robot's acceleration and jerk limits: tried when a chunk
    /// cannot be planned from a moving start (typically a start braking harder than the
    /// intended limits allow).
    recovery: Planner,
    limits: JointLimits,
    out_of_limits: OutOfLimits,
    mode: FilterMode,
}

/// A chunk's intended trajectory planned from a [`Handover`], ready for [`Shield::offer`].
#[derive(Clone)]
pub struct PreparedChunk {
    handover: Handover,
    traj: Trajectory,
}

impl PreparedChunk {
    /// The handover it was planned from.
    pub fn handover(&self) -> &Handover {
        &self.handover
    }

    /// The planned intended trajectory (starts at `handover().start`).
    pub fn trajectory(&self) -> &Trajectory {
        &self.traj
    }
}

/// What became of the latest chunk offered ([`Shield::offer`]) or set ([`Shield::set_chunk`])
/// ([`Shield::offer_state`]). The shield records it where it decides it, so that callers
/// (a [`crate::worker::ChunkWorker`], the Python `ShieldLoop`) need not infer it from the
/// commands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OfferState {
    /// No chunk offered yet.
    None,
    /// Waiting for the step at its handover time.
    Waiting,
    /// Taken over as the shield's fresh chunk, with this serial number (see
    /// [`super::ChunkProgress::chunk`]): the next step tries its first monitored step.
    Taken(u64),
    /// Taken over, and the step that tried it verified its first monitored step: the commands
    /// follow it (until a newer chunk takes over).
    Followed(u64),
    /// Taken over, but the step that tried it did not verify its first monitored step: the
    /// shield dropped it and the commands kept their verified path or failsafe.
    Dropped(u64),
    /// Dropped before it was taken over: at its handover the commanded state was not the
    /// planned start (plan it again from a newer handover).
    Stale,
}

impl ChunkPlanner {
    pub(super) fn new(
        planner: Planner,
        recovery: Planner,
        limits: JointLimits,
        out_of_limits: OutOfLimits,
        mode: FilterMode,
    ) -> Self {
        Self {
            planner,
            recovery,
            limits,
            out_of_limits,
            mode,
        }
    }

    /// The chunk's intended trajectory from `start` (the chunk's deltas are integrated from
    /// `start.q`, as in the paper); single-action mode plans to rest after the first action.
    ///
    /// The intended limits keep a braking reserve (acceleration `intended_acc_fraction` of the
    /// robot's, jerk at most `intended_jerk`). A start the failsafe is braking from may lie
    /// beyond them; if the chunk cannot be planned from a moving start within the intended
    /// limits, it is planned within the robot's acceleration and jerk limits (velocity still
    /// intended). Safety does not rest on the reserve: a trajectory along which the failsafe
    /// cannot brake admissibly is simply not verified, and the robot keeps braking.
    pub fn plan(&mut self, start: &JointState, chunk: &Chunk) -> Result<Trajectory, ShieldError> {
        let n = self.limits.dof();
        let wp = chunk.waypoints(&start.q[..n], &self.limits, self.out_of_limits)?;
        let single = self.mode == FilterMode::SingleAction;
        let plan = |p: &mut Planner| {
            if single {
                p.plan_single_action(start, &wp)
            } else {
                p.plan(start, &wp)
            }
        };
        match plan(&mut self.planner) {
            Ok(t) => Ok(t),
            Err(e) => {
                if !start.is_at_rest(n)
                    && let Ok(t) = plan(&mut self.recovery)
                {
                    return Ok(t);
                }
                Err(e.into())
            }
        }
    }

    /// Plan `chunk` from a handover (off the control loop; hand the result to
    /// [`Shield::offer`]).
    pub fn prepare(
        &mut self,
        handover: &Handover,
        chunk: &Chunk,
    ) -> Result<PreparedChunk, ShieldError> {
        let traj = self.plan(&handover.start, chunk)?;
        Ok(PreparedChunk {
            handover: *handover,
            traj,
        })
    }
}

/// Bitwise equality of the first `dof` joint values of position, velocity and acceleration
/// (`-0.0` and `0.0` are equal; the states come from the same evaluation, so a state the
/// prediction reached is reproduced exactly).
fn same_state(a: &JointState, b: &JointState, dof: usize) -> bool {
    a.q[..dof] == b.q[..dof] && a.dq[..dof] == b.dq[..dof] && a.ddq[..dof] == b.ddq[..dof]
}

impl Shield {
    /// A planner for this shield's chunks that works without the shield (clone it onto the
    /// thread that plans).
    pub fn chunk_planner(&self) -> ChunkPlanner {
        self.chunks.clone()
    }

    /// The handover `lead` safety steps ahead: the step time `time() + lead·α_s` and the
    /// commanded state there if every step until then verifies its candidate (the current path,
    /// or a fresh chunk not yet taken over; where no candidate exists the step follows the
    /// failsafe, and so does the prediction). `lead = 0` is the current commanded state. The
    /// prediction runs the step's own candidate and decision code, so a state it reaches is
    /// reproduced bitwise by the steps. `None` before [`Shield::start`].
    pub fn handover(&self, lead: usize) -> Option<Handover> {
        self.predict(lead, true)
    }

    /// The handover `lead` safety steps ahead if *no* step until then is verified: the commands
    /// follow the verified failsafe (braking along the path; at rest they stay). The better
    /// prediction while a person keeps the steps from verifying (a [`crate::worker::ChunkWorker`]
    /// takes it after an unverified step): a plan from it is taken over at once where the arm
    /// rests, and at the handover while it brakes. `None` before [`Shield::start`].
    pub fn handover_on_failsafe(&self, lead: usize) -> Option<Handover> {
        self.predict(lead, false)
    }

    /// The handover `lead` steps ahead if the next steps go as the latest one did: verified →
    /// [`Self::handover`] (along the path), not verified → [`Self::handover_on_failsafe`]. The
    /// prediction [`crate::worker::ChunkWorker`] and the Python `ShieldLoop` plan from. `None`
    /// before [`Shield::start`].
    pub fn likely_handover(&self, lead: usize) -> Option<Handover> {
        if self.st.last_verified {
            self.handover(lead)
        } else {
            self.handover_on_failsafe(lead)
        }
    }

    /// Whether the latest step verified its candidate (`true` before the first step: the start
    /// at rest is verified).
    pub fn last_verified(&self) -> bool {
        self.st.last_verified
    }

    fn predict(&self, lead: usize, verified: bool) -> Option<Handover> {
        if !self.st.started {
            return None;
        }
        let alpha = self.config.safety_step;
        let (mut slot, mut path) = (self.st.slot, self.st.path);
        let mut failsafe = self.st.failsafe?;
        if lead > 0
            && let Some(s) = self.st.fresh
        {
            (slot, path) = (s, PathState::intended(0.0));
        }
        if !verified {
            // No candidate is chosen: every step follows the stored failsafe, and the last one
            // (at `time + (lead − 1)·α`) evaluates it once — O(1) for any lead.
            if lead > 0 {
                let t = self.st.time + (lead - 1) as f64 * alpha;
                let next = decide(failsafe, None, self.config.mode, t, alpha);
                (slot, path) = (next.slot, next.path);
            }
        } else {
            for k in 0..lead {
                let t = self.st.time + k as f64 * alpha;
                // The step's own decision, with the candidate (where one exists) verified.
                let cand = self.candidate(slot, path).map(|(go, brake)| Candidate {
                    slot,
                    go,
                    brake,
                    verified: true,
                });
                let next = decide(failsafe, cand, self.config.mode, t, alpha);
                (slot, path, failsafe) = (next.slot, next.path, next.failsafe);
            }
        }
        Some(Handover {
            t: self.st.time + lead as f64 * alpha,
            start: self.joint_state(slot, &path),
        })
    }

    /// Offer a chunk planned off the loop. Taken over (as if [`Shield::set_chunk`] had been
    /// called then) by the first step whose commanded state before it is bitwise
    /// `chunk.handover().start` — at its handover time, or at once if the robot already stands
    /// there; dropped ([`OfferState::Stale`]) if the step at the handover time finds another
    /// state. A newer offer replaces a waiting one. Errors: the handover is already past
    /// (the shield's time is beyond it and the state differs) — plan again from a newer one.
    pub fn offer(&mut self, chunk: PreparedChunk) -> Result<(), ShieldError> {
        if !self.st.started {
            return Err(ShieldError::NotStarted);
        }
        // Trajectories replaced in earlier steps are dropped here, outside the step.
        self.spare = None;
        let tol = super::time_tolerance(self.st.time);
        if same_state(&self.state(), &chunk.handover.start, self.dof) {
            self.take_over(chunk.traj);
            self.pending = None;
            return Ok(());
        }
        if chunk.handover.t < self.st.time - tol {
            self.st.offer_state = OfferState::Stale;
            return Err(ShieldError::Stale {
                handover: chunk.handover.t,
                time: self.st.time,
            });
        }
        self.pending = Some(chunk);
        self.st.offer_state = OfferState::Waiting;
        Ok(())
    }

    /// What became of the latest offered chunk.
    pub fn offer_state(&self) -> OfferState {
        self.st.offer_state
    }

    /// Withdraw a waiting offer (its caller gave up on it): no later step takes it over.
    /// Returns whether one was waiting.
    pub fn withdraw_offer(&mut self) -> bool {
        let waiting = self.pending.take().is_some();
        if waiting {
            self.st.offer_state = OfferState::Stale;
        }
        waiting
    }

    /// At the start of the step at `t`: take a waiting offer over if the commanded state is its
    /// planned start, drop it if its handover time has come and the state differs. Allocation
    /// free (a dropped or replaced trajectory waits in `spare`).
    pub(super) fn take_offer(&mut self, t: f64) {
        let Some(p) = &self.pending else { return };
        let tol = super::time_tolerance(t);
        if same_state(&self.state(), &p.handover.start, self.dof) {
            let p = self.pending.take().expect("checked above");
            self.take_over(p.traj);
        } else if t >= p.handover.t - tol {
            self.spare = self.pending.take().map(|p| p.traj);
            self.st.offer_state = OfferState::Stale;
        }
    }

    /// Install `traj` (planned from the current commanded state) as the fresh chunk in the slot
    /// the verified failsafe does not live on; the trajectory it replaces waits in `spare`.
    pub(super) fn take_over(&mut self, traj: Trajectory) {
        self.chunks_accepted += 1;
        let slot = self.st.take_over_slot(self.chunks_accepted);
        self.spare = self.trajs[slot].replace(traj);
    }
}
