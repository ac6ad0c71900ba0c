//! # pacs-verify
//!
//! The one ISO/TS 15066 rule of pacs ([`iso15066`]): the SSM/PFL decision for one time interval —
//! contact between the robot's link occupancies and the body parts' occupancies, the robot at
//! rest or not, the whole robot's kinetic-energy bound against the body part's threshold, and the
//! clamping classification — with its soundness statement and harness. The online filters
//! (`pacs-shield`) and the offline audit (`pacs-audit`) both call it; there is no other copy.
//!
//! Units: m, rad/s, J.

pub mod iso15066;

pub use iso15066::{
    ConstraintKind, ContactRule, EnvShape, Judgement, ObjectOutcome, ObjectRule, ObjectViolation,
    Outcome, PairViolation, RuleError,
};
