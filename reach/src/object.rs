//! Occupancy of dynamic objects (claim C4′): where an object modelled by
//! [`pacs_models::object::ObjectModel`] can be over a time interval, as a zonotope dilated by a
//! radius. Fixed-size and allocation-free (one object, one interval: well under a microsecond).
//!
//! # The set
//! Let `τ = t − (t_m − δ)` be the time since the measured state. For the double integrator
//! `p̈ = u ∈ U = c_u ⊕ G_u ⊕ B(a)` with `p₀ ∈ B(p_m, e_p)`, `v₀ ∈ B(v_m, e_v)`:
//!
//! `p(τ) = p₀ + τ v₀ + ∫₀^τ (τ − s) u(s) ds`, and since the weights `τ − s ≥ 0` integrate to
//! `τ²/2` and `U` is convex, the integral lies in `(τ²/2) U`. Hence
//!
//! `p(τ) ∈ p_m + f(τ) ⊕ (τ²/2) G_u ⊕ B(e_p + τ e_v + a τ²/2)`, `f(τ) = τ v_m + (τ²/2) c_u`.
//!
//! Over `τ ∈ [τ_a, τ_b]` (Girard's time-interval enclosure, evaluated exactly for this nilpotent
//! system): with `τ = τ_m + s h`, `s ∈ [−1, 1]`, and `s² = (1 + t)/2`, `t ∈ [−1, 1]`,
//!
//! `f(τ) = τ_m v_m + (τ_m²/2 + h²/4) c_u + s·h (v_m + τ_m c_u) + t·(h²/4) c_u`,
//!
//! a zonotope with two generators that contains the curve. The terms `(τ²/2) G_u` and the ball
//! grow with `τ` and `G_u` is centred, so their values at `τ_b` contain all earlier ones. The
//! object's shape `S ⊕ B(r)` is added. With a speed bound the object is also within
//! `B(p_m, e_p + v_max τ_b) ⊕ S ⊕ B(r)`; a point must lie in both sets.
//!
//! Every coefficient is computed in outward-rounded interval arithmetic; a generator is the
//! midpoint of its interval and the radii go into the zonotope's error box, so the floats
//! represent a superset of the real set.

use crate::error::ReachError;
use crate::human::{elapsed_hi, elapsed_lo, vel_radius};
use crate::interval::Interval;
use crate::rounding::{add_up, mul_down, mul_up, norm3_down, norm3_up, sub_up};
use crate::zonotope::Zonotope3;
use pacs_models::object::{MAX_ACC_GENERATORS, MAX_SHAPE_GENERATORS, ObjectModel};
use pacs_models::shape::Capsule;

pub mod consistency;

/// Generators of an occupancy zonotope: the two of the time interval, the acceleration set's and
/// the shape's.
pub const MAX_OCCUPANCY_GENERATORS: usize = 2 + MAX_ACC_GENERATORS + MAX_SHAPE_GENERATORS;
/// The zonotopes of an [`ObjectOccupancy`]: room for [`MAX_OCCUPANCY_GENERATORS`] generators
/// (240 bytes, against 1152 for the default [`Zonotope3`]), as the shield builds and moves one
/// per object and interval in every step.
pub type OccupancyZonotope = Zonotope3<MAX_OCCUPANCY_GENERATORS>;

/// A measurement of an object stamped `time` (s): the true state at `time − delay` is within the
/// model's errors of `position` (m) and, if given, `velocity` (m/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObjectMeasurement {
    /// Time stamp `t_m` (s).
    pub time: f64,
    /// Measured position of the reference point (m).
    pub position: [f64; 3],
    /// Measured velocity (m/s); `None`: unknown within the model's speed bound.
    pub velocity: Option<[f64; 3]>,
}

impl ObjectMeasurement {
    /// Every value (time, position, velocity if given) is finite.
    pub fn is_finite(&self) -> bool {
        self.time.is_finite()
            && self.position.iter().all(|x| x.is_finite())
            && self
                .velocity
                .is_none_or(|v| v.iter().all(|x| x.is_finite()))
    }

    /// Keep the newest of `latest` and `self`: `self` replaces it only if strictly newer (an
    /// older or equal-time measurement arriving late is ignored). The one rule for every stamped
    /// measurement, [`crate::stamped::keep_newest`].
    pub fn keep_newest(self, latest: &mut Option<ObjectMeasurement>) {
        crate::stamped::keep_newest(&self, latest);
    }
}

