//! The audit core: sound SSM and PFL checks of every span between consecutive robot samples.
//!
//! For a span `[t_i, t_{i+1}]` the robot's joint positions lie in a box derived from the two
//! samples and the velocity limits, its velocities in a box derived from the acceleration limits;
//! the human lies in the reachable occupancy of the newest measurement (by stamp) logged before
//! `t_i`. A
//! violation is *possible* if the enclosures admit one, *certain* if it holds at a recorded sample
//! with the measured keypoints taken at face value. See `docs/audit.md` for the exact semantics.

// Per-joint loops index several parallel arrays; ranges read better than zipped iterators.
#![allow(clippy::needless_range_loop)]

use crate::enclosure::{Sample, SpanBoxes, SpanEnclosure, span_boxes};
use crate::verdict::{
    ConstraintKind, InconclusiveSpan, Metrics, ModelNames, RunResult, Verdict, Violation,
};
use nalgebra::{Isometry3, Point3};
use pacs_log::LogModels;
use pacs_models::object::{ObjectContact, ObjectModel};
use pacs_models::robot::MAX_DOF;
use pacs_models::{Capsule, HumanModel, RobotModel};
use pacs_reach::geometry::segment_distance_upper_bound;
use pacs_reach::human::{HumanMeasurement, HumanReach};
use pacs_reach::object::{ObjectMeasurement, ObjectOccupancy};
use pacs_reach::robot::{ReachScratch, RobotReach};
use pacs_reach::rounding::{add_down, add_up, dist3_up, mul_down, norm3_up, sub_down};
use pacs_verify::iso15066::{
    ContactRule, EnvShape, ObjectRule, Outcome, frames_can_pinch, threshold,
};
use std::ops::ControlFlow;

pub use crate::config::AuditConfig;

/// Maximum number of robot capsules supported (bit masks).
pub use pacs_verify::iso15066::MAX_CAPSULES;
/// Spans checked together by the block fast path (see `Auditor::check_block`).
pub const BLOCK_SPANS: usize = 32;
/// The smallest part of a block that [`Auditor::check_block`] is tried on after the whole block
/// failed (halving from [`BLOCK_SPANS`]); smaller parts are checked span by span.
pub const MIN_SUB_BLOCK: usize = 4;
/// Human measurements (and, per object, object measurements) kept, the newest by stamp, to
/// check each new record against every one of them.
pub const HUMAN_HISTORY: usize = 64;
pub use crate::series::SERIES_BUCKETS;

#[derive(Clone, Copy)]
struct SpanHit {
    part: usize,
    link: usize,
    kind: ConstraintKind,
    energy: f64,
    threshold: f64,
    constrained: bool,
    certain: bool,
    separation: f64,
}

#[derive(Clone, Copy)]
struct OpenInterval {
    v_start: f64,
    v_end: f64,
    kind: ConstraintKind,
    min_sep: f64,
    energy: f64,
    threshold: f64,
    constrained: bool,
    certain: bool,
    spans: u64,
    last_span: u64,
}

use crate::error::AuditError;
use crate::series::{Series, max_opt, min_opt};
use crate::verdict::InconclusiveReason as Reason;

// The span checks (block fast path, span by span) and the certain check live in submodules
// with access to the auditor's state.
mod certain;
mod finish;
mod spans;

/// A dynamic object of the log: its model, allowed contact and measurements.
#[derive(Debug, Clone)]
struct ObjectTrack {
    id: String,
    model: ObjectModel,
    contact: ObjectContact,
    /// The measurement in use: the newest by stamp, the first of equal stamps (the shield's
    /// [`ObjectMeasurement::keep_newest`]).
    latest: Option<ObjectMeasurement>,
    /// The latest [`HUMAN_HISTORY`] measurements by stamp, for the model check of each record.
    history: std::collections::VecDeque<ObjectMeasurement>,
    /// The measurement in use for the span the last robot sample opened (like `span_human`).
    span: Option<ObjectMeasurement>,
    /// Its occupancy over the span being checked (`None`: outside the workspace ball).
    occ: Option<ObjectOccupancy>,
}

