//! Intended trajectories as time-optimised C² cubic splines: one constant-jerk piece per segment
//! between consecutive waypoints (the first and last segments are split into two pieces, which
//! gives the two extra degrees of freedom a clamped start (q, q̇, q̈) and end (q̇, q̈ = 0) need),
//! knots at the waypoint times. For given segment durations the spline is the unique solution of a
//! small linear system (the same matrix for every joint); the durations are then optimised by a
//! fixed-point iteration that lengthens segments whose pieces exceed a limit and shortens those
//! with slack, with an exact uniform time scaling (for starts at rest) making every iterate a
//! feasible candidate. The caller checks the assembled trajectory exactly before using it.
//!
//! Moving starts (the next chunk planned from wherever the robot is) do not scale exactly, so the
//! optimiser starts three times and keeps the shortest plan: from the rest-to-rest durations,
//! at the start's own pace, and *shaped*: the later segments at a common multiple of the
//! durations the same waypoints get from rest, the first segment's duration searched on its own
//! (a start that is already moving reaches the next waypoint within the jerk limit only in a
//! narrow window of durations, which the fixed-point update cannot find).
//!
//! Uniform time scaling by λ keeps the spline shape (for a start at rest): velocities scale by
//! 1/λ, accelerations by 1/λ², jerks by 1/λ³, so the smallest admissible λ for given durations
//! follows from the per-piece ratios in closed form.

use crate::chunk::Waypoints;
use crate::intended::{overshoot, rest_to_rest_time};
use crate::profile::Piece;
use crate::trajectory::{EndCondition, JointState, Limits, Trajectory};
use pacs_models::MAX_DOF;

/// Duration factor of the damped update for moving starts: r^MOVING_STEP_EXPONENT, at most ±15 %
/// a step (r: a segment's ratio over the target).
fn damped_factor(r: f64) -> f64 {
    r.powf(MOVING_STEP_EXPONENT)
        .clamp(MOVING_STEP_CLAMP, 1.0 / MOVING_STEP_CLAMP)
}

/// Largest velocity (rad/s) from which a joint at zero acceleration stops within `d` ≥ 0 rad under
/// the acceleration and jerk limits a, j (jerk-limited braking: d = v·√(v/j) below v = a²/j,
/// else v·(v/a + a/j)/2).
fn stopping_velocity(d: f64, a: f64, j: f64) -> f64 {
    if d <= 0.0 {
        return 0.0;
    }
    if d <= a * a * a / (j * j) {
        (d * j.sqrt()).powf(2.0 / 3.0)
    } else {
        let b = a / (2.0 * j);
        a * (-b + (b * b + 2.0 * d / a).sqrt())
    }
}

/// How the duration optimiser starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Init {
    /// Start at rest: rest-to-rest durations, and every iterate scales exactly.
    Rest,
    /// Moving start, from the rest-to-rest durations.
    Cold,
    /// Moving start, from durations at the start's own pace (see `optimise`).
    Warm,
    /// Moving start, from the from-rest durations' shape (see `optimise`).
    Shaped,
    /// Moving start, from equal durations (the policy's clock: every action takes the same
    /// time, so the demonstrated velocity profile keeps its shape), scanned like `Warm`.
    Uniform,
}

/// Knot whose position is an unknown of the linear system (not a waypoint).
const FREE: usize = usize::MAX;

/// Relative slack accepted on the limit ratios of the optimiser (the exact check allows 1e-9).
const RATIO_TOL: f64 = 1e-10;

/// Ratio the optimiser aims at for starts that are not at rest.
const MOVING_TARGET: f64 = 0.97;

/// Exponent of the duration update t_k ← t_k · r_k^e (r_k: segment k's scale-normalised ratio).
const STEP_EXPONENT: f64 = 0.6;

/// Exponent and per-iteration clamp of the duration update for moving starts.
const MOVING_STEP_EXPONENT: f64 = 0.3;
const MOVING_STEP_CLAMP: f64 = 0.85;

/// Shaped moving starts ([`SplineSolver::shaped_search`]): the later segments' from-rest durations
/// are scaled by c = SHAPE_SCALE_STEP^±i, at most SHAPE_SCALES steps from 1 within
/// [SHAPE_SCALE_MIN, SHAPE_SCALE_MAX] (upwards the walk stops when the largest ratio has fallen
/// by less than 1 − STALL_RATIO after STALL_AFTER steps); the first segment's duration is
/// scanned over [FIRST_MIN, FIRST_MAX] times its from-rest duration at FIRST_POINTS geometric
/// points and refined by GOLDEN_STEPS golden-section steps, and within ±20 % at REFINE_POINTS
/// in each of REFINE_ITERATIONS refinement iterations.
const SHAPE_SCALES: usize = 8;
const SHAPE_SCALE_MIN: f64 = 0.6;
const SHAPE_SCALE_MAX: f64 = 1.9;
const SHAPE_SCALE_STEP: f64 = 1.08;
const FIRST_MIN: f64 = 0.02;
const FIRST_MAX: f64 = 3.0;
const FIRST_POINTS: usize = 40;
const REFINE_ITERATIONS: usize = 4;
const REFINE_POINTS: usize = 5;
const GOLDEN_STEPS: usize = 6;
/// Ringing past the waypoints (rad, [`overshoot`]) a shaped plan may have where the other starts
/// found no plan or ring less.
const SHAPED_OVERSHOOT: f64 = 1e-4;
const STALL_AFTER: usize = 2;
const STALL_RATIO: f64 = 0.97;

