//! Dynamic objects: a sphere whose centre moves as a 3-D double integrator, observed with delay and
//! errors, and its occupancy over a time interval (reachability of [`super::LtiReach`]).

use super::{LtiReach, LtiSystem, ReachError, ReachOptions};
use crate::rounding::{add_down, add_up, mul_up, sub_down, sub_up};
use crate::zonotope::{BallApprox, Zonotope, Zonotope3, ball_zonotope};
use nalgebra::{DMatrix, DVector};
use pacs_models::shape::Capsule;

/// A sphere of radius `radius` (m) whose centre moves as a 3-D double integrator with
/// `‖acceleration‖ ≤ max_acc` (m/s²) and optionally `‖velocity‖ ≤ max_speed` (m/s), observed with
/// delay `delay` (s) and Euclidean position / velocity errors `pos_error` (m), `vel_error` (m/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DynamicObject {
    radius: f64,
    max_acc: f64,
    max_speed: Option<f64>,
    delay: f64,
    pos_error: f64,
    vel_error: f64,
    approx: BallApprox,
}

/// A measurement of a dynamic object stamped `time` (s): the true state at `time − delay` is within
/// the errors of `position` (m) and `velocity` (m/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObjectMeasurement {
    /// Time stamp `t_m` (s).
    pub time: f64,
    /// Measured centre position (m).
    pub position: [f64; 3],
    /// Measured velocity (m/s).
    pub velocity: [f64; 3],
}

impl DynamicObject {
    /// Validate and build (all values finite and ≥ 0); `approx` selects the ball over-approximation.
    pub fn new(
        radius: f64,
        max_acc: f64,
        max_speed: Option<f64>,
        delay: f64,
        pos_error: f64,
        vel_error: f64,
        approx: BallApprox,
    ) -> Result<Self, ReachError> {
        for v in [radius, max_acc, delay, pos_error, vel_error]
            .into_iter()
            .chain(max_speed)
        {
            if !(v.is_finite() && v >= 0.0) {
                return Err(ReachError::Invalid {
                    what: "object parameter",
                    reason: "must be finite and >= 0",
                });
            }
        }
        Ok(Self {
            radius,
            max_acc,
            max_speed,
            delay,
            pos_error,
            vel_error,
            approx,
        })
    }

    /// Occupancy over `[t_a, t_b]` (s) after measurement `meas`: contains every point of the sphere
    /// for every admissible motion consistent with the measurement. Requires `t_m − δ ≤ t_a ≤ t_b`.
    ///
    /// # Soundness
    /// Claim C4′: as stated, for the double-integrator model with the measurement errors and the
    /// delay of the spec. Harness `j1_object_occupancy_contains_motion` (property test: the
    /// occupancy uses the LP-based zonotope code, beyond the model checker); mutant `x13` caught.
    pub fn occupancy(
        &self,
        meas: &ObjectMeasurement,
        t_a: f64,
        t_b: f64,
    ) -> Result<ObjectOccupancy, ReachError> {
        if !(t_a.is_finite() && t_b.is_finite() && meas.time.is_finite() && t_a <= t_b) {
            return Err(ReachError::Invalid {
                what: "time interval",
                reason: "need finite t_a <= t_b",
            });
        }
        // Elapsed time since the true state, enclosed outward.
        let tau_a = add_down(sub_down(t_a, meas.time), self.delay);
        let tau_b = add_up(sub_up(t_b, meas.time), self.delay);
        if t_a - meas.time + self.delay < 0.0 {
            return Err(ReachError::Invalid {
                what: "t_a",
                reason: "before the measured state (t_m - delay)",
            });
        }
        let tau_a = tau_a.max(0.0);
        let sys = LtiSystem::double_integrator_3d();
        let opts = ReachOptions {
            taylor_terms: 2,
            max_order: 12,
        };
        let u = ball_zonotope([0.0; 3], self.max_acc, self.approx)?;
        let bp = ball_zonotope([0.0; 3], self.pos_error, self.approx)?;
        let bv = ball_zonotope([0.0; 3], self.vel_error, self.approx)?;
        let (mp, mv) = (bp.num_generators(), bv.num_generators());
        let mut c = DVector::zeros(6);
        let mut g = DMatrix::zeros(6, mp + mv);
        for i in 0..3 {
            c[i] = meas.position[i];
            c[i + 3] = meas.velocity[i];
            for j in 0..mp {
                g[(i, j)] = bp.generators()[(i, j)];
            }
            for j in 0..mv {
                g[(i + 3, mp + j)] = bv.generators()[(i, j)];
            }
        }
        let x0 = Zonotope::new(c, g)?;
        let xa = if tau_a > 0.0 {
            LtiReach::new(&sys, &u, tau_a, opts)?.point_set(&x0)?
        } else {
            x0
        };
        let r = sub_up(tau_b, tau_a).max(0.0);
        let xi = LtiReach::new(&sys, &u, r, opts)?.first_interval(&xa)?;
        let pos = xi.project(&[0, 1, 2])?;
        let centres = Zonotope3::from_zonotope(&pos)?;
        let speed_ball = match self.max_speed {
            Some(vm) => {
                let rad = add_up(self.pos_error, mul_up(vm, tau_b));
                Some(Zonotope3::new(meas.position, &[], [0.0; 3]).map(|z| (z, rad))?)
            }
            None => None,
        };
        Ok(ObjectOccupancy {
            centres,
            radius: self.radius,
            speed_ball,
            t_a,
            t_b,
        })
    }
}

