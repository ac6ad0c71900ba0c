//! The rule for dynamic objects: the same ISO/TS 15066 decision as for body parts (one rest test,
//! one whole-robot energy bound), with a contact constraint per object
//! ([`pacs_models::object::ObjectContact`]).
//!
//! # Soundness (claim C8 for objects)
//! If every true link capsule lies in its occupancy capsule, the object lies in its occupancy
//! (`pacs_reach::object`, claim C4′), every true joint velocity is in the box and the true kinetic
//! energy is at most `E`, and [`ObjectRule::check`] reports no violation, then at every instant of
//! the interval: a `no_contact` object is not touched; an `ssm` object is touched only while every
//! joint speed is within `rest_speed`; a `pfl` object is touched only with kinetic energy at most
//! its threshold. Contact is excluded only where a rigorous distance lower bound is positive
//! (the bounding capsule's, then the occupancy's own), so touching counts as contact. Tests:
//! `verify/tests/object_rule.rs`.

use super::broad_phase::Aabb;
use super::{RuleError, at_rest};
use pacs_models::object::ObjectContact;
use pacs_models::{Capsule, RobotModel};
use pacs_reach::JointBox;
use pacs_reach::geometry::capsule_separation_lower_bound;
use pacs_reach::object::ObjectOccupancy;
use pacs_reach::robot::RobotReach;

/// A possible violation of an object's contact constraint on one interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObjectViolation {
    /// The first robot link (model order) that may touch the object.
    pub link: usize,
    /// The constraint violated.
    pub contact: ObjectContact,
    /// Energy bound of the whole robot (J) for PFL, 0 otherwise.
    pub energy: f64,
}

/// The result of [`ObjectRule::check`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObjectOutcome {
    /// The robot may touch the object.
    pub contact: bool,
    /// The violation, if one is possible.
    pub violation: Option<ObjectViolation>,
    /// Lower bound (m) of the distance between robot and object occupancies (0 on possible
    /// contact). Only computed when asked for; else +∞ without contact.
    pub separation: f64,
}

/// The object rule for one robot (its capsules' links, the rest speed and the ball containing it
/// in every configuration). Allocates nothing in [`Self::check`].
#[derive(Debug, Clone)]
pub struct ObjectRule {
    capsule_link: Vec<usize>,
    rest_speed: f64,
    workspace: Capsule,
}

impl ObjectRule {
    /// The rule for `reach`'s capsules (of `robot`) and the rest speed (rad/s).
    pub fn new(robot: &RobotModel, reach: &RobotReach, rest_speed: f64) -> Result<Self, RuleError> {
        let ncaps = reach.capsule_count();
        if ncaps == 0 {
            return Err(RuleError::Capsules {
                robot: robot.name().to_string(),
                capsules: ncaps,
            });
        }
        super::check_rest_speed(rest_speed)?;
        let mut capsule_link = vec![0; ncaps];
        for (l, &(s, e)) in reach.link_ranges().iter().enumerate() {
            for c in &mut capsule_link[s..e] {
                *c = l;
            }
        }
        Ok(Self {
            capsule_link,
            rest_speed,
            workspace: super::workspace_ball(robot, reach.tracking_error()),
        })
    }

    /// Broad phase without the robot's occupancy: if the object's occupancy is provably outside
    /// the ball containing the robot in every configuration, a lower bound (m) of the separation.
    pub fn workspace_clear(&self, occ: &ObjectOccupancy) -> Option<f64> {
        let d = occ.distance_lower_bound(&self.workspace);
        (d > 0.0).then_some(d)
    }

