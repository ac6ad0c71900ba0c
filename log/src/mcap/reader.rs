//! [`McapReader`]: the streaming reader over `mcap`'s sans-I/O linear reader, the reordering
//! window of pending messages, and the `RecordReader` view of them.

mod messages;

use super::header::header_from_summary;
use super::{METADATA_KEY, METADATA_NAME, McapConfig, RECORD_LIMIT};
use crate::cdr::{JointStateMsg, PoseArray};
use crate::error::{Location, LogError};
use crate::format::{Header, ModelOverrides, Record, RecordReader};
use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};
use std::collections::{BinaryHeap, HashMap};
use std::io::{Read, Seek, SeekFrom};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Stream {
    Robot,
    /// Keypoints of the log's only person (`None`) or of person `person_ids[i]`.
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

enum Body {
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
    /// At equal times: human and object measurements first (a measurement logged at `t` is in use from the
    /// robot sample at `t` on), then robot samples, then events.
    fn rank(&self) -> u8 {
        match self.body {
            Body::Human { .. } | Body::Object { .. } => 0,
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
    /// Keypoint count of each person of the header, by id.
    person_keypoints: Vec<(String, usize)>,
    /// Ids of the people whose topics were seen (what `Stream::Human { person }` indexes).
    person_ids: Vec<String>,
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
            && let Some((mut h, off)) = header_from_summary(file, &mut input, size)?
        {
            // A {urdf, side} robot's relative paths are relative to the MCAP file.
            h.robot
                .rebase(&crate::format::dir_of(std::path::Path::new(file)));
            header = Some(h);
            header_from = Some(HeaderFrom::Record(off));
        }
        super::guard::check_chunk_records(file, &mut input, size)?;
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
                person_keypoints: Vec::new(),
                person_ids: Vec::new(),
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
        if self.next_inner()?.is_none() {
            return Ok(None);
        }
        let Some(p) = self.current.as_ref() else {
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
            Body::Human {
                t_meas,
                person,
                positions,
            } => Record::Human {
                t,
                t_meas: *t_meas,
                person: person.map(|i| self.st.person_ids[usize::from(i)].as_str()),
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
