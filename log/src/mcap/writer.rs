//! [`McapLogWriter`]: writes a pacs log as an MCAP file of a ROS 2 recording.

use super::{
    JOINT_STATE, METADATA_KEY, METADATA_NAME, McapConfig, POSE_ARRAY, POSE_STAMPED, STRING,
};
use crate::cdr::{CdrWriter, Stamp};
use crate::format::Header;
use std::io::{Seek, Write};

/// Writes a pacs log as an MCAP file of a ROS 2 recording (the form [`McapReader`] reads): the
/// header as the `pacs` metadata record, then CDR messages on the configured topics. It writes
/// what it is given, record by record (a JSON Lines log's records converted keep their events):
/// where the header promises a `start` or an `end` event (`Header::promising_end`), the caller
/// writes them ([`Self::write_event`]: `start` logged at the first robot sample's header
/// stamp, before it, `end` last), or the audit reads the log as `incomplete_log`.
///
/// [`McapReader`]: super::McapReader
pub struct McapLogWriter<W: Write + Seek> {
    w: mcap::Writer<W>,
    robot: u16,
    human: u16,
    event: u16,
    /// Per object id of `cfg.object_topics`, its `PoseStamped` channel.
    objects: std::collections::BTreeMap<String, u16>,
    /// Per person of a v2 header, its `PoseArray` channel.
    people: std::collections::BTreeMap<String, u16>,
    seq: u32,
    joints: Vec<String>,
    frame_id: String,
}

