//! The PACS online safety shield (paper Algorithm 1) and its OFF and single-action variants.
//!
//! Every safety step α_s the shield builds a **monitored trajectory** from the robot's current
//! commanded state: one step of intended motion (ṡ → 1 along the current path; exactly the
//! intended timing when already on it), then a **failsafe** braking along the same path
//! (ṡ → 0; [`pacs_motion::scaling`]). It encloses the robot over a sequence of time intervals covering
//! the monitored trajectory until standstill (joint boxes from sound path bounds →
//! [`RobotReach`] capsules) and the human over the same intervals from the latest measurement
//! (its age, delay and errors included → [`HumanReach`]), then applies the one ISO/TS 15066 rule
//! ([`pacs_verify::iso15066::ContactRule`], shared with the audit) to every interval: SSM (no contact
//! possible while the robot may move) and PFL (wherever contact is possible, a sound upper bound
//! of the whole robot's kinetic energy over the interval's position and velocity boxes, widened
//! by the controller's velocity tracking error, is at most the body part's threshold — the
//! constrained one if the part may be pinched).
//!
//! Verified → execute the intended step and remember this failsafe. Not verified → continue the
//! last verified failsafe. By induction the robot is always on a verified monitored trajectory;
//! it starts at rest. No valid measurement, an unplannable chunk or an unverifiable candidate only
//! ever lead to following the last verified failsafe. The step allocates nothing.

// Joint-indexed loops over parallel fixed-size arrays read clearer than zipped iterators.
#![allow(clippy::needless_range_loop)]

use pacs_models::{Capsule, ConstraintSpec, HumanModel, MAX_DOF, RobotModel};
use pacs_motion::chunk::{Chunk, OutOfLimits};
use pacs_motion::intended::{PlanMethod, Planner, PlannerConfig};
use pacs_motion::scaling::{PathState, SpeedProfile, admissible};
use pacs_motion::trajectory::{EndCondition, JointState, Limits, Trajectory};
use pacs_reach::JointBox;
use pacs_reach::human::{HumanMeasurement, HumanReach, HumanReachModel};
use pacs_reach::robot::{ReachScratch, RobotReach};
use pacs_verify::iso15066::{ConstraintKind, ContactRule};
use serde::{Deserialize, Serialize};
use std::ops::ControlFlow;
use thiserror::Error;

/// Which filter runs behind the shield interface.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum FilterMode {
    /// PACS: verify every step, brake along the path when needed.
    #[default]
    Pacs,
    /// OFF: follow the intended trajectory, never brake (diagnostics are still computed).
    Off,
    /// PACS planning each action as its own stop-at-target motion (the paper's single-action
    /// baseline), verified like PACS.
    SingleAction,
}

/// Shield settings (units: s, m, rad/s², rad/s³).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShieldConfig {
    /// Safety step α_s (s).
    pub safety_step: f64,
    /// Cartesian tracking error of the low-level controller (m), added to every robot capsule.
    pub tracking_error: f64,
    /// Joint velocity tracking error of the low-level controller (rad/s, per joint): added to
    /// the commanded velocity bounds in every PFL energy bound (the robot's real kinetic energy
    /// comes from its real velocities).
    pub velocity_tracking_error: f64,
    /// Human reachability model.
    pub human_model: HumanReachModel,
    /// Acceleration limit of intended trajectories as a fraction of the robot's (0, 1): the rest
    /// is the braking reserve the failsafe needs when the intended motion is at its limit.
    pub intended_acc_fraction: f64,
    /// Jerk limit of intended trajectories (rad/s³; the paper uses 400), capped by the robot's.
    pub intended_jerk: f64,
    /// Velocity limit scale of intended trajectories, in (0, 1].
    pub intended_vel_scale: f64,
    /// PACS, OFF or single-action.
    pub mode: FilterMode,
    /// Waypoints outside the position limits: reject the chunk or project them.
    pub out_of_limits: OutOfLimits,
    /// Length of the first occupancy interval after the intended step (s); each next one doubles.
    pub first_interval: f64,
    /// Maximum number of occupancy intervals (the last one extends to standstill).
    pub max_intervals: usize,
    /// SSM: the commanded robot is at rest on an interval if every commanded joint speed is
    /// provably at most this (rad/s). Default 0: only a stopped path counts as rest (the audit's
    /// default of 0.02 rad/s covers the controller's velocity tracking error on a real robot).
    pub rest_speed: f64,
}

