//! Proofs of the floating-point steps of the geometric queries, beside them (claim C2). Emitted
//! by [`harness!`] as Kani proofs (`cargo kani -p pacs-reach --lib --harness NAME`) and seeded
//! property tests (`cargo test -p pacs-reach`). The whole queries against sampled points are the
//! property tests `b1_segment_distance_lower_bound`, `b1_separating_axis_any_direction` and
//! `b2_capsule_intersection_conservative` in `proofs/src/harnesses/geometry.rs`; what the split
//! leaves to them: `proofs/README.md`.
// Proof functions are entry points of the model checker, not called from the crate.
#![cfg_attr(kani, allow(dead_code))]
use super::*;
use crate::exact::{cmp_sum, sum_le_zero, tame, two_prod, two_sum};
use crate::interval::proofs::{SCALE_104, grid_value_of};
use crate::rounding::add_up;
use pacs_proof_kit::{Source, harness};
use std::cmp::Ordering::{Greater, Less};

/// A coordinate with at most `bits` significand bits under Kani (any tame float in the twin).
fn short<S: Source>(s: &mut S, m: f64, bits: u32) -> Option<f64> {
    let x = s.f64_short(-m, m, bits);
    s.assume(tame(x)).then_some(x)
}

/// `x·y` as two floats summing to it exactly. Under Kani the factors have at most 8 and 3
/// significand bits, so the product has at most 11 and is itself a float (tame factors in
/// [−1e3, 1e3]: no underflow, no overflow): `(x·y, 0)`, one multiplier for the solver instead of
/// Dekker's seven; in the twin (any widths) Dekker's TwoProduct.
fn exact_prod_parts(x: f64, y: f64) -> (f64, f64) {
    if cfg!(kani) {
        (x * y, 0.0)
    } else {
        two_prod(x, y)
    }
}

/// `dot_bounds(n, a)` encloses the exact dot product: `lo ≤ n·a ≤ hi`, decided exactly (each
/// product split into `p + e`, the sum of the parts by a double-double sum with an error bound:
/// [`sum_le_zero`] is true only if the sum is proved ≤ 0) in the twin, over any tame vectors in
/// ±1e3; Kani checks it on the rounding grid ([`dot_bounds_rounding_grid`], which the twin draws
/// too, with full-width significands), where the products and their sum round (mutant `x7`, no
/// error term, must fail). With 8- and 3-bit inputs and this oracle it timed out.
fn dot_bounds_enclose<S: Source>(s: &mut S) {
    if !cfg!(kani) {
        dot_bounds_any(s);
    }
    dot_bounds_rounding_grid(s);
}

/// The twin's part of [`dot_bounds_enclose`]: any tame vectors in ±1e3.
fn dot_bounds_any<S: Source>(s: &mut S) {
    let (Some(n0), Some(n1), Some(n2)) = (short(s, 1e3, 8), short(s, 1e3, 8), short(s, 1e3, 8))
    else {
        return;
    };
    let (Some(a0), Some(a1), Some(a2)) = (short(s, 1e3, 3), short(s, 1e3, 3), short(s, 1e3, 3))
    else {
        return;
    };
    assert_dot_bounds([n0, n1, n2], [a0, a1, a2]);
}

/// [`dot_bounds_enclose`] on a4's rounding grid (`crate::interval::proofs::grid_value_of`):
/// every coordinate `N·2⁻⁵²`, under Kani `±(1 + m·2⁻⁵²)` (`m ≤ 2`) or 0, so the products round
/// as well as their sums (what `dot_bounds`' error term covers); the exact `n·a` is the integer
/// `Σ N_n·N_a` times 2⁻¹⁰⁴ (below 2¹²⁶ also for the twin's full-width grid), and `lo ≤ n·a ⟺
/// ⌊lo·2¹⁰⁴⌋ ≤ Σ N_n·N_a` (the scaling is exact): decided on integers.
fn dot_bounds_rounding_grid<S: Source>(s: &mut S) {
    let (mut n, mut a, mut exact) = ([0.0; 3], [0.0; 3], 0i128);
    for i in 0..3 {
        let ((x, nx), (y, ny)) = (grid_value_of(s, 1, false), grid_value_of(s, 1, false));
        (n[i], a[i]) = (x, y);
        exact += nx * ny;
    }
    let (lo, hi) = dot_bounds(&Vector3::from(n), &Point3::from(a));
    assert!(
        !lo.is_nan() && ((lo * SCALE_104).floor() as i128) <= exact,
        "dot lower bound {lo} above n·a = {exact}·2⁻¹⁰⁴ (n = {n:?}, a = {a:?})"
    );
    assert!(
        !hi.is_nan() && ((hi * SCALE_104).ceil() as i128) >= exact,
        "dot upper bound {hi} below n·a = {exact}·2⁻¹⁰⁴ (n = {n:?}, a = {a:?})"
    );
}

