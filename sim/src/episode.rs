//! One rollout: a filter, a policy, a scripted human and scripted objects; ground-truth safety
//! metrics computed with exact geometry against the true human and objects (not the
//! measurements).

mod rollout;
mod scoring;

pub use rollout::run_setup;
pub use scoring::{ground_truth, object_ground_truth};

use crate::SimError;
use crate::humans::HumanScript;
use crate::objects::SimObject;
use crate::policy::{DemoSet, Demonstration};
use crate::task::ToolGoal;
use pacs_baselines::FilterKind;
use pacs_log::{Header, ModelRef};
use pacs_models::{ConstraintSpec, HumanModel, RobotModel};
use pacs_shield::ChunkMotion;
use serde::{Deserialize, Serialize};

/// Which safety filter runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
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
            Method::Off => FilterKind::Off,
            Method::Direct => FilterKind::Direct,
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
    /// How chunk filters move across chunks, and when they get the next one:
    /// [`ChunkMotion::Stop`] every h·Δt (the policy's clock); [`ChunkMotion::Continuous`] when
    /// the current chunk's last waypoint is one safety step away (the robot runs each chunk at
    /// its own time-optimal pace and hands over moving), and at the latest every h·Δt (a
    /// braking or stopped robot still gets fresh chunks). The direct baseline sends an action
    /// every Δt either way.
    pub chunk_motion: ChunkMotion,
}

impl Default for EpisodeConfig {
    fn default() -> Self {
        Self {
            dt: 0.001,
            policy_dt: crate::task::DEMO_DT,
            max_time: 8.0,
            goal_tolerance: 0.02,
            camera_period: 0.01,
            seed: 1,
            tracking_error: 5e-4,
            chunk_motion: ChunkMotion::Stop,
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
    /// True minimum separation between robot links and the human or an object (m; ≤ 0:
    /// contact).
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
#[derive(Debug, Clone, Serialize, Deserialize)]
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
    /// [`pacs_audit::verdict::safe_success`] with the ground truth as evidence: success and no
    /// violation against the true human (and objects).
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
    /// Chunks the filter could not plan (ignored; the robot kept its verified motion).
    pub chunks_rejected: usize,
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
#[derive(Debug, Clone, Serialize, Deserialize)]
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
            Goal::Tool(g) => g.reached(tool),
        }
    }
}

/// What an episode runs: models, ground truth, policy and goals (borrowed).
pub struct Setup<'a> {
    /// Robot.
    pub robot: &'a RobotModel,
    /// Human model used by the filter.
    pub human: &'a HumanModel,
    /// Constraints the filter enforces (and the ground truth is scored against).
    pub spec: &'a ConstraintSpec,
    /// Ground-truth motion.
    pub script: &'a dyn HumanScript,
    /// Further people (same human model), each measured by its own camera, logged with its id
    /// and checked by the filter and the truth audit.
    pub others: &'a [Box<dyn HumanScript>],
    /// Dynamic objects (each with its model, contact and true motion).
    pub objects: &'a [SimObject],
    /// The policy.
    pub policy: &'a mut dyn crate::policy::TaskPolicy,
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
    /// Write the run as an audit log (format v1, or v2 with several people: the measurements the
    /// filter received).
    pub log: Option<&'a mut dyn std::io::Write>,
    /// Keep every n-th step in [`Episode::samples`] (0: none).
    pub record_every: usize,
    /// Audit the run against the ground-truth human ([`Episode::truth_audit`]).
    pub truth_audit: bool,
}

/// Joint speed (rad/s) up to which the robot counts as at rest: the audit's default
/// `rest_speed` (a robot holding position under a controller is never exactly still).
pub const REST_SPEED: f64 = 0.02;

/// The id of person `i` of a scene with several people (`human0`, `human1`, …: the filter's
/// order; the Python `Shield` names unnamed people the same way).
pub fn person_id(i: usize) -> String {
    format!("human{i}")
}

/// The audit-log header of an episode (models inline, objects with their contact, `meta` with
/// task, policy, filter, human).
#[allow(clippy::too_many_arguments)]
pub fn log_header(
    label: &str,
    task: &str,
    robot: &RobotModel,
    human: &HumanModel,
    spec: &ConstraintSpec,
    script: &dyn HumanScript,
    objects: &[SimObject],
    others: usize,
    policy: &str,
) -> Header {
    let robot_ref = ModelRef::Spec(Box::new(robot.spec().clone()));
    let human_ref = ModelRef::Spec(Box::new(human.spec().clone()));
    let spec_ref = ModelRef::Spec(Box::new(spec.clone()));
    let mut h = if others == 0 {
        Header::new(robot_ref, human_ref, spec_ref)
    } else {
        // Several people: ids `human0`, `human1`, … (the filter's order).
        let people = (0..=others)
            .map(|i| pacs_log::PersonEntry {
                id: person_id(i),
                human: human_ref.clone(),
            })
            .collect();
        Header::with_people(robot_ref, people, spec_ref)
    };
    h.objects = objects
        .iter()
        .map(|o| pacs_log::ObjectEntry {
            id: o.id.clone(),
            object: ModelRef::Spec(Box::new(o.spec.clone())),
            contact: o.contact,
        })
        .collect();
    // The task (`crowded`, `sphere`, ...), not its constraint preset's name (`sorting` for
    // every SSM task): the fleet report groups runs by it.
    h.meta.insert("task".into(), task.into());
    h.meta.insert("policy".into(), policy.into());
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
) -> Result<Episode, SimError> {
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
) -> Result<Episode, SimError> {
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
        others: &[],
        objects: &[],
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
