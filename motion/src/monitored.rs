//! Monitored trajectory: the intended motion for one safety step α_s from t0, then the failsafe
//! from there. State and sound bounds queries over absolute time; building one costs a failsafe
//! construction and allocates nothing.

use crate::error::FailsafeError;
use crate::failsafe::Failsafe;
use crate::trajectory::{Bounds, JointState, Limits, Trajectory};

/// Default safety step α_s (s).
pub const DEFAULT_SAFETY_STEP: f64 = 0.001;

/// Intended motion on [t0, t0 + α_s], then a verified path-consistent failsafe to standstill.
#[derive(Debug, Clone, Copy)]
pub struct Monitored<'a> {
    traj: &'a Trajectory,
    t0: f64,
    t_switch: f64,
    failsafe: Failsafe,
}

impl<'a> Monitored<'a> {
    /// Build from the intended trajectory at time `t0` (s) with safety step `alpha` (s), the
    /// failsafe verified against `lim` (normally the robot's hardware limits).
    pub fn new(
        traj: &'a Trajectory,
        t0: f64,
        alpha: f64,
        lim: &Limits,
    ) -> Result<Self, FailsafeError> {
        let t_switch = t0 + alpha.max(0.0);
        let failsafe = Failsafe::new(traj, t_switch, lim)?;
        Ok(Self {
            traj,
            t0,
            t_switch,
            failsafe,
        })
    }
    /// Start time t0 (s).
    pub fn start_time(&self) -> f64 {
        self.t0
    }
    /// Time where the failsafe takes over, t0 + α_s (s).
    pub fn switch_time(&self) -> f64 {
        self.t_switch
    }
    /// Absolute time (s) of standstill.
    pub fn stop_time(&self) -> f64 {
        self.t_switch + self.failsafe.stop_time()
    }
    /// The failsafe part.
    pub fn failsafe(&self) -> &Failsafe {
        &self.failsafe
    }
    /// The intended trajectory it follows.
    pub fn intended(&self) -> &'a Trajectory {
        self.traj
    }
    /// Exact state at absolute time `t` (s): intended before the switch, failsafe after.
    pub fn state_at(&self, t: f64) -> JointState {
        if t <= self.t_switch {
            self.traj.state_at(t)
        } else {
            self.failsafe.state_at(self.traj, t - self.t_switch)
        }
    }
    /// Sound ranges of q, q̇, q̈ per joint over absolute [ta, tb] (s).
    pub fn bounds(&self, ta: f64, tb: f64) -> Bounds {
        let tb = tb.max(ta);
        let mut b = Bounds::default();
        if ta <= self.t_switch {
            b = self.traj.bounds(ta, tb.min(self.t_switch));
        }
        if tb > self.t_switch {
            self.failsafe.extend_bounds(
                self.traj,
                ta.max(self.t_switch) - self.t_switch,
                tb - self.t_switch,
                &mut b,
            );
        }
        b
    }
    /// Consecutive intervals [t_k, t_(k+1)] of length `dt` (s; last one shorter) covering
    /// [t0, stop time]; empty for dt ≤ 0.
    pub fn intervals(&self, dt: f64) -> impl Iterator<Item = (f64, f64)> + use<> {
        let (t0, t1) = (self.t0, self.stop_time());
        let n = if dt > 0.0 && t1 > t0 {
            ((t1 - t0) / dt).ceil() as usize
        } else {
            0
        };
        (0..n).map(move |k| (t0 + k as f64 * dt, (t0 + (k + 1) as f64 * dt).min(t1)))
    }
}
