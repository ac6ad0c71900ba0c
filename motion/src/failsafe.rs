//! Path-consistent failsafe: a jerk-limited time scaling s(τ) of the intended trajectory with ṡ
//! decreasing from 1 to 0, so every configuration lies on the intended path. Admissibility is
//! proven from sound bounds of the path derivatives over the path window it covers (chain rule
//! q̇ = q′ṡ, q̈ = q′s̈ + q″ṡ², q⃛ = q‴ṡ³ + 3q″ṡs̈ + q′s⃛), never by clamping joint values.
//!
//! Construction (see docs/trajectory.md): from s0 the failsafe may first follow the intended
//! timing for a delay δ (ṡ = 1, admissible because the intended trajectory satisfies limits that
//! are not above the failsafe's limits — checked, otherwise the delay window is checked too), then
//! brakes with path jerk −J, plateau deceleration −A, path jerk +J (ṡ: 1 → 0). For a window
//! W = [s_b, s_b + w] with per-joint bounds Q1 ≥ |q′|, Q2 ≥ |q″|, Q3 ≥ |q‴| and ṡ ∈ [0, 1],
//! s̈ ∈ [−A, 0], |s⃛| ≤ J: |q̇| ≤ Q1, |q̈| ≤ Q1·A + Q2, |q⃛| ≤ Q3 + 3·Q2·A + Q1·J. A and J are the
//! largest values making these ≤ the limits (times a 0.98 safety factor), iterated until the
//! braking distance Δs = (brake time)/2 fits in W; the final inequalities are re-evaluated in
//! outward-rounded interval arithmetic. Candidate delays are 0 and the next piece breakpoints;
//! if the intended trajectory ends at rest, following it to the end is always admissible.

use crate::error::FailsafeError;
use crate::profile::{LIMIT_REL_TOL, Range};
use crate::trajectory::{EndCondition, JointState, Limits, Trajectory};
use pacs_models::MAX_DOF;

/// How the failsafe stops.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FailsafeKind {
    /// Follow the intended timing for `delay`, then brake along the path.
    Brake,
    /// Follow the intended trajectory to its end at rest.
    FollowToEnd,
}

/// Path state at the start of a failsafe phase: relative time τ (s), s (s), ṡ (1), s̈ (1/s), s⃛ (1/s²).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct Phase {
    tau: f64,
    s: f64,
    sd: f64,
    sdd: f64,
    sddd: f64,
}

impl Phase {
    #[inline]
    fn eval(&self, d: f64) -> (f64, f64, f64) {
        (
            self.s + d * (self.sd + d * (0.5 * self.sdd + d * self.sddd / 6.0)),
            self.sd + d * (self.sdd + d * 0.5 * self.sddd),
            self.sdd + d * self.sddd,
        )
    }
}

/// Maximum number of delay candidates tried before falling back to following to the end.
pub const MAX_DELAY_CANDIDATES: usize = 6;
const SAFETY: f64 = 0.98;
const A_CAP: f64 = 1.0e3;
const J_CAP: f64 = 1.0e6;

/// A verified path-consistent braking motion starting on the intended trajectory at s0 (ṡ = 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Failsafe {
    kind: FailsafeKind,
    s0: f64,
    delay: f64,
    jerk: f64,
    acc: f64,
    stop_time: f64,
    s_stop: f64,
    phases: [Phase; 5],
    nphases: usize,
    dof: usize,
}

#[derive(Clone, Copy)]
struct Window {
    q1: [f64; MAX_DOF],
    q2: [f64; MAX_DOF],
    q3: [f64; MAX_DOF],
}