impl Default for ShieldConfig {
    fn default() -> Self {
        Self {
            safety_step: 0.001,
            tracking_error: 0.005,
            velocity_tracking_error: 0.004,
            human_model: HumanReachModel::Combined,
            intended_acc_fraction: 0.8,
            intended_jerk: 400.0,
            intended_vel_scale: 1.0,
            mode: FilterMode::Pacs,
            out_of_limits: OutOfLimits::Reject,
            first_interval: 0.002,
            max_intervals: 12,
            rest_speed: 0.0,
        }
    }
}

pub use pacs_verify::iso15066::EnvShape;

/// Errors of shield construction and chunk handling.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ShieldError {
    /// Invalid configuration or model (names the field and value).
    #[error("{0}")]
    Invalid(String),
    /// The shield must be started (at rest) first.
    #[error("shield not started: call start(t, q) with the robot at rest")]
    NotStarted,
    /// The chunk could not be planned; it is ignored and the robot keeps its verified motion.
    #[error("chunk ignored: {0}")]
    Chunk(#[from] pacs_motion::error::TrajectoryError),
}

/// What decided a step.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum Binding {
    /// Nothing bound: the intended step was verified.
    None,
    /// No valid human measurement yet.
    NoMeasurement,
    /// No admissible path-speed profile (limits leave no margin).
    NoProfile,
    /// SSM: contact possible while moving.
    Ssm {
        /// Robot link index.
        link: usize,
        /// Body part index.
        body_part: usize,
        /// Occupancy interval index.
        interval: usize,
    },
    /// CBF baseline: barrier constraints were active this step.
    Barrier {
        /// Number of active barrier rows.
        active: usize,
    },
    /// PFL: energy bound above the threshold where contact is possible.
    Pfl {
        /// Robot link index.
        link: usize,
        /// Body part index.
        body_part: usize,
        /// Energy upper bound (J).
        energy: f64,
        /// Threshold (J).
        threshold: f64,
        /// Constrained (clamping) contact.
        constrained: bool,
    },
}

/// Per-step diagnostics.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Diagnostics {
    /// The intended step was verified (and executed).
    pub verified: bool,
    /// The robot follows a failsafe (braking) this step.
    pub on_failsafe: bool,
    /// What decided the step.
    pub binding: Binding,
    /// Lower bound of the separation between robot and human occupancies over the first interval
    /// (m; +∞ without human).
    pub min_separation: f64,
    /// Largest energy bound where contact was possible (J; 0 if none).
    pub contact_energy: f64,
    /// Threshold belonging to `contact_energy` (J).
    pub contact_threshold: f64,
    /// Path speed ṡ after the step (1 = intended timing, 0 = stopped).
    pub path_speed: f64,
    /// Time (s) at which the monitored trajectory reaches standstill.
    pub stop_time: f64,
}

/// The command for the low-level controller at time `t`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Command {
    /// Time the command is for (s).
    pub t: f64,
    /// Joint state (entries beyond dof are 0).
    pub state: JointState,
    /// Number of joints carrying targets in `state` (the robot's).
    pub dof: usize,
    /// Diagnostics.
    pub diag: Diagnostics,
}

/// The last verified failsafe: braking profile `profile` on trajectory slot `slot`, started at
/// absolute time `t0`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VerifiedFailsafe {
    /// Trajectory slot the failsafe lives on.
    pub slot: usize,
    /// Braking path-speed profile (ṡ → 0).
    pub profile: SpeedProfile,
    /// Absolute time of the profile start.
    pub t0: f64,
}

/// A candidate of one shield step: the go-profile for α_s, then `brake`, on `slot`, and whether
/// the monitored trajectory was verified.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Candidate {
    /// Trajectory slot of the candidate.
    pub slot: usize,
    /// Intended step (ṡ → 1) for α_s.
    pub go: SpeedProfile,
    /// Failsafe after the step (ṡ → 0).
    pub brake: SpeedProfile,
    /// The monitored trajectory (go, then brake) was verified.
    pub verified: bool,
}

/// The outcome of [`decide`]: the executed slot and path state at `t + α_s` and the (possibly
/// new) last verified failsafe.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Decision {
    /// Slot of the executed command.
    pub slot: usize,
    /// Executed path state at `t + α_s`.
    pub path: PathState,
    /// The last verified failsafe after this step.
    pub failsafe: VerifiedFailsafe,
    /// The candidate was adopted (verified, or OFF mode).
    pub adopted: bool,
}

