//! Soundness of robot occupancies: link points for random configurations in random joint boxes
//! (corners, faces and interior) lie in the occupancy capsules; and the enclosure is not vacuous.

use nalgebra::{Point3, Vector3};
use pacs_models::fr3::fr3;
use pacs_reach::JointBox;
use pacs_reach::geometry::capsule_contains_point;
use pacs_reach::robot::RobotReach;
use proptest::prelude::*;
use proptest::test_runner::{RngAlgorithm, TestRng};

/// A joint box from ordered finite bounds (test inputs).
fn jb(lo: &[f64], hi: &[f64]) -> JointBox {
    JointBox::new(lo, hi).expect("valid joint box")
}

fn rand_in_ball(rng: &mut TestRng, r: f64) -> Vector3<f64> {
    loop {
        let v = Vector3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        if v.norm() <= 1.0 && v.norm() > 0.0 {
            let s = if rng.random_bool(0.5) {
                1.0 / v.norm()
            } else {
                1.0
            };
            return v * (s * r);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 10_000, ..ProptestConfig::default() })]

    #[test]
    fn fr3_link_points_stay_in_box_occupancy(seed in any::<u64>()) {
        let mut rng = TestRng::from_seed(RngAlgorithm::ChaCha, &seed.to_le_bytes().repeat(4));
        let robot = fr3();
        let lim = robot.limits();
        let te = if rng.random_bool(0.5) { 0.0 } else { rng.random_range(0.0..0.02) };
        let reach = RobotReach::new(&robot, te);
        // Box widths from 0 (a point) up to 1 rad; the shield uses small boxes, the CLI any.
        let scale = [0.0, 1e-4, 1e-2, 0.1, 1.0][rng.random_range(0..5)];
        let mut lo = [0.0; 7];
        let mut hi = [0.0; 7];
        for i in 0..7 {
            let a = rng.random_range(lim.q_min()[i]..=lim.q_max()[i]);
            let w = rng.random_range(0.0..=scale);
            lo[i] = a;
            hi[i] = a + w;
        }
        let caps = reach.occupancy(&jb(&lo, &hi)).unwrap();
        for _ in 0..4 {
            let mut q = [0.0; 7];
            for i in 0..7 {
                q[i] = match rng.random_range(0..4) {
                    0 => lo[i],
                    1 => hi[i],
                    _ => rng.random_range(lo[i]..=hi[i]),
                };
            }
            let world = robot.capsules_world(&q);
            for (ci, (_, c)) in world.iter().enumerate() {
                let lambda: f64 = rng.random_range(0.0..=1.0);
                let on_axis = c.p1() + (c.p2() - c.p1()) * lambda;
                let x: Point3<f64> = on_axis + rand_in_ball(&mut rng, c.radius() + te);
                prop_assert!(capsule_contains_point(&caps[ci], &x),
                    "capsule {ci}: q {q:?} in [{lo:?}, {hi:?}]: {x:?} outside {:?}", caps[ci]);
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 10_000, ..ProptestConfig::default() })]

    /// Shield-sized boxes (every half-width ≤ 0.025 rad: one shared chain around the centre),
    /// mostly at corners, where the mean-value and interval forms are both at their limit.
    #[test]
    fn fr3_link_points_stay_in_small_box_occupancy(seed in any::<u64>()) {
        let mut rng = TestRng::from_seed(RngAlgorithm::ChaCha, &seed.to_le_bytes().repeat(4));
        let robot = fr3();
        let lim = robot.limits();
        let reach = RobotReach::new(&robot, 0.0);
        let mut lo = [0.0; 7];
        let mut hi = [0.0; 7];
        for i in 0..7 {
            let c: f64 = rng.random_range(lim.q_min()[i]..=lim.q_max()[i]);
            let d: f64 = if rng.random_bool(0.5) { 0.025 } else { rng.random_range(0.0..=0.025) };
            lo[i] = c - d;
            hi[i] = c + d;
        }
        let caps = reach.occupancy(&jb(&lo, &hi)).unwrap();
        for _ in 0..4 {
            let mut q = [0.0; 7];
            for i in 0..7 {
                q[i] = if rng.random_bool(0.8) {
                    if rng.random_bool(0.5) { lo[i] } else { hi[i] }
                } else {
                    rng.random_range(lo[i]..=hi[i])
                };
            }
            for (ci, (_, c)) in robot.capsules_world(&q).iter().enumerate() {
                for e in [c.p1(), c.p2()] {
                    let x = e + rand_in_ball(&mut rng, c.radius());
                    prop_assert!(capsule_contains_point(&caps[ci], &x),
                        "capsule {ci}: q {q:?} in [{lo:?}, {hi:?}]: {x:?} outside {:?}", caps[ci]);
                }
            }
        }
    }
}

