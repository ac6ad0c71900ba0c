//! The intended trajectory: per joint a piecewise constant-jerk polynomial, with exact state
//! queries and sound extrema of q, q̇, q̈ (and jerk) over any time window. Queries allocate nothing.

use crate::error::TrajectoryError;
use crate::profile::{LIMIT_REL_TOL, Piece, Range};
use pacs_models::{JointLimits, MAX_DOF};

/// Joint state (rad, rad/s, rad/s², rad/s³); entries beyond the robot's dof are zero.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointState {
    /// Positions (rad).
    pub q: [f64; MAX_DOF],
    /// Velocities (rad/s).
    pub dq: [f64; MAX_DOF],
    /// Accelerations (rad/s²).
    pub ddq: [f64; MAX_DOF],
    /// Jerks (rad/s³).
    pub dddq: [f64; MAX_DOF],
}

impl Default for JointState {
    fn default() -> Self {
        Self {
            q: [0.0; MAX_DOF],
            dq: [0.0; MAX_DOF],
            ddq: [0.0; MAX_DOF],
            dddq: [0.0; MAX_DOF],
        }
    }
}

impl JointState {
    /// State at rest at `q` (at most [`MAX_DOF`] entries are used).
    pub fn at_rest(q: &[f64]) -> Self {
        let mut s = Self::default();
        let n = q.len().min(MAX_DOF);
        s.q[..n].copy_from_slice(&q[..n]);
        s
    }
    /// State from slices of equal length (at most [`MAX_DOF`] entries are used).
    pub fn new(q: &[f64], dq: &[f64], ddq: &[f64]) -> Self {
        let mut s = Self::at_rest(q);
        let n = dq.len().min(MAX_DOF);
        s.dq[..n].copy_from_slice(&dq[..n]);
        let n = ddq.len().min(MAX_DOF);
        s.ddq[..n].copy_from_slice(&ddq[..n]);
        s
    }
    /// Whether the first `dof` joints have zero velocity and zero acceleration (exactly; −0.0
    /// counts as zero): the start of a plan from rest, where every plan scales exactly.
    pub fn is_at_rest(&self, dof: usize) -> bool {
        self.dq[..dof]
            .iter()
            .chain(&self.ddq[..dof])
            .all(|&x| x == 0.0)
    }
}

/// Sound per-joint ranges of q (rad), q̇ (rad/s) and q̈ (rad/s²) over a time window.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bounds {
    /// Position ranges.
    pub q: [Range; MAX_DOF],
    /// Velocity ranges.
    pub dq: [Range; MAX_DOF],
    /// Acceleration ranges.
    pub ddq: [Range; MAX_DOF],
}

impl Default for Bounds {
    fn default() -> Self {
        Self {
            q: [Range::EMPTY; MAX_DOF],
            dq: [Range::EMPTY; MAX_DOF],
            ddq: [Range::EMPTY; MAX_DOF],
        }
    }
}

/// Sound ranges of q, q′, q″, q‴ of one joint over a window (used by the failsafe).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Derivs {
    /// Position, velocity, acceleration, jerk ranges.
    pub r: [Range; 4],
}

/// Kinematic limits as fixed-size arrays (rad, rad/s, rad/s², rad/s³).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    /// Number of joints.
    pub dof: usize,
    /// Lower position limits.
    pub q_min: [f64; MAX_DOF],
    /// Upper position limits.
    pub q_max: [f64; MAX_DOF],
    /// Velocity limits.
    pub v: [f64; MAX_DOF],
    /// Acceleration limits.
    pub a: [f64; MAX_DOF],
    /// Jerk limits.
    pub j: [f64; MAX_DOF],
}