/// Streaming auditor of one log: feed records in time order, then [`Auditor::finish`].
/// After warm-up, robot samples allocate nothing.
pub struct Auditor {
    cfg: AuditConfig,
    robot: RobotModel,
    human: HumanModel,
    /// The one ISO/TS 15066 rule (shared with the shield).
    rule: ContactRule,
    /// Its object form, and the log's objects (their hits follow the body parts': part index
    /// `parts + k` for object `k`).
    object_rule: ObjectRule,
    objects: Vec<ObjectTrack>,
    environment: Vec<Capsule>,
    names: ModelNames,
    rreach: RobotReach,
    hreach: HumanReach,
    n: usize,
    parts: usize,
    links: usize,
    cap_local: Vec<Capsule>,
    // Buffers.
    rcaps: Vec<Capsule>,
    hcaps: Vec<Capsule>,
    energies: Vec<f64>,
    /// Robot-occupancy scratch (the energy bound of the same box reuses its frames).
    scratch: Box<ReachScratch>,
    frames: Vec<Isometry3<f64>>,
    nom_caps: Vec<Capsule>,
    /// The joint positions (rad) `nom_caps` were computed at (valid when `nom_key_valid`).
    nom_key: [f64; MAX_DOF],
    nom_key_valid: bool,
    /// The nominal kinetic energy (J) at `nom_key` and the velocities (rad/s) it was computed for.
    nom_energy: Option<(f64, [f64; MAX_DOF])>,
    hits: Vec<SpanHit>,
    // State.
    prev: Option<Sample>,
    /// Buffered samples whose spans all use the human measurement `block_human`.
    block: Vec<Sample>,
    /// The enclosures of the block's spans (a buffer of `flush_block`).
    block_encl: Vec<SpanEnclosure>,
    /// The last spans checked one by one were mostly violating: skip the halves of the next
    /// block that fails (speed only).
    dense_violations: bool,
    /// Use the block fast path (off: every span on its own, the reference it is tested against).
    block_fast_path: bool,
    block_human: Option<usize>,
    humans: [Option<HumanMeasurement>; 2],
    latest_human: Option<usize>,
    /// Pairs of human measurements adjacent in stamp order, and of object measurements, that
    /// contradict their model (merged when they chain), reported as `human_exceeds_model` /
    /// `object_exceeds_model`.
    model_breaks: Vec<InconclusiveSpan>,
    /// The latest [`HUMAN_HISTORY`] human measurements in stamp order, for the model check of
    /// each record against them (records may arrive out of order).
    human_history: std::collections::VecDeque<HumanMeasurement>,
    /// The bounding box of each kept measurement's keypoints (same order as `human_history`).
    human_boxes: std::collections::VecDeque<KeypointBox>,
    span_human: Option<usize>,
    span_index: u64,
    open: Vec<Option<OpenInterval>>,
    violations: Vec<Violation>,
    inconclusive: Vec<(InconclusiveSpan, Reason, u64)>,
    samples: u64,
    human_records: u64,
    /// Earliest measurement time of the human records pushed since the last robot sample.
    unused_human_t_meas: Option<f64>,
    /// Earliest measurement time of the human records pushed between the last two robot samples:
    /// they are in use only from the last sample on, which starts no span yet.
    awaiting_human_t_meas: Option<f64>,
    t_first: f64,
    t_last: f64,
    violating_samples: u64,
    certain_samples: u64,
    last_span_violated: bool,
    last_span_certain: bool,
    inconclusive_duration: f64,
    min_separation: Option<f64>,
    success: Option<bool>,
    series: Series,
    /// The person this auditor checks (a v2 log's person id; `None` for v1 logs): named in its
    /// violations and person-related inconclusive spans.
    person: Option<String>,
    /// The violating samples by index, for merging the passes of several people.
    track: Option<Box<crate::people::Tracks>>,
}

/// An energy bound as reported (JSON has no infinity): an unbounded energy is reported as
/// `f64::MAX` J, still an upper bound of any physical robot's energy, never `null`.
fn reportable(e: f64) -> f64 {
    if e.is_finite() { e } else { f64::MAX }
}