/// Fraction of the room the predicted actions leave before a pause or turn within which a Moving
/// chunk must be able to stop at its end (see `end_velocity`). The next chunk brakes on a spline
/// whose jerk is constant per segment: its deceleration ramps up and down instead of holding the
/// limit, which on average halves it and doubles the stopping distance of the time-optimal
/// profile that `stopping_velocity` assumes. With the whole room the robot reached
/// the pauses of the simulation's demonstrations too fast: the next chunk could not stop in
/// time, rang 20–90 mrad past the pause and took 0.6–0.9 s; with half the room the tasks without
/// people run 8–18 % faster.
const PAUSE_ROOM_FRACTION: f64 = 0.5;

/// Smallest segment duration the optimiser uses (s): zero-length segments (repeated waypoints)
/// still get a piece.
const MIN_SEGMENT: f64 = 1e-3;

/// Scratch space and state of the spline optimiser (reused across plans; no allocation once warm).
#[derive(Debug, Default, Clone)]
pub(crate) struct SplineSolver {
    /// Segment durations of the current iterate (s).
    seg_t: Vec<f64>,
    /// Best feasible segment durations found so far.
    best_t: Vec<f64>,
    /// Per-segment limit ratios (max over pieces and joints of |j|/J, |a|/A, |v|/V).
    rj: Vec<f64>,
    ra: Vec<f64>,
    rv: Vec<f64>,
    /// Pieces per segment.
    split: Vec<usize>,
    /// Piece durations and the segment of each piece.
    tau: Vec<f64>,
    seg_of: Vec<usize>,
    /// Per knot: waypoint index or [`FREE`]; and the unknown index of a free knot's position.
    knot_wp: Vec<usize>,
    knot_var: Vec<usize>,
    /// Per knot: the unknown index of its acceleration ([`FREE`] for the known M_0 and M_p).
    acc_var: Vec<usize>,
    /// Dense system (row-major), right-hand sides (one column per joint).
    mat: Vec<f64>,
    /// Right-hand sides, row-major with stride `n` (one column per joint).
    rhs: Vec<f64>,
    /// Lower and upper bandwidth of the system (from its sparsity pattern).
    band: (usize, usize),
    /// Cached scale-normalised ratio per segment.
    rs: Vec<f64>,
    /// Knot positions and accelerations per joint.
    y: Vec<[f64; MAX_DOF]>,
    acc: Vec<[f64; MAX_DOF]>,
    /// End velocity per joint.
    v_end: [f64; MAX_DOF],
    /// Duration of the first piece of a two-piece first segment (s; 0: half the segment).
    first_ramp: f64,
    /// Segment durations of the same waypoints planned from rest (the shape of `Init::Shaped`).
    shape: Vec<f64>,
}

impl SplineSolver {
    /// Knot layout for `h` segments: the first and last segment split in two (one segment: three).
    fn layout(&mut self, h: usize) {
        self.split.clear();
        for k in 0..h {
            self.split.push(if h == 1 {
                3
            } else if k == 0 || k == h - 1 {
                2
            } else {
                1
            });
        }
        self.seg_of.clear();
        self.knot_wp.clear();
        self.knot_var.clear();
        self.knot_wp.push(0);
        for k in 0..h {
            for s in 0..self.split[k] {
                self.seg_of.push(k);
                self.knot_wp
                    .push(if s + 1 == self.split[k] { k + 1 } else { FREE });
            }
        }
        // Unknowns interleaved in knot order (free position, then acceleration) so that the
        // system is banded: equation q couples only knots q − 1, q, q + 1.
        let p = self.seg_of.len();
        self.acc_var.clear();
        let mut next = 0;
        for (q, &w) in self.knot_wp.iter().enumerate() {
            if w == FREE {
                self.knot_var.push(next);
                next += 1;
            } else {
                self.knot_var.push(FREE);
            }
            if q > 0 && q < p {
                self.acc_var.push(next);
                next += 1;
            } else {
                self.acc_var.push(FREE);
            }
        }
        debug_assert_eq!(next, p + 1);
        // Equation q couples the unknowns of knots q − 1, q, q + 1.
        let (mut lb, mut ub) = (0usize, 0usize);
        for q in 0..=p {
            for k in q.saturating_sub(1)..=(q + 1).min(p) {
                for v in [self.knot_var[k], self.acc_var[k]] {
                    if v != FREE {
                        lb = lb.max(q.saturating_sub(v));
                        ub = ub.max(v.saturating_sub(q));
                    }
                }
            }
        }
        self.band = (lb, ub);
        self.tau.resize(p, 0.0);
        self.y.resize(p + 1, [0.0; MAX_DOF]);
        self.acc.resize(p + 1, [0.0; MAX_DOF]);
        self.mat.resize((p + 1) * (p + 1), 0.0);
    }

