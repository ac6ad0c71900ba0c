//! Proofs of the interval operations, beside them (claim C1: every interval operation contains
//! the exact result for every pair of members). Emitted by [`harness!`] as Kani proofs
//! (`cargo kani -p pacs-reach --lib --harness NAME`) and seeded property tests (`cargo test -p
//! pacs-reach`). Results, widths and splits: `proofs/README.md`.
// Proof functions are entry points of the model checker, not called from the crate.
#![cfg_attr(kani, allow(dead_code))]
use super::*;
use crate::exact::{cmp_prod, cmp_sum, tame};
use crate::rounding::proofs::num;
use crate::rounding::{mul_down, mul_up};
use pacs_proof_kit::{Source, harness};
use std::cmp::Ordering::{Greater, Less};

/// An interval `[lo, lo + w]` with `w ∈ [0, wmax]` (a point interval when `w = 0`).
pub(crate) fn interval<S: Source>(s: &mut S, m: f64, wmax: f64) -> Option<Interval> {
    let lo = num(s, m)?;
    let w = s.f64_in(0.0, wmax);
    let hi = lo + w;
    s.assume(tame(hi) && tame(w)).then_some(())?;
    Interval::new(lo, hi)
}

/// An interval whose two ends have at most [`NARROW`] significand bits under Kani (drawn independently
/// and ordered), any interval of width ≤ 10 in the twin: the second operand of the split
/// harnesses' sums and products, narrow for the same reason as `y` in a2 (products of a
/// full-width and a 6-bit significand still round).
fn narrow_interval<S: Source>(s: &mut S, m: f64) -> Option<Interval> {
    if !cfg!(kani) {
        return interval(s, m, 10.0);
    }
    let (p, q) = (s.f64_short(-m, m, NARROW), s.f64_short(-m, m, NARROW));
    s.assume(tame(p) && tame(q) && p <= q).then_some(())?;
    Interval::new(p, q)
}

/// Significand bits of the narrow operand of the split `×` and `scale` harnesses under Kani: a
/// full-width factor times a 3-bit factor has up to 56 significant bits, so the products still
/// round (what the claims are about), and each of the four products of `×` is a narrow
/// multiplier for the solver.
const NARROW: u32 = 3;

/// An interval in [−1e3, 1e3]: under Kani two independent ends of the harness width, ordered
/// (no adder between the inputs and the operation, as in [`interval`]); in the twin as
/// [`interval`].
fn wide_interval<S: Source>(s: &mut S) -> Option<Interval> {
    if !cfg!(kani) {
        return interval(s, 1e3, 10.0);
    }
    let (p, q) = (num(s, 1e3)?, num(s, 1e3)?);
    s.assume(p <= q).then_some(())?;
    Interval::new(p, q)
}

/// Two intervals: `a` with the harness width ([`wide_interval`]), `b` narrow under Kani
/// ([`narrow_interval`]).
fn interval_operands<S: Source>(s: &mut S) -> Option<(Interval, Interval)> {
    Some((wide_interval(s)?, narrow_interval(s, 1e3)?))
}

/// A member of `a`, anywhere in it (biased to the ends by the source).
fn member<S: Source>(s: &mut S, a: Interval) -> f64 {
    s.f64_in(a.lo(), a.hi())
}

/// `2⁵²` and `2¹⁰⁴`: the scales of the grid harnesses' integer oracles (powers of two, so a
/// float times them is exact).
pub(crate) const SCALE_52: f64 = 4_503_599_627_370_496.0;
pub(crate) const SCALE_104: f64 = SCALE_52 * SCALE_52;

/// A value of the rounding grid with its integer `N` (the value is `N·2⁻⁵²` exactly): 0, or
/// `±(2⁵² + m)·2^(e − 52)`. Under Kani `m ∈ {0, 1, 2}` and `e ∈ {0, 1}` — significands with
/// only their two lowest bits free, so products of values with `m ≠ 0` round, and so do sums
/// of values of different exponents where the smaller one has `m = 1` (`(1 + 2⁻⁵²) + 2`: what
/// the claims are about), while the solver's multipliers stay small; in the twin any `m < 2⁵²`
/// and `e ∈ [0, 8]` (full-width significands). `|N| < 2⁶¹`: products of two `N` are below
/// 2¹²², exact in `i128`.
pub(crate) fn grid_value<S: Source>(s: &mut S) -> (f64, i128) {
    grid_value_of(s, 2, false)
}

