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

/// Stubs for `#[kani::stub]` (`harness!(…, stub = (f => g), …)`): each over-approximates the
/// function it replaces, so a claim proved with the stub holds for the function.
#[cfg(kani)]
pub mod stubs {
    /// Any non-negative finite value below 1e160 for a positive finite `x`, else IEEE `√`'s
    /// result (`x` for ±0 and +∞, NaN below 0 and for NaN). Over-approximates IEEE `√` (and
    /// the contract of `pacs_reach::ieee::sqrt`): the square root of a positive finite double
    /// is a positive double below √MAX ≈ 1.34e154. For claims that hold whatever value the
    /// square root takes (e1's rest claims: the last phase is set to the target whatever the
    /// ramp lengths are), it spares the solver the contract's two exact 53-bit squares.
    pub fn sqrt_any_nonneg(x: f64) -> f64 {
        if x.is_nan() || x < 0.0 {
            return f64::NAN;
        }
        if x == 0.0 || x == f64::INFINITY {
            return x;
        }
        let r: f64 = kani::any();
        kani::assume(r >= 0.0 && r < 1.0e160);
        r
    }
}
