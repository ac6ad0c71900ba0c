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
//! constrained one if the part may be pinched). Dynamic objects ([`Shield::add_object`]) are
//! enclosed over the same intervals ([`pacs_reach::object`]) and checked with the same rule's
//! object form ([`ObjectRule`]: no contact, SSM or PFL per object).
//!
//! Verified → execute the intended step and remember this failsafe. Not verified → continue the
//! last verified failsafe. By induction the robot is always on a verified monitored trajectory;
//! it starts at rest. No valid measurement, an unplannable chunk or an unverifiable candidate only
//! ever lead to following the last verified failsafe. The step allocates nothing.

// Joint-indexed loops over parallel fixed-size arrays read clearer than zipped iterators.
#![allow(clippy::needless_range_loop)]

mod builder;
mod command;
mod decision;
mod error;
mod handover;
mod intervals;
#[cfg(kani)]
mod proofs;
pub(crate) mod step;
mod verification;

pub use builder::ShieldBuilder;
pub use command::{Binding, BindingNames, Command, Diagnostics};
pub use decision::{
    Candidate, Choice, Decision, VerifiedFailsafe, choose, choose_in_proven_range, chosen_by_rule,
    decide,
};
pub use error::ShieldError;
pub use handover::{ChunkPlanner, Handover, OfferState, PreparedChunk};
pub use intervals::{
    OccupancyIntervals, Piece, interval_end, interval_inputs, interval_within, verify_fine,
};
pub use verification::monitored_joint_boxes;

use pacs_models::object::{ObjectContact, ObjectModel};
use pacs_models::{Capsule, ConstraintSpec, HumanModel, RobotModel};
use pacs_motion::chunk::{Chunk, OutOfLimits};
use pacs_motion::intended::{PlanMethod, Planner, PlannerConfig};
use pacs_motion::scaling::{PathState, SpeedProfile};
use pacs_motion::trajectory::{EndCondition, JointState, Limits, Trajectory};
use pacs_reach::human::{HumanMeasurement, HumanReach, HumanReachModel};
use pacs_reach::object::consistency::{ObjectBounds, object_pair_breaks};
use pacs_reach::object::{ObjectMeasurement, ObjectOccupancy};
use pacs_reach::robot::{ReachScratch, RobotReach};
use pacs_verify::iso15066::{ContactRule, ObjectRule};
use serde::{Deserialize, Serialize};

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

impl FilterMode {
    /// The mode's name as logs record the filter that ran (`meta.filter`: `pacs`, `off`,
    /// `single-action`; reports group runs by it).
    pub fn label(self) -> &'static str {
        match self {
            FilterMode::Pacs => "pacs",
            FilterMode::Off => "off",
            FilterMode::SingleAction => "single-action",
        }
    }
}

/// Shield settings (units: s, m, rad/s², rad/s³).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShieldConfig {
    /// Safety step α_s (s), within [`SAFETY_STEP_RANGE`].
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
    /// Maximum number of occupancy intervals (the last one extends to standstill), 1 to
    /// [`MAX_INTERVALS`].
    pub max_intervals: usize,
    /// SSM: the commanded robot is at rest on an interval if every commanded joint speed is
    /// provably at most this (rad/s). Default 0: only a stopped path counts as rest (the audit's
    /// default of 0.02 rad/s covers the controller's velocity tracking error on a real robot).
    pub rest_speed: f64,
    /// How each chunk's intended trajectory ends at its last executed waypoint q̂_h.
    /// [`EndCondition::AtRest`] (default): every chunk stops at q̂_h.
    /// [`EndCondition::Moving`] (opt-in, see `docs/shield.md`): it passes q̂_h moving and, unless
    /// the next chunk takes over, stops on a checked stopping tail along the same direction — so
    /// a chunk handed over near q̂_h ([`Shield::remaining`]) continues without stopping. The
    /// single-action mode always stops. Safety does not depend on this choice: the failsafe
    /// brakes along whatever path is executed, and the tail is checked like every other piece.
    pub chunk_end: EndCondition,
    /// Planner of the intended trajectories (default: the per-segment planner, whose ramp-up
    /// from rest along a fresh path leaves more verifiable steps; [`PlanMethod::Spline`] is the
    /// faster time-optimised spline with the per-segment planner as its fallback).
    pub plan_method: PlanMethod,
    /// Compute the separation figure of every step ([`Diagnostics::min_separation`]; default
    /// `true`). It is a diagnostic, not part of the decision, and costs 1.5–2 µs per step
    /// (capsule distances between every body part and the nearest robot capsules;
    /// `docs/performance.md`): a 1 kHz loop that does not log it can turn it off. Off, the
    /// figure is reported only where it comes for free: the bound for a human outside the
    /// robot's workspace ball, 0 where contact is possible, +∞ otherwise (not computed).
    pub separation_figure: bool,
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
            chunk_end: EndCondition::AtRest,
            plan_method: PlanMethod::Segments,
            separation_figure: true,
        }
    }
}