impl Failsafe {
    /// Build the shortest admissible candidate from path position `s0` (s, intended time) against
    /// `lim` (normally the robot's hardware limits): allocation-free.
    pub fn new(traj: &Trajectory, s0: f64, lim: &Limits) -> Result<Self, FailsafeError> {
        let big_t = traj.duration();
        let at_rest = traj.end() == EndCondition::AtRest;
        if !s0.is_finite() || s0 < 0.0 || (s0 > big_t && !at_rest) {
            return Err(FailsafeError::StartOutsideTrajectory {
                s0,
                duration: big_t,
            });
        }
        let n = traj.dof();
        // Is following the intended timing admissible by the intended trajectory's own check?
        let tol = 1.0 + LIMIT_REL_TOL;
        let follow_ok = (0..n).all(|i| {
            let p = traj.peaks(i);
            p[0] <= lim.v[i] * tol && p[1] <= lim.a[i] * tol && p[2] <= lim.j[i] * tol
        }) || Self::intended_within(traj, lim, s0, big_t.max(s0));
        let mut best: Option<Failsafe> = None;
        if at_rest && follow_ok {
            best = Some(Self::follow_to_end(traj, s0));
        }
        let mut sb = s0;
        // Piece-search hints per joint: candidate start times only increase.
        let mut hints = [usize::MAX; MAX_DOF];
        for _ in 0..MAX_DELAY_CANDIDATES {
            if let Some(b) = &best
                && sb - s0 >= b.stop_time
            {
                break;
            }
            if sb >= big_t && at_rest {
                break;
            }
            let mut blocking = None;
            if follow_ok || Self::intended_within(traj, lim, s0, sb) {
                let max_brake = best.map_or(f64::INFINITY, |b| b.stop_time - (sb - s0));
                match Self::try_brake(traj, lim, s0, sb, n, max_brake, &mut hints) {
                    Ok(f) => {
                        if best.is_none_or(|b| f.stop_time < b.stop_time) {
                            best = Some(f);
                        }
                        break;
                    }
                    Err(j) => blocking = j,
                }
            }
            let next = match blocking {
                Some(i) => traj
                    .next_joint_breakpoint(i, sb)
                    .or_else(|| traj.next_breakpoint(sb)),
                None => traj.next_breakpoint(sb),
            };
            match next {
                Some(t) if t < big_t || at_rest => sb = t,
                _ => break,
            }
        }
        best.ok_or(FailsafeError::NoAdmissibleBraking { s0 })
    }

    fn intended_within(traj: &Trajectory, lim: &Limits, sa: f64, sb: f64) -> bool {
        if sb <= sa {
            return true;
        }
        let tol = 1.0 + LIMIT_REL_TOL;
        (0..traj.dof()).all(|i| {
            let d = traj.joint_derivs(i, sa, sb);
            d.r[1].abs_max() <= lim.v[i] * tol
                && d.r[2].abs_max() <= lim.a[i] * tol
                && d.r[3].abs_max() <= lim.j[i] * tol
        })
    }

    fn follow_to_end(traj: &Trajectory, s0: f64) -> Self {
        let t = traj.duration().max(s0);
        let mut phases = [Phase::default(); 5];
        phases[0] = Phase {
            tau: 0.0,
            s: s0,
            sd: 1.0,
            sdd: 0.0,
            sddd: 0.0,
        };
        phases[1] = Phase {
            tau: t - s0,
            s: t,
            sd: 0.0,
            sdd: 0.0,
            sddd: 0.0,
        };
        Self {
            kind: FailsafeKind::FollowToEnd,
            s0,
            delay: t - s0,
            jerk: 0.0,
            acc: 0.0,
            stop_time: t - s0,
            s_stop: t,
            phases,
            nphases: 2,
            dof: traj.dof(),
        }
    }

    fn window(
        traj: &Trajectory,
        sa: f64,
        sb: f64,
        n: usize,
        hints: &mut [usize; MAX_DOF],
    ) -> Window {
        let mut w = Window {
            q1: [0.0; MAX_DOF],
            q2: [0.0; MAX_DOF],
            q3: [0.0; MAX_DOF],
        };
        for i in 0..n {
            let d = traj.joint_derivs_hint(i, &mut hints[i], sa, sb);
            w.q1[i] = d.r[1].abs_max();
            w.q2[i] = d.r[2].abs_max();
            w.q3[i] = d.r[3].abs_max();
        }
        w
    }

