//! One rollout: a filter, a policy, a scripted human; ground-truth safety metrics computed with
//! exact geometry against the true human (not the measurements).

use crate::humans::{Camera, HumanScript};
use crate::policy::{ChunkPolicy, DemoSet, Demonstration};
use crate::task::{ToolGoal, tool_point};
use nalgebra::Point3;
use pacs_audit::{AuditConfig, Auditor};
use pacs_log::{Header, LogModels, ModelRef};
use pacs_models::{ConstraintSpec, HumanModel, RobotModel, TaskConstraints};
use pacs_motion::chunk::{ActionKind, Chunk};
use pacs_reach::geometry::segment_distance_lower_bound;
use pacs_shield::FilterKind;
use pacs_shield::shield::ShieldError;
use pacs_shield::shield_log::ShieldLog;
use serde::Serialize;

/// Which safety filter runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// No filter (intended trajectories, never brake).
    Off,
    /// PACS with chunk trajectories.
    Pacs,
    /// PACS planning each action as its own stop-at-target motion.
    SingleAction,
    /// Control barrier function.
    Cbf,
    /// The standard policy setup without time parameterisation (the paper's H4 baseline): each
    /// action is sent as a position target every Δt to a jerk-limited low-level controller that
    /// moves to it from its current state (no safety filter).
    Direct,
}

impl std::str::FromStr for Method {
    type Err = crate::UnknownName;
    fn from_str(s: &str) -> Result<Self, crate::UnknownName> {
        match s {
            "off" => Ok(Self::Off),
            "pacs" => Ok(Self::Pacs),
            "single-action" => Ok(Self::SingleAction),
            "cbf" => Ok(Self::Cbf),
            "direct" => Ok(Self::Direct),
            o => Err(crate::UnknownName {
                kind: "method",
                given: o.into(),
                choices: "off, pacs, single-action, cbf, direct".into(),
            }),
        }
    }
}

impl Method {
    /// The online filter this method runs (`Direct` runs OFF: its actions go straight to the
    /// controller, one target every Δt).
    pub fn filter_kind(self) -> FilterKind {
        match self {
            Method::Off | Method::Direct => FilterKind::Off,
            Method::Pacs => FilterKind::Pacs,
            Method::SingleAction => FilterKind::SingleAction,
            Method::Cbf => FilterKind::Cbf,
        }
    }
}

/// Episode settings.
#[derive(Debug, Clone, Copy)]
pub struct EpisodeConfig {
    /// Safety step (s).
    pub dt: f64,
    /// Policy period Δt (s): one action per Δt; a new chunk every h·Δt.
    pub policy_dt: f64,
    /// Time limit (s).
    pub max_time: f64,
    /// Goal tolerance (rad, max over joints).
    pub goal_tolerance: f64,
    /// Camera period (s).
    pub camera_period: f64,
    /// Noise seed.
    pub seed: u64,
    /// Amplitude (rad) of the simulated joint tracking error: the robot's actual joints deviate
    /// from the commanded ones by a smooth per-joint sinusoid (0.2–1 Hz) of this amplitude. With
    /// 5e-4 rad every point of the FR3 (lever arms ≤ 1.2 m, 7 joints) stays within 4.2 mm of its
    /// commanded position, inside the shield's 5 mm tracking-error margin, and every joint speed
    /// within 5e-4·2π ≈ 0.0031 rad/s of the commanded one, inside the shield's 0.004 rad/s
    /// velocity tracking margin.
    pub tracking_error: f64,
}

impl Default for EpisodeConfig {
    fn default() -> Self {
        Self {
            dt: 0.001,
            policy_dt: 0.033,
            max_time: 8.0,
            goal_tolerance: 0.02,
            camera_period: 0.01,
            seed: 1,
            tracking_error: 5e-4,
        }
    }
}

/// One recorded step.
#[derive(Debug, Clone, Serialize)]
pub struct Sample {
    /// Time (s).
    pub t: f64,
    /// Joint positions (rad).
    pub q: Vec<f64>,
    /// Joint velocities (rad/s).
    pub dq: Vec<f64>,
    /// True minimum separation between moving robot links and the human (m; ≤ 0: contact).
    pub separation: f64,
    /// Ground-truth violation at this step.
    pub violation: bool,
    /// Robot kinetic energy (J, nominal).
    pub energy: f64,
    /// Filter verified its intended step.
    pub verified: bool,
    /// Tool centre point (m).
    pub tool: [f64; 3],
    /// Tool speed (m/s, finite difference over the recording period).
    pub tool_speed: f64,
}

