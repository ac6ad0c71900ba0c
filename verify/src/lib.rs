//! Verification.
pub mod audit;
