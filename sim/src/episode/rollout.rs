//! The rollout loop of an episode: policy chunks, filter steps, the simulated tracking error, the
//! camera, the log and the truth audit, and the episode's result.

use super::{
    Episode, EpisodeConfig, Goal, Method, Outputs, Sample, Setup, TruthAudit, ground_truth,
    log_header, object_ground_truth,
};
use crate::SimError;
use crate::humans::{Camera, HumanScript};
use crate::objects::{ObjectCamera, SimObject};
use crate::policy::{Observation, TaskPolicy};
use crate::task::tool_point;
use pacs_audit::{AuditConfig, Auditor};
use pacs_baselines::SafetyFilter;
use pacs_log::LogModels;
use pacs_models::{HumanModel, RobotModel, TaskConstraints};
use pacs_motion::chunk::{ActionKind, Chunk};
use pacs_reach::human::HumanMeasurement;
use pacs_shield::ChunkMotion;
use pacs_shield::session::MeasurementInbox;
use pacs_shield::shield_log::ShieldLog;
use std::io::Write;

/// The truth audit: one person, or several (one pass each, merged).
enum TruthAuditor {
    One(Box<Auditor>),
    /// The auditor and the people's ids (`human0`, `human1`, …), made once.
    Many(pacs_audit::people::PeopleAuditor, Vec<String>),
}

impl TruthAuditor {
    /// Person `i`'s true keypoints at `t` (s).
    fn push_human(
        &mut self,
        i: usize,
        t: f64,
        kp: &[[f64; 3]],
    ) -> Result<(), pacs_audit::AuditError> {
        match self {
            TruthAuditor::One(a) => a.push_human(t, t, kp),
            TruthAuditor::Many(p, ids) => p.push_human(ids.get(i).map(String::as_str), t, t, kp),
        }
    }
    fn push_object(
        &mut self,
        t: f64,
        t_meas: f64,
        id: &str,
        p: [f64; 3],
        v: Option<[f64; 3]>,
    ) -> Result<(), pacs_audit::AuditError> {
        match self {
            TruthAuditor::One(a) => a.push_object(t, t_meas, id, p, v),
            TruthAuditor::Many(m, _) => m.push_object(t, t_meas, id, p, v),
        }
    }
    fn push_robot(
        &mut self,
        t: f64,
        q: &[f64],
        dq: Option<&[f64]>,
    ) -> Result<(), pacs_audit::AuditError> {
        match self {
            TruthAuditor::One(a) => a.push_robot(t, q, dq),
            TruthAuditor::Many(m, _) => m.push_robot_with_acc(t, q, dq, None),
        }
    }
    fn push_event(&mut self, name: &str) {
        match self {
            TruthAuditor::One(a) => a.push_event(name),
            TruthAuditor::Many(m, _) => m.push_event(name),
        }
    }
    fn finish(self, log: &str) -> pacs_audit::RunResult {
        match self {
            TruthAuditor::One(a) => a.finish(log, serde_json::Map::new()),
            TruthAuditor::Many(m, _) => m.finish(log, serde_json::Map::new()),
        }
    }
}

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

/// [`ChunkMotion::Continuous`]: the next chunk is requested once the current one has less than this many
/// safety steps of intended motion left (the last step before its last waypoint).
const HANDOVER_STEPS: f64 = 1.5;

fn invalid(e: impl Into<SimError>) -> SimError {
    e.into()
}