/// Result of one episode.
#[derive(Debug, Clone, Serialize)]
pub struct Episode {
    /// Method.
    pub method: Method,
    /// Method label as given (e.g. `pacs-pfl`).
    pub variant: String,
    /// Human script name.
    pub human: String,
    /// Task constraint preset.
    pub task: String,
    /// Reached the goal within the time limit.
    pub success: bool,
    /// Success and no ground-truth violation.
    pub safe_success: bool,
    /// Fraction of steps with a ground-truth violation at the sampled states (exact geometry
    /// against the true human).
    pub violation_fraction: f64,
    /// Offline audit of the rollout against the ground-truth human (the paper's "Safety Viol."),
    /// when requested.
    pub truth_audit: Option<TruthAudit>,
    /// Sub-goals reached, in order.
    pub goals_reached: usize,
    /// Chunks the policy produced out of its training distribution.
    pub ood_chunks: usize,
    /// Time to reach the goal (s), or the time limit.
    pub duration: f64,
    /// Smallest true separation (m).
    pub min_separation: f64,
    /// Largest joint-space deviation from the demonstration (rad).
    pub max_deviation: f64,
    /// Fraction of steps where the filter verified its intended step.
    pub verified_fraction: f64,
    /// Mean tool speed while moving toward the goals (m/s): tool path length / duration.
    pub mean_tool_speed: f64,
    /// Recorded steps (every `record_every`-th).
    #[serde(skip)]
    pub samples: Vec<Sample>,
}

/// The offline audit of a rollout against the true human motion (sampled every safety step,
/// no measurement error, no delay). `certain_fraction` is the paper's "Safety Viol." (steps whose
/// recorded state violates); `violation_fraction` adds the steps where the audit cannot exclude
/// a violation between samples (its bound assumes only the joint limits between 1 ms samples).
#[derive(Debug, Clone, Serialize)]
pub struct TruthAudit {
    /// Verdict.
    pub verdict: pacs_audit::Verdict,
    /// Robot samples in violation / samples.
    pub violation_fraction: f64,
    /// Robot samples in a certain violation / samples.
    pub certain_fraction: f64,
}

/// A success sub-goal of an episode.
#[derive(Debug, Clone, PartialEq)]
pub enum Goal {
    /// Every joint within `tolerance` (rad) of `q`.
    Joint {
        /// Target (rad).
        q: Vec<f64>,
        /// Tolerance (rad).
        tolerance: f64,
    },
    /// The tool centre point within the goal's tolerance.
    Tool(ToolGoal),
}

impl Goal {
    fn reached(&self, q: &[f64], tool: &[f64; 3]) -> bool {
        match self {
            Goal::Joint { q: g, tolerance } => {
                q.iter().zip(g).all(|(a, b)| (a - b).abs() <= *tolerance)
            }
            Goal::Tool(g) => {
                let d = (0..3).map(|i| (tool[i] - g.point[i]).powi(2)).sum::<f64>();
                d.sqrt() <= g.tolerance
            }
        }
    }
}

/// What an episode runs: models, ground truth, policy and goals (borrowed).
pub struct Setup<'a> {
    /// Robot.
    pub robot: &'a RobotModel,
    /// Human (or object) model used by the filter.
    pub human: &'a HumanModel,
    /// Constraints the filter enforces (and the ground truth is scored against).
    pub spec: &'a ConstraintSpec,
    /// Ground-truth motion.
    pub script: &'a dyn HumanScript,
    /// The policy.
    pub policy: &'a mut DemoSet,
    /// Sub-goals in order; success when all are reached.
    pub goals: &'a [Goal],
    /// Start configuration at rest (rad).
    pub start: &'a [f64],
    /// Method label (e.g. `pacs-pfl`).
    pub label: &'a str,
    /// Task name.
    pub task: &'a str,
    /// Time limit (s).
    pub max_time: f64,
}

/// Optional outputs of an episode.
#[derive(Default)]
pub struct Outputs<'a> {
    /// Write the run as an audit log (format v1, the measurements the filter received).
    pub log: Option<&'a mut dyn std::io::Write>,
    /// Keep every n-th step in [`Episode::samples`] (0: none).
    pub record_every: usize,
    /// Audit the run against the ground-truth human ([`Episode::truth_audit`]).
    pub truth_audit: bool,
}

/// Joint speed (rad/s) up to which the robot counts as at rest: the audit's default
/// `rest_speed` (a robot holding position under a controller is never exactly still).
pub const REST_SPEED: f64 = 0.02;