/// Where an object can be over `[t_a, t_b]`: every point of the object lies in
/// `reach ⊕ B(radius)` and, with a speed bound, also in `speed ⊕ B(speed_radius)`.
#[derive(Debug, Clone, PartialEq)]
pub struct ObjectOccupancy {
    reach: OccupancyZonotope,
    radius: f64,
    speed: Option<(OccupancyZonotope, f64)>,
    t_a: f64,
    t_b: f64,
}

/// `x` as a point interval.
#[inline(always)]
fn pt(x: f64) -> Interval {
    Interval::point(x)
}

/// `[a·b]` rounded outward, without the exactness test of point-interval products (the hot path
/// only needs an enclosure).
#[inline(always)]
fn product(a: f64, b: f64) -> Interval {
    Interval::new(mul_down(a, b), mul_up(a, b)).unwrap_or(Interval::ENTIRE)
}

/// Split an interval into a float (its midpoint) and a radius bound that covers the rest.
#[inline(always)]
fn mid_rad(x: Interval) -> (f64, f64) {
    (x.mid(), x.rad_up())
}

/// `(τ_m, h)`, floats with `[τ_m − h, τ_m + h] ⊇ [tau_a, tau_b]` (`h` rounded up).
#[inline]
pub(crate) fn time_split(tau_a: f64, tau_b: f64) -> (f64, f64) {
    let tau_m = 0.5 * (tau_a + tau_b);
    (
        tau_m,
        sub_up(tau_b, tau_m).max(sub_up(tau_m, tau_a)).max(0.0),
    )
}

/// One axis of the time-interval enclosure (module docs): every value `p + τ v + (τ²/2) c_u` with
/// `τ ∈ [τ_m − h, τ_m + h]` equals `centre + s·g_s + t·g_t + δ` for some `|s|, |t| ≤ 1` and
/// `|δ| ≤ err`. Returns `(centre, g_s, g_t, err)`.
///
/// # Soundness
/// Exact algebra (module docs) evaluated in outward-rounded intervals, each coefficient's
/// radius added to `err`. Harness `j2_object_curve_encloses` (beside this module).
#[inline]
pub(crate) fn curve_enclosure(
    p: f64,
    v: f64,
    c_u: f64,
    tau_m: f64,
    h: f64,
) -> (f64, f64, f64, f64) {
    let quarter_h2 = product(h, h).scale(0.25);
    let k = product(tau_m, tau_m).scale(0.5) + quarter_h2;
    let (c, rc) = mid_rad(pt(p) + product(tau_m, v) + k * pt(c_u));
    let (g_s, rs) = mid_rad((pt(v) + product(tau_m, c_u)).scale(h));
    let (g_t, rt) = mid_rad(quarter_h2 * pt(c_u));
    (c, g_s, g_t, add_up(add_up(rc, rs), rt))
}

/// The elapsed times `(τ_a, τ_b)` since the measured state (`time − delay`) of the query
/// `[t_a, t_b]`: `t_a − time + delay` rounded down and clamped at 0 (the measured state at the
/// earliest), `t_b − time + delay` rounded up and at least `τ_a`. The two roundings are the
/// human occupancy's (`human::elapsed_lo`, `human::elapsed_hi`: one implementation, whose Kani
/// contracts — `≤ t_a − time + delay` and `≥ t_b − time + delay` exactly — are proven on them
/// by `c1_elapsed_lo_contract` and `c1_elapsed_hi_contract`); the clamps only widen the range.
/// (`occupancy` evaluates its precondition `t_a ≥ time − delay` in floating point: a query it
/// accepts may lie, exactly, up to an ulp before the measured state; `τ_b` is then kept at
/// least `τ_a = 0`, so the enclosure covers the measured state and not `τ_m < 0`, a case the
/// twin of `j1_object_time_and_balls` draws.) The scalar steps of [`occupancy`] (this one and
/// the two radii below) are free functions of floats so that the proofs beside this module
/// check them without an `ObjectModel`.
#[inline(always)]
pub(crate) fn elapsed_range(time: f64, delay: f64, t_a: f64, t_b: f64) -> (f64, f64) {
    let tau_a = elapsed_lo(time, delay, t_a).max(0.0);
    let tau_b = elapsed_hi(time, delay, t_b).max(tau_a);
    (tau_a, tau_b)
}

