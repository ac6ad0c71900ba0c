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

/// Whether every field of `p` is finite: the range in which `stubs::any_speed_profile`
/// over-approximates the planner (checked by f1's twin for every profile it plans).
pub fn profile_in_stub_range(p: &pacs_motion::scaling::SpeedProfile) -> bool {
    let (phases, _, settle, target, acc, jerk) = p.to_parts();
    phases
        .iter()
        .all(|&(a, b, c, d, e)| [a, b, c, d, e].into_iter().all(f64::is_finite))
        && [settle, target, acc, jerk].into_iter().all(f64::is_finite)
}

/// The range `[x(1 − 1e-12) − 1e-300, x(1 + 1e-12) + 1e-300]` (each end rounded to nearest) in
/// which `stubs::sqrt_by_square` keeps the rounded square `fl(r·r)` of the root `r` it draws for a
/// positive finite `x`. It contains `fl(fl(√x)²)` for IEEE `√`: `fl(√x) = √x(1 + δ)` with
/// `|δ| ≤ 2⁻⁵³`, so its square is `x(1 + δ)²` within `2.3e-16·x` of `x`, and rounding the
/// product adds at most `1.2e-16` relative, or `2⁻¹⁰⁷⁴` absolute when it underflows; both ends
/// carry at least `1e-12·x`/`1e-300` of slack, far above these and above their own rounding
/// (monotone rounding keeps `fl(x(1 − 1e-12)) ≤ x − 2.3e-16·x`). Near overflow the square may
/// round to +∞, and the upper end `fl(x(1 + 1e-12))` is then +∞ too. Checked against the
/// library's `√` by `tests::sqrt_meets_the_square_stub`.
pub fn sqrt_square_range(x: f64) -> (f64, f64) {
    (x * (1.0 - 1e-12) - 1e-300, x * (1.0 + 1e-12) + 1e-300)
}

/// Stubs for `#[kani::stub]` (`harness!(…, stub = (f => g), …)`): each over-approximates the
/// function it replaces, so a claim proved with the stub holds for the function.
#[cfg(kani)]
pub mod stubs {
    /// Any speed profile of 1 to 4 phases whose every field is a finite float, whatever the
    /// arguments. Over-approximates `SpeedProfile::plan` wherever the planner's profiles are
    /// finite, which the twin of f1 checks for every profile it plans
    /// (`profile_in_stub_range`). For claims that hold for every profile (f1: `choose` only
    /// copies the profiles it is given, and the claims compare bit patterns), it removes the
    /// planner from the formula. Finite: a NaN has no fixed bit pattern in the SMT encoding
    /// (`proofs/smt/bitwuzla_cli.py`), which would make bitwise claims fail spuriously.
    pub fn any_speed_profile(
        _start: pacs_motion::scaling::PathState,
        _target: f64,
        _acc: f64,
        _jerk: f64,
    ) -> pacs_motion::scaling::SpeedProfile {
        let n: usize = kani::any();
        kani::assume((1..=4).contains(&n));
        let field = || {
            let x: f64 = kani::any();
            kani::assume(x.is_finite());
            x
        };
        let phase = || (field(), field(), field(), field(), field());
        let phases = [phase(), phase(), phase(), phase()];
        pacs_motion::scaling::SpeedProfile::from_parts(
            phases,
            n,
            field(),
            field(),
            field(),
            field(),
        )
    }

    /// Any finite `r ≥ 0` whose rounded square `fl(r·r)` lies in [`crate::sqrt_square_range`]`(x)`
    /// for a positive finite `x`, else IEEE `√`'s result (`x` for ±0 and +∞, NaN below 0 and for
    /// NaN). Over-approximates IEEE `√` (the range contains `fl(fl(√x)²)`:
    /// `sqrt_square_range`'s doc and test) with one multiplier instead of the exact contract of
    /// `pacs_reach::ieee::sqrt`, and, unlike a stub of any value in `[0, x + 1]`,
    /// ties the root to `x` within 1e-12 relative, which claims on the planner's ramps need (e1: the last ramp
    /// brings s̈ back to 0 only if the peak s̈ is at least the start's).
    pub fn sqrt_by_square(x: f64) -> f64 {
        if x.is_nan() || x < 0.0 {
            return f64::NAN;
        }
        if x == 0.0 || x == f64::INFINITY {
            return x;
        }
        let (lo, hi) = crate::sqrt_square_range(x);
        let r: f64 = kani::any();
        kani::assume(r >= 0.0 && r.is_finite());
        let rr = r * r;
        kani::assume(rr >= lo && rr <= hi);
        r
    }
}

#[cfg(test)]
mod tests {
    /// IEEE `√` of every argument below meets `stubs::sqrt_by_square`'s constraint: its
    /// rounded square lies in [`crate::sqrt_square_range`].
    #[test]
    fn sqrt_meets_the_square_stub() {
        let mut random = crate::RandomSource::new("sqrt_square_range", 0);
        let mut xs = vec![
            f64::MIN_POSITIVE,
            5e-324,
            1e-310,
            1.0,
            2.0,
            0.25,
            f64::MAX,
            1e300,
            1e-300,
        ];
        for _ in 0..200_000 {
            let bits = random.next_u64() & 0x7fef_ffff_ffff_ffff;
            let x = f64::from_bits(bits);
            let r = f64::from_bits(random.next_u64() >> 12 | 0x3ff0_0000_0000_0000);
            xs.extend([x, r * r, (r * r).next_up(), (r * r).next_down()]);
        }
        for x in xs.into_iter().filter(|x| x.is_finite() && *x > 0.0) {
            let (lo, hi) = crate::sqrt_square_range(x);
            let r = pacs_reach::ieee::sqrt(x);
            let rr = r * r;
            assert!(
                r >= 0.0 && lo <= rr && rr <= hi,
                "√{x} = {r}: r² = {rr} outside [{lo}, {hi}]"
            );
        }
    }
}
