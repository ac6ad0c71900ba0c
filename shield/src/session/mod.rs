//! What every runner of a shield shares (the CLI's scene runner, the Python binding, the
//! real-time loop), so that each of them is a thin adapter:
//! - [`MeasurementInbox`]: timed measurements of people and objects (and the runner's own timed
//!   inputs) delivered at the first safety step at or after their arrival, to the shield and to
//!   the run's log;
//! - [`Session`]: one shield run: start (with or without a log), measurements through the inbox,
//!   chunks, steps on the safety-step grid, and a close that writes what was due and the log's
//!   `end` record;
//! - [`PacedHandover`]: handing a chunk over while a real-time loop steps the session — planned
//!   off the session's lock, offered a few steps ahead and planned again under the one
//!   [`crate::ReplanPolicy`].
//!
//! Which measurement is in use is not decided here: the shield keeps the newest by
//! [`pacs_reach::stamped`]'s rule; the session only decides *when* each one reaches it.

mod inbox;
mod paced;
mod run;

pub use inbox::{Due, InboxError, MeasurementInbox, MeasurementSink, Pending};
pub use paced::PacedHandover;
pub use run::{MAX_WAITING, Session, SessionError};
