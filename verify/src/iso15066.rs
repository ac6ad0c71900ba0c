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
//!   the contact may be a pinch: another person shares the cell (they may be anywhere:
//!   [`ContactRule::set_other_people`]), or the part may also touch an environment shape, a body
//!   part it can be clamped against (`HumanModel::clampable`), or robot capsules on **two
//!   different frames**
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
//! # Soundness (claim C8′, harnesses `proofs::harnesses::rule::i1_*`)
//! If the inputs enclose the true motion over the interval (every true link capsule inside its
//! occupancy capsule, every true body-part capsule inside its occupancy, every true joint velocity
//! inside the box, the true kinetic energy ≤ `E`) and [`ContactRule::check`] reports no
//! violation, then at every instant of the interval: no SSM body part touches the robot while a
//! joint moves faster than `rest_speed`, and every PFL body part touching the robot does so with
//! kinetic energy at most its threshold for the true contact type (constrained whenever the part
//! is truly pinched between two frames, the environment, a clampable part or — with other
//! people in the cell, [`ContactRule::set_other_people`], which then takes every PFL contact as
//! a possible pinch — another person).
//! The broad phase only skips pairs that are provably disjoint (outward-padded boxes, a ball
//! containing the robot in every configuration), so it never hides a contact.
//!
//! Kani checks the claim in parts: the narrow phase ([`ContactRule::judge`]) for any contact
//! masks containing the true contacts (`i1_rule_judgement_sound`), the broad phase's boxes
//! ([`broad_phase_box`], `i1_broad_phase_boxes_contain`) and the capsule test
//! (`pacs_reach::geometry`, b1/b2); the property test `i1_rule_sound` checks the whole `check`.

mod broad_phase;
mod check;
mod environment;
mod object;

pub use broad_phase::{box_contains_capsule, broad_phase_box, capsule_is_finite, workspace_ball};
pub use environment::EnvShape;
pub use object::{
    ObjectOutcome, ObjectRule, ObjectViolation, contact_allowed_only_within_rule, contact_violates,
};

use broad_phase::Aabb;
use pacs_models::{Capsule, Constraint, HumanModel, RobotModel};
use pacs_reach::JointBox;
use pacs_reach::robot::RobotReach;
use serde::{Deserialize, Serialize};
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
    /// `rest_speed` is negative, not finite, or above [`MAX_REST_SPEED`].
    #[error(
        "rest_speed: value {0} rad/s must be finite and within [0, 0.05] rad/s (a robot whose joints move faster is not at rest: a larger value would let SSM accept contact while it moves)"
    )]
    RestSpeed(f64),
}

/// Which ISO/TS 15066 mode a violation concerns.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ConstraintKind {
    /// Speed and separation monitoring.
    Ssm,
    /// Power and force limiting.
    Pfl,
    /// No contact at all (a dynamic object that must not be touched; never a body part).
    #[serde(rename = "no_contact")]
    NoContact,
}

impl ConstraintKind {
    /// The short name assessors use: `SSM`, `PFL`, `no contact`.
    pub fn label(self) -> &'static str {
        match self {
            ConstraintKind::Ssm => "SSM",
            ConstraintKind::Pfl => "PFL",
            ConstraintKind::NoContact => "no contact",
        }
    }

    /// The kind of an object's contact constraint.
    pub fn of_object(c: pacs_models::object::ObjectContact) -> Self {
        match c {
            pacs_models::object::ObjectContact::NoContact => ConstraintKind::NoContact,
            pacs_models::object::ObjectContact::Ssm => ConstraintKind::Ssm,
            pacs_models::object::ObjectContact::Pfl { .. } => ConstraintKind::Pfl,
        }
    }
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
///
/// # Soundness
/// Its Kani contract is [`threshold_within_limits`] (proven on this function for every
/// constraint, flag and threshold, NaN included, by `i1_threshold_contract`): never above a
/// limit that applies, so a clamp is never judged against the free-contact limit alone.
#[cfg_attr(kani, kani::ensures(|r: &f64| threshold_within_limits(c, constrained, *r)))]
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

/// The contract of [`threshold`]: the threshold `r` (J) for constraint `c` is 0 under SSM; under
/// PFL it is one of the two limits (or NaN only if both are) and never above the unconstrained
/// limit, nor above the constrained one for a possible clamp (`constrained`), except where that
/// limit is NaN (a NaN limit is ignored by `min`; the rule judges a NaN threshold a violation).
pub fn threshold_within_limits(c: Constraint, constrained: bool, r: f64) -> bool {
    match c {
        Constraint::Ssm => r == 0.0 && r.is_sign_positive(),
        Constraint::Pfl {
            unconstrained: u,
            constrained: cons,
        } => {
            let one_of = r.to_bits() == u.to_bits()
                || (constrained && r.to_bits() == cons.to_bits())
                || (r.is_nan() && u.is_nan() && (!constrained || cons.is_nan()));
            one_of && (u.is_nan() || r <= u) && (!constrained || cons.is_nan() || r <= cons)
        }
    }
}

