//! The records of the linear pass: schemas, channels (checked against the configured topics),
//! the `pacs` metadata record, and messages decoded from CDR into pending records.

use super::{Body, HeaderFrom, Pending, State, Stream};
use crate::cdr;
use crate::error::{Location, LogError};
use crate::format::{Header, LogModels};
use crate::mcap::fields::{FieldError, Fields};
use crate::mcap::header::parse_metadata;
use crate::mcap::{JOINT_STATE, MAX_PENDING, METADATA_NAME, POSE_ARRAY, POSE_STAMPED, STRING};
use mcap::records::op;

impl State {
    fn err(&self, p: impl Into<String>) -> LogError {
        LogError::input(&self.file, Location::Offset(self.pos), p)
    }

    pub(super) fn set_header(&mut self, h: Header) -> Result<(), LogError> {
        let eff = h.with_overrides(&self.overrides);
        let loc = match self.header_from {
            Some(HeaderFrom::Record(o)) => Location::Offset(o),
            _ => Location::File,
        };
        let models = LogModels::from_header(&eff)
            .map_err(|p| LogError::input(&self.file, loc, p.to_string()))?;
        self.joints = models
            .robot
            .joints()
            .iter()
            .map(|j| j.name.clone())
            .collect();
        self.keypoints = models.human.keypoint_count();
        self.person_keypoints = models
            .people
            .iter()
            .map(|(id, m)| (id.clone(), m.keypoint_count()))
            .collect();
        self.header = Some(h);
        Ok(())
    }

    pub(super) fn record(&mut self, opcode: u8, data: &[u8]) -> Result<(), LogError> {
        // Top-level records end exactly at `pos` (the reader is fed only the bytes it asks for).
        let start = self.pos.saturating_sub(9 + data.len() as u64);
        match opcode {
            op::SCHEMA | op::CHANNEL | op::MESSAGE | op::METADATA => {}
            _ => return Ok(()),
        }
        let bad = |p: FieldError| {
            LogError::input(
                &self.file,
                Location::Offset(self.pos),
                format!("invalid MCAP record (opcode 0x{opcode:02x}): {p}"),
            )
        };
        let mut f = Fields { b: data };
        match opcode {
            op::SCHEMA => {
                let id = f.u16("schema id").map_err(bad)?;
                let name = f.str("schema name").map_err(bad)?;
                let encoding = f.str("schema encoding").map_err(bad)?;
                f.bytes("schema data").map_err(bad)?;
                if let Some(old) = self.schemas.get(&id) {
                    if old.0 != name || old.1 != encoding {
                        return Err(self.err(format!(
                            "schema id {id} redefined (`{}` then `{name}`)",
                            old.0
                        )));
                    }
                } else if id != 0 {
                    self.schemas.insert(id, (name.into(), encoding.into()));
                }
            }
            op::CHANNEL => {
                let id = f.u16("channel id").map_err(bad)?;
                let schema_id = f.u16("channel schema id").map_err(bad)?;
                let topic = f.str("channel topic").map_err(bad)?;
                let enc = f.str("channel message encoding").map_err(bad)?;
                f.map("channel metadata", |_, _| {}).map_err(bad)?;
                self.channel(id, schema_id, topic, enc)?;
            }
            op::METADATA => {
                let (name, h) = parse_metadata(data).map_err(bad)?;
                if let Some(h) = h {
                    debug_assert_eq!(name, METADATA_NAME);
                    match self.header_from {
                        Some(HeaderFrom::Given) => {}
                        Some(HeaderFrom::Record(o)) if o == start => {}
                        Some(HeaderFrom::Record(o)) => {
                            return Err(self.err(format!(
                                "a second metadata record named `{METADATA_NAME}` (the header is at offset {o})"
                            )));
                        }
                        None => {
                            self.header_from = Some(HeaderFrom::Record(start));
                            let mut h = h.map_err(|p| {
                                LogError::input(&self.file, Location::Offset(start), p.to_string())
                            })?;
                            // Relative {urdf, side} paths: relative to the MCAP file.
                            h.robot
                                .rebase(&crate::format::dir_of(std::path::Path::new(&self.file)));
                            self.set_header(h)?;
                        }
                    }
                }
            }
            _ => {
                let header = mcap::records::MessageHeader {
                    channel_id: f.u16("message channel id").map_err(bad)?,
                    sequence: f.u32("message sequence").map_err(bad)?,
                    log_time: f.u64("message log time").map_err(bad)?,
                    publish_time: f.u64("message publish time").map_err(bad)?,
                };
                self.message(&header, f.b)?;
            }
        }
        Ok(())
    }

