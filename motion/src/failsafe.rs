//! The whole-trajectory failsafe of `pacs trajectory --brake-at`: the earliest stop along the
//! path from an intended instant, by the shield's path-speed braking ([`crate::scaling`]).

use crate::scaling::{PathState, SpeedProfile, admissible};
use crate::trajectory::{EndCondition, Limits, Trajectory};

/// A failsafe from intended time `t_b`: follow the intended timing for `delay` s, then the
/// shield's path-speed braking (`profile`), or, with no profile, follow the intended trajectory
/// to its end (where it is at rest).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BrakePlan {
    /// Time (s) the intended timing is followed before braking starts.
    pub delay: f64,
    /// The path-speed braking profile from `t_b + delay`; `None`: follow the trajectory to its
    /// end, where it is at rest.
    pub profile: Option<SpeedProfile>,
}

impl BrakePlan {
    /// Time (s) from `t_b` until the robot is at rest: `delay` plus the profile's settle time.
    pub fn stop_after(&self) -> f64 {
        self.delay + self.profile.map_or(0.0, |p| p.settle_time())
    }
}

/// The earliest-stopping failsafe from intended time `tb` (s) on `traj` within the limits `hw`.
///
/// Guarantee: every candidate is the shield's braking from `tb + δ`, admitted by
/// [`admissible`] (jerk-limited, within `hw` along the path), δ over a growing grid (0, 1, 3, 7,
/// 15, … ms) up to the trajectory's end; for a trajectory that ends at rest, following it to its
/// end is also a candidate. Of these, the one that stops first is returned (the earlier δ on
/// ties); `None` if no candidate exists (an instant where the intended motion leaves no
/// acceleration margin admits no braking, and one with little margin only a slow one).
pub fn brake_plan(traj: &Trajectory, hw: &Limits, tb: f64) -> Option<BrakePlan> {
    let end = traj.duration();
    let mut best = (traj.end() == EndCondition::AtRest).then_some(BrakePlan {
        delay: end - tb,
        profile: None,
    });
    let (mut delay, mut step) = (0.0, 1e-3);
    loop {
        let s = (tb + delay).min(end);
        if best.as_ref().is_some_and(|b| s - tb >= b.stop_after()) {
            break;
        }
        if let Some(p) = admissible(traj, hw, PathState::intended(s), 0.0, None) {
            let cand = BrakePlan {
                delay: s - tb,
                profile: Some(p),
            };
            if best
                .as_ref()
                .is_none_or(|b| cand.stop_after() < b.stop_after())
            {
                best = Some(cand);
            }
        }
        if s >= end {
            break;
        }
        delay += step;
        step *= 2.0;
    }
    best
}
