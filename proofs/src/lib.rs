//! # pacs-proofs
//!
//! Proof harnesses for the safety argument of pacs (see `proofs/README.md`): the harnesses of
//! compositions (occupancies, the rule, the shield, the audit). Harnesses of single functions sit
//! beside their function (`pacs_reach::rounding`, `pacs_reach::interval`). All are written with
//! the kit of [`pacs_proof_kit`]: a body generic over a [`Source`], emitted by [`harness!`] as a
//! Kani proof (`cfg(kani)`) and as a seeded property test (`cfg(test)`).
//!
//! [`exact`] holds the exact-arithmetic oracles the harnesses compare against (error-free
//! transformations and integer significands, no interval library, no FMA), usable under Kani.

/// The exact oracles live beside the code whose contracts they decide (`pacs_reach::exact`).
pub use pacs_reach::exact;

#[cfg(kani)]
pub use pacs_proof_kit::KaniSource;
pub use pacs_proof_kit::{DEFAULT_CASES, RandomSource, Source, harness, run_cases};

#[cfg(any(test, kani))]
pub mod harnesses;
