//! Human reachable occupancies over a time interval after a measurement (SaRA-style models).
//!
//! Semantics (what every function here guarantees): let a measurement stamped `time` give keypoint
//! positions `p_k` (and optionally velocities `v_k`). For every true motion of the keypoints such
//! that, at `time − delay`, each keypoint was within `measurement_error_pos` of `p_k` (and its
//! velocity within `measurement_error_vel` of `v_k`, when velocities are used), and afterwards each
//! keypoint's speed stays ≤ `v_max[k]` (models `vel`, `pos`, `combined`) and its acceleration ≤
//! `a_max[k]` (models `acc`, `combined`) — and, for `pos`, every point of an extremity's body parts
//! stays within `length + thickness/2` of its base keypoint — every point of every body part
//! (its segment swept by `thickness/2`) at every time `t ∈ [t_a, t_b]` lies in the reported capsule.
//!
//! Keypoint sets, with elapsed time T = t − time + delay ≥ 0, e_p, e_v the error bounds:
//! - `vel`: Ball(p, e_p + v_max·T) — concentric and growing, so the ball at T_b covers [T_a, T_b];
//! - `acc`: Ball(p + v·T, e_p + e_v·T + ½·a_max·T²) — centre linear and radius convex in T, so the
//!   smallest ball enclosing the balls at T_a and T_b contains every ball in between (each is a
//!   convex combination of the two);
//! - `combined`: both bounds hold for the true motion, so the keypoint is in the `vel` set and in
//!   the `acc` set: we report the smaller of the two (SaRA's combined closed form is tighter; we do
//!   not use it until it has a proof here). Without measured velocities it equals `vel`;
//! - a measured velocity faster than the speed bound allows (`|v_k| > v_max[k] +
//!   measurement_error_vel`, decided with outward rounding) shows one assumption false — the
//!   speed bound or the velocity's error bound — without telling which: for that keypoint `acc`
//!   and `combined` use the smallest ball enclosing both the `vel` and the `acc` set, which holds
//!   under either;
//! - `pos`: body parts of an extremity: Ball(p_base, e_p + v_max,base·T + length + thickness/2);
//!   parts not covered by an extremity use `vel`.
//!
//! A body part between keypoints with sets Ball(c₁, r₁), Ball(c₂, r₂) lies in the capsule
//! [c₁, c₂] with radius max(r₁, r₂) + thickness/2 (each point of the true segment is a convex
//! combination of points within r₁ of c₁ and r₂ of c₂). All radii are rounded up; centres computed
//! in floating point have their rounding error bounded and added to the radius.

pub use crate::error::ReachError;
use crate::rounding::{
    INFLATE, TINY, add_down, add_up, dist3_up, mul_down, mul_up, sub_down, sub_up,
};
use nalgebra::{Point3, Vector3};
use pacs_models::human::Extremity;
use pacs_models::{Capsule, HumanModel};
use serde::{Deserialize, Serialize};

/// Which bounds of the human model to use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum HumanReachModel {
    /// Extremity reach around base keypoints (bounded position), `vel` elsewhere.
    Pos,
    /// Bounded speed.
    Vel,
    /// Bounded acceleration (needs measured velocities).
    Acc,
    /// Bounded speed and acceleration (the tighter of `vel` and `acc` per keypoint).
    Combined,
}

impl std::str::FromStr for HumanReachModel {
    type Err = ReachError;
    fn from_str(s: &str) -> Result<Self, ReachError> {
        match s {
            "pos" => Ok(Self::Pos),
            "vel" => Ok(Self::Vel),
            "acc" => Ok(Self::Acc),
            "combined" => Ok(Self::Combined),
            other => Err(ReachError::Input(format!(
                "unknown human reach model `{other}` (pos, vel, acc, combined)"
            ))),
        }
    }
}