    /// Spline for the segment durations `seg_t`: knot positions and accelerations of every joint.
    /// Returns false if the system is singular.
    fn solve(
        &mut self,
        lim: &Limits,
        n: usize,
        start: &JointState,
        wp: &Waypoints,
        end: EndCondition,
        seg_t: &[f64],
    ) -> bool {
        let p = self.seg_of.len();
        let m = p + 1;
        let h = seg_t.len();
        for (q, t) in self.tau.iter_mut().enumerate() {
            let k = self.seg_of[q];
            *t = seg_t[k] / self.split[k] as f64;
        }
        if self.split[0] == 2 && self.first_ramp > 0.0 {
            self.tau[0] = self.first_ramp.clamp(0.1 * seg_t[0], 0.5 * seg_t[0]);
            self.tau[1] = seg_t[0] - self.tau[0];
        }
        match end {
            EndCondition::AtRest => self.v_end[..n].iter_mut().for_each(|x| *x = 0.0),
            EndCondition::Moving => self.end_velocity(lim, wp, seg_t[h - 1]),
        }
        self.mat.iter_mut().for_each(|x| *x = 0.0);
        self.rhs.clear();
        self.rhs.resize(m * n, 0.0);
        self.rhs[..n].copy_from_slice(&start.dq[..n]);
        self.rhs[p * n..(p + 1) * n].copy_from_slice(&self.v_end[..n]);
        // Velocity at the start of piece q: (y_{q+1} − y_q)/τ − τ(2M_q + M_{q+1})/6;
        // at its end: (y_{q+1} − y_q)/τ + τ(M_q + 2M_{q+1})/6.
        // Row 0: start velocity; row q (1..p−1): continuity at knot q; row p: end velocity.
        for row in 0..=p {
            if row < p {
                // − v_start of piece `row`.
                let t = self.tau[row];
                let s = if row == 0 { 1.0 } else { -1.0 };
                self.coef_y(n, m, start, wp, row, row + 1, s / t);
                self.coef_y(n, m, start, wp, row, row, -s / t);
                self.coef_m(n, m, start, row, row, -s * t / 3.0);
                self.coef_m(n, m, start, row, row + 1, -s * t / 6.0);
            }
            if row > 0 {
                // + v_end of piece `row − 1`.
                let t = self.tau[row - 1];
                self.coef_y(n, m, start, wp, row, row, 1.0 / t);
                self.coef_y(n, m, start, wp, row, row - 1, -1.0 / t);
                self.coef_m(n, m, start, row, row - 1, t / 6.0);
                self.coef_m(n, m, start, row, row, t / 3.0);
            }
        }
        // Banded Gaussian elimination with partial pivoting, all joints' right-hand sides at
        // once; pivoting widens the upper band by the lower bandwidth.
        let (lb, ub) = self.band;
        let ub = ub + lb;
        for c in 0..m {
            let r_end = m.min(c + lb + 1);
            let k_end = m.min(c + ub + 1);
            let mut piv = c;
            let mut best = self.mat[c * m + c].abs();
            for r in c + 1..r_end {
                let v = self.mat[r * m + c].abs();
                if v > best {
                    best = v;
                    piv = r;
                }
            }
            if best == 0.0 || !best.is_finite() {
                return false;
            }
            if piv != c {
                for k in c..k_end {
                    self.mat.swap(c * m + k, piv * m + k);
                }
                for i in 0..n {
                    self.rhs.swap(c * n + i, piv * n + i);
                }
            }
            let d = 1.0 / self.mat[c * m + c];
            for r in c + 1..r_end {
                let f = self.mat[r * m + c] * d;
                if f != 0.0 {
                    for k in c + 1..k_end {
                        self.mat[r * m + k] -= f * self.mat[c * m + k];
                    }
                    let (top, bottom) = self.rhs.split_at_mut(r * n);
                    let rc = &top[c * n..(c + 1) * n];
                    for (x, y) in bottom[..n].iter_mut().zip(rc) {
                        *x -= f * y;
                    }
                }
            }
        }
        for c in (0..m).rev() {
            let d = 1.0 / self.mat[c * m + c];
            let (top, bottom) = self.rhs.split_at_mut((c + 1) * n);
            let x = &mut top[c * n..];
            for k in c + 1..m.min(c + ub + 1) {
                let f = self.mat[c * m + k];
                if f != 0.0 {
                    let xk = &bottom[(k - c - 1) * n..(k - c) * n];
                    for (xi, yi) in x.iter_mut().zip(xk) {
                        *xi -= f * yi;
                    }
                }
            }
            for xi in x.iter_mut() {
                *xi *= d;
            }
        }
        // Knot accelerations and positions from the unknowns.
        for q in 0..=p {
            for i in 0..n {
                self.acc[q][i] = if q == 0 {
                    start.ddq[i]
                } else if q == p {
                    0.0
                } else {
                    self.rhs[self.acc_var[q] * n + i]
                };
                self.y[q][i] = match self.knot_wp[q] {
                    FREE => self.rhs[self.knot_var[q] * n + i],
                    0 => start.q[i],
                    w => wp.row(w)[i],
                };
            }
        }
        self.y.iter().all(|r| r[..n].iter().all(|x| x.is_finite()))
            && self
                .acc
                .iter()
                .all(|r| r[..n].iter().all(|x| x.is_finite()))
    }

    /// Add `c`·y_knot to equation `row` (known positions go to the right-hand side).
    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn coef_y(
        &mut self,
        n: usize,
        m: usize,
        start: &JointState,
        wp: &Waypoints,
        row: usize,
        knot: usize,
        c: f64,
    ) {
        match self.knot_wp[knot] {
            FREE => self.mat[row * m + self.knot_var[knot]] += c,
            w => {
                let q = if w == 0 { &start.q[..n] } else { wp.row(w) };
                for i in 0..n {
                    self.rhs[row * n + i] -= c * q[i];
                }
            }
        }
    }

    /// Add `c`·M_knot to equation `row` (M_0 = start acceleration and M_p = 0 are known).
    #[inline]
    fn coef_m(&mut self, n: usize, m: usize, start: &JointState, row: usize, knot: usize, c: f64) {
        let p = m - 1;
        if knot == 0 {
            for i in 0..n {
                self.rhs[row * n + i] -= c * start.ddq[i];
            }
        } else if knot < p {
            self.mat[row * m + self.acc_var[knot]] += c;
        }
    }

