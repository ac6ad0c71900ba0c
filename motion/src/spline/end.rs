//! The velocity a Moving chunk ends with: the pace its waypoints continue with, capped where its
//! predicted actions pause or turn back by the speed from which it can still stop in time.

use super::SplineSolver;
use crate::chunk::Waypoints;
use crate::trajectory::Limits;

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

/// Fraction of the room the predicted actions leave before a pause or turn within which a Moving
/// chunk must be able to stop at its end (see `end_velocity`). The next chunk brakes on a spline
/// whose jerk is constant per segment: its deceleration ramps up and down instead of holding the
/// limit, which on average halves it and doubles the stopping distance of the time-optimal
/// profile that `stopping_velocity` assumes. With the whole room the robot reached
/// the pauses of the simulation's demonstrations too fast: the next chunk could not stop in
/// time, rang 20–90 mrad past the pause and took 0.6–0.9 s; with half the room the tasks without
/// people run 8–18 % faster.
const PAUSE_ROOM_FRACTION: f64 = 0.5;

impl SplineSolver {
    /// Velocities (rad/s) at q̂_h for a Moving end, into `v_end`, with `t_last` (s) the duration
    /// of the last segment. Without a lookahead: the last segment's mean velocity. With q̂_{h+1}
    /// ([`Waypoints::lookahead`]): the central difference (q̂_{h+1} − q̂_{h−1})/(t_last·(1 + r)),
    /// assuming the pace continues (r = |q̂_{h+1} − q̂_h| / |q̂_h − q̂_{h−1}|, clamped to
    /// [0.25, 4]), so that the next chunk starts close to the velocity it continues with.
    pub(super) fn end_velocity(&mut self, lim: &Limits, wp: &Waypoints, t_last: f64) {
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
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::chunk::{ActionKind, Chunk, OutOfLimits};
    use crate::trajectory::{EndCondition, JointState};
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