/// Run one episode of `setup` with `method` (Algorithm 1: a chunk every h·Δt, a safety step
/// every `cfg.dt`; [`Method::Direct`] sends each action as a target every Δt instead).
pub fn run_setup(
    method: Method,
    setup: Setup<'_>,
    cfg: &EpisodeConfig,
    out: Outputs<'_>,
) -> Result<Episode, SimError> {
    let Outputs {
        log,
        record_every,
        truth_audit,
    } = out;
    let mut log = match log {
        Some(w) => Some(start_log(&setup, w)?),
        None => None,
    };
    let mut auditor = if truth_audit {
        Some(TruthAuditor::new(&setup)?)
    } else {
        None
    };
    let tc = setup.spec.resolve(setup.human).map_err(invalid)?;
    let mut filter = start_filter(method, &setup, cfg)?;
    let Setup {
        robot,
        human,
        spec: _,
        script,
        others,
        objects,
        policy,
        goals,
        start,
        label,
        task,
        max_time,
    } = setup;
    let mut cameras = Cameras::new(cfg, others.len(), objects);
    let tracking = Tracking::new(cfg.tracking_error, robot.dof(), cfg.seed);
    let n = robot.dof();
    let steps = (max_time / cfg.dt).round() as usize;
    let action_every = (cfg.policy_dt / cfg.dt).round().max(1.0) as usize;
    let chunk_every = policy.execute() * action_every;
    // Steps since the last chunk (the first chunk is due at once).
    let mut since_chunk = chunk_every;
    let (mut q, mut dq) = (start.to_vec(), vec![0.0; n]);
    // The last command's time (s): the last robot sample of the log, where its closing events go
    // (the log's `end` event must not lie after its last sample).
    let mut last_cmd_t = 0.0f64;
    let mut waypoints: Vec<Vec<f64>> = Vec::new();
    let mut tally = Tally::new(tool_point(robot, &q));
    tracking.apply(0.0, &mut q, &mut dq);
    // The actual joints over the last policy step Δt (one entry per safety step), so that a
    // policy can observe q now and one Δt before (the paper's policies see two timesteps); at
    // rest before the start.
    let mut past = vec![q.clone(); action_every];
    let mut before = q.clone();
    if let Some(a) = auditor.as_mut() {
        let truths = others.iter().map(|o| o.keypoints(0.0));
        a.push_truth(0.0, &script.keypoints(0.0), truths, objects, &q, &dq)?;
    }
    for k in 0..steps {
        tally.steps_run += 1;
        let t = k as f64 * cfg.dt;
        before.copy_from_slice(&past[k % action_every]);
        past[k % action_every].copy_from_slice(&q);
        let direct = method == Method::Direct;
        let chunk_due = if direct {
            k % chunk_every == 0
        } else {
            since_chunk >= chunk_every
                || (cfg.chunk_motion == ChunkMotion::Continuous
                    && since_chunk >= action_every
                    && filter
                        .remaining()
                        .is_some_and(|r| r < HANDOVER_STEPS * cfg.dt))
        };
        // The person as the policy perceives them (only when it is asked for a chunk).
        let (person, person_before) = if chunk_due {
            (
                script.keypoints(t),
                script.keypoints((t - cfg.policy_dt).max(0.0)),
            )
        } else {
            (Vec::new(), Vec::new())
        };
        let obs = Observation {
            q: &q,
            q_before: &before,
            stage: tally.next_goal,
            t,
            person: &person,
            person_before: &person_before,
        };
        if direct {
            let clock = (k, chunk_every, action_every);
            send_direct_target(filter.as_mut(), policy, &obs, &mut waypoints, clock, t);
        } else if chunk_due {
            since_chunk = 0;
            let c = policy.act(&obs);
            // An unplannable chunk is ignored by the filter (counted).
            if filter.set_chunk(t, &c).is_err() {
                tally.chunks_rejected += 1;
            }
        }
        since_chunk += 1;
        let m = cameras.measure(
            human,
            script,
            others,
            objects,
            t,
            filter.as_mut(),
            log.as_mut(),
        )?;
        let cmd = filter.step(t, m)?;
        if let Some(l) = log.as_mut() {
            l.record(t, m, &cmd).map_err(invalid)?;
        }
        last_cmd_t = cmd.t;
        q.copy_from_slice(cmd.q());
        dq.copy_from_slice(cmd.dq());
        tracking.apply(cmd.t, &mut q, &mut dq);
        let truth = script.keypoints(cmd.t);
        let truths: Vec<Vec<[f64; 3]>> = others.iter().map(|o| o.keypoints(cmd.t)).collect();
        if let Some(a) = auditor.as_mut() {
            a.push_truth(cmd.t, &truth, truths.iter(), objects, &q, &dq)?;
        }
        let people = (human, &tc, truth.as_slice(), truths.as_slice());
        let (separation, violation, energy) =
            step_ground_truth(robot, people, objects, cmd.t, &q, &dq);
        let step = Step {
            t: cmd.t,
            q: &q,
            dq: &dq,
            separation,
            violation,
            energy,
            verified: cmd.diag.verified,
        };
        tally.score(robot, goals, &step, policy.deviation(&q));
        if record_every > 0 && k % record_every == 0 {
            tally.record(k, record_every as f64 * cfg.dt, &step);
        }
        if tally.success_at.is_some_and(|ts| cmd.t > ts + 0.2) {
            break;
        }
    }
    let success = tally.success_at.is_some();
    if let Some(mut l) = log {
        l.event(last_cmd_t, if success { "success" } else { "failure" })
            .map_err(invalid)?;
        l.finish().map_err(invalid)?;
    }
    let truth_audit = auditor.map(|a| a.verdict(success));
    Ok(tally.episode(
        method,
        (label, script.name(), task),
        &*policy,
        truth_audit,
        max_time,
    ))
}

