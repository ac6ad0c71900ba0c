//! The IEEE 754 operations beyond `+ − × ÷` that sound bounds rely on: `√`, fused multiply-add,
//! `sin`/`cos`.
//!
//! Every sound function of pacs calls these instead of `f64::sqrt`, `f64::mul_add` and
//! `f64::sin_cos`, so that a model checker sees each of them through its contract:
//!
//! - In normal builds they are the library functions (no overhead: `#[inline(always)]`).
//! - Under Kani (`cfg(kani)`) each returns a nondeterministic value constrained only by the
//!   contract below. CBMC models `+ − × ÷` bit-exactly but not `√` (its model is not exact) and
//!   over-approximates `fma`, `sin` and `cos`; a proof over the contract holds for every function
//!   that meets it, in particular for the real one. A contract is *sound* if the real function
//!   always meets it; each is checked against the real function by a test in this module
//!   (`contracts_hold_for_the_library`, 10⁶ arguments each, biased to hard cases).
//!
//! The contracts:
//! - [`sqrt`] (IEEE 754 correctly rounded): for `x > 0` finite the result `r` satisfies
//!   `prev(r)² ≤ x ≤ next(r)²` exactly (decided by [`crate::exact::cmp_sqrt`]); for `x = ±0`,
//!   `+∞`, `x < 0` and NaN the IEEE results (`x`, `+∞`, NaN, NaN). This is looser than correct
//!   rounding (within one ulp instead of half), so every bound proved with it holds for IEEE `√`.
//! - [`mul_add`]: `a·b + c` rounded once (hardware FMA) or twice (`fl(fl(a·b) + c)`); the code
//!   that uses it is analysed for two roundings, so under Kani it is `fl(fl(a·b) + c)`, which
//!   CBMC models exactly.
//! - [`sin_cos`]: both values in `[−1, 1]` (libm's accuracy, 1 ulp on the reduced range, is not
//!   part of the contract; claims that need it leave it to the property tests, see
//!   `proofs/README.md`, claim C1).

/// `√x` (see the module doc for the contract under Kani).
#[cfg(not(kani))]
#[inline(always)]
pub fn sqrt(x: f64) -> f64 {
    x.sqrt()
}

/// `√x` under Kani: a nondeterministic `r` with `prev(r)² ≤ x ≤ next(r)²` (exactly, on integer
/// significands: [`crate::exact::cmp_sqrt`], which neither overflows nor underflows).
#[cfg(kani)]
pub fn sqrt(x: f64) -> f64 {
    any_root(x)
}

/// The body of [`sqrt`] under Kani, callable from stubs that replace `sqrt` (a stub cannot call
/// the function it replaces).
#[cfg(kani)]
pub fn any_root(x: f64) -> f64 {
    if x.is_nan() || x < 0.0 {
        return f64::NAN;
    }
    if x == 0.0 || x == f64::INFINITY {
        return x;
    }
    // √MAX ≈ 1.34e154: the bound keeps next(r) finite.
    let r: f64 = kani::any();
    kani::assume(r > 0.0 && r < 1.0e160);
    kani::assume(sqrt_contract(x, r));
    r
}

/// A `√` stub for claims that need only a root that is not too small (a norm bounded from above,
/// a divisor that must not shrink a gap): for `x ≥ 2⁻⁹⁰⁰` finite any finite `r ≥ 0` with
/// `fl(r·r) ≥ fl(x·(1 − 2⁻⁵⁰))` ([`root_not_below_holds`]), one multiplier instead of
/// [`sqrt`]'s exact contract; [`any_root`] for every other `x`. Over-approximates IEEE `√`: its
/// root `r₀ = fl(√x)` has `r₀ ≥ √x(1 − u)`, so `fl(r₀²) ≥ x(1 − 2u)(1 − u) ≥ x(1 − 3u)`, while
/// `fl(x(1 − 2⁻⁵⁰)) ≤ x(1 − 8u)(1 + u) < x(1 − 3u)` (`u = 2⁻⁵³`; no underflow above 2⁻⁹⁰⁰);
/// tested against the library by `contracts_hold_for_the_library`. Used with `#[kani::stub]`
/// by `b4_distance_bound_shared_point`.
#[cfg(kani)]
pub fn root_not_below(x: f64) -> f64 {
    if !(x >= ROOT_NOT_BELOW_FROM && x.is_finite()) {
        return any_root(x);
    }
    let r: f64 = kani::any();
    kani::assume(root_not_below_holds(x, r));
    r
}

/// Where [`root_not_below`]'s one-multiplier constraint starts (`2⁻⁹⁰⁰`).
pub const ROOT_NOT_BELOW_FROM: f64 = f64::from_bits((1023 - 900) << 52);

