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

use crate::cdr::{self, CdrWriter, JointStateMsg, PoseArray, Stamp};
use crate::error::{HeaderError, Location, LogError, McapConfigError};
use crate::format::{Header, LogModels, ModelOverrides, Record, RecordReader};
use mcap::records::op;
use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};
use serde::{Deserialize, Serialize};
use std::collections::{BinaryHeap, HashMap};
use std::io::{Read, Seek, SeekFrom, Write};

/// The name of the MCAP metadata record holding the pacs header.
pub const METADATA_NAME: &str = "pacs";
/// The key, in that metadata record, whose value is the header's JSON text.
pub const METADATA_KEY: &str = "header";
/// Schema name of robot messages.
pub const JOINT_STATE: &str = "sensor_msgs/msg/JointState";
/// Schema name of human keypoint messages.
pub const POSE_ARRAY: &str = "geometry_msgs/msg/PoseArray";
/// Schema name of event messages.
pub const STRING: &str = "std_msgs/msg/String";
/// Largest MCAP record (other than a chunk, which is streamed) the reader accepts, in bytes.
pub const RECORD_LIMIT: usize = 64 << 20;
/// Most messages held back for reordering at once; more is an error (memory stays bounded).
pub const MAX_PENDING: usize = 1 << 18;
/// The MCAP magic bytes at the start (and end) of every MCAP file.
pub const MAGIC: &[u8] = mcap::MAGIC;

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
    /// Topic of task events (`std_msgs/msg/String`). Default `/pacs/events`.
    pub event_topic: String,
    /// Messages are put in time order within this window (s); a message older than one already
    /// handed to the checker by more than this is an error. Default 1.0 s.
    pub reorder_window: f64,
}

