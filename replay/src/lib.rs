//! # pacs-replay
//!
//! A Foxglove replay of an audited log (`pacs audit LOG --scene out.mcap`): an MCAP file with
//! Foxglove's scene messages (protobuf `foxglove.SceneUpdate`, written with the Foxglove SDK) and
//! a JSON metrics channel, in the world frame `world`, one frame every `frame_period` of log
//! time:
//!
//! | topic | content |
//! |---|---|
//! | `/pacs/robot` | the robot's link capsules at the frame's sample (blue; red while a violation interval is open) |
//! | `/pacs/human` | every person's latest measured body parts (capsules of the body-part thickness; orange) |
//! | `/pacs/human_occupancy` | every person's reachable occupancy from that measurement over the frame (what the audit checks the robot against; translucent) |
//! | `/pacs/robot_occupancy` | the robot's occupancy for the joint box of the frame's logged samples (translucent blue; a picture: the audit's span enclosures also bound the motion between samples) |
//! | `/pacs/violations` | a red sphere on the violating link and a text (constraint, body part) over each violation interval |
//! | `/pacs/metrics` | JSON `{t, min_separation_m, energy_bound_j, threshold_j, energy_nominal_j, violation, inconclusive}` per plot bucket of the audit (plot it in Foxglove) |
//!
//! Log times become MCAP times in nanoseconds from the log's time origin (times before 0 are
//! shifted so that the first is 0).

use foxglove::schemas::{
    Color, CylinderPrimitive, Pose, Quaternion, SceneEntity, SceneUpdate, SpherePrimitive,
    TextPrimitive, Timestamp, Vector3,
};
use foxglove::{Context, PartialMetadata, Schema};
use nalgebra::{Point3, UnitQuaternion, Vector3 as V3};
use pacs_audit::RunResult;
use pacs_log::{LogModels, Record, RecordReader};
use pacs_models::human::BodyPart;
use pacs_models::{Capsule, RobotModel};
use pacs_reach::JointBox;
use pacs_reach::human::{HumanMeasurement, HumanReach, HumanReachModel};
use pacs_reach::robot::RobotReach;
use std::io::{Seek, Write};
use std::sync::Arc;

/// Errors of writing a replay.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    /// The log cannot be read (names file and location).
    #[error("{0}")]
    Log(#[from] pacs_log::LogError),
    /// The scene file cannot be written.
    #[error("cannot write the scene: {0}")]
    Write(String),
    /// A model or measurement the replay cannot use.
    #[error("{0}")]
    Model(String),
}

/// Replay settings.
#[derive(Debug, Clone, Copy)]
pub struct SceneOptions {
    /// Log time between scene frames (s). Default 0.02 s (50 frames per second).
    pub frame_period: f64,
    /// Human reachability model for the occupancy channel. Default `Combined`.
    pub human_model: HumanReachModel,
    /// Extra radius of the robot capsules (m), as the audit's `tracking_error`.
    pub tracking_error: f64,
}

impl Default for SceneOptions {
    fn default() -> Self {
        Self {
            frame_period: 0.02,
            human_model: HumanReachModel::Combined,
            tracking_error: 0.0,
        }
    }
}

/// Messages written per topic.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SceneCounts {
    pub frames: usize,
    pub robot: usize,
    pub human: usize,
    pub human_occupancy: usize,
    pub robot_occupancy: usize,
    pub violations: usize,
    pub metrics: usize,
}

const ROBOT: [f64; 4] = [0.2, 0.45, 0.9, 0.9];
const ROBOT_VIOLATING: [f64; 4] = [0.9, 0.1, 0.1, 0.95];
const HUMAN: [f64; 4] = [0.95, 0.55, 0.15, 0.9];
const HUMAN_OCC: [f64; 4] = [0.95, 0.55, 0.15, 0.18];
const ROBOT_OCC: [f64; 4] = [0.2, 0.45, 0.9, 0.15];
const MARKER: [f64; 4] = [1.0, 0.0, 0.0, 1.0];

fn color(c: [f64; 4]) -> Option<Color> {
    Some(Color {
        r: c[0],
        g: c[1],
        b: c[2],
        a: c[3],
    })
}

