//! Object occupancy (`pacs_reach::object`, claim C4′): soundness against sampled admissible
//! motions of a sphere (30 acceleration pieces of 20 ms each, starts at the edge of the
//! measurement errors, optional speed bound), exact values of the closed form, tightness, and
//! input errors. (The 3-D shapes, biased and zonotope acceleration sets and unknown velocities:
//! the property test `j1_object_occupancy_contains_motion` in pacs-proofs.)

use nalgebra::Point3;
use pacs_models::object::{ObjectModel, ObjectSpec, ShapeSpec};
use pacs_models::shape::Capsule;
use pacs_reach::object::{ObjectMeasurement, occupancy};
use proptest::collection::vec;
use proptest::prelude::*;

const CASES: u32 = 10_000;

/// A sphere of `radius` (a point object, radius 0, gets a 1 µm sphere: points are refused).
fn ball(
    radius: f64,
    a_max: f64,
    max_speed: Option<f64>,
    delay: f64,
    e_p: f64,
    e_v: f64,
) -> ObjectModel {
    ObjectModel::new(&ObjectSpec {
        name: "ball".into(),
        shape: ShapeSpec::Sphere {
            radius: radius.max(1e-6),
        },
        max_acc: a_max,
        acc_bias: [0.0; 3],
        acc_generators: vec![],
        max_speed,
        measurement_error_pos: e_p,
        measurement_error_vel: e_v,
        delay,
    })
    .unwrap()
}

// ---------- dynamic object ----------

#[derive(Debug, Clone)]
struct ObjCase {
    radius: f64,
    a_max: f64,
    delay: f64,
    e_p: f64,
    e_v: f64,
    meas_p: [f64; 3],
    meas_v: [f64; 3],
    t_m: f64,
    dt_a: f64,
    width: f64,
    theta: f64,
    ep_dir: Vec<f64>,
    ep_s: f64,
    ev_dir: Vec<f64>,
    ev_s: f64,
    acc: Vec<(Vec<f64>, f64)>,
    surface: Vec<f64>,
    use_speed: bool,
}

const ACC_PIECE: f64 = 0.02;

fn unit(v: &[f64]) -> [f64; 3] {
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if n < 1e-9 {
        [1.0, 0.0, 0.0]
    } else {
        [v[0] / n, v[1] / n, v[2] / n]
    }
}

fn scale01() -> impl Strategy<Value = f64> {
    prop_oneof![2 => 0.0..=1.0f64, 1 => Just(1.0)]
}

fn obj_case() -> impl Strategy<Value = ObjCase> {
    (
        (
            0.0..0.2f64,
            0.0..6.0f64,
            0.0..0.1f64,
            0.0..0.05f64,
            0.0..0.2f64,
        ),
        (
            vec(-1.0..1.0f64, 3),
            vec(-1.5..1.5f64, 3),
            -10.0..10.0f64,
            0.0..0.4f64,
            0.0..0.1f64,
            0.0..=1.0f64,
        ),
        (
            vec(-1.0..1.0f64, 3),
            scale01(),
            vec(-1.0..1.0f64, 3),
            scale01(),
        ),
        vec((vec(-1.0..1.0f64, 3), scale01()), 30),
        vec(-1.0..1.0f64, 3),
        prop::bool::ANY,
    )
        .prop_map(
            |(
                (radius, a_max, delay, e_p, e_v),
                (mp, mv, t_m, dt_a, width, theta),
                (epd, eps, evd, evs),
                acc,
                surface,
                use_speed,
            )| ObjCase {
                radius,
                a_max,
                delay,
                e_p,
                e_v,
                meas_p: [mp[0], mp[1], mp[2]],
                meas_v: [mv[0], mv[1], mv[2]],
                t_m,
                dt_a,
                width,
                theta,
                ep_dir: epd,
                ep_s: eps,
                ev_dir: evd,
                ev_s: evs,
                acc,
                surface,
                use_speed,
            },
        )
}