/// [`grid_value`] with `e < exponents` under Kani (1 or 2), and with `middle` also `m = 2²⁶`:
/// `(1 + 2⁻²⁶)² = 1 + 2⁻²⁵ + 2⁻⁵²` is a float with its last bit set, so sums of squares round
/// on the one-exponent grid too (squares of `1 + m·2⁻⁵²`, `m ≤ 2`, round to even multiples of
/// 2⁻⁵², whose sums in [2, 4) are exact).
pub(crate) fn grid_value_of<S: Source>(s: &mut S, exponents: usize, middle: bool) -> (f64, i128) {
    let zero = s.index(8) == 0;
    // The twin draws Kani's grid half of the time, full-width significands otherwise.
    let (m, e) = if cfg!(kani) || s.bool() {
        let m = match s.index(if middle { 4 } else { 3 }) {
            3 => 1 << 26,
            i => i as i128,
        };
        (m, s.index(exponents) as u32)
    } else {
        (
            (s.f64_in(0.0, 4_503_599_627_370_495.0) as u64) as i128,
            s.index(9) as u32,
        )
    };
    let n = ((1i128 << 52) + m) << e;
    let n = if zero {
        0
    } else if s.bool() {
        -n
    } else {
        n
    };
    // `|n| < 2⁶¹` with at most 53 significant bits: the conversion and the scaling are exact.
    (n as f64 / SCALE_52, n)
}

/// An interval with grid ends and a grid member of it: `(a, x, N_x)`.
fn grid_interval_member<S: Source>(s: &mut S) -> Option<(Interval, f64, i128)> {
    let mut v = [grid_value(s), grid_value(s), grid_value(s)];
    if !cfg!(kani) {
        // The twin orders its draws (rejecting five of six would waste them); Kani assumes.
        v.sort_by_key(|&(_, n)| n);
        v.swap(1, 2);
    }
    let [(p, _), (q, _), (x, nx)] = v;
    s.assume(p <= q && p <= x && x <= q).then_some(())?;
    Some((Interval::new(p, q)?, x, nx))
}

/// `r` scaled by `scale` (a power of two) contains the integer `exact`: the ends of `r` times
/// the scale are exact (no overflow below 2¹²⁷), and `lo·scale ≤ S ⟺ ⌊lo·scale⌋ ≤ S` for an
/// integer `S` (and `≥` with `⌈·⌉`), so the comparison is exact on integers. A NaN end (which
/// would cast to 0) is never accepted.
fn grid_contains(r: Interval, scale: f64, exact: i128) -> bool {
    !r.lo().is_nan()
        && !r.hi().is_nan()
        && ((r.lo() * scale).floor() as i128) <= exact
        && ((r.hi() * scale).ceil() as i128) >= exact
}

fn inside_sum(r: Interval, x: f64, y: f64) -> bool {
    cmp_sum(x, y, r.lo()) != Less && cmp_sum(x, y, r.hi()) != Greater
}

fn inside_prod(r: Interval, x: f64, y: f64) -> bool {
    cmp_prod(x, y, r.lo()) != Less && cmp_prod(x, y, r.hi()) != Greater
}

/// Interval `+`, `−` and negation contain the exact result for every pair of members (the
/// whole claim). Kani checks it on the rounding grid ([`grid_value`]: ends and members of
/// both operands, an integer oracle); the twin draws the grid with full-width significands and
/// any intervals in ±1e3 (with [`cmp_sum`] as the oracle). The per-end splits below prove the
/// two ends at 27-bit operands.
fn interval_add_sub<S: Source>(s: &mut S) {
    if !cfg!(kani)
        && let (Some(a), Some(b)) = (interval(s, 1e3, 10.0), interval(s, 1e3, 10.0))
    {
        let (x, y) = (member(s, a), member(s, b));
        if s.assume(tame(x) && tame(y)) {
            assert!(inside_sum(a + b, x, y), "{a:?} + {b:?} ∌ {x} + {y}");
            assert!((-a).contains(-x));
            assert!(inside_sum(a - b, x, -y), "{a:?} - {b:?} ∌ {x} - {y}");
        }
    }
    let (Some((a, x, nx)), Some((b, y, ny))) = (grid_interval_member(s), grid_interval_member(s))
    else {
        return;
    };
    assert!(
        grid_contains(a + b, SCALE_52, nx + ny),
        "{a:?} + {b:?} ∌ {x} + {y}"
    );
    assert!((-a).contains(-x));
    assert!(
        grid_contains(a - b, SCALE_52, nx - ny),
        "{a:?} - {b:?} ∌ {x} - {y}"
    );
}
harness!(
    a4_interval_add_sub_enclose,
    unwind = 2,
    bits = 52,
    cases = pacs_proof_kit::DEFAULT_CASES,
    interval_add_sub
);

