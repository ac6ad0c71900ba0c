//! The object form of the one rule (`pacs_verify::iso15066::ObjectRule`): soundness against
//! sampled true configurations and object motions, and the constraint semantics (no contact,
//! SSM rest test, PFL threshold) on hand-built cases.

use nalgebra::Point3;
use pacs_models::object::{ObjectContact, ObjectModel, ObjectSpec, ShapeSpec};
use pacs_models::{Capsule, fr3};
use pacs_reach::JointBox;
use pacs_reach::geometry::segment_distance_lower_bound;
use pacs_reach::object::{ObjectMeasurement, occupancy};
use pacs_reach::robot::RobotReach;
use pacs_verify::iso15066::ObjectRule;

struct Lcg(u64);
impl Lcg {
    fn unit(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + self.unit() * (hi - lo)
    }
}

fn ball(radius: f64) -> ObjectModel {
    ObjectModel::new(&ObjectSpec {
        name: "ball".into(),
        shape: ShapeSpec::Sphere { radius },
        max_acc: 1.0,
        acc_bias: [0.0; 3],
        acc_generators: vec![],
        max_speed: None,
        measurement_error_pos: 0.002,
        measurement_error_vel: 0.01,
        delay: 0.01,
    })
    .unwrap()
}

fn zero_box(n: usize) -> JointBox {
    JointBox::new(&vec![0.0; n], &vec![0.0; n]).unwrap()
}

/// Soundness: over random joint boxes around the ready pose and random balls near the arm, when
/// the rule reports no contact, no sampled configuration of the box touches the ball at any
/// sampled point of its (constant-velocity, exactly measured) motion — exact distances, 2000
/// cases × 20 samples, in both modes (with the separation figure, and the decision only, which
/// skips pairs by their broad-phase boxes). Also: the rule reports contact in a fair share of the
/// cases (not vacuous), and the box-skipping mode differs from the other in few cases.
#[test]
fn no_contact_reported_only_when_disjoint() {
    let robot = fr3::fr3();
    let reach = RobotReach::try_new(&robot, 0.0).unwrap();
    let rule = ObjectRule::new(&robot, &reach, 0.0).unwrap();
    let mut caps = vec![
        Capsule::new_unchecked(Point3::origin(), Point3::origin(), 0.0);
        reach.capsule_count()
    ];
    let mut rng = Lcg(7);
    let (mut contacts, mut clear, mut fast_only_clear) = (0, 0, 0);
    for _ in 0..2000 {
        let w = rng.range(0.0, 0.1);
        let (lo, hi): (Vec<f64>, Vec<f64>) = fr3::Q_READY
            .iter()
            .map(|q| {
                let c = q + rng.range(-0.3, 0.3);
                (c - w, c + w)
            })
            .unzip();
        let qbox = JointBox::new(&lo, &hi).unwrap();
        reach.occupancy_into(&qbox, &mut caps).unwrap();
        let r = rng.range(0.02, 0.1);
        let obj = ball(r);
        let p = [
            rng.range(0.0, 0.8),
            rng.range(-0.5, 0.5),
            rng.range(0.0, 0.9),
        ];
        let v = [
            rng.range(-0.5, 0.5),
            rng.range(-0.5, 0.5),
            rng.range(-0.5, 0.5),
        ];
        let meas = ObjectMeasurement {
            time: 0.0,
            position: p,
            velocity: Some(v),
        };
        let occ = occupancy(&obj, &meas, 0.0, 0.05).unwrap();
        let check = |sep| {
            rule.check(
                &caps,
                &zero_box(7),
                &occ,
                ObjectContact::NoContact,
                || 0.0,
                sep,
            )
        };
        let (out, fast) = (check(true), check(false));
        assert_eq!(out.contact, out.violation.is_some());
        assert_eq!(fast.contact, fast.violation.is_some());
        // The decision-only mode skips pairs by boxes: it may clear more, never less.
        assert!(fast.contact <= out.contact);
        if fast.contact != out.contact {
            fast_only_clear += 1;
        }
        if fast.contact {
            contacts += 1;
            continue;
        }
        clear += 1;
        assert!(out.contact || out.separation > 0.0);
        assert_eq!(fast.separation, f64::INFINITY);
        for _ in 0..20 {
            let q: Vec<f64> = lo.iter().zip(&hi).map(|(a, b)| rng.range(*a, *b)).collect();
            // True state at t_m − δ = −0.01 is the measurement; constant velocity afterwards.
            let tau = rng.range(0.01, 0.06);
            let c = Point3::new(p[0] + v[0] * tau, p[1] + v[1] * tau, p[2] + v[2] * tau);
            for (_, cap) in robot.capsules_world(&q) {
                let d =
                    segment_distance_lower_bound(&c, &c, &cap.p1(), &cap.p2()) - cap.radius() - r;
                assert!(
                    d > -1e-12,
                    "touching at q = {q:?}, ball {c:?} (reported separation {})",
                    out.separation
                );
            }
        }
    }
    assert!(
        contacts > 100 && clear > 100 && fast_only_clear < 20,
        "contacts {contacts}, clear {clear}, cleared only by boxes {fast_only_clear}"
    );
}

