//! # pacs-shield
//!
//! The online filters between a chunking policy and the robot:
//! - [`shield`]: the PACS shield (paper Algorithm 1; OFF and single-action by configuration):
//!   every safety step a monitored trajectory (one intended step, then braking along the same
//!   path) is verified with the one ISO/TS 15066 rule (`pacs_verify::iso15066`);
//! - [`chunk_motion`]: whether chunks end at rest or pass their last waypoint moving;
//! - [`replan`]: the one re-plan policy for a chunk whose hand-over failed;
//! - [`session`]: what every runner shares: a [`Session`] (one run: timed measurements delivered
//!   at the first safety step at or after their arrival, to the shield and the log; steps on the
//!   safety-step grid; chunks) and the [`PacedHandover`] of chunks while a real-time loop steps it;
//! - [`settings`]: shield settings as users write them (scene files, the Python package);
//! - [`shield_log`]: a shield run written as an audit log (`pacs-log` format v1);
//! - [`worker`]: a planning thread that keeps chunk planning out of a real-time loop.
//!
//! The baselines (CBF, the filter kinds behind one trait) and the bench scenarios are in
//! `pacs-baselines`.
//!
//! Units: rad, rad/s, rad/s², rad/s³, s, m, J.

// Joint loops index several fixed-size per-joint arrays at once; index loops read clearer.
#![allow(clippy::needless_range_loop)]

pub mod chunk_motion;
pub mod replan;
pub mod session;
pub mod settings;
pub mod shield;
pub mod shield_log;
pub mod worker;

pub use chunk_motion::ChunkMotion;
pub use replan::ReplanPolicy;
pub use session::{
    Due, InboxError, MeasurementInbox, MeasurementSink, PacedHandover, Session, SessionError,
};
pub use settings::ShieldSettings;
pub use shield::{
    Binding, Command, Diagnostics, FilterMode, Shield, ShieldBuilder, ShieldConfig, ShieldError,
};
pub use shield_log::ShieldLog;
pub use worker::ChunkWorker;
