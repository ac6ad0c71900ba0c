//! Two measurements of one object held against each other: whether they contradict its model
//! (velocities, positions and the direction of a measured velocity; `object_exceeds_model` in
//! the audit, which checks every record against the others kept; the shield does not trust a
//! measurement that contradicts the ones it trusts). Every test is conservative: distances
//! rounded up, allowances rounded down, and the quick accepts in plain floats only where their
//! rounding error is far inside a 1e-9 margin. The Kani harnesses (`h3_object_pair_sound`,
//! `h3_object_accept_sound`) sit with the audit's record checks (`audit/src/check/consistency/
//! proofs.rs`), which call these.

use super::ObjectMeasurement;
use crate::human::consistency::within_plain;
use crate::rounding::{add_down, dist3_up, mul_down, norm3_up, sub_down};
use pacs_models::object::ObjectModel;

/// A Euclidean norm rounded down (`crate::rounding::norm3_down`, harness a3).
fn norm3_down(v: [f64; 3]) -> f64 {
    crate::rounding::norm3_down(v[0], v[1], v[2])
}

/// An upper bound of the norm of every acceleration in an object's acceleration set (m/s²):
/// |bias| + Σ|generators| + `max_acc` (triangle inequality), each norm rounded down, so the
/// bound is below the exact one by ulps at most (a check using it flags within-ulp cases too).
pub fn object_acc_bound(model: &ObjectModel) -> f64 {
    let mut acc = norm3_down(model.acc_bias());
    for g in model.acc_generators() {
        acc = add_down(acc, norm3_down(*g));
    }
    add_down(acc, model.max_acc())
}

/// What [`object_pair_breaks`] needs of an object model: the bound of every acceleration
/// ([`object_acc_bound`], m/s², rounded down: it may lie just below zero), the speed bound (m/s)
/// if any, and the velocity and position errors (m/s, m), all ≥ 0; and whether the plain-float
/// accept takes these bounds ([`object_pair_within_plain`]), decided once.
#[derive(Debug, Clone, Copy)]
pub struct ObjectBounds {
    /// The bound of every acceleration (m/s², rounded down: it may lie just below zero).
    acc: f64,
    /// The speed bound (m/s), if any.
    max_speed: Option<f64>,
    /// The velocity error (m/s).
    vel_error: f64,
    /// The position error (m).
    pos_error: f64,
    /// The bounds are tame for the plain-float accept: the acceleration bound (taken as at
    /// least 0), its half, the speed bound and the errors each zero or normal and ≤ 1e100.
    plain: bool,
}

impl ObjectBounds {
    /// The speed bound (m/s), if the model has one, and twice the position error (m): what
    /// the audit's `LetGo` holds an object's records to.
    pub fn speed_and_2e(&self) -> (Option<f64>, f64) {
        (self.max_speed, 2.0 * self.pos_error)
    }

    /// The acceleration bound (m/s², at least 0) and twice the velocity error (m/s): what
    /// the audit's `LetGo` holds an object's measured velocities to (`velocities_break` per axis).
    pub fn acc_and_2ev(&self) -> (f64, f64) {
        (self.acc.max(0.0), 2.0 * self.vel_error)
    }

    /// The bound of every acceleration (m/s², rounded down: it may lie just below zero).
    pub fn acc(&self) -> f64 {
        self.acc
    }
    /// The speed bound (m/s), if any.
    pub fn max_speed(&self) -> Option<f64> {
        self.max_speed
    }
    /// The velocity error (m/s).
    pub fn vel_error(&self) -> f64 {
        self.vel_error
    }
    /// The position error (m).
    pub fn pos_error(&self) -> f64 {
        self.pos_error
    }

    /// The bounds, and whether the plain-float accept takes them (decided here, once: the
    /// fields cannot change afterwards).
    pub fn new(acc: f64, max_speed: Option<f64>, vel_error: f64, pos_error: f64) -> Self {
        let a = acc.max(0.0);
        let plain = [a, 0.5 * a, max_speed.unwrap_or(0.0), vel_error, pos_error]
            .into_iter()
            .all(plain_scalar);
        Self {
            acc,
            max_speed,
            vel_error,
            pos_error,
            plain,
        }
    }

