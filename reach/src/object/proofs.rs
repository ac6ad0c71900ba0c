//! Proofs of the object occupancy's scalar steps, beside them (claim C4′, the parts a model
//! checker can decide):
//!
//! - `j2_object_curve_encloses` (Kani outside CI, over the budget: both terms on the splits'
//!   interval with `p = 0`; in CI the two splits below; the twin the grids below): for
//!   every `τ` in `[τ_a, τ_b]`, the exact `p + τ v + (τ²/2) c_u` lies in
//!   `centre ± (|g_s| + |g_t| + err)` of [`curve_enclosure`] after [`time_split`] (one axis; in
//!   one dimension the zonotope is exactly that interval). Inputs on dyadic grids (`τ = i/2⁸` s,
//!   `p = j/2⁸` m, `v = k/2⁶` m/s, `c_u = l/2⁴` m/s²), small enough that the exact value is a
//!   float computed without rounding, so the claim is checked against the real number itself.
//!   - `j2_object_curve_velocity`: the same claim with `c_u = 0` (constant velocity; under Kani
//!     `p = 0`, one time interval `[48/256, 112/256]` s, any `τ` of it and any `v` on the 4-bit
//!     grids);
//!   - `j2_object_curve_acceleration`: with `v = 0` (the quadratic term alone; under Kani as
//!     above with any `c_u`).
//!   Both with `Interval::scale` replaced by an over-approximation (`scale_point_or_outward`).
//!   The curve is linear in `(p, v, c_u)` and so is the exact algebra of the enclosure (module
//!   docs); both terms at once (the rounding of their sum) are the whole claim's (Kani on the
//!   same interval with `p = 0`, outside CI), other time intervals and `p` the twins'. Mutant `x17` (the chord generator `g_s` dropped) fails each split.
//! - `j1_object_time_and_balls` (split of `j1_object_occupancy_contains_motion`, whose twin in
//!   `pacs-proofs` samples whole 3-D motions, shapes and the distance test): for any measured
//!   time and any query `[t_a, t_b]` that `occupancy` accepts (`t_a ≥ t_m − δ` as it evaluates
//!   it), every instant `t` of it has its elapsed time `max(t − t_m + δ, 0)` in
//!   [`elapsed_range`]'s `[τ_a, τ_b]`, and the ball terms at that elapsed time are within the
//!   radii the occupancy uses ([`ball_radius`]: `e_p + τ e_v + a τ²/2 + r`; [`speed_radius`]:
//!   `e_p + v_max τ + r`). Under Kani the model's numbers are constants; the twin draws them.
//!   Mutant `x13` (the elapsed time without the delay) fails it.

// Proof functions are entry points of the model checker, not called from the crate.
#![cfg_attr(kani, allow(dead_code))]

use super::*;
use crate::rounding::{add_down, sub_down};
use pacs_proof_kit::{Source, harness};

/// `n / 2^shift` for an integer `n` in `[−max, max]` (`signed`) or `[0, max]`.
fn grid<S: Source>(s: &mut S, max: usize, shift: i32, signed: bool) -> f64 {
    let n = s.index(max + 1) as f64;
    // 2^−shift from its bits (no `powi`: an LLVM intrinsic the model checker lacks).
    let x = n * f64::from_bits(((1023 - shift) as u64) << 52);
    if signed && s.bool() { -x } else { x }
}

/// The terms of the curve a harness draws: the velocity, the acceleration or both (and `p`).
#[derive(Clone, Copy, PartialEq)]
enum Terms {
    Both,
    Velocity,
    Acceleration,
}

fn curve<S: Source>(s: &mut S) {
    curve_terms(s, Terms::Both);
}
fn curve_velocity<S: Source>(s: &mut S) {
    curve_terms(s, Terms::Velocity);
}
fn curve_acceleration<S: Source>(s: &mut S) {
    curve_terms(s, Terms::Acceleration);
}

