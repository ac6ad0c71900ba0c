//! # pacs-log
//!
//! The log format v2 (and v1, still read; `docs/log-format.md`) of logged robot runs, independent of the checker that
//! audits them:
//! - [`format`]: the header (models by name or inline spec), the record view every reader yields,
//!   the models a header refers to ([`LogModels`]) and the JSON Lines writer ([`LogWriter`]);
//! - [`jsonl`], [`csv`], [`mcap`] (+ [`cdr`]): streaming readers of the three forms; [`db3`]: ROS 2
//!   sqlite3 bags, with the MCAP form's topics and messages (one conversion for both, `ros`);
//! - [`order`]: records of equal time in the one canonical order (human, robot, event, file order);
//! - [`time`]: whether time stamps resolve a step (one rule for the shield and the audit);
//! - [`error`]: input errors naming the file, line or offset, and the problem.

pub mod cdr;
pub mod csv;
pub mod db3;
pub mod error;
pub mod format;
pub mod jsonl;
pub mod mcap;
pub mod open;
pub mod order;
mod ros;
pub mod time;

pub use error::{HeaderError, Location, LogError, McapConfigError};
pub use format::{
    END_EVENT, FORMAT, Header, LogModels, LogWriter, MAX_PEOPLE, ModelOverrides, ModelRef,
    ObjectEntry, PersonEntry, Record, RecordReader, RobotRef, START_EVENT, V1_PERSON, VERSION,
    VERSIONS, WriteError, dir_of,
};
pub use open::{
    is_db3, is_jsonl, is_mcap, open_log, open_log_in_row_order, read_log, takes_header,
};
pub use order::{EqualTimeGroup, MAX_EQUAL_TIME, TooManyAtOneTime};