impl Auditor {
    /// Prepare an auditor for the models; fails if the constraints do not resolve against the
    /// human model, the config is invalid, or the robot has more than [`MAX_CAPSULES`] capsules.
    pub fn new(models: LogModels, cfg: AuditConfig) -> Result<Self, AuditError> {
        cfg.validate()?;
        let tc = models
            .constraints
            .resolve(&models.human)
            .map_err(AuditError::Constraints)?;
        let rreach = RobotReach::try_new(&models.robot, cfg.tracking_error)
            .map_err(AuditError::TrackingError)?;
        let ncaps = rreach.capsule_count();
        if models.robot.links().len() > MAX_CAPSULES {
            return Err(AuditError::TooManyLinks {
                robot: models.robot.name().to_string(),
                max: MAX_CAPSULES,
            });
        }
        let env: Vec<EnvShape> = models.environment.iter().map(EnvShape::from).collect();
        let rule = ContactRule::new(
            &models.robot,
            &rreach,
            &models.human,
            &tc.per_part,
            env,
            cfg.rest_speed,
        )
        .map_err(AuditError::Rule)?;
        let cap_local: Vec<Capsule> = models
            .robot
            .links()
            .iter()
            .flat_map(|l| l.capsules.iter().copied())
            .collect();
        let zero = Capsule::new_unchecked(Point3::origin(), Point3::origin(), 0.0);
        let rcaps = vec![zero; ncaps];
        let n = models.robot.dof();
        let parts = models.human.body_parts().len();
        // A name says which model was used only where the spec is that built-in's: an inline
        // spec that reuses a built-in name (say "fr3" with other capsules) is labelled as such,
        // so that a report never presents a modified model under a built-in's name.
        let robot_name = models.robot.name();
        let human_name = &models.human.spec().name;
        let names = ModelNames {
            robot: label(
                robot_name,
                RobotModel::builtin(robot_name)
                    .ok()
                    .map(|b| b.spec() == models.robot.spec()),
            ),
            human: label(
                human_name,
                HumanModel::builtin(human_name)
                    .ok()
                    .map(|b| b.spec() == models.human.spec()),
            ),
            constraints: label(
                &tc.name,
                pacs_models::ConstraintSpec::builtin(&models.constraints.name)
                    .ok()
                    .map(|b| b == models.constraints),
            ),
            robot_v_max: models.robot.limits().v_max().to_vec(),
            robot_a_max: models.robot.limits().a_max().to_vec(),
            human_v_max: models.human.v_max().to_vec(),
            human_measurement_error_pos: models.human.measurement_error_pos(),
            human_delay: models.human.delay(),
            environment_shapes: models.environment.len(),
            specs: serde_json::json!({
                "robot": models.robot.spec(),
                "human": models.human.spec(),
                "constraints": models.constraints,
                "environment": models.environment.iter().map(|c| [
                    c.p1().x, c.p1().y, c.p1().z, c.p2().x, c.p2().y, c.p2().z, c.radius()
                ]).collect::<Vec<_>>(),
                "objects": models.objects.iter().map(|(id, m, contact)| serde_json::json!({
                    "id": id, "contact": contact,
                    "shape_generators": m.shape_generators(), "shape_radius": m.shape_radius(),
                    "max_acc": m.max_acc(), "acc_bias": m.acc_bias(),
                    "acc_generators": m.acc_generators(), "max_speed": m.max_speed(),
                    "pos_error": m.pos_error(), "vel_error": m.vel_error(), "delay": m.delay(),
                })).collect::<Vec<_>>(),
            }),
        };
        let links = models.robot.links().len();
        let object_rule =
            ObjectRule::new(&models.robot, &rreach, cfg.rest_speed).map_err(AuditError::Rule)?;
        let objects: Vec<ObjectTrack> = models
            .objects
            .iter()
            .map(|(id, model, contact)| ObjectTrack {
                id: id.clone(),
                model: *model,
                contact: *contact,
                latest: None,
                history: std::collections::VecDeque::with_capacity(HUMAN_HISTORY + 1),
                span: None,
                occ: None,
            })
            .collect();
        let slots = parts + objects.len();
        Ok(Self {
            object_rule,
            objects,
            hreach: HumanReach::new(models.human.clone(), cfg.human_model),
            rreach,
            cfg,
            n,
            parts,
            links,
            cap_local,
            rule,
            rcaps,
            hcaps: vec![zero; parts],
            energies: vec![0.0; n + 1],
            scratch: Box::default(),
            frames: vec![Isometry3::identity(); n + 1],
            nom_caps: vec![zero; ncaps],
            nom_key: [0.0; MAX_DOF],
            nom_key_valid: false,
            nom_energy: None,
            hits: Vec::with_capacity(slots * links),
            prev: None,
            block: Vec::with_capacity(BLOCK_SPANS + 1),
            block_encl: Vec::with_capacity(BLOCK_SPANS),
            dense_violations: false,
            block_fast_path: true,
            block_human: None,
            humans: [None, None],
            latest_human: None,
            model_breaks: Vec::new(),
            human_history: std::collections::VecDeque::with_capacity(HUMAN_HISTORY + 1),
            human_boxes: std::collections::VecDeque::with_capacity(HUMAN_HISTORY + 1),
            span_human: None,
            span_index: 0,
            open: vec![None; slots * links],
            violations: Vec::new(),
            inconclusive: Vec::new(),
            samples: 0,
            human_records: 0,
            unused_human_t_meas: None,
            awaiting_human_t_meas: None,
            t_first: f64::NAN,
            t_last: f64::NAN,
            violating_samples: 0,
            certain_samples: 0,
            last_span_violated: false,
            last_span_certain: false,
            inconclusive_duration: 0.0,
            min_separation: None,
            success: None,
            series: Series {
                t0: 0.0,
                width: 1e-3,
                buckets: Vec::with_capacity(SERIES_BUCKETS + 1),
            },
            environment: models.environment,
            robot: models.robot,
            human: models.human,
            names,
            person: None,
            track: None,
        })
    }

    /// An auditor of one person of a log (`person`: its id, named in the findings): the models
    /// with that person's human model. With `track`, the violating samples are kept by index,
    /// so that the passes of several people merge exactly (`crate::people`).
    pub fn for_person(
        models: LogModels,
        cfg: AuditConfig,
        person: &str,
        track: bool,
    ) -> Result<Self, AuditError> {
        let mut a = Self::new(models, cfg)?;
        a.person = Some(person.to_string());
        if track {
            a.track = Some(Box::default());
        }
        Ok(a)
    }

    /// Check every span on its own, without the block fast path: the reference the fast path is
    /// tested against (`audit/tests/audit_blocks.rs`: same verdict, violations and inconclusive
    /// spans), several times slower.
    #[doc(hidden)]
    pub fn without_block_fast_path(mut self) -> Self {
        self.block_fast_path = false;
        self
    }

    /// Robot degrees of freedom.
    pub fn dof(&self) -> usize {
        self.n
    }

