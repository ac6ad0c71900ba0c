//! # pacs-reach
//!
//! Sound reachability: every set here contains what it claims to contain, under outward rounding.
//! - [`rounding`]: directed-rounding scalar helpers and rigorous sin/cos enclosures;
//! - [`ieee`]: `√`, FMA, sin/cos as the sound code calls them (contracts under Kani);
//! - [`exact`]: exact comparisons of float expressions (error-free transformations), the oracles
//!   of the harnesses and of the contracts;
//! - [`interval`]: a fast outward-rounded interval type (checked against `inari` in tests);
//! - [`zonotope`]: zonotopes and reachability of linear time-invariant systems;
//! - [`geometry`]: conservative capsule/sphere/zonotope intersection and distance bounds;
//! - [`human`]: human reachable occupancies (SaRA-style pos/vel/acc/combined models);
//! - [`joint_box`]: boxes of joint values, valid by construction (the input of every robot query);
//! - [`robot`]: robot reachable occupancies for joint boxes (interval forward kinematics).

pub mod error;
pub mod exact;
pub mod geometry;
pub mod human;
pub mod ieee;
pub mod interval;
pub mod joint_box;
pub mod lti;
pub mod object;
pub mod robot;
pub mod rounding;
pub mod stamped;
pub mod zonotope;

pub use error::ReachError;
pub use interval::Interval;
pub use joint_box::{JointBox, JointBoxError};
pub use stamped::{Stamped, stamp_supersedes, supersedes};