fn v3(x: f64, y: f64, z: f64) -> Option<Vector3> {
    Some(Vector3 { x, y, z })
}

fn pose(p: &Point3<f64>, q: &UnitQuaternion<f64>) -> Option<Pose> {
    Some(Pose {
        position: v3(p.x, p.y, p.z),
        orientation: Some(Quaternion {
            x: q.i,
            y: q.j,
            z: q.k,
            w: q.w,
        }),
    })
}

/// A capsule as Foxglove primitives: a cylinder along the segment and a sphere at each end.
fn capsule_primitives(
    c: &Capsule,
    rgba: [f64; 4],
    cylinders: &mut Vec<CylinderPrimitive>,
    spheres: &mut Vec<SpherePrimitive>,
) {
    let (a, b, r) = (c.p1(), c.p2(), c.radius());
    let d = b - a;
    let len = d.norm();
    if len > 0.0 {
        let rot = UnitQuaternion::rotation_between(&V3::z(), &d).unwrap_or_else(|| {
            // Opposite to z: half a turn about x.
            UnitQuaternion::from_axis_angle(&V3::x_axis(), std::f64::consts::PI)
        });
        cylinders.push(CylinderPrimitive {
            pose: pose(&Point3::from((a.coords + b.coords) / 2.0), &rot),
            size: v3(2.0 * r, 2.0 * r, len),
            bottom_scale: 1.0,
            top_scale: 1.0,
            color: color(rgba),
        });
    }
    for p in [a, b] {
        spheres.push(SpherePrimitive {
            pose: pose(&p, &UnitQuaternion::identity()),
            size: v3(2.0 * r, 2.0 * r, 2.0 * r),
            color: color(rgba),
        });
        if len == 0.0 {
            break;
        }
    }
}

fn entity(id: &str, ns: u64, caps: &[Capsule], rgba: [f64; 4]) -> SceneEntity {
    let (mut cylinders, mut spheres) = (Vec::new(), Vec::new());
    for c in caps {
        capsule_primitives(c, rgba, &mut cylinders, &mut spheres);
    }
    SceneEntity {
        timestamp: Some(stamp(ns)),
        frame_id: "world".into(),
        id: id.into(),
        frame_locked: false,
        cylinders,
        spheres,
        ..Default::default()
    }
}

fn stamp(ns: u64) -> Timestamp {
    Timestamp::new((ns / 1_000_000_000) as u32, (ns % 1_000_000_000) as u32)
}

struct Channels {
    robot: foxglove::Channel<SceneUpdate>,
    human: foxglove::Channel<SceneUpdate>,
    human_occ: foxglove::Channel<SceneUpdate>,
    robot_occ: foxglove::Channel<SceneUpdate>,
    violations: foxglove::Channel<SceneUpdate>,
    metrics: Arc<foxglove::RawChannel>,
}

/// The JSON schema of the `/pacs/metrics` messages (our own: one audit plot bucket).
const METRICS_SCHEMA: &str = r#"{
  "title": "pacs.Metrics",
  "description": "One plot bucket of the pacs audit: the separation lower bound, the energy bound and the threshold over the bucket",
  "type": "object",
  "properties": {
    "t": {"type": "number", "description": "bucket start (s, log time)"},
    "t_end": {"type": "number", "description": "bucket end (s)"},
    "min_separation_m": {"type": "number", "description": "lower bound of the robot-human separation over the bucket's checked spans (m)"},
    "energy_bound_j": {"type": "number", "description": "largest sub-chain kinetic energy bound over possible PFL contacts (J)"},
    "threshold_j": {"type": "number", "description": "smallest PFL threshold of those contacts (J)"},
    "energy_nominal_j": {"type": "number", "description": "nominal whole-robot kinetic energy at the bucket's first sample (J)"},
    "violation": {"type": "boolean", "description": "a violation is possible in the bucket"},
    "inconclusive": {"type": "boolean", "description": "part of the bucket could not be checked"}
  }
}"#;

