//! Intended trajectories from waypoints. Default ([`PlanMethod::Spline`]): a time-optimised C² cubic
//! spline (see [`crate::spline`]). Fallback and single targets ([`PlanMethod::Segments`]): per segment
//! a time-synchronized jerk-limited state-to-state motion (rsruckig single target, Ruckig steps 1
//! and 2), with the velocities at intermediate waypoints chosen by a few sweeps of a fixed-point
//! heuristic. Every trajectory is checked by our own exact piecewise limit and continuity checks
//! before it is returned.

mod candidates;
mod segment;

use crate::chunk::Waypoints;
use crate::error::TrajectoryError;
use crate::profile::LIMIT_REL_TOL;
use crate::spline::SplineSolver;
use crate::trajectory::{EndCondition, JointState, Limits, Trajectory};
use rsruckig::prelude::*;
use segment::{FALLBACK_MARGIN, RuckigSolver, SOLVER_MARGIN, SegmentSolver};

/// How the intended trajectory through several waypoints is computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PlanMethod {
    /// Time-optimised C² cubic spline (one constant-jerk piece per segment; see [`crate::spline`]),
    /// falling back to [`PlanMethod::Segments`] if it fails the exact check or is slower than stopping
    /// at every waypoint.
    #[default]
    Spline,
    /// Per-segment synchronized rsruckig solves with waypoint velocities from `sweeps` sweeps.
    Segments,
}

/// Planner settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlannerConfig {
    /// How the trajectory ends at q̂_h.
    pub end: EndCondition,
    /// Spline (default) or per-segment solver.
    pub method: PlanMethod,
    /// Iterations of the spline duration optimiser.
    pub spline_iterations: usize,
    /// Number of waypoint-velocity refinement sweeps after the rest-to-rest start (0: single-action-like).
    pub sweeps: usize,
    /// Intermediate waypoint velocities: fraction of the neighbouring segments' mean velocity.
    pub velocity_gain: f64,
    /// Intermediate waypoint accelerations: fraction of the central-difference acceleration
    /// (0: pass every waypoint with zero acceleration).
    pub acceleration_gain: f64,
}

impl Default for PlannerConfig {
    fn default() -> Self {
        Self {
            end: EndCondition::AtRest,
            method: PlanMethod::Spline,
            spline_iterations: 16,
            sweeps: 3,
            velocity_gain: 1.0,
            acceleration_gain: 0.0,
        }
    }
}

/// A clone is a fresh planner with the same limits and settings (the scratch buffers are not
/// state: every plan starts from them anew).
impl Clone for Planner {
    fn clone(&self) -> Self {
        Planner::new(self.limits, self.config)
    }
}

/// Reusable planner (holds the segment solver and scratch buffers; reuse it across chunks).
pub struct Planner {
    limits: Limits,
    config: PlannerConfig,
    engine: SegmentSolver,
    /// Same solver with a larger margin below the limits: used for candidates with non-zero
    /// waypoint velocities (their solver error is larger), and swapped in for a second attempt
    /// if nothing passes the checks.
    fallback: SegmentSolver,
    /// Candidate profiles: [candidate][segment][joint].
    cand: Vec<Vec<Profile>>,
    cand_dur: Vec<Vec<f64>>,
    vel: Vec<f64>,
    acc: Vec<f64>,
    spline: SplineSolver,
    last: PlanMethod,
}

impl std::fmt::Debug for Planner {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Planner")
            .field("limits", &self.limits)
            .field("config", &self.config)
            .finish()
    }
}

impl Planner {
    /// A planner for the given (planning) limits.
    pub fn new(limits: Limits, config: PlannerConfig) -> Self {
        let n = limits.dof;
        let make = |margin: f64| {
            if n == 7 {
                SegmentSolver::Seven(Box::new(RuckigSolver::new(&limits, margin)))
            } else {
                SegmentSolver::Dyn(Box::new(RuckigSolver::new(&limits, margin)))
            }
        };
        let engine = make(SOLVER_MARGIN);
        let fallback = make(FALLBACK_MARGIN);
        Self {
            limits,
            config,
            engine,
            fallback,
            cand: Vec::new(),
            cand_dur: Vec::new(),
            vel: Vec::new(),
            acc: Vec::new(),
            spline: SplineSolver::default(),
            last: PlanMethod::Segments,
        }
    }