    /// A human measurement logged at `t`, taken at `t_meas` (s). Errors name the field and value.
    ///
    /// The measurement in use for the spans is the newest by stamp, as in the shield
    /// (`HumanSlot::take`: an older or equal-stamp record arriving later is ignored); every
    /// record, used or not, is checked against the human model beside its neighbours in time
    /// ([`Self::check_human_model`]), so a record that contradicts the others cannot hide
    /// behind a newer one.
    pub fn push_human(
        &mut self,
        t: f64,
        t_meas: f64,
        positions: &[[f64; 3]],
    ) -> Result<(), AuditError> {
        if !t_meas.is_finite() {
            return Err(AuditError::NotFinite {
                field: "t_meas".into(),
                value: t_meas,
            });
        }
        if t_meas > t {
            return Err(AuditError::MeasurementFromFuture { t_meas, t });
        }
        let m = HumanMeasurement::new(&self.human, t_meas, positions, None)
            .map_err(AuditError::Measurement)?;
        self.check_human_model(&m);
        self.human_records += 1;
        // Every human record after the last robot sample counts, used or not: keep the earliest
        // measurement time (a record describing a time inside the log after its last sample).
        self.unused_human_t_meas = Some(self.unused_human_t_meas.map_or(t_meas, |u| u.min(t_meas)));
        let in_use = self.latest_human.and_then(|s| self.humans[s].as_ref());
        if !m.supersedes(in_use) {
            // Not newer than the measurement in use: checked above, not used (as the shield).
            return Ok(());
        }
        // Check the pending spans first: afterwards only `span_human`'s slot is still needed.
        self.flush_block();
        self.block_human = self.span_human;
        let slot = match self.span_human {
            Some(s) => 1 - s,
            None => 0,
        };
        self.humans[slot] = Some(m);
        self.latest_human = Some(slot);
        Ok(())
    }