/// Centre position at time `t` and the maximal speed over `[t_m − δ, t]`.
fn simulate_object(c: &ObjCase, t: f64) -> ([f64; 3], f64) {
    let shrink = 1.0 - 1e-9; // stay inside the bounds by more than the simulation rounding
    let up = unit(&c.ep_dir);
    let uv = unit(&c.ev_dir);
    let mut p = [0.0; 3];
    let mut v = [0.0; 3];
    for i in 0..3 {
        p[i] = c.meas_p[i] + c.e_p * c.ep_s * shrink * up[i];
        v[i] = c.meas_v[i] + c.e_v * c.ev_s * shrink * uv[i];
    }
    let tau = t - c.t_m + c.delay;
    let speed = |v: &[f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let mut vmax = speed(&v);
    let mut s = 0.0;
    for (dir, mag) in &c.acc {
        if s >= tau {
            break;
        }
        let h = ACC_PIECE.min(tau - s);
        let ua = unit(dir);
        let a = c.a_max * mag * shrink;
        for i in 0..3 {
            p[i] += v[i] * h + 0.5 * a * ua[i] * h * h;
            v[i] += a * ua[i] * h;
        }
        vmax = vmax.max(speed(&v));
        s += ACC_PIECE;
    }
    if s < tau {
        // after the last piece: constant velocity
        for i in 0..3 {
            p[i] += v[i] * (tau - s);
        }
    }
    (p, vmax)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(CASES))]

    /// Every sampled admissible motion (errors, delay, bounded acceleration, optional speed bound
    /// equal to the sampled maximum) keeps every point of the sphere inside the occupancy: a
    /// zero-radius capsule at a sphere point is never reported disjoint.
    #[test]
    fn object_occupancy_contains_sampled_motions(c in obj_case()) {
        let t_a = c.t_m + c.dt_a;
        let t_b = t_a + c.width;
        let t = (t_a + c.theta * (t_b - t_a)).clamp(t_a, t_b);
        // 30 pieces of 20 ms cover τ ≤ 0.6 s = 0.4 + 0.1 + 0.1.
        let (p, vmax) = simulate_object(&c, t);
        let vmax_bound = if c.use_speed { Some(vmax * (1.0 + 1e-9) + 1e-12) } else { None };
        let obj = ball(c.radius, c.a_max, vmax_bound, c.delay, c.e_p, c.e_v);
        let meas = ObjectMeasurement { time: c.t_m, position: c.meas_p, velocity: Some(c.meas_v) };
        let occ = occupancy(&obj, &meas, t_a, t_b).unwrap();
        let su = unit(&c.surface);
        let k = c.radius * (1.0 - 1e-9);
        for q in [p, [p[0] + k * su[0], p[1] + k * su[1], p[2] + k * su[2]]] {
            let probe = Capsule::new(Point3::new(q[0], q[1], q[2]), Point3::new(q[0], q[1], q[2]), 0.0).unwrap();
            prop_assert!(occ.distance_lower_bound(&probe) == 0.0, "sphere point {q:?} outside occupancy (bound {})", occ.distance_lower_bound(&probe));
        }
    }
}

fn capsule(p1: [f64; 3], p2: [f64; 3], r: f64) -> Capsule {
    Capsule::new(Point3::from(p1), Point3::from(p2), r).unwrap()
}

/// Constant velocity, no errors, no acceleration: over τ ∈ [0, 1] s the centre sweeps the segment
/// p + [0, 1]·v exactly — centre p + v/2, one generator v/2, no error box.
#[test]
fn constant_velocity_is_exact() {
    let obj = ball(0.1, 0.0, None, 0.0, 0.0, 0.0);
    let meas = ObjectMeasurement {
        time: 0.0,
        position: [1.0, 2.0, 3.0],
        velocity: Some([1.0, 0.0, 0.0]),
    };
    let occ = occupancy(&obj, &meas, 0.0, 1.0).unwrap();
    // Exact up to the outward rounding of τ_b (1 + 2 ulp).
    let z = occ.zonotope();
    let near = |a: [f64; 3], b: [f64; 3]| (0..3).all(|i| (a[i] - b[i]).abs() <= 1e-15);
    assert!(near(z.center(), [1.5, 2.0, 3.0]), "{:?}", z.center());
    assert!(
        near(z.generators()[0], [0.5, 0.0, 0.0]),
        "{:?}",
        z.generators()
    );
    assert_eq!(z.generators()[1], [0.0, 0.0, 0.0]);
    assert!(near(z.error_box(), [0.0; 3]), "{:?}", z.error_box());
    assert!(
        occ.radius() >= 0.1 && occ.radius() <= 0.1 + 1e-15,
        "{}",
        occ.radius()
    );
    // A capsule 1 m to the side of the swept segment, radius 0.2: 1 − 0.1 − 0.2 = 0.7 m.
    let lb = occ.distance_lower_bound(&capsule([1.5, 3.0, 3.0], [1.5, 3.0, 4.0], 0.2));
    assert!((0.7 - 1e-12..=0.7).contains(&lb), "lb = {lb}");
    // Beyond the end of the sweep (x = 2.0 + 0.1 + 0.3 + 0.1): separated by 0.3 m.
    let lb = occ.distance_lower_bound(&capsule([2.5, 2.0, 3.0], [3.5, 2.0, 3.0], 0.1));
    assert!((0.3 - 1e-12..=0.3).contains(&lb), "lb = {lb}");
    // Touching the swept sphere's end: not disjoint.
    let lb = occ.distance_lower_bound(&capsule([2.1, 2.0, 3.0], [3.0, 2.0, 3.0], 0.0));
    assert_eq!(lb, 0.0);
    // The bounding capsule is the sweep itself (up to rounding).
    let bc = occ.bounding_capsule().unwrap();
    assert!(
        (bc.p1() - Point3::new(1.0, 2.0, 3.0)).norm() < 1e-15,
        "{bc:?}"
    );
    assert!(
        (bc.p2() - Point3::new(2.0, 2.0, 3.0)).norm() < 1e-15,
        "{bc:?}"
    );
    assert!(bc.radius() >= 0.1 && bc.radius() < 0.1 + 1e-14);
}

