//! (j) Dynamic objects (claim C4′): the object occupancy contains every point of the sphere for
//! every admissible motion consistent with the measurement.
//!
//! Admissible motion (`reach::lti::DynamicObject::occupancy`): at `t_m − delay` the centre is
//! within `pos_error` of the measured position and its velocity within `vel_error` of the
//! measured one; afterwards its acceleration stays within `max_acc` (here piecewise constant in
//! two pieces, each any vector of the ball) and, with a speed bound, its speed within
//! `max_speed`. The occupancy over `[t_a, t_b]` must then not be disjoint from a capsule
//! around any sphere point at any `t ∈ [t_a, t_b]`.
//!
//! Property test only: the occupancy runs the LTI reachability (interval matrix series over
//! 6 × 6 matrices, zonotope order reduction), far beyond a model checker. The pieces it is built
//! from are harnessed: `b4` (zonotope ⊕ ball vs capsule), `a4` (the interval arithmetic of the
//! matrix series).

#[cfg(test)]
mod twin {
    use crate::Source;
    use nalgebra::Point3;
    use pacs_models::Capsule;
    use pacs_reach::lti::{DynamicObject, ObjectMeasurement};
    use pacs_reach::zonotope::BallApprox;

    fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
        [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
    }
    fn scale(a: [f64; 3], k: f64) -> [f64; 3] {
        [a[0] * k, a[1] * k, a[2] * k]
    }
    fn norm(a: [f64; 3]) -> f64 {
        (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
    }

    fn object_occupancy<S: Source>(s: &mut S) {
        let approx = [BallApprox::Box, BallApprox::Seven, BallApprox::Thirteen][s.index(3)];
        let radius = s.f64_in(0.0, 0.2);
        let max_acc = s.f64_in(0.0, 5.0);
        let (pos_error, vel_error, delay) =
            (s.f64_in(0.0, 0.05), s.f64_in(0.0, 0.3), s.f64_in(0.0, 0.1));
        let max_speed = if s.bool() {
            Some(s.f64_in(0.1, 3.0))
        } else {
            None
        };
        let obj = DynamicObject::new(
            radius, max_acc, max_speed, delay, pos_error, vel_error, approx,
        )
        .expect("valid object");
        let meas = ObjectMeasurement {
            time: s.f64_in(0.0, 10.0),
            position: s.vec3(-2.0, 2.0),
            velocity: s.vec3(-1.0, 1.0),
        };
        let t_a = s.f64_in(meas.time - delay, meas.time + 0.3);
        // The occupancy's own precondition, as it evaluates it (rounding can put t_a an ulp early).
        if !s.assume(t_a - meas.time + delay >= 0.0) {
            return;
        }
        let t_b = t_a + s.f64_in(0.0, 0.3);
        let t = s.f64_in(t_a, t_b);
        // The true motion, over the elapsed time T (rounded down: never more than admissible).
        let elapsed = ((t - meas.time) + delay).max(0.0) * (1.0 - 1e-12);
        let p0 = add(meas.position, s.in_ball(pos_error));
        let v0 = add(meas.velocity, s.in_ball(vel_error));
        let (a1, a2) = (s.in_ball(max_acc), s.in_ball(max_acc));
        let t1 = s.f64_in(0.0, elapsed);
        let v1 = add(v0, scale(a1, t1));
        let p1 = add(add(p0, scale(v0, t1)), scale(a1, 0.5 * t1 * t1));
        let t2 = elapsed - t1;
        let v2 = add(v1, scale(a2, t2));
        let p = add(add(p1, scale(v1, t2)), scale(a2, 0.5 * t2 * t2));
        if let Some(vm) = max_speed {
            // Speed is convex along each piece: the ends bound it.
            if !s.assume(norm(v0) <= vm && norm(v1) <= vm && norm(v2) <= vm) {
                return;
            }
        }
        let point = add(p, s.in_ball(radius));
        let occ = obj.occupancy(&meas, t_a, t_b).expect("valid interval");
        // A capsule containing the true point (radius well above the generator's rounding).
        let cap = Capsule::new_unchecked(Point3::from(point), Point3::from(point), 1e-9);
        assert!(
            !occ.is_disjoint(&cap),
            "sphere point {point:?} at t={t} (elapsed {elapsed}) outside the occupancy over \
             [{t_a}, {t_b}] of {obj:?} measured {meas:?}"
        );
    }

    #[test]
    fn j1_object_occupancy_contains_motion() {
        crate::run_cases(
            "j1_object_occupancy_contains_motion",
            crate::DEFAULT_CASES,
            object_occupancy,
        );
    }
}