    fn channel(
        &mut self,
        id: u16,
        schema_id: u16,
        topic: &str,
        message_encoding: &str,
    ) -> Result<(), LogError> {
        let cfg = &self.cfg;
        let (stream, expected) = if topic == cfg.robot_topic {
            (Stream::Robot, JOINT_STATE)
        } else if topic == cfg.human_topic {
            (Stream::Human { person: None }, POSE_ARRAY)
        } else if let Some(id) = cfg
            .human_topics
            .iter()
            .find(|(_, t)| *t == topic)
            .map(|(id, _)| id.clone())
            .or_else(|| {
                cfg.human_topics
                    .is_empty()
                    .then(|| crate::mcap::person_of_topic(topic).map(str::to_string))
                    .flatten()
            })
        {
            let i = match self.person_ids.iter().position(|p| *p == id) {
                Some(i) => i,
                None => {
                    self.person_ids.push(id);
                    self.person_ids.len() - 1
                }
            };
            let i = u16::try_from(i).map_err(|_| self.err("more than 65535 person topics"))?;
            (Stream::Human { person: Some(i) }, POSE_ARRAY)
        } else if topic == cfg.event_topic {
            (Stream::Event, STRING)
        } else if cfg.object_topics.values().any(|t| t == topic) {
            // Either pose message; which one is decided by the channel's schema below.
            let stamped = self
                .schemas
                .get(&schema_id)
                .is_some_and(|(name, _)| name == POSE_STAMPED);
            (
                Stream::Object { stamped },
                if stamped { POSE_STAMPED } else { POSE_ARRAY },
            )
        } else {
            (Stream::Ignored, "")
        };
        if let Some((old, _)) = self.channels.get(&id) {
            if old != topic {
                return Err(self.err(format!(
                    "channel id {id} redefined (topic `{old}` then `{topic}`)"
                )));
            }
            return Ok(());
        }
        if stream != Stream::Ignored {
            let what = format!("channel {} on topic `{}`", id, topic);
            if schema_id == 0 {
                return Err(self.err(format!("{what} has no schema (expected `{expected}`)")));
            }
            let Some((name, encoding)) = self.schemas.get(&schema_id) else {
                return Err(self.err(format!(
                    "{what} refers to schema id {} which is not defined before it",
                    schema_id
                )));
            };
            if name != expected {
                return Err(self.err(format!(
                    "{what}: unknown schema `{name}` (expected `{expected}`)"
                )));
            }
            if encoding != "ros2msg" && encoding != "ros2idl" {
                return Err(self.err(format!(
                    "{what}: schema encoding `{encoding}` is not supported (expected `ros2msg`)"
                )));
            }
            if message_encoding != "cdr" {
                return Err(self.err(format!(
                    "{what}: message encoding `{}` is not supported (expected `cdr`)",
                    message_encoding
                )));
            }
        }
        self.channels.insert(id, (topic.to_string(), stream));
        Ok(())
    }

    fn what(&self, h: &mcap::records::MessageHeader) -> String {
        let topic = self
            .channels
            .get(&h.channel_id)
            .map_or("?", |c| c.0.as_str());
        format!(
            "message on `{topic}` (log time {} ns, sequence {})",
            h.log_time, h.sequence
        )
    }

    /// Seconds since the time base of a time stamp in nanoseconds.
    fn secs(&self, ns: i128) -> f64 {
        let base = i128::from(self.base_s.unwrap_or(0)) * 1_000_000_000;
        (ns - base) as f64 / 1e9
    }