impl Limits {
    /// Copy of a model's limits.
    pub fn from_joint_limits(l: &JointLimits) -> Self {
        let n = l.dof().min(MAX_DOF);
        let mut s = Self {
            dof: n,
            q_min: [0.0; MAX_DOF],
            q_max: [0.0; MAX_DOF],
            v: [0.0; MAX_DOF],
            a: [0.0; MAX_DOF],
            j: [0.0; MAX_DOF],
        };
        s.q_min[..n].copy_from_slice(&l.q_min()[..n]);
        s.q_max[..n].copy_from_slice(&l.q_max()[..n]);
        s.v[..n].copy_from_slice(&l.v_max()[..n]);
        s.a[..n].copy_from_slice(&l.a_max()[..n]);
        s.j[..n].copy_from_slice(&l.j_max()[..n]);
        s
    }
    /// Velocity, acceleration and jerk limits multiplied by `factor` ∈ (0, 1] (slower execution).
    pub fn scaled(mut self, factor: f64) -> Result<Self, TrajectoryError> {
        if !(factor > 0.0 && factor <= 1.0) {
            return Err(TrajectoryError::Scale(factor));
        }
        for i in 0..self.dof {
            self.v[i] *= factor;
            self.a[i] *= factor;
            self.j[i] *= factor;
        }
        Ok(self)
    }
    /// Acceleration and jerk limits replaced by min(current, a) and min(current, j).
    pub fn with_uniform_acc_jerk(mut self, a: f64, j: f64) -> Self {
        for i in 0..self.dof {
            self.a[i] = self.a[i].min(a);
            self.j[i] = self.j[i].min(j);
        }
        self
    }
}

/// How the intended trajectory ends at the last executed waypoint q̂_h.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum EndCondition {
    /// At rest at q̂_h (and holds q̂_h afterwards).
    #[default]
    AtRest,
    /// Passing q̂_h with a velocity v_end toward the next chunk, then — unless a next chunk takes
    /// over — a jerk-limited **stopping tail** along v_end: q(T + u) = q̂_h + v_end·σ(u) with the
    /// time-optimal scalar stop σ′: 1 → 0 under the planning limits (see
    /// [`Trajectory::rest_time`]). The tail is part of the trajectory: it is checked against every
    /// limit (positions included) like the rest, so following a Moving trajectory to its end is a
    /// stop, and any failsafe braking along it stays on checked path.
    Moving,
}

/// A jerk-limited intended trajectory through waypoints, starting at time 0.
#[derive(Debug, Clone, PartialEq)]
pub struct Trajectory {
    dof: usize,
    pieces: Vec<Piece>,
    offsets: [usize; MAX_DOF + 1],
    duration: f64,
    /// Time (s) from which the trajectory is at rest (the duration, or the end of the stopping tail).
    rest_time: f64,
    waypoint_times: Vec<f64>,
    /// Leading waypoints a blend passes within [`crate::intended::BLEND_TOLERANCE`] instead of
    /// exactly (0: every waypoint exactly).
    blended: usize,
    end: EndCondition,
    peak: [[f64; 3]; MAX_DOF],
    /// Sound q, q̇, q̈ ranges of each whole piece (terminal pieces: their start state only).
    full: Vec<[Range; 3]>,
}

impl Trajectory {
    /// Standing still at `q` (rad) forever: zero duration, one waypoint, at rest.
    pub fn standstill(q: &[f64]) -> Trajectory {
        let n = q.len();
        let mut offsets = [0usize; MAX_DOF + 1];
        let pieces: Vec<Piece> = q
            .iter()
            .map(|&x| Piece {
                t: 0.0,
                q: x,
                v: 0.0,
                a: 0.0,
                j: 0.0,
            })
            .collect();
        for (i, o) in offsets.iter_mut().enumerate().take(n + 1) {
            *o = i;
        }
        Self::from_parts(n, pieces, offsets, 0.0, vec![0.0], EndCondition::AtRest)
    }

