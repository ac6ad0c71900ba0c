//! `pacs shield --input scene.json`: run the shield on a user's own scene — a robot, a human,
//! dynamic objects, the constraints, timed action chunks and timed measurements — and write the
//! command of every safety step (JSON Lines) and the run as an audit-format log.
//!
//! The scene's model fields are those of a log header (`robot`, `human`, `constraints`,
//! `environment`, `objects`: built-in names or inline specs), so the log written is audited
//! against exactly the models the shield used. A measurement stamped `t` reaches the shield at
//! its `received` time (default: `t`), a chunk at its `t`: each is handed over at the first
//! safety step at or after that time, in file order for equal times.

use super::{CliError, check_vec, read_file};
use pacs_log::{Header, LogModels, ModelRef, ObjectEntry};
use pacs_models::ConstraintSpec;
use pacs_models::human::HumanSpec;
use pacs_motion::chunk::{ActionKind, Chunk};
use pacs_reach::human::HumanMeasurement;
use pacs_reach::object::ObjectMeasurement;
use pacs_shield::session::{MeasurementInbox, Pending, Session, SessionError};
use pacs_shield::settings::ShieldSettings;
use pacs_shield::shield::{BindingNames, Command, Shield};
use serde::Deserialize;
use serde_json::{Value, json};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

/// The scene file (see docs/cli.md, `pacs shield`).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Scene {
    robot: pacs_log::RobotRef,
    /// The one person's model (or `humans`).
    #[serde(default)]
    human: Option<ModelRef<HumanSpec>>,
    /// Several people, each with an id that `human_measurements[].id` names.
    #[serde(default)]
    humans: Vec<pacs_log::PersonEntry>,
    constraints: ModelRef<ConstraintSpec>,
    #[serde(default)]
    environment: Vec<pacs_models::shape::CapsuleSpec>,
    #[serde(default)]
    objects: Vec<ObjectEntry>,
    #[serde(default)]
    config: ShieldSettings,
    /// Start configuration at rest (rad) at `t0`.
    start: Vec<f64>,
    /// Start time (s).
    #[serde(default)]
    t0: f64,
    /// Run length (s): steps at t0, t0 + α_s, … while t < t0 + duration.
    duration: f64,
    #[serde(default)]
    chunks: Vec<TimedChunk>,
    #[serde(default)]
    human_measurements: Vec<HumanEntry>,
    #[serde(default)]
    object_measurements: Vec<ObjectEntryMeasurement>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct TimedChunk {
    /// When the policy hands the chunk over (s).
    t: f64,
    #[serde(default)]
    kind: ActionKind,
    actions: Vec<Vec<f64>>,
    execute: usize,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct HumanEntry {
    /// The person (an id of `humans`; may be omitted with one person).
    #[serde(default)]
    id: Option<String>,
    /// Measurement time stamp (s).
    t: f64,
    /// When the shield receives it (s; default `t`).
    received: Option<f64>,
    /// Keypoint positions (m), in the model's order.
    keypoints: Vec<[f64; 3]>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ObjectEntryMeasurement {
    /// Measurement time stamp (s).
    t: f64,
    /// When the shield receives it (s; default `t`).
    received: Option<f64>,
    /// Object id (declared in `objects`).
    id: String,
    /// Position (m).
    position: [f64; 3],
    /// Velocity (m/s), if measured.
    velocity: Option<[f64; 3]>,
}

fn input(msg: impl Into<String>) -> CliError {
    CliError::Input(msg.into())
}

fn finite(field: &str, v: f64) -> Result<f64, CliError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(input(format!("{field}: value {v} is not finite")))
    }
}