/// The largest joint speed (rad/s) that may count as "at rest" for SSM: 0.05 rad/s, about 6 cm/s
/// at the FR3's reach. A larger `rest_speed` would let SSM accept contact with a moving robot,
/// so the rule refuses it ([`RuleError::RestSpeed`]).
pub const MAX_REST_SPEED: f64 = 0.05;

/// `rest_speed` (rad/s) is finite and within `[0, MAX_REST_SPEED]`.
pub fn check_rest_speed(rest_speed: f64) -> Result<(), RuleError> {
    if (0.0..=MAX_REST_SPEED).contains(&rest_speed) {
        Ok(())
    } else {
        Err(RuleError::RestSpeed(rest_speed))
    }
}

/// The robot is provably at rest on the interval: every joint's velocity box lies in
/// `[−rest_speed, rest_speed]` (rad/s). The one rest test of SSM, for body parts and objects.
///
/// # Soundness
/// Its Kani contract is [`every_speed_within`]: `true` only if no velocity in the box is faster
/// than `rest_speed`. Checked by the twin `i1_decision_atoms_within_rule` (up to 7 joints) and
/// proven on this function by `i1_at_rest_contract` (`proof_for_contract`, boxes of 7 joints
/// from any floats; Bitwuzla, in CI); mutant `x72` fails both.
#[cfg_attr(kani, kani::ensures(|r: &bool| !*r || every_speed_within(dq, rest_speed)))]
#[inline]
pub fn at_rest(dq: &JointBox, rest_speed: f64) -> bool {
    (0..dq.dof()).all(|j| {
        let (lo, hi) = dq.bounds(j);
        lo >= -rest_speed && hi <= rest_speed
    })
}

/// The contract of [`at_rest`]: every joint velocity `v` (rad/s) in the box `dq` has
/// `|v| ≤ rest_speed` (both ends of each joint's interval do, and `|v|` is at most the larger of
/// theirs).
pub fn every_speed_within(dq: &JointBox, rest_speed: f64) -> bool {
    (0..dq.dof()).all(|j| {
        let (lo, hi) = dq.bounds(j);
        lo.abs() <= rest_speed && hi.abs() <= rest_speed
    })
}

/// One (body part, link) pair in violation on the interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairViolation {
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
    /// The separation figure (m) of robot and human occupancies: the least over capsule pairs
    /// of a lower bound of their core-segment distance minus their radii
    /// ([`pacs_reach::geometry::capsule_separation_lower_bound`]). Positive: provably apart by at
    /// least this much. ≤ 0 exactly when contact is possible (then the most negative pair's
    /// figure: how far the radii overlap). +∞ without body parts. Only computed when asked for;
    /// else +∞ without contact and ≤ 0 with contact.
    pub separation: f64,
    /// For PFL contacts: (largest energy bound, smallest threshold) seen (J).
    pub pfl: Option<(f64, f64)>,
}

/// The narrow phase's part of an [`Outcome`] ([`ContactRule::judge`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Judgement {
    /// A violation is possible (some hit was reported).
    pub violated: bool,
    /// For PFL contacts: (largest energy bound, smallest threshold) seen (J).
    pub pfl: Option<(f64, f64)>,
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
    /// Other people share the cell ([`Self::set_other_people`]): every PFL contact may be a
    /// pinch against one of them.
    other_people: bool,
    rest_speed: f64,
    workspace: Capsule,
    // Scratch.
    robot_aabb: Vec<Aabb>,
    part_aabb: Vec<Aabb>,
    /// Box distances (m) of the separation figure's search: per part to the robot's union box,
    /// per robot capsule to the current part's box (+∞ once taken).
    part_gap: Vec<f64>,
    capsule_gap: Vec<f64>,
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
        check_rest_speed(rest_speed)?;
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
            other_people: false,
            rest_speed,
            workspace,
            robot_aabb: vec![Aabb::default(); ncaps],
            part_aabb: vec![Aabb::default(); parts],
            part_gap: vec![0.0; parts],
            capsule_gap: vec![0.0; ncaps],
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

    /// The rule for one of several people in the cell (`present`): a body part touched by the
    /// robot may be pinched between the robot and another person (a hand pressed against a
    /// colleague's arm), so every PFL contact is judged against the constrained (clamping)
    /// threshold, `min(constrained, unconstrained)`. Each person's occupancy is checked on its
    /// own (the shield per person, the audit in one pass per person), so where another person
    /// is cannot be told here: the rule assumes they may be anywhere. Over-approximating the
    /// clamping flag only lowers the threshold (module docs), so this keeps claim C8′ for
    /// clamps against people. SSM is unaffected (no contact is allowed while the robot moves).
    pub fn set_other_people(&mut self, present: bool) {
        self.other_people = present;
    }

    /// Whether the rule counts other people as surfaces to be pinched against
    /// ([`Self::set_other_people`]).
    pub fn other_people(&self) -> bool {
        self.other_people
    }
}