/// Write the replay of the log `reader` (its models with the audit's overrides: `models`) and
/// its audit `run` to `out`.
pub fn write_scene<W: Write + Seek + Send + 'static>(
    reader: &mut dyn RecordReader,
    models: &LogModels,
    run: &RunResult,
    out: W,
    opts: &SceneOptions,
) -> Result<(W, SceneCounts), ReplayError> {
    if !(opts.frame_period > 0.0 && opts.frame_period.is_finite()) {
        return Err(ReplayError::Model(format!(
            "frame_period: {} s must be positive",
            opts.frame_period
        )));
    }
    let ctx = Context::new();
    let writer = ctx
        .mcap_writer()
        .create(out)
        .map_err(|e| ReplayError::Write(e.to_string()))?;
    let ch = Channels::new(&ctx)?;
    let robot = &models.robot;
    let reach = RobotReach::try_new(robot, opts.tracking_error)
        .map_err(|e| ReplayError::Model(e.to_string()))?;
    let n = robot.dof();
    let mut replay = Replay {
        ch,
        robot,
        reach,
        people: people_of(models, opts.human_model),
        run,
        opts,
        counts: SceneCounts::default(),
        t0: None,
        next_frame: f64::NEG_INFINITY,
        lo: vec![f64::INFINITY; n],
        hi: vec![f64::NEG_INFINITY; n],
        marked: vec![false; run.violations.len()],
        last: Vec::with_capacity(n),
        last_ns: 0,
    };
    while let Some(rec) = reader.next_record()? {
        match rec {
            Record::Human {
                t_meas,
                person,
                positions,
                ..
            } => {
                // The person's slot (a v1 log's, or a record without id: the first).
                let k = person
                    .and_then(|id| replay.people.iter().position(|p| p.id == id))
                    .unwrap_or(0);
                if let Some(p) = replay.people.get_mut(k) {
                    let pts: Vec<[f64; 3]> = positions.to_vec();
                    p.latest = HumanMeasurement::new(p.reach.model(), t_meas, &pts, None).ok();
                }
            }
            Record::Robot { t, q, .. } => replay.robot_sample(t, q),
            _ => {}
        }
    }
    replay.late_markers();
    replay.metrics()?;
    let w = writer
        .close()
        .map_err(|e| ReplayError::Write(e.to_string()))?;
    Ok((w, replay.counts))
}

/// Log time `t` (s) as MCAP time (ns) from the time origin `t0` (s); times before it are 0.
fn ns_of(t: f64, t0: f64) -> u64 {
    ((t - t0).max(0.0) * 1e9).round() as u64
}

impl Channels {
    /// The replay's topics on `ctx`, in the order they are listed in the crate docs.
    fn new(ctx: &Arc<Context>) -> Result<Self, ReplayError> {
        let scene = |topic: &str| ctx.channel_builder(topic).build::<SceneUpdate>();
        Ok(Channels {
            robot: scene("/pacs/robot"),
            human: scene("/pacs/human"),
            human_occ: scene("/pacs/human_occupancy"),
            robot_occ: scene("/pacs/robot_occupancy"),
            violations: scene("/pacs/violations"),
            metrics: ctx
                .channel_builder("/pacs/metrics")
                .message_encoding("json")
                .schema(Schema::new(
                    "pacs.Metrics",
                    "jsonschema",
                    METRICS_SCHEMA.as_bytes().to_vec(),
                ))
                .build_raw()
                .map_err(|e| ReplayError::Write(e.to_string()))?,
        })
    }
}

/// One person of the log in the replay: the model's reach and body parts, and the latest
/// measurement.
struct Person {
    id: String,
    reach: HumanReach,
    parts: Vec<BodyPart>,
    latest: Option<HumanMeasurement>,
}

/// The log's people (a v1 log's one person, or every person of a v2 log with its own model).
fn people_of(models: &LogModels, kind: HumanReachModel) -> Vec<Person> {
    let person = |id: &str, h: &pacs_models::HumanModel| Person {
        id: id.to_string(),
        reach: HumanReach::new(h.clone(), kind),
        parts: h.body_parts().to_vec(),
        latest: None,
    };
    if models.people.is_empty() {
        vec![person("", &models.human)]
    } else {
        models.people.iter().map(|(id, h)| person(id, h)).collect()
    }
}