/// A measurement's time stamp and arrival time (default: the stamp), both finite, the arrival
/// not before the stamp; errors name `field`.
fn stamp_and_arrival(field: &str, t: f64, received: Option<f64>) -> Result<(f64, f64), CliError> {
    let t = finite(&format!("{field}.t"), t)?;
    let received = finite(&format!("{field}.received"), received.unwrap_or(t))?;
    if received < t {
        return Err(input(format!(
            "{field}.received: {received} s is before the time stamp {t} s"
        )));
    }
    Ok((t, received))
}

/// Built-in example scene (`examples/scene.json`).
const SCENE_EXAMPLE: &str = include_str!("../../examples/scene.json");

/// A scene read and checked: its name (the path shown in messages), the scene, the log header
/// of the models it names, those models and the shield configuration.
struct Loaded {
    name: String,
    scene: Scene,
    header: Header,
    models: LogModels,
    cfg: pacs_shield::shield::ShieldConfig,
}

/// Read the scene (`None`: the built-in example) and build the log header of its models.
fn load(path: Option<&Path>) -> Result<Loaded, CliError> {
    let (name, text) = match path {
        Some(p) => (p.display().to_string(), read_file(p)?),
        None => ("examples/scene.json".to_string(), SCENE_EXAMPLE.to_string()),
    };
    let scene: Scene = serde_json::from_str(&text).map_err(|e| {
        input(format!(
            "{name}: invalid scene: {}",
            pacs_models::describe_json_error(&text, &e)
        ))
    })?;
    // A {urdf, side} robot (paths relative to the scene file) is logged as its converted spec:
    // the log stands on its own.
    let robot_ref = match &scene.robot {
        pacs_log::RobotRef::Urdf { .. } => pacs_log::RobotRef::Spec(Box::new(
            super::load_robot(&scene.robot, path)?.spec().clone(),
        )),
        other => other.clone(),
    };
    let mut header = match (&scene.human, scene.humans.is_empty()) {
        (Some(h), true) => Header::new(robot_ref, h.clone(), scene.constraints.clone()),
        (None, false) => {
            Header::with_people(robot_ref, scene.humans.clone(), scene.constraints.clone())
        }
        (Some(_), false) => {
            return Err(input(format!(
                "{name}: both `human` and `humans`: give one person as `human` or several as `humans`: [{{\"id\": ..., \"human\": ...}}]"
            )));
        }
        (None, true) => {
            return Err(input(format!(
                "{name}: no person: give `human` (a model) or `humans`: [{{\"id\": ..., \"human\": ...}}]"
            )));
        }
    };
    header
        .check()
        .map_err(|e| input(format!("{name}: {}", e.to_string().replace("header.", ""))))?;
    header.environment = scene.environment.clone();
    header.objects = scene.objects.clone();
    let cfg = scene
        .config
        .config()
        .map_err(|e| input(format!("{name}: {e}")))?;
    // A scene's person measurements carry positions only: `acc` would never verify a step.
    if cfg.human_model == pacs_reach::human::HumanReachModel::Acc {
        return Err(input(format!(
            "{name}: config.human_model: `acc` needs measured velocities, which a scene's human_measurements do not carry (every step would go unverified): use `combined` (the default), `vel` or `pos`"
        )));
    }
    // The filter that ran (the configured mode, as `pacs simulate` labels its runs): reports
    // group runs by it, so PACS and OFF runs of one scene are never averaged together.
    header.meta.insert("filter".into(), cfg.mode.label().into());
    header.meta.insert("tool".into(), "pacs shield".into());
    header.meta.insert("scene".into(), name.clone().into());
    let models = LogModels::from_header(&header)
        .map_err(|e| input(format!("{name}: {}", e.to_string().replace("header.", ""))))?;
    Ok(Loaded {
        name,
        scene,
        header,
        models,
        cfg,
    })
}

/// An input error found in the scene `name` after it was parsed, naming the file (unless the
/// message already does).
fn in_scene(name: &str, e: CliError) -> CliError {
    match e {
        CliError::Input(m) if !m.starts_with(name) => CliError::Input(format!("{name}: {m}")),
        e => e,
    }
}

