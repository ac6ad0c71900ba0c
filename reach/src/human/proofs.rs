//! Kani splits of claim C3 (the human occupancy contains every admissible motion), beside the
//! per-keypoint arithmetic of [`HumanReach::occupancy_into`] (`elapsed_range`, `vel_radius`,
//! `acc_ball_at`, `part_radius`, `extremity_radius`). The whole claim — the default 9-keypoint
//! human, random uncertainties, sampled motions, `capsule_contains_point` — is the property test
//! `c1_human_occupancy_contains_motion` (`pacs-proofs`); these splits prove, per reach model,
//! that a keypoint's (or extremity's) radius bounds the farthest reach of every admissible motion:
//!
//! - `c1_vel_reach`: vel (and the parts of `pos` outside an extremity). The keypoint set at the
//!   elapsed time T is Ball(p, e_p + v_max·T) around the measured position p itself (no
//!   rounded centre), and a body-part point is a convex combination of two keypoints plus an
//!   offset ≤ thickness/2: the part lies in the capsule [p₁, p₂] of radius R once
//!   R ≥ e_p + v_max,ᵢ·T + thickness/2 for both keypoints (module doc of `human`), which this
//!   claims for the query's end (the farthest instant) and, in the twin, any instant.
//!   Mutant `m2` (the elapsed time without the delay) fails it.
//! - `c1_pos_reach`: pos, an extremity's part (consistent measurement): every point within
//!   length + thickness/2 of the base keypoint, which moves as in vel, lies in the ball of
//!   `extremity_radius` around the measured base: R ≥ e_p + v_max·T + length + thickness/2.
//!   Mutants `m2` and `x33` (the base's travel dropped) fail it.
//! - `c1_acc_ball_at`: acc at one elapsed time t. The keypoint set is Ball(p + v·t, e_p + e_v·t +
//!   ½·a_max·t²) (the sum of the balls of the position, velocity and acceleration errors); the
//!   ball `acc_ball_at` returns, centred at the rounded p + v·t, contains it: |p + v·t − c| +
//!   ρ(t) ≤ radius, exactly. Under Kani for a keypoint measured at rest at the origin (a claim
//!   on the radius: the centre is exact), in the twin for any p, v (the centre's rounding
//!   bounded by TwoSum and a neighbour-float gap). Mutant `x6` (the radius without e_v·t) fails
//!   it.
//!
//! Under Kani the model's bounds are dyadic constants near the default human's arm (v_max =
//! 2 m/s, a_max = 50 m/s²) and the largest uncertainties of c1's twin (e_p = 1/16 m, e_v =
//! 1/4 m/s, delay 1/16 s; thickness 1/8 m, extremity 3/4 m), and the times lie on a grid of
//! 1/256 s: every elapsed time and every term of the reach is then a float computed exactly, so
//! the claims compare the code's outward-rounded radius with the real reach itself. In the twins
//! (any floats, random bounds in c1's ranges) the reach is bounded above with the outward-rounded
//! helpers (`add_up`, `sub_up`, `mul_up`: claim C1, harnesses a1, a2). With symbolic floats
//! instead of the grid (8-bit significands) `c1_vel_reach` and `c1_pos_reach` timed out at
//! 180–200 s (Bitwuzla, load ≈ 4): the solver had to prove the rounded steps monotone.
//!
//! Left to `c1`'s twin: instants inside the query (under Kani its end), full-width times,
//! random bounds, the loops over keypoints and parts, the measurement's indexing, the `back`
//! term of a query starting up to 1e-9 s before the measured state (it only enlarges a ball),
//! the rounding of acc's centre, acc's `Ball::enclose` of the balls at T_lo and T_hi (a square
//! root), combined's choice of the smaller ball, `pos`'s consistency test
//! (`extremity_consistent`; also `reach/tests/human_occupancy.rs`, mutant `x27`) and the
//! capsule containment test itself.

// Proof functions are entry points of the model checker, not called from the crate.
#![cfg_attr(kani, allow(dead_code))]

use super::*;
use pacs_proof_kit::{Source, harness};

/// The model's bounds for one body part (m, m/s, m/s², s).
struct Bounds {
    e_p: f64,
    e_v: f64,
    delay: f64,
    /// Speed bounds of the part's two keypoints.
    v_max: (f64, f64),
    a_max: f64,
    thickness: f64,
    length: f64,
}