/// The pure decision of one shield step (paper Algorithm 1), as used by [`Shield::step`]: a
/// verified candidate (or any candidate in OFF mode) is executed for α_s and its brake profile
/// becomes the stored failsafe (starting at `t + α_s`); otherwise (no candidate, or not verified)
/// the stored failsafe is continued to `t + α_s`.
///
/// # Soundness
/// Claim C8 (induction): the robot is always on a verified monitored trajectory; the stored
/// failsafe changes only on a verified candidate. Harness `f1_shield_decision_induction`, property
/// test `f3_real_shield_commands_on_verified_failsafe`; mutant `x2` caught.
pub fn decide(
    stored: VerifiedFailsafe,
    candidate: Option<Candidate>,
    mode: FilterMode,
    t: f64,
    alpha: f64,
) -> Decision {
    match candidate {
        Some(c) if c.verified || mode == FilterMode::Off => Decision {
            slot: c.slot,
            path: c.go.eval(alpha),
            failsafe: VerifiedFailsafe {
                slot: c.slot,
                profile: c.brake,
                t0: t + alpha,
            },
            adopted: true,
        },
        _ => Decision {
            slot: stored.slot,
            path: stored.profile.eval(t + alpha - stored.t0),
            failsafe: stored,
            adopted: false,
        },
    }
}

/// The occupancy time intervals of a monitored trajectory, as used by the shield's verification:
/// items `(k, t_a, t_b)` relative to the step start: `[0, α_s]` (k = 0), then durations
/// `first·2^(k−1)` until `stop`, the interval `max_intervals − 1` extending to `stop`. For finite
/// `0 < α_s ≤ stop`, `first > 0`, the intervals are contiguous and cover `[0, stop]`.
///
/// # Soundness
/// Claim C7: a step is verified only if every interval of the whole monitored trajectory passed,
/// and these intervals cover it. Harness `f2_occupancy_intervals_cover`; mutant `m4` caught.
#[derive(Debug, Clone, Copy)]
pub struct OccupancyIntervals {
    alpha: f64,
    stop: f64,
    max: usize,
    ta: f64,
    k: usize,
    dur: f64,
    done: bool,
}

impl OccupancyIntervals {
    /// Intervals for step `alpha`, standstill at `stop`, first duration `first`, at most `max`.
    pub fn new(alpha: f64, stop: f64, first: f64, max: usize) -> Self {
        Self {
            alpha,
            stop,
            max,
            ta: 0.0,
            k: 0,
            dur: first,
            done: false,
        }
    }
}

impl Iterator for OccupancyIntervals {
    type Item = (usize, f64, f64);
    fn next(&mut self) -> Option<(usize, f64, f64)> {
        if self.done || !(self.ta < self.stop || self.k == 0) {
            return None;
        }
        let (k, ta, stop) = (self.k, self.ta, self.stop);
        let tb = if k == 0 {
            self.alpha.min(stop.max(self.alpha))
        } else if k + 1 >= self.max {
            stop
        } else {
            (ta + self.dur).min(stop)
        };
        if k > 0 {
            self.dur *= 2.0;
        }
        self.k += 1;
        self.ta = tb;
        if tb >= stop {
            self.done = true;
        }
        Some((k, ta, tb))
    }
}

/// The PACS shield (also OFF and single-action, by configuration).
pub struct Shield {
    robot: RobotModel,
    dof: usize,
    hw: Limits,
    planner: Planner,
    reach: RobotReach,
    /// The human's reachability and the ISO/TS 15066 rule for its body parts.
    human: Option<(HumanReach, ContactRule)>,
    config: ShieldConfig,
    trajs: [Option<Trajectory>; 2],
    /// Current slot and path state at `time`.
    slot: usize,
    path: PathState,
    time: f64,
    started: bool,
    /// Slot of a chunk planned from the current state (not yet verified).
    fresh: Option<usize>,
    failsafe: Option<VerifiedFailsafe>,
    /// Latest measurement (buffer allocated at construction; valid when `has_meas`).
    meas: Option<HumanMeasurement>,
    has_meas: bool,
    // Scratch buffers (allocated once).
    robot_caps: Vec<Capsule>,
    human_caps: Vec<Capsule>,
    energies: Vec<f64>,
    scratch: ReachScratch,
}