/// Smooth bounded tracking error: per joint `amp · sin(2π f t + φ)`, f ∈ [0.2, 1] Hz.
struct Tracking {
    amp: f64,
    freq: Vec<f64>,
    phase: Vec<f64>,
}

impl Tracking {
    fn new(amp: f64, n: usize, seed: u64) -> Self {
        let mut rng = crate::humans::Rng::new(seed ^ 0x7AC4);
        let freq = (0..n).map(|_| 0.2 + 0.8 * rng.uniform()).collect();
        let phase = (0..n)
            .map(|_| std::f64::consts::TAU * rng.uniform())
            .collect();
        Self { amp, freq, phase }
    }
    /// Actual joint positions and velocities for commanded ones at time `t`.
    fn apply(&self, t: f64, q: &mut [f64], dq: &mut [f64]) {
        for i in 0..q.len() {
            let w = std::f64::consts::TAU * self.freq[i];
            let a = w * t + self.phase[i];
            q[i] += self.amp * a.sin();
            dq[i] += self.amp * w * a.cos();
        }
    }
}

/// Ground truth at (q, q̇) under the ISO/TS 15066 rule of [`pacs_verify::iso15066`]: minimum
/// separation of the robot's links (the fixed base included) to the true human, and whether a
/// constraint is violated (SSM: contact while some joint moves faster than [`REST_SPEED`]; PFL:
/// contact with the whole robot's kinetic energy ½q̇ᵀM(q)q̇ above the body part's threshold, the
/// constrained one if the part touches links on two different frames or a clampable body part
/// touches it). Returns (separation, violation, kinetic energy).
pub fn ground_truth(
    robot: &RobotModel,
    human: &HumanModel,
    tc: &TaskConstraints,
    q: &[f64],
    dq: &[f64],
    kp: &[[f64; 3]],
) -> (f64, bool, f64) {
    use pacs_verify::iso15066::{frames_can_pinch, threshold};
    let caps = robot.capsules_world(q);
    let energy = robot.kinetic_energy(q, dq);
    let moving = dq.iter().any(|v| v.abs() > REST_SPEED);
    let part_cap = |bp: &pacs_models::human::BodyPart| {
        (
            Point3::from(kp[bp.from]),
            Point3::from(kp[bp.to]),
            bp.thickness / 2.0,
        )
    };
    let parts = human.body_parts();
    let mut sep = f64::INFINITY;
    let mut violation = false;
    for (b, bp) in parts.iter().enumerate() {
        let (a, c, r) = part_cap(bp);
        let mut touched: Option<usize> = None;
        let mut pinched = false;
        for (li, cap) in &caps {
            let frame = robot.links()[*li].frame;
            let d = segment_distance_lower_bound(&a, &c, &cap.p1(), &cap.p2()) - cap.radius() - r;
            sep = sep.min(d);
            if d <= 0.0 {
                match touched {
                    Some(f) if frames_can_pinch(f, frame) => pinched = true,
                    Some(_) => {}
                    None => touched = Some(frame),
                }
            }
        }
        if touched.is_none() || !moving {
            continue;
        }
        let clamped = pinched
            || parts.iter().enumerate().any(|(o, op)| {
                let (oa, oc, orad) = part_cap(op);
                human.clampable(b, o)
                    && segment_distance_lower_bound(&a, &c, &oa, &oc) - r - orad <= 0.0
            });
        if energy > threshold(tc.per_part[b], clamped) {
            violation = true;
        }
    }
    (sep, violation, energy)
}

/// The audit-log header of an episode (models inline, `meta` with task, policy, filter, human).
pub fn log_header(
    label: &str,
    robot: &RobotModel,
    human: &HumanModel,
    spec: &ConstraintSpec,
    script: &dyn HumanScript,
) -> Header {
    let mut h = Header::new(
        ModelRef::Spec(Box::new(robot.spec().clone())),
        ModelRef::Spec(Box::new(human.spec().clone())),
        ModelRef::Spec(Box::new(spec.clone())),
    );
    h.meta.insert("task".into(), spec.name.clone().into());
    h.meta.insert("policy".into(), "nn-demonstration".into());
    h.meta.insert("filter".into(), label.into());
    h.meta.insert("human".into(), script.name().into());
    h
}

