//! Intended trajectories from waypoints. Default ([`PlanMethod::Spline`]): a time-optimised C² cubic
//! spline (see [`crate::spline`]). Fallback and single targets ([`PlanMethod::Segments`]): per segment
//! a time-synchronized jerk-limited state-to-state motion (rsruckig single target, Ruckig steps 1
//! and 2), with the velocities at intermediate waypoints chosen by a few sweeps of a fixed-point
//! heuristic. Every trajectory is checked by our own exact piecewise limit and continuity checks
//! before it is returned.

use crate::chunk::Waypoints;
use crate::error::TrajectoryError;
use crate::profile::{LIMIT_REL_TOL, Piece};
use crate::spline::SplineSolver;
use crate::trajectory::{EndCondition, JointState, Limits, Trajectory};
use pacs_models::MAX_DOF;
use rsruckig::prelude::*;

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
    pub fn plan(
        &mut self,
        start: &JointState,
        wp: &Waypoints,
    ) -> Result<Trajectory, TrajectoryError> {
        let sweeps = self.config.sweeps;
        let end = self.config.end;
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

    fn plan_with(
        &mut self,
        start: &JointState,
        wp: &Waypoints,
        sweeps: usize,
        end: EndCondition,
    ) -> Result<Trajectory, TrajectoryError> {
        self.validate(start, wp)?;
        // One segment ending at rest: nothing to choose, one rest-to-rest solve.
        let sweeps = if wp.segments() == 1 && end == EndCondition::AtRest {
            0
        } else {
            sweeps
        };
        match self.plan_candidates(start, wp, sweeps, end) {
            Ok(t) => Ok(t),
            Err(_) => {
                std::mem::swap(&mut self.engine, &mut self.fallback);
                let r = self.plan_candidates(start, wp, sweeps, end);
                std::mem::swap(&mut self.engine, &mut self.fallback);
                r
            }
        }
    }

    fn plan_candidates(
        &mut self,
        start: &JointState,
        wp: &Waypoints,
        sweeps: usize,
        end: EndCondition,
    ) -> Result<Trajectory, TrajectoryError> {
        let n = self.limits.dof;
        let h = wp.segments();
        let ncand = sweeps + 1;
        self.cand.resize_with(ncand, Vec::new);
        self.cand_dur.resize_with(ncand, Vec::new);
        self.vel.clear();
        self.vel.resize((h + 1) * n, 0.0);
        self.acc.clear();
        self.acc.resize((h + 1) * n, 0.0);
        self.vel[..n].copy_from_slice(&start.dq[..n]);
        let mut errors: Option<TrajectoryError> = None;
        let mut valid = [false; 64];
        let ncand = ncand.min(64);
        if sweeps == 0 {
            self.solve_candidate(start, wp, 0)?;
            valid[0] = true;
        } else {
            // Candidate 0's durations by closed form (rest-to-rest, synchronized to the slowest
            // joint): the same numbers the solver would give, at no solver cost.
            self.estimate_rest_to_rest(wp, 0);
            let mut base = 0;
            for c in 1..ncand {
                self.choose_velocities(wp, base, end);
                match self.solve_candidate(start, wp, c) {
                    Ok(()) => {
                        valid[c] = true;
                        base = c;
                    }
                    Err(e) => {
                        errors.get_or_insert(e);
                    }
                }
            }
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
            let mut traj = self.assemble(wp, c, end);
            match traj.check(&self.limits) {
                Ok(()) => return Ok(traj),
                Err(e) => last_err = Some(e),
            }
        }
        if sweeps > 0 {
            // Fallback: stop at every waypoint (always solvable from rest-to-rest states).
            for x in &mut self.vel[n..] {
                *x = 0.0;
            }
            for x in &mut self.acc[n..] {
                *x = 0.0;
            }
            self.solve_candidate(start, wp, 0)?;
            let mut traj = self.assemble(wp, 0, end);
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

    /// Closed-form synchronized rest-to-rest segment durations into candidate `c`'s durations.
    fn estimate_rest_to_rest(&mut self, wp: &Waypoints, c: usize) {
        let n = self.limits.dof;
        let l = self.limits;
        let d = &mut self.cand_dur[c];
        d.clear();
        for k in 1..=wp.segments() {
            d.push(
                (0..n)
                    .map(|i| {
                        rest_to_rest_time(
                            (wp.row(k)[i] - wp.row(k - 1)[i]).abs(),
                            l.v[i],
                            l.a[i],
                            l.j[i],
                        )
                    })
                    .fold(0.0, f64::max),
            );
        }
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
        let ga = self.config.acceleration_gain;
        for k in 1..h {
            for i in 0..n {
                let v_prev = self.vel[(k - 1) * n + i];
                let a = ga * (self.vel[(k + 1) * n + i] - v_prev) / (dur[k - 1] + dur[k]);
                let amax = 0.9 * self.limits.a[i];
                let mut a = a.clamp(-amax, amax);
                // Keep the target state reachable within the velocity limit: |v + a|a|/(2j)| ≤ v_max.
                let v = self.vel[k * n + i];
                if (v + a * a.abs() / (2.0 * self.limits.j[i])).abs() > 0.99 * self.limits.v[i] {
                    a = 0.0;
                }
                self.acc[k * n + i] = a;
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
        let exact = c == 0
            || (self.vel[n..].iter().all(|&v| v == 0.0) && self.acc[n..].iter().all(|&a| a == 0.0));
        let mut profs = std::mem::take(&mut self.cand[c]);
        let mut durs = std::mem::take(&mut self.cand_dur[c]);
        profs.clear();
        durs.clear();
        let mut result = Ok(());
        let mut cur = [[0.0; MAX_DOF]; 3];
        let mut tgt = [[0.0; MAX_DOF]; 3];
        for k in 1..=h {
            for i in 0..n {
                if k == 1 {
                    cur[0][i] = start.q[i];
                    cur[1][i] = start.dq[i];
                    cur[2][i] = start.ddq[i];
                } else {
                    cur[0][i] = wp.row(k - 1)[i];
                    cur[1][i] = self.vel[(k - 1) * n + i];
                    cur[2][i] = self.acc[(k - 1) * n + i];
                }
                tgt[0][i] = wp.row(k)[i];
                tgt[1][i] = self.vel[k * n + i];
                tgt[2][i] = self.acc[k * n + i];
            }
            // Rest-to-rest (candidate 0) uses the near-exact solver; candidates with waypoint
            // velocities use the larger margin, whose room the exactness correction needs.
            let engine = if exact {
                &mut self.engine
            } else {
                &mut self.fallback
            };
            let r = match engine {
                SegmentSolver::Seven(e) => e.solve(n, &cur, &tgt, &mut profs),
                SegmentSolver::Dyn(e) => e.solve(n, &cur, &tgt, &mut profs),
            };
            match r {
                Ok(d) => durs.push(d),
                Err(e) => {
                    result = Err(TrajectoryError::Solver {
                        segment: k,
                        message: e.to_string(),
                    });
                    break;
                }
            }
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
                let target = [wp.row(k + 1)[i], p.vf, p.af];
                push_corrected(p, seg_start, durs[k], target, self.limits.j[i], &mut pieces);
                seg_start = times[k];
            }
            // Terminal piece: exactly at the last waypoint with its target velocity.
            let v_end = if end == EndCondition::AtRest {
                0.0
            } else {
                profs[(h - 1) * n + i].vf
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

/// The segment solver: rsruckig single target with stack storage for 7 joints, heap otherwise.
enum SegmentSolver {
    Seven(Box<RuckigSolver<7>>),
    Dyn(Box<RuckigSolver<0>>),
}

struct RuckigSolver<const N: usize> {
    otg: Ruckig<N, ThrowErrorHandler>,
    input: InputParameter<N>,
    out: rsruckig::trajectory::Trajectory<N>,
}

impl<const N: usize> RuckigSolver<N> {
    fn new(l: &Limits, margin: f64) -> Self {
        let dofs = if N == 0 { Some(l.dof) } else { None };
        let mut input = InputParameter::<N>::new(dofs);
        for i in 0..l.dof {
            input.max_velocity[i] = l.v[i] * (1.0 - margin);
            input.max_acceleration[i] = l.a[i] * (1.0 - margin);
            input.max_jerk[i] = l.j[i] * (1.0 - margin);
        }
        Self {
            otg: Ruckig::<N, ThrowErrorHandler>::new(dofs, 0.001),
            input,
            out: rsruckig::trajectory::Trajectory::<N>::new(dofs),
        }
    }

    /// Time-synchronized jerk-limited motion from `cur` to `tgt` ((q, q̇, q̈) per joint); pushes
    /// one profile per joint and returns the duration (s).
    fn solve(
        &mut self,
        n: usize,
        cur: &[[f64; MAX_DOF]; 3],
        tgt: &[[f64; MAX_DOF]; 3],
        out: &mut Vec<Profile>,
    ) -> Result<f64, RuckigError> {
        for i in 0..n {
            self.input.current_position[i] = cur[0][i];
            self.input.current_velocity[i] = cur[1][i];
            self.input.current_acceleration[i] = cur[2][i];
            self.input.target_position[i] = tgt[0][i];
            self.input.target_velocity[i] = tgt[1][i];
            self.input.target_acceleration[i] = tgt[2][i];
        }
        self.otg.calculate(&self.input, &mut self.out)?;
        let ps = &self.out.profiles[0];
        for i in 0..n {
            out.push(ps[i]);
        }
        Ok(self.out.duration)
    }
}

/// Relative margin below the limits given to the segment solver, room for the exactness
/// correction of [`push_corrected`].
const SOLVER_MARGIN: f64 = 1e-6;
/// Margin of the solver for candidates with waypoint velocities (durations grow by less than
/// this fraction).
const FALLBACK_MARGIN: f64 = 1e-4;

/// Append the pieces of one segment profile, with the phase jerks corrected (minimum-norm) so
/// that re-integration from the profile's start state ends exactly at `target` (q, q̇, q̈): the
/// solver ends within ~1e-8 rad of its target, we need the waypoint within 1e-9. The correction
/// is tiny (≈ error/T³ in jerk), weighted away from phases whose jerk is at the limit, and the
/// result is re-checked against the limits by the caller.
fn push_corrected(
    p: &Profile,
    t0: f64,
    dur: f64,
    target: [f64; 3],
    j_max: f64,
    out: &mut Vec<Piece>,
) {
    // Phases: (duration, jerk).
    let mut ph = [(0.0f64, 0.0f64); 10];
    let mut m = 0;
    let (q0, v0, a0) = if p.brake.duration > 0.0 {
        (p.brake.p[0], p.brake.v[0], p.brake.a[0])
    } else {
        (p.p[0], p.v[0], p.a[0])
    };
    if p.brake.duration > 0.0 {
        for b in 0..2 {
            if p.brake.t[b] > 0.0 {
                ph[m] = (p.brake.t[b], p.brake.j[b]);
                m += 1;
            }
        }
    }
    let mut total = 0.0;
    for b in 0..m {
        total += ph[b].0;
    }
    for k in 0..7 {
        if p.t[k] > 0.0 {
            ph[m] = (p.t[k], p.j[k]);
            m += 1;
            total += p.t[k];
        }
    }
    if total < dur - 1e-12 {
        ph[m] = (dur - total, 0.0);
        m += 1;
    }
    let integrate = |ph: &[(f64, f64)]| {
        let (mut q, mut v, mut a) = (q0, v0, a0);
        for &(t, j) in ph {
            q += t * (v + t * (0.5 * a + t * j / 6.0));
            v += t * (a + 0.5 * t * j);
            a += t * j;
        }
        (q, v, a)
    };
    // Sensitivities of the end state to each phase jerk.
    let mut sens = [[0.0f64; 3]; 10];
    let mut w = [1.0f64; 10];
    let mut rest = dur.max(total);
    for k in 0..m {
        let t = ph[k].0;
        rest -= t;
        let r = rest.max(0.0);
        sens[k] = [
            t * t * t / 6.0 + t * t * r / 2.0 + t * r * r / 2.0,
            t * t / 2.0 + t * r,
            t,
        ];
        if ph[k].1.abs() > 0.9 * j_max {
            w[k] = 1e-6;
        }
    }
    // Weighted minimum-norm correction with iterative refinement; uniform weights after 3 rounds.
    for round in 0..6 {
        let (qe, ve, ae) = integrate(&ph[..m]);
        let e = [target[0] - qe, target[1] - ve, target[2] - ae];
        if m == 0 || (e[0].abs() <= 1e-13 && e[1].abs() <= 1e-13 && e[2].abs() <= 1e-12) {
            break;
        }
        if round == 3 {
            w = [1.0; 10];
        }
        let mut g = [[0.0f64; 3]; 3];
        for (s, wk) in sens[..m].iter().zip(&w) {
            for r in 0..3 {
                for c in 0..3 {
                    g[r][c] += wk * s[r] * s[c];
                }
            }
        }
        let tr = g[0][0] + g[1][1] + g[2][2];
        for (r, row) in g.iter_mut().enumerate() {
            row[r] += 1e-14 * tr + f64::MIN_POSITIVE;
        }
        match solve3(&g, &e) {
            Some(y) => {
                for k in 0..m {
                    ph[k].1 += w[k] * (sens[k][0] * y[0] + sens[k][1] * y[1] + sens[k][2] * y[2]);
                }
            }
            None => break,
        }
    }
    let (mut q, mut v, mut a) = (q0, v0, a0);
    let mut t = t0;
    for &(d, j) in &ph[..m] {
        out.push(Piece { t, q, v, a, j });
        q += d * (v + d * (0.5 * a + d * j / 6.0));
        v += d * (a + 0.5 * d * j);
        a += d * j;
        t += d;
    }
}

/// Solve a 3×3 linear system by Cramer's rule (None if singular).
fn solve3(g: &[[f64; 3]; 3], e: &[f64; 3]) -> Option<[f64; 3]> {
    let det = |m: &[[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det(g);
    if d == 0.0 || !d.is_finite() {
        return None;
    }
    let mut y = [0.0; 3];
    for (c, yc) in y.iter_mut().enumerate() {
        let mut m = *g;
        for r in 0..3 {
            m[r][c] = e[r];
        }
        *yc = det(&m) / d;
    }
    Some(y)
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
