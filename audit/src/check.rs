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

use crate::enclosure::{
    Sample, SpanBoxes, SpanEnclosure, SpanLimits, adjacent_spans_agree, span_boxes_into,
};
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
use pacs_reach::rounding::{add_down, add_up, norm3_up, sub_down};
use pacs_verify::iso15066::{
    ContactRule, EnvShape, ObjectRule, Outcome, frames_can_pinch, threshold,
};
use std::ops::ControlFlow;

pub use crate::config::AuditConfig;

/// Maximum number of robot capsules supported (bit masks).
pub use pacs_verify::iso15066::MAX_CAPSULES;
/// Spans checked together by the block fast path (see `Auditor::check_block`): at most this many
/// share one check. 40 holds every span of one person record at 30 Hz (33–34 spans at 1 kHz) in
/// one block, so no such record leaves a lone span to check besides.
pub const BLOCK_SPANS: usize = 40;
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
use crate::series::{NominalAt, Series, max_opt, min_opt};
use crate::verdict::InconclusiveReason as Reason;

// The span checks (block fast path, span by span) and the certain check live in submodules
// with access to the auditor's state.
mod certain;
mod consistency;
mod finish;
mod spans;

use consistency::{
    KeypointBox, LetGo, Nearest, ObjectBounds, human_pair_breaks, object_pair_breaks,
    object_record_breaks, pair_within_boxes,
};