    /// A verified braking from `sb`, or the joint whose margin blocked it (if one did).
    fn try_brake(
        traj: &Trajectory,
        lim: &Limits,
        s0: f64,
        sb: f64,
        n: usize,
        max_brake: f64,
        hints: &mut [usize; MAX_DOF],
    ) -> Result<Self, Option<usize>> {
        let big_t = traj.duration();
        let moving = traj.end() == EndCondition::Moving;
        // Initial window from the point values at sb (cheap estimate of the braking distance);
        // a joint without acceleration margin at sb already rejects this start (the window
        // contains sb, so the window check would reject it too).
        let mut wlen = {
            let mut a0 = A_CAP;
            let mut j0 = J_CAP;
            for i in 0..n {
                let (_, v, a) = traj.joint_at_hint(i, &mut hints[i], sb);
                if a.abs() >= lim.a[i] && v != 0.0 {
                    return Err(Some(i));
                }
                if v != 0.0 {
                    a0 = a0.min(((lim.a[i] - a.abs()) / v.abs()).max(1e-3));
                    j0 = j0.min((0.5 * lim.j[i] / v.abs()).max(1e-3));
                }
            }
            let (t1, t2) = if a0 * a0 >= j0 {
                (1.0 / j0.sqrt(), 0.0)
            } else {
                (a0 / j0, 1.0 / a0 - a0 / j0)
            };
            (0.5 * (2.0 * t1 + t2) * 1.25).clamp(1e-4, 0.5)
        };
        for _ in 0..5 {
            if moving && sb + wlen > big_t {
                wlen = big_t - sb;
                if wlen <= 0.0 {
                    return Err(None);
                }
            }
            let w = Self::window(traj, sb, sb + wlen, n, hints);
            let mut a_s = A_CAP;
            for i in 0..n {
                if w.q1[i] > lim.v[i] * (1.0 + LIMIT_REL_TOL) {
                    return Err(Some(i));
                }
                let margin = lim.a[i] - w.q2[i];
                if margin <= 0.0 {
                    return Err(Some(i));
                }
                if w.q1[i] > 0.0 {
                    a_s = a_s.min(SAFETY * margin / w.q1[i]);
                }
                // Leave at least half the jerk margin for J.
                let jm = lim.j[i] - w.q3[i];
                if jm <= 0.0 {
                    return Err(Some(i));
                }
                if w.q2[i] > 0.0 {
                    a_s = a_s.min(0.5 * jm / (3.0 * w.q2[i]));
                }
            }
            let mut j_s = J_CAP;
            for i in 0..n {
                if w.q1[i] > 0.0 {
                    j_s = j_s.min(SAFETY * (lim.j[i] - w.q3[i] - 3.0 * w.q2[i] * a_s) / w.q1[i]);
                }
            }
            if !(a_s > 0.0 && j_s > 0.0) {
                return Err(None);
            }
            let f = Self::braking(s0, sb, a_s, j_s, n);
            let need = f.s_stop - sb;
            if 2.0 * need >= max_brake {
                // Not shorter than the best candidate so far (e.g. following to the end).
                return Err(None);
            }
            if need <= wlen {
                // Sound re-check in outward-rounded interval arithmetic over the window.
                return if Self::verify(&w, lim, a_s, j_s, n) {
                    Ok(f)
                } else {
                    Err(None)
                };
            }
            if moving && sb + need > big_t {
                return Err(None);
            }
            wlen = need * 1.25;
        }
        Err(None)
    }

    fn verify(w: &Window, lim: &Limits, a_s: f64, j_s: f64, n: usize) -> bool {
        let sd = Range { lo: 0.0, hi: 1.0 };
        let sdd = Range { lo: -a_s, hi: 0.0 };
        let sddd = Range { lo: -j_s, hi: j_s };
        (0..n).all(|i| {
            let q1 = Range {
                lo: -w.q1[i],
                hi: w.q1[i],
            };
            let q2 = Range {
                lo: -w.q2[i],
                hi: w.q2[i],
            };
            let q3 = Range {
                lo: -w.q3[i],
                hi: w.q3[i],
            };
            let v = q1.times(sd);
            let a = q1.times(sdd).plus(q2.times(sd.times(sd)));
            let j = q3
                .times(sd.times(sd).times(sd))
                .plus(q2.times(sd).times(sdd).scale(3.0))
                .plus(q1.times(sddd));
            v.abs_max() <= lim.v[i] * (1.0 + LIMIT_REL_TOL)
                && a.abs_max() <= lim.a[i]
                && j.abs_max() <= lim.j[i]
        })
    }

    /// The braking profile: path jerk −J for t1, deceleration −A for t2, +J for t1 (ṡ: 1 → 0).
    fn braking(s0: f64, sb: f64, a_s: f64, j_s: f64, n: usize) -> Self {
        let (t1, t2, a_eff) = if a_s * a_s >= j_s {
            let t1 = 1.0 / j_s.sqrt();
            (t1, 0.0, j_s * t1)
        } else {
            (a_s / j_s, 1.0 / a_s - a_s / j_s, a_s)
        };
        let delay = sb - s0;
        let mut phases = [Phase::default(); 5];
        phases[0] = Phase {
            tau: 0.0,
            s: s0,
            sd: 1.0,
            sdd: 0.0,
            sddd: 0.0,
        };
        phases[1] = Phase {
            tau: delay,
            s: sb,
            sd: 1.0,
            sdd: 0.0,
            sddd: -j_s,
        };
        let (s, sd, _) = phases[1].eval(t1);
        phases[2] = Phase {
            tau: delay + t1,
            s,
            sd,
            sdd: -a_eff,
            sddd: 0.0,
        };
        let (s, sd, _) = phases[2].eval(t2);
        phases[3] = Phase {
            tau: delay + t1 + t2,
            s,
            sd,
            sdd: -a_eff,
            sddd: j_s,
        };
        let brake = 2.0 * t1 + t2;
        let s_stop = sb + 0.5 * brake;
        phases[4] = Phase {
            tau: delay + brake,
            s: s_stop,
            sd: 0.0,
            sdd: 0.0,
            sddd: 0.0,
        };
        Self {
            kind: FailsafeKind::Brake,
            s0,
            delay,
            jerk: j_s,
            acc: a_eff,
            stop_time: delay + brake,
            s_stop,
            phases,
            nphases: 5,
            dof: n,
        }
    }