/// A validated measurement of all keypoints: finite values, one entry per keypoint.
#[derive(Debug, Clone, PartialEq)]
pub struct HumanMeasurement {
    time: f64,
    positions: Vec<Point3<f64>>,
    /// Velocity buffer (kept allocated); meaningful only when `has_velocities`.
    velocities: Vec<Vector3<f64>>,
    has_velocities: bool,
    /// The first keypoint (index, axis, coordinate in m) farther than `MAX_REACH` (10⁶ m) from
    /// the world origin on an axis, if any: no measurement of a person in the cell
    /// ([`HumanReach::occupancy_into`] refuses it, naming it).
    beyond_reach: Option<(usize, usize, f64)>,
}

impl HumanMeasurement {
    /// Validate against the model's keypoint count; every value must be finite.
    pub fn new(
        model: &HumanModel,
        time: f64,
        positions: &[[f64; 3]],
        velocities: Option<&[[f64; 3]]>,
    ) -> Result<Self, ReachError> {
        if !time.is_finite() {
            return Err(ReachError::Input(format!(
                "measurement.time: value {time} is not finite"
            )));
        }
        let n = model.keypoint_count();
        let check = |field: &str, v: &[[f64; 3]]| -> Result<(), ReachError> {
            if v.len() != n {
                return Err(ReachError::Input(format!(
                    "measurement.{field}: expected {n} keypoints ({}), found {}",
                    model.keypoints().join(", "),
                    v.len()
                )));
            }
            for (i, p) in v.iter().enumerate() {
                if let Some(j) = p.iter().position(|x| !x.is_finite()) {
                    return Err(ReachError::Input(format!(
                        "measurement.{field}[{i}][{j}] ({}): value {} is not finite",
                        model.keypoints()[i],
                        p[j]
                    )));
                }
            }
            Ok(())
        };
        check("positions", positions)?;
        if let Some(v) = velocities {
            check("velocities", v)?;
        }
        Ok(Self {
            time,
            positions: positions.iter().map(|p| Point3::from(*p)).collect(),
            velocities: match velocities {
                Some(v) => v.iter().map(|p| Vector3::from(*p)).collect(),
                None => vec![Vector3::zeros(); n],
            },
            has_velocities: velocities.is_some(),
            beyond_reach: positions.iter().enumerate().find_map(|(k, p)| {
                (0..3)
                    .find(|&a| p[a].abs() > pacs_models::MAX_REACH)
                    .map(|a| (k, a, p[a]))
            }),
        })
    }

    /// Overwrite with `other`, reusing this measurement's buffers (no allocation when the
    /// keypoint counts match and velocity presence is unchanged).
    pub fn assign_from(&mut self, other: &HumanMeasurement) {
        self.time = other.time;
        self.positions.clone_from(&other.positions);
        self.velocities.clone_from(&other.velocities);
        self.has_velocities = other.has_velocities;
        self.beyond_reach = other.beyond_reach;
    }

    /// Time stamp (s).
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Whether this measurement replaces `current` as the one in use: it is strictly newer (an
    /// older or equal-stamp one arriving later is ignored; the first of equal stamps stays).
    /// The one rule for every stamped measurement, [`crate::stamped::supersedes`].
    pub fn supersedes(&self, current: Option<&HumanMeasurement>) -> bool {
        crate::stamped::supersedes(self, current)
    }
    /// Measured positions (m).
    pub fn positions(&self) -> &[Point3<f64>] {
        &self.positions
    }
    /// Measured velocities (m/s), if any.
    pub fn velocities(&self) -> Option<&[Vector3<f64>]> {
        self.has_velocities.then_some(self.velocities.as_slice())
    }
}

/// A closed ball (centre in m, radius in m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ball {
    /// Centre.
    pub centre: Point3<f64>,
    /// Radius, ≥ 0.
    pub radius: f64,
}