/// The episode's log on `w`: the header, then the `episode_start` event.
fn start_log<'w>(
    setup: &Setup<'_>,
    w: &'w mut dyn Write,
) -> Result<ShieldLog<&'w mut dyn Write>, SimError> {
    let h = log_header(
        setup.label,
        setup.task,
        setup.robot,
        setup.human,
        setup.spec,
        setup.script,
        setup.objects,
        setup.others.len(),
        setup.policy.name(),
    );
    let mut l = ShieldLog::new(w, &h, 0.0, setup.start).map_err(invalid)?;
    l.event(0.0, "episode_start").map_err(invalid)?;
    Ok(l)
}

/// The safety filter of `method` for the setup's robot, people and objects, started at rest at
/// `setup.start`.
fn start_filter(
    method: Method,
    setup: &Setup<'_>,
    cfg: &EpisodeConfig,
) -> Result<Box<dyn SafetyFilter + Send>, SimError> {
    let (human, spec) = (setup.human, setup.spec);
    let mut filter = method
        .filter_kind()
        .build_with(setup.robot, human, spec, cfg.chunk_motion)?;
    for o in setup.objects {
        filter.add_object(o.model, o.contact)?;
    }
    for _ in setup.others {
        filter.add_human(human.clone(), spec)?;
    }
    filter.start(0.0, setup.start)?;
    Ok(filter)
}

impl TruthAuditor {
    /// The truth audit of `setup`: the exact human model (no measurement uncertainty) and the
    /// objects' exact models; one pass per person where there are several.
    fn new(setup: &Setup<'_>) -> Result<Self, SimError> {
        let (robot, human, objects, others) =
            (setup.robot, setup.human, setup.objects, setup.others);
        let exact = human.with_uncertainty(0.0, 0.0, 0.0).map_err(invalid)?;
        let models = LogModels {
            robot: robot.clone(),
            people: vec![(pacs_log::V1_PERSON.to_string(), exact.clone())],
            human: exact,
            constraints: setup.spec.clone(),
            environment: vec![],
            objects: objects
                .iter()
                .map(|o| Ok((o.id.clone(), o.exact_model().map_err(invalid)?, o.contact)))
                .collect::<Result<_, SimError>>()?,
        };
        Ok(if others.is_empty() {
            TruthAuditor::One(Box::new(
                Auditor::new(models, AuditConfig::default()).map_err(invalid)?,
            ))
        } else {
            let mut models = models;
            models.people = (0..=others.len())
                .map(|i| (super::person_id(i), models.human.clone()))
                .collect();
            TruthAuditor::Many(
                pacs_audit::people::PeopleAuditor::new(&models, &AuditConfig::default())
                    .map_err(invalid)?,
                models.people.iter().map(|(id, _)| id.clone()).collect(),
            )
        })
    }

    /// The true state at `t` (s): the first person's keypoints `truth`, the other people's
    /// `others` in order, every object's true motion, and the robot's actual `q`, `dq`.
    fn push_truth<K: AsRef<[[f64; 3]]>>(
        &mut self,
        t: f64,
        truth: &[[f64; 3]],
        others: impl Iterator<Item = K>,
        objects: &[SimObject],
        q: &[f64],
        dq: &[f64],
    ) -> Result<(), SimError> {
        self.push_human(0, t, truth).map_err(invalid)?;
        for (i, tr) in others.enumerate() {
            self.push_human(1 + i, t, tr.as_ref()).map_err(invalid)?;
        }
        for o in objects {
            let (p, v) = o.script.state(t);
            self.push_object(t, t, &o.id, p, Some(v)).map_err(invalid)?;
        }
        self.push_robot(t, q, Some(dq)).map_err(invalid)
    }

    /// The audit's verdict, once the episode's `success` or failure event is in.
    fn verdict(mut self, success: bool) -> TruthAudit {
        self.push_event(if success { "success" } else { "failure" });
        let r = self.finish("ground-truth");
        let samples = r.metrics.samples.max(1) as f64;
        TruthAudit {
            verdict: r.verdict,
            violation_fraction: r.metrics.violation_fraction,
            certain_fraction: r.metrics.certain_violating_samples as f64 / samples,
        }
    }
}

