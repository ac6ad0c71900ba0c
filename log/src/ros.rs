//! ROS 2 messages on the configured topics, turned into records and put in time order: the one
//! conversion shared by the MCAP reader ([`crate::mcap`]) and the rosbag2 sqlite3 reader
//! ([`crate::db3`]). A reader finds each message's topic, type, log time (ns) and CDR payload in
//! its container and hands them to [`Messages::message`]; it takes the records back in time order
//! with [`Messages::pop_ready`].
//!
//! - robot: `sensor_msgs/msg/JointState`; `header.stamp` is `t`; joints are mapped by name to the
//!   robot model's joint order (by index when `name` is empty);
//! - human: `geometry_msgs/msg/PoseArray`, pose positions in the human model's keypoint order;
//!   `header.stamp` is `t_meas`, the log time is `t`;
//! - object: `geometry_msgs/msg/PoseStamped` (or `PoseArray`, first pose) of a header object;
//! - event: `std_msgs/msg/String`; the log time is `t`.
//!
//! Times are seconds since a whole-second time base: the log time of the first message on a
//! configured topic, rounded down to the second. Messages are released in time order within
//! [`McapConfig::reorder_window`]; a message that would need a longer window is an error.

use crate::cdr::{self, JointStateMsg, PoseArray};
use crate::error::{Location, LogError};
use crate::format::{Header, LogModels, ModelOverrides, Record};
use crate::mcap::{JOINT_STATE, MAX_PENDING, McapConfig, POSE_ARRAY, POSE_STAMPED, STRING};
use std::collections::{BinaryHeap, VecDeque};

/// More than 65,535 person topics (a person's index is 16 bits).
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("more than 65535 person topics")]
pub(crate) struct TooManyPeople;

/// What a topic carries, by the configuration.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Stream {
    Robot,
    /// Keypoints of the log's only person (`None`) or of person [`Messages::person_ids`]`[i]`.
    Human {
        person: Option<u16>,
    },
    /// A dynamic object's positions: `PoseStamped` (`stamped`) or `PoseArray` (first pose).
    Object {
        stamped: bool,
    },
    Event,
    Ignored,
}

pub(crate) enum Body {
    Robot {
        q: Vec<f64>,
        dq: Option<Vec<f64>>,
    },
    Human {
        t_meas: f64,
        person: Option<u16>,
        positions: Vec<[f64; 3]>,
    },
    Event(String),
    Object {
        /// The header's object id.
        id: String,
        t_meas: f64,
        position: [f64; 3],
    },
}

/// A converted message waiting for its turn.
pub(crate) struct Pending {
    pub(crate) t: f64,
    seq: u64,
    /// Where the message is in its file.
    pub(crate) loc: Location,
    /// Which file of the log it is in ([`Messages::part`] when it was read).
    pub(crate) part: u16,
    body: Body,
}

impl PartialEq for Pending {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o) == std::cmp::Ordering::Equal
    }
}
impl Eq for Pending {}
impl PartialOrd for Pending {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}

/// At equal times: human and object measurements first (a measurement logged at `t` is in use
/// from the robot sample at `t` on), then robot samples, then events.
fn rank_of(body: &Body) -> u8 {
    match body {
        Body::Human { .. } | Body::Object { .. } => 0,
        Body::Robot { .. } => 1,
        Body::Event(_) => 2,
    }
}

impl Pending {
    /// [`rank_of`] its body.
    fn rank(&self) -> u8 {
        rank_of(&self.body)
    }

    /// The record view of this message; `person_ids` are [`Messages::person_ids`].
    pub(crate) fn record<'a>(&'a self, person_ids: &'a [String]) -> Record<'a> {
        let t = self.t;
        match &self.body {
            Body::Robot { q, dq } => Record::Robot {
                t,
                q,
                dq: dq.as_deref(),
                ddq: None,
            },
            Body::Human {
                t_meas,
                person,
                positions,
            } => Record::Human {
                t,
                t_meas: *t_meas,
                person: person.map(|i| person_ids[usize::from(i)].as_str()),
                positions,
            },
            Body::Event(name) => Record::Event { t, name },
            Body::Object {
                id,
                t_meas,
                position,
            } => Record::Object {
                t,
                t_meas: *t_meas,
                id,
                position: *position,
                velocity: None,
            },
        }
    }
}