/// The ball term `e_p + τ_b e_v + a τ_b²/2 + r` (module docs), rounded up: position error,
/// velocity error, acceleration ball and shape radius at `τ_b` (each grows with `τ`). The
/// first two terms are the human occupancy's travel radius (`human::vel_radius`).
///
/// # Soundness
/// Claim ([`covers_ball`]): finite and `≥ e_p + τ_b e_v + a τ_b²/2 + r` exactly, for
/// non-negative inputs of magnitude ≤ 10¹⁰⁰ (property test `j1_radius_claims_hold`; Kani checks
/// it at constant model numbers in `j1_object_time_and_balls`). Not a Kani contract: its proof
/// over 8-bit symbolic floats timed out at 300 s (proofs/README.md).
#[inline(always)]
pub(crate) fn ball_radius(e_p: f64, e_v: f64, a: f64, r: f64, tau_b: f64) -> f64 {
    add_up(
        vel_radius(e_p, e_v, tau_b),
        add_up(mul_up(mul_up(mul_up(tau_b, tau_b), 0.5), a), r),
    )
}

/// The speed bound's radius `e_p + v_max τ_b + r` around the measured position, rounded up:
/// the human occupancy's travel radius (`human::vel_radius`) plus the shape radius.
///
/// # Soundness
/// Claim ([`covers_speed`]): finite and `≥ e_p + v_max τ_b + r` exactly, for non-negative
/// inputs of magnitude ≤ 10¹⁰⁰ (property test `j1_radius_claims_hold`; Kani checks it at
/// constant model numbers in `j1_object_time_and_balls`). Its travel term is `vel_radius`,
/// whose contract is proven (`c1_vel_radius_contract`); a contract of this function timed out
/// at 300 s (8-bit symbolic floats, proofs/README.md).
#[inline(always)]
pub(crate) fn speed_radius(e_p: f64, v_max: f64, r: f64, tau_b: f64) -> f64 {
    add_up(vel_radius(e_p, v_max, tau_b), r)
}

/// The claim of [`ball_radius`]: `out` finite and `≥ e_p + τ e_v + a τ²/2 + r` exactly
/// (`out ≥ ⌈⌈e_p + ⌈τ·e_v⌉⌉ + ⌈⌈⌈⌈τ·τ⌉·½⌉·a⌉ + r⌉⌉`, each step the exact upward rounding of
/// [`crate::exact`], so each bounds the real value of its terms).
pub fn covers_ball(e_p: f64, e_v: f64, a: f64, r: f64, tau: f64, out: f64) -> bool {
    use crate::exact::{ceil_prod, ceil_sum};
    let travel = ceil_sum(e_p, ceil_prod(tau, e_v));
    let acc = ceil_sum(ceil_prod(ceil_prod(ceil_prod(tau, tau), 0.5), a), r);
    out.is_finite() && out >= ceil_sum(travel, acc)
}

/// The claim of [`speed_radius`]: `out` finite and `≥ e_p + v_max τ + r` exactly
/// (`out ≥ ⌈⌈e_p + ⌈v_max·τ⌉⌉ + r⌉`).
pub fn covers_speed(e_p: f64, v_max: f64, r: f64, tau: f64, out: f64) -> bool {
    use crate::exact::{ceil_prod, ceil_sum};
    out.is_finite() && out >= ceil_sum(ceil_sum(e_p, ceil_prod(v_max, tau)), r)
}