pub use pacs_verify::iso15066::EnvShape;

/// The safety steps α_s a shield accepts (s): 10 µs to 1 s. Below, a run's steps outnumber
/// what a clock and a log can tell apart; above, one step of intended motion is no longer a
/// small part of a braking manoeuvre.
pub const SAFETY_STEP_RANGE: std::ops::RangeInclusive<f64> = 1e-5..=1.0;

/// The most occupancy intervals a monitored trajectory is split into
/// ([`ShieldConfig::max_intervals`]): the interval proofs cover 1 to 12.
pub const MAX_INTERVALS: usize = 12;

/// Whether a clock reading `t` (s) resolves a thousandth of the safety step `alpha` (s): the
/// spacing of floats at `|t|` is at most `alpha / 1000`. Beyond that, `t₀ + k·α_s` no longer
/// advances by α_s per step (at `|t|` = 10¹³ s a 1 ms step rounds to 0 or 2 ms), and every
/// delay and age the shield computes from times is off by as much. Unix-time clocks (≈ 1.8·10⁹
/// s) pass for α_s ≥ 0.4 ms.
///
/// The one rule, [`pacs_log::time::clock_resolves`], which the audit applies to every span too.
pub use pacs_log::time::clock_resolves;

/// How far (s) a step time may be from the expected grid time `t` (float rounding of
/// `t_0 + k·α_s`): 1 ns, or 8 ulps of `t` for large (e.g. Unix-time) clocks.
pub fn time_tolerance(t: f64) -> f64 {
    1e-9_f64.max(8.0 * f64::EPSILON * t.abs())
}

/// The PACS shield (also OFF and single-action, by configuration).
#[derive(Clone)]
pub struct Shield {
    robot: RobotModel,
    dof: usize,
    hw: Limits,
    /// Plans chunks (a copy serves planning off the loop: [`Shield::chunk_planner`]).
    chunks: ChunkPlanner,
    reach: RobotReach,
    /// The humans: reachability, the ISO/TS 15066 rule for their body parts, the latest
    /// measurement and the occupancy buffer of each.
    humans: Vec<HumanSlot>,
    /// Static environment shapes (for the rule of humans added later).
    env: Vec<EnvShape>,
    config: ShieldConfig,
    trajs: [Option<Trajectory>; 2],
    /// The state the induction is about: slot, path state and time of the command, the stored
    /// verified failsafe, the fresh chunk, the offer's fate ([`step::StepState`]).
    st: step::StepState,
    /// Chunks accepted so far.
    chunks_accepted: u64,
    /// A chunk planned off the loop, waiting for its handover ([`Shield::offer`]).
    pending: Option<PreparedChunk>,
    /// A trajectory replaced or dropped in a step, kept so the step frees nothing (dropped by
    /// the next `offer`/`set_chunk`).
    spare: Option<Trajectory>,
    /// Verifications left that skip the whole-trajectory check (it failed recently), and how
    /// many it skips after its next failure: `verification::COARSE_SKIP` after a pass, doubling
    /// (plus one) with each failure in a row up to `verification::COARSE_SKIP_MAX`. Only the cost
    /// depends on these, never soundness.
    coarse_skip: u32,
    coarse_backoff: u32,
    /// Dynamic objects with their constraints and latest measurements.
    objects: Vec<ObjectSlot>,
    object_rule: ObjectRule,
    // Scratch buffers (allocated once).
    /// Per object, its own occupancy over the interval being checked, where computed.
    object_occ: Vec<Option<ObjectOccupancy>>,
    /// Per object, its occupancy over the whole monitored trajectory of the current
    /// verification (it contains the occupancy over every interval of it: the intervals test it
    /// first and compute their own only where it touches the robot).
    object_window: Vec<Option<ObjectOccupancy>>,
    /// Per object, which occupancy the interval being checked uses.
    object_pick: Vec<verification::ObjectPick>,
    robot_caps: Vec<Capsule>,
    energies: Vec<f64>,
    scratch: ReachScratch,
}