impl Ord for Pending {
    /// Reversed (earliest time, then [`Pending::rank`], then earliest in the file, first) for the
    /// max-heap.
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        o.t.total_cmp(&self.t)
            .then(o.rank().cmp(&self.rank()))
            .then(o.seq.cmp(&self.seq))
    }
}

/// One message as its container holds it.
pub(crate) struct Message<'a> {
    pub(crate) stream: Stream,
    pub(crate) topic: &'a str,
    /// Log (receive) time, ns.
    pub(crate) log_time: u64,
    /// The CDR payload.
    pub(crate) data: &'a [u8],
    /// Where it is, for errors and [`Pending::loc`].
    pub(crate) loc: Location,
}

/// The conversion state of one log: the effective models' joint names and keypoint count, the
/// time base, the reordering window and the decode buffers (reused across messages).
pub(crate) struct Messages {
    pub(crate) file: String,
    pub(crate) cfg: McapConfig,
    overrides: ModelOverrides,
    pub(crate) header: Option<Header>,
    /// Model joint names (effective robot) and keypoint count (effective human).
    joints: Vec<String>,
    keypoints: usize,
    /// Keypoint count of each person of the header, by id.
    person_keypoints: Vec<(String, usize)>,
    /// Ids of the people whose topics were seen (what `Stream::Human { person }` indexes).
    pub(crate) person_ids: Vec<String>,
    /// Whole seconds subtracted from every time stamp (the first message's log time).
    pub(crate) base_s: Option<i64>,
    /// Messages waiting for their turn: those that arrived in order (each after the last one
    /// queued here, the usual case) in `run`, in order; the others in `heap`. The next message
    /// is the earlier of the two fronts.
    run: VecDeque<Pending>,
    heap: BinaryHeap<Pending>,
    seq: u64,
    max_t: f64,
    /// Where the message of time `max_t` is (its location, part and log time in ns), for
    /// errors: a message stamped far ahead of its neighbours makes the next ones look late.
    max_at: (Location, u16, u64),
    last_released: f64,
    /// The rank ([`Pending::rank`]) of the message released last: one of equal time and lower
    /// rank would have to go before it.
    last_released_rank: u8,
    /// The part of the log being read (a split bag's file index), recorded with each message.
    pub(crate) part: u16,
    js: JointStateMsg,
    pa: PoseArray,
    /// Cached name → model-order map of the `JointState.name` list of `js` at
    /// [`JointStateMsg::names_version`] `map_version`.
    map_version: Option<u64>,
    map: Vec<usize>,
    f64_pool: Vec<Vec<f64>>,
    pos_pool: Vec<Vec<[f64; 3]>>,
    str_pool: Vec<String>,
}

impl Messages {
    /// A converter for `file` (named in errors) with the topic settings `cfg` and the model
    /// overrides of the audit config; the header comes later ([`Messages::set_header`]).
    pub(crate) fn new(file: &str, cfg: McapConfig, overrides: ModelOverrides) -> Self {
        Self {
            file: file.to_string(),
            cfg,
            overrides,
            header: None,
            joints: Vec::new(),
            keypoints: 0,
            person_keypoints: Vec::new(),
            person_ids: Vec::new(),
            base_s: None,
            run: VecDeque::new(),
            heap: BinaryHeap::new(),
            seq: 0,
            max_t: f64::NEG_INFINITY,
            max_at: (Location::File, 0, 0),
            last_released: f64::NEG_INFINITY,
            last_released_rank: 0,
            part: 0,
            js: JointStateMsg::default(),
            pa: PoseArray::default(),
            map_version: None,
            map: Vec::new(),
            f64_pool: Vec::new(),
            pos_pool: Vec::new(),
            str_pool: Vec::new(),
        }
    }

    /// Take the header: resolve the effective models (overrides applied); errors at `loc`.
    pub(crate) fn set_header(&mut self, h: Header, loc: Location) -> Result<(), LogError> {
        let eff = h.with_overrides(&self.overrides);
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
        // `mcap.human_topics` must name the header's people (one topic each: `McapConfig::
        // validate`): an undeclared id would leave its topic unread without a word.
        let declared: Vec<&str> = models.people.iter().map(|(id, _)| id.as_str()).collect();
        for id in self.cfg.human_topics.keys() {
            if !declared.is_empty() && !declared.contains(&id.as_str()) {
                return Err(LogError::input(
                    &self.file,
                    loc,
                    format!(
                        "mcap.human_topics: `{id}` is not a person of the header (people: {})",
                        declared.join(", ")
                    ),
                ));
            }
        }
        self.header = Some(h);
        Ok(())
    }