/// A falling object (acc_bias = gravity) released at rest: z(τ) = −4.905 τ², over [0, 0.2] s in
/// [−0.1962, 0]. The enclosure (τ_m = h = 0.1): centre −(0.005 + 0.0025)·9.81 = −0.073575,
/// generators h·τ_m·g = −0.0981 and h²/4·g = −0.024525 — it contains the fall and overshoots at
/// the top by at most h²|g|/2 = 0.04905 m (the parallelogram around the parabola).
#[test]
fn falling_object_hand_values() {
    let spec = ObjectSpec {
        name: "dropped".into(),
        shape: ShapeSpec::Sphere { radius: 0.05 },
        max_acc: 0.0,
        acc_bias: [0.0, 0.0, -9.81],
        acc_generators: vec![],
        max_speed: None,
        measurement_error_pos: 0.0,
        measurement_error_vel: 0.0,
        delay: 0.0,
    };
    let obj = ObjectModel::new(&spec).unwrap();
    let meas = ObjectMeasurement {
        time: 0.0,
        position: [0.0; 3],
        velocity: Some([0.0; 3]),
    };
    let occ = occupancy(&obj, &meas, 0.0, 0.2).unwrap();
    let z = occ.zonotope();
    let near = |a: f64, b: f64| (a - b).abs() < 1e-12;
    assert!(near(z.center()[2], -0.073575), "{:?}", z.center());
    assert!(near(z.generators()[0][2], -0.0981) && near(z.generators()[1][2], -0.024525));
    let (lo, hi) = z.interval_hull();
    assert!(lo[2] <= -0.1962 && lo[2] > -0.1962 - 1e-12, "{lo:?}");
    assert!(hi[2] >= 0.0 && hi[2] < 0.04906, "{hi:?}");
    assert!(lo[0].abs() < 1e-15 && hi[0].abs() < 1e-15, "{lo:?} {hi:?}");
}

/// Without a measured velocity the speed bound is the velocity's set; without either it is an
/// error. The speed set is a ball of e_p + v_max τ_b around the measured position.
#[test]
fn unknown_velocity_uses_the_speed_bound() {
    let with_speed = ball(0.05, 2.0, Some(1.5), 0.02, 0.01, 0.1);
    let meas = ObjectMeasurement {
        time: 1.0,
        position: [0.0; 3],
        velocity: None,
    };
    let occ = occupancy(&with_speed, &meas, 1.0, 1.1).unwrap();
    // τ_b = 0.12: reach radius e_p + v_max τ_b + a τ_b²/2 + r = 0.01 + 0.18 + 0.0144 + 0.05.
    assert!((occ.radius() - 0.2544).abs() < 1e-12, "{}", occ.radius());
    let (z, r) = occ.speed_set().unwrap();
    assert_eq!(z.center(), [0.0; 3]);
    assert!((r - (0.01 + 0.18 + 0.05)).abs() < 1e-12, "{r}");
    let no_speed = ball(0.05, 2.0, None, 0.02, 0.01, 0.1);
    let e = occupancy(&no_speed, &meas, 1.0, 1.1).unwrap_err();
    assert!(e.to_string().contains("no velocity"), "{e}");
}

/// A measured velocity faster than the speed bound allows (`|v| > v_max + e_v`) contradicts the
/// model and is ignored: the occupancy is the one without a velocity (so the two sets always
/// meet at the measured position). A ball at rest measured at 10 m/s against a 1 m/s bound:
/// trusted, the velocity set (x ≥ 0.25 m after 20 ms of delay plus the interval) and the speed
/// ball (x ≤ 0.08 m) would miss each other, and no capsule would be near the object. At the
/// bound itself (1.1 m/s here) the velocity is used.
#[test]
fn a_velocity_beyond_the_speed_bound_is_ignored() {
    let m = ball(0.05, 2.0, Some(1.0), 0.02, 0.01, 0.1);
    let at = |velocity| ObjectMeasurement {
        time: 1.0,
        position: [0.0; 3],
        velocity,
    };
    let without = occupancy(&m, &at(None), 1.0, 1.1).unwrap();
    // The capsule through the measured position: it touches the object at rest.
    let here = Capsule::new(
        Point3::new(0.0, -1.0, 0.0),
        Point3::new(0.0, 1.0, 0.0),
        0.01,
    )
    .unwrap();
    for v in [[10.0, 0.0, 0.0], [0.0, -1.11, 0.0], [0.8, 0.8, 0.0]] {
        let occ = occupancy(&m, &at(Some(v)), 1.0, 1.1).unwrap();
        assert_eq!(occ.radius(), without.radius(), "{v:?}");
        assert_eq!(
            occ.zonotope().center(),
            without.zonotope().center(),
            "{v:?}"
        );
        assert!(occ.distance_lower_bound(&here) <= 0.0, "{v:?}");
    }
    // Within the bound: the velocity moves the set.
    let occ = occupancy(&m, &at(Some([1.1, 0.0, 0.0])), 1.0, 1.1).unwrap();
    assert!(
        occ.zonotope().center()[0] > 0.05,
        "{:?}",
        occ.zonotope().center()
    );
}