/// [`root_not_below`]'s constraint on `r` for `x` in `[2⁻⁹⁰⁰, MAX]`: `r ≥ 0` finite and
/// `fl(r·r) ≥ fl(x·(1 − 2⁻⁵⁰))`.
pub fn root_not_below_holds(x: f64, r: f64) -> bool {
    const SHRINK: f64 = 1.0 - 1.0 / (1u64 << 50) as f64;
    r >= 0.0 && r.is_finite() && r * r >= x * SHRINK
}

/// The contract of [`sqrt`] for `x > 0` finite and `r` with finite neighbours:
/// `prev(r)² ≤ x ≤ next(r)²` exactly.
pub fn sqrt_contract(x: f64, r: f64) -> bool {
    use crate::exact::cmp_sqrt;
    use std::cmp::Ordering::{Greater, Less};
    r >= 0.0 && cmp_sqrt(x, r.next_down()) != Less && cmp_sqrt(x, r.next_up()) != Greater
}

/// `a·b + c`: the hardware's fused multiply-add where the build has one, else two roundings.
/// Callers' error analyses allow for two roundings (module doc).
#[cfg(not(kani))]
#[inline(always)]
pub fn mul_add(a: f64, b: f64, c: f64) -> f64 {
    if cfg!(target_feature = "fma") {
        a.mul_add(b, c)
    } else {
        a * b + c
    }
}

/// `a·b + c` under Kani: two correctly rounded operations (module doc).
#[cfg(kani)]
#[inline(always)]
pub fn mul_add(a: f64, b: f64, c: f64) -> f64 {
    a * b + c
}

/// `(sin x, cos x)` from libm.
#[cfg(not(kani))]
#[inline(always)]
pub fn sin_cos(x: f64) -> (f64, f64) {
    x.sin_cos()
}

/// `(sin x, cos x)` under Kani: any two values in `[−1, 1]` (NaN for non-finite `x`).
#[cfg(kani)]
pub fn sin_cos(x: f64) -> (f64, f64) {
    if !x.is_finite() {
        return (f64::NAN, f64::NAN);
    }
    let s: f64 = kani::any();
    let c: f64 = kani::any();
    kani::assume((-1.0..=1.0).contains(&s) && (-1.0..=1.0).contains(&c));
    (s, c)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A float biased to hard cases: every exponent, mantissas near powers of two, squares of
    /// floats and their neighbours (where `√` is exact or nearly a tie).
    fn arg(state: &mut u64) -> f64 {
        *state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let z = *state;
        let e = ((z >> 40) % 2000) as i32 - 1000;
        let m = match z % 4 {
            0 => 1.0,
            1 => 2f64.next_down(),
            _ => 1.0 + (z >> 11) as f64 / (1u64 << 53) as f64,
        };
        let v = m * 2f64.powi(e);
        match (z >> 20) % 4 {
            0 => v * v,
            1 => (v * v).next_up(),
            2 => (v * v).next_down(),
            _ => v,
        }
    }

    #[test]
    fn contracts_hold_for_the_library() {
        let mut state = 7u64;
        for _ in 0..1_000_000 {
            let x = arg(&mut state);
            if x > 0.0 && x.is_finite() && (1e-150..=1e150).contains(&x) {
                assert!(sqrt_contract(x, x.sqrt()), "sqrt({x:e}) = {:e}", x.sqrt());
            }
            if x >= ROOT_NOT_BELOW_FROM && x.is_finite() {
                assert!(
                    root_not_below_holds(x, x.sqrt()),
                    "root_not_below({x:e}) misses {:e}",
                    x.sqrt()
                );
            }
            let (s, c) = sin_cos(x);
            if x.is_finite() {
                assert!(
                    (-1.0..=1.0).contains(&s) && (-1.0..=1.0).contains(&c),
                    "{x}"
                );
            }
        }
        // The stub's constraint is not vacuous: a root 2⁻⁴⁹ too small fails it.
        for x in [2.0, 3.0, 1e-200, ROOT_NOT_BELOW_FROM, f64::MAX] {
            assert!(!root_not_below_holds(
                x,
                x.sqrt() * (1.0 - 1.0 / (1u64 << 49) as f64)
            ));
        }
        // The contract is not vacuous: two ulps off fails it.
        assert!(!sqrt_contract(2.0, 2f64.sqrt().next_up().next_up()));
        assert!(!sqrt_contract(2.0, 2f64.sqrt().next_down().next_down()));
        assert_eq!(sqrt(4.0), 2.0);
        assert_eq!(mul_add(2.0, 3.0, 1.0), 7.0);
    }
}
