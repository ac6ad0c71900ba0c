//! Proofs of the interval operations, beside them (claim C1: every interval operation contains
//! the exact result for every pair of members). Emitted by [`harness!`] as Kani proofs
//! (`cargo kani -p pacs-reach --lib --harness NAME`) and seeded property tests (`cargo test -p
//! pacs-reach`). Results, widths and splits: `proofs/README.md`.
// Proof functions are entry points of the model checker, not called from the crate.
#![cfg_attr(kani, allow(dead_code))]
use super::*;
use crate::exact::{cmp_prod, cmp_sum, tame};
use crate::rounding::proofs::num;
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

/// An interval whose two ends have at most 6 significand bits under Kani (drawn independently
/// and ordered), any interval of width ≤ 10 in the twin: the second operand of a product,
/// narrow for the same reason as `y` in a2.
fn narrow_interval<S: Source>(s: &mut S, m: f64) -> Option<Interval> {
    if !cfg!(kani) {
        return interval(s, m, 10.0);
    }
    let (p, q) = (s.f64_short(-m, m, 6), s.f64_short(-m, m, 6));
    s.assume(tame(p) && tame(q) && p <= q).then_some(())?;
    Interval::new(p, q)
}

/// Two intervals in [−1e3, 1e3 + 10] and a member of each.
///
/// Split (proofs/README.md): under Kani the members are the intervals' ends, `x ∈ {a.lo, a.hi}`
/// and `y ∈ {b.lo, b.hi}`: sums and products of real intervals take their extremes at the ends
/// (`x + y` is monotone in each argument, `x·y` bilinear), so a result that contains the exact
/// results at the four corners contains those of every pair of members. `a` has the harness
/// width, `b` narrow ends ([`narrow_interval`]). The twin draws both intervals at full width and
/// members anywhere in them. (A symbolic member between two symbolic ends makes the model
/// checker prove the monotonicity of its float multipliers: beyond the budget.)
fn interval_pair<S: Source>(s: &mut S) -> Option<(Interval, Interval, f64, f64)> {
    let a = interval(s, 1e3, 10.0)?;
    let b = narrow_interval(s, 1e3)?;
    let (x, y) = (member(s, a), member(s, b));
    s.assume(tame(x) && tame(y)).then_some((a, b, x, y))
}

/// A member of `a`: under Kani one of its ends (the split of [`interval_pair`]), anywhere in `a`
/// in the twin.
fn member<S: Source>(s: &mut S, a: Interval) -> f64 {
    if cfg!(kani) {
        if s.bool() { a.lo() } else { a.hi() }
    } else {
        s.f64_in(a.lo(), a.hi())
    }
}

fn inside_sum(r: Interval, x: f64, y: f64) -> bool {
    cmp_sum(x, y, r.lo()) != Less && cmp_sum(x, y, r.hi()) != Greater
}

fn inside_prod(r: Interval, x: f64, y: f64) -> bool {
    cmp_prod(x, y, r.lo()) != Less && cmp_prod(x, y, r.hi()) != Greater
}

/// Interval `+`, `−` and negation contain the exact result for every pair of members.
///
/// Split: under Kani `+` and negation (`a − b` is implemented as `a + (−b)`, bit for bit, so
/// the two proved claims cover it); the twin checks all three directly.
fn interval_add_sub<S: Source>(s: &mut S) {
    let Some((a, b, x, y)) = interval_pair(s) else {
        return;
    };
    assert!(inside_sum(a + b, x, y), "{a:?} + {b:?} ∌ {x} + {y}");
    assert!((-a).contains(-x));
    if !cfg!(kani) {
        assert!(inside_sum(a - b, x, -y), "{a:?} - {b:?} ∌ {x} - {y}");
    }
}
harness!(
    a4_interval_add_sub_enclose,
    unwind = 2,
    bits = 27,
    cases = pacs_proof_kit::DEFAULT_CASES,
    interval_add_sub
);

/// Interval `×` contains the exact product for every pair of members. Under Kani `a` has full
/// width and `b` 6-bit ends: products of up to 59 bits, which round (with both narrow every
/// product would be exact and the outward rounding untested; mutant `x3` must fail here).
fn interval_mul<S: Source>(s: &mut S) {
    let Some((a, b, x, y)) = interval_pair(s) else {
        return;
    };
    assert!(inside_prod(a * b, x, y), "{a:?} * {b:?} ∌ {x} * {y}");
}
harness!(
    a4_interval_mul_enclose,
    unwind = 2,
    bits = 52,
    cases = pacs_proof_kit::DEFAULT_CASES,
    interval_mul
);

/// `scale` and `sqr` contain the exact product / square of every member (under Kani: of each
/// end, and 0 for `sqr` when the interval holds it — the extremes of `x·k` and `x²`; see
/// [`interval_pair`]).
///
/// Split: under Kani `a` has full width and `k` 6 bits (as in a2), so `scale`'s products round;
/// `sqr` is checked on an interval with 8-bit ends, whose squares are exact: that checks its
/// case logic (signs, the straddling case), while its outward rounding — a square rounds only
/// beyond 26 bits, where the model checker would have to equate two 27-bit multipliers — is the
/// twin's (full-width intervals).
fn interval_scale_sqr<S: Source>(s: &mut S) {
    let Some(a) = interval(s, 1e3, 10.0) else {
        return;
    };
    let x = member(s, a);
    let k = s.f64_short(-1e3, 1e3, 6);
    if !s.assume(tame(x) && tame(k)) {
        return;
    }
    assert!(
        inside_prod(a.scale(k), x, k),
        "{a:?}.scale({k}) ∌ {x} * {k}"
    );
    let (b, z) = if cfg!(kani) {
        let p = s.f64_short(-1e3, 1e3, 8);
        let q = s.f64_short(-1e3, 1e3, 8);
        if !s.assume(tame(p) && tame(q) && p <= q) {
            return;
        }
        let b = Interval::new(p, q).expect("ordered");
        (b, if s.bool() { p } else { q })
    } else {
        (a, x)
    };
    let sq = b.sqr();
    assert!(inside_prod(sq, z, z), "{b:?}.sqr() ∌ {z}²");
    assert!(sq.lo() >= 0.0 && (!b.contains(0.0) || sq.lo() == 0.0));
}
harness!(
    a4_interval_scale_sqr_enclose,
    unwind = 2,
    bits = 52,
    cases = pacs_proof_kit::DEFAULT_CASES,
    interval_scale_sqr
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