/// Run one episode from the demonstration's start at rest (single-demonstration policy, success
/// at the demonstration's last configuration within `cfg.goal_tolerance`).
#[allow(clippy::too_many_arguments)]
pub fn run(
    method: Method,
    robot: &RobotModel,
    human: &HumanModel,
    spec: &ConstraintSpec,
    script: &dyn HumanScript,
    demo: &Demonstration,
    cfg: &EpisodeConfig,
    record_every: usize,
) -> Result<Episode, ShieldError> {
    run_logged(
        method,
        robot,
        human,
        spec,
        script,
        demo,
        cfg,
        record_every,
        None,
    )
}

/// [`run`], also writing the run as an audit log (format v1) to `log` when given.
#[allow(clippy::too_many_arguments)]
pub fn run_logged(
    method: Method,
    robot: &RobotModel,
    human: &HumanModel,
    spec: &ConstraintSpec,
    script: &dyn HumanScript,
    demo: &Demonstration,
    cfg: &EpisodeConfig,
    record_every: usize,
    log: Option<&mut dyn std::io::Write>,
) -> Result<Episode, ShieldError> {
    let mut policy = DemoSet::from_demonstration(demo);
    let goals = [Goal::Joint {
        q: demo.goal().to_vec(),
        tolerance: cfg.goal_tolerance,
    }];
    let label = serde_json::to_value(method)
        .ok()
        .and_then(|v| v.as_str().map(String::from))
        .unwrap_or_default();
    let setup = Setup {
        robot,
        human,
        spec,
        script,
        policy: &mut policy,
        goals: &goals,
        start: &demo.path()[0],
        label: &label,
        task: &spec.name,
        max_time: cfg.max_time,
    };
    run_setup(
        method,
        setup,
        cfg,
        Outputs {
            log,
            record_every,
            truth_audit: false,
        },
    )
}

fn invalid(e: impl std::fmt::Display) -> ShieldError {
    ShieldError::Invalid(e.to_string())
}