/// Bitwise equality of two intervals (the same result, computed two ways).
fn same_bits(a: Interval, b: Interval) -> bool {
    a.lo().to_bits() == b.lo().to_bits() && a.hi().to_bits() == b.hi().to_bits()
}

/// Which end of an operation's result a split harness checks.
#[derive(Clone, Copy, PartialEq)]
enum End {
    Lower,
    Upper,
}

/// The split of a4 `+` for the model checker, one end per harness. Over real numbers `x + y` is
/// increasing in both arguments, so a result contains the sum of every pair of members exactly
/// when its lower end is ≤ `a.lo + b.lo` and its upper end ≥ `a.hi + b.hi` (exact sums). `a − b`
/// is `a + (−b)` bit for bit and negation is exact, so these two claims cover `−` as well
/// (the twin [`interval_add_sub`] checks `−` directly). The sum of two points (the exact-sum
/// path) is decided whole by the lower harness, so the upper one takes the other cases: each
/// claim then reads the operands as the code path it checks does (one term for the solver).
fn interval_add_end<S: Source>(s: &mut S, end: End) {
    let Some((a, b)) = interval_operands(s) else {
        return;
    };
    let points = a.lo() == a.hi() && b.lo() == b.hi();
    let r = a + b;
    match end {
        End::Lower => {
            assert!(
                cmp_sum(a.lo(), b.lo(), r.lo()) != Less,
                "{a:?} + {b:?}: lower"
            );
            if points {
                assert!(
                    cmp_sum(a.lo(), b.lo(), r.hi()) != Greater,
                    "{a:?} + {b:?}: point"
                );
            }
        }
        End::Upper => {
            if !points {
                assert!(
                    cmp_sum(a.hi(), b.hi(), r.hi()) != Greater,
                    "{a:?} + {b:?}: upper"
                );
            }
        }
    }
}
fn interval_add_lower<S: Source>(s: &mut S) {
    interval_add_end(s, End::Lower);
}
fn interval_add_upper<S: Source>(s: &mut S) {
    interval_add_end(s, End::Upper);
}
harness!(
    a4_interval_add_lower,
    unwind = 2,
    bits = 27,
    cases = pacs_proof_kit::DEFAULT_CASES,
    interval_add_lower
);
harness!(
    a4_interval_add_upper,
    unwind = 2,
    bits = 27,
    cases = pacs_proof_kit::DEFAULT_CASES,
    interval_add_upper
);

/// Interval `×` contains the exact product for every pair of members (the whole claim). Kani
/// checks it on the rounding grid ([`grid_value`]: ends and members of both operands, points
/// included, an integer oracle); the twin draws the grid with full-width significands and any
/// intervals in ±1e3 (with [`cmp_prod`] as the oracle). [`interval_mul_corners`] proves the
/// composition at 4- and 3-bit ends.
fn interval_mul<S: Source>(s: &mut S) {
    if !cfg!(kani)
        && let (Some(a), Some(b)) = (interval(s, 1e3, 10.0), interval(s, 1e3, 10.0))
    {
        let (x, y) = (member(s, a), member(s, b));
        if s.assume(tame(x) && tame(y)) {
            assert!(inside_prod(a * b, x, y), "{a:?} * {b:?} ∌ {x} * {y}");
        }
    }
    let (Some((a, x, nx)), Some((b, y, ny))) = (grid_interval_member(s), grid_interval_member(s))
    else {
        return;
    };
    assert!(
        grid_contains(a * b, SCALE_104, nx * ny),
        "{a:?} * {b:?} ∌ {x} * {y}"
    );
}
harness!(
    a4_interval_mul_enclose,
    unwind = 2,
    bits = 52,
    cases = pacs_proof_kit::DEFAULT_CASES,
    interval_mul
);

