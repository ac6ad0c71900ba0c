//! Streaming reader of MCAP files of ROS 2 recordings (see `docs/log-format.md#mcap-form`), and
//! [`McapLogWriter`], which writes such files.
//!
//! - robot: `sensor_msgs/msg/JointState` on [`McapConfig::robot_topic`]; `header.stamp` is `t`;
//!   joints are mapped by name to the robot model's joint order (by index when `name` is empty);
//! - human: `geometry_msgs/msg/PoseArray` on [`McapConfig::human_topic`], pose positions in the
//!   human model's keypoint order; `header.stamp` is `t_meas`, the message's log time is `t`;
//! - events: `std_msgs/msg/String` on [`McapConfig::event_topic`]; the log time is `t`;
//! - the pacs header: the JSON text of the JSON Lines header line, in key [`METADATA_KEY`] of the
//!   metadata record named [`METADATA_NAME`], or given separately (`pacs audit --header`).
//!
//! Message payloads are CDR (decoded by [`crate::cdr`]). The file is read once, front to back,
//! through `mcap`'s sans-I/O linear reader (chunks are decompressed as a stream), and messages are
//! put into time order within a bounded window ([`McapConfig::reorder_window`]); a message that
//! would need a longer window is an error, never silently reordered or dropped.

mod fields;
mod guard;
mod header;
mod reader;
mod writer;

pub use header::{header_from_value, load_header_file, parse_header_json};
pub use reader::McapReader;
pub use writer::{McapLogWriter, McapWriteError};

use crate::error::McapConfigError;
use serde::{Deserialize, Serialize};

/// The name of the MCAP metadata record holding the pacs header.
pub const METADATA_NAME: &str = "pacs";
/// The key, in that metadata record, whose value is the header's JSON text.
pub const METADATA_KEY: &str = "header";
/// Schema name of robot messages.
pub const JOINT_STATE: &str = "sensor_msgs/msg/JointState";
/// Schema name of human keypoint messages.
pub const POSE_ARRAY: &str = "geometry_msgs/msg/PoseArray";
/// Schema name of single-object pose messages (object topics also accept [`POSE_ARRAY`], first
/// pose).
pub const POSE_STAMPED: &str = "geometry_msgs/msg/PoseStamped";
/// Schema name of event messages.
pub const STRING: &str = "std_msgs/msg/String";
/// Largest MCAP record (other than a chunk, which is streamed) the reader accepts, in bytes.
pub const RECORD_LIMIT: usize = 64 << 20;
/// Most messages held back for reordering at once; more is an error (memory stays bounded).
pub const MAX_PENDING: usize = 1 << 18;
/// The MCAP magic bytes at the start (and end) of every MCAP file.
pub const MAGIC: &[u8] = mcap::MAGIC;

/// The default topic of person `id`'s keypoints (`PoseArray`) in a v2 recording:
/// `/humans/ID/keypoints` (used where `mcap.human_topics` names no topic for the person).
pub fn person_topic(id: &str) -> String {
    format!("/humans/{id}/keypoints")
}

/// The person id of a default per-person topic (`/humans/ID/keypoints`), if `topic` is one.
pub fn person_of_topic(topic: &str) -> Option<&str> {
    let id = topic.strip_prefix("/humans/")?.strip_suffix("/keypoints")?;
    (!id.is_empty() && !id.contains('/')).then_some(id)
}

/// Whether `prefix` (the first bytes of a file) starts with the MCAP magic.
pub fn has_magic(prefix: &[u8]) -> bool {
    prefix.starts_with(MAGIC)
}

/// MCAP reading settings: the `[mcap]` table of the audit config.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct McapConfig {
    /// Topic of the robot's `sensor_msgs/msg/JointState`. Default `/joint_states`.
    pub robot_topic: String,
    /// Topic of the human keypoints (`geometry_msgs/msg/PoseArray`). Default `/human/keypoints`.
    pub human_topic: String,
    /// Per person of a v2 header (its id), the topic of its keypoints (`PoseArray`). Default
    /// none: then person `ID` is read from `/humans/ID/keypoints` ([`person_topic`]), and
    /// `human_topic` carries the measurements of a log's only person (no id).
    #[serde(default)]
    pub human_topics: std::collections::BTreeMap<String, String>,
    /// Topic of task events (`std_msgs/msg/String`). Default `/pacs/events`.
    pub event_topic: String,
    /// Per dynamic object of the header (its id), the topic of its position
    /// (`geometry_msgs/msg/PoseStamped`, or `PoseArray` whose first pose is used; no velocity).
    /// Default none: a log whose header declares objects then has no object measurements.
    pub object_topics: std::collections::BTreeMap<String, String>,
    /// Messages are put in time order within this window (s); a message older than one already
    /// handed to the checker by more than this is an error. Default 1.0 s.
    pub reorder_window: f64,
}

impl Default for McapConfig {
    fn default() -> Self {
        Self {
            robot_topic: "/joint_states".into(),
            human_topic: "/human/keypoints".into(),
            human_topics: Default::default(),
            event_topic: "/pacs/events".into(),
            object_topics: Default::default(),
            reorder_window: 1.0,
        }
    }
}

impl McapConfig {
    /// Check every value; the error names the field and value.
    pub fn validate(&self) -> Result<(), McapConfigError> {
        if !(self.reorder_window.is_finite() && self.reorder_window >= 0.0) {
            return Err(McapConfigError::ReorderWindow(self.reorder_window));
        }
        let mut topics = vec![
            ("mcap.robot_topic", &self.robot_topic),
            ("mcap.human_topic", &self.human_topic),
            ("mcap.event_topic", &self.event_topic),
        ];
        topics.extend(
            self.object_topics
                .values()
                .map(|t| ("mcap.object_topics", t)),
        );
        topics.extend(self.human_topics.values().map(|t| ("mcap.human_topics", t)));
        for (i, (f, t)) in topics.iter().enumerate() {
            if t.is_empty() {
                return Err(McapConfigError::EmptyTopic(f));
            }
            if let Some((g, _)) = topics[..i].iter().find(|(_, u)| u == t) {
                return Err(McapConfigError::DuplicateTopic {
                    field: f,
                    topic: t.to_string(),
                    other: g,
                });
            }
        }
        Ok(())
    }
}
