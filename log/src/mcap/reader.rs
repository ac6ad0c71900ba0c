//! [`McapReader`]: the streaming reader over `mcap`'s sans-I/O linear reader, the reordering
//! window of pending messages, and the `RecordReader` view of them.

mod chunk;
mod messages;

use super::header::header_from_summary;
use super::{METADATA_KEY, METADATA_NAME, McapConfig, RECORD_LIMIT};
use crate::error::{Location, LogError};
use crate::format::{Header, ModelOverrides, Record, RecordReader};
use crate::ros::{Messages, Pending, Stream};
use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};
use std::collections::HashMap;
use std::io::{Read, Seek, SeekFrom};

/// Where the header came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum HeaderFrom {
    /// Given by the caller (side file): `pacs` metadata records are ignored.
    Given,
    /// The metadata record at this offset.
    Record(u64),
}

/// The channels defined so far, by id (a table indexed by the 16-bit id: looked up once per
/// message, without hashing), and the messages read on each.
#[derive(Default)]
struct Channels {
    by_id: Vec<Option<(String, Stream)>>,
    read: Vec<u64>,
}

impl Channels {
    fn get(&self, id: &u16) -> Option<&(String, Stream)> {
        self.by_id.get(usize::from(*id))?.as_ref()
    }

    fn insert(&mut self, id: u16, c: (String, Stream)) {
        let i = usize::from(id);
        if self.by_id.len() <= i {
            self.by_id.resize_with(i + 1, || None);
            self.read.resize(i + 1, 0);
        }
        self.by_id[i] = Some(c);
    }

    /// Count a message read on channel `id` (defined).
    fn count(&mut self, id: u16) {
        if let Some(n) = self.read.get_mut(usize::from(id)) {
            *n += 1;
        }
    }

    /// The messages read on channel `id` (0 if none), and its topic if it is configured.
    fn read_on(&self, id: u16) -> (u64, Option<&str>) {
        let n = self.read.get(usize::from(id)).copied().unwrap_or(0);
        let topic = self
            .get(&id)
            .filter(|(_, s)| *s != Stream::Ignored)
            .map(|(t, _)| t.as_str());
        (n, topic)
    }

    /// Add the messages read per configured topic to `into` (topic, count).
    fn add_counts(&self, into: &mut Vec<(String, u64)>) {
        for (c, n) in self.by_id.iter().zip(&self.read) {
            let Some((topic, stream)) = c else { continue };
            if *stream == Stream::Ignored {
                continue;
            }
            match into.iter_mut().find(|(t, _)| t == topic) {
                Some((_, k)) => *k += n,
                None => into.push((topic.clone(), *n)),
            }
        }
    }
}

/// Everything but the byte source and the MCAP state machine (split for the borrow checker).
struct State {
    size: u64,
    pos: u64,
    header_from: Option<HeaderFrom>,
    schemas: HashMap<u16, (String, String)>,
    channels: Channels,
    done: bool,
    /// Where the chunk being read starts in the file.
    chunk_at: u64,
    /// The messages' conversion and time order (shared with the db3 reader).
    conv: Messages,
    /// Messages read per configured topic in the parts already read to their end.
    counted: Vec<(String, u64)>,
    /// The part's Statistics record's messages per channel id, if it has one.
    stats: Option<Vec<(u16, u64)>>,
    /// The reader was handed over (its header is read): records found later change it no more.
    opened: bool,
    /// The header was given by the caller (`--header`), not read from the bag's metadata.
    given_by_caller: bool,
}

/// Streaming reader of an MCAP log (a ROS 2 recording); see the module docs.
pub struct McapReader<R: Read + Seek> {
    input: R,
    lin: LinearReader,
    /// The chunk being read (whole chunks come from `lin`, see [`chunk`]).
    chunk: chunk::Chunk,
    st: State,
    current: Option<Pending>,
    /// The files still to read after this one (the later parts of a split bag), with names.
    rest: std::collections::VecDeque<(String, R)>,
    /// Every part's name, by [`Pending::part`].
    part_names: Vec<String>,
    /// The recorder's message counts per topic to hold the files to, and the file that states
    /// them (a bag's `metadata.yaml`), if any.
    expected: Option<(String, Vec<(String, u64)>)>,
    /// The file the header was read from, when that is not the log itself.
    header_file: Option<String>,
}