/// The cameras of an episode (the first person's, the other people's and the objects') and the
/// measurement inbox that delivers their frames: the one delivery rule of every runner
/// ([`MeasurementInbox`]; the frames arrive at their stamps).
struct Cameras {
    person: Camera,
    others: Vec<Camera>,
    objects: Vec<ObjectCamera>,
    inbox: MeasurementInbox,
}

impl Cameras {
    fn new(cfg: &EpisodeConfig, others: usize, objects: &[SimObject]) -> Self {
        Self {
            person: Camera::new(cfg.camera_period, cfg.seed),
            others: (0..others)
                .map(|i| Camera::new(cfg.camera_period, cfg.seed ^ (0xCA3E + i as u64)))
                .collect(),
            objects: (0..objects.len())
                .map(|i| ObjectCamera::new(cfg.camera_period, cfg.seed ^ (0x0B1E + i as u64)))
                .collect(),
            inbox: MeasurementInbox::new(
                1 + others,
                objects.iter().map(|o| o.id.clone()).collect(),
            ),
        }
    }

    /// Every camera's frame due at `t` (s), delivered through the inbox: the other people's and
    /// the objects' to the filter, each to the log; returns the first person's, for the
    /// filter's step (which logs it with the step's sample).
    #[allow(clippy::too_many_arguments)]
    fn measure<W: Write>(
        &mut self,
        human: &HumanModel,
        script: &dyn HumanScript,
        others: &[Box<dyn HumanScript>],
        objects: &[SimObject],
        t: f64,
        filter: &mut dyn SafetyFilter,
        log: Option<&mut ShieldLog<W>>,
    ) -> Result<Option<&HumanMeasurement>, SimError> {
        for (i, (o, cam)) in others.iter().zip(&mut self.others).enumerate() {
            if let Some(om) = cam.measure(human, o.as_ref(), t) {
                self.inbox.push_person(t, 1 + i, om)?;
            }
        }
        for (i, (o, cam)) in objects.iter().zip(&mut self.objects).enumerate() {
            if let Some(om) = cam.measure(o, t) {
                self.inbox.push_object(t, i, om)?;
            }
        }
        // The first person's last: its record goes beside the step's sample, as the step logs it.
        if let Some(m) = self.person.measure(human, script, t) {
            self.inbox.push_person(t, 0, m)?;
        }
        let due = self.inbox.deliver(t, filter, log)?;
        if let Some(e) = due.log_error {
            return Err(SimError::Log(e));
        }
        Ok(due.first)
    }
}

/// [`Method::Direct`] at safety step `k` of `clock` = (k, steps per chunk, steps per action):
/// a chunk from the policy every chunk, its executed actions integrated into `waypoints` from
/// the current joints, and the next waypoint sent to the filter as a target every action.
fn send_direct_target(
    filter: &mut dyn SafetyFilter,
    policy: &mut dyn TaskPolicy,
    obs: &Observation,
    waypoints: &mut Vec<Vec<f64>>,
    (k, chunk_every, action_every): (usize, usize, usize),
    t: f64,
) {
    if k % chunk_every == 0 {
        let c = policy.act(obs);
        waypoints.clear();
        let mut w = obs.q.to_vec();
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
}

/// The people as the ground truth sees them: the human model, the task's constraints, the first
/// person's and the other people's true keypoints (m).
type PeopleTruth<'a> = (
    &'a HumanModel,
    &'a TaskConstraints,
    &'a [[f64; 3]],
    &'a [Vec<[f64; 3]>],
);

/// The ground truth of the robot's actual state `q`, `dq` at `t` (s): the least separation (m)
/// from every person (`people` = the human model, the task's constraints, the first person's
/// and the other people's true keypoints) and every object, whether any constraint is violated,
/// and the robot's kinetic energy (J).
fn step_ground_truth(
    robot: &RobotModel,
    (human, tc, truth, truths): PeopleTruth<'_>,
    objects: &[SimObject],
    t: f64,
    q: &[f64],
    dq: &[f64],
) -> (f64, bool, f64) {
    let (mut sep, mut viol, energy) = ground_truth(robot, human, tc, q, dq, truth);
    for tr in truths {
        let (s, v, _) = ground_truth(robot, human, tc, q, dq, tr);
        sep = sep.min(s);
        viol |= v;
    }
    if !objects.is_empty() {
        let caps: Vec<_> = robot
            .capsules_world(q)
            .into_iter()
            .map(|(_, c)| c)
            .collect();
        for o in objects {
            let (s, v) = object_ground_truth(o, t, &caps, dq, energy);
            sep = sep.min(s);
            viol |= v;
        }
    }
    (sep, viol, energy)
}

