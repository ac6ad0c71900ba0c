//! Audit results: verdicts, violation intervals, inconclusive spans, metrics and plot series.

use serde::{Deserialize, Serialize};

/// Outcome of auditing one log.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Verdict {
    /// Every covered time was checked and no violation is possible.
    Pass,
    /// A violation is possible (or certain) somewhere.
    Fail,
    /// No violation was found, but part of the log could not be checked.
    Inconclusive,
}

impl Verdict {
    /// The CLI exit code of this verdict alone (0 pass, 1 fail, 2 inconclusive).
    pub fn exit_code(self) -> u8 {
        match self {
            Verdict::Pass => 0,
            Verdict::Fail => 1,
            Verdict::Inconclusive => 2,
        }
    }
    /// The verdict of one log from its findings: `fail` if it has a violation, else
    /// `inconclusive` if any part could not be checked, else `pass`.
    ///
    /// # Soundness
    /// Claim C9 (with the span checks): a log with a violation is never `pass`, nor is one with
    /// an unchecked span. Harness `h1_verdict_never_hides_findings`.
    pub fn of_findings(violation: bool, unchecked: bool) -> Verdict {
        if violation {
            Verdict::Fail
        } else if unchecked {
            Verdict::Inconclusive
        } else {
            Verdict::Pass
        }
    }
    /// Combined verdict of several logs: fail if any fails, else inconclusive if any is, else pass.
    ///
    /// # Soundness
    /// `pass` only if every log passed, `fail` if any failed. Harness
    /// `h1_verdict_never_hides_findings`.
    pub fn combine(verdicts: impl IntoIterator<Item = Verdict>) -> Verdict {
        let mut out = Verdict::Pass;
        for v in verdicts {
            match v {
                Verdict::Fail => return Verdict::Fail,
                Verdict::Inconclusive => out = Verdict::Inconclusive,
                Verdict::Pass => {}
            }
        }
        out
    }
}

pub use pacs_verify::iso15066::ConstraintKind;

/// A maximal run of consecutive checked spans in which one (body part, link) pair violates its
/// constraint.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Violation {
    /// Start of the first violating span (s).
    pub t_start: f64,
    /// End of the last violating span (s).
    pub t_end: f64,
    /// SSM or PFL.
    pub constraint: ConstraintKind,
    /// The person (a v2 log's person id; absent for v1 logs and for objects).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub person: Option<String>,
    /// Body part name (human model).
    pub body_part: String,
    /// Robot link name.
    pub link: String,
    /// Smallest signed separation (m) between the link's capsules and the body part as measured,
    /// at the recorded robot samples of the interval (negative: overlap depth).
    pub min_separation: f64,
    /// Largest sound upper bound (J) of the whole robot's kinetic energy (PFL; 0 for SSM).
    pub energy: f64,
    /// Smallest energy threshold (J) that applied (0 for SSM).
    pub threshold: f64,
    /// Whether the constrained (clamping) threshold applied at some span.
    pub constrained: bool,
    /// True if the violation holds at a recorded robot sample with the measured human keypoints
    /// taken at face value (no uncertainty): it certainly happened.
    pub certain: bool,
    /// Number of spans in the interval.
    pub spans: u64,
    /// Index of the interval's first span in the log's run of spans (internal, not serialized:
    /// the passes of a log with several people each find an object's violating spans where
    /// their person lets them check, and their intervals are joined on these indices).
    #[serde(skip)]
    pub first_span: u64,
}