    /// The stream of `topic` and the message type it must have (`""` for ignored topics), or
    /// what is wrong. `type_name` is the topic's message type where known: on an object topic,
    /// `PoseStamped` selects the stamped form (anything else is expected to be a `PoseArray`).
    /// A person's topic (`mcap.human_topics`, or `/humans/ID/keypoints` when that is empty)
    /// registers the person's id.
    /// Whether messages on `topic` are read (not [`Stream::Ignored`]), by its name alone, as
    /// [`Self::stream_of`] decides it.
    pub(crate) fn watches(&self, topic: &str) -> bool {
        let cfg = &self.cfg;
        topic == cfg.robot_topic
            || topic == cfg.human_topic
            || topic == cfg.event_topic
            || cfg.object_topics.values().any(|t| t == topic)
            || cfg.human_topics.iter().any(|(_, t)| t == topic)
            || (cfg.human_topics.is_empty() && crate::mcap::person_of_topic(topic).is_some())
    }

    pub(crate) fn stream_of(
        &mut self,
        topic: &str,
        type_name: Option<&str>,
    ) -> Result<(Stream, &'static str), TooManyPeople> {
        let cfg = &self.cfg;
        Ok(if topic == cfg.robot_topic {
            (Stream::Robot, JOINT_STATE)
        } else if topic == cfg.human_topic {
            (Stream::Human { person: None }, POSE_ARRAY)
        } else if topic == cfg.event_topic {
            (Stream::Event, STRING)
        } else if cfg.object_topics.values().any(|t| t == topic) {
            let stamped = type_name == Some(POSE_STAMPED);
            (
                Stream::Object { stamped },
                if stamped { POSE_STAMPED } else { POSE_ARRAY },
            )
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
            let i = u16::try_from(i).map_err(|_| TooManyPeople)?;
            (Stream::Human { person: Some(i) }, POSE_ARRAY)
        } else {
            (Stream::Ignored, "")
        })
    }

    /// Whether no message is waiting.
    pub(crate) fn is_empty(&self) -> bool {
        self.heap.is_empty() && self.run.is_empty()
    }

    /// Seconds since the time base of a time stamp in nanoseconds.
    fn secs(&self, ns: i128) -> f64 {
        let base = i128::from(self.base_s.unwrap_or(0)) * 1_000_000_000;
        (ns - base) as f64 / 1e9
    }

    /// Convert one message on a configured topic (`m.stream` not ignored) and queue it; `what`
    /// describes the message in errors (topic, log time, and the container's own reference).
    /// The header must be set.
    pub(crate) fn message(
        &mut self,
        m: Message<'_>,
        what: &dyn Fn() -> String,
    ) -> Result<(), LogError> {
        self.base_s
            .get_or_insert((m.log_time / 1_000_000_000) as i64);
        let log_t = self.secs(i128::from(m.log_time));
        let pending = match m.stream {
            Stream::Robot => self.robot_message(&m, what)?,
            Stream::Human { person } => self.human_message(&m, person, log_t, what)?,
            Stream::Object { stamped } => self.object_message(&m, stamped, log_t, what)?,
            Stream::Event | Stream::Ignored => {
                let mut s = self.str_pool.pop().unwrap_or_default();
                cdr::decode_string(m.data, &mut s).map_err(|e| {
                    LogError::input(&self.file, m.loc, format!("{}: String: {e}", what()))
                })?;
                (log_t, Body::Event(s))
            }
        };
        let (t, body) = pending;
        let err = |p: String| LogError::input(&self.file, m.loc, p);
        // Equal times go in rank order (measurements, robot samples, events): a message of the
        // time released last but of a lower rank would have to go before it, as one of an
        // earlier time would (the audit applies these records as they come).
        if t < self.last_released
            || (t == self.last_released && rank_of(&body) < self.last_released_rank)
        {
            let (at, part, logged) = self.max_at;
            let part = if part == self.part {
                String::new()
            } else {
                format!(" in part {} of the log", part + 1)
            };
            return Err(err(format!(
                "{}: out of time order: t = {} s is at least mcap.reorder_window = {} s before t = {} s of a message read before it (log time {} ns, {}{}), and after messages already handed over: either that message's time is wrong (far ahead of its neighbours) or the log needs a longer mcap.reorder_window",
                what(),
                t,
                self.cfg.reorder_window,
                self.max_t,
                logged,
                at.to_string().trim_end_matches(": "),
                part
            )));
        }
        if self.heap.len() + self.run.len() >= MAX_PENDING {
            return Err(err(format!(
                "more than {MAX_PENDING} messages within mcap.reorder_window = {} s",
                self.cfg.reorder_window
            )));
        }
        if t > self.max_t {
            self.max_t = t;
            self.max_at = (m.loc, self.part, m.log_time);
        }
        self.seq += 1;
        let p = Pending {
            t,
            seq: self.seq,
            loc: m.loc,
            part: self.part,
            body,
        };
        // `Pending`'s order is reversed (for the max-heap): `a > b` means `a` goes first.
        if self.run.back().is_none_or(|last| p < *last) {
            self.run.push_back(p);
        } else {
            self.heap.push(p);
        }
        Ok(())
    }