/// The linear reader's settings: every length bounded, whole chunks handed over, the data and
/// summary sections' CRCs checked.
fn linear_reader() -> LinearReader {
    LinearReader::new_with_options(
        LinearReaderOptions::default()
            .with_record_length_limit(RECORD_LIMIT)
            .with_emit_chunks(true)
            .with_validate_data_section_crc(true)
            .with_validate_summary_section_crc(true),
    )
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
        input: R,
        cfg: &McapConfig,
        overrides: &ModelOverrides,
        header: Option<Header>,
    ) -> Result<Self, LogError> {
        Self::new_parts(
            vec![(file.to_string(), input)],
            cfg,
            overrides,
            header,
            None,
        )
    }

    /// [`Self::new`] over the parts of one recording read one after the other (a rosbag2 bag
    /// split into several MCAP files, in the metadata's order), as one log: one time base and one
    /// reordering window across the files; each file's schemas and channels are its own; errors
    /// name the file they are in. The header (`header`, else the first file's) holds for every
    /// part; `pacs` metadata records of later parts are ignored. `header_file` names the file a
    /// given header was read from (a bag's `metadata.yaml`), for errors in it. `parts` must not be
    /// empty.
    pub fn new_parts(
        parts: Vec<(String, R)>,
        cfg: &McapConfig,
        overrides: &ModelOverrides,
        header: Option<Header>,
        header_file: Option<&str>,
    ) -> Result<Self, LogError> {
        let part_names: Vec<String> = parts.iter().map(|(n, _)| n.clone()).collect();
        if part_names.len() > usize::from(u16::MAX) {
            return Err(LogError::input(
                &part_names[0],
                Location::File,
                format!("an MCAP log of {} files (at most 65535)", part_names.len()),
            ));
        }
        let mut rest: std::collections::VecDeque<(String, R)> = parts.into();
        let Some((file, mut input)) = rest.pop_front() else {
            return Err(LogError::input(
                "",
                Location::File,
                "an MCAP log of no files",
            ));
        };
        let file = file.as_str();
        let io = |e: std::io::Error| LogError::Io {
            file: file.to_string(),
            source: e,
        };
        let mcfg = cfg.clone();
        mcfg.validate()
            .map_err(|p| LogError::input(file, Location::File, format!("invalid config: {p}")))?;
        let size = input.seek(SeekFrom::End(0)).map_err(io)?;
        let header_given = header.is_some();
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
        // A given header in place of the file's own, which the summary indexes: the own one's
        // promises still hold (`keep_own_promises`; a file without summary has its own before
        // the first message, read below). (A given header stands for a malformed own one.)
        let own = match &header_from {
            Some(HeaderFrom::Given) => header_from_summary(file, &mut input, size).ok().flatten(),
            _ => None,
        };
        super::guard::check_chunk_records(file, &mut input, size)?;
        input.seek(SeekFrom::Start(0)).map_err(io)?;
        let lin = linear_reader();
        let mut r = Self {
            input,
            lin,
            chunk: chunk::Chunk::default(),
            rest,
            part_names,
            expected: None,
            header_file: None,
            st: State {
                size,
                pos: 0,
                header_from,
                schemas: HashMap::new(),
                channels: Channels::default(),
                done: false,
                chunk_at: 0,
                counted: Vec::new(),
                stats: None,
                conv: Messages::new(file, mcfg, overrides.clone()),
                opened: false,
                given_by_caller: header_given && header_file.is_none(),
            },
            current: None,
        };
        if let Some(h) = header {
            match header_file {
                Some(f) => {
                    let file = std::mem::replace(&mut r.st.conv.file, f.to_string());
                    let set = r.st.set_header(h);
                    r.st.conv.file = file;
                    set?;
                    r.header_file = Some(f.to_string());
                }
                None => r.st.set_header(h)?,
            }
        }
        if let Some((own, _)) = own {
            r.st.keep_own_promises(&own);
        }
        // Read until the header is known and the first message is queued (fixing the time base).
        while r.st.conv.is_empty() && !r.st.done {
            r.pump()?;
        }
        r.st.opened = true;
        if r.st.conv.header.is_none() {
            return Err(LogError::input(
                file,
                Location::File,
                format!(
                    "missing header: no metadata record named `{METADATA_NAME}` with key `{METADATA_KEY}` (give one: `--header FILE`, or `header=` in Python)"
                ),
            ));
        }
        if let (Some(h), Some(b)) = (r.st.conv.header.as_mut(), r.st.conv.base_s) {
            h.meta.insert("mcap_time_base_s".into(), b.into());
        }
        Ok(r)
    }

    /// Process one MCAP record (one of the chunk being read, or the next in the file), or note
    /// the end of the file.
    fn pump(&mut self) -> Result<(), LogError> {
        let st = &mut self.st;
        loop {
            match self.chunk.next_record() {
                Ok(Some((opcode, data))) => return st.record(opcode, data),
                Ok(None) => {}
                Err(e) => return Err(st.chunk_error(&e)),
            }
            let ev = match self.lin.next_event() {
                None => {
                    st.check_statistics()?;
                    st.channels.add_counts(&mut st.counted);
                    let Some((file, input)) = self.rest.pop_front() else {
                        st.done = true;
                        return check_counts(&self.expected, &st.counted, &st.conv);
                    };
                    self.input = input;
                    st.next_part(file, &mut self.input)?;
                    self.lin = linear_reader();
                    continue;
                }
                Some(Err(e)) => {
                    return Err(LogError::input(
                        &st.conv.file,
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
                                    file: st.conv.file.clone(),
                                    source: e,
                                });
                            }
                        }
                    };
                    st.pos += k as u64;
                    self.lin.notify_read(k);
                }
                LinearReadEvent::Record {
                    opcode: mcap::records::op::CHUNK,
                    data,
                } => {
                    // The chunk starts where its 9-byte opcode and length do.
                    st.chunk_at = st.pos.saturating_sub(9 + data.len() as u64);
                    self.chunk.open(data).map_err(|e| st.chunk_error(&e))?;
                }
                LinearReadEvent::Record { opcode, data } => {
                    return st.record(opcode, data);
                }
            }
        }
    }
}

