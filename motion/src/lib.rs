//! # pacs-motion
//!
//! From an action chunk to the motion the robot is commanded, and how it brakes:
//! - [`chunk`]: action chunks to waypoints (deltas or absolute; out-of-limit waypoints rejected or projected);
//! - [`trajectory`]: the piecewise constant-jerk trajectory with exact state and sound bounds queries;
//! - [`intended`]: the planners (time-synchronized jerk-limited segments through every waypoint, and
//!   the spline planner); [`intended::Planner::plan_single_action`] is the paper's single-action
//!   baseline;
//! - [`scaling`]: path-speed profiles from any path state (braking and resuming along the path) —
//!   the one braking, run by the shield and by `pacs trajectory --brake-at`;
//! - [`failsafe`]: the whole-trajectory failsafe of `pacs trajectory --brake-at` (the earliest
//!   stop by that braking, [`failsafe::brake_plan`]);
//! - [`profile`]: constant-jerk pieces, sound extrema and interval arithmetic;
//! - [`anchors`]: the seeded FR3 chunk problem set of the trajectory anchors.
//!
//! Units: rad, rad/s, rad/s², rad/s³, seconds.

// Joint loops index several fixed-size per-joint arrays at once; index loops read clearer.
#![allow(clippy::needless_range_loop)]

pub mod anchors;
pub mod chunk;
pub mod error;
pub mod failsafe;
pub mod intended;
pub mod profile;
pub mod scaling;
pub mod spline;
pub mod trajectory;

pub use chunk::{ActionKind, Chunk, OutOfLimits, Waypoints};
pub use error::TrajectoryError;
pub use failsafe::{BrakePlan, brake_plan};
pub use intended::{PlanMethod, Planner, PlannerConfig};
pub use profile::{LIMIT_REL_TOL, Piece, Range};
pub use trajectory::{Bounds, EndCondition, JointState, Limits, Trajectory};