    /// Velocities (rad/s) at q̂_h for a Moving end, into `v_end`, with `t_last` (s) the duration
    /// of the last segment. Without a lookahead: the last segment's mean velocity. With q̂_{h+1}
    /// ([`Waypoints::lookahead`]): the central difference (q̂_{h+1} − q̂_{h−1})/(t_last·(1 + r)),
    /// assuming the pace continues (r = |q̂_{h+1} − q̂_h| / |q̂_h − q̂_{h−1}|, clamped to
    /// [0.25, 4]), so that the next chunk starts close to the velocity it continues with.
    fn end_velocity(&mut self, lim: &Limits, wp: &Waypoints, t_last: f64) {
        let n = lim.dof;
        let h = wp.segments();
        let (a, b) = (wp.row(h - 1), wp.row(h));
        let Some(c) = wp.lookahead() else {
            for i in 0..n {
                self.v_end[i] = (b[i] - a[i]) / t_last;
            }
            return;
        };
        let dist = |x: &[f64], y: &[f64]| {
            x.iter()
                .zip(y)
                .map(|(p, q)| (p - q) * (p - q))
                .sum::<f64>()
                .sqrt()
        };
        let (l0, l1) = (dist(a, b), dist(b, c));
        let r = if l0 > 0.0 {
            (l1 / l0).clamp(0.25, 4.0)
        } else {
            1.0
        };
        for i in 0..n {
            self.v_end[i] = (c[i] - a[i]) / (t_last * (1.0 + r));
        }
        // Where the predicted (not executed) actions pause or turn back, the chunk must not end
        // faster than it could stop within the room they leave along its direction of travel
        // (at the planning limits of the slowest joint; within PAUSE_ROOM_FRACTION of it: the
        // next chunk brakes on a spline, not on a time-optimal profile). Without this cap a chunk ran into a
        // demonstration's pause at the pace before it, the next chunk rang past the pause, and,
        // replaced before it came back, the robot crept on (handover with people: 3 of 10
        // rollouts left the demonstrations).
        let speed = self.v_end[..n].iter().map(|x| x * x).sum::<f64>().sqrt();
        if speed == 0.0 {
            return;
        }
        let mut room = 0.0f64;
        let mut k = 0;
        while let Some(p) = wp.predicted(k) {
            let along: f64 = (0..n).map(|i| (p[i] - b[i]) * self.v_end[i]).sum::<f64>() / speed;
            room = room.max(along);
            k += 1;
        }
        if k == 0 {
            return;
        }
        let (amin, jmin) = (0..n).fold((f64::INFINITY, f64::INFINITY), |(x, y), i| {
            (x.min(lim.a[i]), y.min(lim.j[i]))
        });
        let vmax = stopping_velocity(PAUSE_ROOM_FRACTION * room, amin, jmin);
        if speed > vmax {
            let f = vmax / speed;
            self.v_end[..n].iter_mut().for_each(|x| *x *= f);
        }
    }

    /// Velocity at the start of piece `q` for joint `i`.
    #[inline]
    fn v_start(&self, q: usize, i: usize) -> f64 {
        let t = self.tau[q];
        (self.y[q + 1][i] - self.y[q][i]) / t
            - t * (2.0 * self.acc[q][i] + self.acc[q + 1][i]) / 6.0
    }

    /// Per-segment limit ratios of the current spline (into `rj`, `ra`, `rv`).
    fn ratios(&mut self, n: usize, lim: &Limits, h: usize) {
        self.rj.clear();
        self.rj.resize(h, 0.0);
        self.ra.clear();
        self.ra.resize(h, 0.0);
        self.rv.clear();
        self.rv.resize(h, 0.0);
        for q in 0..self.tau.len() {
            let k = self.seg_of[q];
            let t = self.tau[q];
            let (mut rj, mut ra, mut rv) = (self.rj[k], self.ra[k], self.rv[k]);
            for i in 0..n {
                let (m0, m1) = (self.acc[q][i], self.acc[q + 1][i]);
                let j = (m1 - m0) / t;
                let v0 = self.v_start(q, i);
                let v1 = v0 + 0.5 * t * (m0 + m1);
                let mut vm = v0.abs().max(v1.abs());
                if m0 * m1 < 0.0 {
                    let d = -m0 / j;
                    vm = vm.max((v0 + d * (m0 + 0.5 * j * d)).abs());
                }
                rj = rj.max(j.abs() / lim.j[i]);
                ra = ra.max(m0.abs().max(m1.abs()) / lim.a[i]);
                rv = rv.max(vm / lim.v[i]);
            }
            self.rj[k] = rj;
            self.ra[k] = ra;
            self.rv[k] = rv;
        }
        self.rs.clear();
        for k in 0..h {
            self.rs
                .push(self.rj[k].cbrt().max(self.ra[k].sqrt()).max(self.rv[k]));
        }
    }

    /// Scale-normalised ratio of segment k (> 1: too fast, < 1: slack), as of the last
    /// [`SplineSolver::ratios`].
    #[inline]
    fn seg_ratio(&self, k: usize) -> f64 {
        self.rs[k]
    }

