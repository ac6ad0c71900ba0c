//! The harnesses, grouped by claim (see `proofs/README.md`).

// Bodies of twin-only harnesses (and their helpers) are used by the property tests only.
#![cfg_attr(kani, allow(dead_code))]

pub mod audit;
pub mod enclosure;
pub mod energy;
pub mod geometry;
pub mod human;
pub mod object;
pub mod profile;
pub mod robot;
pub mod rule;
pub mod shield;
pub mod solver;