#[test]
fn scratch_reuse_matches_fresh_computation() {
    // Occupancy then energy on the same box with one scratch (frames reused), across a narrow
    // and a wide box, equals the fresh computations.
    use pacs_models::Capsule;
    use pacs_reach::robot::ReachScratch;
    let robot = fr3();
    let reach = RobotReach::new(&robot, 0.003);
    let q = pacs_models::fr3::Q_READY;
    let mut scratch = ReachScratch::default();
    let mut out = vec![
        Capsule::new_unchecked(Point3::origin(), Point3::origin(), 0.0);
        reach.capsule_count()
    ];
    for d in [0.001, 0.3, 0.01, 0.01] {
        let lo: Vec<f64> = q.iter().map(|x| x - d).collect();
        let hi: Vec<f64> = q.iter().map(|x| x + d).collect();
        let vl = [-0.5; 7];
        let vh = [0.4; 7];
        reach
            .occupancy_with(&mut scratch, &jb(&lo, &hi), &mut out)
            .unwrap();
        let fresh = reach.occupancy(&jb(&lo, &hi)).unwrap();
        assert_eq!(out, fresh);
        let mut e1 = [0.0; 8];
        let mut e2 = [0.0; 8];
        reach
            .subchain_energy_bounds_with(&mut scratch, &jb(&lo, &hi), &jb(&vl, &vh), &mut e1)
            .unwrap();
        reach
            .subchain_energy_bounds_into(&jb(&lo, &hi), &jb(&vl, &vh), &mut e2)
            .unwrap();
        assert_eq!(e1, e2);
    }
}

#[test]
fn point_box_is_tight() {
    // A degenerate box gives the link capsules themselves, enlarged by at most 1e-9 m.
    let robot = fr3();
    let reach = RobotReach::new(&robot, 0.0);
    let q = pacs_models::fr3::Q_READY;
    let caps = reach.occupancy(&jb(&q, &q)).unwrap();
    for (i, (_, c)) in robot.capsules_world(&q).iter().enumerate() {
        assert!(caps[i].radius() >= c.radius());
        assert!(
            caps[i].radius() - c.radius() < 1e-9,
            "capsule {i}: {} vs {}",
            caps[i].radius(),
            c.radius()
        );
        assert!((caps[i].p1() - c.p1()).norm() < 1e-12);
    }
}

#[test]
fn small_box_growth_is_close_to_first_order() {
    // For a box of half-width d on joint 1 only, the hand moves by at most d times its distance
    // from the joint-1 axis; the enclosure should not be much larger than that.
    let robot = fr3();
    let reach = RobotReach::new(&robot, 0.0);
    let q = pacs_models::fr3::Q_READY;
    let d = 0.01;
    let mut lo = q;
    let mut hi = q;
    lo[0] -= d;
    hi[0] += d;
    let caps = reach.occupancy(&jb(&lo, &hi)).unwrap();
    let world = robot.capsules_world(&q);
    let hand = world.len() - 1;
    let c = world[hand].1;
    let r_axis = c.p1().coords.xy().norm().max(c.p2().coords.xy().norm());
    let growth = caps[hand].radius() - c.radius();
    assert!(
        growth >= d * r_axis * 0.99,
        "growth {growth} below true excursion {}",
        d * r_axis
    );
    assert!(
        growth <= 1.5 * d * r_axis,
        "growth {growth} far above first order {}",
        d * r_axis
    );
}

#[test]
fn invalid_boxes_are_errors() {
    let robot = fr3();
    let reach = RobotReach::new(&robot, 0.0);
    let q = pacs_models::fr3::Q_READY;
    // A valid box over the wrong number of joints.
    let e = reach.occupancy(&jb(&q[..6], &q[..6])).unwrap_err();
    assert!(e.to_string().contains("expected 7 joints, found 6"), "{e}");
    // Invalid boxes cannot be built at all.
    assert!(JointBox::new(&q[..6], &q).is_err());
    let mut hi = q;
    hi[2] -= 0.1;
    let e = JointBox::new(&q, &hi).unwrap_err();
    assert!(e.to_string().contains("joint 2"), "{e}");
    let mut nan = q;
    nan[0] = f64::NAN;
    assert!(JointBox::new(&nan, &q).is_err());
    assert!(RobotReach::try_new(&robot, -0.1).is_err());
}
