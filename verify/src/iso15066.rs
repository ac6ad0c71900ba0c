//! The one ISO/TS 15066 rule: the SSM/PFL decision for one time interval, used by the shield
//! (for every interval of a monitored trajectory) and by the offline audit (for every span
//! between logged samples). There is no other copy of this rule.
//!
//! # Inputs (all enclosures over the same time interval `[t_a, t_b]`)
//! - the robot's link occupancy: capsules containing every link for every configuration the
//!   robot may take (`pacs_reach::robot::RobotReach`), with each capsule's link and carrying frame;
//! - the robot's joint velocity box (rad/s), for the rest test;
//! - an upper bound `E` of the **whole robot's** kinetic energy ½ q̇ᵀM(q)q̇ over the interval,
//!   computed on demand (only when PFL contact is possible);
//! - each body part's occupancy (`pacs_reach::human::HumanReach`), its constraint and the human
//!   model's clampable pairs; the static environment.
//!
//! # The rule
//! A body part *may be in contact* with a link if one of the link's capsules and the part's
//! occupancy are not provably disjoint (touching counts). For each part with possible contact:
//! - **SSM**: violated unless the robot is provably at rest (every joint's velocity box inside
//!   `[−rest_speed, rest_speed]`). Contact with the base link counts: SSM allows no contact while
//!   the robot moves.
//! - **PFL**: violated if `E` exceeds the part's threshold, the *constrained* (clamping) one if
//!   the contact may be a pinch: the part may also touch an environment shape, a body part it can
//!   be clamped against (`HumanModel::clampable`), or robot capsules on **two different frames**
//!   (adjacent links included: a joint between them can close the gap, e.g. an elbow pinch between
//!   links 3 and 4; the base, frame 0, counts as a surface to be pinched against). Otherwise the
//!   unconstrained threshold. The constrained threshold used is `min(constrained, unconstrained)`,
//!   so an over-approximated clamping classification can never raise the threshold.
//!
//! Why the whole-robot energy: at a contact the distal links push too (they add reflected mass),
//! so the kinetic energy of the sub-chain up to the touched link can understate what is
//! transferred. For a contact normal `n` with Jacobian row `Jₙ`, the energy transferable in an
//! impact is at most ½(Jₙq̇)²/(JₙM⁻¹Jₙᵀ) ≤ ½q̇ᵀMq̇ (Cauchy–Schwarz in the M-inner product), so the
//! whole-robot kinetic energy bounds it at any contact point.
//!
//! # Soundness (claim C8, harness `proofs::harnesses::rule::i1_rule_sound`)
//! If the inputs enclose the true motion over the interval (every true link capsule inside its
//! occupancy capsule, every true body-part capsule inside its occupancy, every true joint velocity
//! inside the box, the true kinetic energy ≤ `E`) and [`ContactRule::check`] reports no
//! violation, then at every instant of the interval: no SSM body part touches the robot while a
//! joint moves faster than `rest_speed`, and every PFL body part touching the robot does so with
//! kinetic energy at most its threshold for the true contact type (constrained whenever the part
//! is truly pinched between two frames, the environment or a clampable part).
//! The broad phase only skips pairs that are provably disjoint (outward-padded boxes, a ball
//! containing the robot in every configuration), so it never hides a contact.

use pacs_models::robot::MAX_DOF;
use pacs_models::{Capsule, Constraint, HumanModel, RobotModel};
use pacs_reach::JointBox;
use pacs_reach::geometry::{capsule_distance_lower_bound, capsules_may_intersect};
use pacs_reach::robot::RobotReach;
use pacs_reach::rounding::{add_up, mul_up, norm3_up};
use serde::{Deserialize, Serialize};
use std::ops::ControlFlow;
use thiserror::Error;

/// Maximum number of robot capsules the rule supports (contact bit masks).
pub const MAX_CAPSULES: usize = 128;

