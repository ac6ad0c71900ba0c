//! # pacs-baselines
//!
//! What the PACS shield (`pacs-shield`) is compared with and timed on, kept out of the safety
//! crate:
//! - [`cbf`]: the control-barrier-function baseline (a QP per step, clarabel);
//! - [`filter`]: PACS, OFF, single-action, direct and CBF as kinds of one
//!   [`filter::SafetyFilter`] (what the simulation runs);
//! - [`mod@bench`]: reproducible timing scenarios for `pacs bench`.
//!
//! Units: rad, rad/s, rad/s², rad/s³, s, m, J.

// Joint loops index several fixed-size per-joint arrays at once; index loops read clearer.
#![allow(clippy::needless_range_loop)]

pub mod bench;
pub mod cbf;
pub mod filter;

pub use filter::{FilterKind, SafetyFilter};