    pub fn of(model: &ObjectModel) -> Self {
        Self::new(
            object_acc_bound(model),
            model.max_speed(),
            model.vel_error(),
            model.pos_error(),
        )
    }
}

/// Whether two measurements of one object, `early` stamped no later than `late`, contradict its
/// model's bounds `b` (both describe the state `delay` before their stamps, so `Δt` is the
/// stamps' difference):
/// - velocities, where both are measured, farther apart than `a·Δt + 2·vel_error`;
/// - positions farther apart than the model allows over `Δt` plus twice the position error:
///   the smallest of `max_speed·Δt` (with a speed bound) and `(|v| + vel_error)·Δt + a·Δt²/2`
///   for each measured velocity `v` (forward from the early one, backward from the late one);
///   with none of these the model bounds nothing and no pair contradicts it;
/// - for each measured velocity `v`, the displacement farther than `vel_error·Δt + a·Δt²/2`
///   plus twice the position error from `v·Δt` (its direction, not only its length).
///
/// # Soundness
/// Claim C9: false only if each of these holds exactly (allowances rounded down, distances and
/// norms bounded from the safe side: rounding never hides a contradiction). Harness
/// `h3_object_pair_sound`: its twin checks the whole function at full width with the exact
/// oracle, its Kani proof the velocity test ([`velocities_break`], on grids of dyadic values);
/// mutants `x56` (the velocity test dropped) and `x53` (the check dropped in the auditor, by the
/// audit's tests) fail.
pub fn object_pair_breaks(
    b: &ObjectBounds,
    early: &ObjectMeasurement,
    late: &ObjectMeasurement,
) -> bool {
    !object_pair_within_plain(b, early, late) && object_pair_breaks_rounded(b, early, late)
}

/// [`object_pair_breaks`] without its fast accept: each test with outward rounding.
pub fn object_pair_breaks_rounded(
    b: &ObjectBounds,
    early: &ObjectMeasurement,
    late: &ObjectMeasurement,
) -> bool {
    let dt = sub_down(late.time, early.time).max(0.0);
    let (acc, ev) = (b.acc, b.vel_error);
    if let (Some(a), Some(v)) = (early.velocity, late.velocity)
        && velocities_break(&a, &v, acc, dt, ev)
    {
        return true;
    }
    // Equal positions are within any distance allowance (exact duplicates are no
    // contradiction); the direction test below still holds them to a measured velocity (a
    // frozen tracker repeating a moving ball's record is one).
    let same_place = early.position == late.position;
    let by_speed = b.max_speed.map(|v| mul_down(v, dt));
    let by_velocity = [early.velocity, late.velocity]
        .into_iter()
        .flatten()
        .map(|v| {
            let speed = add_down(norm3_down(v), ev);
            // The acceleration term's lower bound, at least 0 (its exact value is): `acc` may lie
            // just below zero (a model without acceleration), and times `Δt²` up to 1e200 that
            // would lower the allowance by far more than an ulp.
            let by_acc = mul_down(mul_down(0.5, acc), mul_down(dt, dt)).max(0.0);
            add_down(mul_down(speed, dt), by_acc)
        })
        .reduce(f64::min);
    let allowed = match (by_speed, by_velocity) {
        (Some(a), Some(b)) => a.min(b),
        (Some(a), None) | (None, Some(a)) => a,
        (None, None) => return false,
    };
    let allowed = add_down(allowed, mul_down(2.0, b.pos_error));
    if !same_place && dist3_up(&early.position, &late.position) > allowed {
        return true;
    }
    // Direction: from a measured velocity `v`, the displacement lies within
    // `vel_error·Δt + a·Δt²/2` (plus twice the position error) of `v·Δt` — forward from the
    // early record, backward from the late one (`|Δp − v·Δt|` either way). The distance test
    // above bounds only its length: a velocity pointing away passed it.
    let dt_hi = crate::rounding::sub_up(late.time, early.time).max(0.0);
    let dts = crate::Interval::new(dt, dt_hi.max(dt)).unwrap_or(crate::Interval::point(dt_hi));
    let by_acc = mul_down(mul_down(0.5, acc), mul_down(dt, dt)).max(0.0);
    let band = add_down(
        add_down(mul_down(ev, dt), by_acc),
        mul_down(2.0, b.pos_error),
    );
    [early.velocity, late.velocity]
        .into_iter()
        .flatten()
        .any(|v| {
            let r: [f64; 3] = std::array::from_fn(|i| {
                let pt = crate::Interval::point;
                (pt(late.position[i]) - pt(early.position[i]) - pt(v[i]) * dts).mag()
            });
            // NaN (an overflow) is no proof of consistency: a break.
            let n = norm3_up(r[0], r[1], r[2]);
            n.is_nan() || n > band
        })
}