    /// A `JointState` on the robot topic: the time stamp and the positions (and velocities, if
    /// any) in the model's joint order.
    fn robot_message(
        &mut self,
        m: &Message<'_>,
        what: &dyn Fn() -> String,
    ) -> Result<(f64, Body), LogError> {
        let err = |p: String| LogError::input(&self.file, m.loc, p);
        self.js
            .decode(m.data)
            .map_err(|e| err(format!("{}: JointState: {e}", what())))?;
        let js = &self.js;
        let k = js.names.len();
        let n = self.joints.len();
        if k > 0 && js.position.len() != k {
            return Err(err(format!(
                "{}: JointState has {k} names but {} positions",
                what(),
                js.position.len()
            )));
        }
        let vlen = js.velocity.len();
        if vlen != 0 && vlen != js.position.len() {
            return Err(err(format!(
                "{}: JointState has {} positions but {vlen} velocities",
                what(),
                js.position.len()
            )));
        }
        if k == 0 && js.position.len() != n {
            return Err(err(format!(
                "{}: wrong joint count: JointState has {} positions and no names, the robot model has {n} joints",
                what(),
                js.position.len()
            )));
        }
        if k > 0 && self.map_version != Some(js.names_version()) {
            let mut map = vec![usize::MAX; n];
            for (i, name) in js.names.iter().enumerate() {
                if let Some(j) = self.joints.iter().position(|x| x == name) {
                    if map[j] != usize::MAX {
                        return Err(err(format!(
                            "{}: joint `{name}` appears twice in JointState.name",
                            what()
                        )));
                    }
                    map[j] = i;
                }
            }
            if let Some(j) = map.iter().position(|&i| i == usize::MAX) {
                return Err(err(format!(
                    "{}: wrong joints: robot joint `{}` is missing from JointState.name",
                    what(),
                    self.joints[j]
                )));
            }
            self.map = map;
            self.map_version = Some(js.names_version());
        }
        let mut q = self.f64_pool.pop().unwrap_or_default();
        let mut dq = (vlen > 0).then(|| self.f64_pool.pop().unwrap_or_default());
        q.clear();
        if let Some(d) = dq.as_mut() {
            d.clear();
        }
        // Every value finite (the usual case, one pass over the message); otherwise the first
        // non-finite value of a model joint, in joint order, is the error (other joints'
        // values are not read).
        let all_finite = js
            .position
            .iter()
            .chain(js.velocity.iter())
            .all(|x| x.is_finite());
        if !all_finite {
            for j in 0..n {
                let i = if k == 0 { j } else { self.map[j] };
                let (x, v) = (js.position[i], js.velocity.get(i).copied());
                for (f, val) in [("position", Some(x)), ("velocity", v)] {
                    if let Some(val) = val.filter(|v| !v.is_finite()) {
                        return Err(err(format!(
                            "{}: JointState.{f}[{i}] (joint `{}`): value {val} is not finite",
                            what(),
                            self.joints[j]
                        )));
                    }
                }
            }
        }
        if k == 0 {
            q.extend_from_slice(&js.position[..n]);
            if let Some(d) = dq.as_mut() {
                d.extend_from_slice(&js.velocity[..n]);
            }
        } else {
            q.extend(self.map.iter().map(|&i| js.position[i]));
            if let Some(d) = dq.as_mut() {
                d.extend(self.map.iter().map(|&i| js.velocity[i]));
            }
        }
        Ok((self.secs(js.stamp.nanos()), Body::Robot { q, dq }))
    }