impl Ball {
    /// A ball containing both balls (and so their convex hull), radius rounded up.
    pub fn enclose(a: &Ball, b: &Ball) -> Ball {
        let d = dist3_up(&a.centre.coords.into(), &b.centre.coords.into());
        if add_up(d, b.radius) <= a.radius {
            return *a;
        }
        if add_up(d, a.radius) <= b.radius {
            return *b;
        }
        // Nominal minimal enclosing centre; the radius below is sound for any centre.
        let (big, small) = if a.radius >= b.radius { (a, b) } else { (b, a) };
        let diff = big.centre - small.centre;
        let n = diff.norm();
        let centre = if n > 0.0 {
            nalgebra::center(&big.centre, &small.centre)
                + diff * ((big.radius - small.radius) / (2.0 * n))
        } else {
            big.centre
        };
        let ra = add_up(
            dist3_up(&centre.coords.into(), &a.centre.coords.into()),
            a.radius,
        );
        let rb = add_up(
            dist3_up(&centre.coords.into(), &b.centre.coords.into()),
            b.radius,
        );
        Ball {
            centre,
            radius: ra.max(rb),
        }
    }
}

/// Elapsed times `(T_a, T_b)` since the measured true state (`time − delay`) of the query
/// `[t_a, t_b]`: `t_a − time + delay` rounded down and `t_b − time + delay` rounded up. The
/// per-keypoint arithmetic of [`HumanReach::occupancy_into`] is in free functions of floats
/// (this one, its two ends and the radii below) so that the proofs beside this module
/// (`human/proofs.rs`) check it without building a `HumanModel`.
///
/// # Soundness
/// `T_a ≤ t_a − time + delay` and `t_b − time + delay ≤ T_b`, exactly: the contracts of its two
/// ends, [`elapsed_lo`] and [`elapsed_hi`], each proven on its function (as one function with
/// one contract, and as this pair composed by `stub_verified`, the proof timed out at 300 s);
/// twin `c1_radius_contracts_hold` ([`elapsed_range_encloses`]).
#[inline(always)]
fn elapsed_range(time: f64, delay: f64, t_a: f64, t_b: f64) -> (f64, f64) {
    (elapsed_lo(time, delay, t_a), elapsed_hi(time, delay, t_b))
}

/// `t_a − time + delay` rounded down (the start of [`elapsed_range`]).
///
/// # Soundness
/// Kani contract ([`elapsed_lo_below`]): `≤ t_a − time + delay` exactly. Proven on this function
/// by `c1_elapsed_lo_contract` (`proof_for_contract`, 8-bit significands).
#[cfg_attr(kani, kani::requires(radius_input(time) && radius_input(delay) && radius_input(t_a)))]
#[cfg_attr(kani, kani::ensures(|lo: &f64| elapsed_lo_below(time, delay, t_a, *lo)))]
#[inline(always)]
pub(crate) fn elapsed_lo(time: f64, delay: f64, t_a: f64) -> f64 {
    add_down(sub_down(t_a, time), delay)
}

/// `t_b − time + delay` rounded up (the end of [`elapsed_range`]).
///
/// # Soundness
/// Kani contract ([`elapsed_hi_above`]): `≥ t_b − time + delay` exactly. Proven on this function
/// by `c1_elapsed_hi_contract` (`proof_for_contract`, 8-bit significands).
#[cfg_attr(kani, kani::requires(radius_input(time) && radius_input(delay) && radius_input(t_b)))]
#[cfg_attr(kani, kani::ensures(|hi: &f64| elapsed_hi_above(time, delay, t_b, *hi)))]
#[inline(always)]
pub(crate) fn elapsed_hi(time: f64, delay: f64, t_b: f64) -> f64 {
    add_up(sub_up(t_b, time), delay)
}