    /// Whether `m` is consistent with the human model beside every kept measurement (the latest
    /// [`HUMAN_HISTORY`] by stamp, in whatever order they arrived): every keypoint moved at most
    /// `v_max·|Δt| + 2·e_pos` (m) between the two stamps (both describe the state `delay`
    /// earlier). Checking every kept one, not only the neighbours in time, also catches a chain
    /// of records each within `2·e_pos` of the previous (equal stamps) drifting away from the
    /// first. A contradiction is recorded as `human_exceeds_model` over the stamps of `m` and of
    /// the nearest contradicting record on each side in time ([`Nearest`]): the audit's
    /// occupancies assume the model, so a pass there would rest on an assumption the log itself
    /// refutes. `m` is then kept.
    fn check_human_model(&mut self, m: &HumanMeasurement) {
        let mut nearest = Nearest::new(m.time());
        let mbox = KeypointBox::of(m);
        let v_min = self
            .human
            .v_max()
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min);
        let e2 = 2.0 * self.human.measurement_error_pos();
        for (h, hbox) in self.human_history.iter().zip(&self.human_boxes) {
            if !pair_within_boxes(v_min, e2, h, m, hbox, &mbox)
                && human_pair_breaks(&self.human, h, m)
            {
                nearest.add(h.time());
            }
        }
        for (t0, t1) in nearest.pairs() {
            self.model_break(t0, t1, Reason::HumanExceedsModel);
        }
        // Keep `m` in stamp order; when full, the oldest's storage is reused (no allocation
        // after warm-up), and a record older than all kept ones is not kept.
        let at = self.human_history.partition_point(|h| h.time() <= m.time());
        if self.human_history.len() < HUMAN_HISTORY {
            self.human_history.insert(at, m.clone());
            self.human_boxes.insert(at, mbox);
        } else if at > 0 {
            let mut slot = self.human_history.pop_front().expect("the history is full");
            slot.assign_from(m);
            self.human_history.insert(at - 1, slot);
            self.human_boxes.pop_front();
            self.human_boxes.insert(at - 1, mbox);
        }
    }

    /// Record a contradiction of a model between the stamps `t0 ≤ t1` (merged with the previous
    /// one of the same reason where they chain).
    fn model_break(&mut self, t0: f64, t1: f64, reason: Reason) {
        match self.model_breaks.last_mut() {
            Some(last) if last.reason == reason && last.t_end >= t0 && last.t_start <= t1 => {
                last.t_start = last.t_start.min(t0);
                last.t_end = last.t_end.max(t1);
                last.spans += 1;
            }
            _ => self.model_breaks.push(InconclusiveSpan {
                t_start: t0,
                t_end: t1,
                reason,
                spans: 1,
                person: None,
            }),
        }
    }

    /// A measurement of object `id` (declared in the header) logged at `t`, taken at `t_meas`
    /// (s): position (m), velocity (m/s) if measured. Errors name the field and value.
    pub fn push_object(
        &mut self,
        t: f64,
        t_meas: f64,
        id: &str,
        position: [f64; 3],
        velocity: Option<[f64; 3]>,
    ) -> Result<(), AuditError> {
        let Some(k) = self.objects.iter().position(|o| o.id == id) else {
            return Err(AuditError::UnknownObject { id: id.to_string() });
        };
        for (field, v) in std::iter::once(("t_meas", t_meas))
            .chain(position.iter().map(|x| ("position", *x)))
            .chain(velocity.iter().flatten().map(|x| ("velocity", *x)))
        {
            if !v.is_finite() {
                return Err(AuditError::NotFinite {
                    field: format!("object `{id}`: {field}"),
                    value: v,
                });
            }
        }
        if t_meas > t {
            return Err(AuditError::MeasurementFromFuture { t_meas, t });
        }
        let m = ObjectMeasurement {
            time: t_meas,
            position,
            velocity,
        };
        // Every record is checked against every kept one (older or newer, as it arrives); the
        // newest by stamp is the one in use, as in the shield (`keep_newest`: the first of equal
        // stamps stays).
        if object_record_breaks(&self.objects[k].model, &m) {
            self.model_break(m.time, m.time, Reason::ObjectExceedsModel);
        }
        let mut nearest = Nearest::new(m.time);
        let o = &self.objects[k];
        for cur in &o.history {
            let (early, late) = if cur.time <= m.time {
                (cur, &m)
            } else {
                (&m, cur)
            };
            if object_pair_breaks(&o.model, early, late) {
                nearest.add(cur.time);
            }
        }
        for (t0, t1) in nearest.pairs() {
            self.model_break(t0, t1, Reason::ObjectExceedsModel);
        }
        let o = &mut self.objects[k];
        let at = o.history.partition_point(|h| h.time <= m.time);
        o.history.insert(at, m);
        if o.history.len() > HUMAN_HISTORY {
            o.history.pop_front();
        }
        m.keep_newest(&mut o.latest);
        Ok(())
    }

    /// An event; `success` and `failure` set the task outcome (the last one counts).
    pub fn push_event(&mut self, name: &str) {
        match name {
            "success" => self.success = Some(true),
            "failure" => self.success = Some(false),
            _ => {}
        }
    }

    /// A robot sample at `t` (s): positions (rad), optional velocities (rad/s). Checks the span
    /// from the previous sample. Errors (wrong length, non-finite value) name the field.
    pub fn push_robot(&mut self, t: f64, q: &[f64], dq: Option<&[f64]>) -> Result<(), AuditError> {
        self.push_robot_with_acc(t, q, dq, None)
    }

    /// A robot sample at `t` (s): positions (rad), optional velocities (rad/s) and optional
    /// accelerations (rad/s², used with the jerk limit between samples; only together with
    /// velocities). Checks the span from the previous sample. Errors name the field.
    pub fn push_robot_with_acc(
        &mut self,
        t: f64,
        q: &[f64],
        dq: Option<&[f64]>,
        ddq: Option<&[f64]>,
    ) -> Result<(), AuditError> {
        let n = self.n;
        if q.len() != n {
            return Err(AuditError::JointCount {
                field: "q",
                what: "positions",
                expected: n,
                robot: self.names.robot.clone(),
                found: q.len(),
            });
        }
        if let Some((i, x)) = q.iter().enumerate().find(|(_, x)| !x.is_finite()) {
            return Err(AuditError::NotFinite {
                field: format!("q[{i}]"),
                value: *x,
            });
        }
        if !t.is_finite() {
            return Err(AuditError::NotFinite {
                field: "t".into(),
                value: t,
            });
        }
        let mut s = Sample {
            t,
            q: [0.0; MAX_DOF],
            dq: [0.0; MAX_DOF],
            ddq: [0.0; MAX_DOF],
            has_dq: false,
            has_ddq: false,
        };
        s.q[..n].copy_from_slice(q);
        for (field, what, src, dst, flag) in [
            ("dq", "velocities", dq, &mut s.dq, &mut s.has_dq),
            ("ddq", "accelerations", ddq, &mut s.ddq, &mut s.has_ddq),
        ] {
            let Some(v) = src else { continue };
            if v.len() != n {
                return Err(AuditError::JointCount {
                    field,
                    what,
                    expected: n,
                    robot: self.names.robot.clone(),
                    found: v.len(),
                });
            }
            if let Some((i, x)) = v.iter().enumerate().find(|(_, x)| !x.is_finite()) {
                return Err(AuditError::NotFinite {
                    field: format!("{field}[{i}]"),
                    value: *x,
                });
            }
            dst[..n].copy_from_slice(v);
            *flag = true;
        }
        if s.has_ddq && !s.has_dq {
            return Err(AuditError::AccelerationWithoutVelocity);
        }
        // The human records before the previous sample are in use for the span that this sample
        // closes; those since the previous sample wait for the span this sample opens.
        self.awaiting_human_t_meas = self.unused_human_t_meas.take();
        if self.prev.is_none() {
            self.t_first = t;
            self.series.t0 = t;
        }
        if self.block.is_empty() {
            self.block_human = self.span_human;
        } else if self.span_human != self.block_human {
            // The new span uses another human measurement: close the block.
            self.flush_block();
            self.block_human = self.span_human;
        }
        self.block.push(s);
        if self.block.len() > BLOCK_SPANS {
            self.flush_block();
            self.block_human = self.latest_human;
        }
        // The next span uses the newest object measurements: if one changed, the block (whose
        // spans all used `span`) is checked first, with the measurements it used.
        if self.objects.iter().any(|o| o.span != o.latest) {
            self.flush_block();
        }
        self.prev = Some(s);
        self.span_human = self.latest_human;
        for o in &mut self.objects {
            o.span = o.latest;
        }
        self.samples += 1;
        self.t_last = t;
        Ok(())
    }
}

/// A model's name for reports: the name where the spec is the built-in of that name
/// (`same = Some(true)`), else marked as a custom spec (and, where a built-in has that name, as
/// not being it).
fn label(name: &str, same: Option<bool>) -> String {
    match same {
        Some(true) => name.to_string(),
        Some(false) => format!("{name} (custom spec, not the built-in {name})"),
        None => format!("{name} (custom spec)"),
    }
}

/// Whether the stamps of a span `[t0, t1]` resolve its length (`pacs_log::time::clock_resolves`
/// at the larger stamp, the shield's rule for its clock). A zero-length span needs no resolution
/// (its samples are judged by their consistency; a log of only such spans is `no_time_covered`).
pub(crate) fn stamps_resolve(t0: f64, t1: f64) -> bool {
    let dt = t1 - t0;
    dt <= 0.0 || pacs_log::time::clock_resolves(t0.abs().max(t1.abs()), dt)
}

