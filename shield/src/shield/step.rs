//! One safety step of the shield: the latest measurement, the candidate (go, then brake) and the
//! decision between it and the stored failsafe.

use super::{Binding, Candidate, Command, Diagnostics, OfferState, Shield, ShieldError, decide};
use pacs_motion::scaling::{PathState, SpeedProfile, admissible};
use pacs_reach::human::HumanMeasurement;

impl Shield {
    /// Replace the first human's latest measurement if `m` is newer (older or equal-time ones are
    /// ignored, as are ones from the future and ones for another model's keypoint count).
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
    pub fn step(
        &mut self,
        t: f64,
        measurement: Option<&HumanMeasurement>,
    ) -> Result<Command, ShieldError> {
        let alpha = self.config.safety_step;
        if !self.started {
            return Err(ShieldError::NotStarted);
        }
        self.take_measurement(measurement, t);
        self.take_offer(t);
        self.time = t;
        // Candidate: a fresh chunk starting at the current state, else the current path.
        let tried = self.fresh.take();
        let (cand_slot, cand_start, ramp) = match tried {
            Some(s) if self.at_rest() => {
                // At rest the robot is at the new trajectory's start q(0), where q̇ = q̈ = 0 as
                // well: it can take the intended timing at once (tried first), or adopt the new
                // path at path speed 0 (standing still is verified on either path) and
                // accelerate along it as fast as verification allows (if the intended timing
                // does not verify).
                self.slot = s;
                self.path = PathState::rest(0.0);
                (s, PathState::intended(0.0), true)
            }
            Some(s) => (s, PathState::intended(0.0), false),
            None => (self.slot, self.path, false),
        };
        let mut diag = Diagnostics {
            verified: false,
            on_failsafe: false,
            binding: Binding::None,
            min_separation: f64::INFINITY,
            contact_energy: 0.0,
            contact_threshold: 0.0,
            path_speed: 0.0,
            stop_time: t,
        };
        let mut outcome = self.candidate(cand_slot, cand_start).map(|(go, brake)| {
            let result = self.verify(cand_slot, &go, &brake, t, &mut diag);
            (go, brake, result)
        });
        if ramp && !outcome.is_some_and(|(_, _, ok)| ok) {
            outcome = self
                .candidate(cand_slot, PathState::rest(0.0))
                .map(|(go, brake)| {
                    let result = self.verify(cand_slot, &go, &brake, t, &mut diag);
                    (go, brake, result)
                });
        }
        if outcome.is_none() {
            diag.binding = Binding::NoProfile;
        }
        let stored = self
            .failsafe
            .expect("a verified failsafe exists once started");
        let cand = outcome.map(|(go, brake, ok)| Candidate {
            slot: cand_slot,
            go,
            brake,
            verified: ok,
        });
        let next = decide(stored, cand, self.config.mode, t, alpha);
        self.slot = next.slot;
        self.path = next.path;
        self.failsafe = Some(next.failsafe);
        // Adopted: the candidate runs (verified; in OFF mode any candidate).
        let adopted = next.adopted;
        self.last_verified = adopted;
        if let Some(s) = tried {
            // The fresh chunk had its one try: record its fate for the caller that handed it in.
            let n = self.chunk_serial[s];
            if self.offer_state == OfferState::Taken(n) {
                self.offer_state = if adopted {
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
        diag.path_speed = self.path.sd;
        self.time = t + alpha;
        Ok(Command {
            t: t + alpha,
            state: self.state(),
            dof: self.dof,
            diag,
        })
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