/// `vel`: the radius `e_p + v_max·T_hi` (rounded up) of a keypoint's ball around its measured
/// position; it contains the balls of every earlier elapsed time.
///
/// # Soundness
/// Kani contract ([`covers_vel_reach`], for the inputs [`radius_input`] admits, non-negative):
/// `≥ e_p + v_max·T_hi` exactly. Proven on this function by `c1_vel_radius_contract`
/// (`proof_for_contract`, 8-bit significands); twin `c1_radius_contracts_hold`.
#[cfg_attr(kani, kani::requires(radius_input(e_p) && radius_input(v_max) && radius_input(t_hi) && e_p >= 0.0 && v_max >= 0.0 && t_hi >= 0.0))]
#[cfg_attr(kani, kani::ensures(|r: &f64| covers_vel_reach(e_p, v_max, t_hi, *r)))]
#[inline(always)]
pub(crate) fn vel_radius(e_p: f64, v_max: f64, t_hi: f64) -> f64 {
    add_up(e_p, mul_up(v_max, t_hi))
}

/// `acc`: the ball of a keypoint measured at `p` with velocity `v` at the elapsed time `t`.
#[inline(always)]
fn acc_ball_at(e_p: f64, e_v: f64, a_max: f64, p: &Point3<f64>, v: &Vector3<f64>, t: f64) -> Ball {
    // Centre p + v·t in floating point: per coordinate the rounding error is at most
    // 2u(|p| + |v·t|)(1 + u) < 3u(|p| + |v|·t); the vector error is at most the sum over
    // coordinates (L1 ≥ L2), added to the radius. Radius: a sum of products of non-negative
    // floats, inflated by `INFLATE` (see `rounding`).
    let centre = p + v * t;
    let err =
        ((p.x.abs() + p.y.abs() + p.z.abs()) + (v.x.abs() + v.y.abs() + v.z.abs()) * t) * 1e-15;
    let r = e_p + e_v * t + 0.5 * a_max * t * t;
    Ball {
        centre,
        radius: (r + err) * INFLATE + TINY,
    }
}

/// The radius of the capsule between two keypoints' balls of radii `r1`, `r2` for a body part
/// of `thickness` (module doc).
///
/// # Soundness
/// Kani contract ([`covers_part`], for the inputs [`radius_input`] admits, non-negative):
/// `≥ max(r1, r2) + thickness/2` exactly. Proven on this function by `c1_part_radius_contract`
/// (`proof_for_contract`, 8-bit significands); twin `c1_radius_contracts_hold`.
#[cfg_attr(kani, kani::requires(radius_input(r1) && radius_input(r2) && radius_input(thickness) && r1 >= 0.0 && r2 >= 0.0 && thickness >= 0.0))]
#[cfg_attr(kani, kani::ensures(|r: &f64| covers_part(r1, r2, thickness, *r)))]
#[inline(always)]
fn part_radius(r1: f64, r2: f64, thickness: f64) -> f64 {
    add_up(r1.max(r2), thickness * 0.5)
}

/// `pos`: the radius of an extremity's ball (`length`, `thickness`) around its base keypoint's
/// measured position, the base moving for up to `t` (the elapsed `T_hi` plus `back`).
///
/// # Soundness
/// `≥ e_p + v_max·t + length + thickness/2` exactly ([`covers_extremity_reach`]; twin
/// `c1_radius_contracts_hold`; Kani: `c1_pos_reach` on a grid, and `vel_radius`'s contract for
/// the base's reach). As a Kani contract its proof timed out (300 s), also with `vel_radius`
/// replaced by its verified contract.
#[inline(always)]
fn extremity_radius(e_p: f64, v_max: f64, length: f64, thickness: f64, t: f64) -> f64 {
    // The base's reach is `vel`'s radius (the same operations in the same order).
    add_up(vel_radius(e_p, v_max, t), add_up(length, thickness * 0.5))
}

// The contracts of the per-keypoint arithmetic above: each a bound compared with the value
// the same expression takes with exact directed rounding at every step (`exact::ceil_sum`,
// `ceil_prod`, `floor_sum`: the float next to each exact intermediate on the safe side), so a
// predicate that holds proves the real-number claim; public so that the proofs, their twins and
// any caller state the same claim.

/// An input the contracts above admit: finite, of magnitude at most 1e100 (no sum or product
/// of such inputs overflows). One value, no loop: Kani evaluates a precondition wherever its
/// function is called, so a loop in it would need an unwinding bound in every harness that
/// reaches the function.
pub fn radius_input(x: f64) -> bool {
    x.abs() <= 1e100
}