/// Check the start and the run's time span and build the shield of the scene (not started).
fn build_shield(l: &Loaded) -> Result<Shield, CliError> {
    let (scene, models, cfg, name) = (&l.scene, &l.models, l.cfg, &l.name);
    check_vec("start", &scene.start, models.robot.dof())?;
    let t0 = finite("t0", scene.t0)?;
    let duration = finite("duration", scene.duration)?;
    if duration <= 0.0 || duration > 3600.0 {
        return Err(input(format!(
            "duration: {duration} s is outside (0, 3600]"
        )));
    }
    if duration < cfg.safety_step {
        return Err(input(format!(
            "duration: {duration} s is shorter than one safety step ({} s)",
            cfg.safety_step
        )));
    }
    if !pacs_shield::shield::clock_resolves(t0 + duration, cfg.safety_step) {
        return Err(input(format!(
            "t0: {t0} s (to {} s) is too large to resolve the safety step ({} s): count time from the run's start",
            t0 + duration,
            cfg.safety_step
        )));
    }
    let env: Vec<_> = models
        .environment
        .iter()
        .map(pacs_shield::shield::EnvShape::from)
        .collect();
    let mut shield = Shield::new(
        models.robot.clone(),
        Some((models.human.clone(), &models.constraints)),
        env,
        cfg,
    )
    .map_err(|e| input(format!("{name}: {e}")))?;
    for (id, human) in models.people.iter().skip(1) {
        shield
            .add_human(human.clone(), &models.constraints)
            .map_err(|e| input(format!("humans `{id}`: {e}")))?;
    }
    for (id, model, contact) in &models.objects {
        shield
            .add_object(*model, *contact)
            .map_err(|e| input(format!("objects `{id}`: {e}")))?;
    }
    Ok(shield)
}

/// The scene's chunks, checked, in the order they are handed over (by time, file order for
/// equal times), each with its time (s) and index; every measurement is put in `session`'s
/// inbox (human, then object measurements, each in file order, so that measurements arriving
/// at one time reach the shield in that order).
fn inputs(l: &Loaded, session: &mut Session<Out>) -> Result<Vec<(f64, usize, Chunk)>, CliError> {
    let (scene, models) = (&l.scene, &l.models);
    let n = models.robot.dof();
    let pushed = |e: SessionError| CliError::Internal(format!("inputs: {e}"));
    let mut chunks = Vec::with_capacity(scene.chunks.len());
    for (i, c) in scene.chunks.iter().enumerate() {
        let field = format!("chunks[{i}]");
        let t = finite(&format!("{field}.t"), c.t)?;
        for (a, row) in c.actions.iter().enumerate() {
            check_vec(&format!("{field}.actions[{a}]"), row, n)?;
        }
        if c.execute == 0 || c.execute > c.actions.len() {
            return Err(input(format!(
                "{field}.execute: {} is outside 1..={} (the number of actions)",
                c.execute,
                c.actions.len()
            )));
        }
        let chunk = Chunk {
            kind: c.kind,
            actions: c.actions.clone(),
            execute: c.execute,
            gripper: None,
        };
        chunks.push((t, i, chunk));
    }
    chunks.sort_by(|a, b| a.0.total_cmp(&b.0));
    for (i, m) in scene.human_measurements.iter().enumerate() {
        let field = format!("human_measurements[{i}]");
        let (t, received) = stamp_and_arrival(&field, m.t, m.received)?;
        let p = person_index(&field, m.id.as_deref(), models)?;
        let hm = HumanMeasurement::new(&models.people[p].1, t, &m.keypoints, None)
            .map_err(|e| input(format!("{field}.keypoints: {e}")))?;
        session.measure_person_at(received, p, hm).map_err(pushed)?;
    }
    for (i, m) in scene.object_measurements.iter().enumerate() {
        let field = format!("object_measurements[{i}]");
        let (t, received) = stamp_and_arrival(&field, m.t, m.received)?;
        let Some(k) = models.objects.iter().position(|(id, _, _)| *id == m.id) else {
            return Err(input(format!(
                "{field}.id: no object `{}` in `objects`",
                m.id
            )));
        };
        for (j, x) in m
            .position
            .iter()
            .chain(m.velocity.iter().flatten())
            .enumerate()
        {
            finite(
                &format!("{field}.{}", if j < 3 { "position" } else { "velocity" }),
                *x,
            )?;
        }
        let om = ObjectMeasurement {
            time: t,
            position: m.position,
            velocity: m.velocity,
        };
        session.measure_object_at(received, k, om).map_err(pushed)?;
    }
    Ok(chunks)
}