/// Errors of [`McapLogWriter`].
#[derive(Debug, thiserror::Error)]
pub enum McapWriteError {
    /// The MCAP writer failed.
    #[error("MCAP write failed: {0}")]
    Mcap(#[from] mcap::McapError),
    /// The header could not be serialized.
    #[error("header: {0}")]
    Header(#[from] serde_json::Error),
    /// A time stamp does not fit a ROS 2 `builtin_interfaces/Time` (or the log time is negative).
    #[error("time stamp {0} ns is out of range")]
    Time(i128),
    /// An object id without a topic in the config's `object_topics`.
    #[error("object `{0}` has no topic in mcap.object_topics")]
    UnknownObject(String),
    /// A person id the header does not declare.
    #[error("person `{0}` is not among the header's humans")]
    UnknownPerson(String),
}

impl<W: Write + Seek> McapLogWriter<W> {
    /// Start an MCAP log: writes the header metadata, schemas and channels. `joints` names the
    /// robot joints (written into every `JointState.name`; empty: positions by index).
    pub fn new(
        out: W,
        opts: mcap::WriteOptions,
        header: &Header,
        cfg: &McapConfig,
        joints: &[&str],
    ) -> Result<Self, McapWriteError> {
        let mut w = opts.profile("ros2").create(out)?;
        let mut md = std::collections::BTreeMap::new();
        md.insert(METADATA_KEY.to_string(), serde_json::to_string(header)?);
        w.write_metadata(&mcap::records::Metadata {
            name: METADATA_NAME.into(),
            metadata: md,
        })?;
        let none = std::collections::BTreeMap::new();
        let people_ids: Vec<&str> = if header.version >= 2 {
            header.humans.iter().map(|p| p.id.as_str()).collect()
        } else {
            vec![]
        };
        let mut chan = |name: &str, def: &str, topic: &str| -> Result<u16, McapWriteError> {
            let s = w.add_schema(name, "ros2msg", def.as_bytes())?;
            Ok(w.add_channel(s, topic, "cdr", &none)?)
        };
        let robot = chan(JOINT_STATE, JOINT_STATE_DEF, &cfg.robot_topic)?;
        let human = chan(POSE_ARRAY, POSE_ARRAY_DEF, &cfg.human_topic)?;
        let event = chan(STRING, "string data\n", &cfg.event_topic)?;
        let mut objects = std::collections::BTreeMap::new();
        for (id, topic) in &cfg.object_topics {
            objects.insert(id.clone(), chan(POSE_STAMPED, POSE_STAMPED_DEF, topic)?);
        }
        // One channel per person: `mcap.human_topics`, else `/humans/ID/keypoints`.
        let mut people = std::collections::BTreeMap::new();
        for id in people_ids {
            let topic = cfg
                .human_topics
                .get(id)
                .cloned()
                .unwrap_or_else(|| crate::mcap::person_topic(id));
            people.insert(id.to_string(), chan(POSE_ARRAY, POSE_ARRAY_DEF, &topic)?);
        }
        Ok(Self {
            w,
            robot,
            human,
            event,
            objects,
            people,
            seq: 0,
            joints: joints.iter().map(|s| s.to_string()).collect(),
            frame_id: "world".into(),
        })
    }

    fn put(&mut self, channel_id: u16, log_time: i128, data: &[u8]) -> Result<(), McapWriteError> {
        let lt = u64::try_from(log_time).map_err(|_| McapWriteError::Time(log_time))?;
        self.seq = self.seq.wrapping_add(1);
        self.w.write_to_known_channel(
            &mcap::records::MessageHeader {
                channel_id,
                sequence: self.seq,
                log_time: lt,
                publish_time: lt,
            },
            data,
        )?;
        Ok(())
    }

    /// A robot sample: `header.stamp` = `stamp` (ns), logged at `log_time` (ns).
    pub fn write_robot(
        &mut self,
        stamp: i128,
        log_time: i128,
        q: &[f64],
        dq: Option<&[f64]>,
    ) -> Result<(), McapWriteError> {
        let st = Stamp::from_nanos(stamp).ok_or(McapWriteError::Time(stamp))?;
        let names: Vec<&str> = self.joints.iter().map(String::as_str).collect();
        let data = CdrWriter::joint_state(st, &names, q, dq.unwrap_or(&[]), &[]);
        self.put(self.robot, log_time, &data)
    }

    /// A human measurement taken at `stamp` (ns), logged at `log_time` (ns).
    pub fn write_human(
        &mut self,
        stamp: i128,
        log_time: i128,
        positions: &[[f64; 3]],
    ) -> Result<(), McapWriteError> {
        let st = Stamp::from_nanos(stamp).ok_or(McapWriteError::Time(stamp))?;
        let data = CdrWriter::pose_array(st, &self.frame_id, positions);
        self.put(self.human, log_time, &data)
    }

    /// A measurement of person `id` (a person of the v2 header given to [`Self::new`])
    /// taken at `stamp` (ns), logged at `log_time` (ns), on the person's topic. An unknown id
    /// is an error.
    pub fn write_person(
        &mut self,
        id: &str,
        stamp: i128,
        log_time: i128,
        positions: &[[f64; 3]],
    ) -> Result<(), McapWriteError> {
        let Some(&channel) = self.people.get(id) else {
            return Err(McapWriteError::UnknownPerson(id.to_string()));
        };
        let st = Stamp::from_nanos(stamp).ok_or(McapWriteError::Time(stamp))?;
        let data = CdrWriter::pose_array(st, &self.frame_id, positions);
        self.put(channel, log_time, &data)
    }

    /// A position of object `id` (a key of the config's `object_topics`) taken at `stamp` (ns),
    /// logged at `log_time` (ns), as a `PoseStamped`. An unknown id is an error.
    pub fn write_object(
        &mut self,
        id: &str,
        stamp: i128,
        log_time: i128,
        position: [f64; 3],
    ) -> Result<(), McapWriteError> {
        let Some(&channel) = self.objects.get(id) else {
            return Err(McapWriteError::UnknownObject(id.to_string()));
        };
        let st = Stamp::from_nanos(stamp).ok_or(McapWriteError::Time(stamp))?;
        let data = CdrWriter::pose_stamped(st, &self.frame_id, position);
        self.put(channel, log_time, &data)
    }

    /// A log record as the ROS 2 message a recording of it would hold (times in s become ns;
    /// robot samples stamped at their log time, measurements at their measurement time).
    /// Accelerations and shield diagnostics have no message here and are skipped; an object
    /// record needs its id among the config's `object_topics`.
    pub fn write_record(&mut self, rec: &crate::format::Record<'_>) -> Result<(), McapWriteError> {
        use crate::format::Record;
        let ns = |t: f64| (t * 1e9).round() as i128;
        match *rec {
            Record::Robot { t, q, dq, .. } => self.write_robot(ns(t), ns(t), q, dq),
            Record::Human {
                t,
                t_meas,
                person: None,
                positions,
            } => self.write_human(ns(t_meas), ns(t), positions),
            Record::Human {
                t,
                t_meas,
                person: Some(id),
                positions,
            } => self.write_person(id, ns(t_meas), ns(t), positions),
            Record::Object {
                t,
                t_meas,
                id,
                position,
                ..
            } => self.write_object(id, ns(t_meas), ns(t), position),
            Record::Event { t, name } => self.write_event(ns(t), name),
            Record::Shield { .. } => Ok(()),
        }
    }

    /// An event logged at `log_time` (ns).
    pub fn write_event(&mut self, log_time: i128, name: &str) -> Result<(), McapWriteError> {
        let data = CdrWriter::string_msg(name);
        self.put(self.event, log_time, &data)
    }

    /// Write the summary and footer; returns the inner writer.
    pub fn finish(mut self) -> Result<W, McapWriteError> {
        self.w.finish()?;
        Ok(self.w.into_inner())
    }
}

const JOINT_STATE_DEF: &str = "std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\nfloat64[] effort\n";
const POSE_STAMPED_DEF: &str = "std_msgs/Header header\ngeometry_msgs/Pose pose\n";
const POSE_ARRAY_DEF: &str = "std_msgs/Header header\ngeometry_msgs/Pose[] poses\n";
