//! # pacs-motion
//!
//! From an action chunk to the motion the robot is commanded, and how it brakes:
//! - [`chunk`]: action chunks to waypoints (deltas or absolute; out-of-limit waypoints rejected or projected);
//! - [`trajectory`]: the piecewise constant-jerk trajectory with exact state and sound bounds queries;
//! - [`intended`]: the planners (time-synchronized jerk-limited segments through every waypoint, and
//!   the spline planner); [`intended::Planner::plan_single_action`] is the paper's single-action
//!   baseline;
//! - [`scaling`]: path-speed profiles from any path state (braking and resuming along the path) —
//!   what the shield runs;
//! - [`failsafe`], [`monitored`]: braking of a whole trajectory and the monitored trajectory, used by
//!   `pacs trajectory --brake-at` (to be merged into [`scaling`], see issue 13);
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
pub mod monitored;
pub mod profile;
pub mod scaling;
pub mod spline;
pub mod trajectory;

pub use chunk::{ActionKind, Chunk, OutOfLimits, Waypoints};
pub use error::{FailsafeError, TrajectoryError};
pub use failsafe::Failsafe;
pub use intended::{PlanMethod, Planner, PlannerConfig};
pub use monitored::Monitored;
pub use profile::{LIMIT_REL_TOL, Piece, Range};
pub use trajectory::{Bounds, EndCondition, JointState, Limits, Trajectory};