    /// Planning limits.
    pub fn limits(&self) -> &Limits {
        &self.limits
    }
    /// Settings.
    pub fn config(&self) -> &PlannerConfig {
        &self.config
    }
    /// Change the settings (e.g. the end condition) for later plans.
    pub fn set_config(&mut self, c: PlannerConfig) {
        self.config = c;
    }

    /// Intended trajectory from `start` through q̂_1 … q̂_h of `wp` (q̂_0 must equal `start.q`),
    /// passing every waypoint exactly, within every limit at every instant (checked), and
    /// continuous in q, q̇, q̈ with `start`. The shortest of the candidates tried is returned.
    ///
    /// With [`EndCondition::Moving`] the trajectory passes q̂_h moving and then stops along its
    /// stopping tail ([`Trajectory::rest_time`]); the tail is checked like every other piece. If
    /// the tail would leave the limits (e.g. run into a position limit), the chunk is planned to
    /// end at rest instead ([`Trajectory::end`] tells which).
    pub fn plan(
        &mut self,
        start: &JointState,
        wp: &Waypoints,
    ) -> Result<Trajectory, TrajectoryError> {
        let t = self.plan_end(start, wp, self.config.end)?;
        if t.end() != EndCondition::Moving {
            return Ok(t);
        }
        if let Some(mut tailed) = t.with_stop_tail(&self.limits)
            && tailed.check(&self.limits).is_ok()
        {
            return Ok(tailed);
        }
        self.plan_end(start, wp, EndCondition::AtRest)
    }

    fn plan_end(
        &mut self,
        start: &JointState,
        wp: &Waypoints,
        end: EndCondition,
    ) -> Result<Trajectory, TrajectoryError> {
        let sweeps = self.config.sweeps;
        // A single segment ending at rest is one time-optimal single-target solve: no spline.
        if self.config.method == PlanMethod::Spline
            && (wp.segments() >= 2 || end == EndCondition::Moving)
        {
            self.validate(start, wp)?;
            let sp = self
                .spline
                .plan(&self.limits, start, wp, end, self.config.spline_iterations);
            if let Some(mut t) = sp
                && t.check(&self.limits).is_ok()
            {
                // A moving chunk whose spline rings past a waypoint (typically where the chunk
                // slows into a pause of the demonstration) takes the per-segment solver, whose
                // waypoint velocities follow the neighbouring segments and do not overshoot:
                // ringing there makes the robot hunt back and forth around the pause.
                if end == EndCondition::Moving
                    && overshoot(&t, wp) > MOVING_OVERSHOOT
                    && let Ok(s) = self.plan_with(start, wp, sweeps, end)
                {
                    self.last = PlanMethod::Segments;
                    return Ok(s);
                }
                if t.duration() <= self.rest_to_rest_total(wp) {
                    self.last = PlanMethod::Spline;
                    return Ok(t);
                }
                // Slower than stopping at every waypoint (e.g. long moves where a cubic cannot
                // cruise at the velocity limit): take the per-segment solver if it is shorter.
                return Ok(match self.plan_with(start, wp, sweeps, end) {
                    Ok(s) if s.duration() < t.duration() => {
                        self.last = PlanMethod::Segments;
                        s
                    }
                    _ => {
                        self.last = PlanMethod::Spline;
                        t
                    }
                });
            }
        }
        self.last = PlanMethod::Segments;
        self.plan_with(start, wp, sweeps, end)
    }

    /// Which method produced the trajectory of the last successful [`Planner::plan`] call.
    pub fn last_method(&self) -> PlanMethod {
        self.last
    }

    /// Σ_k of the synchronized closed-form rest-to-rest segment durations (s): the single-action
    /// duration for a start at rest.
    fn rest_to_rest_total(&self, wp: &Waypoints) -> f64 {
        let l = &self.limits;
        (1..=wp.segments())
            .map(|k| {
                (0..l.dof)
                    .map(|i| {
                        rest_to_rest_time(
                            (wp.row(k)[i] - wp.row(k - 1)[i]).abs(),
                            l.v[i],
                            l.a[i],
                            l.j[i],
                        )
                    })
                    .fold(0.0, f64::max)
            })
            .sum()
    }