#[test]
fn invalid_queries_are_errors() {
    let obj = ball(0.05, 2.0, None, 0.03, 0.0, 0.0);
    let meas = ObjectMeasurement {
        time: 1.0,
        position: [0.0; 3],
        velocity: Some([0.0; 3]),
    };
    // Before the measured state (t_m − delay = 0.97).
    assert!(occupancy(&obj, &meas, 0.96, 1.0).is_err());
    assert!(occupancy(&obj, &meas, 0.97, 1.0).is_ok());
    assert!(occupancy(&obj, &meas, 1.1, 1.0).is_err());
    assert!(occupancy(&obj, &meas, f64::NAN, 1.0).is_err());
    let bad = ObjectMeasurement {
        position: [f64::INFINITY, 0.0, 0.0],
        ..meas
    };
    assert!(occupancy(&obj, &bad, 1.0, 1.1).is_err());
    // Too large to bound: an error, never an infinite set passed off as a bound.
    let huge = ObjectMeasurement {
        velocity: Some([1e300, 0.0, 0.0]),
        ..meas
    };
    assert!(occupancy(&obj, &huge, 1.0, 1e10).is_err());
}

#[test]
fn invalid_models_are_refused_with_the_field() {
    let base = ObjectSpec {
        name: "o".into(),
        shape: ShapeSpec::Sphere { radius: 0.05 },
        max_acc: 1.0,
        acc_bias: [0.0; 3],
        acc_generators: vec![],
        max_speed: None,
        measurement_error_pos: 0.0,
        measurement_error_vel: 0.0,
        delay: 0.0,
    };
    let err = |s: ObjectSpec| ObjectModel::new(&s).unwrap_err().to_string();
    let e = err(ObjectSpec {
        shape: ShapeSpec::Sphere { radius: 0.0 },
        ..base.clone()
    });
    assert!(e.contains("shape.sphere.radius"), "{e}");
    let e = err(ObjectSpec {
        shape: ShapeSpec::Box {
            half_extents: [0.0; 3],
        },
        ..base.clone()
    });
    assert!(e.contains("no extent"), "{e}");
    let e = err(ObjectSpec {
        max_acc: -1.0,
        ..base.clone()
    });
    assert!(e.contains("max_acc") && e.contains("-1"), "{e}");
    let e = err(ObjectSpec {
        acc_generators: vec![[0.0, 0.0, f64::NAN]],
        ..base.clone()
    });
    assert!(e.contains("acc_generators[0][2]"), "{e}");
    let e = err(ObjectSpec {
        shape: ShapeSpec::Zonotope {
            generators: vec![[0.1, 0.0, 0.0]; 5],
            radius: 0.0,
        },
        ..base.clone()
    });
    assert!(e.contains("shape.zonotope.generators"), "{e}");
    let e = err(ObjectSpec {
        max_speed: Some(0.0),
        ..base
    });
    assert!(e.contains("max_speed"), "{e}");
}

/// One 10 ms window of the built-in ball, 50 ms after a measurement: the occupancy is a few
/// centimetres wider than the ball, not a loose box.
#[test]
fn ball_window_is_tight() {
    let obj = ObjectModel::new(&pacs_models::object::default_ball()).unwrap();
    let meas = ObjectMeasurement {
        time: 0.0,
        position: [0.5, 0.0, 0.04],
        velocity: Some([0.0, 0.5, 0.0]),
    };
    let occ = occupancy(&obj, &meas, 0.05, 0.06).unwrap();
    // τ ∈ [0.08, 0.09]: centre sweeps y ∈ [0.04, 0.045]; radius 0.005 + 0.09·0.02 + 1.5·0.0081 +
    // 0.04 = 0.05895.
    assert!((occ.radius() - 0.05895).abs() < 1e-12, "{}", occ.radius());
    let bc = occ.bounding_capsule().unwrap();
    assert!((bc.p1().y - 0.04).abs() < 1e-12 && (bc.p2().y - 0.045).abs() < 1e-12);
}
