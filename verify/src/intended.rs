//! Intended trajectories from waypoints: per segment a time-synchronized jerk-limited
//! state-to-state motion (rsruckig single target, Ruckig steps 1 and 2), with the velocities at
//! intermediate waypoints chosen by a few sweeps of a fixed-point heuristic, every candidate
//! checked by our own exact piecewise limit and continuity checks before it is returned.

use crate::chunk::Waypoints;
use crate::error::TrajectoryError;
use crate::profile::{LIMIT_REL_TOL, Piece};
use crate::trajectory::{EndCondition, JointState, Limits, Trajectory};
use pacs_models::MAX_DOF;
use rsruckig::prelude::*;

/// Planner settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlannerConfig {
    /// How the trajectory ends at q̂_h.
    pub end: EndCondition,
    /// Number of waypoint-velocity refinement sweeps after the rest-to-rest start (0: single-action-like).
    pub sweeps: usize,
    /// Intermediate waypoint velocities: fraction of the neighbouring segments' mean velocity.
    pub velocity_gain: f64,
}

impl Default for PlannerConfig {
    fn default() -> Self {
        Self {
            end: EndCondition::AtRest,
            sweeps: 3,
            velocity_gain: 1.0,
        }
    }
}

/// Reusable planner (holds the segment solver and scratch buffers; reuse it across chunks).
pub struct Planner {
    limits: Limits,
    config: PlannerConfig,
    otg: Ruckig<0, ThrowErrorHandler>,
    input: InputParameter<0>,
    out: rsruckig::trajectory::Trajectory<0>,
    /// Candidate profiles: [candidate][segment][joint].
    cand: Vec<Vec<Profile>>,
    cand_dur: Vec<Vec<f64>>,
    vel: Vec<f64>,
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
        let mut input = InputParameter::<0>::new(Some(n));
        for i in 0..n {
            input.max_velocity[i] = limits.v[i];
            input.max_acceleration[i] = limits.a[i];
            input.max_jerk[i] = limits.j[i];
        }
        Self {
            limits,
            config,
            otg: Ruckig::<0, ThrowErrorHandler>::new(Some(n), 0.001),
            input,
            out: rsruckig::trajectory::Trajectory::<0>::new(Some(n)),
            cand: Vec::new(),
            cand_dur: Vec::new(),
            vel: Vec::new(),
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
    pub fn plan(
        &mut self,
        start: &JointState,
        wp: &Waypoints,
    ) -> Result<Trajectory, TrajectoryError> {
        let sweeps = self.config.sweeps;
        self.plan_with(start, wp, sweeps, self.config.end)
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

    fn plan_with(
        &mut self,
        start: &JointState,
        wp: &Waypoints,
        sweeps: usize,
        end: EndCondition,
    ) -> Result<Trajectory, TrajectoryError> {
        self.validate(start, wp)?;
        let n = self.limits.dof;
        let h = wp.segments();
        let ncand = sweeps + 1;
        self.cand.resize_with(ncand, Vec::new);
        self.cand_dur.resize_with(ncand, Vec::new);
        self.vel.clear();
        self.vel.resize((h + 1) * n, 0.0);
        let mut errors: Option<TrajectoryError> = None;
        let mut valid = [false; 64];
        for c in 0..ncand.min(64) {
            if c > 0 {
                self.choose_velocities(wp, c - 1, end);
            }
            match self.solve_candidate(start, wp, c) {
                Ok(()) => valid[c] = true,
                Err(e) => {
                    if c == 0 {
                        return Err(e);
                    }
                    errors.get_or_insert(e);
                }
            }
            // Later sweeps start from the best so far.
        }
        // Try candidates shortest first; return the first that passes our checks.
        let mut order: [usize; 64] = [0; 64];
        let mut m = 0;
        for (c, ok) in valid.iter().enumerate().take(ncand.min(64)) {
            if *ok {
                order[m] = c;
                m += 1;
            }
        }
        let total = |d: &Vec<f64>| d.iter().sum::<f64>();
        order[..m].sort_by(|&a, &b| total(&self.cand_dur[a]).total_cmp(&total(&self.cand_dur[b])));
        let mut last_err = errors;
        for &c in &order[..m] {
            let traj = self.assemble(wp, c, end);
            match traj.check(&self.limits) {
                Ok(()) => return Ok(traj),
                Err(e) => last_err = Some(e),
            }
        }
        Err(last_err.unwrap_or(TrajectoryError::Infeasible {
            segment: 1,
            joint: 0,
            reason: "no candidate".into(),
        }))
    }

    /// Waypoint velocities for the next candidate from the segment durations of candidate `from`:
    /// the mean velocity over the two neighbouring segments, zero where a joint reverses direction.
    fn choose_velocities(&mut self, wp: &Waypoints, from: usize, end: EndCondition) {
        let n = self.limits.dof;
        let h = wp.segments();
        let dur = &self.cand_dur[from];
        let g = self.config.velocity_gain;
        for k in 1..=h {
            for i in 0..n {
                let d1 = wp.row(k)[i] - wp.row(k - 1)[i];
                let v = if k < h {
                    let d2 = wp.row(k + 1)[i] - wp.row(k)[i];
                    if d1 * d2 <= 0.0 {
                        0.0
                    } else {
                        g * (d1 + d2) / (dur[k - 1] + dur[k])
                    }
                } else {
                    match end {
                        EndCondition::AtRest => 0.0,
                        EndCondition::Moving => g * d1 / dur[k - 1],
                    }
                };
                let vmax = self.limits.v[i] * 0.999;
                self.vel[k * n + i] = v.clamp(-vmax, vmax);
            }
        }
    }

    fn solve_candidate(
        &mut self,
        start: &JointState,
        wp: &Waypoints,
        c: usize,
    ) -> Result<(), TrajectoryError> {
        let n = self.limits.dof;
        let h = wp.segments();
        let mut profs = std::mem::take(&mut self.cand[c]);
        let mut durs = std::mem::take(&mut self.cand_dur[c]);
        profs.clear();
        durs.clear();
        let mut result = Ok(());
        for k in 1..=h {
            for i in 0..n {
                if k == 1 {
                    self.input.current_position[i] = start.q[i];
                    self.input.current_velocity[i] = start.dq[i];
                    self.input.current_acceleration[i] = start.ddq[i];
                } else {
                    self.input.current_position[i] = wp.row(k - 1)[i];
                    self.input.current_velocity[i] = self.vel[(k - 1) * n + i];
                    self.input.current_acceleration[i] = 0.0;
                }
                self.input.target_position[i] = wp.row(k)[i];
                self.input.target_velocity[i] = self.vel[k * n + i];
                self.input.target_acceleration[i] = 0.0;
            }
            match self.otg.calculate(&self.input, &mut self.out) {
                Ok(_) => {}
                Err(e) => {
                    result = Err(TrajectoryError::Solver {
                        segment: k,
                        message: e.to_string(),
                    });
                    break;
                }
            }
            let ps = &self.out.profiles[0];
            for i in 0..n {
                profs.push(ps[i]);
            }
            durs.push(self.out.duration);
        }
        self.cand[c] = profs;
        self.cand_dur[c] = durs;
        result
    }

    fn assemble(&self, wp: &Waypoints, c: usize, end: EndCondition) -> Trajectory {
        let n = self.limits.dof;
        let h = wp.segments();
        let profs = &self.cand[c];
        let durs = &self.cand_dur[c];
        let mut pieces = Vec::with_capacity(n * (h * 8 + 1));
        let mut offsets = [0usize; MAX_DOF + 1];
        let mut times = Vec::with_capacity(h);
        let mut t0 = 0.0;
        for d in durs {
            t0 += d;
            times.push(t0);
        }
        for i in 0..n {
            offsets[i] = pieces.len();
            let mut seg_start = 0.0;
            for k in 0..h {
                let p = &profs[k * n + i];
                let mut off = 0.0;
                if p.brake.duration > 0.0 {
                    for b in 0..2 {
                        if p.brake.t[b] > 0.0 {
                            pieces.push(Piece {
                                t: seg_start + off,
                                q: p.brake.p[b],
                                v: p.brake.v[b],
                                a: p.brake.a[b],
                                j: p.brake.j[b],
                            });
                            off += p.brake.t[b];
                        }
                    }
                    off = p.brake.duration;
                }
                let mut acc = 0.0;
                for ph in 0..7 {
                    if p.t[ph] > 0.0 {
                        pieces.push(Piece {
                            t: seg_start + off + acc,
                            q: p.p[ph],
                            v: p.v[ph],
                            a: p.a[ph],
                            j: p.j[ph],
                        });
                    }
                    acc += p.t[ph];
                }
                if off + acc < durs[k] - 1e-12 {
                    pieces.push(Piece {
                        t: seg_start + off + acc,
                        q: p.p[7],
                        v: p.v[7],
                        a: p.a[7],
                        j: 0.0,
                    });
                }
                seg_start = times[k];
            }
            // Terminal piece: exactly at the last waypoint with its target velocity.
            let v_end = if end == EndCondition::AtRest {
                0.0
            } else {
                self.vel[h * n + i]
            };
            pieces.push(Piece {
                t: seg_start,
                q: wp.row(h)[i],
                v: v_end,
                a: 0.0,
                j: 0.0,
            });
        }
        offsets[n] = pieces.len();
        Trajectory::from_parts(n, pieces, offsets, t0, times, end)
    }
}