    /// Time-optimised spline trajectory through the waypoints, or `None` if the optimiser found no
    /// spline within the limits (by its own ratios; the caller still runs the exact check).
    ///
    /// From a moving start the first piece is given the time to swing the start acceleration
    /// across the acceleration range at the jerk limit, τ_r = max_i (|q̈_0,i| + a_i)/j_i (clamped
    /// to [0.1, 0.5] of the first segment); if no spline is found, τ_r/2 and 2τ_r are tried.
    pub(crate) fn plan(
        &mut self,
        lim: &Limits,
        start: &JointState,
        wp: &Waypoints,
        end: EndCondition,
        iterations: usize,
    ) -> Option<Trajectory> {
        let n = lim.dof;
        let h = wp.segments();
        if h == 0 {
            return None;
        }
        self.layout(h);
        if start.is_at_rest(n) {
            self.first_ramp = 0.0;
            return self.optimise(lim, start, wp, end, iterations, Init::Rest);
        }
        let ramp = (0..n)
            .map(|i| (start.ddq[i].abs() + lim.a[i]) / lim.j[i])
            .fold(0.0, f64::max);
        let mut best: Option<Trajectory> = None;
        // The shape of the third start: the same waypoints planned from rest here.
        {
            self.first_ramp = 0.0;
            let rest = JointState::at_rest(&start.q[..n]);
            if self
                .optimise(lim, &rest, wp, end, iterations, Init::Rest)
                .is_some()
            {
                let mut shape = std::mem::take(&mut self.shape);
                shape.clear();
                shape.extend_from_slice(&self.best_t);
                self.shape = shape;
            } else {
                self.shape.clear();
            }
        }
        // Three starts of the optimiser (rest-to-rest, warm and shaped durations); the shortest
        // plan wins, but the shaped one only if it rings past its waypoints no more than the
        // others (at most SHAPED_OVERSHOOT where there are none): where a demonstration pauses
        // its waypoints bunch up, and a short plan that runs through them rings; replaced by
        // the next chunk before it comes back, it makes the robot creep past the pause.
        let inits: &[Init] = if self.shape.is_empty() {
            &[Init::Cold, Init::Warm]
        } else {
            &[Init::Cold, Init::Warm, Init::Shaped, Init::Uniform]
        };
        for &init in inits {
            // (The shaped start scans the first segment itself: one ramp is enough.)
            let ramps: &[f64] = if init == Init::Shaped {
                &[1.0]
            } else {
                &[1.0, 0.5, 2.0]
            };
            for &c in ramps {
                self.first_ramp = c * ramp;
                if let Some(t) = self.optimise(lim, start, wp, end, iterations, init) {
                    let better = match &best {
                        None => init != Init::Shaped || overshoot(&t, wp) <= SHAPED_OVERSHOOT,
                        Some(b) => {
                            t.duration() < b.duration()
                                && (init != Init::Shaped
                                    || overshoot(&t, wp) <= overshoot(b, wp).max(SHAPED_OVERSHOOT))
                        }
                    };
                    if better {
                        best = Some(t);
                    }
                    break;
                }
            }
        }
        best
    }