/// The split of a4 `×` for the model checker. Over real numbers `x·y` is bilinear, so its
/// extremes over a box of members are taken at the four corners; `×` returns the least
/// `mul_down` and the greatest `mul_up` of the corners, which enclose the exact corner products
/// by a2 (`mul_down`/`mul_up`, proved beside them). The harness proves the composition: for two
/// intervals that are not points, the result's lower end is ≤ `mul_down` and its upper end ≥
/// `mul_up` of every corner (the same terms as the code's, compared in floating point); a point
/// operand makes `×` the `scale` of the other, checked bit for bit (the `scale` harness proves
/// that). The twin checks the exact claim at a random corner. Under Kani `a` has 4-bit and `b`
/// [`NARROW`]-bit ends: the composition does not depend on whether the products round (a2
/// proves `mul_down`/`mul_up` at full width), and narrow factors keep the solver's four
/// multipliers small; mutant `x3` (the lower end from the nominal products) still fails, as
/// `mul_down` is always below the nominal product.
fn interval_mul_corners<S: Source>(s: &mut S) {
    let Some((a, b)) = interval_operands(s) else {
        return;
    };
    let r = a * b;
    if a.lo() == a.hi() {
        assert!(same_bits(r, b.scale(a.lo())));
        return;
    }
    if b.lo() == b.hi() {
        assert!(same_bits(r, a.scale(b.lo())));
        return;
    }
    for (x, y) in [
        (a.lo(), b.lo()),
        (a.lo(), b.hi()),
        (a.hi(), b.lo()),
        (a.hi(), b.hi()),
    ] {
        assert!(
            r.lo() <= mul_down(x, y),
            "{a:?} * {b:?}: lower above {x}·{y}"
        );
        assert!(r.hi() >= mul_up(x, y), "{a:?} * {b:?}: upper below {x}·{y}");
    }
    if !cfg!(kani) {
        let x = if s.bool() { a.lo() } else { a.hi() };
        let y = if s.bool() { b.lo() } else { b.hi() };
        assert!(inside_prod(r, x, y), "{a:?} * {b:?} ∌ {x}·{y}");
    }
}
harness!(
    a4_interval_mul_corners,
    unwind = 5,
    bits = 4,
    cases = pacs_proof_kit::DEFAULT_CASES,
    interval_mul_corners
);

/// `scale` and `sqr` contain the exact product / square of every member (the whole claim), and
/// a square's lower end is ≥ 0, and 0 where the interval holds 0. Kani checks it on the rounding
/// grid ([`grid_value`]: the ends, the member and `k`, an integer oracle); the twin draws the
/// grid with full-width significands and any intervals and `k` in ±1e3 (with [`cmp_prod`]).
/// The splits below prove the composition at 8- and 3-bit operands.
fn interval_scale_sqr<S: Source>(s: &mut S) {
    if !cfg!(kani)
        && let Some(a) = interval(s, 1e3, 10.0)
    {
        let x = member(s, a);
        let k = s.f64_in(-1e3, 1e3);
        if s.assume(tame(x) && tame(k)) {
            assert!(
                inside_prod(a.scale(k), x, k),
                "{a:?}.scale({k}) ∌ {x} * {k}"
            );
            let sq = a.sqr();
            assert!(inside_prod(sq, x, x), "{a:?}.sqr() ∌ {x}²");
            assert!(sq.lo() >= 0.0 && (!a.contains(0.0) || sq.lo() == 0.0));
        }
    }
    let Some((a, x, nx)) = grid_interval_member(s) else {
        return;
    };
    let (k, nk) = grid_value(s);
    assert!(
        grid_contains(a.scale(k), SCALE_104, nx * nk),
        "{a:?}.scale({k}) ∌ {x} * {k}"
    );
    let sq = a.sqr();
    assert!(grid_contains(sq, SCALE_104, nx * nx), "{a:?}.sqr() ∌ {x}²");
    assert!(sq.lo() >= 0.0 && (!a.contains(0.0) || sq.lo() == 0.0));
}
harness!(
    a4_interval_scale_sqr_enclose,
    unwind = 2,
    bits = 52,
    cases = pacs_proof_kit::DEFAULT_CASES,
    interval_scale_sqr
);

