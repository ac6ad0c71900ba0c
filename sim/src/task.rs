//! The evaluation tasks: Sorting (SSM), Handover (PFL hand), Feeding (PFL head), the sphere
//! task (SSM against a rolling sphere, a dynamic object) and the crowded task (Sorting with a
//! person reaching across and two rolling spheres at once). Each task fixes a workspace layout
//! (the FR3 on a table top at z = 0, people on the floor at z = [`FLOOR_Z`]), a set of
//! demonstrations (the policy's "training data"), success sub-goals for the tool centre point,
//! and randomised human and object motions per rollout.

use crate::humans::{Bystander, Diner, FLOOR_Z, HumanScript, Offerer, Reacher, Rng};
use crate::objects::{RollingSphere, SimObject, sphere_spec};
use crate::policy::kernel::{MIN_PACE, replay_path};
use crate::policy::{DemoSet, KernelPolicy, Recording};
use pacs_models::object::ObjectContact;
use pacs_models::{ConstraintSpec, HumanModel, RobotModel, default_human, fr3};
use serde::{Deserialize, Serialize};

/// One of the evaluation tasks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TaskKind {
    /// Pick a block and put it into a box while a person reaches across the table (SSM).
    Sorting,
    /// Take a block from a person's hand and put it into the box (PFL hand).
    Handover,
    /// Bring a fork to a seated person's mouth and withdraw it (PFL head).
    Feeding,
    /// Pick and place while a sphere rolls on the table (SSM against the sphere, a dynamic
    /// object; a bystander stands 2 m away).
    Sphere,
    /// Sorting while a person reaches across the table and two spheres roll on it (SSM against
    /// the person and both spheres).
    Crowded,
}

impl TaskKind {
    /// All tasks.
    pub const ALL: [TaskKind; 5] = [
        Self::Sorting,
        Self::Handover,
        Self::Feeding,
        Self::Sphere,
        Self::Crowded,
    ];

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Sorting => "sorting",
            Self::Handover => "handover",
            Self::Feeding => "feeding",
            Self::Sphere => "sphere",
            Self::Crowded => "crowded",
        }
    }
}

impl std::str::FromStr for TaskKind {
    type Err = crate::UnknownName;
    fn from_str(s: &str) -> Result<Self, crate::UnknownName> {
        Self::ALL
            .into_iter()
            .find(|t| t.name() == s)
            .ok_or_else(|| crate::UnknownName {
                kind: "task",
                given: s.into(),
                choices: "sorting, handover, feeding, sphere, crowded".into(),
            })
    }
}

/// Which constraints a safety filter enforces.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ConstraintMode {
    /// SSM for every body part and object.
    Ssm,
    /// The task's PFL thresholds (Handover / Feeding presets; Sorting and the object tasks use
    /// the Handover thresholds, as the paper's PFL variant of its SSM tasks; objects
    /// [`SPHERE_PFL_THRESHOLD`]).
    Pfl,
}

/// A success sub-goal: the tool centre point within `tolerance` (m) of `point` (m).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ToolGoal {
    /// Target (m, world frame).
    pub point: [f64; 3],
    /// Tolerance (m).
    pub tolerance: f64,
    /// Short name ("pick", "place", "mouth", ...).
    pub name: &'static str,
}

impl ToolGoal {
    /// Whether the tool centre point `tool` (m) is within the tolerance of the goal.
    pub fn reached(&self, tool: &[f64; 3]) -> bool {
        let d = (0..3)
            .map(|i| (tool[i] - self.point[i]).powi(2))
            .sum::<f64>();
        d.sqrt() <= self.tolerance
    }
}

/// The success sub-goals of `task`, in order.
pub(crate) fn tool_goals(task: TaskKind) -> Vec<ToolGoal> {
    let (tools, goal_idx) = tool_keyframes(task);
    goal_idx
        .iter()
        .map(|&(k, name, tol)| ToolGoal {
            point: tools[k],
            tolerance: tol,
            name,
        })
        .collect()
}

