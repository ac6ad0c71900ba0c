//! Conservative geometric queries on capsules (a sphere is a capsule with `p1 == p2`).
//!
//! Guarantee: [`segment_distance_lower_bound`] never exceeds the exact distance between the two
//! segments (as real-number sets with the given f64 endpoints), so [`capsules_disjoint`] never says
//! "disjoint" when the exact capsules touch or overlap.
//!
//! Method: closest points are computed in ordinary floating point only to get a direction
//! `n = P − Q`; the bound itself is a separating-axis certificate,
//! `min_a n·a − max_b n·b` over the segment endpoints, divided by `|n|`, evaluated with outward
//! rounding. Any direction yields a valid lower bound; the closest-point direction makes it tight
//! (equal to the distance up to a few ulps).

use crate::rounding::{add_up, div_down, norm3_up, sub_down};
use nalgebra::{Point3, Vector3};
use pacs_models::Capsule;

/// Relative error bound used for a 3-term dot product: ≥ γ₃ = 3u/(1−3u), u = 2⁻⁵³ (Higham, Thm 3.1),
/// with margin for the rounding of the bound itself.
const DOT_REL: f64 = 1e-15;

/// Lower and upper bounds of the exact dot product `n·a` of two f64 vectors.
///
/// # Soundness
/// Claim C2: `lo ≤ n·a ≤ hi` exactly, for finite `n`, `a` without overflow (a three-term dot
/// product is within γ₃·Σ|nᵢaᵢ| of the exact value; `DOT_REL` exceeds γ₃ with margin for the
/// rounding of the bound, `MIN_POSITIVE` covers underflow). Harness `b1_dot_bounds_enclose`
/// (beside this module; Kani on a grid where the products and their sum round, its twin any
/// vectors) and the Kani split `b1_dot_bounds_grid` (exact products of wider range whose sum
/// rounds); mutant `x7` caught by both.
#[inline]
pub(crate) fn dot_bounds(n: &Vector3<f64>, a: &Point3<f64>) -> (f64, f64) {
    let d = n.x * a.x + n.y * a.y + n.z * a.z;
    let mag = (n.x * a.x).abs() + (n.y * a.y).abs() + (n.z * a.z).abs();
    let err = mag * DOT_REL + f64::MIN_POSITIVE;
    (d - err, d + err)
}