/// A replay being written: its channels and models, and what the log has shown so far.
struct Replay<'a> {
    ch: Channels,
    robot: &'a RobotModel,
    reach: RobotReach,
    /// Every person (all drawn on `/pacs/human` and `/pacs/human_occupancy`).
    people: Vec<Person>,
    run: &'a RunResult,
    opts: &'a SceneOptions,
    counts: SceneCounts,
    /// The log's time origin (s): the first robot sample's time, or 0 if that is later.
    t0: Option<f64>,
    /// Log time (s) of the next frame.
    next_frame: f64,
    /// Joint box (rad or m) of the samples since the last frame.
    lo: Vec<f64>,
    hi: Vec<f64>,
    /// Which violation intervals have their marker.
    marked: Vec<bool>,
    /// The last frame's configuration and MCAP time (ns).
    last: Vec<f64>,
    last_ns: u64,
}

impl Replay<'_> {
    /// A robot sample at log time `t` (s): into the joint box, and a frame if one is due.
    /// Samples with the wrong number of joints are skipped.
    fn robot_sample(&mut self, t: f64, q: &[f64]) {
        let n = self.robot.dof();
        if q.len() != n {
            return;
        }
        let origin = *self.t0.get_or_insert(t.min(0.0));
        for ((lo, hi), &x) in self.lo.iter_mut().zip(&mut self.hi).zip(q) {
            *lo = lo.min(x);
            *hi = hi.max(x);
        }
        if t < self.next_frame {
            return;
        }
        self.next_frame = t + self.opts.frame_period;
        let ns = ns_of(t, origin);
        self.counts.frames += 1;
        self.robot_frame(t, q, ns);
        self.human_frame(t, ns);
        self.violation_markers(t, q, ns);
        self.last.clear();
        self.last.extend_from_slice(q);
        self.last_ns = ns;
    }

    /// The robot's capsules at `q` (red while a violation interval is open at `t`, s) and its
    /// occupancy for the joint box of the samples since the last frame; the box restarts at `q`.
    fn robot_frame(&mut self, t: f64, q: &[f64], ns: u64) {
        let violating = self
            .run
            .violations
            .iter()
            .any(|v| v.t_start <= t && t <= v.t_end);
        let caps: Vec<Capsule> = self
            .robot
            .capsules_world(q)
            .into_iter()
            .map(|(_, c)| c)
            .collect();
        let rgba = if violating { ROBOT_VIOLATING } else { ROBOT };
        log_scene(&self.ch.robot, entity("robot", ns, &caps, rgba), ns);
        self.counts.robot += 1;
        if let Ok(b) = JointBox::new(&self.lo, &self.hi)
            && let Ok(occ) = self.reach.occupancy(&b)
        {
            log_scene(
                &self.ch.robot_occ,
                entity("robot_occupancy", ns, &occ, ROBOT_OCC),
                ns,
            );
            self.counts.robot_occupancy += 1;
        }
        self.lo.fill(f64::INFINITY);
        self.hi.fill(f64::NEG_INFINITY);
        self.lo.copy_from_slice(q);
        self.hi.copy_from_slice(q);
    }

    /// Every person's latest measured body parts and occupancy from them over the frame, `t` to
    /// `t + frame_period` (s), all people in one entity per topic; nothing before the first
    /// measurement.
    fn human_frame(&mut self, t: f64, ns: u64) {
        let (mut body, mut occ) = (Vec::new(), Vec::new());
        let mut any_occ = false;
        for Person {
            reach,
            parts,
            latest,
            ..
        } in &mut self.people
        {
            let Some(m) = latest.as_ref() else { continue };
            let kp = m.positions();
            body.extend(
                parts
                    .iter()
                    .filter_map(|bp| Capsule::new(kp[bp.from], kp[bp.to], bp.thickness / 2.0).ok()),
            );
            if let Ok(o) = reach.occupancy(m, t, t + self.opts.frame_period) {
                occ.extend(o);
                any_occ = true;
            }
        }
        if body.is_empty() {
            return;
        }
        log_scene(&self.ch.human, entity("human", ns, &body, HUMAN), ns);
        self.counts.human += 1;
        if any_occ {
            log_scene(
                &self.ch.human_occ,
                entity("human_occupancy", ns, &occ, HUMAN_OCC),
                ns,
            );
            self.counts.human_occupancy += 1;
        }
    }

    /// Violation markers: each interval once, at the first frame at or after its start, on the
    /// named link.
    fn violation_markers(&mut self, t: f64, q: &[f64], ns: u64) {
        for (k, v) in self.run.violations.iter().enumerate() {
            if !self.marked[k] && v.t_start <= t + 1e-12 {
                self.marked[k] = true;
                log_scene(
                    &self.ch.violations,
                    marker(self.robot, q, k, v, ns, self.opts),
                    ns,
                );
                self.counts.violations += 1;
            }
        }
    }

    /// Intervals starting after the last frame: at the last frame (none without a frame).
    fn late_markers(&mut self) {
        if self.last.is_empty() {
            return;
        }
        for (k, v) in self.run.violations.iter().enumerate() {
            if !self.marked[k] {
                log_scene(
                    &self.ch.violations,
                    marker(self.robot, &self.last, k, v, self.last_ns, self.opts),
                    self.last_ns,
                );
                self.counts.violations += 1;
            }
        }
    }

    /// One `/pacs/metrics` message per plot bucket of the audit, at the bucket's start.
    fn metrics(&mut self) -> Result<(), ReplayError> {
        let origin = self.t0.unwrap_or(0.0);
        for p in &self.run.series {
            let mut m = serde_json::Map::new();
            m.insert("t".into(), p.t.into());
            m.insert("t_end".into(), p.t_end.into());
            for (k, v) in [
                ("min_separation_m", p.min_separation),
                ("far_separation_m", p.far_separation),
                ("energy_bound_j", p.energy_bound),
                ("threshold_j", p.threshold),
                ("energy_nominal_j", p.energy_nominal),
            ] {
                if let Some(x) = v.filter(|x| x.is_finite()) {
                    m.insert(k.into(), x.into());
                }
            }
            m.insert("violation".into(), p.violation.into());
            m.insert("inconclusive".into(), p.inconclusive.into());
            let bytes = serde_json::to_vec(&m).map_err(|e| ReplayError::Write(e.to_string()))?;
            self.ch
                .metrics
                .log_with_meta(&bytes, PartialMetadata::with_log_time(ns_of(p.t, origin)));
            self.counts.metrics += 1;
        }
        Ok(())
    }
}