impl Default for McapConfig {
    fn default() -> Self {
        Self {
            robot_topic: "/joint_states".into(),
            human_topic: "/human/keypoints".into(),
            event_topic: "/pacs/events".into(),
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
        let topics = [
            ("mcap.robot_topic", &self.robot_topic),
            ("mcap.human_topic", &self.human_topic),
            ("mcap.event_topic", &self.event_topic),
        ];
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

/// Parse a pacs header from JSON text (the JSON Lines header object); the error names the problem.
pub fn parse_header_json(text: &str) -> Result<Header, HeaderError> {
    let value: serde_json::Value =
        serde_json::from_str(text).map_err(|e| HeaderError::Json(e.to_string()))?;
    header_from_value(value)
}

/// A header from a parsed JSON value: must have `"type": "header"` and the v1 fields.
pub fn header_from_value(value: serde_json::Value) -> Result<Header, HeaderError> {
    if value.get("type").and_then(|t| t.as_str()) != Some("header") {
        return Err(HeaderError::MissingType);
    }
    let header: Header =
        serde_json::from_value(value).map_err(|e| HeaderError::Fields(e.to_string()))?;
    header.check()?;
    Ok(header)
}

/// Load a header side file (`pacs audit --header FILE`): JSON, or TOML when the name ends in
/// `.toml`. Errors name the file.
pub fn load_header_file(path: &std::path::Path) -> Result<Header, LogError> {
    let name = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| LogError::Io {
        file: name.clone(),
        source: e,
    })?;
    let value = if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("toml"))
    {
        let v: toml::Value = toml::from_str(&text)
            .map_err(|e| LogError::input(&name, Location::File, format!("invalid TOML: {e}")))?;
        serde_json::to_value(v)
            .map_err(|e| LogError::input(&name, Location::File, format!("invalid header: {e}")))?
    } else {
        serde_json::from_str(&text)
            .map_err(|e| LogError::input(&name, Location::File, format!("invalid JSON: {e}")))?
    };
    header_from_value(value).map_err(|p| LogError::input(&name, Location::File, p.to_string()))
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Stream {
    Robot,
    Human,
    Event,
    Ignored,
}

enum Body {
    Robot {
        q: Vec<f64>,
        dq: Option<Vec<f64>>,
    },
    Human {
        t_meas: f64,
        positions: Vec<[f64; 3]>,
    },
    Event(String),
}

struct Pending {
    t: f64,
    seq: u64,
    offset: u64,
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
impl Pending {
    /// At equal times: human measurements first (a measurement logged at `t` is in use from the
    /// robot sample at `t` on), then robot samples, then events.
    fn rank(&self) -> u8 {
        match self.body {
            Body::Human { .. } => 0,
            Body::Robot { .. } => 1,
            Body::Event(_) => 2,
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

/// Where the header came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum HeaderFrom {
    /// Given by the caller (side file): `pacs` metadata records are ignored.
    Given,
    /// The metadata record at this offset.
    Record(u64),
}

/// Everything but the byte source and the MCAP state machine (split for the borrow checker).
struct State {
    file: String,
    size: u64,
    pos: u64,
    cfg: McapConfig,
    overrides: ModelOverrides,
    header: Option<Header>,
    header_from: Option<HeaderFrom>,
    /// Model joint names (effective robot) and keypoint count (effective human).
    joints: Vec<String>,
    keypoints: usize,
    schemas: HashMap<u16, (String, String)>,
    channels: HashMap<u16, (String, Stream)>,
    /// Whole seconds subtracted from every time stamp (the first message's log time).
    base_s: Option<i64>,
    heap: BinaryHeap<Pending>,
    seq: u64,
    max_t: f64,
    last_released: f64,
    done: bool,
    js: JointStateMsg,
    pa: PoseArray,
    /// Cached name → model-order map of the last `JointState.name` list.
    map_names: Vec<String>,
    map: Vec<usize>,
    f64_pool: Vec<Vec<f64>>,
    pos_pool: Vec<Vec<[f64; 3]>>,
    str_pool: Vec<String>,
}

/// Streaming reader of an MCAP log (a ROS 2 recording); see the module docs.
pub struct McapReader<R: Read + Seek> {
    input: R,
    lin: LinearReader,
    st: State,
    current: Option<Pending>,
}

fn mcap_problem(e: &mcap::McapError) -> String {
    match e {
        mcap::McapError::UnexpectedEof => {
            "truncated file: unexpected end of file inside a record or before the footer".into()
        }
        mcap::McapError::BadMagic => "not an MCAP file, or damaged: bad magic bytes".into(),
        e => format!("invalid MCAP: {e}"),
    }
}

impl<R: Read + Seek> McapReader<R> {
    /// Open an MCAP log: find the header (`header` if given, else the `pacs` metadata record via
    /// the summary's metadata index or before the first message), resolve the effective models
    /// (`cfg`'s overrides applied) and read up to the first message. `file` names the input in
    /// errors.
    pub fn new(
        file: &str,
        mut input: R,
        cfg: &McapConfig,
        overrides: &ModelOverrides,
        header: Option<Header>,
    ) -> Result<Self, LogError> {
        let io = |e: std::io::Error| LogError::Io {
            file: file.to_string(),
            source: e,
        };
        let mcfg = cfg.clone();
        mcfg.validate()
            .map_err(|p| LogError::input(file, Location::File, format!("invalid config: {p}")))?;
        let size = input.seek(SeekFrom::End(0)).map_err(io)?;
        let mut header_from = header.as_ref().map(|_| HeaderFrom::Given);
        let mut header = header;
        if header.is_none()
            && let Some((h, off)) = header_from_summary(file, &mut input, size)?
        {
            header = Some(h);
            header_from = Some(HeaderFrom::Record(off));
        }
        input.seek(SeekFrom::Start(0)).map_err(io)?;
        let lin = LinearReader::new_with_options(
            LinearReaderOptions::default()
                .with_record_length_limit(RECORD_LIMIT)
                .with_validate_chunk_crcs(true)
                .with_validate_data_section_crc(true)
                .with_validate_summary_section_crc(true),
        );
        let mut r = Self {
            input,
            lin,
            st: State {
                file: file.to_string(),
                size,
                pos: 0,
                cfg: mcfg,
                overrides: overrides.clone(),
                header: None,
                header_from,
                joints: Vec::new(),
                keypoints: 0,
                schemas: HashMap::new(),
                channels: HashMap::new(),
                base_s: None,
                heap: BinaryHeap::new(),
                seq: 0,
                max_t: f64::NEG_INFINITY,
                last_released: f64::NEG_INFINITY,
                done: false,
                js: JointStateMsg::default(),
                pa: PoseArray::default(),
                map_names: Vec::new(),
                map: Vec::new(),
                f64_pool: Vec::new(),
                pos_pool: Vec::new(),
                str_pool: Vec::new(),
            },
            current: None,
        };
        if let Some(h) = header {
            r.st.set_header(h)?;
        }
        // Read until the header is known and the first message is queued (fixing the time base).
        while r.st.heap.is_empty() && !r.st.done {
            r.pump()?;
        }
        if r.st.header.is_none() {
            return Err(LogError::input(
                file,
                Location::File,
                format!(
                    "missing header: no metadata record named `{METADATA_NAME}` with key `{METADATA_KEY}` (give one with --header)"
                ),
            ));
        }
        if let (Some(h), Some(b)) = (r.st.header.as_mut(), r.st.base_s) {
            h.meta.insert("mcap_time_base_s".into(), b.into());
        }
        Ok(r)
    }

    /// Process one MCAP event that yields a record (or the end of the file).
    fn pump(&mut self) -> Result<(), LogError> {
        let st = &mut self.st;
        loop {
            let ev = match self.lin.next_event() {
                None => {
                    st.done = true;
                    return Ok(());
                }
                Some(Err(e)) => {
                    return Err(LogError::input(
                        &st.file,
                        Location::Offset(st.pos),
                        mcap_problem(&e),
                    ));
                }
                Some(Ok(ev)) => ev,
            };
            match ev {
                LinearReadEvent::ReadRequest(n) => {
                    let remaining = st.size.saturating_sub(st.pos);
                    if remaining == 0 {
                        self.lin.notify_read(0);
                        continue;
                    }
                    let want = (n.max(1) as u64).min(remaining) as usize;
                    let buf = self.lin.insert(want);
                    let k = loop {
                        match self.input.read(buf) {
                            Ok(k) => break k,
                            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                            Err(e) => {
                                return Err(LogError::Io {
                                    file: st.file.clone(),
                                    source: e,
                                });
                            }
                        }
                    };
                    st.pos += k as u64;
                    self.lin.notify_read(k);
                }
                LinearReadEvent::Record { opcode, data } => {
                    return st.record(opcode, data);
                }
            }
        }
    }
}

/// A field of an MCAP record body that cannot be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
enum FieldError {
    /// The field's declared length runs past the record.
    #[error("{what}: {declared} bytes declared, only {remaining} remain in the record")]
    Truncated {
        what: &'static str,
        declared: u64,
        remaining: usize,
    },
    /// A string field is not UTF-8.
    #[error("{0}: not valid UTF-8")]
    Utf8(&'static str),
}

/// The `pacs` header a metadata record holds, or why it holds none.
#[derive(Debug, thiserror::Error)]
enum MetadataHeaderError {
    /// The record has no header key.
    #[error("missing header: metadata record `{METADATA_NAME}` has no key `{METADATA_KEY}`")]
    NoKey,
    /// The header key appears twice.
    #[error("key `{METADATA_KEY}` appears twice")]
    DuplicateKey,
    /// The header text is invalid.
    #[error("header: {0}")]
    Header(#[from] HeaderError),
}

/// Little-endian field reader over one MCAP record body; every length is checked against the
/// remaining bytes before use (`mcap`'s own record parser reserves a string's declared length
/// before checking it, so the records the audit needs are parsed here).
struct Fields<'a> {
    b: &'a [u8],
}

impl<'a> Fields<'a> {
    fn take(&mut self, n: u64, what: &'static str) -> Result<&'a [u8], FieldError> {
        if n > self.b.len() as u64 {
            return Err(FieldError::Truncated {
                what,
                declared: n,
                remaining: self.b.len(),
            });
        }
        let (h, t) = self.b.split_at(n as usize);
        self.b = t;
        Ok(h)
    }
    fn int<const N: usize>(&mut self, what: &'static str) -> Result<[u8; N], FieldError> {
        let s = self.take(N as u64, what)?;
        let mut a = [0u8; N];
        a.copy_from_slice(s);
        Ok(a)
    }
    fn u16(&mut self, what: &'static str) -> Result<u16, FieldError> {
        Ok(u16::from_le_bytes(self.int(what)?))
    }
    fn u32(&mut self, what: &'static str) -> Result<u32, FieldError> {
        Ok(u32::from_le_bytes(self.int(what)?))
    }
    fn u64(&mut self, what: &'static str) -> Result<u64, FieldError> {
        Ok(u64::from_le_bytes(self.int(what)?))
    }
    fn bytes(&mut self, what: &'static str) -> Result<&'a [u8], FieldError> {
        let n = self.u32(what)?;
        self.take(u64::from(n), what)
    }
    fn str(&mut self, what: &'static str) -> Result<&'a str, FieldError> {
        std::str::from_utf8(self.bytes(what)?).map_err(|_| FieldError::Utf8(what))
    }
    /// A `Map<string, string>` (byte length, then key/value pairs); visits each pair.
    fn map(
        &mut self,
        what: &'static str,
        mut f: impl FnMut(&'a str, &'a str),
    ) -> Result<(), FieldError> {
        let n = self.u32(what)?;
        let mut m = Fields {
            b: self.take(u64::from(n), what)?,
        };
        while !m.b.is_empty() {
            let k = m.str(what)?;
            let v = m.str(what)?;
            f(k, v);
        }
        Ok(())
    }
}

/// Look for the `pacs` metadata record through the summary's metadata index. A missing or
/// unreadable summary gives `None` (the linear pass then looks for the record, and reports a
/// damaged file); a `pacs` index entry pointing at an invalid record is an error.
fn header_from_summary<R: Read + Seek>(
    file: &str,
    input: &mut R,
    size: u64,
) -> Result<Option<(Header, u64)>, LogError> {
    // Footer record (opcode, length, summary_start, summary_offset_start, crc) + end magic.
    const TAIL: u64 = 1 + 8 + 8 + 8 + 4 + 8;
    let io = |e: std::io::Error| LogError::Io {
        file: file.to_string(),
        source: e,
    };
    if size < TAIL + 8 {
        return Ok(None);
    }
    let mut tail = [0u8; TAIL as usize];
    input.seek(SeekFrom::Start(size - TAIL)).map_err(io)?;
    if input.read_exact(&mut tail).is_err() || tail[0] != op::FOOTER || &tail[29..] != MAGIC {
        return Ok(None);
    }
    let mut f = Fields { b: &tail[9..29] };
    let (Ok(start), Ok(_)) = (f.u64(""), f.u64("")) else {
        return Ok(None);
    };
    let end = size - TAIL;
    if start == 0 || start >= end {
        return Ok(None);
    }
    // Walk the summary section's records, reading only metadata index bodies.
    let mut pos = start;
    let mut found: Option<(u64, u64)> = None;
    while pos + 9 <= end {
        let mut head = [0u8; 9];
        input.seek(SeekFrom::Start(pos)).map_err(io)?;
        if input.read_exact(&mut head).is_err() {
            return Ok(None);
        }
        let len = u64::from_le_bytes(head[1..9].try_into().unwrap_or([0xff; 8]));
        let Some(next) = (pos + 9).checked_add(len).filter(|&n| n <= end) else {
            return Ok(None);
        };
        if head[0] == op::METADATA_INDEX && len <= 4096 {
            let mut body = vec![0u8; len as usize];
            if input.read_exact(&mut body).is_err() {
                return Ok(None);
            }
            let mut m = Fields { b: &body };
            let (Ok(offset), Ok(length), Ok(name)) = (m.u64(""), m.u64(""), m.str("")) else {
                return Ok(None);
            };
            if name == METADATA_NAME {
                if found.is_some() {
                    return Err(LogError::input(
                        file,
                        Location::Offset(offset),
                        format!(
                            "more than one metadata record named `{METADATA_NAME}` (ambiguous header)"
                        ),
                    ));
                }
                found = Some((offset, length));
            }
        }
        pos = next;
    }
    let Some((offset, len)) = found else {
        return Ok(None);
    };
    let loc = Location::Offset(offset);
    let err = |p: String| LogError::input(file, loc, p);
    if len < 9 || len > RECORD_LIMIT as u64 || offset.saturating_add(len) > size {
        return Err(err(format!(
            "metadata index of `{METADATA_NAME}`: record length {len} at offset {offset} does not fit the file"
        )));
    }
    input.seek(SeekFrom::Start(offset)).map_err(io)?;
    let mut buf = vec![0u8; len as usize];
    input.read_exact(&mut buf).map_err(io)?;
    let body_len = buf
        .get(1..9)
        .and_then(|b| b.try_into().ok())
        .map(u64::from_le_bytes);
    if buf.first() != Some(&op::METADATA) || body_len != Some(len - 9) {
        return Err(err(format!(
            "metadata index of `{METADATA_NAME}` does not point at a metadata record"
        )));
    }
    match parse_metadata(&buf[9..]) {
        Ok((_, Some(h))) => Ok(Some((h.map_err(|p| err(p.to_string()))?, offset))),
        Ok((_, None)) => Err(err(format!(
            "metadata index of `{METADATA_NAME}` points at another record"
        ))),
        Err(p) => Err(err(format!("invalid metadata record: {p}"))),
    }
}

/// A metadata record body: its name, and (for a `pacs` record) the header it holds (`None` for
/// any other record).
#[allow(clippy::type_complexity)]
fn parse_metadata(
    body: &[u8],
) -> Result<(&str, Option<Result<Header, MetadataHeaderError>>), FieldError> {
    let mut f = Fields { b: body };
    let name = f.str("metadata name")?;
    let mut text = None;
    let mut count = 0;
    f.map("metadata", |k, v| {
        if k == METADATA_KEY {
            text = Some(v);
            count += 1;
        }
    })?;
    let h = match (name == METADATA_NAME, text) {
        (false, _) => None,
        (true, None) => Some(Err(MetadataHeaderError::NoKey)),
        (true, Some(_)) if count > 1 => Some(Err(MetadataHeaderError::DuplicateKey)),
        (true, Some(t)) => Some(parse_header_json(t).map_err(MetadataHeaderError::from)),
    };
    Ok((name, h))
}

impl State {
    fn err(&self, p: impl Into<String>) -> LogError {
        LogError::input(&self.file, Location::Offset(self.pos), p)
    }

    fn set_header(&mut self, h: Header) -> Result<(), LogError> {
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
        self.header = Some(h);
        Ok(())
    }

    fn record(&mut self, opcode: u8, data: &[u8]) -> Result<(), LogError> {
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
                            let h = h.map_err(|p| {
                                LogError::input(&self.file, Location::Offset(start), p.to_string())
                            })?;
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
            (Stream::Human, POSE_ARRAY)
        } else if topic == cfg.event_topic {
            (Stream::Event, STRING)
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
            Stream::Human => {
                self.pa
                    .decode(data)
                    .map_err(|e| self.err(format!("{}: PoseArray: {e}", self.what(h))))?;
                let m = self.pa.positions.len();
                if m != self.keypoints {
                    return Err(self.err(format!(
                        "{}: wrong keypoint count: PoseArray has {m} poses, the human model has {} keypoints", self.what(h),
                        self.keypoints
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
                        positions,
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

    fn recycle(&mut self, p: Pending) {
        match p.body {
            Body::Robot { q, dq } => {
                self.f64_pool.push(q);
                self.f64_pool.extend(dq);
            }
            Body::Human { positions, .. } => self.pos_pool.push(positions),
            Body::Event(s) => self.str_pool.push(s),
        }
    }
}

impl<R: Read + Seek> McapReader<R> {
    /// The next record in time order (the `RecordReader` implementation), needing the config for
    /// the header overrides of a late header.
    fn next_inner(&mut self) -> Result<Option<&Pending>, LogError> {
        if let Some(p) = self.current.take() {
            self.st.recycle(p);
        }
        loop {
            let ready = self.st.heap.peek().is_some_and(|top| {
                self.st.done || top.t <= self.st.max_t - self.st.cfg.reorder_window
            });
            if ready && let Some(p) = self.st.heap.pop() {
                self.st.last_released = p.t;
                self.current = Some(p);
                return Ok(self.current.as_ref());
            }
            if self.st.done {
                return Ok(None);
            }
            self.pump()?;
        }
    }
}

impl<R: Read + Seek> RecordReader for McapReader<R> {
    fn header(&self) -> &Header {
        // `new` fails unless the header is known.
        self.st
            .header
            .as_ref()
            .expect("McapReader::new guarantees a header")
    }

    fn next_record(&mut self) -> Result<Option<Record<'_>>, LogError> {
        let Some(p) = self.next_inner()? else {
            return Ok(None);
        };
        let t = p.t;
        Ok(Some(match &p.body {
            Body::Robot { q, dq } => Record::Robot {
                t,
                q,
                dq: dq.as_deref(),
                ddq: None,
            },
            Body::Human { t_meas, positions } => Record::Human {
                t,
                t_meas: *t_meas,
                positions,
            },
            Body::Event(name) => Record::Event { t, name },
        }))
    }

    fn location(&self) -> Location {
        Location::Offset(self.current.as_ref().map_or(self.st.pos, |p| p.offset))
    }

    fn header_location(&self) -> Location {
        match self.st.header_from {
            Some(HeaderFrom::Record(o)) => Location::Offset(o),
            _ => Location::File,
        }
    }

    fn file(&self) -> &str {
        &self.st.file
    }
}

/// Writes a pacs log as an MCAP file of a ROS 2 recording (the form [`McapReader`] reads): the
/// header as the `pacs` metadata record, then CDR messages on the configured topics.
pub struct McapLogWriter<W: Write + Seek> {
    w: mcap::Writer<W>,
    robot: u16,
    human: u16,
    event: u16,
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
        let mut chan = |name: &str, def: &str, topic: &str| -> Result<u16, McapWriteError> {
            let s = w.add_schema(name, "ros2msg", def.as_bytes())?;
            Ok(w.add_channel(s, topic, "cdr", &none)?)
        };
        let robot = chan(JOINT_STATE, JOINT_STATE_DEF, &cfg.robot_topic)?;
        let human = chan(POSE_ARRAY, POSE_ARRAY_DEF, &cfg.human_topic)?;
        let event = chan(STRING, "string data\n", &cfg.event_topic)?;
        Ok(Self {
            w,
            robot,
            human,
            event,
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
const POSE_ARRAY_DEF: &str = "std_msgs/Header header\ngeometry_msgs/Pose[] poses\n";