/// A random input [`radius_input`] admits, for the twins of the contracts (here and in the
/// object occupancy): 0, a value in [0, 2], a magnitude from 1e-300 to 1e100 (subnormal
/// results included) or a multiple of 1/256 below 2; negated at random when `signed`.
#[cfg(test)]
pub(crate) fn draw_radius_input(s: &mut pacs_proof_kit::RandomSource, signed: bool) -> f64 {
    use pacs_proof_kit::Source;
    let v = match s.index(4) {
        0 => 0.0,
        1 => s.f64_in(0.0, 2.0),
        2 => 10f64.powi(s.index(401) as i32 - 300) * s.f64_in(1.0, 9.99),
        _ => (s.index(512) as f64) / 256.0,
    };
    let v = if signed && s.bool() { -v } else { v };
    if radius_input(v) { v } else { 0.0 }
}

/// Contract of `vel_radius`: `r ≥ e_p + v·t` exactly (`r ≥ ⌈e_p + ⌈v·t⌉⌉`).
pub fn covers_vel_reach(e_p: f64, v: f64, t: f64, r: f64) -> bool {
    use crate::exact::{ceil_prod, ceil_sum};
    r.is_finite() && r >= ceil_sum(e_p, ceil_prod(v, t))
}

/// Contract of `part_radius`: `r ≥ max(r1, r2) + thickness/2` exactly.
pub fn covers_part(r1: f64, r2: f64, thickness: f64, r: f64) -> bool {
    use crate::exact::{ceil_prod, ceil_sum};
    r.is_finite() && r >= ceil_sum(r1.max(r2), ceil_prod(thickness, 0.5))
}

/// The claim of `extremity_radius`: `r ≥ e_p + v·t + length + thickness/2` exactly (`r ≥
/// ⌈⌈e_p + ⌈v·t⌉⌉ + ⌈length + ⌈thickness/2⌉⌉⌉`), `r` finite.
pub fn covers_extremity_reach(
    e_p: f64,
    v: f64,
    length: f64,
    thickness: f64,
    t: f64,
    r: f64,
) -> bool {
    use crate::exact::{ceil_prod, ceil_sum};
    let travel = ceil_sum(e_p, ceil_prod(v, t));
    let extent = ceil_sum(length, ceil_prod(thickness, 0.5));
    r.is_finite() && r >= ceil_sum(travel, extent)
}

/// The claim of `elapsed_range`: `lo ≤ t_a − time + delay` and `hi ≥ t_b − time + delay`,
/// exactly (its two ends' contracts).
pub fn elapsed_range_encloses(time: f64, delay: f64, t_a: f64, t_b: f64, r: (f64, f64)) -> bool {
    elapsed_lo_below(time, delay, t_a, r.0) && elapsed_hi_above(time, delay, t_b, r.1)
}

/// Contract of `elapsed_lo`: `lo ≤ t_a − time + delay` exactly, decided as a chain through a
/// witness (`a ≤ t_a − time`, `lo ≤ a + delay`, each checked exactly); with the tightest
/// rounding as the witness the proof of both ends at once timed out (300 s).
pub fn elapsed_lo_below(time: f64, delay: f64, t_a: f64, lo: f64) -> bool {
    use crate::exact::cmp_sum;
    use std::cmp::Ordering::Less;
    let a = sub_down(t_a, time);
    lo.is_finite() && cmp_sum(t_a, -time, a) != Less && cmp_sum(a, delay, lo) != Less
}

/// Contract of `elapsed_hi`: `hi ≥ t_b − time + delay` exactly (as [`elapsed_lo_below`]).
pub fn elapsed_hi_above(time: f64, delay: f64, t_b: f64, hi: f64) -> bool {
    use crate::exact::cmp_sum;
    use std::cmp::Ordering::Greater;
    let b = sub_up(t_b, time);
    hi.is_finite() && cmp_sum(t_b, -time, b) != Greater && cmp_sum(b, delay, hi) != Greater
}

