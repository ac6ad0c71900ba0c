//! `pacs trajectory`: intended trajectory from an action chunk, optionally with a failsafe.
//! Contract: docs/trajectory.md.

use super::{CliError, RobotRef, check_vec, read_json};
use pacs_motion::scaling::PathState;
use pacs_motion::{
    Chunk, EndCondition, JointState, Limits, OutOfLimits, Planner, PlannerConfig, Trajectory,
    brake_plan,
};
use serde::Deserialize;
use serde_json::{Value, json};
use std::path::Path;

/// Largest number of samples one output list may hold.
const MAX_SAMPLES: f64 = 1.0e6;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct StateIn {
    q: Vec<f64>,
    #[serde(default)]
    dq: Option<Vec<f64>>,
    #[serde(default)]
    ddq: Option<Vec<f64>>,
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
enum Mode {
    #[default]
    Chunk,
    SingleAction,
}

fn default_scale() -> f64 {
    1.0
}
fn default_dt() -> f64 {
    0.001
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Input {
    robot: RobotRef,
    state: StateIn,
    chunk: Chunk,
    #[serde(default = "default_scale")]
    limit_scale: f64,
    #[serde(default)]
    mode: Mode,
    #[serde(default = "default_dt")]
    sample_dt: f64,
    /// Uniform cap on the planning acceleration limits (rad/s²), e.g. the paper's 10.
    #[serde(default)]
    max_acc: Option<f64>,
    /// Uniform cap on the planning jerk limits (rad/s³), e.g. the paper's 400.
    #[serde(default)]
    max_jerk: Option<f64>,
    #[serde(default)]
    end: EndCondition,
    #[serde(default)]
    out_of_limits: OutOfLimits,
    #[serde(default)]
    sweeps: Option<usize>,
}

fn positive(field: &str, x: Option<f64>) -> Result<(), CliError> {
    match x {
        Some(v) if !(v.is_finite() && v > 0.0) => Err(CliError::Input(format!(
            "{field}: value {v} must be finite and > 0"
        ))),
        _ => Ok(()),
    }
}

fn sample_count(field: &str, span: f64, dt: f64) -> Result<usize, CliError> {
    let n = (span / dt).ceil();
    if n > MAX_SAMPLES {
        return Err(CliError::Input(format!(
            "{field}: {n} samples exceed the maximum {MAX_SAMPLES}; raise sample_dt"
        )));
    }
    Ok(n.max(0.0) as usize)
}

fn state_json(t: f64, s: &JointState, n: usize) -> Value {
    json!({"t": t, "q": &s.q[..n], "dq": &s.dq[..n], "ddq": &s.ddq[..n], "dddq": &s.dddq[..n]})
}

fn times(t0: f64, t1: f64, dt: f64, count: usize) -> impl Iterator<Item = f64> {
    (0..=count).map(move |k| if k == count { t1 } else { t0 + k as f64 * dt })
}

/// Run `pacs trajectory --input F [--brake-at t]`.
pub fn run(path: &Path, brake_at: Option<f64>) -> Result<Value, CliError> {
    let input: Input = read_json(path)?;
    let robot = super::load_robot(&input.robot, Some(path))?;
    let n = robot.limits().dof();
    check_vec("state.q", &input.state.q, n)?;
    let dq = input.state.dq.clone().unwrap_or_else(|| vec![0.0; n]);
    let ddq = input.state.ddq.clone().unwrap_or_else(|| vec![0.0; n]);
    check_vec("state.dq", &dq, n)?;
    check_vec("state.ddq", &ddq, n)?;
    if !(input.sample_dt.is_finite() && input.sample_dt > 0.0) {
        return Err(CliError::Input(format!(
            "sample_dt: value {} must be finite and > 0",
            input.sample_dt
        )));
    }
    positive("max_acc", input.max_acc)?;
    positive("max_jerk", input.max_jerk)?;
    if let Some(s) = input.sweeps
        && s > 32
    {
        return Err(CliError::Input(format!("sweeps: value {s} must be <= 32")));
    }
    let hw = Limits::from_joint_limits(robot.limits());
    let mut plan_limits = hw
        .scaled(input.limit_scale)
        .map_err(|e| CliError::Input(e.to_string()))?;
    plan_limits = plan_limits.with_uniform_acc_jerk(
        input.max_acc.unwrap_or(f64::INFINITY),
        input.max_jerk.unwrap_or(f64::INFINITY),
    );
    let wp = input
        .chunk
        .waypoints(&input.state.q, robot.limits(), input.out_of_limits)
        .map_err(|e| CliError::Input(e.to_string()))?;
    let start = JointState::new(&input.state.q, &dq, &ddq);
    let mut config = PlannerConfig {
        end: input.end,
        ..PlannerConfig::default()
    };
    if let Some(s) = input.sweeps {
        config.sweeps = s;
    }
    let mut planner = Planner::new(plan_limits, config);
    let traj: Trajectory = match input.mode {
        Mode::Chunk => planner.plan(&start, &wp),
        Mode::SingleAction => planner.plan_single_action(&start, &wp),
    }
    .map_err(|e| CliError::Input(e.to_string()))?;
    let dt = input.sample_dt;
    let count = sample_count("samples", traj.duration(), dt)?;
    let samples: Vec<Value> = times(0.0, traj.duration(), dt, count)
        .map(|t| state_json(t, &traj.state_at(t), n))
        .collect();
    let waypoints: Vec<&[f64]> = (0..=wp.segments()).map(|k| wp.row(k)).collect();
    let mut out = json!({
        "duration": traj.duration(),
        "waypoint_times": traj.waypoint_times(),
        "blended_waypoints": traj.blended(),
        "waypoints": waypoints,
        "samples": samples,
    });
    if let Some(g) = wp.gripper() {
        out["gripper"] = json!(g);
    }
    if let Some(tb) = brake_at {
        let t_end = traj.duration();
        if !(tb.is_finite() && tb >= 0.0 && tb <= t_end) {
            return Err(CliError::Input(format!(
                "--brake-at: value {tb} must lie in [0, {t_end}] s"
            )));
        }
        // The shield's braking (one implementation): the path speed ṡ goes from the intended
        // timing to 0 along the same path, jerk-limited, within the robot's limits. Where the
        // intended motion leaves no margin at t_b (a joint at its acceleration limit), it keeps
        // the intended timing until braking is admissible (`delay`); a trajectory that ends at
        // rest is followed to its end if no later instant admits braking.
        let plan = brake_plan(&traj, &hw, tb).ok_or_else(|| {
            CliError::Input(format!(
                "--brake-at: no admissible braking profile from t = {tb} s within the robot's limits"
            ))
        })?;
        let delay = plan.delay;
        let duration = plan.stop_after();
        let count = sample_count("failsafe samples", duration, dt)?;
        let fsamples: Vec<Value> = times(0.0, duration, dt, count)
            .map(|tau| {
                let p = match plan.profile {
                    Some(b) if tau >= delay => b.eval(tau - delay),
                    _ => PathState::intended((tb + tau).min(tb + delay)),
                };
                let mut v = state_json(tb + tau, &p.joint_state(&traj), n);
                v["s"] = json!(p.s);
                v
            })
            .collect();
        let (acc, jerk) = plan.profile.map_or((0.0, 0.0), |p| p.limits());
        let s_stop = plan.profile.map_or(tb + delay, |p| p.settle_s());
        let q0 = traj.state_at(tb);
        // Sound per-joint bound of how far the robot moves while braking: the path's range over
        // [s(t_b), s_stop], outward rounded.
        let dist: Vec<f64> = (0..n)
            .map(|i| {
                let r = traj.joint_derivs(i, tb, s_stop).r[0];
                (r.hi - q0.q[i]).max(q0.q[i] - r.lo).max(0.0).next_up()
            })
            .collect();
        out["failsafe"] = json!({
            "start_time": tb,
            "stop_time": tb + duration,
            "duration": duration,
            "kind": match (plan.profile.is_some(), delay > 0.0) {
                (false, _) => "follow-to-end",
                (true, true) => "delayed-brake",
                (true, false) => "brake",
            },
            "delay": delay,
            "path_jerk": jerk,
            "path_acc": acc,
            "s_stop": s_stop,
            "distance_bound": dist,
            "limits": "robot",
            "samples": fsamples,
        });
    }
    Ok(out)
}