/// The split of a4 `scale` for the model checker: `x·k` is linear in `x`, so its extremes over
/// the members are at `a.lo` and `a.hi`; `scale` returns the least `mul_down` and the greatest
/// `mul_up` of the two ends, which enclose the exact products by a2. The harness proves the
/// composition (the result's ends against `mul_down`/`mul_up` of both ends, the same terms as
/// the code's) and, for a point, the exact-product path against the exact product; the twin
/// checks the exact claim at either end. Under Kani `a` has 8-bit ends and `k` [`NARROW`] bits
/// (the composition does not depend on the widths; a2 proves the roundings at full width).
fn interval_scale_ends<S: Source>(s: &mut S) {
    let Some(a) = wide_interval(s) else {
        return;
    };
    let k = s.f64_short(-1e3, 1e3, NARROW);
    if !s.assume(tame(k)) {
        return;
    }
    if a.lo() == a.hi() {
        // A point: `a4_interval_scale_point`.
        return;
    }
    let r = a.scale(k);
    for x in [a.lo(), a.hi()] {
        assert!(
            r.lo() <= mul_down(x, k),
            "{a:?}.scale({k}): lower above {x}·{k}"
        );
        assert!(
            r.hi() >= mul_up(x, k),
            "{a:?}.scale({k}): upper below {x}·{k}"
        );
    }
    if !cfg!(kani) {
        let x = if s.bool() { a.lo() } else { a.hi() };
        assert!(inside_prod(r, x, k), "{a:?}.scale({k}) ∌ {x}·{k}");
    }
}
harness!(
    a4_interval_scale_ends,
    unwind = 3,
    bits = 8,
    cases = pacs_proof_kit::DEFAULT_CASES,
    interval_scale_ends
);

/// `scale` of a point: where the product is exactly a float (the exact-product path, a point
/// result) the result contains the exact product, decided on the code's own exact test; where it
/// is not (the general path, never a point: `mul_down < mul_up`), the result's ends bound
/// `mul_down`/`mul_up` of the point, as in [`interval_scale_ends`] (a2 proves them exact bounds).
/// `x` of the harness width, `k` [`NARROW`] bits; the twin checks the exact claim throughout.
fn interval_scale_point<S: Source>(s: &mut S) {
    let Some(x) = num(s, 1e3) else {
        return;
    };
    let k = s.f64_short(-1e3, 1e3, NARROW);
    if !s.assume(tame(k)) {
        return;
    }
    let r = Interval::point(x).scale(k);
    if r.lo() == r.hi() || !cfg!(kani) {
        assert!(inside_prod(r, x, k), "[{x}].scale({k}) ∌ {x}·{k}");
    }
    if r.lo() != r.hi() {
        assert!(r.lo() <= mul_down(x, k) && r.hi() >= mul_up(x, k));
    }
}
harness!(
    a4_interval_scale_point,
    unwind = 2,
    bits = 52,
    cases = pacs_proof_kit::DEFAULT_CASES,
    interval_scale_point
);

/// The split of a4 `sqr` for the model checker: `x²` over `[lo, hi]` takes its maximum at an
/// end and its minimum at an end or, when the interval holds 0, at 0; the harness checks the
/// result against any end and is ≥ 0, and 0 when the interval holds 0. Ends of 8 bits, whose
/// squares are exact: this checks the case logic (signs, the straddling case); the outward
/// rounding of squares (beyond 26 bits, where the model checker would have to equate two
/// 27-bit multipliers) is the twin's, at full width.
fn interval_sqr_cases<S: Source>(s: &mut S) {
    let p = s.f64_short(-1e3, 1e3, 8);
    let q = s.f64_short(-1e3, 1e3, 8);
    if !s.assume(tame(p) && tame(q) && p <= q) {
        return;
    }
    let b = Interval::new(p, q).expect("ordered");
    let z = if s.bool() { p } else { q };
    let sq = b.sqr();
    assert!(inside_prod(sq, z, z), "{b:?}.sqr() ∌ {z}²");
    assert!(sq.lo() >= 0.0 && (!b.contains(0.0) || sq.lo() == 0.0));
}
harness!(
    a4_interval_sqr_cases,
    unwind = 2,
    bits = 8,
    cases = pacs_proof_kit::DEFAULT_CASES,
    interval_sqr_cases
);

/// `mid` is a member and `rad_up` bounds the distance from it to either end.
fn interval_mid_rad<S: Source>(s: &mut S) {
    let Some(a) = interval(s, 1e3, 10.0) else {
        return;
    };
    let m = a.mid();
    assert!(a.contains(m), "mid {m} ∉ {a:?}");
    let r = a.rad_up();
    assert!(cmp_sum(a.hi(), -m, r) != Greater && cmp_sum(m, -a.lo(), r) != Greater);
}
harness!(
    a4_interval_mid_rad,
    unwind = 2,
    bits = 16,
    cases = pacs_proof_kit::DEFAULT_CASES,
    interval_mid_rad
);