/// Parameters `(s, t)` in [0, 1]² of (approximately) closest points `a0 + s(a1−a0)`, `b0 + t(b1−b0)`.
/// Only used to choose a direction; correctness of the bounds does not depend on it.
#[inline]
fn closest_params(
    a0: &Point3<f64>,
    a1: &Point3<f64>,
    b0: &Point3<f64>,
    b1: &Point3<f64>,
) -> (f64, f64) {
    let d1 = a1 - a0;
    let d2 = b1 - b0;
    let r = a0 - b0;
    let a = d1.dot(&d1);
    let e = d2.dot(&d2);
    let f = d2.dot(&r);
    const EPS: f64 = 1e-300;
    if a <= EPS && e <= EPS {
        return (0.0, 0.0);
    }
    if a <= EPS {
        return (0.0, (f / e).clamp(0.0, 1.0));
    }
    let c = d1.dot(&r);
    if e <= EPS {
        return ((-c / a).clamp(0.0, 1.0), 0.0);
    }
    let b = d1.dot(&d2);
    let denom = a * e - b * b;
    let mut s = if denom > 1e-18 * a * e {
        ((b * f - c * e) / denom).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let mut t = (b * s + f) / e;
    if t < 0.0 {
        t = 0.0;
        s = (-c / a).clamp(0.0, 1.0);
    } else if t > 1.0 {
        t = 1.0;
        s = ((b - c) / a).clamp(0.0, 1.0);
    }
    (s, t)
}

/// Nominal (round-to-nearest) closest points of segments `a0a1` and `b0b1`: for controllers and
/// diagnostics, not a bound.
pub fn segment_closest_points(
    a0: &Point3<f64>,
    a1: &Point3<f64>,
    b0: &Point3<f64>,
    b1: &Point3<f64>,
) -> (Point3<f64>, Point3<f64>) {
    let (s, t) = closest_params(a0, a1, b0, b1);
    (a0 + (a1 - a0) * s, b0 + (b1 - b0) * t)
}

/// A lower bound (m, ≥ 0) of the exact Euclidean distance between segments `a0a1` and `b0b1`.
///
/// # Soundness
/// Claim C2: never above the exact distance (outward-rounded separating-axis bound). Harness
/// `b1_segment_distance_lower_bound`; mutant `x7` caught.
#[inline]
pub fn segment_distance_lower_bound(
    a0: &Point3<f64>,
    a1: &Point3<f64>,
    b0: &Point3<f64>,
    b1: &Point3<f64>,
) -> f64 {
    let (s, t) = closest_params(a0, a1, b0, b1);
    let p = a0 + (a1 - a0) * s;
    let q = b0 + (b1 - b0) * t;
    separating_axis_lower_bound(&(p - q), a0, a1, b0, b1)
}

/// The separating-axis certificate along direction `n`: a lower bound (m, ≥ 0) of the exact
/// distance between segments `a0a1` and `b0b1`, `(min_a n·a − max_b n·b) / |n|` over the
/// endpoints, outward rounded; 0 when `n` is 0 or not finite, or the segments' projections
/// overlap.
///
/// # Soundness
/// Claim C2, for **every** direction `n` (the closest-point direction of
/// [`segment_distance_lower_bound`] only makes it tight). Argument: every point `p` of `a0a1` is a
/// convex combination of its ends, so `n·p ≥ min(n·a0, n·a1) ≥ min(a0l, a1l)` (the lower ends of
/// [`dot_bounds`]); likewise `n·q ≤ max(b0h, b1h)` on `b0b1`; then `|p − q| ≥ n·(p − q)/|n| ≥
/// gap/len` (Cauchy–Schwarz) where `gap ≤` the exact difference (`sub_down`) and `len ≥ |n|`
/// (`norm3_up`), and `div_down` rounds the quotient down. The floating-point steps are proved
/// one by one: `dot_bounds` by harness `b1_dot_bounds_enclose` (beside this module), `sub_down`
/// by `a1_sub_enclose`, `div_down` by `a2_div_enclose`, `norm3_up` by `a3_norm_up_encloses`; the
/// whole bound against sampled points for random directions by the twin
/// `b1_separating_axis_any_direction` and, with the closest-point direction, by
/// `b1_segment_distance_lower_bound` (`proofs/README.md`). Mutant `x7` caught. The quotient is
/// clamped at 0 (a distance is never negative, so 0 is a lower bound too): a one-ulp gap over
/// `|n| > 2` underflows to 0, which `div_down` steps to −2⁻¹⁰⁷⁴ (test
/// `a_gap_that_underflows_gives_a_bound_of_zero_not_below`, beside this module).
#[inline]
pub fn separating_axis_lower_bound(
    n: &Vector3<f64>,
    a0: &Point3<f64>,
    a1: &Point3<f64>,
    b0: &Point3<f64>,
    b1: &Point3<f64>,
) -> f64 {
    if !(n.x.is_finite() && n.y.is_finite() && n.z.is_finite()) {
        return 0.0;
    }
    let len = norm3_up(n.x, n.y, n.z);
    if len == 0.0 || !len.is_finite() {
        return 0.0;
    }
    let (a0l, _) = dot_bounds(n, a0);
    let (a1l, _) = dot_bounds(n, a1);
    let (_, b0h) = dot_bounds(n, b0);
    let (_, b1h) = dot_bounds(n, b1);
    let gap = sub_down(a0l.min(a1l), b0h.max(b1h));
    // `max`: a quotient that underflows to 0 steps down to −2⁻¹⁰⁷⁴; the bound stays ≥ 0.
    if gap > 0.0 {
        div_down(gap, len).max(0.0)
    } else {
        0.0
    }
}

/// An upper bound (m) of the exact distance between the two segments (from explicit points,
/// rounded up). Together with the lower bound it brackets the distance.
pub fn segment_distance_upper_bound(
    a0: &Point3<f64>,
    a1: &Point3<f64>,
    b0: &Point3<f64>,
    b1: &Point3<f64>,
) -> f64 {
    let (s, t) = closest_params(a0, a1, b0, b1);
    let p = a0 + (a1 - a0) * s;
    let q = b0 + (b1 - b0) * t;
    // p and q are within a few ulps of the segments; bound that drift generously.
    let drift =
        |x: &Point3<f64>, y: &Point3<f64>| (x.coords.abs().max() + y.coords.abs().max()) * 1e-14;
    let n = p - q;
    add_up(
        add_up(norm3_up(n.x, n.y, n.z), drift(a0, a1)),
        drift(b0, b1),
    )
}

/// A lower bound (m, ≥ 0) of the distance between two capsules' surfaces (0 if they may touch).
#[inline]
pub fn capsule_distance_lower_bound(a: &Capsule, b: &Capsule) -> f64 {
    capsule_separation_lower_bound(a, b).max(0.0)
}

/// `d − (ra + rb)` rounded down: the margin of two capsules of radii `ra`, `rb` whose core
/// segments are at least `d` apart.
///
/// # Soundness
/// Claim C2: `≤ d − ra − rb` exactly, so a positive margin proves `d > ra + rb`. Harness
/// `b2_capsule_margin_sound` (beside this module).
#[inline]
pub(crate) fn margin(d: f64, ra: f64, rb: f64) -> f64 {
    sub_down(d, add_up(ra, rb))
}

/// The separation figure of two capsules (m): a lower bound of the distance between their core
/// segments minus the sum of their radii, rounded down, **not** clamped at 0. Positive: the
/// capsules are provably apart by at least this much. Zero or negative: they may overlap, and
/// the magnitude is how far the radii overlap at the bound (not a bound on penetration depth).
/// [`capsule_distance_lower_bound`] is this clamped at 0.
pub fn capsule_separation_lower_bound(a: &Capsule, b: &Capsule) -> f64 {
    let d = segment_distance_lower_bound(&a.p1(), &a.p2(), &b.p1(), &b.p2());
    margin(d, a.radius(), b.radius())
}

/// True only if the capsules are provably disjoint (exact distance > sum of radii).
///
/// # Soundness
/// Claim C2: given `d ≤` the exact segment distance (`segment_distance_lower_bound`), `true` only
/// if `d > ra + rb` exactly. The rounding step is harness `b2_capsule_margin_sound` (beside this
/// module); the whole test against touching capsules is the twin
/// `b2_capsule_intersection_conservative`.
#[inline]
pub fn capsules_disjoint(a: &Capsule, b: &Capsule) -> bool {
    capsule_separation_lower_bound(a, b) > 0.0
}

/// True unless the capsules are provably disjoint: touching counts as intersecting.
///
/// # Soundness
/// Claim C2: `false` only if the capsules are disjoint (touching counts as intersecting).
/// Harness `b2_capsule_intersection_conservative`.
#[inline]
pub fn capsules_may_intersect(a: &Capsule, b: &Capsule) -> bool {
    !capsules_disjoint(a, b)
}

/// A lower bound (m, ≥ 0) of the distance from point `p` to the capsule's surface (0 if inside).
pub fn point_capsule_distance_lower_bound(p: &Point3<f64>, c: &Capsule) -> f64 {
    let d = segment_distance_lower_bound(p, p, &c.p1(), &c.p2());
    sub_down(d, c.radius()).max(0.0)
}

/// True only if point `p` provably lies in the closed capsule (distance to axis ≤ radius).
pub fn capsule_contains_point(c: &Capsule, p: &Point3<f64>) -> bool {
    segment_distance_upper_bound(p, p, &c.p1(), &c.p2()) <= c.radius()
}

/// The Kani proofs of this module, each also a property test (`proofs/README.md`).
#[cfg(any(test, kani))]
mod proofs;