impl<R: Read + Seek> McapReader<R> {
    /// Hold the messages read per configured topic, at the end of the last part, to the
    /// recorder's counts `counts` (a bag's `topics_with_message_count`, stated in `file`): fewer
    /// means a part is missing or was cut short, more that the counts are not this recording's;
    /// either is an error naming `file`. Topics not configured are not counted.
    pub fn expect_topic_counts(
        &mut self,
        file: &str,
        counts: Vec<(String, u64)>,
    ) -> Result<(), LogError> {
        self.expected = Some((file.to_string(), counts));
        if self.st.done {
            check_counts(&self.expected, &self.st.counted, &self.st.conv)?;
        }
        Ok(())
    }
}

/// The counts read against the expected ones (see [`McapReader::expect_topic_counts`]).
fn check_counts(
    expected: &Option<(String, Vec<(String, u64)>)>,
    counted: &[(String, u64)],
    conv: &Messages,
) -> Result<(), LogError> {
    let Some((file, expected)) = expected else {
        return Ok(());
    };
    let read = |topic: &str| {
        let n = counted.iter().find(|(t, _)| t == topic);
        n.map_or(0, |(_, n)| *n)
    };
    crate::db3::check_topic_counts(file, expected, read, conv)
}

impl<R: Read + Seek> McapReader<R> {
    /// The next record in time order (the `RecordReader` implementation), needing the config for
    /// the header overrides of a late header.
    fn next_inner(&mut self) -> Result<Option<&Pending>, LogError> {
        if let Some(p) = self.current.take() {
            self.st.conv.recycle(p);
        }
        loop {
            if let Some(p) = self.st.conv.pop_ready(self.st.done) {
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
            .conv
            .header
            .as_ref()
            .expect("McapReader::new guarantees a header")
    }

    fn next_record(&mut self) -> Result<Option<Record<'_>>, LogError> {
        if self.next_inner()?.is_none() {
            return Ok(None);
        }
        Ok(self
            .current
            .as_ref()
            .map(|p| p.record(&self.st.conv.person_ids)))
    }

    fn location(&self) -> Location {
        self.current
            .as_ref()
            .map_or(Location::Offset(self.st.pos), |p| p.loc)
    }

    fn header_file(&self) -> &str {
        self.header_file.as_deref().unwrap_or(&self.st.conv.file)
    }

    fn header_location(&self) -> Location {
        match self.st.header_from {
            Some(HeaderFrom::Record(o)) => Location::Offset(o),
            _ => Location::File,
        }
    }

    fn in_canonical_order(&self) -> bool {
        // Released from the reordering window in `(t, rank, arrival)` order (`ros::Pending`).
        true
    }

    fn file(&self) -> &str {
        // The part of the record handed over last (a split bag's messages may be handed over
        // after the next part is opened).
        match &self.current {
            Some(p) => self
                .part_names
                .get(usize::from(p.part))
                .map_or(&self.st.conv.file, |n| n),
            None => &self.st.conv.file,
        }
    }
}