/// `(min, max)` of two times.
fn order(a: f64, b: f64) -> (f64, f64) {
    (a.min(b), a.max(b))
}

/// The stamps of the records that contradict a new record at `t`, reduced to the nearest one at
/// or before `t` and the nearest one after it: the break is reported over the shortest spans of
/// time it is known to lie in.
struct Nearest {
    t: f64,
    before: Option<f64>,
    after: Option<f64>,
}

impl Nearest {
    fn new(t: f64) -> Self {
        Self {
            t,
            before: None,
            after: None,
        }
    }

    fn add(&mut self, s: f64) {
        if s <= self.t {
            self.before = Some(self.before.map_or(s, |b| b.max(s)));
        } else {
            self.after = Some(self.after.map_or(s, |a| a.min(s)));
        }
    }

    /// `(t_start, t_end)` of each break found (none, one or two).
    fn pairs(&self) -> impl Iterator<Item = (f64, f64)> + use<> {
        let t = self.t;
        self.before
            .map(|b| order(b, t))
            .into_iter()
            .chain(self.after.map(|a| order(t, a)))
    }
}

/// Whether two measurements of one person contradict the human model: some keypoint moved
/// farther than `v_max·|Δt| + 2·e_pos` (m) between their stamps. Conservative both ways: the
/// distance rounded up, the allowance rounded down, so rounding never hides a contradiction
/// (only one within an ulp is flagged too).
fn human_pair_breaks(model: &HumanModel, a: &HumanMeasurement, b: &HumanMeasurement) -> bool {
    let (lo, hi) = order(a.time(), b.time());
    // Plain floats for the fast accept below; outward-rounded bounds only where it does not
    // decide.
    let (dt_plain, e2_plain) = ((hi - lo).max(0.0), 2.0 * model.measurement_error_pos());
    a.positions()
        .iter()
        .zip(b.positions())
        .zip(model.v_max())
        .any(|((p, q), v)| {
            // Equal positions moved by 0 m, within any allowance (≥ 0): an exact duplicate of a
            // record is no contradiction, even where outward rounding of a zero distance would
            // exceed a zero allowance (no measurement error, equal stamps).
            if p == q {
                return false;
            }
            // Fast accept in plain floats: the squared distance and the squared allowance (three
            // rounded operations from exact values) each carry a relative rounding error of a few
            // ε, far inside the 1e-9 margin, so a pair accepted here is within the allowance
            // exactly. Only where neither overflows (d² finite) nor underflows (allowance ≥
            // 1e-150, so its square is normal and an underflowed d² is far below it); everything
            // else is decided by the outward-rounded distance and allowance.
            let plain = v * dt_plain + e2_plain;
            let (dx, dy, dz) = (p.x - q.x, p.y - q.y, p.z - q.z);
            let d2 = dx * dx + dy * dy + dz * dz;
            if plain >= 1e-150 && d2.is_finite() && d2 <= plain * plain * (1.0 - 1e-9) {
                return false;
            }
            let dt = sub_down(hi, lo).max(0.0);
            let allowed = add_down(
                mul_down(*v, dt),
                mul_down(2.0, model.measurement_error_pos()),
            );
            dist3_up(&[p.x, p.y, p.z], &[q.x, q.y, q.z]) > allowed
        })
}

/// The axis-aligned bounding box of a measurement's keypoints (m): `[min x, min y, min z, max
/// x, max y, max z]`.
#[derive(Debug, Clone, Copy)]
struct KeypointBox([f64; 6]);

impl KeypointBox {
    fn of(m: &HumanMeasurement) -> Self {
        let mut b = [
            f64::INFINITY,
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ];
        for p in m.positions() {
            for (k, x) in [p.x, p.y, p.z].into_iter().enumerate() {
                b[k] = b[k].min(x);
                b[k + 3] = b[k + 3].max(x);
            }
        }
        Self(b)
    }
}

/// A quick accept for [`human_pair_breaks`]: true only if no keypoint of `a` and `b` moved more
/// than the least allowance of any keypoint (`v_min · |Δt| + e2`, `v_min` the least of the
/// model's `v_max`, `e2` twice its position error), shown by the diagonal of the box holding both
/// measurements' keypoints, which bounds every keypoint's displacement. In plain floats, with the
/// margin and the range conditions of the fast accept in [`human_pair_breaks`] (relative rounding
/// errors of a few ε, far inside 1e-9). False says nothing; the caller then applies
/// [`human_pair_breaks`]. Property test `the_box_accept_of_a_human_pair_is_sound`.
fn pair_within_boxes(
    v_min: f64,
    e2: f64,
    a: &HumanMeasurement,
    b: &HumanMeasurement,
    ba: &KeypointBox,
    bb: &KeypointBox,
) -> bool {
    let allowed = v_min * (a.time() - b.time()).abs() + e2;
    let mut d2 = 0.0;
    for k in 0..3 {
        let e = ba.0[k + 3].max(bb.0[k + 3]) - ba.0[k].min(bb.0[k]);
        d2 += e * e;
    }
    allowed >= 1e-150 && d2.is_finite() && d2 <= allowed * allowed * (1.0 - 1e-9)
}