impl std::fmt::Debug for Shield {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Shield")
            .field("config", &self.config)
            .field("time", &self.time)
            .finish()
    }
}

impl Shield {
    /// Build a shield for a robot, an optional human with a task constraint spec, and static
    /// environment shapes.
    pub fn new(
        robot: RobotModel,
        human: Option<(HumanModel, &ConstraintSpec)>,
        env: Vec<EnvShape>,
        config: ShieldConfig,
    ) -> Result<Self, ShieldError> {
        let c = &config;
        let bad = |f: &str, v: f64| {
            ShieldError::Invalid(format!("shield config `{f}`: invalid value {v}"))
        };
        if !(c.safety_step > 0.0 && c.safety_step.is_finite()) {
            return Err(bad("safety_step", c.safety_step));
        }
        if !(c.velocity_tracking_error >= 0.0 && c.velocity_tracking_error.is_finite()) {
            return Err(bad("velocity_tracking_error", c.velocity_tracking_error));
        }
        if !(c.tracking_error >= 0.0 && c.tracking_error.is_finite()) {
            return Err(bad("tracking_error", c.tracking_error));
        }
        if !(c.intended_acc_fraction > 0.0 && c.intended_acc_fraction < 1.0) {
            return Err(bad(
                "intended_acc_fraction (must be in (0, 1): braking reserve)",
                c.intended_acc_fraction,
            ));
        }
        if !(c.intended_jerk > 0.0 && c.intended_jerk.is_finite()) {
            return Err(bad("intended_jerk", c.intended_jerk));
        }
        if !(c.intended_vel_scale > 0.0 && c.intended_vel_scale <= 1.0) {
            return Err(bad("intended_vel_scale", c.intended_vel_scale));
        }
        if !(c.first_interval > 0.0 && c.first_interval.is_finite()) || c.max_intervals < 1 {
            return Err(bad("first_interval/max_intervals", c.first_interval));
        }
        let dof = robot.dof();
        let hw = Limits::from_joint_limits(robot.limits());
        let mut plan = hw;
        for i in 0..dof {
            plan.v[i] *= c.intended_vel_scale;
            plan.a[i] *= c.intended_acc_fraction;
            plan.j[i] = plan.j[i].min(c.intended_jerk);
        }
        let planner = Planner::new(
            plan,
            PlannerConfig {
                end: EndCondition::AtRest,
                // The per-segment planner: the spline's time-optimal trajectories use the
                // acceleration limit from the first piece on, which leaves the shield's ramp-up
                // from rest along a fresh path fewer verifiable steps (tests/shield.rs).
                method: PlanMethod::Segments,
                ..PlannerConfig::default()
            },
        );
        let reach = RobotReach::try_new(&robot, c.tracking_error)
            .map_err(|e| ShieldError::Invalid(e.to_string()))?;
        let mut meas_buffer = None;
        let human = match human {
            None => None,
            Some((h, spec)) => {
                let tc = spec
                    .resolve(&h)
                    .map_err(|e| ShieldError::Invalid(format!("constraints: {e}")))?;
                tc.check_robot(&robot)
                    .map_err(|e| ShieldError::Invalid(e.to_string()))?;
                let zeros = vec![[0.0; 3]; h.keypoint_count()];
                meas_buffer = Some(
                    HumanMeasurement::new(&h, 0.0, &zeros, Some(&zeros))
                        .map_err(|e| ShieldError::Invalid(e.to_string()))?,
                );
                let rule = ContactRule::new(&robot, &reach, &h, &tc.per_part, env, c.rest_speed)
                    .map_err(|e| ShieldError::Invalid(e.to_string()))?;
                Some((HumanReach::new(h, c.human_model), rule))
            }
        };
        let parts = human
            .as_ref()
            .map_or(0, |(h, _)| h.model().body_parts().len());
        Ok(Self {
            dof,
            hw,
            planner,
            robot_caps: vec![
                Capsule::new_unchecked(Default::default(), Default::default(), 0.0);
                reach.capsule_count()
            ],
            human_caps: vec![
                Capsule::new_unchecked(Default::default(), Default::default(), 0.0);
                parts
            ],
            energies: vec![0.0; dof + 1],
            scratch: ReachScratch::default(),
            reach,
            human,
            config,
            robot,
            trajs: [None, None],
            slot: 0,
            path: PathState::rest(0.0),
            time: 0.0,
            started: false,
            fresh: None,
            failsafe: None,
            meas: meas_buffer,
            has_meas: false,
        })
    }