/// A dynamic object of the log: its model, allowed contact and measurements.
#[derive(Debug, Clone)]
struct ObjectTrack {
    id: String,
    model: ObjectModel,
    /// What the record-against-record check needs of `model` (its acceleration bound: norms of
    /// the bias and generators), computed once.
    bounds: ObjectBounds,
    contact: ObjectContact,
    /// The measurement in use: the newest by stamp, the first of equal stamps
    /// ([`ObjectMeasurement::keep_newest`]; the shield's rule for measurements that agree with
    /// the ones it trusts — one that contradicts them it does not use, and the audit finds the
    /// contradiction).
    latest: Option<ObjectMeasurement>,
    /// The latest [`HUMAN_HISTORY`] measurements by stamp, for the model check of each record.
    history: std::collections::VecDeque<ObjectMeasurement>,
    /// The newest stamp of a record let go from `history` (or not kept), if any: a later
    /// record as old as every kept one, with a let-go one older than it, cannot be checked
    /// against its neighbours in time ([`too_late`], `object_record_too_late`).
    dropped: Option<f64>,
    /// What the records let go from `history` still require of later ones ([`LetGo`]): their
    /// positions (under the speed bound) and their measured velocities (under the acceleration
    /// bound).
    let_go: LetGo,
    let_go_vel: LetGo,
    /// The newest record let go that carries a velocity: later records are held to it whole
    /// (its direction included, which [`LetGo`] does not keep).
    let_go_moving: Option<ObjectMeasurement>,
    /// The measurement in use for the span the last robot sample opened (like `span_human`).
    span: Option<ObjectMeasurement>,
    /// Its occupancy over the span being checked (`None`: outside the workspace ball, or none).
    occ: Option<ObjectOccupancy>,
    /// Why the object cannot be checked on the span being checked, if it cannot.
    unusable: Option<Reason>,
    /// The records that may clear what the one in `others_for` shows (`spans.rs`,
    /// `collect_other_object_records`); `others_for` is reset when a record arrives.
    others: Vec<ObjectMeasurement>,
    others_for: Option<ObjectMeasurement>,
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
    /// Per joint, the position band a sample must lie in (rad): the limits widened by the
    /// relative `limit_slack` (at least `limit_slack` rad), computed once; lower and upper
    /// ends, unbounded beyond the robot's joints (so that the test runs over every lane).
    q_band: ([f64; MAX_DOF], [f64; MAX_DOF]),
    /// The joints' rate limits as the span enclosures read them, prepared once.
    span_limits: SpanLimits,
    parts: usize,
    links: usize,
    cap_local: Vec<Capsule>,
    // Buffers.
    rcaps: Vec<Capsule>,
    hcaps: Vec<Capsule>,
    /// The human occupancy from another measurement than the span's (see
    /// `clear_by_other_measurements`), and the (part, link) pairs it leaves violating.
    alt_hcaps: Vec<Capsule>,
    alt_pairs: Vec<(usize, usize)>,
    /// Indices into `human_history` of the records that may clear what the one in `humans`
    /// slot `alt_humans_for` shows (`collect_other_human_records`); `None` once either changes.
    alt_humans: Vec<usize>,
    alt_humans_for: Option<usize>,
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
    /// Buffered samples whose spans all use the human measurement `block_human`.
    block: Vec<Sample>,
    /// The enclosures of the block's spans (a buffer of `flush_block`).
    block_encl: Vec<SpanEnclosure>,
    /// The sample before the last one of the latest block checked (`flush_block`): at the end,
    /// the sample before the log's last one, whose span bounds the final instant's velocities.
    before_last: Option<Sample>,
    /// The latest sample stamped before the last block's last sample (`flush_block`): the start
    /// of the span the next block's first span must agree with ([`adjacent_spans_agree`]).
    earlier: Option<Sample>,
    /// The last spans checked one by one were mostly violating: check the next blocks span by
    /// span, neither whole nor in halves (speed only).
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
    /// The newest stamp of a record let go from `human_history` (or not kept), if any: a later
    /// record as old as every kept one, with a let-go one older than it, cannot be checked
    /// against its neighbours in time ([`too_late`], `human_record_too_late`).
    human_dropped: Option<f64>,
    /// What the records let go from `human_history` still require of later ones ([`LetGo`]).
    human_let_go: LetGo,
    /// The bounding box of each kept measurement's keypoints (same order as `human_history`).
    human_boxes: std::collections::VecDeque<KeypointBox>,
    span_human: Option<usize>,
    span_index: u64,
    open: Vec<Option<OpenInterval>>,
    violations: Vec<Violation>,
    inconclusive: Vec<(InconclusiveSpan, Reason, u64)>,
    samples: u64,
    /// Exact copies of the previous sample, skipped ([`Self::repeats_last_sample`]).
    copies: u64,
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

/// Whether a record stamped `t` cannot be checked against its neighbours in time, given the
/// oldest kept record's stamp `oldest` and whether a record was let go (`dropped`, the newest
/// stamp of one): it is older than every kept record after some were let go, or as old as the
/// oldest kept one (a let-go record may be its neighbour: older, or of its own stamp, where two
/// records may differ by `2·e_pos` only) unless it copies a kept record of its stamp
/// (`copies_a_kept_one`: the same values, so the same checks; a tracker's stamp repeated more
/// than [`HUMAN_HISTORY`] times).
fn too_late(
    t: f64,
    oldest: f64,
    dropped: Option<f64>,
    copies_a_kept_one: impl FnOnce() -> bool,
) -> bool {
    dropped.is_some() && (t < oldest || (t == oldest && !copies_a_kept_one()))
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
        let names = model_names(&models, &tc.name);
        let links = models.robot.links().len();
        let object_rule =
            ObjectRule::new(&models.robot, &rreach, cfg.rest_speed).map_err(AuditError::Rule)?;
        let objects = object_tracks(&models);
        let slots = parts + objects.len();
        let mut q_band = ([f64::NEG_INFINITY; MAX_DOF], [f64::INFINITY; MAX_DOF]);
        {
            let (lim, slack) = (models.robot.limits(), cfg.limit_slack);
            for j in 0..n {
                let (lo, hi) = (lim.q_min()[j], lim.q_max()[j]);
                q_band.0[j] = lo - slack * lo.abs().max(1.0);
                q_band.1[j] = hi + slack * hi.abs().max(1.0);
            }
        }
        Ok(Self {
            object_rule,
            objects,
            hreach: HumanReach::new(models.human.clone(), cfg.human_model),
            rreach,
            cfg,
            n,
            q_band,
            span_limits: SpanLimits::new(models.robot.limits()),
            parts,
            links,
            cap_local,
            rule,
            rcaps,
            hcaps: vec![zero; parts],
            alt_hcaps: vec![zero; parts],
            alt_pairs: Vec::with_capacity(slots * links),
            alt_humans: Vec::with_capacity(HUMAN_HISTORY),
            alt_humans_for: None,
            energies: vec![0.0; n + 1],
            scratch: Box::default(),
            frames: vec![Isometry3::identity(); n + 1],
            nom_caps: vec![zero; ncaps],
            nom_key: [0.0; MAX_DOF],
            nom_key_valid: false,
            nom_energy: None,
            hits: Vec::with_capacity(slots * links),
            block: Vec::with_capacity(BLOCK_SPANS + 1),
            block_encl: Vec::with_capacity(BLOCK_SPANS),
            before_last: None,
            earlier: None,
            dense_violations: false,
            block_fast_path: true,
            block_human: None,
            humans: [None, None],
            latest_human: None,
            model_breaks: Vec::new(),
            human_history: std::collections::VecDeque::with_capacity(HUMAN_HISTORY + 1),
            human_dropped: None,
            human_let_go: LetGo::new(models.human.keypoint_count()),
            human_boxes: std::collections::VecDeque::with_capacity(HUMAN_HISTORY + 1),
            span_human: None,
            span_index: 0,
            open: vec![None; slots * links],
            violations: Vec::new(),
            inconclusive: Vec::new(),
            samples: 0,
            copies: 0,
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
                nominal: Vec::with_capacity(SERIES_BUCKETS + 1),
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

    /// Whether other people share the cell: every PFL contact may then be a pinch against one of
    /// them ([`ContactRule::set_other_people`]; `PeopleAuditor` sets it for a log with
    /// several people).
    pub(crate) fn set_other_people(&mut self, present: bool) {
        self.rule.set_other_people(present);
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
        // The new measurement goes into the slot `span_human` does not use. While the pending
        // spans use `span_human`'s slot too (no record arrived since the last sample), they stay
        // pending: the span the next sample closes still uses that measurement and joins their
        // block. Otherwise the pending spans use the slot about to be written: checked first.
        if self.block_human != self.span_human {
            self.flush_block();
            self.block_human = self.span_human;
        }
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
        // The kept records change: the candidates for clearing spans are collected anew.
        self.alt_humans_for = None;
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
        // Against the records let go, in constant memory (a drift through the kept ones).
        let points = m
            .positions()
            .iter()
            .zip(self.human.v_max())
            .map(|(p, &v)| ([p.x, p.y, p.z], v));
        if let Some(d) = self.human_dropped
            && m.time() >= d
            && self.human_let_go.breaks(m.time(), e2, points)
        {
            self.model_break(d, m.time(), Reason::HumanExceedsModel);
        }
        // Keep `m` in stamp order; when full, the oldest's storage is reused (no allocation
        // after warm-up), and a record older than all kept ones is not kept.
        let at = self.human_history.partition_point(|h| h.time() <= m.time());
        // Its older neighbours in time may be gone: not checked against them.
        if let Some(oldest) = self.human_history.front()
            && too_late(m.time(), oldest.time(), self.human_dropped, || {
                self.human_history
                    .iter()
                    .take_while(|h| h.time() == m.time())
                    .any(|h| h.positions() == m.positions() && h.velocities() == m.velocities())
            })
        {
            let t1 = oldest.time();
            self.model_break(m.time(), t1, Reason::HumanRecordTooLate);
        }
        if self.human_history.len() < HUMAN_HISTORY {
            self.human_history.insert(at, m.clone());
            self.human_boxes.insert(at, mbox);
        } else if at == 0 {
            // Not kept: older than (or as old as) every kept one.
            self.human_dropped = Some(self.human_dropped.map_or(m.time(), |d| d.max(m.time())));
            let points = m
                .positions()
                .iter()
                .zip(self.human.v_max())
                .map(|(p, &v)| ([p.x, p.y, p.z], v));
            self.human_let_go.add(m.time(), points);
        } else {
            let mut slot = self.human_history.pop_front().expect("the history is full");
            let gone = slot.time();
            self.human_dropped = Some(self.human_dropped.map_or(gone, |d| d.max(gone)));
            let points = slot
                .positions()
                .iter()
                .zip(self.human.v_max())
                .map(|(p, &v)| ([p.x, p.y, p.z], v));
            self.human_let_go.add(gone, points);
            slot.assign_from(m);
            self.human_history.insert(at - 1, slot);
            self.human_boxes.pop_front();
            self.human_boxes.insert(at - 1, mbox);
        }
    }

    /// Record a contradiction of a model between the stamps `t0 ≤ t1` (merged with the previous
    /// one of the same reason where they chain).
    fn model_break(&mut self, t0: f64, t1: f64, reason: Reason) {
        self.model_break_about(t0, t1, reason, None);
    }

    /// [`Self::model_break`] of object `object`'s model (index), which the span names.
    fn model_break_about(&mut self, t0: f64, t1: f64, reason: Reason, object: Option<usize>) {
        let name = object.map(|k| self.objects[k].id.as_str());
        match self.model_breaks.last_mut() {
            Some(last)
                if last.reason == reason
                    && last.object.as_deref() == name
                    && last.t_end >= t0
                    && last.t_start <= t1 =>
            {
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
                object: name.map(str::to_string),
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
        // newest by stamp is the one in use (`keep_newest`: the first of equal stamps stays), as
        // in the shield where the records agree.
        if object_record_breaks(&self.objects[k].model, &m) {
            self.model_break_about(m.time, m.time, Reason::ObjectExceedsModel, Some(k));
        }
        let mut nearest = Nearest::new(m.time);
        let o = &self.objects[k];
        for cur in &o.history {
            let (early, late) = if cur.time <= m.time {
                (cur, &m)
            } else {
                (&m, cur)
            };
            if object_pair_breaks(&o.bounds, early, late) {
                nearest.add(cur.time);
            }
        }
        for (t0, t1) in nearest.pairs() {
            self.model_break_about(t0, t1, Reason::ObjectExceedsModel, Some(k));
        }
        let o = &self.objects[k];
        // Against the records let go, in constant memory (a drift through the kept ones).
        let (speed, e2) = o.bounds.speed_and_2e();
        let (acc, e2v) = o.bounds.acc_and_2ev();
        let drifted = o.dropped.is_some_and(|d| m.time >= d)
            && (speed.is_some_and(|v| {
                o.let_go
                    .breaks(m.time, e2, std::iter::once((m.position, v)))
            }) || m
                .velocity
                .is_some_and(|u| o.let_go_vel.breaks(m.time, e2v, std::iter::once((u, acc)))));
        // The newest record let go with a velocity, whole (its direction included).
        let moving_break = o
            .let_go_moving
            .filter(|g| m.time >= g.time && object_pair_breaks(&o.bounds, g, &m))
            .map(|g| g.time);
        if let (true, Some(d)) = (drifted, o.dropped) {
            self.model_break_about(d, m.time, Reason::ObjectExceedsModel, Some(k));
        }
        if let Some(t0) = moving_break {
            self.model_break_about(t0, m.time, Reason::ObjectExceedsModel, Some(k));
        }
        let o = &self.objects[k];
        let at = o.history.partition_point(|h| h.time <= m.time);
        // As for human records ([`too_late`]).
        if let Some(oldest) = o.history.front()
            && too_late(m.time, oldest.time, o.dropped, || {
                o.history
                    .iter()
                    .take_while(|h| h.time == m.time)
                    .any(|h| *h == m)
            })
        {
            let t1 = oldest.time;
            self.model_break_about(m.time, t1, Reason::ObjectRecordTooLate, Some(k));
        }
        let o = &mut self.objects[k];
        o.others_for = None;
        o.history.insert(at, m);
        if o.history.len() > HUMAN_HISTORY
            && let Some(gone) = o.history.pop_front()
        {
            o.dropped = Some(o.dropped.map_or(gone.time, |d| d.max(gone.time)));
            if let (Some(v), _) = o.bounds.speed_and_2e() {
                o.let_go.add(gone.time, std::iter::once((gone.position, v)));
            }
            if let Some(u) = gone.velocity {
                let (acc, _) = o.bounds.acc_and_2ev();
                o.let_go_vel.add(gone.time, std::iter::once((u, acc)));
                o.let_go_moving = Some(gone);
            }
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
        for (field, what, src) in [("dq", "velocities", dq), ("ddq", "accelerations", ddq)] {
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
        }
        if ddq.is_some() && dq.is_none() {
            return Err(AuditError::AccelerationWithoutVelocity);
        }
        if self.repeats_last_sample(t, q, dq, ddq) {
            self.copies += 1;
            return Ok(());
        }
        // The human records before the previous sample are in use for the span that this sample
        // closes; those since the previous sample wait for the span this sample opens.
        self.awaiting_human_t_meas = self.unused_human_t_meas.take();
        if self.samples == 0 {
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
        // The sample is written in place at the block's end (≈ 0.4 kB; entries beyond the
        // robot's joints are 0, as `Sample` promises).
        self.block.push(Sample {
            t,
            q: [0.0; MAX_DOF],
            dq: [0.0; MAX_DOF],
            ddq: [0.0; MAX_DOF],
            has_dq: dq.is_some(),
            has_ddq: ddq.is_some(),
        });
        if let Some(s) = self.block.last_mut() {
            s.q[..n].copy_from_slice(q);
            if let Some(v) = dq {
                s.dq[..n].copy_from_slice(v);
            }
            if let Some(v) = ddq {
                s.ddq[..n].copy_from_slice(v);
            }
        }
        if self.block.len() > BLOCK_SPANS {
            self.flush_block();
            self.block_human = self.latest_human;
        }
        // The next span uses the newest object measurements: if one changed, the block (whose
        // spans all used `span`) is checked first, with the measurements it used.
        if self.objects.iter().any(|o| o.span != o.latest) {
            self.flush_block();
        }
        self.span_human = self.latest_human;
        for o in &mut self.objects {
            o.span = o.latest;
        }
        self.samples += 1;
        self.t_last = t;
        Ok(())
    }
}

impl Auditor {
    /// The sample is an exact copy of the previous one (the same stamp, bit for bit the same
    /// values, velocities and accelerations logged alike): it is skipped (counted in `copies`,
    /// not in `samples`), so the audit is that of the log without the copy (records between the
    /// two then count as arriving before the next sample, as they would in that log). Sound: that
    /// log allows the same motions, and a measurement left for a later span is replaced there
    /// by an older one, whose occupancy covers every admissible motion too. The decision depends
    /// on the robot samples alone, so every person's pass makes it alike (their span indices
    /// stay aligned). Checked, the copy's zero-length span has, without `dq`, the velocity box
    /// `[−v_max, v_max]`: a robot at rest whose recorder wrote each message twice failed SSM.
    fn repeats_last_sample(
        &self,
        t: f64,
        q: &[f64],
        dq: Option<&[f64]>,
        ddq: Option<&[f64]>,
    ) -> bool {
        let Some(last) = self.block.last() else {
            return false;
        };
        let same = |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits());
        let n = self.n;
        self.samples > 0
            && last.t.to_bits() == t.to_bits()
            && last.has_dq == dq.is_some()
            && last.has_ddq == ddq.is_some()
            && same(&last.q[..n], q)
            && dq.is_none_or(|v| same(&last.dq[..n], v))
            && ddq.is_none_or(|v| same(&last.ddq[..n], v))
    }
}

/// The names and specs of the models for the report (`constraints`: the resolved constraints'
/// name).
fn model_names(models: &LogModels, constraints: &str) -> ModelNames {
    // A name says which model was used only where the spec is that built-in's: an inline
    // spec that reuses a built-in name (say "fr3" with other capsules) is labelled as such,
    // so that a report never presents a modified model under a built-in's name.
    let robot_name = models.robot.name();
    let human_name = &models.human.spec().name;
    ModelNames {
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
            constraints,
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
        people: Vec::new(),
        specs: without_nulls(serde_json::json!({
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
        })),
    }
}

/// `v` with every `null` member of an object removed, at any depth: a bound a model does not
/// have (an object without `max_speed`) is absent from the report, which holds no `null`.
fn without_nulls(mut v: serde_json::Value) -> serde_json::Value {
    fn strip(v: &mut serde_json::Value) {
        match v {
            serde_json::Value::Object(m) => {
                m.retain(|_, x| !x.is_null());
                m.values_mut().for_each(strip);
            }
            serde_json::Value::Array(a) => a.iter_mut().for_each(strip),
            _ => {}
        }
    }
    strip(&mut v);
    v
}

/// The track of each of the log's dynamic objects (no measurement yet).
fn object_tracks(models: &LogModels) -> Vec<ObjectTrack> {
    models
        .objects
        .iter()
        .map(|(id, model, contact)| ObjectTrack {
            id: id.clone(),
            model: *model,
            bounds: ObjectBounds::of(model),
            contact: *contact,
            latest: None,
            history: std::collections::VecDeque::with_capacity(HUMAN_HISTORY + 1),
            dropped: None,
            let_go: LetGo::new(1),
            let_go_vel: LetGo::new(1),
            let_go_moving: None,
            span: None,
            occ: None,
            unusable: None,
            others: Vec::with_capacity(8),
            others_for: None,
        })
        .collect()
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

/// Whether the span `[t0, t1]` is longer than `max_gap` (s) beyond its stamps' rounding: each
/// decimal stamp stands for the reals within one ulp of it, and their difference is rounded
/// once, so a logger writing 0.1 s steps (`1.1 − 1.0 = 0.10000000000000009` in doubles) is not
/// taken to leave gaps at `max_gap = 0.1`. The tolerance, 4ε of the larger stamp (ε = 2⁻⁵²), is below a microsecond for stamps up to 10⁹ s. A policy on evidence, not a bound: the
/// enclosures hold over spans of any length.
#[inline]
pub(crate) fn longer_than_gap(t0: f64, t1: f64, max_gap: f64) -> bool {
    t1 - t0 > max_gap + 4.0 * f64::EPSILON * t0.abs().max(t1.abs())
}

/// Whether the stamps of a span `[t0, t1]` resolve its length (`pacs_log::time::clock_resolves`
/// at the larger stamp, the shield's rule for its clock). A zero-length span needs no resolution
/// (its samples are judged by their consistency; a log of only such spans is `no_time_covered`).
pub(crate) fn stamps_resolve(t0: f64, t1: f64) -> bool {
    let dt = t1 - t0;
    dt <= 0.0 || pacs_log::time::clock_resolves(t0.abs().max(t1.abs()), dt)
}

/// A seeded xorshift generator of uniform numbers in [0, 1) (the unit tests of this module and
/// its submodules).
#[cfg(test)]
fn uniform(seed: u64) -> impl FnMut() -> f64 {
    let mut x = seed;
    move || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        (x >> 11) as f64 / (1u64 << 53) as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
