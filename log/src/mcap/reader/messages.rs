//! The records of the linear pass: schemas, channels (checked against the configured topics),
//! the `pacs` metadata record, and messages handed to the shared conversion ([`crate::ros`]).

use super::{HeaderFrom, State};
use crate::error::{Location, LogError};
use crate::format::Header;
use crate::mcap::METADATA_NAME;
use crate::mcap::fields::{FieldError, Fields};
use crate::mcap::header::parse_metadata;
use crate::ros::{Message, Stream};
use mcap::records::op;

impl State {
    fn err(&self, p: impl Into<String>) -> LogError {
        LogError::input(&self.conv.file, Location::Offset(self.pos), p)
    }

    /// Start reading the next part `file` (its bytes `input`, checked by the walk of
    /// [`crate::mcap::guard`] and left at its start): offsets, schemas and channels begin anew,
    /// the time base, the reordering window and the header carry over (a later part's `pacs`
    /// metadata record is ignored once the header is known).
    pub(super) fn next_part<R: std::io::Read + std::io::Seek>(
        &mut self,
        file: String,
        input: &mut R,
    ) -> Result<(), LogError> {
        use std::io::SeekFrom;
        let io = |e: std::io::Error| LogError::Io {
            file: file.clone(),
            source: e,
        };
        let size = input.seek(SeekFrom::End(0)).map_err(io)?;
        crate::mcap::guard::check_chunk_records(&file, input, size)?;
        input.seek(SeekFrom::Start(0)).map_err(io)?;
        self.size = size;
        self.pos = 0;
        self.chunk_at = 0;
        self.schemas.clear();
        // (The finished part's counts were added by the caller.)
        self.channels = super::Channels::default();
        self.stats = None;
        self.conv.part += 1;
        if self.conv.header.is_some() {
            self.header_from = Some(HeaderFrom::Given);
        }
        self.conv.file = file;
        Ok(())
    }

    /// At the end of a part: the messages read on each configured topic's channel against the
    /// part's own Statistics record (its `channel_message_counts`), if it has one. A file that
    /// counts messages it does not hold was cut or spliced (or holds messages it does not count):
    /// it contradicts itself, and is refused. Channels the audit does not read are not compared.
    pub(super) fn check_statistics(&self) -> Result<(), LogError> {
        let Some(stats) = &self.stats else {
            return Ok(());
        };
        for &(id, want) in stats {
            let (read, topic) = self.channels.read_on(id);
            let Some(topic) = topic else { continue };
            if read != want {
                return Err(LogError::input(
                    &self.conv.file,
                    Location::File,
                    format!(
                        "the file's Statistics record counts {want} messages on channel {id} (`{topic}`), the file holds {read} ({}): it contradicts itself",
                        if read < want {
                            "messages were cut out"
                        } else {
                            "messages were added"
                        }
                    ),
                ));
            }
        }
        Ok(())
    }

    /// A chunk that cannot be read, at the chunk's offset.
    pub(super) fn chunk_error(&self, e: &super::chunk::ChunkError) -> LogError {
        LogError::input(
            &self.conv.file,
            Location::Offset(self.chunk_at),
            format!("{e} (the chunk at offset {})", self.chunk_at),
        )
    }

    /// The file's own header `own`, found where a header was given in its place: the given
    /// header keeps the `start` and `end` events `own` promises (a file cut short stays
    /// incomplete whatever header the audit is given), and, given by the caller, notes that it
    /// replaced one (`meta.own_header_replaced`).
    pub(super) fn keep_own_promises(&mut self, own: &Header) {
        if let Some(h) = self.conv.header.as_mut() {
            h.keep_promises_of(own);
            if self.given_by_caller {
                h.mark_replacing();
            }
        }
    }

    pub(super) fn set_header(&mut self, h: Header) -> Result<(), LogError> {
        let loc = match self.header_from {
            Some(HeaderFrom::Record(o)) => Location::Offset(o),
            _ => Location::File,
        };
        self.conv.set_header(h, loc)
    }

    pub(super) fn record(&mut self, opcode: u8, data: &[u8]) -> Result<(), LogError> {
        // Top-level records end exactly at `pos` (the reader is fed only the bytes it asks for).
        let start = self.pos.saturating_sub(9 + data.len() as u64);
        match opcode {
            op::SCHEMA | op::CHANNEL | op::MESSAGE | op::METADATA | op::STATISTICS => {}
            _ => return Ok(()),
        }
        let bad = |p: FieldError| {
            LogError::input(
                &self.conv.file,
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
            op::STATISTICS => {
                f.u64("statistics message count").map_err(bad)?;
                f.u16("statistics schema count").map_err(bad)?;
                for what in [
                    "statistics channel count",
                    "statistics attachment count",
                    "statistics metadata count",
                    "statistics chunk count",
                ] {
                    f.u32(what).map_err(bad)?;
                }
                f.u64("statistics message start time").map_err(bad)?;
                f.u64("statistics message end time").map_err(bad)?;
                let n = f.u32("statistics channel message counts").map_err(bad)?;
                let mut m = Fields {
                    b: f.take(u64::from(n), "statistics channel message counts")
                        .map_err(bad)?,
                };
                let mut counts = Vec::new();
                while !m.b.is_empty() {
                    let id = m.u16("statistics channel id").map_err(bad)?;
                    let k = m.u64("statistics channel message count").map_err(bad)?;
                    counts.push((id, k));
                }
                if self.stats.is_some() {
                    return Err(self.err("a second Statistics record"));
                }
                self.stats = Some(counts);
            }
            op::METADATA => {
                let (name, h) = parse_metadata(data).map_err(bad)?;
                if let Some(h) = h {
                    debug_assert_eq!(name, METADATA_NAME);
                    match self.header_from {
                        // A header given in its place: the file's own still promises what it
                        // promises (read before the first message, where it must be).
                        Some(HeaderFrom::Given) => {
                            if !self.opened
                                && let Ok(own) = h
                            {
                                self.keep_own_promises(&own);
                            }
                        }
                        Some(HeaderFrom::Record(o)) if o == start => {}
                        Some(HeaderFrom::Record(o)) => {
                            return Err(self.err(format!(
                                "a second metadata record named `{METADATA_NAME}` (the header is at offset {o})"
                            )));
                        }
                        None => {
                            self.header_from = Some(HeaderFrom::Record(start));
                            let mut h = h.map_err(|p| {
                                LogError::input(
                                    &self.conv.file,
                                    Location::Offset(start),
                                    p.to_string(),
                                )
                            })?;
                            // Relative {urdf, side} paths: relative to the MCAP file.
                            h.robot.rebase(&crate::format::dir_of(std::path::Path::new(
                                &self.conv.file,
                            )));
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
        let schema = self.schemas.get(&schema_id).map(|(name, _)| name.as_str());
        let (stream, expected) = self
            .conv
            .stream_of(topic, schema)
            .map_err(|p| self.err(p.to_string()))?;
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
        self.channels.count(h.channel_id);
        let Some((topic, _)) = self.channels.get(&h.channel_id) else {
            return Ok(());
        };
        let what = || {
            format!(
                "message on `{topic}` (log time {} ns, sequence {})",
                h.log_time, h.sequence
            )
        };
        if self.conv.header.is_none() {
            return Err(self.err(format!(
                "missing header: {} comes before any metadata record named `{METADATA_NAME}` and the summary has none (give one: `--header FILE`, or `header=` in Python)",
                what()
            )));
        }
        let m = Message {
            stream,
            topic,
            log_time: h.log_time,
            data,
            loc: Location::Offset(self.pos),
        };
        self.conv.message(m, &what)
    }
}