/// The claim of [`dot_bounds_enclose`] for given vectors.
fn assert_dot_bounds([n0, n1, n2]: [f64; 3], [a0, a1, a2]: [f64; 3]) {
    let (lo, hi) = dot_bounds(&Vector3::new(n0, n1, n2), &Point3::new(a0, a1, a2));
    let (p0, e0) = exact_prod_parts(n0, a0);
    let (p1, e1) = exact_prod_parts(n1, a1);
    let (p2, e2) = exact_prod_parts(n2, a2);
    if p0 == 0.0 && p1 == 0.0 && p2 == 0.0 {
        // n·a = 0 exactly (tame factors: a nonzero product is ≥ 1e-200 in magnitude, so the
        // parts are all 0); the oracle's own absolute slack (`MIN_POSITIVE`) equals the bound's,
        // so decide this case directly.
        assert!(lo <= 0.0 && 0.0 <= hi, "[{lo}, {hi}] ∌ 0 = n·a");
        return;
    }
    // The exact n·a as few floats: under Kani the products are exact (e = 0) and two TwoSums
    // give p0 + p1 + p2 = t + f1 + f2 exactly (with t the code's own rounded sum, one term for
    // the solver); in the twin all six parts.
    let exact: &[f64] = if cfg!(kani) {
        let (t1, f1) = two_sum(p0, p1);
        let (t, f2) = two_sum(t1, p2);
        &[t, f1, f2]
    } else {
        &[p0, e0, p1, e1, p2, e2]
    };
    let mut below = [0.0; 7];
    let mut above = [0.0; 7];
    below[0] = lo;
    above[0] = -hi;
    for (k, &x) in exact.iter().enumerate() {
        below[k + 1] = -x;
        above[k + 1] = x;
    }
    let n = exact.len() + 1;
    assert!(sum_le_zero(&below[..n]), "dot lower bound {lo} above n·a");
    assert!(sum_le_zero(&above[..n]), "dot upper bound {hi} below n·a");
}
// Kani: the rounding grid (over symbolic widths a timeout in four forms, 150–200 s); the split
// `b1_dot_bounds_grid` below takes exact products of wider range.
harness!(
    b1_dot_bounds_enclose,
    unwind = 4,
    bits = 52,
    cases = pacs_proof_kit::DEFAULT_CASES,
    dot_bounds_enclose
);

/// `2^-k` (`k ≤ 1022`) from its bits (no `powi`: an LLVM intrinsic the model checker lacks).
fn pow2_neg(k: u32) -> f64 {
    f64::from_bits(u64::from(1023 - k) << 52)
}

/// `2⁶²`: the scale of [`dot_bounds_grid`]'s integer oracle.
const GRID_SCALE: f64 = 4_611_686_018_427_387_904.0;

/// Split of `b1_dot_bounds_enclose` for Kani, with an integer oracle: `n_i = N_i·2^−s_i` and
/// `a_i = A_i/4` (`|A_i| ≤ 28`), so the exact `n·a` is the integer `Σ N_i·A_i·2^(60 − s_i)`
/// times `2⁻⁶²` (below 2⁷⁵: exact in `i128`), while the float sum of products up to 2⁶⁰ apart
/// rounds — what `dot_bounds`' error term covers (mutant `x7`, no error term, fails: Kani
/// 1.9 s). The bounds scaled by `2⁶²` are exact (a power of two, no overflow), and
/// `lo·2⁶² ≤ S ⟺ ⌊lo·2⁶²⌋ ≤ S` for the integer `S`, so the claim is decided on bit-vectors and
/// the solver's floating-point work is `dot_bounds`' own. Under Kani `n` is made of signed
/// powers of two (`N_i = ±1`, `s_i ∈ {0, 60}`, any per coordinate: the products are exact and
/// the sum rounds; 27.6 s); with `s_i ∈ {0, 30, 60}` it took 138–148 s (over the budget), with
/// `|N_i| ≤ 255` or any `s_i ∈ [0, 60]` it timed out at 300 s. The twin draws `|N_i| ≤ 255` and any `s_i ∈ [0, 60]`; full-width significands, where
/// the products round themselves, are the twin of the whole claim's.
fn dot_bounds_grid<S: Source>(s: &mut S) {
    let (mut n, mut a, mut exact) = ([0.0; 3], [0.0; 3], 0i128);
    for i in 0..3 {
        let (big_n, shift) = if cfg!(kani) {
            (if s.bool() { 1 } else { -1 }, 60 * s.index(2) as u32)
        } else {
            (s.index(511) as i64 - 255, s.index(61) as u32)
        };
        let big_a = s.index(57) as i64 - 28;
        n[i] = big_n as f64 * pow2_neg(shift);
        a[i] = big_a as f64 * 0.25;
        exact += i128::from(big_n * big_a) << (60 - shift);
    }
    let (lo, hi) = dot_bounds(&Vector3::from(n), &Point3::from(a));
    // |lo|, |hi| < 2²⁰: scaled below 2⁸², where the casts are exact.
    let (lo_s, hi_s) = (lo * GRID_SCALE, hi * GRID_SCALE);
    assert!(
        (lo_s.floor() as i128) <= exact,
        "dot lower bound {lo} above n·a = {exact}·2⁻⁶² (n = {n:?}, a = {a:?})"
    );
    assert!(
        (hi_s.ceil() as i128) >= exact,
        "dot upper bound {hi} below n·a = {exact}·2⁻⁶² (n = {n:?}, a = {a:?})"
    );
}
harness!(
    b1_dot_bounds_grid,
    unwind = 4,
    bits = 52,
    cases = pacs_proof_kit::DEFAULT_CASES,
    dot_bounds_grid
);

