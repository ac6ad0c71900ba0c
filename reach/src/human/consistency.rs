//! Two measurements of one person held against each other: whether they contradict the human
//! model (some keypoint moved farther than `v_max·|Δt| + 2·measurement_error_pos` between their
//! stamps). The audit checks every record against the others kept (`human_exceeds_model`); the
//! shield does not trust a measurement that contradicts the ones it trusts. Every test is
//! conservative: distances rounded up, allowances rounded down, and the quick accepts in plain
//! floats only where their rounding error is far inside a 1e-9 margin, so rounding never hides a
//! contradiction. The Kani harnesses (`h3_keypoint_pair_sound`, `h3_keypoints_accept_sound`,
//! `h3_object_accept_sound`) sit with the audit's record checks (`audit/src/check/consistency/
//! proofs.rs`), which call these.

use super::HumanMeasurement;
use crate::rounding::{add_down, dist3_up, mul_down, sub_down};
use pacs_models::HumanModel;

/// `(min, max)` of two times.
fn order(a: f64, b: f64) -> (f64, f64) {
    (a.min(b), a.max(b))
}

/// Whether two measurements of one person contradict the human model: some keypoint moved
/// farther than `v_max·|Δt| + 2·e_pos` (m) between their stamps ([`keypoint_breaks`] for each
/// keypoint and its own `v_max`).
pub fn human_pair_breaks(model: &HumanModel, a: &HumanMeasurement, b: &HumanMeasurement) -> bool {
    let (lo, hi) = order(a.time(), b.time());
    let e_pos = model.measurement_error_pos();
    let pairs = || {
        a.positions()
            .iter()
            .zip(b.positions())
            .zip(model.v_max())
            .map(|((p, q), &v)| ([p.x, p.y, p.z], [q.x, q.y, q.z], v))
    };
    // Most pairs are accepted by every keypoint's plain-float test at once; only a pair one of
    // them does not accept is decided keypoint by keypoint.
    !keypoints_within_plain(pairs(), lo, hi, e_pos)
        && pairs().any(|(p, q, v)| keypoint_breaks(p, q, v, lo, hi, e_pos))
}

/// Whether every keypoint `(p, q, v)` of a pair of records passes the plain-float accept of
/// [`keypoint_breaks`] ([`keypoint_within_plain`]), all evaluated without early exit: true only
/// if `‖p − q‖ ≤ v·(hi − lo) + 2·e_pos` exactly for every one of them.
///
/// # Soundness
/// Claim C9 (the consistency check's fast accept): harness `h3_keypoints_accept_sound` (Kani on
/// grids of dyadic values with two keypoints; the twin nine keypoints at full width with the
/// exact oracle); mutant `x86` (the pair accepted where any one keypoint is) fails it.
#[inline]
pub fn keypoints_within_plain(
    pairs: impl Iterator<Item = ([f64; 3], [f64; 3], f64)>,
    lo: f64,
    hi: f64,
    e_pos: f64,
) -> bool {
    let mut all_within = true;
    for (p, q, v) in pairs {
        all_within &= keypoint_within_plain(p, q, v, lo, hi, e_pos);
    }
    all_within
}

/// Whether one keypoint, at `p` at one stamp and at `q` at the other (m; stamps `lo ≤ hi`, s),
/// moved farther than `v·(hi − lo) + 2·e_pos` (m; `v` its speed bound, m/s, `e_pos` the
/// position error, m, both ≥ 0).
///
/// # Soundness
/// Claim C9 (the audit's record-against-record consistency): false only if
/// `‖p − q‖ ≤ v·(hi − lo) + 2·e_pos` exactly. Conservative both ways: the distance rounded up,
/// the allowance rounded down, so rounding never hides a contradiction (one within an ulp is
/// flagged too). Harness `h3_keypoint_pair_sound` (Kani on grids of dyadic values, where the
/// decision's terms are exact, with `dist3_up` any upper bound (C1 makes it one); the twin at
/// full width with the exact oracle); mutant `x64` fails it.
#[inline(always)]
pub fn keypoint_breaks(p: [f64; 3], q: [f64; 3], v: f64, lo: f64, hi: f64, e_pos: f64) -> bool {
    // Equal positions moved by 0 m, within any allowance (≥ 0): an exact duplicate of a record
    // is no contradiction, even where outward rounding of a zero distance would exceed a zero
    // allowance (no measurement error, equal stamps).
    if p == q {
        return false;
    }
    if keypoint_within_plain(p, q, v, lo, hi, e_pos) {
        return false;
    }
    let dt = sub_down(hi, lo).max(0.0);
    let allowed = add_down(mul_down(v, dt), mul_down(2.0, e_pos));
    dist3_up(&p, &q) > allowed
}

/// The fast accept of [`keypoint_breaks`] in plain floats: true only if
/// `‖p − q‖ ≤ v·(hi − lo) + 2·e_pos` exactly (arguments as there). The squared distance and the
/// squared allowance (three rounded operations from exact values) each carry a relative
/// rounding error of a few ε, far inside the 1e-9 margin, so a pair accepted here is within the
/// allowance exactly. Only where neither overflows (d² finite, allowance ≤ 1e150 so that its
/// square is finite and keeps the margin) nor underflows (allowance ≥ 1e-135, so its square is
/// normal and an underflowed d² is far below it): the test [`within_plain`]; false otherwise
/// (the caller decides by the outward-rounded distance and allowance). Evaluated for every
/// keypoint of a pair at once by [`keypoints_within_plain`]. Checked with `keypoint_breaks` by
/// `h3_keypoint_pair_sound`, and for several keypoints by `h3_keypoints_accept_sound`.
#[inline(always)]
pub fn keypoint_within_plain(
    p: [f64; 3],
    q: [f64; 3],
    v: f64,
    lo: f64,
    hi: f64,
    e_pos: f64,
) -> bool {
    within_plain(&p, &q, v * (hi - lo).max(0.0) + 2.0 * e_pos)
}

/// The test of every plain-float accept ([`keypoint_within_plain`], [`object_pair_within_plain`]):
/// true only if `‖p − q‖ ≤ allowed` certainly ([`squared_within`] of the squared distance;
/// arguments in m or m/s, `allowed` computed in plain floats with a relative error of a few ε).
///
/// # Soundness
/// Claim C9 (the fast accept of the consistency check): harness `h3_object_accept_sound`
/// (Kani: this test on grids of dyadic values, where the allowance is exact; the twin the
/// whole object accept at full width with the exact oracle), and through the keypoint accept
/// `h3_keypoint_pair_sound`.
#[inline(always)]
pub fn within_plain(p: &[f64; 3], q: &[f64; 3], allowed: f64) -> bool {
    let (dx, dy, dz) = (p[0] - q[0], p[1] - q[1], p[2] - q[2]);
    squared_within(dx * dx + dy * dy + dz * dz, allowed)
}

/// The one margin rule of the plain-float accepts: a squared distance `d2` (m² or m²/s²,
/// computed with a relative error of a few ε; an underflowed difference or square lowers it by
/// at most ≈ 1e-323) within the squared allowance less 1e-9, the allowance in `[1e-135, 1e150]`
/// (its square normal and finite, so the margin, at least 1e-279, holds; and the outward-rounded
/// tests' absolute slack of 1e-150 stays below 1e-15 of the allowance) and `d2` finite.
#[inline(always)]
pub fn squared_within(d2: f64, allowed: f64) -> bool {
    (1e-135..=1e150).contains(&allowed) && d2.is_finite() && d2 <= allowed * allowed * (1.0 - 1e-9)
}
