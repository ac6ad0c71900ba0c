//! (j) Dynamic objects (claim C4′): the object occupancy (`pacs_reach::object::occupancy`)
//! contains every point of the object for every admissible motion consistent with the
//! measurement.
//!
//! Admissible motion (`pacs_models::object`): at `t_m − delay` the reference point is within
//! `pos_error` of the measured position and its velocity within `vel_error` of the measured one
//! (or anywhere within the speed bound when no velocity is measured); afterwards its acceleration
//! stays in `U = acc_bias ⊕ G_u ⊕ B(max_acc)` (here piecewise constant in two pieces, each drawn
//! biased to the boundary of `U`: bang-bang) and, with a speed bound, its speed within
//! `max_speed`. Shapes: sphere, capsule, box and general zonotope, the point drawn biased to the
//! shape's boundary. The occupancy over `[t_a, t_b]` must then not be proven disjoint from a
//! capsule of radius 1e-9 around the true point at any `t ∈ [t_a, t_b]`, and its bounding
//! capsule must contain the point.
//!
//! Property test (`j1`): the distance test runs a GJK iteration and square roots, beyond a model
//! checker. Its parts are harnessed: `j1_object_time_and_balls` (the elapsed-time range and the
//! ball radii, a Kani proof beside `pacs_reach::object`; mutant `x13` caught), `j2` (the
//! time-interval enclosure, beside `pacs_reach::object`, with its Kani splits), `b4` (zonotope ⊕
//! ball vs capsule).

#[cfg(test)]
mod twin {
    use crate::Source;
    use nalgebra::Point3;
    use pacs_models::Capsule;
    use pacs_models::object::{ObjectModel, ObjectSpec, ShapeSpec};
    use pacs_reach::object::{ObjectMeasurement, occupancy};

    fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
        [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
    }
    fn scale(a: [f64; 3], k: f64) -> [f64; 3] {
        [a[0] * k, a[1] * k, a[2] * k]
    }
    fn norm(a: [f64; 3]) -> f64 {
        (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
    }

    /// A coefficient in [−1, 1], often ±1 (a vertex: bang-bang or the shape's corner).
    fn coefficient<S: Source>(s: &mut S) -> f64 {
        match s.index(3) {
            0 => 1.0,
            1 => -1.0,
            _ => s.f64_in(-1.0, 1.0),
        }
    }

    /// A point of `Σ ξ_k g_k ⊕ B(r)` (shrunk by 1e-9 relative: the generator's own rounding).
    fn zonotope_point<S: Source>(s: &mut S, gens: &[[f64; 3]], r: f64) -> [f64; 3] {
        let mut p = s.in_ball(r);
        for g in gens {
            p = add(p, scale(*g, coefficient(s) * (1.0 - 1e-9)));
        }
        p
    }

    fn shape<S: Source>(s: &mut S) -> ShapeSpec {
        match s.index(4) {
            0 => ShapeSpec::Sphere {
                radius: s.f64_in(0.01, 0.2),
            },
            1 => ShapeSpec::Capsule {
                half_axis: s.vec3(-0.2, 0.2),
                radius: s.f64_in(0.0, 0.1),
            },
            2 => ShapeSpec::Box {
                half_extents: [s.f64_in(0.01, 0.3), s.f64_in(0.0, 0.3), s.f64_in(0.0, 0.3)],
            },
            _ => ShapeSpec::Zonotope {
                generators: (0..1 + s.index(4)).map(|_| s.vec3(-0.2, 0.2)).collect(),
                radius: s.f64_in(0.0, 0.05),
            },
        }
    }

    fn object_occupancy<S: Source>(s: &mut S) {
        let max_speed = if s.bool() {
            Some(s.f64_in(0.1, 3.0))
        } else {
            None
        };
        let spec = ObjectSpec {
            name: "o".into(),
            shape: shape(s),
            max_acc: s.f64_in(0.0, 5.0),
            acc_bias: if s.bool() {
                s.vec3(-10.0, 10.0)
            } else {
                [0.0; 3]
            },
            acc_generators: (0..s.index(3)).map(|_| s.vec3(-3.0, 3.0)).collect(),
            max_speed,
            measurement_error_pos: s.f64_in(0.0, 0.05),
            measurement_error_vel: s.f64_in(0.0, 0.3),
            delay: s.f64_in(0.0, 0.1),
        };
        let Ok(model) = ObjectModel::new(&spec) else {
            s.assume(false);
            return;
        };
        let velocity = if max_speed.is_some() && s.bool() {
            None
        } else {
            Some(s.vec3(-1.0, 1.0))
        };
        let meas = ObjectMeasurement {
            time: s.f64_in(0.0, 10.0),
            position: s.vec3(-2.0, 2.0),
            velocity,
        };
        let delay = spec.delay;
        let t_a = s.f64_in(meas.time - delay, meas.time + 0.3);
        // The occupancy's own precondition, as it evaluates it (rounding can put t_a an ulp early).
        if !s.assume(t_a - meas.time + delay >= 0.0) {
            return;
        }
        let t_b = t_a + s.f64_in(0.0, 0.3);
        let t = s.f64_in(t_a, t_b);
        // The true motion, over the elapsed time (rounded down: never more than admissible).
        let elapsed = ((t - meas.time) + delay).max(0.0) * (1.0 - 1e-12);
        let p0 = add(meas.position, s.in_ball(spec.measurement_error_pos));
        let v0 = match velocity {
            Some(v) => add(v, s.in_ball(spec.measurement_error_vel)),
            None => s.in_ball(max_speed.unwrap_or(0.0)),
        };
        let mut input = || {
            add(
                spec.acc_bias,
                zonotope_point(s, &spec.acc_generators, spec.max_acc),
            )
        };
        let (a1, a2) = (input(), input());
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
        let point = add(
            p,
            zonotope_point(s, model.shape_generators(), model.shape_radius()),
        );
        let occ = occupancy(&model, &meas, t_a, t_b).expect("valid interval");
        // A capsule containing the true point (radius well above the generator's rounding).
        let cap = Capsule::new_unchecked(Point3::from(point), Point3::from(point), 1e-9);
        assert!(
            occ.distance_lower_bound(&cap) == 0.0,
            "object point {point:?} at t={t} (elapsed {elapsed}) outside the occupancy over \
             [{t_a}, {t_b}] of {spec:?} measured {meas:?}: bound {}",
            occ.distance_lower_bound(&cap)
        );
        let bc = occ.bounding_capsule().expect("finite");
        // Inside up to the generator's rounding (1e-9 m).
        let grown = Capsule::new(bc.p1(), bc.p2(), bc.radius() + 1e-9).expect("finite");
        assert!(
            pacs_reach::geometry::capsule_contains_point(&grown, &Point3::from(point)),
            "bounding capsule {bc:?} misses {point:?}"
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