/// A Euclidean norm rounded down (`pacs_reach::rounding::norm3_down`, harness a3).
fn norm3_down(v: [f64; 3]) -> f64 {
    pacs_reach::rounding::norm3_down(v[0], v[1], v[2])
}

/// An upper bound of the norm of every acceleration in an object's acceleration set (m/s²):
/// |bias| + Σ|generators| + `max_acc` (triangle inequality), each norm rounded down, so the
/// bound is below the exact one by ulps at most (a check using it flags within-ulp cases too).
fn object_acc_bound(model: &ObjectModel) -> f64 {
    let mut acc = norm3_down(model.acc_bias());
    for g in model.acc_generators() {
        acc = add_down(acc, norm3_down(*g));
    }
    add_down(acc, model.max_acc())
}

/// Whether one measurement of an object contradicts its model: a measured velocity faster than
/// the speed bound plus the velocity error (the true velocity is within `vel_error` of it and
/// never faster than `max_speed`). Rounding never hides a contradiction.
fn object_record_breaks(model: &ObjectModel, m: &ObjectMeasurement) -> bool {
    match (model.max_speed(), m.velocity) {
        (Some(vmax), Some(v)) => norm3_up(v[0], v[1], v[2]) > add_down(vmax, model.vel_error()),
        _ => false,
    }
}