/// Run one episode of `setup` with `method` (Algorithm 1: a chunk every h·Δt, a safety step
/// every `cfg.dt`; [`Method::Direct`] sends each action as a target every Δt instead).
pub fn run_setup(
    method: Method,
    setup: Setup<'_>,
    cfg: &EpisodeConfig,
    out: Outputs<'_>,
) -> Result<Episode, ShieldError> {
    let Setup {
        robot,
        human,
        spec,
        script,
        policy,
        goals,
        start,
        label,
        task,
        max_time,
    } = setup;
    let Outputs {
        log,
        record_every,
        truth_audit,
    } = out;
    let mut log = match log {
        Some(w) => {
            let h = log_header(label, robot, human, spec, script);
            let mut l = ShieldLog::new(w, &h, 0.0, start).map_err(invalid)?;
            l.event(0.0, "episode_start").map_err(invalid)?;
            Some(l)
        }
        None => None,
    };
    let mut auditor = if truth_audit {
        let models = LogModels {
            robot: robot.clone(),
            human: human.with_uncertainty(0.0, 0.0, 0.0).map_err(invalid)?,
            constraints: spec.clone(),
            environment: vec![],
        };
        Some(Auditor::new(models, AuditConfig::default()).map_err(invalid)?)
    } else {
        None
    };
    let tc = spec.resolve(human).map_err(invalid)?;
    let mut filter = method.filter_kind().build(robot, human, spec)?;
    filter.start(0.0, start)?;
    let mut camera = Camera::new(cfg.camera_period, cfg.seed);
    let tracking = Tracking::new(cfg.tracking_error, robot.dof(), cfg.seed);
    let n = robot.dof();
    let steps = (max_time / cfg.dt).round() as usize;
    let action_every = (cfg.policy_dt / cfg.dt).round().max(1.0) as usize;
    let chunk_every = policy.execute * action_every;
    let (mut q, mut dq) = (start.to_vec(), vec![0.0; n]);
    let (mut violations, mut verified, mut min_sep, mut max_dev) =
        (0usize, 0usize, f64::INFINITY, 0.0f64);
    let mut next_goal = 0usize;
    let mut success_at = None;
    let mut samples = Vec::new();
    let mut steps_run = 0usize;
    let mut waypoints: Vec<Vec<f64>> = Vec::new();
    let mut tool = tool_point(robot, &q);
    let mut last_rec_tool = tool;
    let mut prev_tool = tool;
    let mut path_len = 0.0;
    tracking.apply(0.0, &mut q, &mut dq);
    if let Some(a) = auditor.as_mut() {
        a.push_human(0.0, 0.0, &script.keypoints(0.0))
            .map_err(invalid)?;
        a.push_robot(0.0, &q, Some(&dq)).map_err(invalid)?;
    }
    for k in 0..steps {
        steps_run += 1;
        let t = k as f64 * cfg.dt;
        if method == Method::Direct {
            if k % chunk_every == 0 {
                let c = policy.chunk(&q);
                waypoints.clear();
                let mut w = q.clone();
                for a in c.actions.iter().take(c.execute) {
                    w.iter_mut().zip(a).for_each(|(x, d)| *x += d);
                    waypoints.push(w.clone());
                }
            }
            if k % action_every == 0 {
                let i = (k % chunk_every) / action_every;
                if let Some(target) = waypoints.get(i) {
                    let c = Chunk {
                        kind: ActionKind::Absolute,
                        actions: vec![target.clone()],
                        execute: 1,
                        gripper: None,
                    };
                    let _ = filter.set_chunk(t, &c);
                }
            }
        } else if k % chunk_every == 0 {
            let c = policy.chunk(&q);
            let _ = filter.set_chunk(t, &c); // an unplannable chunk is ignored by the filter
        }
        let m = camera.measure(human, script, t);
        let cmd = filter.step(t, m.as_ref())?;
        if let Some(l) = log.as_mut() {
            l.record(t, m.as_ref(), &cmd).map_err(invalid)?;
        }
        q.copy_from_slice(&cmd.state.q[..n]);
        dq.copy_from_slice(&cmd.state.dq[..n]);
        tracking.apply(cmd.t, &mut q, &mut dq);
        let truth = script.keypoints(cmd.t);
        if let Some(a) = auditor.as_mut() {
            a.push_human(cmd.t, cmd.t, &truth).map_err(invalid)?;
            a.push_robot(cmd.t, &q, Some(&dq)).map_err(invalid)?;
        }
        let (sep, viol, energy) = ground_truth(robot, human, &tc, &q, &dq, &truth);
        tool = tool_point(robot, &q);
        min_sep = min_sep.min(sep);
        max_dev = max_dev.max(policy.deviation(&q));
        violations += viol as usize;
        verified += cmd.diag.verified as usize;
        while next_goal < goals.len() && goals[next_goal].reached(&q, &tool) {
            next_goal += 1;
        }
        if success_at.is_none() && next_goal == goals.len() {
            success_at = Some(cmd.t);
        }
        let dist =
            |a: &[f64; 3], b: &[f64; 3]| (0..3).map(|i| (a[i] - b[i]).powi(2)).sum::<f64>().sqrt();
        if success_at.is_none() {
            path_len += dist(&tool, &prev_tool);
        }
        prev_tool = tool;
        if record_every > 0 && k % record_every == 0 {
            let speed = if k == 0 {
                0.0
            } else {
                dist(&tool, &last_rec_tool) / (record_every as f64 * cfg.dt)
            };
            last_rec_tool = tool;
            samples.push(Sample {
                t: cmd.t,
                q: q.clone(),
                dq: dq.clone(),
                separation: sep,
                violation: viol,
                energy,
                verified: cmd.diag.verified,
                tool,
                tool_speed: speed,
            });
        }
        if success_at.is_some_and(|ts| cmd.t > ts + 0.2) {
            break;
        }
    }
    let steps_run = steps_run.max(1) as f64;
    let success = success_at.is_some();
    let t_end = steps_run * cfg.dt;
    if let Some(mut l) = log {
        l.event(t_end, if success { "success" } else { "failure" })
            .map_err(invalid)?;
        l.finish().map_err(invalid)?;
    }
    let truth_audit = auditor.map(|mut a| {
        a.push_event(if success { "success" } else { "failure" });
        let r = a.finish("ground-truth", serde_json::Map::new());
        let samples = r.metrics.samples.max(1) as f64;
        TruthAudit {
            verdict: r.verdict,
            violation_fraction: r.metrics.violation_fraction,
            certain_fraction: r.metrics.certain_violating_samples as f64 / samples,
        }
    });
    let duration = success_at.unwrap_or(max_time);
    Ok(Episode {
        method,
        variant: label.into(),
        human: script.name().into(),
        task: task.into(),
        success,
        safe_success: success
            && violations == 0
            && truth_audit
                .as_ref()
                .is_none_or(|a| a.certain_fraction == 0.0),
        violation_fraction: violations as f64 / steps_run,
        truth_audit,
        goals_reached: next_goal,
        ood_chunks: policy.ood_chunks(),
        duration,
        min_separation: min_sep,
        max_deviation: max_dev,
        verified_fraction: verified as f64 / steps_run,
        mean_tool_speed: path_len / duration.max(1e-9),
        samples,
    })
}