/// Errors of building a [`ContactRule`].
#[derive(Debug, Error, Clone, PartialEq)]
pub enum RuleError {
    /// The robot has more capsules than [`MAX_CAPSULES`] or none.
    #[error("robot `{robot}` has {capsules} capsules; the rule supports 1 to {MAX_CAPSULES}")]
    Capsules {
        /// Robot name.
        robot: String,
        /// Its capsule count.
        capsules: usize,
    },
    /// The constraints do not match the human model's body parts.
    #[error("constraints: {given} entries for {parts} body parts")]
    Constraints {
        /// Entries given.
        given: usize,
        /// Body parts of the human model.
        parts: usize,
    },
    /// `rest_speed` is negative or not finite.
    #[error("rest_speed: value {0} must be finite and >= 0")]
    RestSpeed(f64),
}

/// A static environment shape (for clamping decisions): a capsule or an axis-aligned box (m).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase")]
pub enum EnvShape {
    /// Capsule (a sphere when p1 = p2).
    Capsule {
        /// First endpoint (m).
        p1: [f64; 3],
        /// Second endpoint (m).
        p2: [f64; 3],
        /// Radius (m).
        radius: f64,
    },
    /// Axis-aligned box.
    Box {
        /// Minimum corner (m).
        min: [f64; 3],
        /// Maximum corner (m).
        max: [f64; 3],
    },
}

impl From<&Capsule> for EnvShape {
    fn from(c: &Capsule) -> Self {
        EnvShape::Capsule {
            p1: c.p1().coords.into(),
            p2: c.p2().coords.into(),
            radius: c.radius(),
        }
    }
}

impl EnvShape {
    /// True unless the capsule provably does not touch the shape.
    pub fn may_touch(&self, c: &Capsule) -> bool {
        match *self {
            EnvShape::Capsule { p1, p2, radius } => {
                let e = Capsule::new_unchecked(p1.into(), p2.into(), radius);
                capsules_may_intersect(&e, c)
            }
            EnvShape::Box { min, max } => {
                // The capsule meets the box iff its segment meets the box inflated by its radius;
                // slab test on the inflated box, with a small outward tolerance.
                let r = c.radius() * (1.0 + 1e-12) + 1e-9;
                let (a, b) = (c.p1(), c.p2());
                let (mut t0, mut t1) = (0.0f64, 1.0f64);
                for k in 0..3 {
                    let (lo, hi) = (min[k] - r, max[k] + r);
                    let d = b[k] - a[k];
                    if d.abs() < 1e-300 {
                        if a[k] < lo || a[k] > hi {
                            return false;
                        }
                    } else {
                        let (mut u, mut v) = ((lo - a[k]) / d, (hi - a[k]) / d);
                        if u > v {
                            std::mem::swap(&mut u, &mut v);
                        }
                        t0 = t0.max(u - 1e-12);
                        t1 = t1.min(v + 1e-12);
                        if t0 > t1 {
                            return false;
                        }
                    }
                }
                true
            }
        }
    }
}

/// Which ISO/TS 15066 mode a violation concerns.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ConstraintKind {
    /// Speed and separation monitoring.
    Ssm,
    /// Power and force limiting.
    Pfl,
}

/// Whether two robot capsules carried by frames `a` and `b` can pinch a body part between them:
/// any two different frames (adjacent ones included: the joint between them can close the gap;
/// frame 0 is the fixed base, a surface to be pinched against). Capsules on one frame are one
/// rigid body and cannot close on each other.
#[inline]
pub fn frames_can_pinch(a: usize, b: usize) -> bool {
    a != b
}

/// The threshold (J) for a contact with constraint `c`: SSM 0; PFL the unconstrained threshold,
/// or `min(constrained, unconstrained)` for a possible clamping contact.
#[inline]
pub fn threshold(c: Constraint, constrained: bool) -> f64 {
    match c {
        Constraint::Ssm => 0.0,
        Constraint::Pfl {
            unconstrained,
            constrained: cons,
        } => {
            if constrained {
                cons.min(unconstrained)
            } else {
                unconstrained
            }
        }
    }
}

/// One (body part, link) pair in violation on the interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Body part index (human model order).
    pub part: usize,
    /// Robot link index (robot model order).
    pub link: usize,
    /// SSM or PFL.
    pub kind: ConstraintKind,
    /// Energy bound (J; whole robot) for PFL, 0 for SSM.
    pub energy: f64,
    /// Threshold (J; 0 for SSM).
    pub threshold: f64,
    /// The contact may be a pinch (PFL constrained threshold).
    pub constrained: bool,
}