/// Trusted measurements of a person or object a new one is also held against (besides the one
/// in use).
const RECENT: usize = 16;
/// The least time (s) between two of them: with [`RECENT`], they reach back 0.30 s or more,
/// so a chain of measurements drifting away, each within the model's allowance of the one
/// before (`2·measurement_error_pos` even at equal stamps), is caught once it has moved
/// farther than the model allows since one of them (a drift slower than that is motion the
/// model admits).
const RECENT_SPACING: f64 = 0.02;

/// A human in the shield's scene.
#[derive(Debug, Clone)]
struct HumanSlot {
    reach: HumanReach,
    rule: ContactRule,
    /// Latest measurement (buffer allocated when the human is added; valid when `has_meas`).
    meas: HumanMeasurement,
    has_meas: bool,
    /// A measurement arrived that contradicts `meas` (or a recent trusted one) under the human
    /// model: one of them is wrong, so no step verifies until one newer than every contradicting
    /// one agrees with them (`meas` is kept).
    contradicted: bool,
    /// The newest stamp (s) of a measurement that contradicted the trusted ones.
    rejected_at: f64,
    /// Trusted measurements of the last (`RECENT` − 1)·[`RECENT_SPACING`] s or more, at least
    /// [`RECENT_SPACING`] apart (a ring, buffers allocated when the human is added): a new
    /// measurement must agree with each, so that a chain of measurements each within the model's
    /// allowance of the one before cannot drift away from where the person was.
    recent: Vec<HumanMeasurement>,
    /// Entries of `recent` in use, and the next one to write.
    recent_len: usize,
    recent_next: usize,
    /// Body-part occupancies of the interval being checked.
    caps: Vec<Capsule>,
    /// On the interval being checked, outside the robot's workspace ball.
    clear: bool,
}

impl HumanSlot {
    fn new(
        robot: &RobotModel,
        reach: &RobotReach,
        h: HumanModel,
        spec: &ConstraintSpec,
        env: Vec<EnvShape>,
        c: &ShieldConfig,
    ) -> Result<Self, ShieldError> {
        let tc = spec.resolve(&h).map_err(ShieldError::Constraints)?;
        tc.check_robot(robot)?;
        let zeros = vec![[0.0; 3]; h.keypoint_count()];
        let meas = HumanMeasurement::new(&h, 0.0, &zeros, Some(&zeros))?;
        let rule = ContactRule::new(robot, reach, &h, &tc.per_part, env, c.rest_speed)?;
        let caps = vec![
            Capsule::new_unchecked(Default::default(), Default::default(), 0.0);
            h.body_parts().len()
        ];
        Ok(Self {
            reach: HumanReach::new(h, c.human_model),
            rule,
            recent: vec![meas.clone(); RECENT],
            meas,
            has_meas: false,
            contradicted: false,
            rejected_at: f64::NEG_INFINITY,
            recent_len: 0,
            recent_next: 0,
            caps,
            clear: false,
        })
    }

    /// Replace the measurement in use if `m` is newer and newer than every rejected one (older or
    /// equal-time ones that agree are ignored) — unless `m` and a trusted one contradict the
    /// human model (some keypoint moved farther than
    /// `v_max·|Δt| + 2·measurement_error_pos`, the audit's `human_exceeds_model` test,
    /// [`pacs_reach::human::consistency::human_pair_breaks`]): then one of them is wrong, the
    /// trusted one is kept and the person is `contradicted` — no step verifies (the robot
    /// follows the failsafe verified before) until a newer measurement agrees with the trusted
    /// one (whose allowance grows with the time since it: a person who truly moved is accepted
    /// once the model allows the move). Test `shield/tests/shield.rs::
    /// a_measurement_that_contradicts_the_trusted_one_verifies_nothing` (mutant `x118`).
    fn take(&mut self, m: &HumanMeasurement) {
        if !self.has_meas {
            self.meas.assign_from(m);
            self.has_meas = true;
            self.remember(m);
            return;
        }
        let model = self.reach.model();
        let breaks =
            |r: &HumanMeasurement| pacs_reach::human::consistency::human_pair_breaks(model, r, m);
        if breaks(&self.meas) || self.recent[..self.recent_len].iter().any(breaks) {
            self.contradicted = true;
            self.rejected_at = self.rejected_at.max(m.time());
            return;
        }
        // Only a measurement newer than every rejected one clears a contradiction (an older one
        // would be verified against while a newer one said otherwise).
        if m.supersedes(Some(&self.meas)) && m.time() > self.rejected_at {
            self.meas.assign_from(m);
            self.contradicted = false;
            self.remember(m);
        }
    }