/// The occupancy of `model` over `[t_a, t_b]` (s) after `meas`.
///
/// Errors: non-finite inputs, `t_a > t_b`, `t_a` before the measured state (`t_m − delay`), a
/// missing velocity without a speed bound. A measured velocity faster than the speed bound
/// allows (`|v| > v_max + vel_error`) contradicts the model and is ignored (as a missing one;
/// test `reach/tests/object.rs::a_velocity_beyond_the_speed_bound_is_ignored`, mutant `x117`).
///
/// # Soundness
/// Claim C4′: for every motion the model admits (module docs: double integrator with the
/// acceleration set, the speed bound if any, initial state within the measurement errors at
/// `t_m − delay`), every point of the object at every `t ∈ [t_a, t_b]` lies in both sets of the
/// result. Property test `reach/tests/object.rs` (10⁴ sampled motions with bang-bang inputs
/// from the edge of the measurement errors); harness `j2_object_curve_encloses` (the
/// time-interval enclosure, beside this module; Kani splits `j2_object_curve_velocity`,
/// `j2_object_curve_acceleration`), `j1_object_time_and_balls` (the elapsed-time range and the
/// ball radii, Kani); mutants `x13` (the delay dropped) and `x17` (the enclosure's `s`
/// generator dropped) caught.
pub fn occupancy(
    model: &ObjectModel,
    meas: &ObjectMeasurement,
    t_a: f64,
    t_b: f64,
) -> Result<ObjectOccupancy, ReachError> {
    let finite_meas = meas.time.is_finite()
        && meas.position.iter().all(|x| x.is_finite())
        && meas
            .velocity
            .is_none_or(|v| v.iter().all(|x| x.is_finite()));
    if !finite_meas {
        return Err(ReachError::Invalid {
            what: "object measurement",
            reason: "time, position and velocity must be finite",
        });
    }
    // An object farther than any robot reaches (`MAX_REACH`, 10⁶ m) is no measurement of the
    // cell: its distances' squares would overflow, and the occupancy test would take the
    // unresolved distance as a possible contact (a violation reported against a ball 10²⁰⁰ m
    // away). Refused: the span is `object_reach_error`.
    if meas
        .position
        .iter()
        .any(|x| x.abs() > pacs_models::MAX_REACH)
    {
        return Err(ReachError::Invalid {
            what: "object measurement",
            reason: "position farther than 10^6 m from the world origin",
        });
    }
    if !(t_a.is_finite() && t_b.is_finite() && t_a <= t_b) {
        return Err(ReachError::Invalid {
            what: "time interval",
            reason: "need finite t_a <= t_b",
        });
    }
    // Time since the measured state, enclosed outward: τ ∈ [tau_a, tau_b].
    // (The precondition `t_a ≥ t_m − δ` is evaluated in floating point; the enclosure then
    // starts at τ = 0, the measured state, at the earliest.)
    if t_a < meas.time - model.delay() {
        return Err(ReachError::Invalid {
            what: "t_a",
            reason: "before the measured state (t_m - delay)",
        });
    }
    let (tau_a, tau_b) = elapsed_range(meas.time, model.delay(), t_a, t_b);
    let (v_m, e_v) = match (meas.velocity, model.max_speed()) {
        // A velocity certainly faster than the speed bound allows (`|v| > v_max + e_v`, the norm
        // rounded down, the bound up) contradicts the model, whose every motion keeps the bound:
        // the velocity is ignored (the speed ball and the set without a velocity hold). Trusted,
        // the two sets could miss each other and leave the object nowhere (a ball at rest
        // measured at 10 m/s would clear every capsule).
        (Some(v), Some(v_max))
            if norm3_down(v[0], v[1], v[2]) > add_up(v_max, model.vel_error()) =>
        {
            ([0.0; 3], v_max)
        }
        (Some(v), _) => (v, model.vel_error()),
        (None, Some(v_max)) => ([0.0; 3], v_max),
        (None, None) => {
            return Err(ReachError::Invalid {
                what: "object measurement",
                reason: "no velocity, and the model has no speed bound",
            });
        }
    };
    let (tau_m, h) = time_split(tau_a, tau_b);
    let half_tb2 = product(tau_b, tau_b).scale(0.5);
    let c_u = model.acc_bias();
    let mut gens = [[0.0; 3]; MAX_OCCUPANCY_GENERATORS];
    let mut err = [0.0f64; 3];
    let mut centre = [0.0; 3];
    for i in 0..3 {
        let (c, g1, g2, e) = curve_enclosure(meas.position[i], v_m[i], c_u[i], tau_m, h);
        centre[i] = c;
        gens[0][i] = g1;
        gens[1][i] = g2;
        err[i] = e;
    }
    let mut n = 2;
    for g in model.acc_generators() {
        for i in 0..3 {
            let (x, r) = mid_rad(half_tb2 * pt(g[i]));
            gens[n][i] = x;
            err[i] = add_up(err[i], r);
        }
        n += 1;
    }
    for g in model.shape_generators() {
        gens[n] = *g;
        n += 1;
    }
    let radius = ball_radius(
        model.pos_error(),
        e_v,
        model.max_acc(),
        model.shape_radius(),
        tau_b,
    );
    let reach = OccupancyZonotope::from_parts(centre, &gens[..n], err)?;
    let speed = match model.max_speed() {
        Some(v_max) => {
            let r = speed_radius(model.pos_error(), v_max, model.shape_radius(), tau_b);
            Some((
                OccupancyZonotope::from_parts(meas.position, model.shape_generators(), [0.0; 3])?,
                r,
            ))
        }
        None => None,
    };
    if !(radius.is_finite() && speed.as_ref().is_none_or(|(_, r)| r.is_finite())) {
        return Err(ReachError::Input(format!(
            "object occupancy over [{t_a}, {t_b}] s overflows"
        )));
    }
    Ok(ObjectOccupancy {
        reach,
        radius,
        speed,
        t_a,
        t_b,
    })
}