/// The constraint semantics on one contact: a ball on the flange.
#[test]
fn constraints_decide_a_contact() {
    let robot = fr3::fr3();
    let reach = RobotReach::try_new(&robot, 0.0).unwrap();
    let rule = ObjectRule::new(&robot, &reach, 0.02).unwrap();
    let mut caps = vec![
        Capsule::new_unchecked(Point3::origin(), Point3::origin(), 0.0);
        reach.capsule_count()
    ];
    let q = fr3::Q_READY;
    reach
        .occupancy_into(&JointBox::new(&q, &q).unwrap(), &mut caps)
        .unwrap();
    let (_, last) = robot.capsules_world(&q).pop().unwrap();
    let p = last.p2();
    let meas = ObjectMeasurement {
        time: 0.0,
        position: [p.x, p.y, p.z],
        velocity: Some([0.0; 3]),
    };
    let occ = occupancy(&ball(0.03), &meas, 0.0, 0.01).unwrap();
    let rest = zero_box(7);
    let slow = JointBox::new(&[-0.01; 7], &[0.01; 7]).unwrap();
    let moving = JointBox::new(&[-0.5; 7], &[0.5; 7]).unwrap();
    let check =
        |dq: &JointBox, c: ObjectContact, e: f64| rule.check(&caps, dq, &occ, c, || e, true);
    // No contact allowed: violated even at rest.
    let out = check(&rest, ObjectContact::NoContact, 0.0);
    assert!(out.contact && out.violation.is_some() && out.separation == 0.0);
    // The first link that may touch it is one of the wrist or hand links.
    assert!(out.violation.unwrap().link + 3 >= robot.links().len());
    // SSM: at rest (within rest_speed 0.02 rad/s) allowed, moving not.
    assert!(check(&rest, ObjectContact::Ssm, 0.0).violation.is_none());
    assert!(check(&slow, ObjectContact::Ssm, 0.0).violation.is_none());
    assert!(check(&moving, ObjectContact::Ssm, 0.0).violation.is_some());
    // PFL: the energy bound against the threshold (equal passes; NaN never does).
    let pfl = ObjectContact::Pfl { threshold: 2.0 };
    assert!(check(&moving, pfl, 2.0).violation.is_none());
    let v = check(&moving, pfl, 2.5).violation.unwrap();
    assert_eq!(v.energy, 2.5);
    assert!(check(&moving, pfl, f64::NAN).violation.is_some());
    // The same ball 1 m away: no contact, a positive separation bound below the true gap.
    let far = ObjectMeasurement {
        position: [p.x + 1.0, p.y + 1.0, p.z],
        ..meas
    };
    let occ_far = occupancy(&ball(0.03), &far, 0.0, 0.01).unwrap();
    let out = rule.check(
        &caps,
        &moving,
        &occ_far,
        ObjectContact::NoContact,
        || 0.0,
        true,
    );
    assert!(
        !out.contact && out.violation.is_none() && out.separation > 0.5 && out.separation < 1.42
    );
    // Decision only: the same verdicts, no separation figure.
    for c in [ObjectContact::NoContact, ObjectContact::Ssm, pfl] {
        for dq in [&rest, &slow, &moving] {
            let a = rule.check(&caps, dq, &occ, c, || 2.5, true);
            let b = rule.check(&caps, dq, &occ, c, || 2.5, false);
            assert_eq!((a.contact, a.violation), (b.contact, b.violation));
        }
    }
    let far = rule.check(
        &caps,
        &moving,
        &occ_far,
        ObjectContact::NoContact,
        || 0.0,
        false,
    );
    assert!(!far.contact && far.separation == f64::INFINITY);
}