fn curve_terms<S: Source>(s: &mut S, terms: Terms) {
    // Under Kani 4-bit grids (every product a narrow multiplier); the twin 8 to 12 bits.
    let (big, small) = if cfg!(kani) { (16, 16) } else { (4096, 1024) };
    let (tau_a, tau_b, tau) = if cfg!(kani) {
        // Under Kani one time interval, [48/256, 112/256] s (τ_m = 0.3125 s, h = 0.125 s),
        // and any τ of it on the grid of 1/256 s.
        let (tau_a, tau_b) = (0.1875, 0.4375);
        (tau_a, tau_b, tau_a + grid(s, 64, 8, false))
    } else {
        let tau_a = grid(s, small, 8, false); // [0, 4] s
        let width = grid(s, small / 4, 8, false); // [0, 1] s
        let tau = tau_a + grid(s, small / 4, 8, false);
        (tau_a, tau_a + width, tau)
    };
    if !s.assume(tau <= tau_b) {
        return;
    }
    // Under Kani p = 0 (p only shifts the centre); the twins draw it.
    let p = if cfg!(kani) {
        0.0
    } else {
        grid(s, big, 8, true) // ±16 m
    };
    let v = if terms == Terms::Acceleration {
        0.0
    } else {
        grid(s, small, 6, true) // ±16 m/s
    };
    let c_u = if terms == Terms::Velocity {
        0.0
    } else {
        grid(s, small, 4, true) // ±64 m/s²
    };
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
    bits = 52,
    stub = (crate::interval::Interval::scale => scale_point_or_outward),
    cases = pacs_proof_kit::DEFAULT_CASES,
    curve
);

/// [`Interval::scale`] under the j2 splits, an over-approximation (`-Z stubbing`): for a point
/// interval either the point product (what `scale` returns when its exact-product test holds:
/// `0` if a factor is 0, else the product) or the outward path (what it returns otherwise),
/// chosen by the model checker; for any other interval the outward path, as in `scale` line for
/// line. Every result `scale` gives is one of these, so a claim proved with the stub holds for
/// `scale`; it spares the solver `scale`'s exact test on integer significands (`Dyadic`: with
/// it, the velocity-free split timed out at 180 s with 639 checks), which the intervals of
/// `curve_enclosure` never reach (`product` is never a point: `mul_down < mul_up`).
#[cfg(kani)]
fn scale_point_or_outward(x: Interval, k: f64) -> Interval {
    let (lo, hi) = (x.lo(), x.hi());
    if lo == hi && kani::any() {
        return Interval::point(if lo == 0.0 || k == 0.0 { 0.0 } else { lo * k });
    }
    if (lo * k).is_nan() || (hi * k).is_nan() {
        return Interval::ENTIRE;
    }
    Interval::new(
        mul_down(lo, k).min(mul_down(hi, k)),
        mul_up(lo, k).max(mul_up(hi, k)),
    )
    .unwrap_or(Interval::ENTIRE)
}

harness!(
    j2_object_curve_velocity,
    unwind = 2,
    bits = 52,
    stub = (crate::interval::Interval::scale => scale_point_or_outward),
    cases = pacs_proof_kit::DEFAULT_CASES,
    curve_velocity
);
harness!(
    j2_object_curve_acceleration,
    unwind = 2,
    bits = 52,
    stub = (crate::interval::Interval::scale => scale_point_or_outward),
    cases = pacs_proof_kit::DEFAULT_CASES,
    curve_acceleration
);