    fn optimise(
        &mut self,
        lim: &Limits,
        start: &JointState,
        wp: &Waypoints,
        end: EndCondition,
        iterations: usize,
        init: Init,
    ) -> Option<Trajectory> {
        let at_rest = init == Init::Rest;
        let warm = init == Init::Warm || init == Init::Shaped || init == Init::Uniform;
        let n = lim.dof;
        let h = wp.segments();
        // Start: synchronized rest-to-rest durations (closed form).
        let mut seg_t = std::mem::take(&mut self.seg_t);
        let mut best_t = std::mem::take(&mut self.best_t);
        seg_t.clear();
        for k in 1..=h {
            let t = (0..n)
                .map(|i| {
                    rest_to_rest_time(
                        (wp.row(k)[i] - wp.row(k - 1)[i]).abs(),
                        lim.v[i],
                        lim.a[i],
                        lim.j[i],
                    )
                })
                .fold(0.0, f64::max);
            seg_t.push(t.max(MIN_SEGMENT));
        }
        best_t.clear();
        let mut best = f64::INFINITY;
        if init == Init::Warm || init == Init::Uniform {
            // Warm start (moving starts): durations proportional to the segment lengths
            // (limit-normalised joint-space norm), d_k = c·len_k (Uniform: every len_k the first
            // segment's, i.e. equal durations, the policy's clock), with the smallest feasible c
            // found by a geometric scan around the start's own pace and a bisection. For a
            // moving start the limit ratio is not monotone in c (too slow a pace must brake
            // the start velocity first), hence the scan.
            let norm = |d: &dyn Fn(usize) -> f64| {
                (0..n)
                    .map(|i| (d(i) / lim.v[i]).powi(2))
                    .sum::<f64>()
                    .sqrt()
            };
            let pace = norm(&|i| start.dq[i]);
            let total_len: f64 = (1..=h)
                .map(|k| norm(&|i| wp.row(k)[i] - wp.row(k - 1)[i]))
                .sum();
            let uniform = init == Init::Uniform;
            // Uniform: every segment the first one's length at the start's pace.
            let first_len = norm(&|i| wp.row(1)[i] - wp.row(0)[i]);
            // (Uniform needs a first segment to take its length from.)
            if pace > 0.0 && total_len > 0.0 && (!uniform || first_len > 0.0) {
                let c0 = 1.0 / pace;
                // λ(c): the largest limit ratio of the spline with durations c·len_k (∞ if
                // singular); leaves those durations in `seg_t`.
                let lam_at = |c: f64, this: &mut Self, seg_t: &mut Vec<f64>| -> f64 {
                    seg_t.clear();
                    for k in 1..=h {
                        let len = if uniform {
                            first_len
                        } else {
                            norm(&|i| wp.row(k)[i] - wp.row(k - 1)[i])
                        };
                        seg_t.push((c * len).max(MIN_SEGMENT));
                    }
                    this.lambda(lim, start, wp, end, seg_t)
                };
                let ok = |lam: f64| lam <= 1.0 + RATIO_TOL;
                let mut lo_infeasible = None;
                let mut found = None;
                let mut least = (f64::INFINITY, c0);
                for k in -8i32..=8 {
                    let c = c0 * 2f64.powf(k as f64 / 4.0);
                    let lam = lam_at(c, self, &mut seg_t);
                    if lam < least.0 {
                        least = (lam, c);
                    }
                    if ok(lam) {
                        found = Some(c);
                        break;
                    }
                    lo_infeasible = Some(c);
                }
                if let Some(mut hi) = found {
                    if let Some(mut lo) = lo_infeasible {
                        for _ in 0..5 {
                            let mid = (lo * hi).sqrt();
                            if ok(lam_at(mid, self, &mut seg_t)) {
                                hi = mid;
                            } else {
                                lo = mid;
                            }
                        }
                    }
                    let lam = lam_at(hi, self, &mut seg_t);
                    debug_assert!(ok(lam));
                    best = seg_t.iter().sum();
                    best_t.extend_from_slice(&seg_t);
                } else {
                    // Nothing feasible at a uniform pace: refine from the least infeasible one.
                    lam_at(least.1, self, &mut seg_t);
                }
            }
        }
        if init == Init::Shaped {
            self.shaped_search(
                lim,
                start,
                wp,
                end,
                iterations,
                &mut seg_t,
                &mut best,
                &mut best_t,
            );
        }
        // Moving starts do not scale exactly: aim slightly inside the limits.
        let target = if at_rest { 1.0 } else { MOVING_TARGET };
        let generic = if init == Init::Shaped {
            0
        } else {
            iterations.max(1)
        };
        for _ in 0..generic {
            if !self.solve(lim, n, start, wp, end, &seg_t) {
                break;
            }
            self.ratios(n, lim, h);
            let lam = (0..h).map(|k| self.seg_ratio(k)).fold(0.0, f64::max);
            let total: f64 = seg_t.iter().sum();
            // At rest, λ·durations is exactly feasible; otherwise only an iterate within the
            // limits (λ ≤ 1) is a candidate as it stands.
            let (cand, scale) = if at_rest {
                (lam * total, lam)
            } else if lam <= 1.0 + RATIO_TOL {
                (total, 1.0)
            } else {
                (f64::INFINITY, 1.0)
            };
            if cand < best {
                best = cand;
                best_t.clear();
                best_t.extend(seg_t.iter().map(|t| t * scale));
            }
            for k in 0..h {
                let r = self.seg_ratio(k) / target;
                if r > 0.0 {
                    let f = if !warm {
                        r.powf(STEP_EXPONENT)
                    } else {
                        // Warm (moving) starts: the ratios couple through the fixed start
                        // state, so the update is damped (a smaller exponent, at most ±15 % a
                        // step).
                        damped_factor(r)
                    };
                    seg_t[k] = (seg_t[k] * f).max(MIN_SEGMENT);
                }
            }
        }
        let result = if best_t.is_empty() {
            None
        } else {
            (self.lambda(lim, start, wp, end, &best_t) <= 1.0 + RATIO_TOL)
                .then(|| self.assemble(n, start, wp, end))
        };
        self.seg_t = seg_t;
        self.best_t = best_t;
        result
    }

    /// Largest limit ratio of the spline with durations `seg_t` (∞ if singular).
    fn lambda(
        &mut self,
        lim: &Limits,
        start: &JointState,
        wp: &Waypoints,
        end: EndCondition,
        seg_t: &[f64],
    ) -> f64 {
        let n = lim.dof;
        let h = seg_t.len();
        if !self.solve(lim, n, start, wp, end, seg_t) {
            return f64::INFINITY;
        }
        self.ratios(n, lim, h);
        (0..h).map(|k| self.seg_ratio(k)).fold(0.0, f64::max)
    }

    /// The first segment's duration in [lo, hi] (s) that minimises the largest limit ratio, the
    /// other durations fixed: a geometric scan of `points` durations, then a golden-section
    /// refinement around the best. Leaves it in `seg_t[0]` and returns the ratio.
    #[allow(clippy::too_many_arguments)]
    fn best_first(
        &mut self,
        lim: &Limits,
        start: &JointState,
        wp: &Waypoints,
        end: EndCondition,
        seg_t: &mut [f64],
        lo: f64,
        hi: f64,
        points: usize,
    ) -> f64 {
        let (lo, hi) = (lo.max(MIN_SEGMENT), hi.max(MIN_SEGMENT));
        let step = (hi / lo).powf(1.0 / (points.max(2) - 1) as f64);
        let (mut best_i, mut best_l) = (0usize, f64::INFINITY);
        let mut t = lo;
        for i in 0..points {
            seg_t[0] = t;
            let l = self.lambda(lim, start, wp, end, seg_t);
            if l < best_l {
                (best_i, best_l) = (i, l);
            }
            t *= step;
        }
        let at = |i: f64| lo * step.powf(i);
        // Golden section on log t over the neighbouring grid points.
        let (mut a, mut b) = (best_i as f64 - 1.0, best_i as f64 + 1.0);
        let g = 0.5 * (5f64.sqrt() - 1.0);
        let mut best_t = at(best_i as f64);
        for _ in 0..GOLDEN_STEPS {
            let (x1, x2) = (b - g * (b - a), a + g * (b - a));
            seg_t[0] = at(x1);
            let l1 = self.lambda(lim, start, wp, end, seg_t);
            seg_t[0] = at(x2);
            let l2 = self.lambda(lim, start, wp, end, seg_t);
            if l1 < best_l {
                (best_l, best_t) = (l1, at(x1));
            }
            if l2 < best_l {
                (best_l, best_t) = (l2, at(x2));
            }
            if l1 <= l2 {
                b = x2;
            } else {
                a = x1;
            }
        }
        seg_t[0] = best_t;
        best_l
    }