/// Human occupancy computer: reusable buffers, no allocation per query.
#[derive(Debug, Clone)]
pub struct HumanReach {
    model: HumanModel,
    kind: HumanReachModel,
    balls: Vec<Ball>,
}

impl HumanReach {
    /// Occupancy computer for a human model and a reach model.
    pub fn new(model: HumanModel, kind: HumanReachModel) -> Self {
        let n = model.keypoint_count();
        Self {
            model,
            kind,
            balls: vec![
                Ball {
                    centre: Point3::origin(),
                    radius: 0.0
                };
                n
            ],
        }
    }

    /// The human model.
    pub fn model(&self) -> &HumanModel {
        &self.model
    }
    /// The reach model.
    pub fn kind(&self) -> HumanReachModel {
        self.kind
    }

    /// Elapsed-time bounds [T_a, T_b] since the measured true state, and an extra radius covering
    /// a start an ulp-scale before that state (speed-bounded). Errors if the interval is invalid.
    fn elapsed(
        &self,
        m: &HumanMeasurement,
        t_a: f64,
        t_b: f64,
    ) -> Result<(f64, f64, f64), ReachError> {
        if !(t_a.is_finite() && t_b.is_finite()) || t_a > t_b {
            return Err(ReachError::Input(format!(
                "interval [{t_a}, {t_b}]: need finite t_a <= t_b"
            )));
        }
        let delay = self.model.delay();
        let (lo, hi) = elapsed_range(m.time, delay, t_a, t_b);
        if lo < -1e-9 {
            return Err(ReachError::BeforeMeasurement {
                t_a,
                t_b,
                time: m.time,
                delay,
            });
        }
        let back = if lo < 0.0 { -lo } else { 0.0 };
        Ok((lo.max(0.0), hi, back))
    }

    fn vel_ball(&self, m: &HumanMeasurement, k: usize, t_hi: f64) -> Ball {
        Ball {
            centre: m.positions[k],
            radius: vel_radius(
                self.model.measurement_error_pos(),
                self.model.v_max()[k],
                t_hi,
            ),
        }
    }

    fn acc_ball_at(&self, p: &Point3<f64>, v: &Vector3<f64>, k: usize, t: f64) -> Ball {
        acc_ball_at(
            self.model.measurement_error_pos(),
            self.model.measurement_error_vel(),
            self.model.a_max()[k],
            p,
            v,
            t,
        )
    }

    /// Whether keypoint `k`'s measured velocity (if any) agrees with the speed bound: not
    /// certainly faster than `v_max[k] + measurement_error_vel` (the norm rounded down, the bound
    /// up). Beyond it, the speed bound or the velocity is wrong, and `acc` and `combined` take
    /// the ball enclosing both sets for the keypoint. True without a measured velocity. Test
    /// `human_occupancy.rs::a_velocity_beyond_the_model_is_not_trusted` (mutant `x115`).
    fn velocity_consistent(&self, m: &HumanMeasurement, k: usize) -> bool {
        let Some(v) = m.velocities().and_then(|v| v.get(k)) else {
            return true;
        };
        let speed = crate::rounding::norm3_down(v.x, v.y, v.z);
        let bound = add_up(self.model.v_max()[k], self.model.measurement_error_vel());
        // (A NaN speed is refused when the measurement is made.)
        speed <= bound
    }

    fn acc_ball(&self, m: &HumanMeasurement, k: usize, t_lo: f64, t_hi: f64) -> Option<Ball> {
        let v = *m.velocities()?.get(k)?;
        let p = m.positions[k];
        Some(Ball::enclose(
            &self.acc_ball_at(&p, &v, k, t_lo),
            &self.acc_ball_at(&p, &v, k, t_hi),
        ))
    }