    /// Assemble from per-joint piece lists (each non-empty, sorted, first at t = 0, last extending to +∞).
    pub(crate) fn from_parts(
        dof: usize,
        pieces: Vec<Piece>,
        offsets: [usize; MAX_DOF + 1],
        duration: f64,
        waypoint_times: Vec<f64>,
        end: EndCondition,
    ) -> Self {
        let mut full = vec![[Range::EMPTY; 3]; pieces.len()];
        for i in 0..dof {
            for k in offsets[i]..offsets[i + 1] {
                let d1 = if k + 1 < offsets[i + 1] {
                    pieces[k + 1].t - pieces[k].t
                } else {
                    0.0
                };
                pieces[k].extend_bounds(0.0, d1, &mut full[k]);
            }
        }
        Self {
            dof,
            pieces,
            offsets,
            duration,
            rest_time: duration,
            waypoint_times,
            blended: 0,
            end,
            peak: [[f64::INFINITY; 3]; MAX_DOF],
            full,
        }
    }
    /// Number of joints.
    #[inline]
    pub fn dof(&self) -> usize {
        self.dof
    }
    /// Duration T (s): time at which q̂_h is reached.
    #[inline]
    pub fn duration(&self) -> f64 {
        self.duration
    }
    /// Time (s) from which the trajectory stands still: the duration for [`EndCondition::AtRest`],
    /// the end of the stopping tail for [`EndCondition::Moving`].
    #[inline]
    pub fn rest_time(&self) -> f64 {
        self.rest_time
    }
    /// Times (s) at which q̂_1 … q̂_h are passed (the last equals the duration). The first
    /// [`Self::blended`] of them are the times of closest approach of a blend.
    pub fn waypoint_times(&self) -> &[f64] {
        &self.waypoint_times
    }
    /// How the trajectory ends.
    #[inline]
    pub fn end(&self) -> EndCondition {
        self.end
    }
    /// Constant-jerk pieces of joint `i`, in time order; the last one extends to +∞.
    pub fn pieces(&self, i: usize) -> &[Piece] {
        &self.pieces[self.offsets[i]..self.offsets[i + 1]]
    }

    #[inline]
    fn locate(&self, i: usize, t: f64) -> usize {
        let p = &self.pieces[self.offsets[i]..self.offsets[i + 1]];
        p.partition_point(|x| x.t <= t).max(1) - 1 + self.offsets[i]
    }

    /// A [`EndCondition::Moving`] trajectory with its stopping tail appended: every joint continues
    /// from its state at T = [`Self::duration`] as q̂_h + v_end·σ(u), where σ is the time-optimal
    /// scalar stop (σ′ from 1 to 0, σ″ = 0 at both ends) with |σ″| ≤ min_i a_i/|v_end,i| and
    /// |σ‴| ≤ min_i j_i/|v_end,i|, so the tail itself is within `lim`'s velocity, acceleration
    /// and jerk limits; positions are left to [`Self::check`]. The last piece is exactly at rest.
    /// `None` if the trajectory does not end Moving, already has a tail, or is not at zero
    /// acceleration at T (the tail starts with σ″ = 0). The result must be checked again.
    pub(crate) fn with_stop_tail(&self, lim: &Limits) -> Option<Trajectory> {
        if self.end != EndCondition::Moving || self.rest_time > self.duration {
            return None;
        }
        let t_end = self.duration;
        let mut ends = [(0.0, 0.0); MAX_DOF];
        let (mut acc, mut jerk) = (f64::INFINITY, f64::INFINITY);
        for i in 0..self.dof {
            let (q, v, a) = self.joint_at(i, t_end);
            if a.abs() > 1e-9 * lim.a[i] || !v.is_finite() {
                return None;
            }
            if v != 0.0 {
                acc = acc.min(lim.a[i] / v.abs());
                jerk = jerk.min(lim.j[i] / v.abs());
            }
            ends[i] = (q, v);
        }
        let stop = if acc.is_finite() && jerk.is_finite() {
            Some(crate::scaling::SpeedProfile::plan(
                crate::scaling::PathState::intended(0.0),
                0.0,
                acc,
                jerk,
            ))
        } else {
            None // every joint already at rest at T
        };
        let mut pieces = Vec::with_capacity(self.pieces.len() + 4 * self.dof);
        let mut offsets = [0usize; MAX_DOF + 1];
        let mut rest_time = t_end;
        for i in 0..self.dof {
            offsets[i] = pieces.len();
            // Pieces up to T (the terminal one is replaced by the tail).
            pieces.extend(self.pieces(i).iter().filter(|p| p.t < t_end).copied());
            let (q, v) = ends[i];
            if let Some(stop) = &stop {
                for (t0, st, sj) in stop.phases() {
                    let last = t0 >= stop.settle_time();
                    pieces.push(Piece {
                        t: t_end + t0,
                        q: q + v * st.s,
                        v: if last { 0.0 } else { v * st.sd },
                        a: if last { 0.0 } else { v * st.sdd },
                        j: if last { 0.0 } else { v * sj },
                    });
                }
                rest_time = t_end + stop.settle_time();
            } else {
                pieces.push(Piece {
                    t: t_end,
                    q,
                    v: 0.0,
                    a: 0.0,
                    j: 0.0,
                });
            }
        }
        offsets[self.dof] = pieces.len();
        let mut t = Self::from_parts(
            self.dof,
            pieces,
            offsets,
            t_end,
            self.waypoint_times.clone(),
            EndCondition::Moving,
        );
        t.rest_time = rest_time;
        t.blended = self.blended;
        Some(t)
    }