/// The margin of two capsules (`margin`, used by `capsule_separation_lower_bound`,
/// `capsule_distance_lower_bound` and `capsules_disjoint`) is never above the exact
/// `d − ra − rb`: a positive margin proves `ra + rb < d` (the capsules are disjoint when `d`
/// bounds their core segments' distance from below), and the clamped distance bound is ≤ the
/// exact surface distance. Radii often exactly touch (`rb = d − ra` rounded). Checked as the two
/// roundings it composes, each in its direction (`s = add_up(ra, rb) ≥ ra + rb`,
/// `margin ≤ d − s`, exact by TwoSum), and the conclusion for a positive margin; the twin also
/// checks `margin ≤ d − ra − rb` in one exact sum.
fn capsule_margin<S: Source>(s: &mut S) {
    let d = s.f64_in(0.0, 4.0);
    let ra = s.f64_in(0.0, 1.0);
    let rb = if s.bool() {
        s.f64_in(0.0, 1.0)
    } else {
        (d - ra).max(0.0)
    };
    if !s.assume(tame(d) && tame(ra) && tame(rb)) {
        return;
    }
    let m = margin(d, ra, rb);
    let sum = add_up(ra, rb);
    assert!(cmp_sum(ra, rb, sum) != Greater, "{ra} + {rb} > {sum}");
    assert!(cmp_sum(d, -sum, m) != Less, "margin {m} above {d} − {sum}");
    if m > 0.0 {
        assert!(
            cmp_sum(ra, rb, d) == Less,
            "margin {m} > 0 with {ra} + {rb} ≥ {d}"
        );
        if !cfg!(kani) {
            assert!(
                sum_le_zero(&[m, -d, ra, rb]),
                "margin {m} above {d} − {ra} − {rb}"
            );
        }
    }
}
harness!(
    b2_capsule_margin_sound,
    unwind = 2,
    bits = 27,
    cases = pacs_proof_kit::DEFAULT_CASES,
    capsule_margin
);

/// A separating gap of one subnormal ulp divided by a direction longer than 2 underflows to 0,
/// and rounding that down gives −2⁻¹⁰⁷⁴: [`separating_axis_lower_bound`] clamps it at 0 (its
/// documented range). Scans points `a = (t, 0, 0)`, `b = (u, 0, 0)` just past each other's error
/// band along `n = (k, 0, 0)` for such gaps, the ends taken from [`dot_bounds`] itself; the test
/// fails if none is met, so it keeps exercising the clamp.
#[cfg(test)]
#[test]
fn a_gap_that_underflows_gives_a_bound_of_zero_not_below() {
    use nalgebra::{Point3, Vector3};
    let tiny = f64::from_bits(1);
    let mut underflows = 0;
    for k in [3.0, 4.0, 5.0, 2.5, 3.5] {
        let n = Vector3::new(k, 0.0, 0.0);
        let t0 = 2.0 * f64::MIN_POSITIVE / k;
        for j in 0..4u64 {
            let b = Point3::new(f64::from_bits(j), 0.0, 0.0);
            let (_, bh) = dot_bounds(&n, &b);
            for i in -400i64..400 {
                let t = f64::from_bits((t0.to_bits() as i64 + i) as u64);
                let a = Point3::new(t, 0.0, 0.0);
                let lb = separating_axis_lower_bound(&n, &a, &a, &b, &b);
                assert!(
                    lb >= 0.0,
                    "along {n:?} from {a:?} to {b:?}: bound {lb:e} < 0"
                );
                let (al, _) = dot_bounds(&n, &a);
                if al - bh == 2.0 * tiny {
                    // The gap is one ulp; its quotient by |n| > 2 rounds to 0.
                    underflows += 1;
                    assert_eq!(lb, 0.0);
                }
            }
        }
    }
    assert!(
        underflows > 0,
        "no gap of one ulp met: the scan no longer reaches the clamp"
    );
}