    fn message(&mut self, h: &mcap::records::MessageHeader, data: &[u8]) -> Result<(), LogError> {
        let Some((_, stream)) = self.channels.get(&h.channel_id) else {
            return Err(self.err(format!(
                "message on channel id {} which is not defined before it",
                h.channel_id
            )));
        };
        let stream = *stream;
        if stream == Stream::Ignored {
            return Ok(());
        }
        if self.header.is_none() {
            let what = self.what(h);
            return Err(self.err(format!(
                "missing header: {what} comes before any metadata record named `{METADATA_NAME}` and the summary has none (give one with --header)"
            )));
        }
        self.base_s
            .get_or_insert((h.log_time / 1_000_000_000) as i64);
        let log_t = self.secs(i128::from(h.log_time));
        let pending = match stream {
            Stream::Robot => {
                self.js
                    .decode(data)
                    .map_err(|e| self.err(format!("{}: JointState: {e}", self.what(h))))?;
                let js = &self.js;
                let k = js.names.len();
                let n = self.joints.len();
                if k > 0 && js.position.len() != k {
                    return Err(self.err(format!(
                        "{}: JointState has {k} names but {} positions",
                        self.what(h),
                        js.position.len()
                    )));
                }
                let vlen = js.velocity.len();
                if vlen != 0 && vlen != js.position.len() {
                    return Err(self.err(format!(
                        "{}: JointState has {} positions but {vlen} velocities",
                        self.what(h),
                        js.position.len()
                    )));
                }
                if k == 0 && js.position.len() != n {
                    return Err(self.err(format!(
                        "{}: wrong joint count: JointState has {} positions and no names, the robot model has {n} joints", self.what(h),
                        js.position.len()
                    )));
                }
                if k > 0 && self.map_names != js.names {
                    let mut map = vec![usize::MAX; n];
                    for (i, name) in js.names.iter().enumerate() {
                        if let Some(j) = self.joints.iter().position(|x| x == name) {
                            if map[j] != usize::MAX {
                                return Err(self.err(format!(
                                    "{}: joint `{name}` appears twice in JointState.name",
                                    self.what(h)
                                )));
                            }
                            map[j] = i;
                        }
                    }
                    if let Some(j) = map.iter().position(|&i| i == usize::MAX) {
                        return Err(self.err(format!(
                            "{}: wrong joints: robot joint `{}` is missing from JointState.name",
                            self.what(h),
                            self.joints[j]
                        )));
                    }
                    self.map = map;
                    self.map_names.clone_from(&js.names);
                }
                let mut q = self.f64_pool.pop().unwrap_or_default();
                let mut dq = (vlen > 0).then(|| self.f64_pool.pop().unwrap_or_default());
                q.clear();
                if let Some(d) = dq.as_mut() {
                    d.clear();
                }
                for j in 0..n {
                    let i = if k == 0 { j } else { self.map[j] };
                    let (x, v) = (js.position[i], js.velocity.get(i).copied());
                    for (f, val) in [("position", Some(x)), ("velocity", v)] {
                        if let Some(val) = val.filter(|v| !v.is_finite()) {
                            return Err(self.err(format!(
                                "{}: JointState.{f}[{i}] (joint `{}`): value {val} is not finite",
                                self.what(h),
                                self.joints[j]
                            )));
                        }
                    }
                    q.push(x);
                    if let (Some(d), Some(v)) = (dq.as_mut(), v) {
                        d.push(v);
                    }
                }
                Pending {
                    t: self.secs(js.stamp.nanos()),
                    seq: 0,
                    offset: 0,
                    body: Body::Robot { q, dq },
                }
            }
            Stream::Human { person } => {
                self.pa
                    .decode(data)
                    .map_err(|e| self.err(format!("{}: PoseArray: {e}", self.what(h))))?;
                let m = self.pa.positions.len();
                // The person's model's keypoint count (an id the header does not declare is
                // reported by the audit, which knows the people).
                let expected = match person {
                    None => Some(self.keypoints),
                    Some(i) => {
                        let id = &self.person_ids[usize::from(i)];
                        self.person_keypoints
                            .iter()
                            .find(|(p, _)| p == id)
                            .map(|(_, k)| *k)
                    }
                };
                if let Some(k) = expected
                    && m != k
                {
                    return Err(self.err(format!(
                        "{}: wrong keypoint count: PoseArray has {m} poses, the human model has {k} keypoints", self.what(h),
                    )));
                }
                if let Some((i, c)) = self
                    .pa
                    .positions
                    .iter()
                    .enumerate()
                    .find_map(|(i, p)| p.iter().find(|c| !c.is_finite()).map(|c| (i, *c)))
                {
                    return Err(self.err(format!(
                        "{}: PoseArray.poses[{i}].position: value {c} is not finite",
                        self.what(h)
                    )));
                }
                let mut positions = self.pos_pool.pop().unwrap_or_default();
                positions.clear();
                positions.extend_from_slice(&self.pa.positions);
                Pending {
                    t: log_t,
                    seq: 0,
                    offset: 0,
                    body: Body::Human {
                        t_meas: self.secs(self.pa.stamp.nanos()),
                        person,
                        positions,
                    },
                }
            }
            Stream::Object { stamped } => {
                let topic = self.channels.get(&h.channel_id).map(|c| c.0.as_str());
                let id = self
                    .cfg
                    .object_topics
                    .iter()
                    .find(|(_, t)| Some(t.as_str()) == topic)
                    .map(|(id, _)| id.clone())
                    .unwrap_or_default();
                let (stamp, position) = if stamped {
                    let m = cdr::PoseStamped::decode(data)
                        .map_err(|e| self.err(format!("{}: PoseStamped: {e}", self.what(h))))?;
                    (m.stamp, m.position)
                } else {
                    self.pa
                        .decode(data)
                        .map_err(|e| self.err(format!("{}: PoseArray: {e}", self.what(h))))?;
                    let Some(p) = self.pa.positions.first() else {
                        return Err(self.err(format!(
                            "{}: PoseArray for object `{id}` has no pose",
                            self.what(h)
                        )));
                    };
                    (self.pa.stamp, *p)
                };
                if let Some(c) = position.iter().find(|c| !c.is_finite()) {
                    return Err(self.err(format!(
                        "{}: object `{id}` position: value {c} is not finite",
                        self.what(h)
                    )));
                }
                Pending {
                    t: log_t,
                    seq: 0,
                    offset: 0,
                    body: Body::Object {
                        id,
                        t_meas: self.secs(stamp.nanos()),
                        position,
                    },
                }
            }
            Stream::Event | Stream::Ignored => {
                let mut s = self.str_pool.pop().unwrap_or_default();
                cdr::decode_string(data, &mut s)
                    .map_err(|e| self.err(format!("{}: String: {e}", self.what(h))))?;
                Pending {
                    t: log_t,
                    seq: 0,
                    offset: 0,
                    body: Body::Event(s),
                }
            }
        };
        if pending.t < self.last_released {
            return Err(self.err(format!(
                "{}: out of time order: t = {} s is more than mcap.reorder_window = {} s before t = {} s of a message already read (raise mcap.reorder_window)", self.what(h),
                pending.t, self.cfg.reorder_window, self.max_t
            )));
        }
        if self.heap.len() >= MAX_PENDING {
            return Err(self.err(format!(
                "more than {MAX_PENDING} messages within mcap.reorder_window = {} s",
                self.cfg.reorder_window
            )));
        }
        self.max_t = self.max_t.max(pending.t);
        self.seq += 1;
        self.heap.push(Pending {
            seq: self.seq,
            offset: self.pos,
            ..pending
        });
        Ok(())
    }

    pub(super) fn recycle(&mut self, p: Pending) {
        match p.body {
            Body::Robot { q, dq } => {
                self.f64_pool.push(q);
                self.f64_pool.extend(dq);
            }
            Body::Human { positions, .. } => self.pos_pool.push(positions),
            Body::Event(s) | Body::Object { id: s, .. } => self.str_pool.push(s),
        }
    }
}
