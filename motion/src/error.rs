//! Typed errors of trajectory planning and failsafe construction.

use thiserror::Error;

/// Why a chunk, a start state or a trajectory was rejected.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum TrajectoryError {
    /// A vector had the wrong number of entries.
    #[error("{what}: expected {expected} values, found {found}")]
    Length {
        /// Which input.
        what: String,
        /// Expected length.
        expected: usize,
        /// Found length.
        found: usize,
    },
    /// A value was NaN or infinite.
    #[error("{what}[{index}]: value {value} is not finite")]
    NotFinite {
        /// Which input.
        what: String,
        /// Index within it.
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// A chunk had no executed action, or more executed actions than it holds.
    #[error("chunk: execute = {execute} must be in 1..={available}")]
    Execute {
        /// Requested number of executed actions.
        execute: usize,
        /// Actions in the chunk.
        available: usize,
    },
    /// A waypoint lies outside the joint position limits (and projection was not requested).
    #[error("waypoint {waypoint}, joint {joint}: position {value} rad outside [{lo}, {hi}]")]
    WaypointOutsideLimits {
        /// Waypoint index (1-based: q̂_1 is the first target).
        waypoint: usize,
        /// Joint index.
        joint: usize,
        /// Waypoint value (rad).
        value: f64,
        /// Lower limit (rad).
        lo: f64,
        /// Upper limit (rad).
        hi: f64,
    },
    /// The start state violates a limit.
    #[error("start state, joint {joint}: {quantity} = {value} exceeds limit {limit}")]
    StartOutsideLimits {
        /// Joint index.
        joint: usize,
        /// "q", "dq" or "ddq".
        quantity: &'static str,
        /// The value.
        value: f64,
        /// The limit it exceeds.
        limit: f64,
    },
    /// A limit scale factor outside (0, 1].
    #[error("limit_scale = {0} must be in (0, 1]")]
    Scale(f64),
    /// No candidate trajectory passed the limit checks (e.g. a moving start state that must
    /// overshoot a position limit).
    #[error("no feasible trajectory: segment {segment}, joint {joint}: {reason}")]
    Infeasible {
        /// Segment (1-based).
        segment: usize,
        /// Joint index.
        joint: usize,
        /// What failed.
        reason: String,
    },
    /// The segment solver reported an error.
    #[error("segment {segment}: solver failed: {message}")]
    Solver {
        /// Segment (1-based).
        segment: usize,
        /// Solver message.
        message: String,
    },
}