impl ObjectOccupancy {
    /// The zonotope of the reachable set (m); the object lies in it dilated by [`Self::radius`].
    pub fn zonotope(&self) -> &OccupancyZonotope {
        &self.reach
    }
    /// Dilation radius of [`Self::zonotope`] (m).
    pub fn radius(&self) -> f64 {
        self.radius
    }
    /// The speed-bound set `(zonotope, radius)`, if the model has a speed bound (m).
    pub fn speed_set(&self) -> Option<(&OccupancyZonotope, f64)> {
        self.speed.as_ref().map(|(z, r)| (z, *r))
    }
    /// Time interval `[t_a, t_b]` (s).
    pub fn interval(&self) -> (f64, f64) {
        (self.t_a, self.t_b)
    }

    /// Rigorous lower bound `L`, `0 ≤ L ≤` distance between the occupancy and `capsule` (m);
    /// `L > 0` proves them disjoint.
    ///
    /// # Soundness
    /// Each of the two sets contains the occupancy, so the larger of their rigorous distance
    /// bounds (`Zonotope3::distance_lower_bound`, claim C2, harness `b4`) is one.
    pub fn distance_lower_bound(&self, capsule: &Capsule) -> f64 {
        let mut best = self.reach.distance_lower_bound(self.radius, capsule);
        if let Some((z, r)) = &self.speed {
            best = best.max(z.distance_lower_bound(*r, capsule));
        }
        best
    }

    /// A capsule containing the occupancy (m): the segment `c ± g₁` (the motion's direction over
    /// the interval) with radius `Σ_{k≥2} ‖g_k‖ + ‖e‖ + radius`, rounded up, plus the rounding of
    /// the segment's ends. For broad phases and display; `None` if it overflows.
    pub fn bounding_capsule(&self) -> Option<Capsule> {
        let z = &self.reach;
        let c = z.center();
        let gens = z.generators();
        let axis = gens.first().copied().unwrap_or([0.0; 3]);
        let e = z.error_box();
        let mut r = add_up(norm3_up(e[0], e[1], e[2]), self.radius);
        for g in gens.iter().skip(1) {
            r = add_up(r, norm3_up(g[0], g[1], g[2]));
        }
        let mut p1 = [0.0; 3];
        let mut p2 = [0.0; 3];
        let mut big = 0.0f64;
        for i in 0..3 {
            p1[i] = c[i] - axis[i];
            p2[i] = c[i] + axis[i];
            big = big.max(p1[i].abs()).max(p2[i].abs());
        }
        // Each rounded end coordinate is within half an ulp (≤ ε·big/2) of the exact one: the
        // ends move by at most √3·ε·big/2 < 2ε·big (plus the smallest subnormal step).
        let r = add_up(
            r,
            add_up(mul_up(big, 2.0 * f64::EPSILON), f64::from_bits(1)),
        );
        Capsule::new(p1.into(), p2.into(), r).ok()
    }
}

/// The Kani proof of the time-interval enclosure, also a property test (`proofs/README.md`).
#[cfg(any(test, kani))]
mod proofs;

#[cfg(test)]
mod tests {
    use super::*;

    /// The query the twin of `j1_object_time_and_balls` found: accepted by `occupancy`'s
    /// floating-point precondition, exactly a little before the measured state. The elapsed
    /// range must still contain the measured state (τ = 0) and be ordered; without the
    /// `.max(tau_a)` `τ_b` is −6.9e-17 (the mutant this test catches).
    #[test]
    fn a_query_an_ulp_before_the_measured_state_keeps_its_elapsed_range_ordered() {
        let (time, delay, t) = (2.7725560640097173, 0.1, 2.6725560640097172);
        assert!(t >= time - delay, "the precondition accepts it");
        let (tau_a, tau_b) = elapsed_range(time, delay, t, t);
        assert_eq!(tau_a, 0.0);
        assert!(tau_b >= tau_a, "τ_b = {tau_b} below τ_a = {tau_a}");
        let (tau_m, h) = time_split(tau_a, tau_b);
        assert!(
            tau_m - h <= 0.0 && 0.0 <= tau_m + h,
            "τ = 0 outside [{tau_m} ± {h}]"
        );
    }
}
