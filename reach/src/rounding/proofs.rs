//! Proofs of the rounding helpers, beside them (claim C1: every rounding helper encloses the
//! exact result). Each harness is one body, emitted by [`harness!`] as a Kani proof
//! (`cargo kani -p pacs-reach --lib --harness NAME`) and as a seeded property test (`cargo test -p
//! pacs-reach`), decided against the exact oracles of [`crate::exact`]. Results, widths and
//! splits: `proofs/README.md`.

// Proof functions are entry points of the model checker, not called from the crate.
#![cfg_attr(kani, allow(dead_code))]
use super::*;
use crate::exact::{cmp_prod, cmp_quot, cmp_sqrt, cmp_sum, dist3_le, norm3_ge, norm3_le, tame};
use crate::interval::Interval;
use pacs_proof_kit::{Source, harness};
use std::cmp::Ordering::{Greater, Less};

/// A tame float in [-1e6, 1e6] (0 or magnitude ≥ 1e-100: see [`crate::exact`]).
pub(crate) fn num<S: Source>(s: &mut S, m: f64) -> Option<f64> {
    let x = s.f64_in(-m, m);
    s.assume(tame(x)).then_some(x)
}

/// add up/down bound the exact sum.
fn add<S: Source>(s: &mut S) {
    let (Some(x), Some(y)) = (num(s, 1e6), num(s, 1e6)) else {
        return;
    };
    assert!(cmp_sum(x, y, add_up(x, y)) != Greater, "add_up({x}, {y})");
    assert!(cmp_sum(x, y, add_down(x, y)) != Less, "add_down({x}, {y})");
}
harness!(
    a1_add_enclose,
    unwind = 2,
    bits = 27,
    cases = pacs_proof_kit::DEFAULT_CASES,
    add
);

/// sub up/down bound the exact difference.
fn sub<S: Source>(s: &mut S) {
    let (Some(x), Some(y)) = (num(s, 1e6), num(s, 1e6)) else {
        return;
    };
    assert!(cmp_sum(x, -y, sub_up(x, y)) != Greater, "sub_up({x}, {y})");
    assert!(cmp_sum(x, -y, sub_down(x, y)) != Less, "sub_down({x}, {y})");
}
harness!(
    a1_sub_enclose,
    unwind = 2,
    bits = 27,
    cases = pacs_proof_kit::DEFAULT_CASES,
    sub
);

/// `x` with the harness width (every float for a2), `y` with at most 6 significand bits under
/// Kani: products and quotients of such a pair still round (an exact product needs at most
/// 53 significant bits; a 53-bit `x` times a 6-bit `y` has up to 59), which is what the claim
/// is about (with a 16-bit `x` every product would be exact and the proof vacuous: mutant `x14`
/// survived that width). Any pair in the property test.
fn operands<S: Source>(s: &mut S) -> Option<(f64, f64)> {
    let x = num(s, 1e6)?;
    let y = s.f64_short(-1e6, 1e6, 6);
    s.assume(tame(y)).then_some((x, y))
}

/// mul up/down bound the exact product.
fn mul<S: Source>(s: &mut S) {
    let Some((x, y)) = operands(s) else { return };
    assert!(cmp_prod(x, y, mul_up(x, y)) != Greater, "mul_up({x}, {y})");
    assert!(cmp_prod(x, y, mul_down(x, y)) != Less, "mul_down({x}, {y})");
}
harness!(
    a2_mul_enclose,
    unwind = 2,
    bits = 52,
    cases = pacs_proof_kit::DEFAULT_CASES,
    mul
);

/// div up/down bound the exact quotient.
fn div<S: Source>(s: &mut S) {
    let Some((x, y)) = operands(s) else { return };
    if y != 0.0 {
        assert!(cmp_quot(x, y, div_up(x, y)) != Greater, "div_up({x}, {y})");
        assert!(cmp_quot(x, y, div_down(x, y)) != Less, "div_down({x}, {y})");
    }
}
harness!(
    a2_div_enclose,
    unwind = 2,
    bits = 8,
    cases = pacs_proof_kit::DEFAULT_CASES,
    div
);

/// sqrt up/down bound the exact square root (under Kani: of any value meeting the IEEE contract
/// of `pacs_reach::ieee::sqrt`).
fn sqrt<S: Source>(s: &mut S) {
    let Some(x) = num(s, 1e6) else { return };
    let a = x.abs();
    assert!(cmp_sqrt(a, sqrt_up(a)) != Greater, "sqrt_up({a})");
    assert!(cmp_sqrt(a, sqrt_down(a)) != Less, "sqrt_down({a})");
}
harness!(
    a2_sqrt_enclose,
    unwind = 2,
    bits = 20,
    cases = pacs_proof_kit::DEFAULT_CASES,
    sqrt
);

/// A vector with tame coordinates in [−m, m].
fn vector<S: Source>(s: &mut S, m: f64) -> Option<[f64; 3]> {
    Some([num(s, m)?, num(s, m)?, num(s, m)?])
}

