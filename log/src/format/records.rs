//! The record view every reader yields (borrowing the reader's buffers) and the reader trait.

use super::Header;

/// One record after the header, borrowing the reader's buffers (no allocation per record).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Record<'a> {
    /// A robot sample at `t` (s): joint positions (rad) and, if logged, velocities (rad/s).
    Robot {
        /// Time (s).
        t: f64,
        /// Joint positions (rad).
        q: &'a [f64],
        /// Joint velocities (rad/s), if logged.
        dq: Option<&'a [f64]>,
        /// Joint accelerations (rad/s²), if logged (only together with `dq`).
        ddq: Option<&'a [f64]>,
    },
    /// A human measurement logged at `t`, taken at `t_meas ≤ t` (s); keypoints in model order (m).
    Human {
        /// Log time (s).
        t: f64,
        /// Measurement time stamp (s).
        t_meas: f64,
        /// The person's id (v2 `id`; `None`: the log's only person).
        person: Option<&'a str>,
        /// Keypoint positions (m).
        positions: &'a [[f64; 3]],
    },
    /// A dynamic object's measurement logged at `t`, taken at `t_meas ≤ t` (s): the object `id`
    /// of the header at `position` (m), with `velocity` (m/s) if measured.
    Object {
        /// Log time (s).
        t: f64,
        /// Measurement time stamp (s).
        t_meas: f64,
        /// The header's object id.
        id: &'a str,
        /// Measured position (m).
        position: [f64; 3],
        /// Measured velocity (m/s), if any.
        velocity: Option<[f64; 3]>,
    },
    /// Shield diagnostics (ignored by the verdict).
    Shield {
        /// Time (s).
        t: f64,
    },
    /// A named event (`episode_start`, `success`, `failure`, or any other name).
    Event {
        /// Time (s).
        t: f64,
        /// Event name.
        name: &'a str,
    },
}

impl Record<'_> {
    /// The record's time (s).
    pub fn t(&self) -> f64 {
        match *self {
            Record::Robot { t, .. }
            | Record::Human { t, .. }
            | Record::Object { t, .. }
            | Record::Shield { t }
            | Record::Event { t, .. } => t,
        }
    }
}

/// A streaming source of records: the header first, then records in file order.
pub trait RecordReader {
    /// The file's header (already read and checked for type, format and version).
    fn header(&self) -> &Header;
    /// The next record, `None` at a clean end of file. Errors name the file and location.
    fn next_record(&mut self) -> Result<Option<Record<'_>>, crate::LogError>;
    /// Where the last returned record was found (for errors detected downstream).
    fn location(&self) -> crate::Location;
    /// Where the header was found (for errors in its models). Default: line 1.
    fn header_location(&self) -> crate::Location {
        crate::Location::Line(1)
    }
    /// The file name used in errors.
    fn file(&self) -> &str;
    /// The file the header was read from, as errors in its models name it (with
    /// [`RecordReader::header_location`]). Default: [`RecordReader::file`]; a ROS bag whose header
    /// comes from its metadata's `custom_data` names the metadata.
    fn header_file(&self) -> &str {
        self.file()
    }
    /// Whether records of equal time already come in the canonical order of
    /// [`crate::order::EqualTimeGroup`] (measurements, robot samples, events, then arrival
    /// order): then the audit applies them as they come, without buffering a copy. The ROS
    /// readers (MCAP, db3) sort every message by `(t, rank, arrival)` on the way; JSON Lines and
    /// CSV keep the file's order. Default: no.
    fn in_canonical_order(&self) -> bool {
        false
    }
}