    /// Exact state at time `t` (s; clamped to t ≥ 0), right-continuous at piece boundaries.
    #[inline]
    pub fn state_at(&self, t: f64) -> JointState {
        let t = t.max(0.0);
        let mut s = JointState::default();
        for i in 0..self.dof {
            let p = &self.pieces[self.locate(i, t)];
            let (q, v, a) = p.eval(t - p.t);
            s.q[i] = q;
            s.dq[i] = v;
            s.ddq[i] = a;
            s.dddq[i] = p.j;
        }
        s
    }

    /// Piece index of joint `i` at time `t`, searching forward from `*hint` (a previous result for
    /// an earlier time) and updating it; falls back to binary search.
    #[inline]
    pub(crate) fn locate_hint(&self, i: usize, hint: &mut usize, t: f64) -> usize {
        let (lo, hi) = (self.offsets[i], self.offsets[i + 1]);
        let mut k = *hint;
        if k < lo || k >= hi || self.pieces[k].t > t {
            k = self.locate(i, t);
        } else {
            let mut steps = 0;
            while k + 1 < hi && self.pieces[k + 1].t <= t {
                k += 1;
                steps += 1;
                if steps > 8 {
                    k = self.locate(i, t);
                    break;
                }
            }
        }
        *hint = k;
        k
    }

    /// Position, velocity and acceleration of joint `i` at time `t` (s; clamped to ≥ 0).
    #[inline]
    pub fn joint_at(&self, i: usize, t: f64) -> (f64, f64, f64) {
        let t = t.max(0.0);
        let p = &self.pieces[self.locate(i, t)];
        p.eval(t - p.t)
    }

    /// Sound ranges of q, q̇, q̈, q⃛ of joint `i` over [ta, tb] (s, clamped to ≥ 0): exact piecewise
    /// extrema padded outward (see [`crate::profile`]).
    #[inline]
    pub fn joint_derivs(&self, i: usize, ta: f64, tb: f64) -> Derivs {
        let mut hint = usize::MAX;
        self.joint_derivs_hint(i, &mut hint, ta, tb)
    }

    /// [`Trajectory::joint_derivs`] with a search hint for `ta` (see `locate_hint`).
    #[inline]
    pub(crate) fn joint_derivs_hint(&self, i: usize, hint: &mut usize, ta: f64, tb: f64) -> Derivs {
        let mut r = [Range::EMPTY; 3];
        let mut jr = Range::EMPTY;
        self.walk_pieces(i, hint, ta, tb, |k, part| {
            match part {
                None => {
                    let f = &self.full[k];
                    r[0].union(f[0]);
                    r[1].union(f[1]);
                    r[2].union(f[2]);
                }
                Some((d0, d1)) => self.pieces[k].extend_bounds(d0, d1, &mut r),
            }
            jr.union(Range::point(self.pieces[k].j));
        });
        Derivs {
            r: [r[0], r[1], r[2], jr],
        }
    }