/// Whether two measurements of one object, `early` stamped no later than `late`, contradict its
/// model (both describe the state `delay` before their stamps, so `Δt` is the stamps'
/// difference):
/// - velocities, where both are measured, farther apart than `a·Δt + 2·vel_error` (`a`:
///   [`object_acc_bound`]);
/// - positions farther apart than the model allows over `Δt` plus twice the position error:
///   the smallest of `max_speed·Δt` (with a speed bound) and `(|v| + vel_error)·Δt + a·Δt²/2`
///   for each measured velocity `v` (forward from the early one, backward from the late one);
///   with none of these the model bounds nothing and no pair contradicts it.
///
/// Allowances are rounded down and distances up: rounding never hides a contradiction.
fn object_pair_breaks(
    model: &ObjectModel,
    early: &ObjectMeasurement,
    late: &ObjectMeasurement,
) -> bool {
    let dt = sub_down(late.time, early.time).max(0.0);
    let acc = object_acc_bound(model);
    let ev = model.vel_error();
    if let (Some(a), Some(b)) = (early.velocity, late.velocity)
        && a != b
        && dist3_up(&a, &b) > add_down(mul_down(acc, dt), mul_down(2.0, ev))
    {
        return true;
    }
    // Equal positions are within any allowance (exact duplicates are no contradiction).
    if early.position == late.position {
        return false;
    }
    let by_speed = model.max_speed().map(|v| mul_down(v, dt));
    let by_velocity = [early.velocity, late.velocity]
        .into_iter()
        .flatten()
        .map(|v| {
            let speed = add_down(norm3_down(v), ev);
            add_down(
                mul_down(speed, dt),
                mul_down(mul_down(0.5, acc), mul_down(dt, dt)),
            )
        })
        .reduce(f64::min);
    let allowed = match (by_speed, by_velocity) {
        (Some(a), Some(b)) => a.min(b),
        (Some(a), None) | (None, Some(a)) => a,
        (None, None) => return false,
    };
    let allowed = add_down(allowed, mul_down(2.0, model.pos_error()));
    dist3_up(&early.position, &late.position) > allowed
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A seeded xorshift generator of uniform numbers in [0, 1).
    fn uniform(seed: u64) -> impl FnMut() -> f64 {
        let mut x = seed;
        move || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// The box accept never hides a contradiction: wherever `pair_within_boxes` accepts a pair,
    /// `human_pair_breaks` (the reference) finds none; and it accepts most pairs far apart in
    /// time (what it is for). 20 000 random pairs of the default model's keypoints, moved up to
    /// 2× the allowance, at time differences from 0 to 2 s.
    #[test]
    fn the_box_accept_of_a_human_pair_is_sound() {
        let model = HumanModel::builtin("default").unwrap();
        let mut next = uniform(0x9e37_79b9_7f4a_7c15u64);
        let (mut accepted, mut far, mut far_accepted) = (0, 0, 0);
        for _ in 0..20_000 {
            let dt = 2.0 * next() * next();
            let size = 2.0 * next();
            let base: Vec<[f64; 3]> = (0..9)
                .map(|_| [next() * size, next() * size, 1.0 + next() * size])
                .collect();
            let reach = 2.0 * (2.0 * dt + 2.0 * model.measurement_error_pos()) * next();
            let moved: Vec<[f64; 3]> = base
                .iter()
                .map(|p| {
                    let d = [next() - 0.5, next() - 0.5, next() - 0.5];
                    let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt().max(1e-300);
                    let len = reach * next();
                    [
                        p[0] + d[0] / n * len,
                        p[1] + d[1] / n * len,
                        p[2] + d[2] / n * len,
                    ]
                })
                .collect();
            let (Ok(a), Ok(b)) = (
                HumanMeasurement::new(&model, 0.0, &base, None),
                HumanMeasurement::new(&model, dt, &moved, None),
            ) else {
                continue;
            };
            let v_min = model.v_max().iter().copied().fold(f64::INFINITY, f64::min);
            let e2 = 2.0 * model.measurement_error_pos();
            let quick = pair_within_boxes(
                v_min,
                e2,
                &a,
                &b,
                &KeypointBox::of(&a),
                &KeypointBox::of(&b),
            );
            if quick {
                accepted += 1;
                assert!(
                    !human_pair_breaks(&model, &a, &b),
                    "dt {dt}, size {size}: accepted a contradicting pair"
                );
            }
            // Far apart in time, a person of up to 0.5 m moved by at most a quarter of the
            // allowance: the box diagonal is within it, so the box accepts.
            let allowance = 2.0 * dt + 2.0 * model.measurement_error_pos();
            if dt > 1.0 && size < 0.5 && reach < 0.25 * allowance {
                far += 1;
                far_accepted += quick as usize;
            }
        }
        assert!(accepted > 1_000, "{accepted}");
        assert!(far > 50 && far_accepted == far, "{far_accepted} of {far}");
    }

    /// The fast accept in `human_pair_breaks` is sound: a pair it accepts is within the
    /// allowance by the outward-rounded test applied to the same pair scaled by a power of two
    /// into the unit range (exact scaling, where the rounded test's absolute error terms are
    /// negligible). 20 000 random pairs at scales from 1e-160 to 1e150 m, a third of them with
    /// a keypoint within a relative 1e-12 of the allowance, where rounding decides; where the
    /// fast path does not accept, the answer is the rounded test's.
    #[test]
    fn the_fast_accept_of_a_human_pair_is_sound() {
        let model = HumanModel::builtin("default").unwrap();
        let mut next = uniform(0x2545_f491_4f6c_dd1du64);
        let (mut breaks, mut cases) = (0, 0);
        for i in 0..20_000 {
            let scale = 10f64.powf(-160.0 + 310.0 * next());
            let dt = scale * next();
            let v = model.v_max()[0];
            let base: Vec<[f64; 3]> = (0..9)
                .map(|_| [next() * scale, next() * scale, next() * scale])
                .collect();
            let moved: Vec<[f64; 3]> = base
                .iter()
                .enumerate()
                .map(|(j, p)| {
                    // A direction, and a length: within the allowance (one case in three), at it
                    // (±1e-12) for the first keypoint and half of it for the others, or anywhere
                    // up to 2× for one keypoint.
                    let d = [next() - 0.5, next() - 0.5, next() - 0.5];
                    let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt().max(1e-300);
                    let len = match (i % 3, j) {
                        (0, _) => v * dt * next(),
                        (1, 0) => v * dt * (1.0 + 1e-12 * (2.0 * next() - 1.0)),
                        (2, 0) => 2.0 * v * dt * next(),
                        _ => 0.5 * v * dt,
                    };
                    [
                        p[0] + d[0] / n * len,
                        p[1] + d[1] / n * len,
                        p[2] + d[2] / n * len,
                    ]
                })
                .collect();
            let (Ok(a), Ok(b)) = (
                HumanMeasurement::new(&model, 0.0, &base, None),
                HumanMeasurement::new(&model, dt, &moved, None),
            ) else {
                continue;
            };
            let got = human_pair_breaks(&model, &a, &b);
            // The rounded test on the pair scaled by 2^k (exact) into the unit range.
            let k = -(scale.log2().round() as i32);
            let f = 2f64.powi(k);
            let e2 = mul_down(2.0, model.measurement_error_pos());
            let allowed = add_down(mul_down(v, sub_down(dt, 0.0).max(0.0)), e2) * f;
            let reference = base.iter().zip(&moved).any(|(p, q)| {
                let (ps, qs) = (
                    [p[0] * f, p[1] * f, p[2] * f],
                    [q[0] * f, q[1] * f, q[2] * f],
                );
                dist3_up(&ps, &qs) > allowed
            });
            if !got {
                assert!(
                    !reference,
                    "case {i}, scale {scale}: accepted a pair beyond the allowance"
                );
            }
            let rounded = base
                .iter()
                .zip(&moved)
                .zip(model.v_max())
                .any(|((p, q), v)| {
                    dist3_up(p, q) > add_down(mul_down(*v, sub_down(dt, 0.0).max(0.0)), e2)
                });
            if got {
                assert!(rounded, "case {i}: flagged what the rounded test does not");
            }
            breaks += got as usize;
            cases += 1;
        }
        assert!(
            cases > 19_000 && breaks > cases / 5 && breaks < cases / 2,
            "{breaks} of {cases}"
        );
    }

    #[test]
    fn reach_sphere_contains_the_robot_in_every_sampled_configuration() {
        let robot = RobotModel::builtin("fr3").unwrap();
        let s = pacs_verify::iso15066::workspace_ball(&robot, 0.0);
        let mut next = uniform(0x9e37_79b9_7f4a_7c15u64);
        for _ in 0..2000 {
            // Any configuration, not only within the limits.
            let q: Vec<f64> = (0..7)
                .map(|_| (next() - 0.5) * 4.0 * std::f64::consts::PI)
                .collect();
            for (_, c) in robot.capsules_world(&q) {
                for p in [c.p1(), c.p2()] {
                    assert!((p - s.p1()).norm() + c.radius() <= s.radius());
                }
            }
        }
        // Not absurdly loose: FR3 reaches about 1.2 m including the gripper.
        assert!(s.radius() < 2.0, "{}", s.radius());
    }
}