    /// Keep the trusted measurement `m` among the recent ones if it is at least
    /// [`RECENT_SPACING`] newer than the newest kept (the oldest is let go).
    fn remember(&mut self, m: &HumanMeasurement) {
        let newest = (self.recent_next + RECENT - 1) % RECENT;
        if self.recent_len > 0 && m.time() - self.recent[newest].time() < RECENT_SPACING {
            return;
        }
        self.recent[self.recent_next].assign_from(m);
        self.recent_next = (self.recent_next + 1) % RECENT;
        self.recent_len = (self.recent_len + 1).min(RECENT);
    }
}

/// A dynamic object in the shield's scene.
#[derive(Debug, Clone)]
struct ObjectSlot {
    model: ObjectModel,
    contact: ObjectContact,
    /// The measurement in use (the trusted one).
    meas: Option<ObjectMeasurement>,
    /// What the record-against-record test needs of the model.
    bounds: ObjectBounds,
    /// A measurement arrived that contradicts a trusted one: no step verifies until one newer
    /// than every contradicting one agrees with them (as for people, [`HumanSlot::take`]).
    contradicted: bool,
    /// The newest stamp (s) of a measurement that contradicted the trusted ones.
    rejected_at: f64,
    /// Recent trusted measurements, at least [`RECENT_SPACING`] apart (a ring).
    recent: [ObjectMeasurement; RECENT],
    recent_len: usize,
    recent_next: usize,
}

impl ObjectSlot {
    /// Use `m` if it is newer than the measurement in use — unless it contradicts that one or
    /// a recent trusted one under the object's model (the audit's `object_exceeds_model` test:
    /// positions, velocities and a measured velocity's direction,
    /// [`pacs_reach::object::consistency::object_pair_breaks`]): then one of them is wrong, the
    /// trusted one is kept and no step verifies until a newer measurement agrees with them. Test
    /// `shield/tests/objects.rs::an_object_measurement_that_contradicts_the_trusted_ones_verifies_nothing`
    /// (mutant `x120`).
    fn take(&mut self, m: &ObjectMeasurement) {
        let Some(trusted) = self.meas else {
            self.meas = Some(*m);
            self.remember(m);
            return;
        };
        let b = &self.bounds;
        let breaks = |r: &ObjectMeasurement| {
            let (early, late) = if r.time <= m.time { (r, m) } else { (m, r) };
            object_pair_breaks(b, early, late)
        };
        if breaks(&trusted) || self.recent[..self.recent_len].iter().any(breaks) {
            self.contradicted = true;
            self.rejected_at = self.rejected_at.max(m.time);
            return;
        }
        if m.time > trusted.time && m.time > self.rejected_at {
            self.meas = Some(*m);
            self.contradicted = false;
            self.remember(m);
        }
    }

    /// Keep the trusted measurement `m` among the recent ones if it is at least
    /// [`RECENT_SPACING`] newer than the newest kept (the oldest is let go).
    fn remember(&mut self, m: &ObjectMeasurement) {
        let newest = (self.recent_next + RECENT - 1) % RECENT;
        if self.recent_len > 0 && m.time - self.recent[newest].time < RECENT_SPACING {
            return;
        }
        self.recent[self.recent_next] = *m;
        self.recent_next = (self.recent_next + 1) % RECENT;
        self.recent_len = (self.recent_len + 1).min(RECENT);
    }
}

impl std::fmt::Debug for Shield {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Shield")
            .field("config", &self.config)
            .field("time", &self.st.time)
            .finish()
    }
}

