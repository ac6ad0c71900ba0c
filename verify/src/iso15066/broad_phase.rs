//! The broad phase of the rule: outward-rounded boxes around capsules, and the ball containing
//! the robot in every configuration. Both only ever skip pairs that are provably disjoint.

use pacs_models::robot::MAX_DOF;
use pacs_models::{Capsule, RobotModel};
use pacs_reach::rounding::{add_up, mul_up, norm3_up};

/// An axis-aligned box containing a capsule (bounds rounded outward).
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Aabb {
    lo: [f64; 3],
    hi: [f64; 3],
}

impl Aabb {
    pub(super) const EMPTY: Aabb = Aabb {
        lo: [f64::INFINITY; 3],
        hi: [f64::NEG_INFINITY; 3],
    };
    #[inline]
    pub(super) fn of(c: &Capsule) -> Self {
        let (a, b, r) = (c.p1(), c.p2(), c.radius());
        let mut bx = Aabb::default();
        for k in 0..3 {
            // |x ± r| rounding error ≤ u·|result|: pad relatively (plus a tiny absolute term).
            let lo = a[k].min(b[k]) - r;
            let hi = a[k].max(b[k]) + r;
            bx.lo[k] = lo - lo.abs() * 1e-15 - 1e-300;
            bx.hi[k] = hi + hi.abs() * 1e-15 + 1e-300;
        }
        bx
    }
    #[inline]
    pub(super) fn join(&mut self, o: &Aabb) {
        for k in 0..3 {
            self.lo[k] = self.lo[k].min(o.lo[k]);
            self.hi[k] = self.hi[k].max(o.hi[k]);
        }
    }
    /// Lower bound of the distance between two boxes (0 if they overlap or a bound is NaN).
    #[inline]
    pub(super) fn distance_lb(&self, o: &Aabb) -> f64 {
        let mut d2 = 0.0;
        for k in 0..3 {
            let g = (o.lo[k] - self.hi[k]).max(self.lo[k] - o.hi[k]).next_down();
            if g > 0.0 {
                d2 += g * g;
            }
        }
        // Rounded down: the products and sum of positive terms lose at most a few ulps.
        pacs_reach::ieee::sqrt(d2 * (1.0 - 1e-12))
    }
    /// False only if the boxes are provably apart on some axis (a NaN bound never separates).
    #[inline]
    pub(super) fn overlaps(&self, o: &Aabb) -> bool {
        !(0..3).any(|k| self.lo[k] > o.hi[k] || o.lo[k] > self.hi[k])
    }
}

/// The box (lower corner, upper corner; m) the broad phase puts around capsule `c`: per axis
/// `min(a, b) − r` and `max(a, b) + r` (endpoints `a`, `b`, radius `r`), each padded outward by
/// 1e-15 relative and 1e-300 absolute, which covers the rounding of the subtraction and addition.
///
/// # Soundness
/// Contains the capsule: its ends bound the exact `min(a, b) − r` below and `max(a, b) + r` above
/// for any finite endpoints and radius. Its Kani contract is [`box_contains_capsule`] (proven on
/// this function by `i1_broad_phase_box_contract` for capsules on the first axis with 20-bit
/// significands at any exponent; the twin `i1_broad_phase_boxes_contain` checks it for every axis
/// at full width). So two capsules that share a point have overlapping boxes,
/// and the rule's broad phase only skips provably disjoint pairs.
#[cfg_attr(kani, kani::requires(capsule_is_finite(c)))]
#[cfg_attr(kani, kani::ensures(|b: &([f64; 3], [f64; 3])| box_contains_capsule(c, b)))]
pub fn broad_phase_box(c: &Capsule) -> ([f64; 3], [f64; 3]) {
    let b = Aabb::of(c);
    (b.lo, b.hi)
}

/// The precondition of [`broad_phase_box`]'s contract: finite endpoints and radius (a capsule at
/// infinity gets `∞ − ∞` box ends; capsules of a model and of an occupancy are finite).
pub fn capsule_is_finite(c: &Capsule) -> bool {
    // No loop: Kani evaluates a precondition at every call in a harness.
    let (p, q) = (c.p1(), c.p2());
    p.x.is_finite()
        && p.y.is_finite()
        && p.z.is_finite()
        && q.x.is_finite()
        && q.y.is_finite()
        && q.z.is_finite()
        && c.radius().is_finite()
}

/// The contract of [`broad_phase_box`]: on each axis the box `(lo, hi)` reaches at least to
/// `sub_down(min(a, b), r)` below and `add_up(max(a, b), r)` above (endpoints `a`, `b`, radius
/// `r` of `c`), which bound the exact `min(a, b) − r` and `max(a, b) + r` (claim C1, a1), so the
/// box contains the capsule.
pub fn box_contains_capsule(c: &Capsule, b: &([f64; 3], [f64; 3])) -> bool {
    use pacs_reach::rounding::{add_up, sub_down};
    let (p, q, r) = (c.p1(), c.p2(), c.radius());
    (0..3).all(|k| b.0[k] <= sub_down(p[k].min(q[k]), r) && b.1[k] >= add_up(p[k].max(q[k]), r))
}

/// A ball around the base origin containing every link capsule for every configuration: a point
/// of a capsule carried by frame k is within Σ_{j≤k} |t_j| + |p| + r of the base origin (rotations
/// preserve lengths), rounded up and padded for the rounding of the model's fixed transforms.
pub fn workspace_ball(robot: &RobotModel, tracking_error: f64) -> Capsule {
    let mut cum = [0.0; MAX_DOF + 1];
    for (j, joint) in robot.joints().iter().enumerate() {
        let t = joint.origin.translation.vector;
        cum[j + 1] = add_up(cum[j], norm3_up(t.x, t.y, t.z));
    }
    let mut r: f64 = 0.0;
    for l in robot.links() {
        for c in &l.capsules {
            let (a, b) = (c.p1(), c.p2());
            let p = norm3_up(a.x, a.y, a.z).max(norm3_up(b.x, b.y, b.z));
            r = r.max(add_up(add_up(cum[l.frame], p), c.radius()));
        }
    }
    let r = add_up(mul_up(r, 1.0 + 1e-12), add_up(tracking_error, 1e-9));
    let base = nalgebra::Point3::from(robot.base().translation.vector);
    Capsule::new_unchecked(base, base, r)
}
