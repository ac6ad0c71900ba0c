//! Conservative capsule tests against an independent oracle (nested ternary search on the convex
//! segment-distance function) and against touching constructions.

use nalgebra::{Point3, Vector3};
use pacs_models::Capsule;
use pacs_reach::geometry::{
    capsule_distance_lower_bound, capsules_disjoint, segment_distance_lower_bound,
    segment_distance_upper_bound,
};
use proptest::prelude::*;

/// Exact-to-~1e-13 segment distance: d(s, t) is convex, so nested ternary search converges.
fn oracle(a0: Point3<f64>, a1: Point3<f64>, b0: Point3<f64>, b1: Point3<f64>) -> f64 {
    let inner = |s: f64| {
        let p = a0 + (a1 - a0) * s;
        let f = |t: f64| (p - (b0 + (b1 - b0) * t)).norm();
        let (mut lo, mut hi) = (0.0, 1.0);
        for _ in 0..100 {
            let m1 = lo + (hi - lo) / 3.0;
            let m2 = hi - (hi - lo) / 3.0;
            if f(m1) <= f(m2) { hi = m2 } else { lo = m1 }
        }
        f(0.5 * (lo + hi)).min(f(0.0)).min(f(1.0))
    };
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..100 {
        let m1 = lo + (hi - lo) / 3.0;
        let m2 = hi - (hi - lo) / 3.0;
        if inner(m1) <= inner(m2) {
            hi = m2
        } else {
            lo = m1
        }
    }
    inner(0.5 * (lo + hi)).min(inner(0.0)).min(inner(1.0))
}

fn pt() -> impl Strategy<Value = Point3<f64>> {
    (-2.0f64..2.0, -2.0f64..2.0, -2.0f64..2.0).prop_map(|(x, y, z)| Point3::new(x, y, z))
}

/// Segments: random, degenerate (a point), or parallel to the other.
fn seg_pair() -> impl Strategy<Value = (Point3<f64>, Point3<f64>, Point3<f64>, Point3<f64>)> {
    (pt(), pt(), pt(), pt(), 0u8..4, -1.0f64..1.0).prop_map(
        |(a0, a1, b0, b1, kind, k)| match kind {
            0 => (a0, a1, b0, b1),
            1 => (a0, a0, b0, b1),
            2 => (a0, a1, b0, b0 + (a1 - a0) * k),
            _ => (
                a0,
                a1,
                a0 + (a1 - a0) * k.abs() + Vector3::new(0.0, 0.0, 1e-9),
                b1,
            ),
        },
    )
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 10_000, ..ProptestConfig::default() })]

    #[test]
    fn lower_bound_never_exceeds_distance_and_is_tight((a0, a1, b0, b1) in seg_pair()) {
        let lb = segment_distance_lower_bound(&a0, &a1, &b0, &b1);
        let ub = segment_distance_upper_bound(&a0, &a1, &b0, &b1);
        let d = oracle(a0, a1, b0, b1);
        // The oracle's own error is ~1e-12 here.
        prop_assert!(lb <= d + 1e-12, "lb {lb} > d {d}");
        prop_assert!(ub >= d - 1e-12, "ub {ub} < d {d}");
        // Tightness (not soundness): near-degenerate 1e-9 m offsets may legitimately give 0.
        prop_assert!(lb >= d - 2e-9, "lb {lb} not tight vs {d}");
        prop_assert!(lb <= ub);
    }

    #[test]
    fn touching_capsules_are_never_disjoint((a0, a1, b0, b1) in seg_pair(), share in 0.0f64..=1.0) {
        // Radii summing to (an upper bound of) the exact distance: the capsules touch or overlap.
        let ub = segment_distance_upper_bound(&a0, &a1, &b0, &b1);
        let ra = ub * share;
        let rb = (ub - ra).max(0.0);
        let a = Capsule::new(a0, a1, ra).unwrap();
        let b = Capsule::new(b0, b1, rb).unwrap();
        prop_assert!(!capsules_disjoint(&a, &b));
        prop_assert_eq!(capsule_distance_lower_bound(&a, &b), 0.0);
    }

    #[test]
    fn shared_point_means_not_disjoint(x in pt(), (a0, a1, b0, b1) in seg_pair()) {
        // Any point x lies in capsules around both segments whose radii reach x.
        let ra = segment_distance_upper_bound(&x, &x, &a0, &a1);
        let rb = segment_distance_upper_bound(&x, &x, &b0, &b1);
        let a = Capsule::new(a0, a1, ra).unwrap();
        let b = Capsule::new(b0, b1, rb).unwrap();
        prop_assert!(!capsules_disjoint(&a, &b));
    }

    #[test]
    fn agrees_with_parry((a0, a1, b0, b1) in seg_pair(), ra in 0.0f64..0.5, rb in 0.0f64..0.5) {
        use parry3d_f64::math::{Pose, Vector};
        use parry3d_f64::shape::Segment;
        let v = |p: Point3<f64>| Vector::new(p.x, p.y, p.z);
        // parry's dedicated segment-segment distance (its generic GJK is only ~1e-5 accurate here).
        let d = parry3d_f64::query::details::distance_segment_segment(
            &Pose::identity(), &Segment::new(v(a0), v(a1)), &Segment::new(v(b0), v(b1)));
        let d = (d - ra - rb).max(0.0);
        let a = Capsule::new(a0, a1, ra).unwrap();
        let b = Capsule::new(b0, b1, rb).unwrap();
        let lb = capsule_distance_lower_bound(&a, &b);
        prop_assert!(lb <= d + 1e-9, "lb {lb} > parry {d}");
        prop_assert!(lb >= d - 2e-9, "lb {lb} much below parry {d}");
    }
}

#[test]
fn hand_computed_distances() {
    let p = |x: f64, y: f64, z: f64| Point3::new(x, y, z);
    // Parallel unit segments 1 m apart.
    let lb = segment_distance_lower_bound(
        &p(0., 0., 0.),
        &p(1., 0., 0.),
        &p(0., 1., 0.),
        &p(1., 1., 0.),
    );
    assert!(lb <= 1.0 && lb > 1.0 - 1e-13, "{lb}");
    // Crossing segments (skew) 0.5 apart in z.
    let lb = segment_distance_lower_bound(
        &p(-1., 0., 0.),
        &p(1., 0., 0.),
        &p(0., -1., 0.5),
        &p(0., 1., 0.5),
    );
    assert!(lb <= 0.5 && lb > 0.5 - 1e-13, "{lb}");
    // Endpoint-to-endpoint: (1,0,0) to (2,1,0): sqrt(2).
    let lb = segment_distance_lower_bound(
        &p(0., 0., 0.),
        &p(1., 0., 0.),
        &p(2., 1., 0.),
        &p(3., 2., 0.),
    );
    assert!(lb <= 2f64.sqrt() && lb > 2f64.sqrt() - 1e-13, "{lb}");
    // Capsules exactly touching: radii sum to the distance -> not disjoint.
    let a = Capsule::new(p(0., 0., 0.), p(1., 0., 0.), 0.25).unwrap();
    let b = Capsule::new(p(0., 1., 0.), p(1., 1., 0.), 0.75).unwrap();
    assert!(!capsules_disjoint(&a, &b));
    let b = Capsule::new(p(0., 1., 0.), p(1., 1., 0.), 0.7499999).unwrap();
    assert!(capsules_disjoint(&a, &b));
}
