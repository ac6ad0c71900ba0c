//! # pacs-sim
//!
//! A kinematic simulation of the paper's evaluation, used by `pacs demo` and the evaluation:
//! - [`humans`]: scripted human keypoint motions within the default model's limits, and a
//!   measurement model with delay and bounded noise;
//! - [`objects`]: scripted dynamic objects (the rolling spheres) with their object models and
//!   a measurement model;
//! - [`policy`]: the [`policy::TaskPolicy`] trait, a nearest-neighbour demonstration policy that
//!   emits chunks of joint deltas from the current joint angles only, and a policy learned from
//!   the demonstrations by kernel regression on the last two observations;
//! - [`teleop`]: demonstrations with the variety of human teleoperation (pauses, changes of
//!   pace, hesitations near people, small detours), within the operated limits, for training
//!   learned policies;
//! - [`tolerance`]: whether a policy still succeeds when the shield brakes, holds and resumes
//!   along its path (an intruder's hand stops the robot on the policy's own rollouts);
//! - [`episode`]: runs a filter (PACS, OFF, single-action, CBF) against a policy, a human and
//!   objects, with ground-truth safety metrics (exact geometry against the true human and objects).
//!
//! The robot follows the filter's commands exactly (the occupancy's tracking-error margin covers
//! a real controller's error).

pub mod episode;
pub mod error;
pub mod eval;
pub mod humans;
pub mod objects;
pub mod policy;
pub mod task;
pub mod teleop;
pub mod tolerance;

pub use error::SimError;

/// A name (task, method, variant) that is not one of the choices.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown {kind} `{given}` ({choices})")]
pub struct UnknownName {
    /// What was named (`task`, `method`).
    pub kind: &'static str,
    /// The name given.
    pub given: String,
    /// The choices, as listed in the message.
    pub choices: String,
}