    /// Capsules (one per body part, model order) containing every body part over [t_a, t_b]
    /// (absolute times, s, same clock as the measurement). `out.len()` must equal the number of
    /// body parts. Allocates nothing.
    ///
    /// # Soundness
    /// Claim C3: every body part of every admissible motion (the model's speed/acceleration
    /// bounds since the measured state at `time − delay`, measurement errors `e_p`, `e_v`; for
    /// `pos` also the extremity lengths unless the measurement contradicts them) lies inside its
    /// capsule at every instant of `[t_a, t_b]`. Property test
    /// `c1_human_occupancy_contains_motion`; its Kani splits `c1_vel_reach`, `c1_pos_reach`,
    /// `c1_acc_ball_at` (beside this module, `human/proofs.rs`); mutants `m2`, `x6`, `x33`
    /// caught.
    pub fn occupancy_into(
        &mut self,
        m: &HumanMeasurement,
        t_a: f64,
        t_b: f64,
        out: &mut [Capsule],
    ) -> Result<(), ReachError> {
        let parts = self.model.body_parts().len();
        if out.len() != parts {
            return Err(ReachError::Input(format!(
                "output buffer holds {} capsules, need {parts}",
                out.len()
            )));
        }
        if m.positions.len() != self.model.keypoint_count() {
            return Err(ReachError::Input(
                "measurement does not match the human model".into(),
            ));
        }
        if self.kind == HumanReachModel::Acc && !m.has_velocities {
            return Err(ReachError::Input(
                "model `acc` needs measured velocities (measurement.velocities)".into(),
            ));
        }
        // A keypoint farther than any robot reaches (`MAX_REACH`, 10⁶ m) is no measurement of a
        // person in the cell: a tracker's lost-track value (FLT_MAX, 1e7) would otherwise put the
        // person far away and certify the run as if someone had been measured. Refused, as for
        // objects (the shield does not verify; the audit's span is `human_reach_error`).
        if let Some((keypoint, axis, value)) = m.beyond_reach {
            return Err(ReachError::BeyondReach {
                keypoint,
                axis,
                value,
            });
        }
        let (t_lo, t_hi, back) = self.elapsed(m, t_a, t_b)?;
        for k in 0..self.model.keypoint_count() {
            let mut ball = match self.kind {
                HumanReachModel::Vel | HumanReachModel::Pos => self.vel_ball(m, k, t_hi),
                HumanReachModel::Acc | HumanReachModel::Combined
                    if !self.velocity_consistent(m, k) =>
                {
                    // One assumption is false, the speed bound or the measured velocity: the
                    // ball enclosing both sets holds under either.
                    let acc = self.acc_ball(m, k, t_lo, t_hi).expect("velocities checked");
                    Ball::enclose(&self.vel_ball(m, k, t_hi), &acc)
                }
                HumanReachModel::Acc => {
                    self.acc_ball(m, k, t_lo, t_hi).expect("velocities checked")
                }
                HumanReachModel::Combined => {
                    let v = self.vel_ball(m, k, t_hi);
                    match self.acc_ball(m, k, t_lo, t_hi) {
                        Some(a) if a.radius < v.radius => a,
                        _ => v,
                    }
                }
            };
            if back > 0.0 {
                // The interval may start up to `back` (< 1e-9 s) before the measured state: any
                // admissible motion moves at most (speed bound)·back in that time.
                let mut speed = self.model.v_max()[k];
                if let Some(v) = m.velocities() {
                    let vm = crate::rounding::norm3_up(v[k].x, v[k].y, v[k].z);
                    speed = speed.max(add_up(
                        add_up(vm, self.model.measurement_error_vel()),
                        mul_up(self.model.a_max()[k], 1e-9),
                    ));
                }
                ball.radius = add_up(ball.radius, mul_up(speed, back));
            }
            self.balls[k] = ball;
        }
        for (i, bp) in self.model.body_parts().iter().enumerate() {
            let b1 = self.balls[bp.from];
            let b2 = self.balls[bp.to];
            let r = part_radius(b1.radius, b2.radius, bp.thickness);
            if !(r.is_finite()
                && b1
                    .centre
                    .iter()
                    .chain(b2.centre.iter())
                    .all(|x| x.is_finite()))
            {
                return Err(ReachError::Input(format!(
                    "body part `{}`: the occupancy bound overflows over [{t_a:?}, {t_b:?}]",
                    bp.name
                )));
            }
            out[i] = Capsule::new_unchecked(b1.centre, b2.centre, r);
        }
        if self.kind == HumanReachModel::Pos {
            // Parts covered by an extremity (the first one listing them) get its reach ball.
            for (p, cap) in out.iter_mut().enumerate() {
                if let Some(e) = self
                    .model
                    .extremities()
                    .iter()
                    .find(|e| e.body_parts.contains(&p))
                    && self.extremity_consistent(m, e)
                {
                    let c = m.positions[e.base];
                    let r = extremity_radius(
                        self.model.measurement_error_pos(),
                        self.model.v_max()[e.base],
                        e.length,
                        e.thickness,
                        add_up(t_hi, back),
                    );
                    if !r.is_finite() {
                        return Err(ReachError::Input(format!(
                            "extremity `{}`: the occupancy bound overflows over [{t_a:?}, {t_b:?}]",
                            e.name
                        )));
                    }
                    *cap = Capsule::new_unchecked(c, c, r);
                }
            }
        }
        Ok(())
    }

