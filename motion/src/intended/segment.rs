//! The segment solver (rsruckig single target, time-synchronized and jerk-limited) and the
//! exactness correction of its profiles into trajectory pieces.

use crate::profile::Piece;
use crate::trajectory::Limits;
use pacs_models::MAX_DOF;
use rsruckig::prelude::*;

/// The segment solver: rsruckig single target with stack storage for 7 joints, heap otherwise.
pub(super) enum SegmentSolver {
    Seven(Box<RuckigSolver<7>>),
    Dyn(Box<RuckigSolver<0>>),
}

pub(super) struct RuckigSolver<const N: usize> {
    otg: Ruckig<N, ThrowErrorHandler>,
    input: InputParameter<N>,
    out: rsruckig::trajectory::Trajectory<N>,
}

impl<const N: usize> RuckigSolver<N> {
    pub(super) fn new(l: &Limits, margin: f64) -> Self {
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
    pub(super) fn solve(
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
pub(super) const SOLVER_MARGIN: f64 = 1e-6;
/// Margin of the solver for candidates with waypoint velocities (durations grow by less than
/// this fraction).
pub(super) const FALLBACK_MARGIN: f64 = 1e-4;

/// Append the pieces of one segment profile, with the phase jerks corrected (minimum-norm) so
/// that re-integration from the profile's start state ends exactly at `target` (q, q̇, q̈): the
/// solver ends within ~1e-8 rad of its target, we need the waypoint within 1e-9. The correction
/// is tiny (≈ error/T³ in jerk), weighted away from phases whose jerk is at the limit, and the
/// result is re-checked against the limits by the caller.
pub(super) fn push_corrected(
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