/// Constants under Kani, dyadic (with the grid of [`query`] every elapsed time, reach and radius
/// term is then a float computed exactly: the claims compare with the real number itself), near
/// the default human's arm (v_max = 2 m/s, a_max = 50 m/s²) and the largest uncertainties of
/// c1's twin; random bounds in the twins (c1's ranges).
fn bounds<S: Source>(s: &mut S) -> Bounds {
    if cfg!(kani) {
        Bounds {
            e_p: 0.0625,
            e_v: 0.25,
            delay: 0.0625,
            v_max: (2.0, 2.0),
            a_max: 50.0,
            thickness: 0.125,
            length: 0.75,
        }
    } else {
        Bounds {
            e_p: s.f64_in(0.0, 0.05),
            e_v: s.f64_in(0.0, 0.3),
            delay: s.f64_in(0.0, 0.1),
            v_max: (s.f64_in(0.0, 3.0), s.f64_in(0.0, 3.0)),
            a_max: s.f64_in(0.0, 60.0),
            thickness: s.f64_in(0.0, 0.3),
            length: s.f64_in(0.0, 1.2),
        }
    }
}

/// `n / 2^shift` for an integer `n` in `[0, max]`.
fn grid<S: Source>(s: &mut S, max: usize, shift: i32) -> f64 {
    let n = s.index(max + 1) as f64;
    // 2^−shift from its bits (no `powi`: an LLVM intrinsic the model checker lacks).
    n * f64::from_bits(((1023 - shift) as u64) << 52)
}

/// A measurement time, a query `[t_a, t_b]` starting no earlier than the measured state
/// (`time − delay`, as the twin of c1 draws it) and an instant `t` of it. Under Kani the
/// measurement at `time = 127/16` s, the query's start up to 0.5 s after the measured state and
/// its width up to 0.5 s on a grid of 1/256 s (with a dyadic delay every elapsed time
/// `t − time + delay` is a multiple of 2⁻⁸ below 2 computed exactly), and `t = t_b`: the reach
/// `e_p + v·T (+ …)` grows with `T`, which is linear in `t`, so the end of the query is the
/// farthest (exact arithmetic); any floats and any `t` in the twins.
fn query<S: Source>(s: &mut S, delay: f64) -> (f64, f64, f64, f64) {
    if cfg!(kani) {
        let time = 7.9375;
        let t_a = (time - delay) + grid(s, 128, 8);
        let t_b = t_a + grid(s, 128, 8);
        (time, t_a, t_b, t_b)
    } else {
        let time = s.f64_in(0.0, 10.0);
        let t_a = s.f64_in(time - delay, time + 0.5);
        let t_b = s.f64_in(t_a, t_a + 0.5);
        let t = s.f64_in(t_a, t_b);
        (time, t_a, t_b, t)
    }
}

/// The exact elapsed time `t − time + delay` of the instant `t` under Kani (on the grid of
/// [`query`] every operation is exact), an upper bound of it in the twins (a1).
fn elapsed_up(time: f64, delay: f64, t: f64) -> f64 {
    if cfg!(kani) {
        (t - time) + delay
    } else {
        add_up(sub_up(t, time), delay)
    }
}

/// `x/2` if it is exact (unless the half is subnormal: the twins' thickness from 5e-324 up; the
/// code's `add_up` covers that rounding, the claim is made for the others).
fn half(x: f64) -> Option<f64> {
    let h = x * 0.5;
    (h * 2.0 == x).then_some(h)
}

/// The exact `e_p + v·T + extra` under Kani (dyadic constants, `T` on the grid: every operation
/// exact), an upper bound of it for `v ≥ 0` and `T ≤ t_up` in the twins (a1, a2; the helpers
/// are monotone in each argument).
fn reach_up(e_p: f64, v: f64, t_up: f64, extra: f64) -> f64 {
    if cfg!(kani) {
        (e_p + v * t_up) + extra
    } else {
        add_up(add_up(e_p, mul_up(v, t_up)), extra)
    }
}

fn vel_reach<S: Source>(s: &mut S) {
    let b = bounds(s);
    let (time, t_a, t_b, t) = query(s, b.delay);
    let (_, t_hi) = elapsed_range(time, b.delay, t_a, t_b);
    let r1 = vel_radius(b.e_p, b.v_max.0, t_hi);
    let r2 = vel_radius(b.e_p, b.v_max.1, t_hi);
    let radius = part_radius(r1, r2, b.thickness);
    let t_up = elapsed_up(time, b.delay, t);
    let Some(h) = half(b.thickness) else {
        s.assume(false);
        return;
    };
    let reach = (
        reach_up(b.e_p, b.v_max.0, t_up, h),
        reach_up(b.e_p, b.v_max.1, t_up, h),
    );
    assert!(
        reach.0 <= radius && reach.1 <= radius,
        "vel: reach {reach:?} at t = {t} above the part radius {radius} (measured {time}, [{t_a}, {t_b}], delay {})",
        b.delay
    );
}
harness!(
    c1_vel_reach,
    unwind = 3,
    bits = 8,
    cases = pacs_proof_kit::DEFAULT_CASES,
    vel_reach
);