/// One safety step as scored: the command's time (s), the actual joints, the ground truth
/// (separation in m, violation, kinetic energy in J) and whether the filter verified the step.
struct Step<'a> {
    t: f64,
    q: &'a [f64],
    dq: &'a [f64],
    separation: f64,
    violation: bool,
    energy: f64,
    verified: bool,
}

/// What an episode scores as it runs: safety steps, rejected chunks, ground-truth violations
/// and separation, verified steps, the policy's deviation, the goals reached, the tool's path
/// and the samples kept.
struct Tally {
    steps_run: usize,
    chunks_rejected: usize,
    violations: usize,
    verified: usize,
    min_sep: f64,
    max_dev: f64,
    next_goal: usize,
    success_at: Option<f64>,
    samples: Vec<Sample>,
    /// The tool point now, at the last sample kept, and one step before (m).
    tool: [f64; 3],
    last_rec_tool: [f64; 3],
    prev_tool: [f64; 3],
    /// The tool's path until success (m).
    path_len: f64,
}

/// Distance between two points (m).
fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    (0..3).map(|i| (a[i] - b[i]).powi(2)).sum::<f64>().sqrt()
}

impl Tally {
    /// Nothing scored yet, the tool at `tool` (m).
    fn new(tool: [f64; 3]) -> Self {
        Self {
            steps_run: 0,
            chunks_rejected: 0,
            violations: 0,
            verified: 0,
            min_sep: f64::INFINITY,
            max_dev: 0.0,
            next_goal: 0,
            success_at: None,
            samples: Vec::new(),
            tool,
            last_rec_tool: tool,
            prev_tool: tool,
            path_len: 0.0,
        }
    }

    /// Score `step`: its ground truth, the policy's `deviation` (rad) from its demonstrations,
    /// whether the filter verified it, the goals it reaches (success once all are) and the
    /// tool's path.
    fn score(&mut self, robot: &RobotModel, goals: &[Goal], step: &Step<'_>, deviation: f64) {
        self.tool = tool_point(robot, step.q);
        self.min_sep = self.min_sep.min(step.separation);
        self.max_dev = self.max_dev.max(deviation);
        self.violations += step.violation as usize;
        self.verified += step.verified as usize;
        while self.next_goal < goals.len() && goals[self.next_goal].reached(step.q, &self.tool) {
            self.next_goal += 1;
        }
        if self.success_at.is_none() && self.next_goal == goals.len() {
            self.success_at = Some(step.t);
        }
        if self.success_at.is_none() {
            self.path_len += dist(&self.tool, &self.prev_tool);
        }
        self.prev_tool = self.tool;
    }

    /// Keep `step` (safety step `k`) as a sample, the tool's speed over `period` (s) since the
    /// last one kept.
    fn record(&mut self, k: usize, period: f64, step: &Step<'_>) {
        let speed = if k == 0 {
            0.0
        } else {
            dist(&self.tool, &self.last_rec_tool) / period
        };
        self.last_rec_tool = self.tool;
        self.samples.push(Sample {
            t: step.t,
            q: step.q.to_vec(),
            dq: step.dq.to_vec(),
            separation: step.separation,
            violation: step.violation,
            energy: step.energy,
            verified: step.verified,
            tool: self.tool,
            tool_speed: speed,
        });
    }

    /// The episode's result: `names` = (method label, human script, task).
    fn episode(
        self,
        method: Method,
        (label, human, task): (&str, &str, &str),
        policy: &dyn TaskPolicy,
        truth_audit: Option<TruthAudit>,
        max_time: f64,
    ) -> Episode {
        let steps_run = self.steps_run.max(1) as f64;
        let success = self.success_at.is_some();
        let duration = self.success_at.unwrap_or(max_time);
        Episode {
            method,
            variant: label.into(),
            human: human.into(),
            task: task.into(),
            success,
            safe_success: pacs_audit::verdict::safe_success(
                success,
                self.violations == 0
                    && truth_audit
                        .as_ref()
                        .is_none_or(|a| a.certain_fraction == 0.0),
            ),
            violation_fraction: self.violations as f64 / steps_run,
            truth_audit,
            goals_reached: self.next_goal,
            ood_chunks: policy.ood_chunks(),
            chunks_rejected: self.chunks_rejected,
            duration,
            min_separation: self.min_sep,
            max_deviation: self.max_dev,
            verified_fraction: self.verified as f64 / steps_run,
            mean_tool_speed: self.path_len / duration.max(1e-9),
            samples: self.samples,
        }
    }
}
