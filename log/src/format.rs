//! Log format v2 (and v1, still read; see `docs/log-format.md`): the header, the record view shared
//! by all readers, and the JSON Lines writer the shield uses.
//!
//! The parts: `refs` (models by built-in name, URDF or inline spec), `header` (the header and
//! its validation), `models` (the header's models loaded), `records` (the record view and the
//! reader trait) and `writer` (the JSON Lines writer).

mod header;
mod models;
mod records;
mod refs;
mod writer;

pub use header::{Header, MAX_PEOPLE, ModelOverrides, ObjectEntry, PersonEntry};
pub use models::LogModels;
pub use records::{Record, RecordReader};
pub use refs::{ModelRef, RobotRef, dir_of};
pub use writer::{LogWriter, WriteError};

/// The value of the header's `format` field.
pub const FORMAT: &str = "pacs-log";
/// The format version pacs writes: 2 (several people, each with an id; the end-event promise).
pub const VERSION: u32 = 2;
/// The versions read: 1 (one person, `human`) and 2 (`humans`).
pub const VERSIONS: [u32; 2] = [1, 2];
/// The person id of a v1 log's one person (v1 human records carry no id).
pub const V1_PERSON: &str = "human";
/// The name of the event a writer that promises it (`end_event: true`) logs last, at the end
/// time of the run.
pub const END_EVENT: &str = "end";
/// The name of the event a writer that promises it (`start_event: true`) logs at the time of
/// its first robot sample, just before it.
pub const START_EVENT: &str = "start";
