//! One rollout: a filter, a policy, a scripted human; ground-truth safety metrics computed with
//! exact geometry against the true human (not the measurements).

use crate::humans::{Camera, HumanScript};
use crate::policy::{ChunkPolicy, Demonstration};
use nalgebra::Point3;
use pacs_models::{ConstraintSpec, HumanModel, RobotModel, TaskConstraints};
use pacs_reach::geometry::segment_distance_lower_bound;
use pacs_verify::audit::log::{Header, ModelRef};
use pacs_verify::cbf::{CbfConfig, CbfFilter};
use pacs_verify::shield::{Command, FilterMode, Shield, ShieldConfig, ShieldError};
use pacs_verify::shield_log::ShieldLog;
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
}

impl std::str::FromStr for Method {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "off" => Ok(Self::Off),
            "pacs" => Ok(Self::Pacs),
            "single-action" => Ok(Self::SingleAction),
            "cbf" => Ok(Self::Cbf),
            o => Err(format!(
                "unknown method `{o}` (off, pacs, single-action, cbf)"
            )),
        }
    }
}

/// The filter behind a common interface.
pub enum Filter {
    /// A shield (PACS, OFF or single-action).
    Shield(Box<Shield>),
    /// The CBF baseline.
    Cbf(Box<CbfFilter>),
}