/// The fast accept of [`object_pair_breaks`] in plain floats (arguments as there): true only
/// if, exactly, the velocities (where both are measured) are within `a·Δt + 2·vel_error` of each
/// other and the positions within the least allowance plus `2·pos_error`.
///
/// Taken only where every quantity is tame ([`plain_scalar`], [`plain_vector`]): the model's
/// bounds and `Δt` zero or normal and at most 1e100, velocities' components at most 1e100, and
/// the two intermediates that are multiplied or square-rooted again — `Δt²` and each `‖v‖²` —
/// zero or normal. Then nothing overflows, every factor carries a relative error of a few ε
/// (an intermediate that underflowed and was then scaled up or square-rooted could carry any),
/// and each allowance is a sum of non-negative terms with a relative error of a few ε, plus at
/// most ≈ 1e-323 from a last product that underflowed: far inside the 1e-9 margin of
/// [`within_plain`], whose allowance is at least 1e-135. That bound also keeps the
/// outward-rounded tests' own slack (a relative 1e-14, `INFLATE`, and an absolute 1e-150,
/// `SQRT_TINY`) far below the margin, so a pair accepted here is one those tests accept too:
/// the accept changes no verdict. False otherwise: the caller then decides with outward
/// rounding.
///
/// # Soundness
/// Claim C9 (the fast accept of the consistency check): the twin of `h3_object_pair_sound` (the
/// whole [`object_pair_breaks`] against the exact oracle, pairs drawn near each allowance);
/// `h3_object_accept_sound` (Kani: [`within_plain`] on grids of dyadic values; its twin this
/// accept at full width against the exact oracle); the property test
/// `the_plain_accept_of_an_object_pair_is_sound` (against the outward-rounded tests, from
/// 1e-320 to 1e300, overflows and underflows forced). Mutant `x87` (the allowance doubled in
/// [`within_plain`]) fails all three.
#[inline]
pub fn object_pair_within_plain(
    b: &ObjectBounds,
    early: &ObjectMeasurement,
    late: &ObjectMeasurement,
) -> bool {
    let dt = (late.time - early.time).max(0.0);
    // `b.acc` is the acceleration bound rounded down, so it may lie just below zero (a model
    // without acceleration: `next_down(0)`); the exact bound is ≥ 0, so 0 is below it too.
    let (acc, ev, pe) = (b.acc.max(0.0), b.vel_error, b.pos_error);
    let dt2 = dt * dt;
    if !b.plain || !plain_scalar(dt) || !(dt2 == 0.0 || dt2 >= f64::MIN_POSITIVE) {
        return false;
    }
    if let (Some(a), Some(v)) = (early.velocity, late.velocity)
        && !within_plain(&a, &v, acc * dt + 2.0 * ev)
    {
        return false;
    }
    let mut by_velocity = f64::INFINITY;
    for v in [early.velocity, late.velocity].into_iter().flatten() {
        let Some(n2) = plain_vector(&v) else {
            return false;
        };
        // `√` through `ieee::sqrt`: under Kani its contract (correctly rounded here).
        let allowed = (crate::ieee::sqrt(n2) + ev) * dt + 0.5 * acc * dt2;
        by_velocity = by_velocity.min(allowed);
        if !direction_within_plain(early, late, &v, dt, ev * dt + 0.5 * acc * dt2 + 2.0 * pe) {
            return false;
        }
    }
    let allowed = match b.max_speed {
        Some(vmax) => by_velocity.min(vmax * dt),
        None => by_velocity,
    };
    if allowed == f64::INFINITY {
        // Nothing bounds the positions: `object_pair_breaks` decides by the velocities alone.
        return true;
    }
    within_plain(&early.position, &late.position, allowed + 2.0 * pe)
}