    /// Upper bounds of |q̇|, |q̈|, |q⃛| of joint `i` over [ta, tb] (s, clamped to ≥ 0): the
    /// derivative part of [`Trajectory::joint_derivs`] (the same pieces, instants and pads; each
    /// bound at most its `r[k].abs_max()`), without the position's extrema. For the path-speed
    /// limits ([`crate::scaling::admissible`]), which need no positions.
    #[inline]
    pub fn joint_deriv_abs(&self, i: usize, ta: f64, tb: f64) -> [f64; 3] {
        let mut r = [Range::EMPTY; 2];
        let mut jr = Range::EMPTY;
        let mut hint = usize::MAX;
        self.walk_pieces(i, &mut hint, ta, tb, |k, part| {
            match part {
                None => {
                    let f = &self.full[k];
                    r[0].union(f[1]);
                    r[1].union(f[2]);
                }
                Some((d0, d1)) => self.pieces[k].extend_deriv_bounds(d0, d1, &mut r),
            }
            jr.union(Range::point(self.pieces[k].j));
        });
        [r[0].abs_max(), r[1].abs_max(), jr.abs_max()]
    }

    /// The pieces of joint `i` that [ta, tb] (s, clamped to ≥ 0) touches, in order: `visit(k,
    /// None)` for piece `k` wholly inside (its precomputed ranges apply), `visit(k, Some((d0,
    /// d1)))` for the local part `[d0, d1]` of one cut by an end. At `tb` equal to a piece's start
    /// that piece is included too (state queries are right-continuous).
    #[inline]
    fn walk_pieces(
        &self,
        i: usize,
        hint: &mut usize,
        ta: f64,
        tb: f64,
        mut visit: impl FnMut(usize, Option<(f64, f64)>),
    ) {
        let ta = ta.max(0.0);
        let tb = tb.max(ta);
        let end = self.offsets[i + 1];
        let mut k = self.locate_hint(i, hint, ta);
        loop {
            let p = &self.pieces[k];
            let next_t = if k + 1 < end {
                self.pieces[k + 1].t
            } else {
                f64::INFINITY
            };
            if ta <= p.t && next_t <= tb {
                visit(k, None);
            } else {
                visit(k, Some((ta.max(p.t) - p.t, tb.min(next_t) - p.t)));
            }
            if next_t > tb || k + 1 >= end {
                break;
            }
            k += 1;
        }
    }

    /// Sound ranges of q, q̇, q̈ for every joint over [ta, tb] (s).
    pub fn bounds(&self, ta: f64, tb: f64) -> Bounds {
        let mut b = Bounds::default();
        for i in 0..self.dof {
            let d = self.joint_derivs(i, ta, tb);
            b.q[i] = d.r[0];
            b.dq[i] = d.r[1];
            b.ddq[i] = d.r[2];
        }
        b
    }

