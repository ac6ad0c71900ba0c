//! # pacs-verify
//!
//! Intended trajectories from action chunks and path-consistent failsafe braking:
//! - [`chunk`]: action chunks to waypoints (deltas or absolute; out-of-limit waypoints rejected or projected);
//! - [`trajectory`]: the piecewise constant-jerk trajectory with exact state and sound bounds queries;
//! - [`intended`]: the planner (time-synchronized jerk-limited segments through every waypoint);
//!   [`intended::Planner::plan_single_action`] is the paper's single-action baseline;
//! - [`failsafe`]: braking along the same path by a jerk-limited time scaling, verified by interval bounds;
//! - [`monitored`]: intended motion for one safety step, then the failsafe; queryable state and bounds;
//! - [`profile`]: constant-jerk pieces, sound extrema and interval arithmetic;
//! - [`scaling`]: path-speed profiles from any path state (braking and resuming along the path);
//! - [`iso15066`]: the one ISO/TS 15066 rule (SSM, PFL, clamping) for one time interval, called by
//!   the shield and the audit;
//! - [`shield`]: the PACS online safety shield (OFF and single-action by configuration);
//! - [`cbf`]: the control-barrier-function baseline;
//! - [`bench`]: reproducible timing scenarios for `pacs bench`.
//!
//! Units: rad, rad/s, rad/s², rad/s³, seconds.

// Joint loops index several fixed-size per-joint arrays at once; index loops read clearer.
#![allow(clippy::needless_range_loop)]

pub mod audit;
pub mod bench;
pub mod cbf;
pub mod chunk;
pub mod error;
pub mod failsafe;
pub mod intended;
pub mod iso15066;
pub mod monitored;
pub mod problems;
pub mod profile;
pub mod scaling;
pub mod shield;
pub mod shield_log;
pub mod spline;
pub mod trajectory;

pub use chunk::{ActionKind, Chunk, OutOfLimits, Waypoints};
pub use error::{FailsafeError, TrajectoryError};
pub use failsafe::Failsafe;
pub use intended::{Method, Planner, PlannerConfig};
pub use monitored::Monitored;
pub use profile::{LIMIT_REL_TOL, Piece, Range};
pub use trajectory::{Bounds, EndCondition, JointState, Limits, Trajectory};