/// Why a span (or the log) could not be checked (serialized as its snake_case name, e.g.
/// `"no_human"`; see `docs/audit.md`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum InconclusiveReason {
    /// Consecutive robot samples further apart than `max_gap`.
    Gap,
    /// No human record before the span's first robot sample.
    NoHuman,
    /// The human measurement in use is older than `max_human_age` at the span's end.
    StaleHuman,
    /// The samples contradict each other or the robot's limits.
    ExceedsLimits,
    /// The human occupancy could not be computed.
    HumanReachError,
    /// A human record after the last robot sample describes a time inside the log.
    HumanRecordAfterLastRobotSample,
    /// The log has fewer than two robot samples: it covers no time.
    FewerThanTwoRobotSamples,
    /// A declared object has no measurement before the span's first robot sample.
    NoObject,
    /// An object's measurement in use is older than `max_human_age` at the span's end.
    StaleObject,
    /// The writer promised an `end` event (`end_event: true` in the header) and the log lacks it,
    /// or its robot samples stop before it: the log was cut short, and what is missing was
    /// never checked (`t_start`: the last robot sample; `t_end`: the end event's time, or the
    /// last sample's if there is none). Or the writer promised a `start` event (`start_event`)
    /// and the log lacks it, or its robot samples begin after it: the log was cut at its
    /// beginning (`t_start`: the start event's time, or the first sample's if there is none;
    /// `t_end`: the first sample), or samples precede it (a log glued from two: from the first
    /// sample to the start).
    IncompleteLog,
    /// The span's time stamps cannot resolve its length (doubles near the stamps are more than a
    /// thousandth of the span apart: `pacs_log::time::clock_resolves`, the shield's rule for its
    /// clock); every age and bound computed from those stamps would be off by as much.
    UnresolvedTime,
    /// The robot samples all share one time stamp (≥ 2 samples, duration 0 s): the log covers no
    /// time, and is no evidence of a run.
    NoTimeCovered,
    /// An object's occupancy could not be computed (e.g. it overflows).
    ObjectReachError,
    /// Two human measurements lie farther apart than the model allows (keypoint speed bound ×
    /// time between them + twice the position error): the person broke the model between them,
    /// and what was checked with the earlier one assumed it (`t_start`, `t_end`: the two
    /// measurement stamps).
    HumanExceedsModel,
    /// Two measurements of an object lie farther apart than its model allows (its speed bound,
    /// or the first one's velocity and the acceleration bound, over the time between them, plus
    /// twice the position error): the object broke the model its occupancies assume
    /// (`t_start`, `t_end`: the two measurement stamps).
    ObjectExceedsModel,
    /// A human record arrived after the audit had let go of records near its stamp (it keeps the
    /// latest 64 by stamp; this one is older than all of them, and older ones were let go): it
    /// could not be checked against its neighbours in time, so whether it contradicts the model
    /// there is unknown (`t_start`: its stamp; `t_end`: the oldest kept record's stamp).
    HumanRecordTooLate,
    /// As `HumanRecordTooLate`, for an object's record (the latest 64 of that object kept).
    ObjectRecordTooLate,
}

impl InconclusiveReason {
    /// The snake_case name (as serialized).
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Gap => "gap",
            Self::NoHuman => "no_human",
            Self::StaleHuman => "stale_human",
            Self::ExceedsLimits => "exceeds_limits",
            Self::HumanReachError => "human_reach_error",
            Self::HumanRecordAfterLastRobotSample => "human_record_after_last_robot_sample",
            Self::FewerThanTwoRobotSamples => "fewer_than_two_robot_samples",
            Self::NoObject => "no_object",
            Self::StaleObject => "stale_object",
            Self::IncompleteLog => "incomplete_log",
            Self::UnresolvedTime => "unresolved_time",
            Self::NoTimeCovered => "no_time_covered",
            Self::ObjectReachError => "object_reach_error",
            Self::HumanExceedsModel => "human_exceeds_model",
            Self::ObjectExceedsModel => "object_exceeds_model",
            Self::HumanRecordTooLate => "human_record_too_late",
            Self::ObjectRecordTooLate => "object_record_too_late",
        }
    }
}

impl std::fmt::Display for InconclusiveReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl PartialEq<&str> for InconclusiveReason {
    fn eq(&self, other: &&str) -> bool {
        self.as_str() == *other
    }
}

/// A maximal run of consecutive spans that could not be checked, for one reason.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct InconclusiveSpan {
    /// Start (s).
    pub t_start: f64,
    /// End (s).
    pub t_end: f64,
    /// Why.
    pub reason: InconclusiveReason,
    /// Number of spans.
    pub spans: u64,
    /// The person it concerns (a v2 log's person id, for the reasons about a person's
    /// measurements: `no_human`, `stale_human`, `human_reach_error`, `human_exceeds_model`,
    /// `human_record_too_late`, `human_record_after_last_robot_sample`); absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub person: Option<String>,
    /// The object it concerns (its id in the header, for the reasons about an object's
    /// measurements: `no_object`, `stale_object`, `object_reach_error`, `object_exceeds_model`,
    /// `object_record_too_late`); absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub object: Option<String>,
}