    /// The `pos` model's assumption holds for this measurement: every point of the extremity's
    /// body parts as measured — each keypoint of a part with the part's own radius
    /// (`thickness/2` of the body part) around it — is within `length + thickness/2 + 2·e_pos`
    /// (the extremity's) of its measured base (both measured within `e_pos`). A measurement that
    /// contradicts it (e.g. a hand 1.4 m from the shoulder with a 1.0 m arm, or a hand keypoint
    /// 0.99 m out whose 0.103 m radius reaches past the 1.0 m arm) must not be trusted: the
    /// extremity's parts then keep the speed-bounded (`vel`) occupancy, which does not rest on
    /// the extremity length.
    ///
    /// Decided soundly: consistent only if an upper bound of the exact distance is at most a
    /// lower bound of the exact limit, so a measurement that contradicts the assumption by any
    /// amount, an ulp included, keeps the `vel` occupancy (which contains every `pos` motion:
    /// those are speed-bounded too). Comparing a lower bound of the distance with an upper bound
    /// of the limit instead would let contradictions of a few ulps use the `pos` ball.
    fn extremity_consistent(&self, m: &HumanMeasurement, e: &Extremity) -> bool {
        let base = m.positions[e.base];
        let base = [base.x, base.y, base.z];
        let limit = add_down(
            add_down(e.length, mul_down(e.thickness, 0.5)),
            mul_down(2.0, self.model.measurement_error_pos()),
        );
        e.body_parts.iter().all(|&p| {
            let bp = &self.model.body_parts()[p];
            let radius = mul_up(bp.thickness, 0.5);
            [bp.from, bp.to].iter().all(|&k| {
                let q = m.positions[k];
                add_up(dist3_up(&[q.x, q.y, q.z], &base), radius) <= limit
            })
        })
    }

    /// Allocating convenience form of [`Self::occupancy_into`].
    pub fn occupancy(
        &mut self,
        m: &HumanMeasurement,
        t_a: f64,
        t_b: f64,
    ) -> Result<Vec<Capsule>, ReachError> {
        let mut out = vec![
            Capsule::new_unchecked(Point3::origin(), Point3::origin(), 0.0);
            self.model.body_parts().len()
        ];
        self.occupancy_into(m, t_a, t_b, &mut out)?;
        Ok(out)
    }
}

pub mod consistency;

/// The Kani proofs of the human occupancy's per-keypoint arithmetic (claim C3, split by reach
/// model), each also a property test (`proofs/README.md`).
#[cfg(any(test, kani))]
mod proofs;