    /// Moving start from the from-rest shape (`self.shape`): the later segments at c times their
    /// from-rest durations, the first segment's duration optimised for each c (a moving start
    /// reaches the next waypoint within limits only in a narrow window of durations), then a
    /// damped fixed-point refinement of the later segments with the first re-optimised.
    #[allow(clippy::too_many_arguments)]
    fn shaped_search(
        &mut self,
        lim: &Limits,
        start: &JointState,
        wp: &Waypoints,
        end: EndCondition,
        iterations: usize,
        seg_t: &mut Vec<f64>,
        best: &mut f64,
        best_t: &mut Vec<f64>,
    ) {
        let shape = std::mem::take(&mut self.shape);
        let h = shape.len();
        let ok = |l: f64| l <= 1.0 + RATIO_TOL;
        let record = |seg_t: &[f64], best: &mut f64, best_t: &mut Vec<f64>| {
            let total: f64 = seg_t.iter().sum();
            if total < *best {
                *best = total;
                best_t.clear();
                best_t.extend_from_slice(seg_t);
            }
        };
        // The later segments at c times their from-rest durations (the first one's is then
        // searched by `best_first`).
        let fill = |seg_t: &mut Vec<f64>, c: f64| {
            seg_t.clear();
            seg_t.push(shape[0]);
            seg_t.extend(shape[1..].iter().map(|t| (c * t).max(MIN_SEGMENT)));
        };
        // The scale search starts at c = 1 (the later segments as from rest, where most plans
        // land) and walks down while c stays feasible, else up until it is (or the ratio stops
        // falling: the shape does not fit). The first segment's feasible durations form a
        // narrow valley that moves with the scale, so every scale scans the whole range.
        let tail: f64 = shape[1..].iter().sum();
        let wide = |this: &mut Self, seg_t: &mut Vec<f64>, c: f64| -> f64 {
            fill(seg_t, c);
            this.best_first(
                lim,
                start,
                wp,
                end,
                seg_t,
                FIRST_MIN * shape[0],
                FIRST_MAX * shape[0],
                FIRST_POINTS,
            )
        };
        let mut c = 1.0;
        if ok(wide(self, seg_t, c)) {
            record(seg_t, best, best_t);
            for _ in 0..SHAPE_SCALES {
                c /= SHAPE_SCALE_STEP;
                if c < SHAPE_SCALE_MIN || !ok(wide(self, seg_t, c)) {
                    break;
                }
                record(seg_t, best, best_t);
            }
        } else {
            let mut prev = f64::INFINITY;
            for i in 0..SHAPE_SCALES {
                c *= SHAPE_SCALE_STEP;
                if c > SHAPE_SCALE_MAX || c * tail >= *best {
                    // Slower than a plan already found.
                    break;
                }
                let l = wide(self, seg_t, c);
                if ok(l) {
                    record(seg_t, best, best_t);
                    break;
                }
                if i >= STALL_AFTER && l > STALL_RATIO * prev {
                    break;
                }
                prev = l;
            }
        }
        if best_t.is_empty() {
            self.shape = shape;
            return;
        }
        // Damped fixed-point refinement of the later segments from the best found, the first
        // segment re-optimised around its last duration at every iterate.
        if h > 1 {
            seg_t.clear();
            seg_t.extend_from_slice(best_t);
            for _ in 0..iterations.min(REFINE_ITERATIONS) {
                self.lambda(lim, start, wp, end, seg_t);
                for k in 1..h {
                    let r = self.seg_ratio(k) / MOVING_TARGET;
                    if r > 0.0 {
                        seg_t[k] = (seg_t[k] * damped_factor(r)).max(MIN_SEGMENT);
                    }
                }
                let t0 = seg_t[0];
                let l = self.best_first(
                    lim,
                    start,
                    wp,
                    end,
                    seg_t,
                    0.8 * t0,
                    1.25 * t0,
                    REFINE_POINTS,
                );
                if ok(l) {
                    record(seg_t, best, best_t);
                }
            }
        }
        self.shape = shape;
    }