impl Shield {
    /// Build a shield for a robot, an optional first person (person 0) with a task constraint
    /// spec, and static environment shapes; add more people with [`Self::add_human`].
    /// [`Self::builder`] says the same with every person alike.
    pub fn new(
        robot: RobotModel,
        human: Option<(HumanModel, &ConstraintSpec)>,
        env: Vec<EnvShape>,
        config: ShieldConfig,
    ) -> Result<Self, ShieldError> {
        let c = &config;
        let bad = |field: &'static str, value: f64| ShieldError::Config { field, value };
        if !SAFETY_STEP_RANGE.contains(&c.safety_step) {
            return Err(ShieldError::SafetyStep(c.safety_step));
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
        if !(c.first_interval > 0.0 && c.first_interval.is_finite()) {
            return Err(bad("first_interval", c.first_interval));
        }
        // 1 to 12: the range the interval proofs cover (`f2_intervals_cover_by_contract`,
        // `f2_fine_pieces_cover` and their twins draw `max_intervals` in 1..=12).
        if !(1..=MAX_INTERVALS).contains(&c.max_intervals) {
            return Err(bad("max_intervals", c.max_intervals as f64));
        }
        let dof = robot.dof();
        let hw = Limits::from_joint_limits(robot.limits());
        let mut plan = hw;
        for i in 0..dof {
            plan.v[i] *= c.intended_vel_scale;
            plan.a[i] *= c.intended_acc_fraction;
            plan.j[i] = plan.j[i].min(c.intended_jerk);
        }
        let planner_config = PlannerConfig {
            end: c.chunk_end,
            method: c.plan_method,
            ..PlannerConfig::default()
        };
        let planner = Planner::new(plan, planner_config);
        // For chunks handed over while the robot brakes (harder than the intended limits):
        // the robot's acceleration and jerk, the intended velocity.
        let mut recovery_limits = hw;
        recovery_limits.v = plan.v;
        let recovery = Planner::new(recovery_limits, planner_config);
        let reach = RobotReach::try_new(&robot, c.tracking_error)?;
        let humans = match human {
            None => Vec::new(),
            Some((h, spec)) => vec![HumanSlot::new(&robot, &reach, h, spec, env.clone(), c)?],
        };
        let object_rule = ObjectRule::new(&robot, &reach, c.rest_speed)?;
        Ok(Self {
            dof,
            hw,
            chunks: ChunkPlanner::new(
                planner,
                recovery,
                robot.limits().clone(),
                c.out_of_limits,
                c.mode,
            ),
            robot_caps: vec![
                Capsule::new_unchecked(Default::default(), Default::default(), 0.0);
                reach.capsule_count()
            ],
            energies: vec![0.0; dof + 1],
            scratch: ReachScratch::default(),
            reach,
            humans,
            env,
            config,
            robot,
            trajs: [None, None],
            st: step::StepState {
                chunk_serial: [0, 0],
                slot: 0,
                path: PathState::rest(0.0),
                time: 0.0,
                started: false,
                fresh: None,
                offer_state: OfferState::None,
                last_verified: true,
                failsafe: None,
            },
            chunks_accepted: 0,
            pending: None,
            spare: None,
            coarse_skip: 0,
            coarse_backoff: verification::COARSE_SKIP,
            objects: Vec::new(),
            object_rule,
            object_occ: Vec::new(),
            object_window: Vec::new(),
            object_pick: Vec::new(),
        })
    }

    /// Add a dynamic object with its contact constraint; returns its index (for
    /// [`Self::measure_object`] and [`Binding::Object`]). Until the object has a measurement,
    /// no intended step verifies (the robot follows its verified failsafe). Call before the
    /// control loop: this allocates.
    pub fn add_object(
        &mut self,
        model: ObjectModel,
        contact: ObjectContact,
    ) -> Result<usize, ShieldError> {
        let contact = contact
            .validated()
            .map_err(|error| ShieldError::ObjectContact {
                index: self.objects.len(),
                error,
            })?;
        let bounds = ObjectBounds::of(&model);
        self.objects.push(ObjectSlot {
            model,
            contact,
            meas: None,
            bounds,
            contradicted: false,
            rejected_at: f64::NEG_INFINITY,
            recent: [ObjectMeasurement {
                time: 0.0,
                position: [0.0; 3],
                velocity: None,
            }; RECENT],
            recent_len: 0,
            recent_next: 0,
        });
        self.object_occ.push(None);
        self.object_window.push(None);
        self.object_pick.push(verification::ObjectPick::Cleared);
        Ok(self.objects.len() - 1)
    }

    /// Number of dynamic objects.
    pub fn object_count(&self) -> usize {
        self.objects.len()
    }

    /// Record a measurement of object `id` (`ObjectSlot::take`): it replaces the one in use if it
    /// is newer and agrees with the trusted ones; an older or equal-time one that agrees is
    /// ignored; one that contradicts them, of any stamp, stops verification until one newer than
    /// it agrees. Errors: unknown `id`, non-finite values.
    pub fn measure_object(&mut self, id: usize, m: &ObjectMeasurement) -> Result<(), ShieldError> {
        if !m.is_finite() {
            return Err(ShieldError::ObjectNotFinite(id));
        }
        let n = self.objects.len();
        let Some(slot) = self.objects.get_mut(id) else {
            return Err(ShieldError::UnknownObject { id, count: n });
        };
        slot.take(m);
        Ok(())
    }

    /// The robot model.
    pub fn robot(&self) -> &RobotModel {
        &self.robot
    }
    /// The configuration.
    pub fn config(&self) -> &ShieldConfig {
        &self.config
    }
    /// The first human's model, if any (the one [`Self::step`]'s measurement belongs to).
    pub fn human_model(&self) -> Option<&HumanModel> {
        self.humans.first().map(|h| h.reach.model())
    }

    /// A step's [`Binding`] as outputs print it ([`BindingNames::describe`]), with the names
    /// of this shield's links and body parts (no person or object ids: see
    /// [`Self::binding_names`]). Allocates: for outputs, not the control loop.
    pub fn binding_json(&self, b: &Binding) -> serde_json::Value {
        self.binding_names(&[], &[]).describe(b)
    }

    /// The names a [`Binding`]'s indices stand for: the robot's links, each human's body parts
    /// and its id (`person_ids[i]`, if given), the objects' ids (`object_ids`, in the order of
    /// [`Self::add_object`]). Build once and describe every step's binding with it.
    pub fn binding_names(&self, person_ids: &[String], object_ids: &[String]) -> BindingNames {
        BindingNames {
            links: self.robot.links().iter().map(|l| l.name.clone()).collect(),
            people: self
                .humans
                .iter()
                .enumerate()
                .map(|(i, h)| {
                    (
                        person_ids.get(i).cloned(),
                        h.reach
                            .model()
                            .body_parts()
                            .iter()
                            .map(|b| b.name.clone())
                            .collect(),
                    )
                })
                .collect(),
            objects: object_ids.to_vec(),
        }
    }

    /// Number of humans.
    pub fn human_count(&self) -> usize {
        self.humans.len()
    }

    /// Add another human with its task constraints; returns its index (the first human, given
    /// to [`Self::new`], is 0 and is measured through [`Self::step`]; every human through
    /// [`Self::measure_human`]). Until it has a measurement, no intended step verifies. Call
    /// before the control loop: this allocates.
    pub fn add_human(
        &mut self,
        human: HumanModel,
        constraints: &ConstraintSpec,
    ) -> Result<usize, ShieldError> {
        let slot = HumanSlot::new(
            &self.robot,
            &self.reach,
            human,
            constraints,
            self.env.clone(),
            &self.config,
        )?;
        self.humans.push(slot);
        // Several people: each may be pinched against another (`ContactRule::with_other_people`,
        // the same rule as the audit's passes of a log with several people).
        for h in &mut self.humans {
            h.rule.set_other_people(true);
        }
        Ok(self.humans.len() - 1)
    }

    /// Record a measurement of human `id` (built for that human's model): it replaces the
    /// latest one if it is newer. Errors: unknown `id`, a keypoint count that does not match.
    pub fn measure_human(&mut self, id: usize, m: &HumanMeasurement) -> Result<(), ShieldError> {
        let n = self.humans.len();
        let Some(h) = self.humans.get_mut(id) else {
            return Err(ShieldError::UnknownHuman { id, count: n });
        };
        let k = h.reach.model().keypoint_count();
        if m.positions().len() != k {
            return Err(ShieldError::KeypointCount {
                id,
                got: m.positions().len(),
                expected: k,
            });
        }
        h.take(m);
        Ok(())
    }

    /// Start at rest at `q` (rad) at time `t` (s). The shield only starts from rest.
    pub fn start(&mut self, t: f64, q: &[f64]) -> Result<(), ShieldError> {
        if q.len() != self.dof {
            return Err(ShieldError::StartLength {
                given: q.len(),
                dof: self.dof,
            });
        }
        if let Some(i) = q.iter().position(|x| !x.is_finite()) {
            return Err(ShieldError::StartNotFinite {
                index: i,
                joint: self.robot.joints()[i].name.clone(),
                value: q[i],
            });
        }
        if !t.is_finite() {
            return Err(ShieldError::StartTime(t));
        }
        let l = self.robot.limits();
        if let Some(i) = (0..self.dof).find(|&i| !(l.q_min()[i]..=l.q_max()[i]).contains(&q[i])) {
            return Err(ShieldError::StartOutsideLimits {
                index: i,
                joint: self.robot.joints()[i].name.clone(),
                value: q[i],
                min: l.q_min()[i],
                max: l.q_max()[i],
            });
        }
        if !clock_resolves(t, self.config.safety_step) {
            return Err(ShieldError::ClockUnresolved {
                t,
                safety_step: self.config.safety_step,
            });
        }
        self.trajs = [Some(Trajectory::standstill(q)), None];
        self.st.chunk_serial = [0, 0];
        self.st.slot = 0;
        self.st.path = PathState::rest(0.0);
        self.st.time = t;
        self.st.started = true;
        self.st.fresh = None;
        self.pending = None;
        self.spare = None;
        self.st.offer_state = OfferState::None;
        self.st.last_verified = true;
        // Standing still is the first verified failsafe.
        self.st.failsafe = Some(VerifiedFailsafe {
            slot: 0,
            profile: SpeedProfile::plan(self.st.path, 0.0, 1.0, 1.0),
            t0: t,
        });
        Ok(())
    }

    fn traj(&self, slot: usize) -> &Trajectory {
        self.trajs[slot].as_ref().expect("slot holds a trajectory")
    }

    /// The last verified failsafe (after `start`).
    pub fn verified_failsafe(&self) -> Option<VerifiedFailsafe> {
        self.st.failsafe
    }

    /// The joint state of the last verified failsafe at absolute time `t` (after `start`).
    pub fn failsafe_state_at(&self, t: f64) -> Option<JointState> {
        let f = self.st.failsafe?;
        self.trajs[f.slot].as_ref()?;
        Some(self.joint_state(f.slot, &f.profile.eval(t - f.t0)))
    }

    /// The intended trajectory the commands currently follow and the path state on it (path
    /// position `s` in intended-trajectory time, speed ṡ, acceleration s̈): every command is
    /// `path.joint_state(trajectory)` — on the trajectory of an accepted chunk (or the start's
    /// standstill), never off it.
    pub fn path(&self) -> (&Trajectory, PathState) {
        (self.traj(self.st.slot), self.st.path)
    }

    /// Intended time (s) left on the current trajectory until its last waypoint q̂_h is passed
    /// (0 once passed; at the intended timing — braking makes it last longer). `None` before
    /// [`Self::start`]. A control loop that hands the next chunk over when this drops to one
    /// safety step keeps a Moving trajectory ([`ShieldConfig::chunk_end`]) moving across chunks.
    pub fn remaining(&self) -> Option<f64> {
        if !self.st.started {
            return None;
        }
        let (traj, p) = self.path();
        Some((traj.duration() - p.s).max(0.0))
    }

    /// Current commanded joint state.
    pub fn state(&self) -> JointState {
        self.joint_state(self.st.slot, &self.st.path)
    }

    /// Time (s) of the next step (the time the commanded state [`Self::state`] is for).
    pub fn time(&self) -> f64 {
        self.st.time
    }

    fn joint_state(&self, slot: usize, p: &PathState) -> JointState {
        p.joint_state(self.traj(slot))
    }

    /// Hand a new action chunk to the shield: planned from the current commanded state into a new
    /// intended trajectory, which takes over as soon as one of its steps is verified. A chunk that
    /// cannot be planned is ignored (error returned; the robot keeps its verified motion).
    ///
    /// Plans in the caller's thread (the time: `docs/performance.md#chunk-planning-time`): for
    /// simulations and loops with time to spare. A 1 kHz loop hands its chunks to a
    /// [`crate::worker::ChunkWorker`] instead, whose `set_chunk` costs a few µs.
    pub fn set_chunk(&mut self, chunk: &Chunk) -> Result<(), ShieldError> {
        if !self.st.started {
            return Err(ShieldError::NotStarted);
        }
        let start = self.state();
        let traj = self.chunks.plan(&start, chunk)?;
        self.spare = None;
        self.take_over(traj);
        // A chunk planned off the loop and not yet taken over is older than this one.
        self.pending = None;
        Ok(())
    }

    /// Which chunk the commands follow and how many of its executed actions the commanded
    /// state has passed (`None` before [`Self::start`]). What a real-time-chunking policy needs
    /// to know: the actions `passed..h` of chunk `chunk` are still ahead (or will never run if
    /// a newer chunk takes over).
    pub fn chunk_progress(&self) -> Option<ChunkProgress> {
        if !self.st.started {
            return None;
        }
        let (traj, p) = self.path();
        let times = traj.waypoint_times();
        let passed = if self.st.chunk_serial[self.st.slot] == 0 {
            0
        } else {
            times.iter().take_while(|&&tw| tw <= p.s).count()
        };
        Some(ChunkProgress {
            chunk: self.st.chunk_serial[self.st.slot],
            passed,
            executed: if self.st.chunk_serial[self.st.slot] == 0 {
                0
            } else {
                times.len()
            },
            accepted: self.chunks_accepted,
        })
    }
}

/// Progress along the chunk the shield's commands follow ([`Shield::chunk_progress`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct ChunkProgress {
    /// Serial number of the chunk the commands follow: the n-th chunk accepted by
    /// [`Shield::set_chunk`] is n; 0 is the standstill at the start (no chunk yet).
    pub chunk: u64,
    /// Number of that chunk's waypoints q̂_1 … q̂_h passed by the commanded state (0 ≤ passed ≤ h):
    /// the actions `0..passed` have been executed.
    pub passed: usize,
    /// h: the number of actions of that chunk that are executed (0 for the standstill).
    pub executed: usize,
    /// Chunks accepted so far (a chunk newer than `chunk` waits for a verified step).
    pub accepted: u64,
}

