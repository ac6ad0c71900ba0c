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
use crate::interval::proofs::{SCALE_104, grid_value, grid_value_of};
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
// The whole claim verifies under Kani, but its solve time is heavy-tailed (5.6 s to 285.6 s, and
// a 300 s timeout): not in CI, which checks each end in four sign quadrants (below).
harness!(
    a2_mul_enclose,
    unwind = 2,
    bits = 52,
    cases = pacs_proof_kit::DEFAULT_CASES,
    mul
);

/// The operands of `a2_mul_enclose`, in one sign quadrant unless `sx = sy = 0`: `x` of the
/// sign of `sx`, `y` of the sign of `sy` (0 belongs to both; a zero sign admits any operand,
/// every `operands` value being finite). The four quadrants cover every pair, so each end's
/// claim is the conjunction of its four quadrant harnesses (`a2_mul_up_pp` … `a2_mul_down_nn`),
/// each a smaller problem for the solver than the whole end (times: proofs/README.md).
fn quadrant<S: Source>(s: &mut S, sx: f64, sy: f64) -> Option<(f64, f64)> {
    let (x, y) = operands(s)?;
    s.assume(x * sx >= 0.0 && y * sy >= 0.0).then_some((x, y))
}

/// mul up bounds the exact product from above (one end of `a2_mul_enclose`), in quadrant
/// (`sx`, `sy`).
fn mul_upper_in<S: Source>(s: &mut S, sx: f64, sy: f64) {
    let Some((x, y)) = quadrant(s, sx, sy) else {
        return;
    };
    assert!(cmp_prod(x, y, mul_up(x, y)) != Greater, "mul_up({x}, {y})");
}

/// mul down bounds the exact product from below (the other end), in quadrant (`sx`, `sy`).
fn mul_lower_in<S: Source>(s: &mut S, sx: f64, sy: f64) {
    let Some((x, y)) = quadrant(s, sx, sy) else {
        return;
    };
    assert!(cmp_prod(x, y, mul_down(x, y)) != Less, "mul_down({x}, {y})");
}

// Each end over every pair (Kani, not in CI: heavy-tailed; CI checks the quadrants below).
harness!(
    a2_mul_up_enclose,
    unwind = 2,
    bits = 52,
    cases = pacs_proof_kit::DEFAULT_CASES,
    mul_upper_in(0.0, 0.0)
);
harness!(
    a2_mul_down_enclose,
    unwind = 2,
    bits = 52,
    cases = pacs_proof_kit::DEFAULT_CASES,
    mul_lower_in(0.0, 0.0)
);