/// Everything one rollout needs besides the filter.
pub struct Scenario {
    /// Task.
    pub task: TaskKind,
    /// The robot.
    pub robot: RobotModel,
    /// The human model the filter and the audit use.
    pub human: HumanModel,
    /// Ground-truth motion of the human.
    pub script: Box<dyn HumanScript>,
    /// Further people (same human model): the crowded task's passer-by.
    pub others: Vec<Box<dyn HumanScript>>,
    /// Dynamic objects (models, contact under the task's native mode, true motions).
    pub objects: Vec<SimObject>,
    /// The policy (fresh, at the task's start).
    pub policy: DemoSet,
    /// Sub-goals, in order.
    pub goals: Vec<ToolGoal>,
    /// Start configuration (rad).
    pub start: Vec<f64>,
    /// Time limit (s).
    pub max_time: f64,
}

impl Scenario {
    /// The constraint spec for `mode` on this task.
    pub fn spec(&self, mode: ConstraintMode) -> ConstraintSpec {
        constraint_spec(self.task, mode)
    }

    /// Set every object's contact constraint to the one `mode` gives.
    pub fn set_mode(&mut self, mode: ConstraintMode) {
        for o in &mut self.objects {
            o.contact = object_contact(mode);
        }
    }
}

/// The PFL energy threshold (J) of the spheres: the transient hand/finger value of the
/// Handover preset (unconstrained), a stand-in for an object that may be nudged.
pub const SPHERE_PFL_THRESHOLD: f64 = 0.265;

/// The contact the task's objects allow under `mode`: SSM (contact only at rest), or PFL with
/// [`SPHERE_PFL_THRESHOLD`].
pub fn object_contact(mode: ConstraintMode) -> ObjectContact {
    match mode {
        ConstraintMode::Ssm => ObjectContact::Ssm,
        ConstraintMode::Pfl => ObjectContact::Pfl {
            threshold: SPHERE_PFL_THRESHOLD,
        },
    }
}

/// The constraint spec of `task` under `mode`.
pub fn constraint_spec(task: TaskKind, mode: ConstraintMode) -> ConstraintSpec {
    let preset = |n: &str| ConstraintSpec::preset(n).expect("built-in preset");
    match (task, mode) {
        (_, ConstraintMode::Ssm) => preset("sorting"),
        (TaskKind::Feeding, ConstraintMode::Pfl) => preset("feeding"),
        (_, ConstraintMode::Pfl) => preset("handover"),
    }
}

/// The task's own constraint mode (the paper's choice): SSM for Sorting and the object tasks,
/// PFL for Handover and Feeding.
pub fn native_mode(task: TaskKind) -> ConstraintMode {
    match task {
        TaskKind::Sorting | TaskKind::Sphere | TaskKind::Crowded => ConstraintMode::Ssm,
        TaskKind::Handover | TaskKind::Feeding => ConstraintMode::Pfl,
    }
}

/// Tool centre point (m, world) at `q`.
pub fn tool_point(robot: &RobotModel, q: &[f64]) -> [f64; 3] {
    let f = robot.frames(q);
    let p = (f[robot.dof()] * fr3::tcp_in_joint7()).translation.vector;
    [p.x, p.y, p.z]
}