    /// The paper's single-action baseline: each waypoint as its own time-optimal, synchronized
    /// stop-at-target (rest-to-rest) motion.
    pub fn plan_single_action(
        &mut self,
        start: &JointState,
        wp: &Waypoints,
    ) -> Result<Trajectory, TrajectoryError> {
        self.plan_with(start, wp, 0, EndCondition::AtRest)
    }

    fn validate(&self, start: &JointState, wp: &Waypoints) -> Result<(), TrajectoryError> {
        let n = self.limits.dof;
        if wp.dof() != n {
            return Err(TrajectoryError::Length {
                what: "waypoints".into(),
                expected: n,
                found: wp.dof(),
            });
        }
        let l = &self.limits;
        let tol = 1.0 + LIMIT_REL_TOL;
        for i in 0..n {
            for (what, x) in [
                ("state.q", start.q[i]),
                ("state.dq", start.dq[i]),
                ("state.ddq", start.ddq[i]),
            ] {
                if !x.is_finite() {
                    return Err(TrajectoryError::NotFinite {
                        what: what.into(),
                        index: i,
                        value: x,
                    });
                }
            }
            if start.q[i] < l.q_min[i] - 1e-9 || start.q[i] > l.q_max[i] + 1e-9 {
                return Err(TrajectoryError::StartOutsideLimits {
                    joint: i,
                    quantity: "q",
                    value: start.q[i],
                    limit: if start.q[i] < l.q_min[i] {
                        l.q_min[i]
                    } else {
                        l.q_max[i]
                    },
                });
            }
            if start.dq[i].abs() > l.v[i] * tol {
                return Err(TrajectoryError::StartOutsideLimits {
                    joint: i,
                    quantity: "dq",
                    value: start.dq[i],
                    limit: l.v[i],
                });
            }
            if start.ddq[i].abs() > l.a[i] * tol {
                return Err(TrajectoryError::StartOutsideLimits {
                    joint: i,
                    quantity: "ddq",
                    value: start.ddq[i],
                    limit: l.a[i],
                });
            }
            if (wp.row(0)[i] - start.q[i]).abs() > 1e-9 {
                return Err(TrajectoryError::Infeasible {
                    segment: 0,
                    joint: i,
                    reason: format!(
                        "waypoint 0 ({}) differs from the start position ({})",
                        wp.row(0)[i],
                        start.q[i]
                    ),
                });
            }
        }
        Ok(())
    }
}

/// Overshoot (rad) past a waypoint above which a Moving spline plan gives way to the per-segment
/// solver (see [`Planner::plan`]).
pub const MOVING_OVERSHOOT: f64 = 1e-3;

/// Largest distance (rad) by which any joint of `t` leaves the range between the two waypoints of
/// a segment while running it (a spline ringing past a waypoint and coming back).
pub fn overshoot(t: &Trajectory, wp: &Waypoints) -> f64 {
    let times = t.waypoint_times();
    let mut worst = 0.0f64;
    for k in 0..wp.segments() {
        let ta = if k == 0 { 0.0 } else { times[k - 1] };
        let tb = times[k];
        for i in 0..wp.dof() {
            let (a, b) = (wp.row(k)[i], wp.row(k + 1)[i]);
            let r = t.joint_derivs(i, ta, tb).r[0];
            worst = worst.max(a.min(b) - r.lo).max(r.hi - a.max(b));
        }
    }
    worst
}

/// Time-optimal rest-to-rest duration (s) of one joint moving `d` ≥ 0 rad under limits v, a, j.
pub fn rest_to_rest_time(d: f64, v: f64, a: f64, j: f64) -> f64 {
    if d <= 0.0 {
        return 0.0;
    }
    // Without a velocity plateau.
    let t1 = (d / (2.0 * j)).cbrt();
    let (t, v_peak) = if j * t1 <= a {
        (4.0 * t1, j * t1 * t1)
    } else {
        let t1 = a / j;
        let t2 = 0.5 * (-3.0 * t1 + (t1 * t1 + 4.0 * d / a).sqrt());
        (2.0 * (2.0 * t1 + t2), a * (t1 + t2))
    };
    if v_peak <= v {
        return t;
    }
    // With a velocity plateau at v.
    let (t1, t2) = if v * j <= a * a {
        ((v / j).sqrt(), 0.0)
    } else {
        (a / j, v / a - a / j)
    };
    let ta = 2.0 * t1 + t2;
    2.0 * ta + (d - v * ta) / v
}
