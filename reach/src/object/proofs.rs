//! Proof of the time-interval enclosure of object occupancies, beside it (claim C4′, the part a
//! model checker can decide): for every `τ` in `[τ_a, τ_b]`, the exact `p + τ v + (τ²/2) c_u` lies
//! in `centre ± (|g_s| + |g_t| + err)` of [`curve_enclosure`] after [`time_split`] (one axis; in
//! one dimension the zonotope is exactly that interval).
//!
//! Inputs on dyadic grids (`τ = i/2⁸` s, `p = j/2⁸` m, `v = k/2⁶` m/s, `c_u = l/2⁴` m/s²), small
//! enough that the exact value is a float computed without rounding, so the claim is checked
//! against the real number itself. The end-to-end claim over sampled 3-D motions, shapes, speed
//! bounds and the distance test is the property test `j1_object_occupancy_contains_motion`.

// Proof functions are entry points of the model checker, not called from the crate.
#![cfg_attr(kani, allow(dead_code))]

use super::*;
use pacs_proof_kit::{Source, harness};

/// `n / 2^shift` for an integer `n` in `[−max, max]` (`signed`) or `[0, max]`.
fn grid<S: Source>(s: &mut S, max: usize, shift: i32, signed: bool) -> f64 {
    let n = s.index(max + 1) as f64;
    // 2^−shift from its bits (no `powi`: an LLVM intrinsic the model checker lacks).
    let x = n * f64::from_bits(((1023 - shift) as u64) << 52);
    if signed && s.bool() { -x } else { x }
}

fn curve<S: Source>(s: &mut S) {
    // Under Kani 4-bit grids (every product a narrow multiplier); the twin 8 to 12 bits.
    let (big, small) = if cfg!(kani) { (16, 16) } else { (4096, 1024) };
    let tau_a = grid(s, small, 8, false); // [0, 4] s (Kani: [0, 1/16])
    let width = grid(s, small / 4, 8, false); // [0, 1] s
    let tau_b = tau_a + width;
    let tau = tau_a + grid(s, small / 4, 8, false);
    if !s.assume(tau <= tau_b) {
        return;
    }
    let p = grid(s, big, 8, true); // ±16 m
    let v = grid(s, small, 6, true); // ±16 m/s
    let c_u = grid(s, small, 4, true); // ±64 m/s²
    // Exact: every term is a multiple of 2⁻²¹ below 2³¹ in magnitude.
    let exact = p + tau * v + tau * tau * c_u * 0.5;
    let (tau_m, h) = time_split(tau_a, tau_b);
    let (c, g_s, g_t, err) = curve_enclosure(p, v, c_u, tau_m, h);
    let r = add_up(add_up(g_s.abs(), g_t.abs()), err);
    assert!(
        sub_down(c, r) <= exact && exact <= add_up(c, r),
        "p + τv + τ²c_u/2 = {exact} at τ = {tau} ∉ {c} ± {r} over [{tau_a}, {tau_b}]"
    );
}
harness!(
    j2_object_curve_encloses,
    unwind = 2,
    cases = pacs_proof_kit::DEFAULT_CASES,
    curve
);