    /// Check every limit over the whole trajectory by exact piecewise extrema (tolerance
    /// [`LIMIT_REL_TOL`] relative, positions 1e-9 rad) and continuity of q, q̇, q̈ at every piece
    /// boundary (1e-9 relative to the limits). Names the joint, time and value on failure.
    /// On success the peaks of |q̇|, |q̈|, |q⃛| per joint are recorded (see [`Trajectory::peaks`]).
    pub fn check(&mut self, lim: &Limits) -> Result<(), TrajectoryError> {
        let tol = LIMIT_REL_TOL;
        let mut peak = [[0.0f64; 3]; MAX_DOF];
        for i in 0..self.dof {
            let ps = self.pieces(i);
            for (k, p) in ps.iter().enumerate() {
                let t1 = if k + 1 < ps.len() {
                    ps[k + 1].t
                } else {
                    self.duration.max(p.t)
                };
                let mut r = [Range::EMPTY; 3];
                p.extend_bounds(0.0, t1 - p.t, &mut r);
                let seg = self.segment_of(p.t);
                let fail = |reason: String| {
                    Err(TrajectoryError::Infeasible {
                        segment: seg,
                        joint: i,
                        reason,
                    })
                };
                if r[0].lo < lim.q_min[i] - 1e-9 || r[0].hi > lim.q_max[i] + 1e-9 {
                    return fail(format!(
                        "position range [{}, {}] rad leaves [{}, {}] after t = {} s",
                        r[0].lo, r[0].hi, lim.q_min[i], lim.q_max[i], p.t
                    ));
                }
                if r[1].abs_max() > lim.v[i] * (1.0 + tol) {
                    return fail(format!(
                        "|velocity| {} rad/s > {} after t = {} s",
                        r[1].abs_max(),
                        lim.v[i],
                        p.t
                    ));
                }
                if r[2].abs_max() > lim.a[i] * (1.0 + tol) {
                    return fail(format!(
                        "|acceleration| {} rad/s² > {} after t = {} s",
                        r[2].abs_max(),
                        lim.a[i],
                        p.t
                    ));
                }
                peak[i][0] = peak[i][0].max(r[1].abs_max());
                peak[i][1] = peak[i][1].max(r[2].abs_max());
                peak[i][2] = peak[i][2].max(p.j.abs());
                if p.j.abs() > lim.j[i] * (1.0 + tol) {
                    return fail(format!(
                        "|jerk| {} rad/s³ > {} after t = {} s",
                        p.j.abs(),
                        lim.j[i],
                        p.t
                    ));
                }
                if k + 1 < ps.len() {
                    let n = &ps[k + 1];
                    let (q, v, a) = p.eval(n.t - p.t);
                    if (q - n.q).abs() > 1e-9
                        || (v - n.v).abs() > 1e-9 * lim.v[i]
                        || (a - n.a).abs() > 1e-9 * lim.a[i]
                    {
                        return fail(format!(
                            "discontinuity at t = {} s: (q, dq, ddq) ({q}, {v}, {a}) vs ({}, {}, {})",
                            n.t, n.q, n.v, n.a
                        ));
                    }
                }
            }
        }
        self.peak = peak;
        Ok(())
    }

    /// Sound peaks of |q̇| (rad/s), |q̈| (rad/s²), |q⃛| (rad/s³) of joint `i` over [0, T] as
    /// recorded by the last successful [`Trajectory::check`] (+∞ if never checked).
    #[inline]
    pub fn peaks(&self, i: usize) -> [f64; 3] {
        self.peak[i]
    }

    /// Put the times (s, non-decreasing, at or before the first recorded one) at which a blend
    /// passes the waypoints it was not planned through in front of the waypoint times.
    pub(crate) fn prepend_waypoint_times(&mut self, times: &[f64]) {
        self.waypoint_times.splice(0..0, times.iter().copied());
        self.blended += times.len();
    }

    /// Number of leading waypoints q̂_1 … q̂_k this trajectory passes within
    /// [`crate::intended::BLEND_TOLERANCE`] (joint-space distance) instead of exactly: a blend
    /// from a moving start ([`crate::intended::Planner::plan`]); 0 for every other plan. Every
    /// later waypoint is passed exactly.
    pub fn blended(&self) -> usize {
        self.blended
    }

    fn segment_of(&self, t: f64) -> usize {
        self.waypoint_times.partition_point(|&w| w <= t) + 1
    }
}

impl Trajectory {
    /// Start time of joint `i`'s next piece strictly after `s` (s), if any.
    #[inline]
    pub fn next_joint_breakpoint(&self, i: usize, s: f64) -> Option<f64> {
        let k = self.locate(i, s) + 1;
        (k < self.offsets[i + 1])
            .then(|| self.pieces[k].t)
            .filter(|&t| t > s)
    }

    /// Earliest piece start time of any joint strictly after `s` (s), if any.
    #[inline]
    pub fn next_breakpoint(&self, s: f64) -> Option<f64> {
        let mut best = f64::INFINITY;
        for i in 0..self.dof {
            let k = self.locate(i, s) + 1;
            if k < self.offsets[i + 1] {
                let t = self.pieces[k].t;
                if t > s && t < best {
                    best = t;
                }
            }
        }
        best.is_finite().then_some(best)
    }
}
