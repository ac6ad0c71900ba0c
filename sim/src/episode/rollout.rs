//! The rollout loop of an episode: policy chunks, filter steps, the simulated tracking error, the
//! camera, the log and the truth audit, and the episode's result.

use super::{
    Episode, EpisodeConfig, Method, Outputs, Sample, Setup, TruthAudit, ground_truth, log_header,
    object_ground_truth,
};
use crate::SimError;
use crate::humans::Camera;
use crate::objects::ObjectCamera;
use crate::policy::Observation;
use crate::task::tool_point;
use pacs_audit::{AuditConfig, Auditor};
use pacs_log::LogModels;
use pacs_motion::chunk::{ActionKind, Chunk};
use pacs_shield::ChunkMotion;
use pacs_shield::shield_log::ShieldLog;

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
    let Setup {
        robot,
        human,
        spec,
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
    let Outputs {
        log,
        record_every,
        truth_audit,
    } = out;
    let mut log = match log {
        Some(w) => {
            let h = log_header(
                label,
                robot,
                human,
                spec,
                script,
                objects,
                others.len(),
                policy.name(),
            );
            let mut l = ShieldLog::new(w, &h, 0.0, start).map_err(invalid)?;
            l.event(0.0, "episode_start").map_err(invalid)?;
            Some(l)
        }
        None => None,
    };
    let mut auditor = if truth_audit {
        let exact = human.with_uncertainty(0.0, 0.0, 0.0).map_err(invalid)?;
        let models = LogModels {
            robot: robot.clone(),
            people: vec![(pacs_log::V1_PERSON.to_string(), exact.clone())],
            human: exact,
            constraints: spec.clone(),
            environment: vec![],
            objects: objects
                .iter()
                .map(|o| Ok((o.id.clone(), o.exact_model().map_err(invalid)?, o.contact)))
                .collect::<Result<_, SimError>>()?,
        };
        Some(if others.is_empty() {
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
    } else {
        None
    };
    let tc = spec.resolve(human).map_err(invalid)?;
    let mut filter = method
        .filter_kind()
        .build_with(robot, human, spec, cfg.chunk_motion)?;
    for o in objects {
        filter.add_object(o.model, o.contact)?;
    }
    for _ in others {
        filter.add_human(human.clone(), spec)?;
    }
    filter.start(0.0, start)?;
    let mut camera = Camera::new(cfg.camera_period, cfg.seed);
    let mut other_cameras: Vec<Camera> = (0..others.len())
        .map(|i| Camera::new(cfg.camera_period, cfg.seed ^ (0xCA3E + i as u64)))
        .collect();
    let mut object_cameras: Vec<ObjectCamera> = (0..objects.len())
        .map(|i| ObjectCamera::new(cfg.camera_period, cfg.seed ^ (0x0B1E + i as u64)))
        .collect();
    let tracking = Tracking::new(cfg.tracking_error, robot.dof(), cfg.seed);
    let n = robot.dof();
    let steps = (max_time / cfg.dt).round() as usize;
    let action_every = (cfg.policy_dt / cfg.dt).round().max(1.0) as usize;
    let chunk_every = policy.execute() * action_every;
    // Steps since the last chunk (the first chunk is due at once).
    let mut since_chunk = chunk_every;
    let mut chunks_rejected = 0usize;
    let (mut q, mut dq) = (start.to_vec(), vec![0.0; n]);
    let (mut violations, mut verified, mut min_sep, mut max_dev) =
        (0usize, 0usize, f64::INFINITY, 0.0f64);
    let mut next_goal = 0usize;
    let mut success_at = None;
    let mut samples = Vec::new();
    let mut steps_run = 0usize;
    // The last command's time (s): the last robot sample of the log, where its closing events go
    // (the log's `end` event must not lie after its last sample).
    let mut last_cmd_t = 0.0f64;
    let mut waypoints: Vec<Vec<f64>> = Vec::new();
    let mut tool = tool_point(robot, &q);
    let mut last_rec_tool = tool;
    let mut prev_tool = tool;
    let mut path_len = 0.0;
    tracking.apply(0.0, &mut q, &mut dq);
    // The actual joints over the last policy step Δt (one entry per safety step), so that a
    // policy can observe q now and one Δt before (the paper's policies see two timesteps); at
    // rest before the start.
    let mut past = vec![q.clone(); action_every];
    let mut before = q.clone();
    if let Some(a) = auditor.as_mut() {
        a.push_human(0, 0.0, &script.keypoints(0.0))
            .map_err(invalid)?;
        for (i, o) in others.iter().enumerate() {
            a.push_human(1 + i, 0.0, &o.keypoints(0.0))
                .map_err(invalid)?;
        }
        for o in objects {
            let (p, v) = o.script.state(0.0);
            a.push_object(0.0, 0.0, &o.id, p, Some(v))
                .map_err(invalid)?;
        }
        a.push_robot(0.0, &q, Some(&dq)).map_err(invalid)?;
    }
    for k in 0..steps {
        steps_run += 1;
        let t = k as f64 * cfg.dt;
        before.copy_from_slice(&past[k % action_every]);
        past[k % action_every].copy_from_slice(&q);
        let obs = Observation {
            q: &q,
            q_before: &before,
            stage: next_goal,
        };
        if method == Method::Direct {
            if k % chunk_every == 0 {
                let c = policy.act(&obs);
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
        } else if since_chunk >= chunk_every
            || (cfg.chunk_motion == ChunkMotion::Continuous
                && since_chunk >= action_every
                && filter
                    .remaining()
                    .is_some_and(|r| r < HANDOVER_STEPS * cfg.dt))
        {
            since_chunk = 0;
            let c = policy.act(&obs);
            // An unplannable chunk is ignored by the filter (counted).
            if filter.set_chunk(t, &c).is_err() {
                chunks_rejected += 1;
            }
        }
        since_chunk += 1;
        let m = camera.measure(human, script, t);
        for (i, (o, cam)) in others.iter().zip(&mut other_cameras).enumerate() {
            if let Some(om) = cam.measure(human, o.as_ref(), t) {
                filter.measure_human(1 + i, &om)?;
                if let Some(l) = log.as_mut() {
                    l.person(t, 1 + i, &om).map_err(invalid)?;
                }
            }
        }
        for (i, (o, cam)) in objects.iter().zip(&mut object_cameras).enumerate() {
            if let Some(om) = cam.measure(o, t) {
                filter.measure_object(i, &om)?;
                if let Some(l) = log.as_mut() {
                    l.object(t, &o.id, &om).map_err(invalid)?;
                }
            }
        }
        let cmd = filter.step(t, m.as_ref())?;
        if let Some(l) = log.as_mut() {
            l.record(t, m.as_ref(), &cmd).map_err(invalid)?;
        }
        last_cmd_t = cmd.t;
        q.copy_from_slice(cmd.q());
        dq.copy_from_slice(cmd.dq());
        tracking.apply(cmd.t, &mut q, &mut dq);
        let truth = script.keypoints(cmd.t);
        let truths: Vec<Vec<[f64; 3]>> = others.iter().map(|o| o.keypoints(cmd.t)).collect();
        if let Some(a) = auditor.as_mut() {
            a.push_human(0, cmd.t, &truth).map_err(invalid)?;
            for (i, tr) in truths.iter().enumerate() {
                a.push_human(1 + i, cmd.t, tr).map_err(invalid)?;
            }
            for o in objects {
                let (p, v) = o.script.state(cmd.t);
                a.push_object(cmd.t, cmd.t, &o.id, p, Some(v))
                    .map_err(invalid)?;
            }
            a.push_robot(cmd.t, &q, Some(&dq)).map_err(invalid)?;
        }
        let (mut sep, mut viol, energy) = ground_truth(robot, human, &tc, &q, &dq, &truth);
        for tr in &truths {
            let (s, v, _) = ground_truth(robot, human, &tc, &q, &dq, tr);
            sep = sep.min(s);
            viol |= v;
        }
        if !objects.is_empty() {
            let caps: Vec<_> = robot
                .capsules_world(&q)
                .into_iter()
                .map(|(_, c)| c)
                .collect();
            for o in objects {
                let (s, v) = object_ground_truth(o, cmd.t, &caps, &dq, energy);
                sep = sep.min(s);
                viol |= v;
            }
        }
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
    if let Some(mut l) = log {
        l.event(last_cmd_t, if success { "success" } else { "failure" })
            .map_err(invalid)?;
        l.finish().map_err(invalid)?;
    }
    let truth_audit = auditor.map(|mut a| {
        a.push_event(if success { "success" } else { "failure" });
        let r = a.finish("ground-truth");
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
        safe_success: pacs_audit::verdict::safe_success(
            success,
            violations == 0
                && truth_audit
                    .as_ref()
                    .is_none_or(|a| a.certain_fraction == 0.0),
        ),
        violation_fraction: violations as f64 / steps_run,
        truth_audit,
        goals_reached: next_goal,
        ood_chunks: policy.ood_chunks(),
        chunks_rejected,
        duration,
        min_separation: min_sep,
        max_deviation: max_dev,
        verified_fraction: verified as f64 / steps_run,
        mean_tool_speed: path_len / duration.max(1e-9),
        samples,
    })
}