    /// The robot model.
    pub fn robot(&self) -> &RobotModel {
        &self.robot
    }
    /// The configuration.
    pub fn config(&self) -> &ShieldConfig {
        &self.config
    }
    /// The human model, if any.
    pub fn human_model(&self) -> Option<&HumanModel> {
        self.human.as_ref().map(|(h, _)| h.model())
    }

    /// Start at rest at `q` (rad) at time `t` (s). The shield only starts from rest.
    pub fn start(&mut self, t: f64, q: &[f64]) -> Result<(), ShieldError> {
        if q.len() != self.dof || q.iter().any(|x| !x.is_finite()) || !t.is_finite() {
            return Err(ShieldError::Invalid(format!(
                "start: need {} finite joint values and a finite time",
                self.dof
            )));
        }
        if !self.robot.limits().contains(q) {
            return Err(ShieldError::Invalid(
                "start: configuration outside the joint position limits".into(),
            ));
        }
        self.trajs = [Some(Trajectory::standstill(q)), None];
        self.slot = 0;
        self.path = PathState::rest(0.0);
        self.time = t;
        self.started = true;
        self.fresh = None;
        // Standing still is the first verified failsafe.
        self.failsafe = Some(VerifiedFailsafe {
            slot: 0,
            profile: SpeedProfile::plan(self.path, 0.0, 1.0, 1.0),
            t0: t,
        });
        Ok(())
    }

    fn traj(&self, slot: usize) -> &Trajectory {
        self.trajs[slot].as_ref().expect("slot holds a trajectory")
    }

    /// The last verified failsafe (after `start`).
    pub fn verified_failsafe(&self) -> Option<VerifiedFailsafe> {
        self.failsafe
    }

    /// The joint state of the last verified failsafe at absolute time `t` (after `start`).
    pub fn failsafe_state_at(&self, t: f64) -> Option<JointState> {
        let f = self.failsafe?;
        self.trajs[f.slot].as_ref()?;
        Some(self.joint_state(f.slot, &f.profile.eval(t - f.t0)))
    }

    /// Current commanded joint state.
    pub fn state(&self) -> JointState {
        self.joint_state(self.slot, &self.path)
    }

    fn joint_state(&self, slot: usize, p: &PathState) -> JointState {
        p.joint_state(self.traj(slot))
    }

    /// Hand a new action chunk to the shield: planned from the current commanded state into a new
    /// intended trajectory, which takes over as soon as one of its steps is verified. A chunk that
    /// cannot be planned is ignored (error returned; the robot keeps its verified motion).
    pub fn set_chunk(&mut self, chunk: &Chunk) -> Result<(), ShieldError> {
        if !self.started {
            return Err(ShieldError::NotStarted);
        }
        let start = self.state();
        let wp = chunk.waypoints(
            &start.q[..self.dof],
            self.robot.limits(),
            self.config.out_of_limits,
        )?;
        let traj = if self.config.mode == FilterMode::SingleAction {
            self.planner.plan_single_action(&start, &wp)?
        } else {
            self.planner.plan(&start, &wp)?
        };
        // Use the slot the verified failsafe does not live on.
        let keep = self.failsafe.map(|f| f.slot).unwrap_or(self.slot);
        let slot = if keep == 0 { 1 } else { 0 };
        self.trajs[slot] = Some(traj);
        self.fresh = Some(slot);
        Ok(())
    }

    /// Replace the latest human measurement if `m` is newer (older or equal-time ones are ignored).
    fn take_measurement(&mut self, m: Option<&HumanMeasurement>, t: f64) {
        let Some(m) = m else { return };
        if m.time() > t {
            return; // from the future: ignore
        }
        match &mut self.meas {
            Some(cur) if self.has_meas && cur.time() >= m.time() => {}
            Some(cur) => {
                cur.assign_from(m);
                self.has_meas = true;
            }
            None => {}
        }
    }

