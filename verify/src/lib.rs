//! # pacs-verify
//!
//! The safety checks of PACS: the one ISO/TS 15066 rule, the online filters that apply it, and the
//! offline audit that applies it to logged runs:
//! - [`iso15066`]: the one ISO/TS 15066 rule (SSM, PFL, clamping) for one time interval, called by
//!   the shield and the audit;
//! - [`shield`]: the PACS online safety shield (OFF and single-action by configuration);
//! - [`cbf`]: the control-barrier-function baseline;
//! - [`shield_log`]: a shield run written as an audit log;
//! - [`audit`]: the log format v1 (readers, writer) and the offline checker;
//! - [`bench`]: reproducible timing scenarios for `pacs bench`.
//!
//! Motion (chunks, intended trajectories, path-speed scaling, braking) lives in `pacs-motion`.
//! Units: rad, rad/s, rad/s², rad/s³, seconds, m, J.

// Joint loops index several fixed-size per-joint arrays at once; index loops read clearer.
#![allow(clippy::needless_range_loop)]

pub mod audit;
pub mod bench;
pub mod cbf;
pub mod iso15066;
pub mod shield;
pub mod shield_log;