/// norm3_up bounds the exact Euclidean norm from above.
fn norm_up<S: Source>(s: &mut S) {
    let Some([x, y, z]) = vector(s, 1e6) else {
        return;
    };
    assert!(
        norm3_le(x, y, z, norm3_up(x, y, z)),
        "norm3_up({x}, {y}, {z})"
    );
}
harness!(
    a3_norm_up_encloses,
    unwind = 25,
    bits = 8,
    cases = pacs_proof_kit::DEFAULT_CASES,
    norm_up
);

/// norm3_down bounds the exact Euclidean norm from below.
fn norm_down<S: Source>(s: &mut S) {
    let Some([x, y, z]) = vector(s, 1e6) else {
        return;
    };
    assert!(
        norm3_ge(x, y, z, norm3_down(x, y, z)),
        "norm3_down({x}, {y}, {z})"
    );
}
harness!(
    a3_norm_down_encloses,
    unwind = 25,
    bits = 8,
    cases = pacs_proof_kit::DEFAULT_CASES,
    norm_down
);

/// dist3_up bounds the exact distance of two points from above.
fn dist_up<S: Source>(s: &mut S) {
    let (Some(a), Some(b)) = (vector(s, 1e3), vector(s, 1e3)) else {
        return;
    };
    assert!(dist3_le(&a, &b, dist3_up(&a, &b)), "dist3_up({a:?}, {b:?})");
}
harness!(
    a3_dist_up_encloses,
    unwind = 25,
    bits = 6,
    cases = pacs_proof_kit::DEFAULT_CASES,
    dist_up
);

/// Documented bound of libm `sin`/`cos` error (1 ulp on [-1, 1] ≤ 1.12e-16; see
/// `reach::rounding`, whose test checks libm against a rigorous Taylor enclosure).
const LIBM_ERR: f64 = 1.12e-16;

/// `sin_cos_interval(lo, hi)` contains sin x and cos x for every x in [lo, hi].
///
/// Split: under Kani, libm's `sin`/`cos` are only known to lie in `[−1, 1]` (the contract of
/// `pacs_reach::ieee::sin_cos`), so the proof checks the part of the argument that does not rest
/// on libm's accuracy: every critical point `kπ/2` that may lie in `[lo, hi]` (any point of its
/// enclosure `k·[π/2]`) switches on the matching extremum (±1 for sin or cos), and both intervals
/// are within `[−1, 1]`. The property test checks that too, and the whole claim against libm (whose accuracy
/// within [`LIBM_ERR`] reach tests against a rigorous Taylor enclosure).
fn sin_cos<S: Source>(s: &mut S) {
    let lo = s.f64_in(-7.0, 7.0);
    let w = s.f64_in(0.0, 7.0);
    let hi = lo + w;
    let (si, ci) = sin_cos_interval(lo, hi);
    for iv in [si, ci] {
        assert!(-1.0 <= iv.lo() && iv.lo() <= iv.hi() && iv.hi() <= 1.0);
    }
    // A degenerate interval `lo == hi` returns libm's values, padded: that they reach an
    // extremum at a critical point (cos 0 = 1 ⇒ the upper end is clamped to 1) rests on libm's
    // accuracy, which the Kani contract does not state (any value in [−1, 1]); with the point
    // case included Kani reported "cos max … missed" (e.g. `lo = hi = 0` with a contract value of
    // `cos 0` below 1 − 1e-14). Under Kani the critical-point claim is therefore made for
    // `lo < hi`; the twin checks both against libm.
    if !(cfg!(kani) && lo == hi) {
        // A point of the enclosure of kπ/2 inside [lo, hi] (the true kπ/2 is one such point).
        let k = s.index(12) as i64 - 6;
        let half_pi = Interval::new(
            std::f64::consts::FRAC_PI_2.next_down(),
            std::f64::consts::FRAC_PI_2.next_up(),
        )
        .expect("valid");
        let p = half_pi.scale(k as f64);
        // Full width: with the harness's 3 bits no float lies within an ulp of kπ/2 (k ≠ 0),
        // and the claim would be vacuous there (mutant `x4` survived that).
        let x = s.f64_full(p.lo(), p.hi());
        if lo <= x && x <= hi {
            match k.rem_euclid(4) {
                0 => assert!(ci.hi() == 1.0, "cos max at {k}π/2 ∈ [{lo}, {hi}] missed"),
                1 => assert!(si.hi() == 1.0, "sin max at {k}π/2 ∈ [{lo}, {hi}] missed"),
                2 => assert!(ci.lo() == -1.0, "cos min at {k}π/2 ∈ [{lo}, {hi}] missed"),
                _ => assert!(si.lo() == -1.0, "sin min at {k}π/2 ∈ [{lo}, {hi}] missed"),
            }
        }
    }
    if !cfg!(kani) {
        let x = s.f64_in(lo, hi);
        let (sx, cx) = x.sin_cos();
        for (iv, v, what) in [(si, sx, "sin"), (ci, cx, "cos")] {
            assert!(
                iv.lo() <= (v - LIBM_ERR).max(-1.0) && (v + LIBM_ERR).min(1.0) <= iv.hi(),
                "{what}({x}) = {v} ∉ {iv:?} for [{lo}, {hi}]"
            );
        }
    }
}
harness!(
    a5_sin_cos_interval_encloses,
    unwind = 12,
    bits = 3,
    cases = pacs_proof_kit::DEFAULT_CASES,
    sin_cos
);
