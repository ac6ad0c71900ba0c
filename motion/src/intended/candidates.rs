//! The per-segment method: candidates of waypoint velocities and accelerations (a few fixed-point
//! sweeps), one segment solve per waypoint pair, the shortest candidate that passes the checks.

use super::segment::{SegmentSolver, push_corrected};
use super::{Planner, rest_to_rest_time};
use crate::chunk::Waypoints;
use crate::error::TrajectoryError;
use crate::profile::Piece;
use crate::trajectory::{EndCondition, JointState, Trajectory};
use pacs_models::MAX_DOF;

impl Planner {
    pub(super) fn plan_with(
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