    /// The trajectory of the last solved spline.
    fn assemble(
        &self,
        n: usize,
        start: &JointState,
        wp: &Waypoints,
        end: EndCondition,
    ) -> Trajectory {
        let p = self.tau.len();
        let h = wp.segments();
        let mut pieces = Vec::with_capacity(n * (p + 1));
        let mut offsets = [0usize; MAX_DOF + 1];
        let mut times = Vec::with_capacity(h);
        let mut t = 0.0;
        for q in 0..p {
            t += self.tau[q];
            if self.knot_wp[q + 1] != FREE {
                times.push(t);
            }
        }
        let duration = t;
        for i in 0..n {
            offsets[i] = pieces.len();
            let mut t = 0.0;
            for q in 0..p {
                let tq = self.tau[q];
                let (v, a) = if q == 0 {
                    (start.dq[i], start.ddq[i])
                } else {
                    (self.v_start(q, i), self.acc[q][i])
                };
                pieces.push(Piece {
                    t,
                    q: self.y[q][i],
                    v,
                    a,
                    j: (self.acc[q + 1][i] - self.acc[q][i]) / tq,
                });
                t += tq;
            }
            pieces.push(Piece {
                t: duration,
                q: wp.row(h)[i],
                v: self.v_end[i],
                a: 0.0,
                j: 0.0,
            });
        }
        offsets[n] = pieces.len();
        Trajectory::from_parts(n, pieces, offsets, duration, times, end)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::chunk::{ActionKind, Chunk, OutOfLimits};
    use pacs_models::RobotModel;

    /// Jerk-limited braking from `v` at zero acceleration, simulated with a fine step: the
    /// distance run until the velocity reaches zero.
    fn braking_distance(v: f64, a: f64, j: f64) -> f64 {
        let dt = 1e-6;
        let (mut x, mut vel, mut acc) = (0.0, v, 0.0f64);
        // Jerk −j until the acceleration reaches −a or the velocity left is what ramping the
        // acceleration back to zero removes (v = acc²/(2j)); then hold; then ramp back.
        while vel > 0.0 {
            let ramp_back = acc * acc / (2.0 * j);
            let jerk = if vel <= ramp_back {
                j
            } else if acc > -a {
                -j
            } else {
                0.0
            };
            acc = (acc + jerk * dt).clamp(-a, 0.0);
            vel += acc * dt;
            x += vel.max(0.0) * dt;
        }
        x
    }

    #[test]
    fn stopping_velocity_matches_hand_values_and_simulated_braking() {
        // a = 8 rad/s², j = 400 rad/s³: the acceleration limit is reached above v = a²/j = 0.16
        // rad/s, i.e. beyond d = a³/j² = 0.0032 rad.
        let (a, j) = (8.0, 400.0);
        assert!((stopping_velocity(0.0032, a, j) - 0.16).abs() < 1e-12);
        // Below: d = v·√(v/j): v = 0.04 → d = 0.04 · 0.01 = 0.0004.
        assert!((stopping_velocity(0.0004, a, j) - 0.04).abs() < 1e-12);
        // Above: d = v(v/a + a/j)/2: v = 1 → d = (0.125 + 0.02)/2 = 0.0725.
        assert!((stopping_velocity(0.0725, a, j) - 1.0).abs() < 1e-12);
        assert_eq!(stopping_velocity(0.0, a, j), 0.0);
        assert_eq!(stopping_velocity(-1.0, a, j), 0.0);
        for (v, a, j) in [(0.05, 8.0, 400.0), (0.7, 8.0, 400.0), (2.0, 10.0, 5000.0)] {
            let d = braking_distance(v, a, j);
            let back = stopping_velocity(d, a, j);
            assert!((back - v).abs() < 2e-3 * v, "v {v}: d {d}, back {back}");
        }
    }

    /// A Moving chunk ends no faster than it can stop within the room its predicted actions
    /// leave along its direction (a pause: none), and keeps its pace where they go on.
    #[test]
    fn moving_end_velocity_respects_a_pause_in_the_predicted_actions() {
        let robot = RobotModel::builtin("fr3").unwrap();
        let lim = Limits::from_joint_limits(robot.limits()).with_uniform_acc_jerk(8.0, 400.0);
        let q0 = [0.0, -0.3, 0.0, -2.0, 0.0, 1.9, 0.8];
        let step = [0.004, 0.012, -0.003, 0.008, 0.0, 0.006, 0.0];
        let plan = |predicted: &[f64]| {
            let mut actions = vec![step.to_vec(); 6];
            for &f in predicted {
                actions.push(step.iter().map(|x| x * f).collect());
            }
            let chunk = Chunk {
                kind: ActionKind::Delta,
                actions,
                execute: 6,
                gripper: None,
            };
            let wp = chunk
                .waypoints(&q0, robot.limits(), OutOfLimits::Reject)
                .unwrap();
            let mut s = SplineSolver::default();
            let t = s
                .plan(
                    &lim,
                    &JointState::at_rest(&q0),
                    &wp,
                    EndCondition::Moving,
                    16,
                )
                .unwrap();
            let te = *t.waypoint_times().last().unwrap();
            let v = t.state_at(te).dq;
            (v[..7].iter().map(|x| x * x).sum::<f64>().sqrt(), wp)
        };
        // The path goes on at the same pace: the end velocity is the uncapped estimate.
        let (go, _) = plan(&[1.0; 6]);
        assert!(go > 0.1, "end speed {go}");
        // The path pauses after one more small step: room = that step's length (of which the
        // chunk may use PAUSE_ROOM_FRACTION).
        let (pause, wp) = plan(&[0.25, 0.0, 0.0, 0.0, 0.0, 0.0]);
        let room: f64 = (0..7)
            .map(|i| (wp.predicted(0).unwrap()[i] - wp.row(6)[i]).powi(2))
            .sum::<f64>()
            .sqrt();
        let cap = stopping_velocity(PAUSE_ROOM_FRACTION * room, 8.0, 400.0);
        assert!(pause <= cap * (1.0 + 1e-9), "end speed {pause} > cap {cap}");
        // Half the room: below the time-optimal stopping speed of the whole room.
        assert!(cap < stopping_velocity(room, 8.0, 400.0));
        assert!(pause < 0.5 * go, "pause {pause} vs go {go}");
        // The path turns straight back: the chunk ends at rest.
        let (back, _) = plan(&[-1.0; 6]);
        assert!(back <= 1e-12, "end speed {back}");
    }
}