/// The direction test of [`object_pair_breaks`] in plain floats: true only if, exactly,
/// `|Δp − v·Δt| ≤ band` (`band` = `vel_error·Δt + a·Δt²/2 + 2·pos_error`). The float residual
/// is off the exact one by a few ε of the magnitudes it is computed from (positions, `v·Δt`):
/// eight ε of their sum come off the band, and the band is taken only in `[1e-135, 1e150]` and
/// less a relative 1e-9 (its own rounding, and the outward-rounded test's slack, far below that).
/// False otherwise (the caller then decides with outward rounding).
#[inline]
#[allow(clippy::needless_range_loop)] // three coordinates of three arrays
fn direction_within_plain(
    early: &ObjectMeasurement,
    late: &ObjectMeasurement,
    v: &[f64; 3],
    dt: f64,
    band: f64,
) -> bool {
    if !(1e-135..=1e150).contains(&band) {
        return false;
    }
    let (mut r2, mut mags) = (0.0, 0.0);
    for i in 0..3 {
        let step = v[i] * dt;
        let r = (late.position[i] - early.position[i]) - step;
        r2 += r * r;
        mags += late.position[i].abs() + early.position[i].abs() + step.abs();
    }
    let room = band * (1.0 - 1e-9) - 8.0 * f64::EPSILON * mags;
    mags.is_finite() && room > 0.0 && r2 <= room * room
}

/// Whether a non-negative bound (m, m/s, m/s², s) is one the plain-float accept takes: zero or
/// normal, at most 1e100.
#[inline(always)]
fn plain_scalar(x: f64) -> bool {
    x == 0.0 || (f64::MIN_POSITIVE..=1e100).contains(&x)
}

/// A velocity's squared norm (m²/s²) where the plain-float accept takes the velocity: every
/// component at most 1e100 in magnitude and the squared norm zero or normal (so that its `√`
/// carries a relative error of a few ε); `None` otherwise.
#[inline(always)]
fn plain_vector(v: &[f64; 3]) -> Option<f64> {
    let n2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    (v.iter().all(|c| c.abs() <= 1e100) && (n2 == 0.0 || n2 >= f64::MIN_POSITIVE)).then_some(n2)
}

/// Whether two measured velocities `a`, `v` (m/s) of one object, stamped `dt` (s, at most the
/// stamps' real difference) apart, differ by more than `acc·dt + 2·ev` (`acc`: the bound of
/// every acceleration, m/s²; `ev`: the velocity error, m/s; all ≥ 0).
///
/// # Soundness
/// Claim C9: false only if `‖a − v‖ ≤ acc·dt + 2·ev` exactly (the distance rounded up, the
/// allowance down). Harness `h3_object_pair_sound` (Kani: this test, on grids of dyadic values;
/// the twin: the whole [`object_pair_breaks`]); mutant `x56` fails it.
#[inline]
pub fn velocities_break(a: &[f64; 3], v: &[f64; 3], acc: f64, dt: f64, ev: f64) -> bool {
    a != v && dist3_up(a, v) > add_down(mul_down(acc, dt), mul_down(2.0, ev))
}