#[cfg(test)]
mod tests {
    use super::*;
    use pacs_models::{ConstraintSpec, default_human, fr3};

    /// An FR3 shield with the default human under the built-in constraints `spec`.
    fn fr3_shield(spec: &str, config: ShieldConfig) -> Result<Shield, ShieldError> {
        let spec = ConstraintSpec::builtin(spec).unwrap();
        Shield::new(fr3::fr3(), Some((default_human(), &spec)), vec![], config)
    }

    /// With a second person every person's rule takes a PFL contact as a possible pinch against
    /// the other (`ContactRule::set_other_people`, as the audit's passes of a log with several
    /// people); alone, not.
    #[test]
    fn a_second_person_makes_every_rule_count_the_other_people() {
        let mut sh = fr3_shield("handover", ShieldConfig::default()).unwrap();
        assert!(!sh.humans[0].rule.other_people());
        let spec = ConstraintSpec::builtin("handover").unwrap();
        assert_eq!(sh.add_human(default_human(), &spec).unwrap(), 1);
        assert!(sh.humans.iter().all(|h| h.rule.other_people()));
    }

    /// `max_intervals` outside 1 to 12 (the proofs' range) is refused, naming the field.
    #[test]
    fn max_intervals_outside_the_proven_range_is_refused() {
        let shield = |max_intervals| {
            fr3_shield(
                "ssm",
                ShieldConfig {
                    max_intervals,
                    ..ShieldConfig::default()
                },
            )
        };
        for bad in [0, MAX_INTERVALS + 1, 1000] {
            let Err(e) = shield(bad) else {
                panic!("max_intervals {bad} accepted");
            };
            let e = e.to_string();
            assert!(e.contains("max_intervals"), "{e}");
        }
        for good in [1, MAX_INTERVALS] {
            assert!(shield(good).is_ok());
        }
    }

