//! The harnesses, grouped by claim (see `proofs/README.md`).

pub mod audit;
pub mod enclosure;
pub mod energy;
pub mod geometry;
pub mod human;
pub mod object;
pub mod profile;
pub mod robot;
pub mod rounding;
pub mod rule;
pub mod shield;
