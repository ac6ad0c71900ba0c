//! [`ShieldError`]: why a shield (or a baseline filter behind the same interface) refused a
//! configuration, a model, a start, a measurement or a chunk. Every variant carries the values
//! its message names.

use super::SAFETY_STEP_RANGE;
use pacs_models::ModelError;
use pacs_reach::ReachError;
use pacs_verify::iso15066::RuleError;
use thiserror::Error;

/// Errors of shield construction, start, measurements and chunk handling.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ShieldError {
    /// The safety step (s) is outside [`SAFETY_STEP_RANGE`].
    #[error(
        "shield config `safety_step`: {0} s is outside [{min}, {max}] s",
        min = SAFETY_STEP_RANGE.start(),
        max = SAFETY_STEP_RANGE.end()
    )]
    SafetyStep(f64),
    /// A configuration value outside its range (`field` names it and the range).
    #[error("shield config `{field}`: invalid value {value}")]
    Config { field: &'static str, value: f64 },
    /// The task constraints do not resolve for the person's model.
    #[error("constraints: {0}")]
    Constraints(ModelError),
    /// A model the shield cannot use (e.g. constraints naming links the robot lacks).
    #[error(transparent)]
    Model(#[from] ModelError),
    /// The robot's or a person's reachability model refused its inputs.
    #[error(transparent)]
    Reach(#[from] ReachError),
    /// The ISO/TS 15066 rule cannot be built for this robot and person (e.g. too many
    /// capsules).
    #[error(transparent)]
    Rule(#[from] RuleError),
    /// An object's contact constraint is invalid.
    #[error("object {index}: {error}")]
    ObjectContact { index: usize, error: ModelError },
    /// An object measurement with a NaN or infinite value.
    #[error("object {0}: measurement with a non-finite value")]
    ObjectNotFinite(usize),
    /// An object index that was never added.
    #[error("object {id}: no such object ({count} added)")]
    UnknownObject { id: usize, count: usize },
    /// A person index that was never added.
    #[error("human {id}: no such human ({count} in the scene)")]
    UnknownHuman { id: usize, count: usize },
    /// A person measurement whose keypoint count differs from the person's model.
    #[error("human {id}: measurement with {got} keypoints, the model has {expected}")]
    KeypointCount {
        id: usize,
        got: usize,
        expected: usize,
    },
    /// A start configuration with the wrong number of joints.
    #[error("start: {given} joint values given, the robot has {dof} joints")]
    StartLength { given: usize, dof: usize },
    /// A start angle (rad) that is NaN or infinite.
    #[error("start[{index}] (joint `{joint}`): {value} is not a finite angle (rad)")]
    StartNotFinite {
        index: usize,
        joint: String,
        value: f64,
    },
    /// A start angle (rad) outside the joint's position limits (rad).
    #[error(
        "start[{index}] (joint `{joint}`): {value} rad is outside the joint position limits [{min}, {max}] rad"
    )]
    StartOutsideLimits {
        index: usize,
        joint: String,
        value: f64,
        min: f64,
        max: f64,
    },
    /// A start time (s) that is NaN or infinite.
    #[error("start: the time {0} s is not finite")]
    StartTime(f64),
    /// A start time (s) too large for floats to resolve the safety step (s).
    #[error(
        "start: the time {t} s is too large to resolve the safety step ({safety_step} s): floats at that magnitude are farther apart than a thousandth of it (count time from the run's start)"
    )]
    ClockUnresolved { t: f64, safety_step: f64 },
    /// A planning thread lead of zero steps.
    #[error("ChunkWorker lead must be at least 1 safety step")]
    ZeroLead,
    /// The operating system refused the planning thread.
    #[error("cannot start the planning thread: {0}")]
    PlanningThread(std::io::ErrorKind),
    /// The planning thread is gone.
    #[error("the chunk planning thread has ended (it panicked)")]
    PlanningThreadEnded,
    /// The shield must be started (at rest) first.
    #[error("shield not started: call start(t, q) with the robot at rest")]
    NotStarted,
    /// The chunk could not be planned; it is ignored and the robot keeps its verified motion.
    #[error("chunk ignored: {0}")]
    Chunk(#[from] pacs_motion::error::TrajectoryError),
    /// A chunk planned off the loop arrived after its handover time ([`super::Shield::offer`]):
    /// plan it again from a newer [`super::Shield::likely_handover`].
    #[error(
        "chunk ignored: planned for the step at {handover} s, the shield is already at {time} s"
    )]
    Stale { handover: f64, time: f64 },
}