impl InconclusiveReason {
    /// Whether the reason is about one object's measurements (and names the object).
    pub fn about_an_object(self) -> bool {
        matches!(
            self,
            Self::NoObject
                | Self::StaleObject
                | Self::ObjectReachError
                | Self::ObjectExceedsModel
                | Self::ObjectRecordTooLate
        )
    }

    /// Whether the reason is about one person's measurements (and names the person).
    pub fn about_a_person(self) -> bool {
        matches!(
            self,
            Self::NoHuman
                | Self::StaleHuman
                | Self::HumanReachError
                | Self::HumanExceedsModel
                | Self::HumanRecordTooLate
                | Self::HumanRecordAfterLastRobotSample
        )
    }
}

/// Whether the log is the whole run: what its writer promised about its end, and whether the
/// log keeps that promise.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Completeness {
    /// The writer promised a `start` and an `end` event; both are there and the robot samples
    /// run from the one to the other.
    Complete,
    /// The writer promised an `end` event and no `start` (logs written by pacs before the
    /// `start_event` promise, 2026-12); it is there and the robot samples reach it. A cut at the log's beginning
    /// cannot be told: the audited span is what the log states.
    EndOnly,
    /// The writer promised a `start` or an `end` event; one is missing, or the samples begin
    /// after the start or stop before the end (`incomplete_log`: never `pass`).
    Incomplete,
    /// The writer promised nothing (v1 logs, ROS bags): the audited time span is all the
    /// report can state.
    NotPromised,
}

impl Default for Evidence {
    fn default() -> Self {
        Self {
            t_start: 0.0,
            t_end: 0.0,
            completeness: Completeness::NotPromised,
        }
    }
}

impl RunResult {
    /// The verdict (and `safe_success`) again from the findings, after findings were added.
    pub fn refresh_verdict(&mut self) {
        self.verdict =
            Verdict::of_findings(!self.violations.is_empty(), !self.inconclusive.is_empty());
        self.metrics.safe_success = self
            .metrics
            .success
            .map(|s| safe_success(s, self.verdict == Verdict::Pass));
    }
}

impl Completeness {
    /// The snake_case name (as serialized).
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Complete => "complete",
            Self::EndOnly => "end_only",
            Self::Incomplete => "incomplete",
            Self::NotPromised => "not_promised",
        }
    }
}

/// What the log covers: the audited time span and whether the log is the whole run (default:
/// no samples, nothing promised).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Evidence {
    /// First robot sample (s; 0 without samples).
    pub t_start: f64,
    /// Last robot sample (s; 0 without samples).
    pub t_end: f64,
    /// Whether the log is the whole run.
    pub completeness: Completeness,
}

/// Per-log metrics.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Metrics {
    /// Robot samples.
    pub samples: u64,
    /// Human records.
    pub human_records: u64,
    /// Time from the first to the last robot sample (s).
    pub duration: f64,
    /// Robot samples in violation / samples (the paper's "Safety Viol.").
    pub violation_fraction: f64,
    /// Robot samples in violation.
    pub violating_samples: u64,
    /// Robot samples in a certain violation.
    pub certain_violating_samples: u64,
    /// Total length of inconclusive spans (s).
    pub inconclusive_duration: f64,
    /// Lower bound (m) of the robot–human separation over all checked spans (None if none, or
    /// if the figure is beyond floating point; JSON leaves the key out, never `null`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min_separation: Option<f64>,
    /// Task outcome from the last `success` / `failure` event (None if none was logged; JSON
    /// leaves the key out).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub success: Option<bool>,
    /// [`safe_success`] with the audit as evidence: `success` and verdict `pass` (None if no
    /// outcome was logged; JSON leaves the key out).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub safe_success: Option<bool>,
}