    /// A brake whose settle time is not a finite time after the step (NaN here) is never
    /// verified: the occupancy intervals cover `[0, stop]` only for a finite `stop ≥ α`
    /// (`interval_end`'s precondition). The same brake, planned from a valid state, verifies
    /// against a person 3 m away.
    #[test]
    fn a_brake_without_a_finite_settle_time_is_not_verified() {
        let human = default_human();
        let mut sh = fr3_shield("ssm", ShieldConfig::default()).unwrap();
        let q = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];
        sh.start(0.0, &q).unwrap();
        let far = pacs_testkit::keypoints_in_a_row(3.0);
        let m = HumanMeasurement::new(&human, 0.0, &far, None).unwrap();
        sh.measure_human(0, &m).unwrap();
        let diag = || Diagnostics::unbound(0.0);
        let rest = PathState::rest(0.0);
        let go = SpeedProfile::plan(rest, 0.0, 1.0, 10.0);
        let brake = SpeedProfile::plan(rest, 0.0, 1.0, 10.0);
        let mut d = diag();
        assert!(sh.verify(0, &go, &brake, 0.0, &mut d), "{d:?}");
        let nan = PathState {
            s: 0.0,
            sd: f64::NAN,
            sdd: 0.0,
        };
        let brake = SpeedProfile::plan(nan, 0.0, 1.0, 10.0);
        assert!(!brake.settle_time().is_finite());
        let mut d = diag();
        assert!(!sh.verify(0, &go, &brake, 0.0, &mut d));
        assert_eq!(d.binding, Binding::NoProfile);
    }
}