/// The result of [`ContactRule::check`] for one interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Outcome {
    /// Some body part may touch the robot.
    pub contact: bool,
    /// A violation is possible (some hit was reported).
    pub violated: bool,
    /// Lower bound (m) of the separation between robot and human occupancies (0 on possible
    /// contact, +∞ without body parts). Only computed when asked for; else +∞ unless contact.
    pub separation: f64,
    /// For PFL contacts: (largest energy bound, smallest threshold) seen (J).
    pub pfl: Option<(f64, f64)>,
}

/// An axis-aligned box containing a capsule (bounds rounded outward).
#[derive(Debug, Clone, Copy, Default)]
struct Aabb {
    lo: [f64; 3],
    hi: [f64; 3],
}

impl Aabb {
    const EMPTY: Aabb = Aabb {
        lo: [f64::INFINITY; 3],
        hi: [f64::NEG_INFINITY; 3],
    };
    #[inline]
    fn of(c: &Capsule) -> Self {
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
    fn join(&mut self, o: &Aabb) {
        for k in 0..3 {
            self.lo[k] = self.lo[k].min(o.lo[k]);
            self.hi[k] = self.hi[k].max(o.hi[k]);
        }
    }
    /// Lower bound of the distance between two boxes (0 if they overlap).
    #[inline]
    fn distance_lb(&self, o: &Aabb) -> f64 {
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
    #[inline]
    fn overlaps(&self, o: &Aabb) -> bool {
        (0..3).all(|k| self.lo[k] <= o.hi[k] && o.lo[k] <= self.hi[k])
    }
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

/// The ISO/TS 15066 rule for one robot, one human model, one task and one environment, with its
/// scratch space (allocated once; [`Self::check`] allocates nothing).
#[derive(Debug, Clone)]
pub struct ContactRule {
    capsule_link: Vec<usize>,
    capsule_frame: Vec<usize>,
    constraints: Vec<Constraint>,
    /// Row-major parts × parts: part a can be clamped against part b.
    clampable: Vec<bool>,
    parts: usize,
    environment: Vec<EnvShape>,
    rest_speed: f64,
    workspace: Capsule,
    // Scratch.
    robot_aabb: Vec<Aabb>,
    contact: Vec<u128>,
}

impl ContactRule {
    /// The rule for `reach`'s capsules (of `robot`), the human model's body parts with one
    /// constraint each, the environment, and the rest speed (rad/s) below which the robot counts
    /// as at rest for SSM.
    pub fn new(
        robot: &RobotModel,
        reach: &RobotReach,
        human: &HumanModel,
        constraints: &[Constraint],
        environment: Vec<EnvShape>,
        rest_speed: f64,
    ) -> Result<Self, RuleError> {
        let ncaps = reach.capsule_count();
        if ncaps == 0 || ncaps > MAX_CAPSULES {
            return Err(RuleError::Capsules {
                robot: robot.name().to_string(),
                capsules: ncaps,
            });
        }
        let parts = human.body_parts().len();
        if constraints.len() != parts {
            return Err(RuleError::Constraints {
                given: constraints.len(),
                parts,
            });
        }
        let mut capsule_link = vec![0; ncaps];
        for (l, &(s, e)) in reach.link_ranges().iter().enumerate() {
            for c in &mut capsule_link[s..e] {
                *c = l;
            }
        }
        let capsule_frame = (0..ncaps).map(|i| reach.capsule_frame(i)).collect();
        let clampable = (0..parts * parts)
            .map(|i| human.clampable(i / parts, i % parts))
            .collect();
        Self::from_tables(
            capsule_link,
            capsule_frame,
            constraints.to_vec(),
            clampable,
            environment,
            rest_speed,
            workspace_ball(robot, reach.tracking_error()),
        )
    }

    /// The rule from plain tables (no models): per robot capsule its link and carrying frame
    /// (capsules of one link contiguous), per body part its constraint, the clampable relation
    /// (row-major parts × parts), the environment, the rest speed (rad/s) and a ball containing
    /// the robot in every configuration (see [`workspace_ball`]). Used by the harnesses.
    #[allow(clippy::too_many_arguments)]
    pub fn from_tables(
        capsule_link: Vec<usize>,
        capsule_frame: Vec<usize>,
        constraints: Vec<Constraint>,
        clampable: Vec<bool>,
        environment: Vec<EnvShape>,
        rest_speed: f64,
        workspace: Capsule,
    ) -> Result<Self, RuleError> {
        let ncaps = capsule_link.len();
        let parts = constraints.len();
        if ncaps == 0 || ncaps > MAX_CAPSULES || capsule_frame.len() != ncaps {
            return Err(RuleError::Capsules {
                robot: "tables".into(),
                capsules: ncaps,
            });
        }
        if clampable.len() != parts * parts {
            return Err(RuleError::Constraints {
                given: parts,
                parts: (clampable.len() as f64).sqrt() as usize,
            });
        }
        if !(rest_speed.is_finite() && rest_speed >= 0.0) {
            return Err(RuleError::RestSpeed(rest_speed));
        }
        let clampable = (0..parts * parts)
            .map(|i| i / parts != i % parts && clampable[i])
            .collect();
        Ok(Self {
            capsule_link,
            capsule_frame,
            constraints,
            clampable,
            parts,
            environment,
            rest_speed,
            workspace,
            robot_aabb: vec![Aabb::default(); ncaps],
            contact: vec![0; parts],
        })
    }

    /// Number of robot capsules the rule expects.
    pub fn capsule_count(&self) -> usize {
        self.capsule_link.len()
    }
    /// The link of capsule `c`.
    pub fn capsule_link(&self, c: usize) -> usize {
        self.capsule_link[c]
    }
    /// The carrying frame of capsule `c`.
    pub fn capsule_frame(&self, c: usize) -> usize {
        self.capsule_frame[c]
    }
    /// The constraint of body part `p`.
    pub fn constraint(&self, p: usize) -> Constraint {
        self.constraints[p]
    }
    /// Body part `a` can be clamped against body part `b`.
    pub fn clampable(&self, a: usize, b: usize) -> bool {
        a < self.parts && b < self.parts && self.clampable[a * self.parts + b]
    }
    /// The static environment.
    pub fn environment(&self) -> &[EnvShape] {
        &self.environment
    }
    /// The rest speed (rad/s).
    pub fn rest_speed(&self) -> f64 {
        self.rest_speed
    }

    /// Broad phase, stage 1 (no robot occupancy needed): if every body-part occupancy is
    /// provably outside the ball containing the robot in every configuration, returns a lower
    /// bound (m) of the separation; then no contact is possible on the interval. `None` otherwise.
    pub fn workspace_clear(&self, human_caps: &[Capsule]) -> Option<f64> {
        let mut sep = f64::INFINITY;
        for h in human_caps {
            let d = capsule_distance_lower_bound(&self.workspace, h);
            if d > 0.0 {
                sep = sep.min(d);
            } else {
                return None;
            }
        }
        Some(sep)
    }

    /// The rule for one interval (see the module docs): `robot_caps` the link occupancy (one per
    /// capsule, in `RobotReach` order), `dq` the joint velocity box (rad/s),
    /// `human_caps` the body-part occupancies, `energy` computes an upper bound (J) of the
    /// whole robot's kinetic energy over the interval (called at most once, only on possible PFL
    /// contact; return +∞ if it cannot be bounded). Every violating (part, link) pair is passed
    /// to `sink` in part then link order; `sink` returns `ControlFlow::Break` to stop early.
    /// `separation`: also compute the separation lower bound when no contact is possible
    /// (costs capsule distances).
    pub fn check(
        &mut self,
        robot_caps: &[Capsule],
        dq: &JointBox,
        human_caps: &[Capsule],
        mut energy: impl FnMut() -> f64,
        separation: bool,
        mut sink: impl FnMut(&Hit) -> ControlFlow<()>,
    ) -> Outcome {
        let mut out = Outcome {
            contact: false,
            violated: false,
            separation: f64::INFINITY,
            pfl: None,
        };
        debug_assert_eq!(robot_caps.len(), self.capsule_link.len());
        debug_assert_eq!(human_caps.len(), self.parts);
        // Broad phase, stage 2: boxes around the robot's capsules and their union.
        let mut all = Aabb::EMPTY;
        for (bx, rc) in self.robot_aabb.iter_mut().zip(robot_caps) {
            *bx = Aabb::of(rc);
            all.join(bx);
        }
        for (p, hc) in human_caps.iter().enumerate() {
            let hb = Aabb::of(hc);
            let mut mask = 0u128;
            if all.overlaps(&hb) {
                for (c, rc) in robot_caps.iter().enumerate() {
                    if self.robot_aabb[c].overlaps(&hb) && capsules_may_intersect(rc, hc) {
                        mask |= 1u128 << c;
                    }
                }
            }
            self.contact[p] = mask;
            if mask != 0 {
                out.contact = true;
                out.separation = 0.0;
            } else if separation && all.distance_lb(&hb) < out.separation {
                // Separation lower bound; a pair whose boxes are farther apart than the best so
                // far cannot lower it.
                let mut best = out.separation;
                for (rc, rb) in robot_caps.iter().zip(&self.robot_aabb) {
                    if rb.distance_lb(&hb) < best {
                        best = best.min(capsule_distance_lower_bound(rc, hc));
                    }
                }
                out.separation = best;
            }
        }
        if !out.contact {
            return out;
        }
        // Narrow phase: the constraint of every part that may be touched.
        let at_rest = (0..dq.dof()).all(|j| {
            let (lo, hi) = dq.bounds(j);
            lo >= -self.rest_speed && hi <= self.rest_speed
        });
        let mut e_robot: Option<f64> = None;
        for p in 0..self.parts {
            let mask = self.contact[p];
            if mask == 0 {
                continue;
            }
            let constraint = self.constraints[p];
            let (kind, e, thr, constrained, bad) = match constraint {
                Constraint::Ssm => (ConstraintKind::Ssm, 0.0, 0.0, false, !at_rest),
                Constraint::Pfl { .. } => {
                    let e = *e_robot.get_or_insert_with(|| {
                        let e = energy();
                        if e.is_nan() { f64::INFINITY } else { e }
                    });
                    let constrained = self.may_pinch(p, mask, human_caps);
                    let thr = threshold(constraint, constrained);
                    out.pfl = Some(match out.pfl {
                        Some((a, b)) => (a.max(e), b.min(thr)),
                        None => (e, thr),
                    });
                    (
                        ConstraintKind::Pfl,
                        e,
                        thr,
                        constrained,
                        e > thr || thr.is_nan(),
                    )
                }
            };
            if !bad {
                continue;
            }
            out.violated = true;
            // One hit per touched link (capsules of one link are contiguous).
            let mut last_link = usize::MAX;
            let mut m = mask;
            while m != 0 {
                let c = m.trailing_zeros() as usize;
                m &= m - 1;
                let link = self.capsule_link[c];
                if link == last_link {
                    continue;
                }
                last_link = link;
                let hit = Hit {
                    part: p,
                    link,
                    kind,
                    energy: e,
                    threshold: thr,
                    constrained,
                };
                if sink(&hit).is_break() {
                    return out;
                }
            }
        }
        out
    }

    /// Whether body part `p`, touched by the robot capsules in `mask`, may be pinched: it may
    /// also touch the environment, a body part it can be clamped against, or the robot on two
    /// different frames.
    fn may_pinch(&self, p: usize, mask: u128, human_caps: &[Capsule]) -> bool {
        let hc = &human_caps[p];
        let mut first = usize::MAX;
        let mut m = mask;
        while m != 0 {
            let c = m.trailing_zeros() as usize;
            m &= m - 1;
            let f = self.capsule_frame[c];
            if first == usize::MAX {
                first = f;
            } else if frames_can_pinch(first, f) {
                return true;
            }
        }
        self.environment.iter().any(|e| e.may_touch(hc))
            || (0..self.parts).any(|o| {
                self.clampable[p * self.parts + o] && capsules_may_intersect(&human_caps[o], hc)
            })
    }
}
