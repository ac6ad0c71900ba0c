//! The harnesses, grouped by claim (see `proofs/README.md`).

mod energy;
mod geometry;
mod human;
mod profile;
mod robot;
mod rounding;
mod shield;