    /// How it stops.
    pub fn kind(&self) -> FailsafeKind {
        self.kind
    }
    /// Path position (intended time, s) where the failsafe starts.
    pub fn s0(&self) -> f64 {
        self.s0
    }
    /// Time (s) following the intended timing before braking starts.
    pub fn delay(&self) -> f64 {
        self.delay
    }
    /// Path jerk magnitude J (1/s²) and plateau deceleration A (1/s) of the braking (0 for follow-to-end).
    pub fn path_jerk_acc(&self) -> (f64, f64) {
        (self.jerk, self.acc)
    }
    /// Stop time (s) relative to the failsafe start; at rest afterwards.
    pub fn stop_time(&self) -> f64 {
        self.stop_time
    }
    /// Path position where it stops (s, intended time).
    pub fn s_stop(&self) -> f64 {
        self.s_stop
    }
    /// Sound range of joint `i`'s position over the whole failsafe (rad): the intended path's
    /// range over [s0, s_stop].
    pub fn q_range(&self, traj: &Trajectory, i: usize) -> Range {
        traj.joint_derivs(i, self.s0, self.s_stop).r[0]
    }
    /// Sound bound on the distance joint `i` travels from its start position (rad).
    pub fn distance_bound(&self, traj: &Trajectory, i: usize) -> f64 {
        let (q0, _, _) = traj.joint_at(i, self.s0);
        let r = self.q_range(traj, i);
        (r.hi - q0).max(q0 - r.lo).max(0.0)
    }

    #[inline]
    fn phase_index(&self, tau: f64) -> usize {
        let mut k = 0;
        while k + 1 < self.nphases && self.phases[k + 1].tau <= tau {
            k += 1;
        }
        k
    }

    /// Path state (s, ṡ, s̈, s⃛) at relative time τ ≥ 0 (s).
    #[inline]
    pub fn path_at(&self, tau: f64) -> (f64, f64, f64, f64) {
        let tau = tau.max(0.0);
        let k = self.phase_index(tau);
        let p = &self.phases[k];
        let (s, sd, sdd) = p.eval(tau - p.tau);
        (s, sd, sdd, p.sddd)
    }

    /// Joint state at relative time τ (s) by the chain rule on the intended path.
    #[inline]
    pub fn state_at(&self, traj: &Trajectory, tau: f64) -> JointState {
        let (s, sd, sdd, sddd) = self.path_at(tau);
        let d = traj.state_at(s);
        let mut out = JointState::default();
        for i in 0..self.dof {
            let (q1, q2, q3) = (d.dq[i], d.ddq[i], d.dddq[i]);
            out.q[i] = d.q[i];
            out.dq[i] = q1 * sd;
            out.ddq[i] = q1 * sdd + q2 * sd * sd;
            out.dddq[i] = q3 * sd * sd * sd + 3.0 * q2 * sd * sdd + q1 * sddd;
        }
        out
    }

    /// Widen `b` by sound ranges of q, q̇, q̈ over relative [τa, τb] (s).
    pub fn extend_bounds(
        &self,
        traj: &Trajectory,
        ta: f64,
        tb: f64,
        b: &mut crate::trajectory::Bounds,
    ) {
        let ta = ta.max(0.0);
        let tb = tb.max(ta);
        let mut k = self.phase_index(ta);
        loop {
            let p = &self.phases[k];
            let end = if k + 1 < self.nphases {
                self.phases[k + 1].tau
            } else {
                f64::INFINITY
            };
            let (da, db) = (ta.max(p.tau) - p.tau, tb.min(end) - p.tau);
            let (s_a, sd_a, sdd_a) = p.eval(da);
            let (s_b, sd_b, sdd_b) = p.eval(db);
            let pad = |x: f64| 8.0 * f64::EPSILON * (x.abs() + 1.0) + 1e-15;
            let s_r = Range {
                lo: s_a.min(s_b) - pad(s_a),
                hi: s_a.max(s_b) + pad(s_b),
            };
            let sd_r = Range {
                lo: sd_a.min(sd_b) - pad(1.0),
                hi: sd_a.max(sd_b) + pad(1.0),
            };
            let sdd_r = Range {
                lo: sdd_a.min(sdd_b) - pad(sdd_a),
                hi: sdd_a.max(sdd_b) + pad(sdd_b),
            };
            for i in 0..self.dof {
                let d = traj.joint_derivs(i, s_r.lo, s_r.hi);
                b.q[i].union(d.r[0]);
                b.dq[i].union(d.r[1].times(sd_r));
                b.ddq[i].union(d.r[1].times(sdd_r).plus(d.r[2].times(sd_r.times(sd_r))));
            }
            if end > tb || k + 1 >= self.nphases {
                break;
            }
            k += 1;
        }
    }
}