/// The shield's index of the person a measurement names (`id`; may be omitted with one
/// person); errors name `field`.
fn person_index(field: &str, id: Option<&str>, models: &LogModels) -> Result<usize, CliError> {
    let ids = || {
        models
            .people
            .iter()
            .map(|(id, _)| id.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    };
    match id {
        Some(id) => models
            .people
            .iter()
            .position(|(p, _)| p == id)
            .ok_or_else(|| {
                input(format!(
                    "{field}.id: `{id}` is not a person of the scene (humans: {})",
                    ids()
                ))
            }),
        None if models.people.len() == 1 => Ok(0),
        None => Err(input(format!(
            "{field}.id: missing; the scene has several people ({}): each measurement names one",
            ids()
        ))),
    }
}

/// One command as a JSON Lines record (`names`: what its binding's indices stand for).
fn command_line(cmd: &Command, names: &BindingNames) -> Value {
    let d = &cmd.diag;
    let mut line = json!({
        "t": cmd.t,
        "q": cmd.q(),
        "dq": cmd.dq(),
        "ddq": cmd.ddq(),
        "verified": d.verified,
        "on_failsafe": d.on_failsafe,
        "binding": names.describe(&d.binding),
        "path_speed": d.path_speed,
        "stop_time": d.stop_time,
    });
    if d.min_separation.is_finite() {
        line["min_separation_m"] = json!(d.min_separation);
    }
    line
}

/// The measurements still waiting in the inbox: of people, of objects.
fn not_delivered(inbox: &MeasurementInbox) -> (usize, usize) {
    inbox.pending().fold((0, 0), |(h, o), (_, e)| match e {
        Pending::Person(..) => (h + 1, o),
        _ => (h, o + 1),
    })
}

/// The log and command files' writer.
type Out = BufWriter<File>;

/// Run `pacs shield [--input F] [--out DIR]`: returns the summary printed on stdout.
pub fn run(path: Option<&Path>, out: &Path) -> Result<Value, CliError> {
    let l = load(path)?;
    let shield = build_shield(&l).map_err(|e| in_scene(&l.name, e))?;
    let object_ids: Vec<String> = l.models.objects.iter().map(|o| o.0.clone()).collect();
    // What each command's binding indices stand for (built once): link and body-part names,
    // the person's id in a scene of several people, the object's id.
    let person_ids: Vec<String> = l.scene.humans.iter().map(|p| p.id.clone()).collect();
    let names = shield.binding_names(&person_ids, &object_ids);
    // Every input of a scene file is known in advance: its size bounds the inbox.
    let mut session = Session::new(shield, object_ids).with_max_waiting(usize::MAX);
    let chunks = inputs(&l, &mut session).map_err(|e| in_scene(&l.name, e))?;
    let t0 = l.scene.t0;
    std::fs::create_dir_all(out)
        .map_err(|e| CliError::Output(format!("cannot create {}: {e}", out.display())))?;
    let (cmd_path, log_path) = (out.join("commands.jsonl"), out.join("log.jsonl"));
    let create = |p: &Path| File::create(p).map(BufWriter::new);
    let cannot_create =
        |p: &Path, e| CliError::Output(format!("cannot create {}: {e}", p.display()));
    let mut cmd_out = create(&cmd_path).map_err(|e| cannot_create(&cmd_path, e))?;
    let werr = |p: &Path, e: &dyn std::fmt::Display| {
        CliError::Output(format!("cannot write {}: {e}", p.display()))
    };
    session
        .start_logged(
            t0,
            &l.scene.start,
            &l.header,
            &log_path.display().to_string(),
            || create(&log_path),
        )
        .map_err(|e| match e {
            SessionError::LogCreate { error, .. } => cannot_create(&log_path, error),
            SessionError::LogHeader { error, .. } => {
                CliError::Internal(format!("{}: {error}", log_path.display()))
            }
            e => input(e.to_string()),
        })?;
    let dt = session.shield().config().safety_step;
    let steps = (l.scene.duration / dt).ceil() as usize;
    let (mut verified, mut accepted, mut next_chunk) = (0usize, 0usize, 0usize);
    let mut rejected: Vec<Value> = Vec::new();
    let mut max_step_us: f64 = 0.0;
    for k in 0..steps {
        let t = t0 + k as f64 * dt;
        // Every input reaches the shield at the first step at or after its arrival (never
        // before: a measurement handed over before its stamp would be ignored as from the
        // future while the log said it was received); every input is logged.
        while let Some((_, i, chunk)) = chunks.get(next_chunk).filter(|c| c.0 <= t) {
            next_chunk += 1;
            match session.set_chunk(chunk) {
                Ok(_) => accepted += 1,
                Err(SessionError::ChunkRejected(e)) => {
                    rejected.push(json!({"chunk": i, "t": t, "reason": e.to_string()}))
                }
                Err(e) => return Err(CliError::Internal(format!("chunk {i} at {t} s: {e}"))),
            }
        }
        let clock = std::time::Instant::now();
        let cmd = session.step(t).map_err(|e| match e {
            SessionError::Delivery(e) => input(format!("measurement at {t} s: {e}")),
            e => CliError::Internal(format!("step at {t} s: {e}")),
        })?;
        max_step_us = max_step_us.max(clock.elapsed().as_secs_f64() * 1e6);
        if let Some(e) = session.log_failure() {
            return Err(werr(&log_path, &e));
        }
        verified += cmd.diag.verified as usize;
        serde_json::to_writer(&mut cmd_out, &command_line(&cmd, &names))
            .map_err(|e| werr(&cmd_path, &e))?;
        writeln!(cmd_out).map_err(|e| werr(&cmd_path, &e))?;
    }
    session.close().map_err(|e| match e {
        SessionError::Log { error, .. } => werr(&log_path, &error),
        e => CliError::Internal(e.to_string()),
    })?;
    cmd_out.flush().map_err(|e| werr(&cmd_path, &e))?;
    // Inputs arriving after the last step never reached the shield: say so rather than leave
    // them out of every count.
    let late_chunks: Vec<usize> = chunks[next_chunk..].iter().map(|c| c.1).collect();
    let (late_humans, late_objects) = not_delivered(session.inbox());
    if !late_chunks.is_empty() {
        eprintln!(
            "pacs: warning: chunks {late_chunks:?} are timed after the last step ({} s) and were never handed to the shield (extend `duration`)",
            t0 + steps.saturating_sub(1) as f64 * dt
        );
    }
    Ok(json!({
        "scene": l.name,
        "steps": steps,
        "safety_step_s": dt,
        "verified_fraction": verified as f64 / steps.max(1) as f64,
        "chunks_accepted": accepted,
        "chunks_rejected": rejected,
        "not_delivered": {
            "chunks": late_chunks,
            "human_measurements": late_humans,
            "object_measurements": late_objects,
        },
        "max_step_us": max_step_us,
        "commands": cmd_path,
        "log": log_path,
    }))
}