impl DynamicObject {
    /// Occupancies over the consecutive intervals `[times[k], times[k+1]]` (s, non-decreasing),
    /// each as in [`DynamicObject::occupancy`].
    pub fn occupancy_sequence(
        &self,
        meas: &ObjectMeasurement,
        times: &[f64],
    ) -> Result<Vec<ObjectOccupancy>, ReachError> {
        times
            .windows(2)
            .map(|w| self.occupancy(meas, w[0], w[1]))
            .collect()
    }
}

/// Occupancy of a dynamic object over `[t_a, t_b]`: `(centres ⊕ B(radius)) ∩ (speed ball ⊕ B(radius))`
/// (the second set only with a speed bound). Both sets contain every possible sphere point.
#[derive(Debug, Clone, PartialEq)]
pub struct ObjectOccupancy {
    centres: Zonotope3,
    radius: f64,
    speed_ball: Option<(Zonotope3, f64)>,
    t_a: f64,
    t_b: f64,
}

impl ObjectOccupancy {
    /// Zonotope containing every possible centre position (m).
    pub fn centres(&self) -> &Zonotope3 {
        &self.centres
    }
    /// Sphere radius (m).
    pub fn radius(&self) -> f64 {
        self.radius
    }
    /// `(centre, radius)` of the speed-bound ball of centre positions, if any (m).
    pub fn speed_ball(&self) -> Option<([f64; 3], f64)> {
        self.speed_ball.as_ref().map(|(z, r)| (z.center(), *r))
    }
    /// Time interval `[t_a, t_b]` (s).
    pub fn interval(&self) -> (f64, f64) {
        (self.t_a, self.t_b)
    }
    /// Rigorous lower bound `L`, `0 ≤ L ≤` distance between the occupancy and `capsule` (m).
    pub fn distance_lower_bound(&self, capsule: &Capsule) -> f64 {
        let mut best = self.centres.distance_lower_bound(self.radius, capsule);
        if let Some((ball, r)) = &self.speed_ball {
            best = best.max(ball.distance_lower_bound(add_up(*r, self.radius), capsule));
        }
        best
    }
    /// `true` only if the occupancy and `capsule` are proven disjoint.
    pub fn is_disjoint(&self, capsule: &Capsule) -> bool {
        self.distance_lower_bound(capsule) > 0.0
    }
}
