//! The one error type of `pacs-audit`: a record, a model or a setting the checker cannot use.
//! Each message names the field and the value; the reader adds the file and line
//! (`pacs_log::LogError`).

use thiserror::Error;

/// Why the checker refused a record, the models or its settings.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum AuditError {
    /// An `object` record names an object the header does not declare.
    #[error("object record: id `{id}` is not declared in header.objects")]
    UnknownObject {
        /// The id.
        id: String,
    },
    /// A human record names a person the header does not declare.
    #[error("human record: id `{id}` is not a person of the header (header.humans: {declared})")]
    UnknownPerson {
        /// The id.
        id: String,
        /// The declared ids, comma-separated.
        declared: String,
    },
    /// A human record without `id` in a log of several people.
    #[error(
        "human record: no `id`, and the header declares several people ({declared}): each human record names one"
    )]
    PersonMissing {
        /// The declared ids, comma-separated.
        declared: String,
    },
    /// A second `start` event where the header promises one (two runs in one log).
    #[error(
        "a second `start` event at t = {t} s (the first at t = {first} s): the header promises one, at the run's start (two runs in one log?)"
    )]
    SecondStart {
        /// Its time (s).
        t: f64,
        /// The first one's time (s).
        first: f64,
    },
    /// A record after the `end` event the header promised last.
    #[error(
        "{kind} record at t = {t} s after the `end` event at t = {end} s (the writer promised it last)"
    )]
    AfterEnd {
        /// Record type, with its article (`an event`).
        kind: &'static str,
        /// Its time (s).
        t: f64,
        /// The end event's time (s).
        end: f64,
    },
    /// A value is NaN or infinite.
    #[error("{field}: value {value} is not finite")]
    NotFinite {
        /// Field path, e.g. `q[3]`.
        field: String,
        /// The value.
        value: f64,
    },
    /// A vector has the wrong length for the robot.
    #[error("{field}: expected {expected} joint {what} for robot `{robot}`, found {found}")]
    JointCount {
        /// `q`, `dq` or `ddq`.
        field: &'static str,
        /// `positions`, `velocities` or `accelerations`.
        what: &'static str,
        /// The robot's joint count.
        expected: usize,
        /// Robot name.
        robot: String,
        /// Entries given.
        found: usize,
    },
    /// Accelerations without velocities.
    #[error("ddq: accelerations are only accepted together with velocities (dq)")]
    AccelerationWithoutVelocity,
    /// A human record whose measurement time is after its log time.
    #[error(
        "t_meas: {t_meas} s is after the record's t = {t} s (measurements cannot come from the future)"
    )]
    MeasurementFromFuture {
        /// Measurement time (s).
        t_meas: f64,
        /// Log time (s).
        t: f64,
    },
    /// The human measurement is invalid for the model.
    #[error("{0}")]
    Measurement(pacs_reach::ReachError),
    /// A setting is negative or not finite.
    #[error("{field}: value {value} must be finite and >= 0")]
    Setting {
        /// Setting name.
        field: &'static str,
        /// The value.
        value: f64,
    },
    /// `human_model = "acc"`, which logs cannot support.
    #[error("human_model: `acc` needs measured velocities, which logs do not carry")]
    AccModel,
    /// The MCAP settings are invalid.
    #[error("{0}")]
    Mcap(pacs_log::McapConfigError),
    /// The constraints do not resolve against the human model.
    #[error("constraints: {0}")]
    Constraints(pacs_models::ModelError),
    /// The robot occupancy cannot be set up (e.g. the tracking error).
    #[error("tracking_error: {0}")]
    TrackingError(pacs_reach::ReachError),
    /// The robot has more links than the checker's masks hold.
    #[error("robot `{robot}` has more than {max} links")]
    TooManyLinks {
        /// Robot name.
        robot: String,
        /// The limit.
        max: usize,
    },
    /// `limit_slack` above [`crate::config::MAX_LIMIT_SLACK`].
    #[error(
        "limit_slack: value {0} is above the largest the audit accepts, {max:e} (a larger slack would judge samples consistent that the limits contradict, e.g. dq = 0 beside moving positions)",
        max = crate::config::MAX_LIMIT_SLACK
    )]
    LimitSlack(f64),
    /// The ISO/TS 15066 rule cannot be set up for these models.
    #[error("{0}")]
    Rule(pacs_verify::RuleError),
}