fn time_and_balls<S: Source>(s: &mut S) {
    // (e_p, e_v, a, r, δ, v_max): dyadic constants under Kani near the largest of j1's twin's
    // ranges (with the grid below every elapsed time and ball term is then a float computed
    // exactly: the claims compare with the real number itself), any in the twin.
    let (e_p, e_v, a, r, delay, v_max) = if cfg!(kani) {
        (0.0625, 0.25, 5.0, 0.125, 0.0625, 3.0)
    } else {
        (
            s.f64_in(0.0, 0.05),
            s.f64_in(0.0, 0.3),
            s.f64_in(0.0, 5.0),
            s.f64_in(0.0, 0.2),
            s.f64_in(0.0, 0.1),
            s.f64_in(0.1, 3.0),
        )
    };
    let (time, t_a, t_b, t) = if cfg!(kani) {
        // The measurement at 127/16 s; the query's start up to 0.25 s after the measured state
        // and its width up to 0.25 s on a grid of 1/256 s (every elapsed time a multiple of
        // 2⁻⁸, computed exactly); `t` either end (the elapsed time is linear in `t` and the
        // ball terms grow with it: the ends are the extremes, exact arithmetic).
        let time = 7.9375;
        let t_a = (time - delay) + grid(s, 64, 8, false);
        let t_b = t_a + grid(s, 64, 8, false);
        (time, t_a, t_b, if s.bool() { t_a } else { t_b })
    } else {
        let time = s.f64_in(0.0, 10.0);
        let t_a = s.f64_in(time - delay, time + 0.3);
        let t_b = s.f64_in(t_a, t_a + 0.3);
        (time, t_a, t_b, s.f64_in(t_a, t_b))
    };
    // `occupancy`'s precondition, as it evaluates it (it rejects the query otherwise).
    if !s.assume(t_a >= time - delay) {
        return;
    }
    let (tau_a, tau_b) = elapsed_range(time, delay, t_a, t_b);
    // The exact max(t − time + δ, 0) under Kani (exact operations on the grid); bounds of it in
    // the twin (a1; `max` is monotone).
    let (lo, up) = if cfg!(kani) {
        let exact = ((t - time) + delay).max(0.0);
        (exact, exact)
    } else {
        (
            add_down(sub_down(t, time), delay).max(0.0),
            add_up(sub_up(t, time), delay).max(0.0),
        )
    };
    assert!(
        tau_a <= lo && up <= tau_b,
        "elapsed [{lo}, {up}] at t = {t} not in [{tau_a}, {tau_b}] (measured {time}, [{t_a}, {t_b}], delay {delay})"
    );
    // The ball terms at the exact elapsed time (≥ 0, ≤ up): exact under Kani, upper bounds in
    // the twin (a1, a2, monotone).
    let (ball, speed) = if cfg!(kani) {
        (
            (e_p + up * e_v) + (up * up * 0.5 * a + r),
            (e_p + v_max * up) + r,
        )
    } else {
        (
            add_up(
                add_up(e_p, mul_up(up, e_v)),
                add_up(mul_up(mul_up(mul_up(up, up), 0.5), a), r),
            ),
            add_up(add_up(e_p, mul_up(v_max, up)), r),
        )
    };
    let radius = ball_radius(e_p, e_v, a, r, tau_b);
    assert!(
        ball <= radius,
        "ball {ball} at t = {t} above the radius {radius}"
    );
    let speed_r = speed_radius(e_p, v_max, r, tau_b);
    assert!(
        speed <= speed_r,
        "speed ball {speed} at t = {t} above the radius {speed_r}"
    );
}
harness!(
    j1_object_time_and_balls,
    unwind = 2,
    bits = 8,
    cases = pacs_proof_kit::DEFAULT_CASES,
    time_and_balls
);

// ---------------------------------------------------------------------------------------------
// The claims of the radii (`ball_radius`, `speed_radius`): property tests. Their contracts'
// proofs (`proof_for_contract` over 8-bit symbolic floats of any exponent, as the human
// occupancy's radii) timed out at 300 s; the elapsed-time roundings are the human occupancy's,
// proven there (`c1_elapsed_lo_contract`, `c1_elapsed_hi_contract`), and so is the travel term
// `vel_radius` (`c1_vel_radius_contract`).

/// The radii's claims over random admitted floats (`human::draw_radius_input`), each radius'
/// claim checked.
#[cfg(test)]
#[test]
fn j1_radius_claims_hold() {
    pacs_proof_kit::run_cases("j1_radius_claims_hold", 20_000, |s| {
        let x = |s: &mut pacs_proof_kit::RandomSource| crate::human::draw_radius_input(s, false);
        let (e_p, e_v, a, r, tau) = (x(s), x(s), x(s), x(s), x(s));
        let out = ball_radius(e_p, e_v, a, r, tau);
        assert!(
            covers_ball(e_p, e_v, a, r, tau, out),
            "ball {e_p} {e_v} {a} {r} {tau}: {out}"
        );
        let out = speed_radius(e_p, e_v, r, tau);
        assert!(
            covers_speed(e_p, e_v, r, tau, out),
            "speed {e_p} {e_v} {r} {tau}: {out}"
        );
    });
}