harness!(
    a2_mul_up_pp,
    unwind = 2,
    bits = 52,
    cases = pacs_proof_kit::DEFAULT_CASES,
    mul_upper_in(1.0, 1.0)
);
harness!(
    a2_mul_up_pn,
    unwind = 2,
    bits = 52,
    cases = pacs_proof_kit::DEFAULT_CASES,
    mul_upper_in(1.0, -1.0)
);
harness!(
    a2_mul_up_np,
    unwind = 2,
    bits = 52,
    cases = pacs_proof_kit::DEFAULT_CASES,
    mul_upper_in(-1.0, 1.0)
);
harness!(
    a2_mul_up_nn,
    unwind = 2,
    bits = 52,
    cases = pacs_proof_kit::DEFAULT_CASES,
    mul_upper_in(-1.0, -1.0)
);
harness!(
    a2_mul_down_pp,
    unwind = 2,
    bits = 52,
    cases = pacs_proof_kit::DEFAULT_CASES,
    mul_lower_in(1.0, 1.0)
);
harness!(
    a2_mul_down_pn,
    unwind = 2,
    bits = 52,
    cases = pacs_proof_kit::DEFAULT_CASES,
    mul_lower_in(1.0, -1.0)
);
harness!(
    a2_mul_down_np,
    unwind = 2,
    bits = 52,
    cases = pacs_proof_kit::DEFAULT_CASES,
    mul_lower_in(-1.0, 1.0)
);
harness!(
    a2_mul_down_nn,
    unwind = 2,
    bits = 52,
    cases = pacs_proof_kit::DEFAULT_CASES,
    mul_lower_in(-1.0, -1.0)
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
/// of `pacs_reach::ieee::sqrt`). Kani checks it on a4's rounding grid (`x = N·2⁻⁵²`, whose roots
/// are mostly irrational; `r² ≥ N·2⁵²·2⁻¹⁰⁴` decided on integers by [`square_vs`]); over any
/// tame `x` it took 210 s once (over the budget) and timed out at 300–600 s since, each end alone
/// too. The twin draws the grid with full-width significands and any tame `x` in ±1e6 (with
/// [`cmp_sqrt`]). The split `a2_sqrt_root_step` below proves the step from the root at full
/// width.
fn sqrt<S: Source>(s: &mut S) {
    if !cfg!(kani)
        && let Some(x) = num(s, 1e6)
    {
        let a = x.abs();
        assert!(cmp_sqrt(a, sqrt_up(a)) != Greater, "sqrt_up({a})");
        assert!(cmp_sqrt(a, sqrt_down(a)) != Less, "sqrt_down({a})");
    }
    let (x, n) = grid_value(s);
    let (a, e) = (x.abs(), n.unsigned_abs() << 52);
    let (up, down) = (sqrt_up(a), sqrt_down(a));
    assert!(
        up >= 0.0 && (e == 0 || (up.is_finite() && up > 0.0 && square_vs(up, e).0)),
        "sqrt_up({a}) = {up}"
    );
    assert!(
        down >= 0.0 && (down == 0.0 || (down.is_finite() && square_vs(down, e).1)),
        "sqrt_down({a}) = {down}"
    );
}
harness!(
    a2_sqrt_enclose,
    unwind = 2,
    bits = 52,
    cases = pacs_proof_kit::DEFAULT_CASES,
    sqrt
);

/// Split of `a2_sqrt_enclose`: `sqrt_up(a)` and `sqrt_down(a)` take `√` of `a` itself (the
/// recorded radicand, bitwise), `sqrt_up(a) = next(r)` and `0 ≤ sqrt_down(a) ≤ max(prev(r), 0)`
/// for the root `r` each got (under Kani ANY `r` in `[0, 1e160)`, [`any_root_recorded`]; in the
/// twin the library root), for any `a ≥ 0` at full width. Composition with the `√` contract
/// (`prev(r)² ≤ a ≤ next(r)²`, tested against the library by
/// `ieee::tests::contracts_hold_for_the_library`): `sqrt_down(a) ≤ prev(r) ≤ √a ≤ next(r) =
/// sqrt_up(a)` (for `prev(r) < 0` the lower end is 0 ≤ √a). A `sqrt_down` without its
/// `next_down` (mutant `x30`) or a `sqrt_up` without its `next_up` (mutant `x42`) fails for
/// every `r > 0`. What the split leaves to the contract's test: the root's accuracy; to the
/// twin: the whole claim against the exact oracle.
fn sqrt_root_step<S: Source>(s: &mut S) {
    let Some(x) = num(s, 1e300) else { return };
    let a = x.abs();
    let up = sqrt_up(a);
    let (arg, r) = last_root(a);
    if a > 0.0 && a.is_finite() {
        assert!(arg.to_bits() == a.to_bits(), "sqrt_up({a}) took √{arg}");
        assert!(up == r.next_up(), "sqrt_up({a}) = {up}, not next({r})");
    }
    let down = sqrt_down(a);
    let (arg, r) = last_root(a);
    assert!(down >= 0.0, "sqrt_down({a}) = {down} < 0");
    if a > 0.0 && a.is_finite() {
        assert!(arg.to_bits() == a.to_bits(), "sqrt_down({a}) took √{arg}");
        assert!(
            down <= r.next_down().max(0.0),
            "sqrt_down({a}) = {down} above prev({r})"
        );
    }
}
harness!(
    a2_sqrt_root_step,
    unwind = 2,
    bits = 52,
    stub = (crate::ieee::sqrt => any_root_recorded),
    cases = pacs_proof_kit::DEFAULT_CASES,
    sqrt_root_step
);

/// A vector with tame coordinates in [−m, m].
fn vector<S: Source>(s: &mut S, m: f64) -> Option<[f64; 3]> {
    Some([num(s, m)?, num(s, m)?, num(s, m)?])
}

/// A vector of a4's rounding grid (`crate::interval::proofs::grid_value`) with the integers of
/// its coordinates (each coordinate is `N·2⁻⁵²` exactly).
fn grid_vector<S: Source>(s: &mut S, exponents: usize, middle: bool) -> ([f64; 3], [i128; 3]) {
    let g = |s: &mut S| grid_value_of(s, exponents, middle);
    let [(x, nx), (y, ny), (z, nz)] = [g(s), g(s), g(s)];
    ([x, y, z], [nx, ny, nz])
}

/// `Σ nᵢ²` for `|nᵢ| < 2⁶²` (below 2¹²⁶, exact in `u128`).
fn sum_of_squares(n: [i128; 3]) -> u128 {
    let (a, b, c) = (
        n[0].unsigned_abs(),
        n[1].unsigned_abs(),
        n[2].unsigned_abs(),
    );
    a * a + b * b + c * c
}

/// `r = R·2^q` for a finite `r > 0`: its integer significand `R < 2⁵³` and exponent `q`.
fn significand_exponent(r: f64) -> (u128, i64) {
    let bits = r.to_bits();
    let (exp, mant) = ((bits >> 52) & 0x7ff, bits & ((1 << 52) - 1));
    if exp == 0 {
        (u128::from(mant), -1074)
    } else {
        (u128::from(mant | (1 << 52)), exp as i64 - 1075)
    }
}

/// How `r²` compares with `E·2⁻¹⁰⁴` for `E = Σ nᵢ²` (`|nᵢ| < 2⁶²`), decided exactly on integers:
/// `r = R·2^q`, so `r² ≥ E·2⁻¹⁰⁴ ⟺ R²·2^t ≥ E` with `t = 2q + 104`; `R² < 2¹⁰⁶` and `E < 2¹²⁶`.
/// For `t ≥ 0` the product is formed (below 2¹²⁷) unless `t > 21`, where `R² ≥ 2¹⁰⁴` puts it
/// above every `E`; for `t < 0` `R² ≥ E·2^k ⟺ ⌊R²/2^k⌋ ≥ E` and `R² ≤ E·2^k ⟺ ⌈R²/2^k⌉ ≤ E`
/// (`E·2^k` is a multiple of `2^k`). `r` finite and > 0.
fn square_vs(r: f64, e: u128) -> (bool, bool) {
    let (big_r, q) = significand_exponent(r);
    let (sq, t) = (big_r * big_r, 2 * q + 104);
    if t > 21 {
        // R ≥ 2⁵² here (t > 21 needs a normal r), so R²·2^t ≥ 2¹²⁶ > E.
        (true, false)
    } else if t >= 0 {
        let lhs = sq << t;
        (lhs >= e, lhs <= e)
    } else if t <= -107 {
        // 0 < R²/2^k < 1: below every E ≥ 1, above E = 0.
        (e == 0, e != 0)
    } else {
        let k = (-t) as u32;
        ((sq >> k) >= e, ((sq + (1 << k) - 1) >> k) <= e)
    }
}

/// `r ≥ √(Σ nᵢ²)·2⁻⁵²` exactly ([`square_vs`]).
fn norm_at_least(r: f64, n: [i128; 3]) -> bool {
    let e = sum_of_squares(n);
    r >= 0.0 && (e == 0 || (r.is_finite() && r > 0.0 && square_vs(r, e).0))
}

/// `r ≤ √(Σ nᵢ²)·2⁻⁵²` exactly ([`square_vs`]); true for `r ≤ 0`.
fn norm_at_most(r: f64, n: [i128; 3]) -> bool {
    let e = sum_of_squares(n);
    r <= 0.0 || (r.is_finite() && e > 0 && square_vs(r, e).1)
}

/// The norm oracles decide exactly at the edges: `1` against the norm 1 and its neighbours,
/// and `√5·2⁻⁵²` (a tiny distance of the grid) against its correctly rounded neighbours.
#[cfg(test)]
#[test]
fn the_norm_oracles_are_exact() {
    let one = [1i128 << 52, 0, 0];
    assert!(norm_at_least(1.0, one) && norm_at_most(1.0, one));
    assert!(!norm_at_least(1.0f64.next_down(), one) && norm_at_most(1.0f64.next_down(), one));
    assert!(norm_at_least(1.0f64.next_up(), one) && !norm_at_most(1.0f64.next_up(), one));
    let tiny = [1, 0, 2];
    let r = 5f64.sqrt() * f64::EPSILON; // √5·2⁻⁵², rounded once (not exact)
    let (lo, hi) = if r * r < 5.0 * f64::EPSILON * f64::EPSILON {
        (r, r.next_up())
    } else {
        (r.next_down(), r)
    };
    assert!(!norm_at_least(lo, tiny) && norm_at_most(lo, tiny));
    assert!(norm_at_least(hi, tiny) && !norm_at_most(hi, tiny));
    assert!(norm_at_least(0.0, [0; 3]) && norm_at_most(0.0, [0; 3]));
    // A tiny positive r against E = 0 and E = 1 (the branch t ≤ −107).
    assert_eq!(square_vs(1e-17, 0), (true, false));
    assert_eq!(square_vs(1e-17, 1), (false, true));
    assert!(!norm_at_most(1e-17, [0; 3]) && norm_at_least(1e-17, [0; 3]));
    assert!(!norm_at_least(0.0, tiny) && norm_at_most(0.0, tiny));
    // Large: |n| = 2⁶¹ − 1 on every axis (E near 3·2¹²²).
    let big = [(1i128 << 61) - 1; 3];
    let r = ((3.0f64).sqrt() * ((1u64 << 61) - 1) as f64) / crate::interval::proofs::SCALE_52;
    assert!(
        norm_at_least(r.next_up().next_up(), big) && !norm_at_least(r.next_down().next_down(), big)
    );
}

/// norm3_up bounds the exact Euclidean norm from above. Kani checks it on a4's rounding grid
/// (one exponent with the middle bit, `grid_value_of(s, 1, true)`: coordinates whose squares
/// and sums round; `√` by its contract, `ieee::sqrt` under
/// Kani; the exact norm compared on integers, [`norm_at_least`]); at symbolic widths it timed
/// out (three squares summed against the `√` contract). The twin draws that grid with
/// full-width significands and any tame coordinates in ±1e6 (with [`norm3_le`]). The splits
/// `a3_sum_squares_up` and `a3_norm_up_sqrt_inflate` below prove the composition's parts.
fn norm_up<S: Source>(s: &mut S) {
    if !cfg!(kani)
        && let Some([x, y, z]) = vector(s, 1e6)
    {
        assert!(
            norm3_le(x, y, z, norm3_up(x, y, z)),
            "norm3_up({x}, {y}, {z})"
        );
    }
    let ([x, y, z], n) = grid_vector(s, 1, true);
    let r = norm3_up(x, y, z);
    assert!(norm_at_least(r, n), "norm3_up({x}, {y}, {z}) = {r}");
}
harness!(
    a3_norm_up_encloses,
    unwind = 2,
    bits = 52,
    cases = pacs_proof_kit::DEFAULT_CASES,
    norm_up
);

/// `2⁻⁴⁸ = 32u` (u = 2⁻⁵³), as a constant (no `powi`).
const TWO_M48: f64 = f64::from_bits((1023 - 48) << 52);

/// The bridge between the two splits of a3: `T(S) = fl(S + S·2⁻⁴⁸)` for a computed sum of
/// squares `S ≥ 0` (`S·2⁻⁴⁸` is exact for `S ≥ 2⁻⁹⁷⁴`, and then
/// `S(1 + 30u) ≤ T ≤ S(1 + 34u)`).
fn widened(sum: f64) -> f64 {
    sum + sum * TWO_M48
}

/// Split (i) of a3 (`norm3_up`'s radicand): the upward-rounded sum of squares
/// `U = add_up(add_up(mul_up(x, x), mul_up(y, y)), mul_up(z, z))` is at most `T(S)`
/// ([`widened`]) of the code's radicand `S = fl(fl(x² + y²) + z²)`, for `S > 0` (a float
/// comparison: no exact oracle). `U ≥ x² + y² + z²` exactly by a1 (`add_up`) and a2 (`mul_up`)
/// and monotonicity, so the exact sum of squares is ≤ `T(S)`; for `S = 0` every coordinate is 0
/// (tame coordinates: a non-zero square is ≥ 1e-200). Margin: `U ≤ S(1 + 11u)` roughly (five
/// roundings to nearest and three `next_up`s, each ≤ 2u), `T ≥ S(1 + 30u)`; with no widening
/// (`T = S`) the claim fails. A lemma about the expression `norm3_up` evaluates (the code itself
/// is called by split (ii), which ties its radicand to this `S`). Kani checks it on a4's rounding
/// grid (one exponent with the middle bit: coordinates `±(1 + m·2⁻⁵²)`, `m ∈ {0, 1, 2, 2²⁶}`, or
/// 0, whose squares and sums round), where it
/// also checks the consequence the composition uses, the exact `x² + y² + z² ≤ T(S)` (on
/// integers: `⌊T·2¹⁰⁴⌋ ≥ Σ N²`); over symbolic widths it timed out (a float comparison of two
/// rounded chains over exponents 1e-200 … 1e12: 200 s at 8 bits, 150 s at 3 bits). The twin
/// draws the grid with full-width significands and any tame coordinates in ±1e6.
fn sum_squares_up<S: Source>(s: &mut S) {
    if !cfg!(kani)
        && let Some([x, y, z]) = vector(s, 1e6)
    {
        let sum = x * x + y * y + z * z;
        if sum != 0.0 {
            let up = add_up(add_up(mul_up(x, x), mul_up(y, y)), mul_up(z, z));
            let t = widened(sum);
            assert!(up <= t, "{x}² + {y}² + {z}² ≤ {up}, above T({sum}) = {t}");
        }
    }
    let ([x, y, z], n) = grid_vector(s, 1, true);
    let sum = x * x + y * y + z * z;
    if sum == 0.0 {
        return;
    }
    let up = add_up(add_up(mul_up(x, x), mul_up(y, y)), mul_up(z, z));
    let t = widened(sum);
    assert!(up <= t, "{x}² + {y}² + {z}² ≤ {up}, above T({sum}) = {t}");
    // Coordinates below 2⁹ (the twin; 2² under Kani): t < 2²⁰, t·2¹⁰⁴ below 2¹²⁴, exact.
    assert!(
        (t * SCALE_104).floor() as u128 >= sum_of_squares(n),
        "{x}² + {y}² + {z}² above T({sum}) = {t}"
    );
}
harness!(
    a3_sum_squares_up,
    unwind = 2,
    bits = 52,
    cases = pacs_proof_kit::DEFAULT_CASES,
    sum_squares_up
);

/// `2⁻⁴⁷ = 64u`, as a constant.
const TWO_M47: f64 = f64::from_bits((1023 - 47) << 52);

/// The inflation claim of the `√` splits: `out ≥ r + r·2⁻⁴⁷` exactly ([`cmp_sum`]) for the root
/// `r` the code took; `what` names the call and its radicand in the failure message.
fn assert_inflated(r: f64, out: f64, what: impl Fn() -> String) {
    assert!(
        cmp_sum(r, r * TWO_M47, out) != Greater,
        "{} below the root {r} times 1 + 2⁻⁴⁷",
        what()
    );
}

/// The argument and result of the last `√` of a positive finite value in a proof with
/// [`any_root_recorded`] (bit patterns; 0 before any).
#[cfg(kani)]
static ROOT_ARG: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
#[cfg(kani)]
static ROOT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

/// Stub of [`crate::ieee::sqrt`] for the a3 splits: for a positive finite `x` any `r` in
/// `[0, 1e160)`, recorded with `x` (so the harness can state its claim against the root the code
/// used); IEEE results otherwise (`x` for ±0 and +∞, NaN below 0 and for NaN). Over-approximates
/// IEEE `√` (whose root of a finite value is below √MAX ≈ 1.34e154): a claim proved for every such
/// `r` holds for the real root. The root's accuracy (`prev(r)² ≤ x ≤ next(r)²`, the contract of
/// `ieee::sqrt`, tested against the library by `ieee::tests::contracts_hold_for_the_library`)
/// enters only in the composition written in the docs of the splits.
#[cfg(kani)]
pub(crate) fn any_root_recorded(x: f64) -> f64 {
    use std::sync::atomic::Ordering::Relaxed;
    if x.is_nan() || x < 0.0 {
        return f64::NAN;
    }
    if x == 0.0 || x == f64::INFINITY {
        return x;
    }
    let r: f64 = kani::any();
    kani::assume(r >= 0.0 && r < 1.0e160);
    ROOT_ARG.store(x.to_bits(), Relaxed);
    ROOT.store(r.to_bits(), Relaxed);
    r
}

/// `(x, √x)` of the last `√` the code took, given the radicand the harness expects: under Kani
/// the values [`any_root_recorded`] recorded (so a different radicand in the code is caught), in
/// the twin the expected radicand and its library root (the code's root, `√` being
/// deterministic).
fn last_root(expected: f64) -> (f64, f64) {
    #[cfg(kani)]
    {
        use std::sync::atomic::Ordering::Relaxed;
        let _ = expected;
        (
            f64::from_bits(ROOT_ARG.load(Relaxed)),
            f64::from_bits(ROOT.load(Relaxed)),
        )
    }
    #[cfg(not(kani))]
    {
        (expected, crate::ieee::sqrt(expected))
    }
}

/// Split (ii) of a3 (`norm3_up`'s `√` and inflation): the code takes `√` of its radicand
/// `S = fl(fl(x² + y²) + z²)` (checked bitwise under Kani: the recorded argument), and for the
/// root `r` it got, `norm3_up(x, y, z) ≥ r + r·2⁻⁴⁷` exactly ([`cmp_sum`]; `r·2⁻⁴⁷` is exact for
/// `r ≥ 2⁻⁹⁷⁵`). Under Kani `r` is ANY value in `[0, 1e160)` ([`any_root_recorded`]), with
/// tame coordinates of 8 significand bits; in the twin any tame coordinates and the library
/// root. Mutant `x1` (no `INFLATE`, no `SQRT_TINY`: the result is `r`) fails for every `r > 0`.
///
/// Composition with split (i) (`a3_sum_squares_up`: the exact `x² + y² + z² ≤ T(S) ≤ S(1 + 34u)`)
/// and the `√` contract (`S ≤ next(r)² ≤ r²(1 + 2u)²`): `√(x² + y² + z²) ≤ √S·(1 + 17u) ≤
/// r(1 + 2u)(1 + 17u) < r(1 + 64u) = r(1 + 2⁻⁴⁷) ≤ norm3_up(x, y, z)` (√ is monotone; for `S = 0`
/// the coordinates are 0 and the result is `SQRT_TINY ≥ 0`).
fn norm_up_sqrt_inflate<S: Source>(s: &mut S) {
    let Some([x, y, z]) = vector(s, 1e6) else {
        return;
    };
    let sum = x * x + y * y + z * z;
    let out = norm3_up(x, y, z);
    let (arg, r) = last_root(sum);
    assert!(
        arg.to_bits() == sum.to_bits(),
        "norm3_up({x}, {y}, {z}) took √{arg}, not √{sum}"
    );
    assert_inflated(r, out, || {
        format!("norm3_up({x}, {y}, {z}) = {out}, √{sum}")
    });
}
harness!(
    a3_norm_up_sqrt_inflate,
    unwind = 2,
    bits = 8,
    stub = (crate::ieee::sqrt => any_root_recorded),
    cases = pacs_proof_kit::DEFAULT_CASES,
    norm_up_sqrt_inflate
);

/// norm3_down bounds the exact Euclidean norm from below. Kani checks it on a4's rounding grid
/// with two exponents (with [`norm_at_most`]; on the one-exponent grid with the middle bit
/// mutant `x30` survived: the radicand's own downward roundings hid it); the twin also over any
/// tame coordinates in ±1e6
/// (with [`norm3_ge`]). The split `a3_norm_down_sqrt` below proves the `√` step at 8 bits.
fn norm_down<S: Source>(s: &mut S) {
    if !cfg!(kani)
        && let Some([x, y, z]) = vector(s, 1e6)
    {
        assert!(
            norm3_ge(x, y, z, norm3_down(x, y, z)),
            "norm3_down({x}, {y}, {z})"
        );
    }
    let ([x, y, z], n) = grid_vector(s, 2, false);
    let r = norm3_down(x, y, z);
    assert!(norm_at_most(r, n), "norm3_down({x}, {y}, {z}) = {r}");
}
harness!(
    a3_norm_down_encloses,
    unwind = 2,
    bits = 52,
    cases = pacs_proof_kit::DEFAULT_CASES,
    norm_down
);

/// `norm3_down`'s radicand: `add_down(add_down(mul_down(x, x), mul_down(y, y)), mul_down(z, z))`.
fn radicand_down(x: f64, y: f64, z: f64) -> f64 {
    add_down(add_down(mul_down(x, x), mul_down(y, y)), mul_down(z, z))
}

/// Split (ii) of `norm3_down`: the code takes `√` of its radicand `L` ([`radicand_down`],
/// recomputed and checked bitwise in the twin), and its result is 0 or at most
/// `prev(r)` for the root `r` it got (under Kani any `r` in `[0, 1e160)`, [`any_root_recorded`];
/// in the twin the library root). Composition: `L ≤ x² + y² + z²` exactly by a1 (`add_down`)
/// and a2 (`mul_down`) and monotonicity, and the `√` contract gives `prev(r)² ≤ L`, so
/// `norm3_down ≤ prev(r) ≤ √L ≤ √(x² + y² + z²)`. A `sqrt_down` or
/// `norm3_down` that drops its `next_down` (the result is `r`, mutant `x30`) fails; one that
/// rounds its radicand to nearest fails the twin's radicand check.
fn norm_down_sqrt<S: Source>(s: &mut S) {
    let Some([x, y, z]) = vector(s, 1e6) else {
        return;
    };
    let out = norm3_down(x, y, z);
    assert!(out >= 0.0, "norm3_down({x}, {y}, {z}) = {out} < 0");
    // The radicand is recomputed and checked in the twin only: under Kani the two copies of the
    // `mul_down`/`add_down` chain (`next_down` branches) made the solver prove their equivalence
    // (178.7 s at 8 bits, a timeout at 150 s at 4 bits); `norm3_down` is `sqrt_down` of that
    // chain.
    let l = if cfg!(kani) {
        0.0
    } else {
        radicand_down(x, y, z)
    };
    let (arg, r) = last_root(l);
    if !cfg!(kani) {
        assert!(
            arg.to_bits() == l.to_bits(),
            "norm3_down({x}, {y}, {z}) took √{arg}, not √{l}"
        );
    }
    if arg > 0.0 {
        assert!(
            out == 0.0 || out <= r.next_down(),
            "norm3_down({x}, {y}, {z}) = {out} above prev(√{arg}) = prev({r})"
        );
    } else {
        assert!(
            out == 0.0,
            "norm3_down({x}, {y}, {z}) = {out} for radicand {arg} ≤ 0"
        );
    }
}
harness!(
    a3_norm_down_sqrt,
    unwind = 2,
    bits = 8,
    stub = (crate::ieee::sqrt => any_root_recorded),
    cases = pacs_proof_kit::DEFAULT_CASES,
    norm_down_sqrt
);

/// dist3_up bounds the exact distance of two points from above. Kani checks it on a4's
/// rounding grid (both points' coordinates; their differences round; the exact distance on
/// integers, [`norm_at_least`] of `N_a − N_b`); the twin also over any tame points in ±1e3
/// (with [`dist3_le`]). The split `a3_dist_up_sqrt_inflate` below proves the coordinate bounds
/// and the `√` step at 6 bits.
fn dist_up<S: Source>(s: &mut S) {
    if !cfg!(kani)
        && let (Some(a), Some(b)) = (vector(s, 1e3), vector(s, 1e3))
    {
        assert!(dist3_le(&a, &b, dist3_up(&a, &b)), "dist3_up({a:?}, {b:?})");
    }
    let ((a, na), (b, nb)) = (grid_vector(s, 1, false), grid_vector(s, 1, false));
    let r = dist3_up(&a, &b);
    let d = [na[0] - nb[0], na[1] - nb[1], na[2] - nb[2]];
    assert!(norm_at_least(r, d), "dist3_up({a:?}, {b:?}) = {r}");
}
harness!(
    a3_dist_up_encloses,
    unwind = 4,
    bits = 52,
    cases = pacs_proof_kit::DEFAULT_CASES,
    dist_up
);

/// Split of a3 for `dist3_up` (its coordinate bounds, `√` and inflation): each coordinate bound
/// `dᵢ = max(|sub_down(aᵢ, bᵢ)|, |sub_up(aᵢ, bᵢ)|)` is ≥ `|aᵢ − bᵢ|` exactly ([`cmp_sum`]), the
/// code takes `√` of `S = fl(fl(d₀² + d₁²) + d₂²)` (checked bitwise in the twin), and for the
/// root `r` it got (under Kani: recorded), `dist3_up(a, b) ≥ r + r·2⁻⁴⁷` exactly. Under Kani `r`
/// is any value in `[0, 1e160)` ([`any_root_recorded`]) and the coordinates have 6 significand
/// bits; in the twin any tame coordinates and the library root. Mutant `x1` fails (`dist3_up`
/// calls `norm3_up`). Composition as for [`norm_up_sqrt_inflate`], with `|a − b| ≤ |d|` (the
/// norm is monotone in each `|dᵢ|`) and the sum-of-squares bound of split (i) at `d`.
fn dist_up_sqrt_inflate<S: Source>(s: &mut S) {
    let (Some(a), Some(b)) = (vector(s, 1e3), vector(s, 1e3)) else {
        return;
    };
    let mut d = [0.0; 3];
    for i in 0..3 {
        let lo = sub_down(a[i], b[i]);
        let hi = sub_up(a[i], b[i]);
        d[i] = lo.abs().max(hi.abs());
        assert!(
            cmp_sum(a[i], -b[i], d[i]) != Greater && cmp_sum(a[i], -b[i], -d[i]) != Less,
            "|{} − {}| above {}",
            a[i],
            b[i],
            d[i]
        );
    }
    let sum = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    let out = dist3_up(&a, &b);
    let (arg, r) = last_root(sum);
    // The radicand is checked in the twin only: under Kani the two copies of the coordinate
    // bounds (`next_up`/`next_down` branches) made the solver prove their equivalence, and the
    // proof timed out (150 s); `dist3_up` is `norm3_up(d₀, d₁, d₂)`, whose radicand
    // `a3_norm_up_sqrt_inflate` checks.
    if !cfg!(kani) {
        assert!(
            arg.to_bits() == sum.to_bits(),
            "dist3_up({a:?}, {b:?}) took √{arg}, not √{sum}"
        );
    }
    assert_inflated(r, out, || format!("dist3_up({a:?}, {b:?}) = {out}, √{sum}"));
}
harness!(
    a3_dist_up_sqrt_inflate,
    unwind = 4,
    bits = 6,
    stub = (crate::ieee::sqrt => any_root_recorded),
    cases = pacs_proof_kit::DEFAULT_CASES,
    dist_up_sqrt_inflate
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