/// A violation interval's marker: a red sphere on the named link (at configuration `q`) and a
/// text, shown for the interval.
fn marker(
    robot: &pacs_models::RobotModel,
    q: &[f64],
    k: usize,
    v: &pacs_audit::Violation,
    ns: u64,
    opts: &SceneOptions,
) -> SceneEntity {
    let caps = robot.capsules_world(q);
    let at = robot
        .links()
        .iter()
        .position(|l| l.name == v.link)
        .and_then(|li| caps.iter().find(|(i, _)| *i == li))
        .or(caps.first())
        .map_or(Point3::origin(), |(_, c)| {
            Point3::from((c.p1().coords + c.p2().coords) / 2.0)
        });
    let life = ((v.t_end - v.t_start).max(opts.frame_period) * 1e9) as u64;
    let mut e = entity(&format!("violation_{k}"), ns, &[], MARKER);
    e.lifetime = Some(foxglove::schemas::Duration::new(
        (life / 1_000_000_000) as i32,
        (life % 1_000_000_000) as u32,
    ));
    e.spheres.push(SpherePrimitive {
        pose: pose(&at, &UnitQuaternion::identity()),
        size: v3(0.08, 0.08, 0.08),
        color: color(MARKER),
    });
    e.texts.push(TextPrimitive {
        pose: pose(
            &Point3::new(at.x, at.y, at.z + 0.12),
            &UnitQuaternion::identity(),
        ),
        billboard: true,
        font_size: 14.0,
        scale_invariant: true,
        color: color(MARKER),
        text: format!(
            "{} {} on {} ({:.2}–{:.2} s)",
            v.constraint.label(),
            v.body_part,
            v.link,
            v.t_start,
            v.t_end
        ),
    });
    e
}

fn log_scene(ch: &foxglove::Channel<SceneUpdate>, e: SceneEntity, ns: u64) {
    ch.log_with_time(
        &SceneUpdate {
            deletions: vec![],
            entities: vec![e],
        },
        ns,
    );
}
