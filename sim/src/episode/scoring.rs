//! Scoring against the ground truth: separation, ISO/TS 15066 violation and kinetic energy of a
//! robot state, computed with exact geometry against the true human and objects.

use super::REST_SPEED;
use crate::objects::SimObject;
use nalgebra::Point3;
use pacs_models::{HumanModel, RobotModel, TaskConstraints};
use pacs_reach::geometry::segment_distance_lower_bound;

/// Ground truth at (q, q̇) under the ISO/TS 15066 rule of [`pacs_verify::iso15066`]: minimum
/// separation of the robot's links (the fixed base included) to the true human, and whether a
/// constraint is violated (SSM: contact while some joint moves faster than [`REST_SPEED`]; PFL:
/// contact with the whole robot's kinetic energy ½q̇ᵀM(q)q̇ above the body part's threshold, the
/// constrained one if the part touches links on two different frames or a clampable body part
/// touches it). Returns (separation, violation, kinetic energy).
pub fn ground_truth(
    robot: &RobotModel,
    human: &HumanModel,
    tc: &TaskConstraints,
    q: &[f64],
    dq: &[f64],
    kp: &[[f64; 3]],
) -> (f64, bool, f64) {
    use pacs_verify::iso15066::{frames_can_pinch, threshold};
    let caps = robot.capsules_world(q);
    let energy = robot.kinetic_energy(q, dq);
    let moving = dq.iter().any(|v| v.abs() > REST_SPEED);
    let part_cap = |bp: &pacs_models::human::BodyPart| {
        (
            Point3::from(kp[bp.from]),
            Point3::from(kp[bp.to]),
            bp.thickness / 2.0,
        )
    };
    let parts = human.body_parts();
    let mut sep = f64::INFINITY;
    let mut violation = false;
    for (b, bp) in parts.iter().enumerate() {
        let (a, c, r) = part_cap(bp);
        let mut touched: Option<usize> = None;
        let mut pinched = false;
        for (li, cap) in &caps {
            let frame = robot.links()[*li].frame;
            let d = segment_distance_lower_bound(&a, &c, &cap.p1(), &cap.p2()) - cap.radius() - r;
            sep = sep.min(d);
            if d <= 0.0 {
                match touched {
                    Some(f) if frames_can_pinch(f, frame) => pinched = true,
                    Some(_) => {}
                    None => touched = Some(frame),
                }
            }
        }
        if touched.is_none() || !moving {
            continue;
        }
        let clamped = pinched
            || parts.iter().enumerate().any(|(o, op)| {
                let (oa, oc, orad) = part_cap(op);
                human.clampable(b, o)
                    && segment_distance_lower_bound(&a, &c, &oa, &oc) - r - orad <= 0.0
            });
        if energy > threshold(tc.per_part[b], clamped) {
            violation = true;
        }
    }
    (sep, violation, energy)
}

/// Ground truth of a robot state against the true object at `t` under the object rule of
/// [`pacs_verify::iso15066::contact_violates`] (SSM: contact while some joint moves faster than
/// [`REST_SPEED`]; PFL: contact with the whole robot's kinetic energy above the object's
/// threshold; no-contact: any contact). `caps` are the robot's world capsules at the state,
/// `energy` its kinetic energy (J). Returns (separation in m, violation).
pub fn object_ground_truth(
    object: &SimObject,
    t: f64,
    caps: &[pacs_models::Capsule],
    dq: &[f64],
    energy: f64,
) -> (f64, bool) {
    let sep = caps
        .iter()
        .map(|c| object.separation(t, c))
        .fold(f64::INFINITY, f64::min);
    if sep > 0.0 {
        return (sep, false);
    }
    let at_rest = dq.iter().all(|v| v.abs() <= REST_SPEED);
    let (violation, _) =
        pacs_verify::iso15066::contact_violates(object.contact, at_rest, || energy);
    (sep, violation)
}