fn pos_reach<S: Source>(s: &mut S) {
    let b = bounds(s);
    let (time, t_a, t_b, t) = query(s, b.delay);
    let (t_lo, t_hi) = elapsed_range(time, b.delay, t_a, t_b);
    // As `HumanReach::elapsed`: a query starting before the measured state by a rounding
    // (> −1e-9 s) extends the travel by `back`.
    let back = if t_lo < 0.0 { -t_lo } else { 0.0 };
    let radius = extremity_radius(b.e_p, b.v_max.0, b.length, b.thickness, add_up(t_hi, back));
    let Some(h) = half(b.thickness) else {
        s.assume(false);
        return;
    };
    // Exact under Kani (dyadic), an upper bound in the twins.
    let extent = if cfg!(kani) {
        b.length + h
    } else {
        add_up(b.length, h)
    };
    let reach = reach_up(b.e_p, b.v_max.0, elapsed_up(time, b.delay, t), extent);
    assert!(
        reach <= radius,
        "pos: reach {reach} at t = {t} above the extremity radius {radius} (measured {time}, [{t_a}, {t_b}], delay {})",
        b.delay
    );
}
harness!(
    c1_pos_reach,
    unwind = 2,
    bits = 8,
    cases = pacs_proof_kit::DEFAULT_CASES,
    pos_reach
);

/// An upper bound of `|x − fl(x)|` for a real `x` whose correctly rounded value is `w`: the gap
/// to the farther neighbour of `w` (exact subtractions of neighbouring floats; `w` finite).
fn rounding_gap(w: f64) -> f64 {
    (w.next_up() - w).max(w - w.next_down())
}

/// An upper bound of `|p + v·t − fl(p + fl(v·t))|` (one coordinate of acc's centre): the error
/// of the product (`rounding_gap`) plus the exact error of the sum (TwoSum).
fn centre_error(p: f64, v: f64, t: f64) -> f64 {
    let w = v * t;
    let c = p + w;
    let bb = c - p;
    let sum_err = (p - (c - bb)) + (w - bb);
    add_up(rounding_gap(w), sum_err.abs())
}

fn acc_at<S: Source>(s: &mut S) {
    let b = bounds(s);
    // Under Kani the keypoint measured at rest at the origin (the centre is then exactly p + v·t
    // and the claim is on the radius) and `t` on a grid of 1/256 s up to 1.1 s (with the dyadic
    // bounds every term of ρ(t) is a float computed exactly); any position, velocity and
    // elapsed time of c1's queries (delay ≤ 0.1 s, start ≤ 0.5 s after, width ≤ 0.5 s) in the
    // twin.
    let (x, y, z, t) = if cfg!(kani) {
        ((0.0, 0.0), (0.0, 0.0), (0.0, 0.0), grid(s, 281, 8))
    } else {
        let mut pv = || (s.f64_in(-2.0, 2.0), s.f64_in(-2.0, 2.0));
        let (x, y, z) = (pv(), pv(), pv());
        (x, y, z, s.f64_in(0.0, 1.1))
    };
    let p = Point3::new(x.0, y.0, z.0);
    let v = Vector3::new(x.1, y.1, z.1);
    let ball = acc_ball_at(b.e_p, b.e_v, b.a_max, &p, &v, t);
    // |p + v·t − c| ≤ its 1-norm, each coordinate's error bounded above.
    let c = ball.centre;
    let dist = add_up(
        add_up(centre_error(x.0, x.1, t), centre_error(y.0, y.1, t)),
        centre_error(z.0, z.1, t),
    );
    if !cfg!(kani) {
        // `centre_error` reads the centre as the code computes it: p + fl(v·t) per coordinate.
        for ((p, v), c) in [(x, c.x), (y, c.y), (z, c.z)] {
            assert_eq!((p + v * t).to_bits(), c.to_bits());
        }
    }
    // ρ(t) = e_p + e_v·t + ½·a_max·t²: exact under Kani (dyadic bounds, `t` on the grid), an
    // upper bound in the twin (a1, a2).
    let need = if cfg!(kani) {
        // The exact centre is the origin: so is the computed one.
        assert!(c.x == 0.0 && c.y == 0.0 && c.z == 0.0, "centre {c:?}");
        (b.e_p + b.e_v * t) + 0.5 * b.a_max * t * t
    } else {
        let rho = add_up(
            add_up(b.e_p, mul_up(b.e_v, t)),
            mul_up(mul_up(mul_up(0.5, b.a_max), t), t),
        );
        add_up(dist, rho)
    };
    assert!(
        need <= ball.radius,
        "acc: the set at t = {t} (p = {p:?}, v = {v:?}) reaches {need} from the centre, radius {}",
        ball.radius
    );
}
harness!(
    c1_acc_ball_at,
    unwind = 4,
    bits = 8,
    cases = pacs_proof_kit::DEFAULT_CASES,
    acc_at
);

