//! Shared helpers for the pacs-verify integration tests.
#![allow(dead_code)]

use pacs_models::RobotModel;
use pacs_motion::{JointState, Limits, Trajectory};

pub fn fr3() -> RobotModel {
    RobotModel::builtin("fr3").expect("fr3")
}

/// FR3 hardware limits and the paper's planning limits (a = 10 rad/s², j = 400 rad/s³).
pub fn limits() -> (Limits, Limits) {
    let hw = Limits::from_joint_limits(fr3().limits());
    (hw, hw.with_uniform_acc_jerk(10.0, 400.0))
}

/// Left limit of joint i's (q, q̇, q̈) at time t (evaluated on the piece that ends at t).
pub fn left_limit(traj: &Trajectory, i: usize, t: f64) -> (f64, f64, f64) {
    let ps = traj.pieces(i);
    let k = ps.partition_point(|p| p.t < t).max(1) - 1;
    ps[k].eval(t - ps[k].t)
}

/// Dense sample times over [0, T_rest] (the stopping tail of a Moving trajectory included): a grid
/// of `n` points plus every piece boundary and its neighbours.
pub fn sample_times(traj: &Trajectory, n: usize) -> Vec<f64> {
    let t_end = traj.rest_time();
    let mut ts: Vec<f64> = (0..=n).map(|k| t_end * k as f64 / n as f64).collect();
    for i in 0..traj.dof() {
        for p in traj.pieces(i) {
            if p.t <= t_end {
                ts.extend([p.t, (p.t - 1e-7).max(0.0), (p.t + 1e-7).min(t_end)]);
            }
        }
    }
    ts
}

/// Assert |x| ≤ lim·(1 + 1e-9) (the stated tolerance).
pub fn within(x: f64, lim: f64, what: &str) {
    assert!(x.abs() <= lim * (1.0 + 1e-9), "{what}: |{x}| > {lim}");
}

/// Assert every limit at the sample times (positions with 1e-9 rad).
pub fn assert_limits_at_samples(traj: &Trajectory, lim: &Limits, n: usize) {
    for t in sample_times(traj, n) {
        let s: JointState = traj.state_at(t);
        for i in 0..traj.dof() {
            assert!(
                s.q[i] >= lim.q_min[i] - 1e-9 && s.q[i] <= lim.q_max[i] + 1e-9,
                "q[{i}] = {} at t = {t}",
                s.q[i]
            );
            within(s.dq[i], lim.v[i], &format!("dq[{i}] at t = {t}"));
            within(s.ddq[i], lim.a[i], &format!("ddq[{i}] at t = {t}"));
            within(s.dddq[i], lim.j[i], &format!("dddq[{i}] at t = {t}"));
        }
    }
}

/// A replanned trajectory starts exactly (1e-12) at the state `s` it was planned from: q, q̇, q̈
/// of all seven joints.
pub fn assert_starts_at(traj: &Trajectory, s: &JointState) {
    let s2 = traj.state_at(0.0);
    for i in 0..7 {
        assert!((s2.q[i] - s.q[i]).abs() <= 1e-12, "q[{i}]");
        assert!((s2.dq[i] - s.dq[i]).abs() <= 1e-12, "dq[{i}]");
        assert!((s2.ddq[i] - s.ddq[i]).abs() <= 1e-12, "ddq[{i}]");
    }
}