impl Filter {
    /// Build a filter for `method`.
    pub fn new(
        method: Method,
        robot: &RobotModel,
        human: &HumanModel,
        spec: &ConstraintSpec,
    ) -> Result<Self, ShieldError> {
        Ok(match method {
            Method::Cbf => Filter::Cbf(Box::new(CbfFilter::new(
                robot.clone(),
                Some(human.clone()),
                CbfConfig::default(),
            )?)),
            m => {
                let cfg = ShieldConfig {
                    mode: if m == Method::Off {
                        FilterMode::Off
                    } else {
                        FilterMode::Pacs
                    },
                    single_action: m == Method::SingleAction,
                    ..ShieldConfig::default()
                };
                Filter::Shield(Box::new(Shield::new(
                    robot.clone(),
                    Some((human.clone(), spec)),
                    vec![],
                    cfg,
                )?))
            }
        })
    }
    fn start(&mut self, t: f64, q: &[f64]) -> Result<(), ShieldError> {
        match self {
            Filter::Shield(s) => s.start(t, q),
            Filter::Cbf(c) => c.start(t, q),
        }
    }
    fn set_chunk(&mut self, t: f64, chunk: &pacs_verify::chunk::Chunk) -> Result<(), ShieldError> {
        match self {
            Filter::Shield(s) => s.set_chunk(chunk),
            Filter::Cbf(c) => c.set_chunk(t, chunk),
        }
    }
    fn step(&mut self, t: f64, m: Option<&pacs_reach::human::HumanMeasurement>) -> Command {
        match self {
            Filter::Shield(s) => s.step(t, m),
            Filter::Cbf(c) => c.step(t, m),
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
}

/// Result of one episode.
#[derive(Debug, Clone, Serialize)]
pub struct Episode {
    /// Method.
    pub method: Method,
    /// Human script name.
    pub human: String,
    /// Task constraint preset.
    pub task: String,
    /// Reached the goal within the time limit.
    pub success: bool,
    /// Success and no ground-truth violation.
    pub safe_success: bool,
    /// Fraction of steps with a ground-truth violation (the paper's "Safety Viol.").
    pub violation_fraction: f64,
    /// Time to reach the goal (s), or the time limit.
    pub duration: f64,
    /// Smallest true separation (m).
    pub min_separation: f64,
    /// Largest joint-space deviation from the demonstration (rad).
    pub max_deviation: f64,
    /// Fraction of steps where the filter verified its intended step.
    pub verified_fraction: f64,
    /// Recorded steps (every `record_every`-th).
    #[serde(skip)]
    pub samples: Vec<Sample>,
}

/// Ground truth at (q, q̇): minimum separation of moving links to the true human, and whether a
/// constraint is violated (SSM: contact while moving; PFL: contact with the energy of the sub-chain
/// up to the contacting link above the unconstrained threshold).
pub fn ground_truth(
    robot: &RobotModel,
    human: &HumanModel,
    tc: &TaskConstraints,
    q: &[f64],
    dq: &[f64],
    kp: &[[f64; 3]],
) -> (f64, bool, f64) {
    let caps = robot.capsules_world(q);
    let mut energies = vec![0.0; robot.dof() + 1];
    robot.subchain_energies_into(q, dq, &mut energies);
    let moving = dq.iter().any(|v| v.abs() > 1e-9);
    let mut sep = f64::INFINITY;
    let mut violation = false;
    for (b, bp) in human.body_parts().iter().enumerate() {
        let (a, c) = (Point3::from(kp[bp.from]), Point3::from(kp[bp.to]));
        for (li, cap) in &caps {
            let frame = robot.links()[*li].frame;
            if frame == 0 {
                continue;
            }
            let d = segment_distance_lower_bound(&a, &c, &cap.p1(), &cap.p2())
                - cap.radius()
                - bp.thickness / 2.0;
            sep = sep.min(d);
            if d <= 0.0 && moving {
                let threshold = tc.per_part[b].threshold(false);
                if energies[frame] > threshold {
                    violation = true;
                }
            }
        }
    }
    (sep, violation, energies[robot.dof()])
}

/// Run one episode from the demonstration's start at rest.
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

/// The audit-log header of an episode (models inline, `meta` with task, policy, filter, human).
pub fn log_header(
    method: Method,
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
    h.meta.insert(
        "filter".into(),
        serde_json::to_value(method).unwrap_or_default(),
    );
    h.meta.insert("human".into(), script.name().into());
    h
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
    let mut log = match log {
        Some(w) => {
            let h = log_header(method, robot, human, spec, script);
            let mut l = ShieldLog::new(w, &h, 0.0, &demo.path()[0])
                .map_err(|e| ShieldError::Invalid(e.to_string()))?;
            l.event(0.0, "episode_start")
                .map_err(|e| ShieldError::Invalid(e.to_string()))?;
            Some(l)
        }
        None => None,
    };
    let tc = spec
        .resolve(human)
        .map_err(|e| ShieldError::Invalid(e.to_string()))?;
    let mut filter = Filter::new(method, robot, human, spec)?;
    let q0 = demo.path()[0].clone();
    filter.start(0.0, &q0)?;
    let mut policy = demo.clone();
    let mut camera = Camera::new(cfg.camera_period, cfg.seed);
    let n = robot.dof();
    let steps = (cfg.max_time / cfg.dt).round() as usize;
    let chunk_every = ((policy.execute as f64 * cfg.policy_dt) / cfg.dt)
        .round()
        .max(1.0) as usize;
    let (mut q, mut dq) = (q0.clone(), vec![0.0; n]);
    let (mut violations, mut verified, mut min_sep, mut max_dev) =
        (0usize, 0usize, f64::INFINITY, 0.0f64);
    let mut success_at = None;
    let mut samples = Vec::new();
    let mut steps_run = 0usize;
    for k in 0..steps {
        steps_run += 1;
        let t = k as f64 * cfg.dt;
        if k % chunk_every == 0 {
            let c = policy.chunk(&q);
            let _ = filter.set_chunk(t, &c); // an unplannable chunk is ignored by the filter
        }
        let m = camera.measure(human, script, t);
        let cmd = filter.step(t, m.as_ref());
        if let Some(l) = log.as_mut() {
            l.record(t, m.as_ref(), &cmd)
                .map_err(|e| ShieldError::Invalid(e.to_string()))?;
        }
        q.copy_from_slice(&cmd.state.q[..n]);
        dq.copy_from_slice(&cmd.state.dq[..n]);
        let (sep, viol, energy) =
            ground_truth(robot, human, &tc, &q, &dq, &script.keypoints(cmd.t));
        min_sep = min_sep.min(sep);
        max_dev = max_dev.max(demo.deviation(&q));
        violations += viol as usize;
        verified += cmd.diag.verified as usize;
        if success_at.is_none()
            && q.iter()
                .zip(demo.goal())
                .all(|(a, b)| (a - b).abs() <= cfg.goal_tolerance)
        {
            success_at = Some(cmd.t);
        }
        if record_every > 0 && k % record_every == 0 {
            samples.push(Sample {
                t: cmd.t,
                q: q.clone(),
                dq: dq.clone(),
                separation: sep,
                violation: viol,
                energy,
                verified: cmd.diag.verified,
            });
        }
        if success_at.is_some_and(|ts| cmd.t > ts + 0.2) {
            break;
        }
    }
    let steps_run = steps_run.max(1) as f64;
    let success = success_at.is_some();
    if let Some(mut l) = log {
        let t_end = steps_run * cfg.dt;
        l.event(t_end, if success { "success" } else { "failure" })
            .map_err(|e| ShieldError::Invalid(e.to_string()))?;
        l.finish()
            .map_err(|e| ShieldError::Invalid(e.to_string()))?;
    }
    Ok(Episode {
        method,
        human: script.name().into(),
        task: spec.name.clone(),
        success,
        safe_success: success && violations == 0,
        violation_fraction: violations as f64 / steps_run,
        duration: success_at.unwrap_or(cfg.max_time),
        min_separation: min_sep,
        max_deviation: max_dev,
        verified_fraction: verified as f64 / steps_run,
        samples,
    })
}