    /// One safety step at time `t` (s; must follow the previous step by α_s) with the latest
    /// human measurement, if any. Returns the command for time t + α_s; before
    /// [`Shield::start`] there is no command to give ([`ShieldError::NotStarted`]).
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
        self.time = t;
        // Candidate: a fresh chunk starting at the current state, else the current path.
        let (cand_slot, cand_start) = match self.fresh.take() {
            Some(s) if self.at_rest() => {
                // At rest the robot is at the new trajectory's start q(0), where q′ = 0: it can
                // adopt the new path at path speed 0 (standing still is verified on either path)
                // and accelerate along it as fast as verification allows.
                self.slot = s;
                self.path = PathState::rest(0.0);
                (s, PathState::rest(0.0))
            }
            Some(s) => (s, PathState::intended(0.0)),
            None => (self.slot, self.path),
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
        let outcome = self.candidate(cand_slot, cand_start).map(|(go, brake)| {
            let result = self.verify(cand_slot, &go, &brake, t, &mut diag);
            (go, brake, result)
        });
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
        let verified = next.adopted;
        diag.on_failsafe = !verified;
        diag.stop_time = next.failsafe.t0 + next.failsafe.profile.settle_time();
        diag.verified = verified;
        diag.path_speed = self.path.sd;
        self.time = t + alpha;
        Ok(Command {
            t: t + alpha,
            state: self.state(),
            dof: self.dof,
            diag,
        })
    }

    /// Whether the commanded joint velocity and acceleration are exactly zero.
    fn at_rest(&self) -> bool {
        let st = self.state();
        st.dq[..self.dof]
            .iter()
            .chain(&st.ddq[..self.dof])
            .all(|&x| x == 0.0)
    }