    /// A `PoseArray` on a human topic (the log's only person, or person `person`): the log time
    /// `log_t` and the keypoints with their stamp.
    fn human_message(
        &mut self,
        m: &Message<'_>,
        person: Option<u16>,
        log_t: f64,
        what: &dyn Fn() -> String,
    ) -> Result<(f64, Body), LogError> {
        let err = |p: String| LogError::input(&self.file, m.loc, p);
        self.pa
            .decode(m.data)
            .map_err(|e| err(format!("{}: PoseArray: {e}", what())))?;
        let n = self.pa.positions.len();
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
            && n != k
        {
            return Err(err(format!(
                "{}: wrong keypoint count: PoseArray has {n} poses, the human model has {k} keypoints",
                what(),
            )));
        }
        if let Some((i, c)) = self
            .pa
            .positions
            .iter()
            .enumerate()
            .find_map(|(i, p)| p.iter().find(|c| !c.is_finite()).map(|c| (i, *c)))
        {
            return Err(err(format!(
                "{}: PoseArray.poses[{i}].position: value {c} is not finite",
                what()
            )));
        }
        let mut positions = self.pos_pool.pop().unwrap_or_default();
        positions.clear();
        positions.extend_from_slice(&self.pa.positions);
        let t_meas = self.secs(self.pa.stamp.nanos());
        Ok((
            log_t,
            Body::Human {
                t_meas,
                person,
                positions,
            },
        ))
    }

    /// A `PoseStamped` (`stamped`) or `PoseArray` (its first pose) on an object topic: the log
    /// time `log_t` and the object's position with its stamp.
    fn object_message(
        &mut self,
        m: &Message<'_>,
        stamped: bool,
        log_t: f64,
        what: &dyn Fn() -> String,
    ) -> Result<(f64, Body), LogError> {
        let err = |p: String| LogError::input(&self.file, m.loc, p);
        let id = self
            .cfg
            .object_topics
            .iter()
            .find(|(_, t)| t.as_str() == m.topic)
            .map(|(id, _)| id.clone())
            .unwrap_or_default();
        let (stamp, position) = if stamped {
            let p = cdr::PoseStamped::decode(m.data)
                .map_err(|e| err(format!("{}: PoseStamped: {e}", what())))?;
            (p.stamp, p.position)
        } else {
            self.pa
                .decode(m.data)
                .map_err(|e| err(format!("{}: PoseArray: {e}", what())))?;
            let Some(p) = self.pa.positions.first() else {
                return Err(err(format!(
                    "{}: PoseArray for object `{id}` has no pose",
                    what()
                )));
            };
            (self.pa.stamp, *p)
        };
        if let Some(c) = position.iter().find(|c| !c.is_finite()) {
            return Err(err(format!(
                "{}: object `{id}` position: value {c} is not finite",
                what()
            )));
        }
        let t_meas = self.secs(stamp.nanos());
        Ok((
            log_t,
            Body::Object {
                id,
                t_meas,
                position,
            },
        ))
    }

    /// The next message in time order if it is ready: at least `reorder_window` older than the
    /// latest message read, or any message once the input is `done`.
    pub(crate) fn pop_ready(&mut self, done: bool) -> Option<Pending> {
        let from_run = match (self.run.front(), self.heap.peek()) {
            (Some(a), Some(b)) => a > b,
            (a, _) => a.is_some(),
        };
        let first = if from_run {
            self.run.front()
        } else {
            self.heap.peek()
        };
        let ready = first.is_some_and(|p| done || p.t <= self.max_t - self.cfg.reorder_window);
        let p = match (ready, from_run) {
            (false, _) => None,
            (true, true) => self.run.pop_front(),
            (true, false) => self.heap.pop(),
        }?;
        self.last_released = p.t;
        self.last_released_rank = p.rank();
        Some(p)
    }

    /// Give a released message's buffers back for reuse.
    pub(crate) fn recycle(&mut self, p: Pending) {
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