/// One bucket of the plot series (time-decimated, at most a fixed number of buckets per log).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SeriesPoint {
    /// Bucket start (s).
    pub t: f64,
    /// Bucket end (s).
    pub t_end: f64,
    /// Lower bound (m) of the separation over the bucket's checked spans where the robot's
    /// occupancy was computed (None if none).
    pub min_separation: Option<f64>,
    /// Lower bound (m) of the separation over the bucket's spans where the people and objects
    /// were all outside the robot's workspace ball, so only the distance to that ball was
    /// computed: a coarse figure (always > 0), far below the true distance to the arm. Reports
    /// draw it apart from `min_separation` (None if no such span).
    #[serde(default)]
    pub far_separation: Option<f64>,
    /// Nominal whole-robot kinetic energy (J) at the bucket's first sample.
    pub energy_nominal: Option<f64>,
    /// Largest sub-chain energy bound (J) over possible PFL contacts in the bucket.
    pub energy_bound: Option<f64>,
    /// Smallest PFL threshold (J) of those contacts.
    pub threshold: Option<f64>,
    /// A violation is possible in the bucket.
    pub violation: bool,
    /// Part of the bucket is inconclusive.
    pub inconclusive: bool,
    /// The robot is nominally at rest over the whole bucket: every logged (or, without
    /// velocities, sample-difference) joint speed is at most the config's `rest_speed`.
    pub at_rest: bool,
}

/// The audit of one log.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunResult {
    /// Log file name as given.
    pub log: String,
    /// Verdict.
    pub verdict: Verdict,
    /// Violation intervals, by start time.
    pub violations: Vec<Violation>,
    /// Unchecked spans, by start time.
    pub inconclusive: Vec<InconclusiveSpan>,
    /// Metrics.
    pub metrics: Metrics,
    /// The audited time span and whether the log is the whole run.
    #[serde(default)]
    pub evidence: Evidence,
    /// The people of the log (ids in header order; empty for a v1 log, whose one person is
    /// unnamed).
    #[serde(default)]
    pub people: Vec<String>,
    /// The header's `meta` object.
    pub meta: serde_json::Map<String, serde_json::Value>,
    /// Robot, human and task names, for the report.
    pub models: ModelNames,
    /// Plot series (reports only; not part of `pacs audit --json`).
    #[serde(skip_serializing, default)]
    pub series: Vec<SeriesPoint>,
}

/// Names of the models a run was audited with.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModelNames {
    /// Robot name.
    pub robot: String,
    /// Human model name.
    pub human: String,
    /// Task constraints name.
    pub constraints: String,
    /// Robot joint velocity limits (rad/s) the span boxes use.
    pub robot_v_max: Vec<f64>,
    /// Robot joint acceleration limits (rad/s²) the velocity boxes use.
    pub robot_a_max: Vec<f64>,
    /// Human keypoint speed bounds (m/s).
    pub human_v_max: Vec<f64>,
    /// Human position measurement error bound (m).
    pub human_measurement_error_pos: f64,
    /// Human sensor delay (s).
    pub human_delay: f64,
    /// Number of static environment capsules.
    pub environment_shapes: usize,
    /// With several people: each person's human model (in header order). `human`, `human_v_max`,
    /// `human_measurement_error_pos` and `human_delay` above are then the first person's, and
    /// `human` lists every person's model where they differ.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub people: Vec<PersonModel>,
    /// The full model parameters: `{"robot": spec, "human": spec, "constraints": spec,
    /// "environment": [capsules], "objects": [...]}` (reports hash and print them; not part of
    /// `pacs audit --json`).
    #[serde(skip_serializing, default)]
    pub specs: serde_json::Value,
}

/// The human model one person of a log was audited with ([`ModelNames::people`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PersonModel {
    /// The person's id.
    pub id: String,
    /// Human model name (as [`ModelNames::human`]).
    pub human: String,
    /// Keypoint speed bounds (m/s).
    pub human_v_max: Vec<f64>,
    /// Position measurement error bound (m).
    pub human_measurement_error_pos: f64,
    /// Sensor delay (s).
    pub human_delay: f64,
}

/// **Safe success**, the one definition (the paper's metric, used by the audit, the reports, `pacs
/// demo` and `pacs simulate`): the task succeeded and no safety violation occurred. What shows
/// "no violation" is the evidence, named with every figure: in an audit and its report, the
/// audit's verdict `pass` (sound: a pass excludes every violation the models allow); in the
/// simulation, no violation against the true (simulated) human, which an audit pass implies but
/// not the other way round.
pub fn safe_success(success: bool, no_violation: bool) -> bool {
    success && no_violation
}