    /// The go-profile (toward ṡ = 1 for one step) and the brake profile after it, both admissible.
    fn candidate(&self, slot: usize, start: PathState) -> Option<(SpeedProfile, SpeedProfile)> {
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

    /// Verify the monitored trajectory (go for α_s from t, then brake) against the human.
    fn verify(
        &mut self,
        slot: usize,
        go: &SpeedProfile,
        brake: &SpeedProfile,
        t: f64,
        diag: &mut Diagnostics,
    ) -> bool {
        let alpha = self.config.safety_step;
        let stop = alpha + brake.settle_time();
        if self.human.is_none() {
            return true;
        }
        if !self.has_meas {
            diag.binding = Binding::NoMeasurement;
            return false;
        }
        let Some(meas) = self.meas.take() else {
            diag.binding = Binding::NoMeasurement;
            return false;
        };
        // Coarse check first: the whole monitored trajectory as one interval (its occupancy
        // contains that of every sub-interval, so passing it verifies the step). Usually decides
        // when the human is far; otherwise the fine intervals below decide.
        if self.config.mode != FilterMode::Off && stop > alpha {
            let mut coarse = *diag;
            if self.check_interval(slot, go, brake, t, 0.0, stop, 0, &meas, &mut coarse) {
                *diag = coarse;
                self.meas = Some(meas);
                return true;
            }
        }
        let mut ok = true;
        let intervals = OccupancyIntervals::new(
            alpha,
            stop,
            self.config.first_interval,
            self.config.max_intervals,
        );
        for (k, ta, tb) in intervals {
            if !self.check_interval(slot, go, brake, t, ta, tb, k, &meas, diag) {
                ok = false;
                if self.config.mode != FilterMode::Off {
                    break;
                }
            }
        }
        self.meas = Some(meas);
        ok
    }

    /// Path and speed ranges of the monitored trajectory over relative time [ta, tb].
    fn path_ranges(
        go: &SpeedProfile,
        brake: &SpeedProfile,
        alpha: f64,
        ta: f64,
        tb: f64,
    ) -> (f64, f64, f64, f64) {
        let mut s_lo = f64::INFINITY;
        let mut s_hi = f64::NEG_INFINITY;
        let mut sd_lo = f64::INFINITY;
        let mut sd_hi = f64::NEG_INFINITY;
        let mut add = |r: (f64, f64, f64, f64, f64)| {
            s_lo = s_lo.min(r.0);
            s_hi = s_hi.max(r.1);
            sd_lo = sd_lo.min(r.2);
            sd_hi = sd_hi.max(r.3);
        };
        if ta < alpha {
            add(go.ranges(ta, tb.min(alpha)));
        }
        if tb > alpha {
            add(brake.ranges(ta.max(alpha) - alpha, tb - alpha));
        }
        (s_lo, s_hi, sd_lo.max(0.0), sd_hi)
    }

    #[allow(clippy::too_many_arguments)]
    fn check_interval(
        &mut self,
        slot: usize,
        go: &SpeedProfile,
        brake: &SpeedProfile,
        t: f64,
        ta: f64,
        tb: f64,
        k: usize,
        meas: &HumanMeasurement,
        diag: &mut Diagnostics,
    ) -> bool {
        let alpha = self.config.safety_step;
        let n = self.dof;
        let (s_lo, s_hi, sd_lo, sd_hi) = Self::path_ranges(go, brake, alpha, ta, tb);
        let tr = self.trajs[slot].as_ref().expect("slot holds a trajectory");
        let mut q_lo = [0.0; MAX_DOF];
        let mut q_hi = [0.0; MAX_DOF];
        let mut v_lo = [0.0; MAX_DOF];
        let mut v_hi = [0.0; MAX_DOF];
        for i in 0..n {
            let d = tr.joint_derivs(i, s_lo, s_hi);
            q_lo[i] = d.r[0].lo;
            q_hi[i] = d.r[0].hi;
            // q̇ = q′·ṡ with ṡ ∈ [sd_lo, sd_hi] ⊂ [0, ∞): interval product, rounded outward.
            let (a, b) = (d.r[1].lo, d.r[1].hi);
            let c = [a * sd_lo, a * sd_hi, b * sd_lo, b * sd_hi];
            v_lo[i] = c.iter().copied().fold(f64::INFINITY, f64::min).next_down();
            v_hi[i] = c
                .iter()
                .copied()
                .fold(f64::NEG_INFINITY, f64::max)
                .next_up();
            if sd_hi == 0.0 {
                // Path speed exactly 0 over the interval: the commanded joints are at rest.
                (v_lo[i], v_hi[i]) = (0.0, 0.0);
            }
        }
        let Self {
            reach,
            scratch,
            robot_caps,
            human_caps,
            energies,
            human,
            config,
            ..
        } = self;
        let Some((hr, rule)) = human.as_mut() else {
            return true;
        };
        // Non-finite path ranges never verify.
        let (Ok(q_box), Ok(v_box)) = (
            JointBox::new(&q_lo[..n], &q_hi[..n]),
            JointBox::new(&v_lo[..n], &v_hi[..n]),
        ) else {
            return false;
        };
        if hr.occupancy_into(meas, t + ta, t + tb, human_caps).is_err() {
            diag.binding = Binding::NoMeasurement;
            return false;
        }
        // Broad phase, stage 1: the human is outside the robot's workspace ball.
        if let Some(sep) = rule.workspace_clear(human_caps) {
            if k == 0 {
                diag.min_separation = diag.min_separation.min(sep);
            }
            return true;
        }
        if reach.occupancy_with(scratch, &q_box, robot_caps).is_err() {
            return false;
        }
        // The robot's real velocities may differ from the commanded ones by the controller's
        // velocity tracking error (rounded outward): the energy bound uses the widened box.
        let e_track = config.velocity_tracking_error;
        let energy = || {
            let widened = JointBox::from_fn(n, |i| {
                let (lo, hi) = v_box.bounds(i);
                ((lo - e_track).next_down(), (hi + e_track).next_up())
            });
            // Same joint box as the occupancy above: the scratch's frames are reused.
            match widened.map(|w| reach.subchain_energy_bounds_with(scratch, &q_box, &w, energies))
            {
                Ok(Ok(())) => energies[n],
                _ => f64::INFINITY,
            }
        };
        let mut first = None;
        let outcome = rule.check(robot_caps, &v_box, human_caps, energy, k == 0, |h| {
            first = Some(*h);
            ControlFlow::Break(())
        });
        if k == 0 {
            diag.min_separation = diag.min_separation.min(outcome.separation);
        }
        if let Some((e, thr)) = outcome.pfl
            && e > diag.contact_energy
        {
            diag.contact_energy = e;
            diag.contact_threshold = thr;
        }
        let Some(h) = first else { return true };
        if matches!(diag.binding, Binding::None) {
            diag.binding = match h.kind {
                ConstraintKind::Ssm => Binding::Ssm {
                    link: h.link,
                    body_part: h.part,
                    interval: k,
                },
                ConstraintKind::Pfl => Binding::Pfl {
                    link: h.link,
                    body_part: h.part,
                    energy: h.energy,
                    threshold: h.threshold,
                    constrained: h.constrained,
                },
            };
        }
        false
    }
}