// ---------------------------------------------------------------------------------------------
// The contracts of the per-keypoint arithmetic (`elapsed_range`, `vel_radius`, `part_radius`,
// `extremity_radius`), each proven on the real function with `proof_for_contract` (Kani assumes
// the precondition and checks the postcondition on every path), and their common twin.

/// The inputs of the contract proofs: floats of at most 8 significant bits (any exponent in the
/// range) under Kani — with 64-bit significands every one of them timed out (300 s, Bitwuzla):
/// the exact oracle's integer product and two-sums over four unknown doubles.
#[cfg(kani)]
fn short_in(lo: f64, hi: f64) -> f64 {
    use pacs_proof_kit::Source;
    pacs_proof_kit::KaniSource { bits: 8 }.f64_in(lo, hi)
}

/// `vel_radius`'s contract: `≥ e_p + v·T` exactly, for position errors up to 1 m, speeds up to
/// 10 m/s and elapsed times up to 100 s (8-bit significands, any exponent).
#[cfg(kani)]
#[kani::proof_for_contract(vel_radius)]
#[kani::unwind(6)]
fn c1_vel_radius_contract() {
    let _ = vel_radius(
        short_in(0.0, 1.0),
        short_in(0.0, 10.0),
        short_in(0.0, 100.0),
    );
}

/// `part_radius`'s contract: `≥ max(r1, r2) + thickness/2` exactly, for radii up to 100 m and
/// thicknesses up to 2 m (8-bit significands).
#[cfg(kani)]
#[kani::proof_for_contract(part_radius)]
#[kani::unwind(6)]
fn c1_part_radius_contract() {
    let _ = part_radius(
        short_in(0.0, 100.0),
        short_in(0.0, 100.0),
        short_in(0.0, 2.0),
    );
}

/// `elapsed_lo`'s contract: `≤ t_a − time + delay` exactly, for clocks within ±10⁶ s and
/// delays up to 1 s (8-bit significands).
#[cfg(kani)]
#[kani::proof_for_contract(elapsed_lo)]
#[kani::unwind(5)]
fn c1_elapsed_lo_contract() {
    let _ = elapsed_lo(short_in(-1e6, 1e6), short_in(0.0, 1.0), short_in(-1e6, 1e6));
}

/// `elapsed_hi`'s contract: `≥ t_b − time + delay` exactly (as `c1_elapsed_lo_contract`).
#[cfg(kani)]
#[kani::proof_for_contract(elapsed_hi)]
#[kani::unwind(5)]
fn c1_elapsed_hi_contract() {
    let _ = elapsed_hi(short_in(-1e6, 1e6), short_in(0.0, 1.0), short_in(-1e6, 1e6));
}

/// The twin of the contract proofs: random admitted floats (`draw_radius_input`), each
/// function's postcondition checked.
#[cfg(test)]
#[test]
fn c1_radius_contracts_hold() {
    pacs_proof_kit::run_cases("c1_radius_contracts_hold", 20_000, |s| {
        let x = super::draw_radius_input;
        let (e_p, v, t) = (x(s, false), x(s, false), x(s, false));
        assert!(
            covers_vel_reach(e_p, v, t, vel_radius(e_p, v, t)),
            "vel {e_p} {v} {t}"
        );
        let (len, th) = (x(s, false), x(s, false));
        let r = extremity_radius(e_p, v, len, th, t);
        assert!(covers_extremity_reach(e_p, v, len, th, t, r), "extremity");
        let (r1, r2) = (x(s, false), x(s, false));
        assert!(
            covers_part(r1, r2, th, part_radius(r1, r2, th)),
            "part {r1} {r2} {th}"
        );
        let (time, delay, ta, tb) = (x(s, true), x(s, false), x(s, true), x(s, true));
        let r = elapsed_range(time, delay, ta, tb);
        assert!(
            elapsed_range_encloses(time, delay, ta, tb, r),
            "elapsed {time} {delay} {ta} {tb}: {r:?}"
        );
    });
}