    /// The rule for one object on one interval: `robot_caps` the link occupancy (one per capsule,
    /// `RobotReach` order), `dq` the joint velocity box (rad/s), `occ` the object's occupancy,
    /// `contact` its constraint, `energy` an upper bound (J) of the whole robot's kinetic energy
    /// (called at most once, only on possible PFL contact; +∞ if it cannot be bounded).
    /// `separation`: also compute the separation lower bound (costs a capsule distance per robot
    /// capsule); without it, a robot capsule whose broad-phase box misses the box of the
    /// occupancy's bounding capsule is skipped at once (the decision only needs disjointness).
    ///
    /// # Soundness
    /// A robot capsule is passed over as untouched only if its box and the bounding capsule's
    /// box are disjoint (both contain their capsules: harness `i1_broad_phase_boxes_contain`),
    /// or the bounding capsule's distance lower bound is positive, or the occupancy's own is
    /// (claim C2/C4′). Tests: `verify/tests/object_rule.rs` (both modes).
    pub fn check(
        &self,
        robot_caps: &[Capsule],
        dq: &JointBox,
        occ: &ObjectOccupancy,
        contact: ObjectContact,
        energy: impl FnOnce() -> f64,
        separation: bool,
    ) -> ObjectOutcome {
        debug_assert_eq!(robot_caps.len(), self.capsule_link.len());
        let bounding = occ.bounding_capsule();
        let bounding_box = bounding.as_ref().map(Aabb::of);
        let mut figure = f64::INFINITY;
        let mut touched = None;
        for (c, rc) in robot_caps.iter().enumerate() {
            if let (Some(b), Some(bb)) = (&bounding, &bounding_box) {
                if !separation && !Aabb::of(rc).overlaps(bb) {
                    continue;
                }
                // One capsule distance decides and bounds (positive: provably disjoint).
                let d = capsule_separation_lower_bound(rc, b);
                if d > 0.0 {
                    figure = figure.min(d);
                    continue;
                }
            }
            let d = occ.distance_lower_bound(rc);
            if d > 0.0 {
                figure = figure.min(d);
            } else {
                touched = Some(self.capsule_link[c]);
                break;
            }
        }
        let Some(link) = touched else {
            return ObjectOutcome {
                contact: false,
                violation: None,
                // Without the figure, pairs skipped by boxes are missing from the minimum.
                separation: if separation { figure } else { f64::INFINITY },
            };
        };
        let (bad, e) = contact_violates(contact, at_rest(dq, self.rest_speed), energy);
        ObjectOutcome {
            contact: true,
            violation: bad.then_some(ObjectViolation {
                link,
                contact,
                energy: e,
            }),
            separation: 0.0,
        }
    }
}

/// Whether a contact with an object under `contact` violates it: `no_contact` always, `ssm`
/// unless the robot is `at_rest`, `pfl` when the kinetic-energy bound `energy` (J, called only
/// for PFL; NaN counts as +∞) exceeds the threshold. Returns (violation, the energy used, 0 for
/// SSM and no-contact). The one decision for objects: [`ObjectRule::check`] applies it to
/// reachable sets, the simulation's ground truth to exact states.
///
/// # Soundness
/// Its Kani contract is [`contact_allowed_only_within_rule`] (proven on this function for every
/// contact kind, rest flag, threshold and energy, NaN included, by
/// `i1_object_decision_contract`): no violation only where the rule allows the contact.
#[cfg_attr(kani, kani::ensures(|r: &(bool, f64)| contact_allowed_only_within_rule(contact, at_rest, *r)))]
pub fn contact_violates(
    contact: ObjectContact,
    at_rest: bool,
    energy: impl FnOnce() -> f64,
) -> (bool, f64) {
    match contact {
        ObjectContact::NoContact => (true, 0.0),
        ObjectContact::Ssm => (!at_rest, 0.0),
        ObjectContact::Pfl { threshold } => {
            let e = energy();
            let e = if e.is_nan() { f64::INFINITY } else { e };
            (e > threshold || threshold.is_nan(), e)
        }
    }
}

/// The contract of [`contact_violates`]: a result `(violated, energy)` that reports no violation
/// only where the object's rule allows the contact: never under `no_contact`, under `ssm` only
/// `at_rest`, under `pfl` only with an energy (the bound used, not NaN) at most the threshold.
pub fn contact_allowed_only_within_rule(
    contact: ObjectContact,
    at_rest: bool,
    (violated, energy): (bool, f64),
) -> bool {
    violated
        || match contact {
            ObjectContact::NoContact => false,
            ObjectContact::Ssm => at_rest,
            ObjectContact::Pfl { threshold } => energy <= threshold,
        }
}