/// Position-only inverse kinematics by damped least squares (numeric Jacobian) from `seed`;
/// joints stay 0.1 rad inside their limits. Returns the configuration and the remaining error (m).
pub fn solve_ik(robot: &RobotModel, seed: &[f64], target: [f64; 3]) -> (Vec<f64>, f64) {
    let n = robot.dof();
    let lim = robot.limits();
    let mut q = seed.to_vec();
    let mut err = f64::INFINITY;
    for _ in 0..200 {
        let p = tool_point(robot, &q);
        let e = [target[0] - p[0], target[1] - p[1], target[2] - p[2]];
        err = (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt();
        if err < 1e-5 {
            break;
        }
        // Numeric Jacobian J (3 × n).
        let h = 1e-6;
        let mut jac = vec![[0.0; 3]; n];
        for (i, col) in jac.iter_mut().enumerate() {
            let mut qh = q.clone();
            qh[i] += h;
            let ph = tool_point(robot, &qh);
            *col = [(ph[0] - p[0]) / h, (ph[1] - p[1]) / h, (ph[2] - p[2]) / h];
        }
        // dq = Jᵀ (J Jᵀ + λ² I)⁻¹ e.
        let mut a = nalgebra::Matrix3::<f64>::identity() * 1e-4;
        for col in &jac {
            let c = nalgebra::Vector3::from(*col);
            a += c * c.transpose();
        }
        let Some(inv) = a.try_inverse() else { break };
        let y = inv * nalgebra::Vector3::from(e);
        for (i, col) in jac.iter().enumerate() {
            let step = (col[0] * y[0] + col[1] * y[1] + col[2] * y[2]).clamp(-0.2, 0.2);
            q[i] = (q[i] + step).clamp(lim.q_min()[i] + 0.1, lim.q_max()[i] - 0.1);
        }
    }
    (q, err)
}

/// Dense joint-space path from `start` through the tool waypoints `tools` (m): the tool moves on
/// straight lines (eased, `counts[k]` samples for segment k), each sample solved by IK seeded
/// with the previous one, so the joint path is continuous and the tool path is what a
/// teleoperator would demonstrate.
fn dense_path(
    robot: &RobotModel,
    start: &[f64],
    tools: &[[f64; 3]],
    counts: &[usize],
) -> Vec<Vec<f64>> {
    dense_path_with_detours(robot, start, tools, counts, &[])
}

/// [`dense_path`] with a detour on segment k: the tool leaves the straight line by
/// `sin(π·e)·detours[k]` (m) at eased progress `e`, so it bends away and back smoothly and
/// still ends on the waypoint (segments without an entry go straight).
pub(crate) fn dense_path_with_detours(
    robot: &RobotModel,
    start: &[f64],
    tools: &[[f64; 3]],
    counts: &[usize],
    detours: &[[f64; 3]],
) -> Vec<Vec<f64>> {
    let mut path = vec![start.to_vec()];
    let mut from = tool_point(robot, start);
    for (k, to) in tools.iter().enumerate() {
        let m = counts[k].max(1);
        let bump = detours.get(k).copied();
        for s in 1..=m {
            let u = s as f64 / m as f64;
            let e = u * u * (3.0 - 2.0 * u);
            let mut target = [
                from[0] + e * (to[0] - from[0]),
                from[1] + e * (to[1] - from[1]),
                from[2] + e * (to[2] - from[2]),
            ];
            if let Some(b) = bump {
                let w = (std::f64::consts::PI * e).sin();
                for i in 0..3 {
                    target[i] += w * b[i];
                }
            }
            let (q, _) = solve_ik(robot, path.last().expect("non-empty"), target);
            path.push(q);
        }
        from = *to;
    }
    path
}

/// A success sub-goal at a tool waypoint: (waypoint index, name, tolerance in m).
pub(crate) type GoalAt = (usize, &'static str, f64);

/// Tool waypoints (m) of a task's demonstration, in order, and the goal names of those that are
/// success sub-goals.
pub(crate) fn tool_keyframes(task: TaskKind) -> (Vec<[f64; 3]>, Vec<GoalAt>) {
    match task {
        TaskKind::Sorting | TaskKind::Sphere | TaskKind::Crowded => (
            vec![
                [0.50, 0.25, 0.25],
                [0.55, 0.25, 0.06],
                [0.58, 0.12, 0.28],
                [0.40, -0.35, 0.22],
            ],
            vec![(1, "pick", 0.03), (3, "place", 0.04)],
        ),
        TaskKind::Handover => (
            vec![
                [0.45, 0.0, 0.35],
                [0.58, 0.0, 0.32],
                [0.48, 0.0, 0.45],
                [0.40, -0.35, 0.22],
            ],
            vec![(1, "grasp", 0.03), (3, "place", 0.04)],
        ),
        TaskKind::Feeding => (
            vec![
                [0.45, 0.0, 0.42],
                [0.62, 0.0, 0.42],
                [0.47, 0.0, 0.52],
                [0.35, 0.15, 0.35],
            ],
            vec![(1, "mouth", 0.025), (3, "retreat", 0.04)],
        ),
    }
}

/// Number of demonstrations per task, and their spread (m) around the nominal tool waypoints.
const DEMOS: usize = 6;
const DEMO_SPREAD: f64 = 0.012;

/// Time between two demonstration samples (s): one sample per policy step (the evaluation's
/// default `EpisodeConfig::policy_dt` is this constant).
pub const DEMO_DT: f64 = 0.033;

/// Samples per tool segment of a dense path from `start` through `tools` (m): the largest joint
/// distance (rad) between consecutive IK keyframes, × 1.5 (the ease's peak speed) / `spacing`
/// (rad per sample), at least `min`.
pub(crate) fn segment_counts(
    robot: &RobotModel,
    start: &[f64],
    tools: &[[f64; 3]],
    spacing: f64,
    min: usize,
) -> Vec<usize> {
    let mut keyframes = vec![start.to_vec()];
    for p in tools {
        let (q, _) = solve_ik(robot, keyframes.last().expect("non-empty"), *p);
        keyframes.push(q);
    }
    keyframes
        .windows(2)
        .map(|w| {
            let d = w[0]
                .iter()
                .zip(&w[1])
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            ((1.5 * d / spacing).ceil() as usize).max(min)
        })
        .collect()
}

/// Build the demonstrations of `task` (deterministic: the same "training data" for every
/// rollout). Joint paths through IK solutions of jittered tool waypoints, eased, ≈ 0.03 rad
/// (0.05 rad for Handover) between samples at most, and never faster than the robot is operated:
/// a demonstration recorded on the robot stays within the acceleration limits it runs at
/// ([`demo_acceleration_limits`]), so a segment whose samples would need more (second
/// differences at [`DEMO_DT`]) is recorded again with proportionally more samples, up to
/// six recordings in all (every task needs at most two; checked by
/// [`within_limits`] in a debug build and by `sim/tests/evaluation.rs`).
pub fn demonstrations(robot: &RobotModel, task: TaskKind) -> Vec<Vec<Vec<f64>>> {
    let (tools, _) = tool_keyframes(task);
    let start = fr3::Q_READY.to_vec();
    // Largest joint step (rad) between demonstration samples (one sample per policy step Δt):
    // the handover partner is approached briskly, as in the paper's handover demonstrations.
    let spacing = if task == TaskKind::Handover {
        0.05
    } else {
        0.03
    };
    // Nominal keyframes and sample counts from the nominal joint distances.
    let mut counts = segment_counts(robot, &start, &tools, spacing, 8);
    // The same jitter for every attempt: only the pace changes.
    let mut rng = Rng::new(0xDE30 + task as u64);
    let jittered: Vec<Vec<[f64; 3]>> = (0..DEMOS)
        .map(|i| {
            tools
                .iter()
                .map(|p| {
                    let j = if i == 0 {
                        [0.0; 3]
                    } else {
                        rng.in_ball(DEMO_SPREAD)
                    };
                    [p[0] + j[0], p[1] + j[1], p[2] + j[2]]
                })
                .collect()
        })
        .collect();
    let a_max = demo_acceleration_limits(robot);
    let mut demos = Vec::new();
    for _ in 0..PACE_ATTEMPTS {
        demos = jittered
            .iter()
            .map(|tools| dense_path(robot, &start, tools, &counts))
            .collect();
        let ratios = acceleration_ratios(&demos, &counts, &a_max);
        if ratios.iter().all(|&r| r <= 1.0) {
            break;
        }
        // Accelerations scale with 1/count² at a given distance (2 % more for the IK's bends).
        for (c, r) in counts.iter_mut().zip(&ratios) {
            if *r > 1.0 {
                *c = ((*c as f64) * r.sqrt() * 1.02).ceil() as usize;
            }
        }
    }
    debug_assert!(
        within_limits(&demos, &a_max),
        "{task:?}: demonstrations still beyond the operated limits after {PACE_ATTEMPTS} recordings"
    );
    demos
}

/// The joint accelerations (rad/s²) a demonstration stays within: the robot's, scaled by the
/// fraction every method here operates it at (the shield's intended limits,
/// `ShieldConfig::intended_acc_fraction`, which keeps a braking reserve; the baselines share
/// them). Demonstrations recorded on the robot as it is operated cannot be faster.
pub fn demo_acceleration_limits(robot: &RobotModel) -> Vec<f64> {
    let fraction = pacs_shield::shield::ShieldConfig::default().intended_acc_fraction;
    robot
        .limits()
        .a_max()
        .iter()
        .map(|a| a * fraction)
        .collect()
}

/// Recordings [`demonstrations`] makes at most, each slower where the last was too fast (the
/// last one is kept; every task's demonstrations are within the limits after at most two).
const PACE_ATTEMPTS: usize = 6;

/// Per tool segment (sample counts `counts`), the largest ratio of a demonstration's joint
/// acceleration (second difference at [`DEMO_DT`]) to the joint's limit `a_max`, over every
/// demonstration; a sample's acceleration counts for the segment it ends and the one after it.
fn acceleration_ratios(demos: &[Vec<Vec<f64>>], counts: &[usize], a_max: &[f64]) -> Vec<f64> {
    // segment[m]: the segment sample m ends (sample 0 is the start).
    let mut segment = vec![0usize];
    for (k, &c) in counts.iter().enumerate() {
        segment.extend(std::iter::repeat_n(k, c.max(1)));
    }
    let mut ratios = vec![0.0f64; counts.len()];
    for d in demos {
        for m in 1..d.len().saturating_sub(1) {
            let r = (0..a_max.len().min(d[m].len()))
                .map(|i| sample_acceleration(&d[m - 1..=m + 1], i) / a_max[i])
                .fold(0.0, f64::max);
            for k in [segment[m], segment[m + 1]] {
                ratios[k] = ratios[k].max(r);
            }
        }
    }
    ratios
}

/// Whether every demonstration of `demos` stays within the joint acceleration limits `a_max`
/// (rad/s², second differences at [`DEMO_DT`]).
pub fn within_limits(demos: &[Vec<Vec<f64>>], a_max: &[f64]) -> bool {
    demos.iter().all(|d| {
        d.windows(3).all(|w| {
            (0..a_max.len().min(w[0].len())).all(|i| sample_acceleration(w, i) <= a_max[i])
        })
    })
}

/// |acceleration| (rad/s²) of joint `i` at the middle of three consecutive demonstration
/// samples `w` (their second difference at [`DEMO_DT`]): the one measure of a demonstration's
/// pace that [`within_limits`] and the re-recording in [`demonstrations`] share.
fn sample_acceleration(w: &[Vec<f64>], i: usize) -> f64 {
    ((w[2][i] - 2.0 * w[1][i] + w[0][i]) / (DEMO_DT * DEMO_DT)).abs()
}

/// [`demonstrations`] computed once per task per process.
fn cached_demonstrations(robot: &RobotModel, task: TaskKind) -> Vec<Vec<Vec<f64>>> {
    use std::collections::HashMap;
    use std::sync::{Mutex, OnceLock};
    type Cache = Mutex<HashMap<TaskKind, Vec<Vec<Vec<f64>>>>>;
    static CACHE: OnceLock<Cache> = OnceLock::new();
    let cache = CACHE.get_or_init(|| Mutex::new(HashMap::new()));
    if let Some(d) = cache.lock().ok().and_then(|c| c.get(&task).cloned()) {
        return d;
    }
    let d = demonstrations(robot, task);
    if let Ok(mut c) = cache.lock() {
        c.insert(task, d.clone());
    }
    d
}

/// Fractions of the recorded pace at which the `kernel-paced` policy also sees every
/// demonstration ([`replay_path`]): half and a quarter, the slow passages a human
/// demonstrator's recordings contain.
pub const REPLAY_PACES: [f64; 2] = [0.5, 0.25];

/// Which replays of its demonstrations a learned policy ([`learned_policy`]) is also trained on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Replays {
    /// None: the demonstrations only (`--policy kernel`).
    None,
    /// Each demonstration at the constant paces [`REPLAY_PACES`] ([`replay_path`];
    /// `kernel-paced`).
    Constant,
    /// Each demonstration with the shield's own braking and resuming along its path
    /// ([`crate::teleop::paced_replay`], the transform `pacs.lerobot.paced_replays` applies to a
    /// user's dataset; `kernel-shield-paced`): one replay with a pause and one with a slow
    /// passage ([`crate::teleop::replay_event`]).
    Shield,
}

/// The two [`Replays::Shield`] replays of a demonstration `path` (one configuration per
/// [`DEMO_DT`]): a pause and a slow passage ([`crate::teleop::replay_event`]), events drawn
/// from `rng`; a replay the planner cannot make is left out. Each with its mean pace (recorded
/// duration over replayed duration, in [`MIN_PACE`]..1).
fn shield_replays(
    robot: &RobotModel,
    path: &[Vec<f64>],
    rng: &mut Rng,
) -> Vec<(Vec<Vec<f64>>, f64)> {
    use crate::teleop::{REPLAY_HOLD, REPLAY_PACE, paced_replay, replay_event};
    let end = (path.len().saturating_sub(1)) as f64 * DEMO_DT;
    let lim = robot.limits();
    (0..2)
        .map(|k| replay_event(end, k, REPLAY_HOLD, REPLAY_PACE, rng))
        .filter_map(|e| paced_replay(path, DEMO_DT, &[e], lim.v_max(), lim.a_max()).ok())
        .filter(|r| r.q.len() > path.len())
        .map(|r| {
            let pace = ((path.len() - 1) as f64 / (r.q.len() - 1) as f64).clamp(MIN_PACE, 0.999);
            (r.q, pace)
        })
        .collect()
}

/// The policy learned from `task`'s demonstrations ([`KernelPolicy`]), with their replays at
/// [`REPLAY_PACES`] if `paced`; trained once per task per process (the same training data for
/// every rollout; clones share it). Each configuration's stage, recorded or replayed, is the
/// number of sub-goals its tool point has reached, in order, by the episode's own rule (within
/// the goal's tolerance).
pub fn learned_policy(task: TaskKind, replays: Replays) -> KernelPolicy {
    use std::collections::HashMap;
    use std::sync::{Arc, Mutex, OnceLock};
    type Cache = Mutex<HashMap<(TaskKind, Replays), Arc<OnceLock<KernelPolicy>>>>;
    static CACHE: OnceLock<Cache> = OnceLock::new();
    let cache = CACHE.get_or_init(|| Mutex::new(HashMap::new()));
    // One cell per key: concurrent rollouts wait for one training instead of each training.
    let cell = match cache.lock() {
        Ok(mut c) => c.entry((task, replays)).or_default().clone(),
        Err(_) => Arc::new(OnceLock::new()),
    };
    cell.get_or_init(|| train_policy(task, replays)).clone()
}

fn train_policy(task: TaskKind, replays: Replays) -> KernelPolicy {
    let robot = fr3::fr3();
    let goals = tool_goals(task);
    // The episode's rule: sub-goals in order, each reached within its tolerance.
    let stages = |path: &[Vec<f64>]| -> Vec<usize> {
        let mut stage = 0;
        path.iter()
            .map(|q| {
                let tool = tool_point(&robot, q);
                while goals.get(stage).is_some_and(|g| g.reached(&tool)) {
                    stage += 1;
                }
                stage
            })
            .collect()
    };
    let paces: &[f64] = if replays == Replays::Constant {
        &REPLAY_PACES
    } else {
        &[]
    };
    let mut rng = Rng::new(0x5EED_0000 + task as u64);
    let mut recordings = Vec::new();
    for (demonstration, path) in cached_demonstrations(&robot, task).into_iter().enumerate() {
        if replays == Replays::Shield {
            for (replay, pace) in shield_replays(&robot, &path, &mut rng) {
                recordings.push(Recording {
                    stages: stages(&replay),
                    path: replay,
                    demonstration,
                    pace,
                });
            }
        }
        for &pace in paces {
            let replay = replay_path(&path, pace).expect("REPLAY_PACES within [MIN_PACE, 1]");
            recordings.push(Recording {
                stages: stages(&replay),
                path: replay,
                demonstration,
                pace,
            });
        }
        recordings.push(Recording {
            stages: stages(&path),
            path,
            demonstration,
            pace: 1.0,
        });
    }
    KernelPolicy::train(&recordings, HORIZON, EXECUTE)
        .expect("DEMOS ≥ 2 well-formed demonstrations")
}

/// Chunk parameters of the paper's policies: H = 16 actions, h = 8 executed.
pub const HORIZON: usize = 16;
/// Executed actions per chunk.
pub const EXECUTE: usize = 8;

/// The scenario of rollout `seed` of `task`; `with_human: false` keeps the person (or sphere)
/// far away (the paper's speed ablation "w/o human").
pub fn scenario(task: TaskKind, seed: u64, with_human: bool) -> Scenario {
    let robot = fr3::fr3();
    let demos = cached_demonstrations(&robot, task);
    let (tools, _) = tool_keyframes(task);
    let goals = tool_goals(task);
    let mut rng = Rng::new(seed.wrapping_mul(7919).wrapping_add(task as u64 + 1));
    let start: Vec<f64> = fr3::Q_READY
        .iter()
        .map(|q| q + rng.range(-0.015, 0.015))
        .collect();
    let human = default_human()
        .with_uncertainty(0.01, 0.1, 0.03)
        .expect("valid uncertainty");
    let away = 3.0;
    // A sphere rolling on the table around `center` (x, y) ± `spread` (m); far away without
    // people and objects.
    let sphere = |rng: &mut Rng, id: &str, center: [f64; 2], spread: [f64; 2]| {
        let circle = rng.uniform() < 0.5;
        let script = RollingSphere {
            center: [
                if with_human {
                    center[0] + rng.range(-spread[0], spread[0])
                } else {
                    away
                },
                center[1] + rng.range(-spread[1], spread[1]),
                0.05,
            ],
            radius: if circle {
                rng.range(0.12, 0.2)
            } else {
                -rng.range(0.15, 0.3)
            },
            omega: rng.range(0.8, 1.6),
            phase: rng.range(0.0, std::f64::consts::TAU),
        };
        SimObject::new(
            id,
            sphere_spec(),
            object_contact(native_mode(task)),
            Box::new(script),
        )
        .expect("valid sphere")
    };
    let reacher = |rng: &mut Rng| {
        let y = rng.range(-0.25, 0.3);
        let t0 = rng.range(0.3, 2.0);
        let stand = [if with_human { 1.05 } else { away }, y];
        let reach = [rng.range(0.62, 0.72), y + rng.range(-0.1, 0.1) - 0.1, 0.04];
        let dwell = rng.range(1.0, 2.5);
        Reacher {
            stand,
            reach: if with_human {
                reach
            } else {
                [away - 0.1, y - 0.25, FLOOR_Z + 0.95]
            },
            times: [t0 + 1.2, t0 + 1.2, t0 + 2.0 + dwell],
        }
    };
    let (script, objects, max_time): (Box<dyn HumanScript>, Vec<SimObject>, f64) = match task {
        TaskKind::Sorting => (Box::new(reacher(&mut rng)), vec![], 20.0),
        TaskKind::Handover => {
            let g = tools[1];
            let offer = [
                g[0] + 0.11 + rng.range(-0.01, 0.01),
                g[1] + rng.range(-0.01, 0.01),
                g[2] + rng.range(-0.01, 0.01),
            ];
            let script = Offerer {
                stand: [if with_human { 1.0 } else { away }, 0.1],
                offer: if with_human {
                    offer
                } else {
                    [away - 0.05, -0.15, FLOOR_Z + 0.95]
                },
                t_offer: rng.range(0.0, 1.0),
                sway: rng.range(0.0, 0.015),
            };
            (Box::new(script), vec![], 20.0)
        }
        TaskKind::Feeding => {
            let m = tools[1];
            let head = [m[0] + 0.21, m[1], m[2] + 0.02];
            let script = Diner {
                seat: [if with_human { head[0] + 0.1 } else { away }, 0.0],
                head: if with_human {
                    head
                } else {
                    [away, 0.0, FLOOR_Z + 1.2]
                },
                lean: [rng.range(-0.04, 0.0), rng.range(-0.02, 0.02), 0.0],
                times: [rng.range(0.5, 3.0), rng.range(6.0, 9.0)],
            };
            (Box::new(script), vec![], 60.0)
        }
        TaskKind::Sphere => {
            let ball = sphere(&mut rng, "sphere", [0.55, 0.025], [0.05, 0.125]);
            (Box::new(Bystander { at: [2.0, 0.5] }), vec![ball], 20.0)
        }
        TaskKind::Crowded => {
            let person = reacher(&mut rng);
            let a = sphere(&mut rng, "sphere-a", [0.55, 0.025], [0.05, 0.125]);
            let b = sphere(&mut rng, "sphere-b", [0.45, -0.2], [0.03, 0.05]);
            (Box::new(person), vec![a, b], 20.0)
        }
    };
    // The crowded task's second person: a passer-by who walks up to the table, reaches across
    // it toward the sorting area and walks away (far away without people).
    let others: Vec<Box<dyn HumanScript>> = match task {
        TaskKind::Crowded => {
            // 1.3 m in at least 1.5 s: at most 1.3 m/s at the ease's peak.
            let arrive = rng.range(1.5, 3.0);
            let reach = arrive + rng.range(0.5, 2.0);
            let leave = reach + rng.range(1.5, 3.0);
            let passer_by = crate::humans::WalkIn {
                reach: if with_human {
                    [rng.range(0.5, 0.65), rng.range(0.15, 0.3), FLOOR_Z + 0.95]
                } else {
                    [away, 1.0, FLOOR_Z + 0.95]
                },
                times: if with_human {
                    [arrive, reach, leave]
                } else {
                    [1e6, 1e6, 1e6]
                },
            };
            vec![Box::new(passer_by)]
        }
        _ => vec![],
    };
    let policy = DemoSet::new(demos, HORIZON, EXECUTE, seed);
    Scenario {
        task,
        robot,
        human,
        script,
        others,
        objects,
        policy,
        goals,
        start,
        max_time,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Distance (rad, max-norm) from `q` to the polyline `path`.
    fn distance_to_path(path: &[Vec<f64>], q: &[f64]) -> f64 {
        path.windows(2)
            .map(|w| {
                // The closest point of the segment in the Euclidean sense, then the max-norm.
                let d: Vec<f64> = w[1].iter().zip(&w[0]).map(|(b, a)| b - a).collect();
                let len2: f64 = d.iter().map(|x| x * x).sum();
                let u = if len2 > 0.0 {
                    let dot: f64 = q
                        .iter()
                        .zip(&w[0])
                        .zip(&d)
                        .map(|((q, a), d)| (q - a) * d)
                        .sum();
                    (dot / len2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                w[0].iter()
                    .zip(&d)
                    .zip(q)
                    .map(|((a, d), q)| (a + u * d - q).abs())
                    .fold(0.0, f64::max)
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// Every task's demonstrations get their two shield replays (a pause, a slow passage): each
    /// longer than its recording, from its first to its last configuration through the
    /// recording's own configurations (every sample within 1e-9 rad of the recorded polyline),
    /// within the FR3's operated limits, and with a mean pace in [MIN_PACE, 1).
    #[test]
    fn shield_replays_follow_their_demonstration() {
        let robot = fr3::fr3();
        let lim = robot.limits();
        for task in TaskKind::ALL {
            let mut rng = Rng::new(7);
            for path in cached_demonstrations(&robot, task) {
                let replays = shield_replays(&robot, &path, &mut rng);
                assert_eq!(replays.len(), 2, "{task:?}");
                for (q, pace) in replays {
                    assert!(q.len() > path.len() && (MIN_PACE..1.0).contains(&pace));
                    assert_eq!(q.first(), path.first());
                    let last = q.last().expect("non-empty");
                    let end = path.last().expect("non-empty");
                    assert!(last.iter().zip(end).all(|(a, b)| (a - b).abs() < 1e-9));
                    for r in &q {
                        assert!(distance_to_path(&path, r) < 1e-9, "{task:?}: off the path");
                    }
                    assert!(crate::teleop::within_operated_limits(
                        &q,
                        DEMO_DT,
                        lim.v_max(),
                        lim.a_max()
                    ));
                }
            }
        }
    }

    /// `kernel-shield-paced` is trained on the recordings and their shield replays: a paced
    /// model, and another model than `kernel`'s.
    #[test]
    fn the_shield_paced_policy_sees_its_replays() {
        let plain = learned_policy(TaskKind::Sorting, Replays::None);
        let shield = learned_policy(TaskKind::Sorting, Replays::Shield);
        assert!(!plain.paced() && shield.paced());
        let cv = |p: &KernelPolicy| p.cross_validation().map(|(_, e)| e).collect::<Vec<_>>();
        assert_ne!(cv(&plain), cv(&shield));
    }
}
