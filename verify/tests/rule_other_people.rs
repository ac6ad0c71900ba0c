//! A body part may be pinched between the robot and another person: with other people in the
//! cell (`ContactRule::set_other_people`), every PFL contact is judged against the constrained
//! threshold; alone, a contact touching neither the environment, a clampable part nor two robot
//! frames is judged against the unconstrained one. SSM is unaffected.

use nalgebra::Point3;
use pacs_models::{Capsule, Constraint};
use pacs_reach::JointBox;
use pacs_verify::iso15066::{ContactRule, PairViolation};
use std::ops::ControlFlow;

const UNCONSTRAINED: f64 = 0.265; // J, a hand's free-contact limit
const CONSTRAINED: f64 = 0.014; // J, its clamping limit
const ENERGY: f64 = 0.1; // J, between the two

fn cap(a: [f64; 3], b: [f64; 3], r: f64) -> Capsule {
    Capsule::new_unchecked(Point3::from(a), Point3::from(b), r)
}

/// One robot capsule (link 0 on frame 1), one body part touching it (a hand), with `constraint`.
fn rule(constraint: Constraint) -> ContactRule {
    ContactRule::from_tables(
        vec![0],
        vec![1],
        vec![constraint],
        vec![false],
        vec![],
        0.01,
        cap([0.0, 0.0, 0.0], [0.0, 0.0, 0.0], 2.0),
    )
    .unwrap()
}

/// The rule's violations for the hand touching the moving robot with kinetic energy `ENERGY`.
fn judge(rule: &mut ContactRule) -> Vec<PairViolation> {
    let robot = [cap([0.0, 0.0, 0.5], [0.0, 0.0, 0.8], 0.05)];
    let hand = [cap([0.04, 0.0, 0.6], [0.1, 0.0, 0.6], 0.03)];
    let dq = JointBox::new(&[0.4], &[0.5]).unwrap();
    let mut out = Vec::new();
    let outcome = rule.check(
        &robot,
        &dq,
        &hand,
        || ENERGY,
        false,
        |v| {
            out.push(*v);
            ControlFlow::Continue(())
        },
    );
    assert!(outcome.contact, "the hand must touch the robot");
    assert_eq!(outcome.violated, !out.is_empty());
    out
}

#[test]
fn another_person_makes_every_pfl_contact_a_possible_pinch() {
    let pfl = Constraint::Pfl {
        unconstrained: UNCONSTRAINED,
        constrained: CONSTRAINED,
    };
    // Alone: a free contact, 0.1 J ≤ 0.265 J.
    let mut alone = rule(pfl);
    assert!(!alone.other_people());
    assert!(judge(&mut alone).is_empty());
    // With another person in the cell: the hand may be pressed against them, 0.1 J > 0.014 J.
    let mut shared = rule(pfl);
    shared.set_other_people(true);
    let v = judge(&mut shared);
    assert_eq!(v.len(), 1, "{v:?}");
    assert!(v[0].constrained);
    assert_eq!(v[0].threshold, CONSTRAINED);
    assert_eq!(v[0].energy, ENERGY);
    // Back to one person: the free contact again.
    shared.set_other_people(false);
    assert!(judge(&mut shared).is_empty());
}

#[test]
fn other_people_leave_ssm_as_it_is() {
    for others in [false, true] {
        let mut r = rule(Constraint::Ssm);
        r.set_other_people(others);
        let v = judge(&mut r);
        assert_eq!(v.len(), 1, "others = {others}: {v:?}");
        assert_eq!(v[0].threshold, 0.0);
    }
}
