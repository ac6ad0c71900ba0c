//! Streaming JSON Lines reader of log formats v1 and v2. Memory is bounded by the longest line; records
//! are parsed into reused buffers, so reading allocates nothing per robot sample.

use crate::error::{Location, LogError};
use crate::format::{Header, Record, RecordReader};
use serde::de::{DeserializeSeed, Deserializer, IgnoredAny, MapAccess, SeqAccess, Visitor};
use std::fmt;
use std::io::BufRead;

mod decimal;
mod fast;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Robot,
    Human,
    Object,
    Shield,
    Event,
    Header,
    Unknown,
}

/// Reused parse buffers of one line.
#[derive(Default, Debug)]
struct LineBuffers {
    kind: Option<Kind>,
    /// The `type` field's text (bytes: the fast scanner's are ASCII, serde_json's UTF-8).
    kind_name: Vec<u8>,
    t: Option<f64>,
    t_meas: Option<f64>,
    q: Vec<f64>,
    has_q: bool,
    dq: Vec<f64>,
    has_dq: bool,
    ddq: Vec<f64>,
    has_ddq: bool,
    positions: Vec<[f64; 3]>,
    has_positions: bool,
    name: String,
    has_name: bool,
    id: String,
    has_id: bool,
    position: Vec<f64>,
    has_position: bool,
    velocity: Vec<f64>,
    has_velocity: bool,
    /// The first unknown field name of the line (bytes, as `kind_name`).
    unknown_field: Vec<u8>,
    duplicate: Option<&'static str>,
}

impl LineBuffers {
    /// The record type as text, for messages.
    fn kind_text(&self) -> std::borrow::Cow<'_, str> {
        String::from_utf8_lossy(&self.kind_name)
    }

    fn reset(&mut self) {
        self.kind = None;
        self.kind_name.clear();
        self.t = None;
        self.t_meas = None;
        self.q.clear();
        self.has_q = false;
        self.dq.clear();
        self.has_dq = false;
        self.ddq.clear();
        self.has_ddq = false;
        self.positions.clear();
        self.has_positions = false;
        self.name.clear();
        self.has_name = false;
        self.id.clear();
        self.has_id = false;
        self.position.clear();
        self.has_position = false;
        self.velocity.clear();
        self.has_velocity = false;
        self.unknown_field.clear();
        self.duplicate = None;
    }
}

enum Field {
    Type,
    T,
    TMeas,
    Q,
    Dq,
    Ddq,
    Positions,
    Name,
    Id,
    Position,
    Velocity,
    Other,
}

impl Field {
    /// The field named `name`; the first unknown name of a line is kept in `unknown`.
    #[inline]
    fn of(name: &[u8], unknown: &mut Vec<u8>) -> Field {
        let field = Field::known(name);
        if matches!(field, Field::Other) && unknown.is_empty() {
            unknown.extend_from_slice(name);
        }
        field
    }

    /// The field of a name, by its length first (then one comparison of at most nine bytes).
    #[inline]
    fn known(name: &[u8]) -> Field {
        match (name.len(), name.first()) {
            (1, Some(b't')) => Field::T,
            (1, Some(b'q')) => Field::Q,
            (2, _) if name == b"dq" => Field::Dq,
            (2, _) if name == b"id" => Field::Id,
            (3, _) if name == b"ddq" => Field::Ddq,
            (4, _) if name == b"type" => Field::Type,
            (4, _) if name == b"name" => Field::Name,
            (6, _) if name == b"t_meas" => Field::TMeas,
            (8, _) if name == b"position" => Field::Position,
            (8, _) if name == b"velocity" => Field::Velocity,
            (9, _) if name == b"positions" => Field::Positions,
            _ => Field::Other,
        }
    }
}

/// Where a field's value comes from: the serde_json parser (the reference, with its error
/// messages) or the fast scanner ([`fast`]). One implementation of what each field means
/// ([`LineBuffers::take`]) serves both.
trait Values {
    type Error;
    fn string(&mut self, into: &mut String) -> Result<(), Self::Error>;
    /// A string's bytes (the record type: compared, not kept as text).
    fn word(&mut self, into: &mut Vec<u8>) -> Result<(), Self::Error>;
    fn number(&mut self) -> Result<f64, Self::Error>;
    fn numbers(&mut self, into: &mut Vec<f64>) -> Result<(), Self::Error>;
    fn points(&mut self, into: &mut Vec<[f64; 3]>) -> Result<(), Self::Error>;
    fn skip(&mut self) -> Result<(), Self::Error>;
}

impl LineBuffers {
    /// Take the value of `field` from `v` into the buffers (a field seen twice is noted in
    /// `duplicate`, the first one only).
    fn take<V: Values>(&mut self, field: Field, v: &mut V) -> Result<(), V::Error> {
        let b = self;
        let mut dup = |seen: bool, name: &'static str| {
            if seen && b.duplicate.is_none() {
                b.duplicate = Some(name);
            }
        };
        match field {
            Field::Type => {
                dup(b.kind.is_some(), "type");
                v.word(&mut b.kind_name)?;
                b.kind = Some(match b.kind_name.as_slice() {
                    b"robot" => Kind::Robot,
                    b"human" => Kind::Human,
                    b"object" => Kind::Object,
                    b"shield" => Kind::Shield,
                    b"event" => Kind::Event,
                    b"header" => Kind::Header,
                    _ => Kind::Unknown,
                });
            }
            Field::T => {
                dup(b.t.is_some(), "t");
                b.t = Some(v.number()?);
            }
            Field::TMeas => {
                dup(b.t_meas.is_some(), "t_meas");
                b.t_meas = Some(v.number()?);
            }
            Field::Q => {
                dup(b.has_q, "q");
                v.numbers(&mut b.q)?;
                b.has_q = true;
            }
            Field::Dq => {
                dup(b.has_dq, "dq");
                v.numbers(&mut b.dq)?;
                b.has_dq = true;
            }
            Field::Ddq => {
                dup(b.has_ddq, "ddq");
                v.numbers(&mut b.ddq)?;
                b.has_ddq = true;
            }
            Field::Positions => {
                dup(b.has_positions, "positions");
                v.points(&mut b.positions)?;
                b.has_positions = true;
            }
            Field::Name => {
                dup(b.has_name, "name");
                v.string(&mut b.name)?;
                b.has_name = true;
            }
            Field::Id => {
                dup(b.has_id, "id");
                v.string(&mut b.id)?;
                b.has_id = true;
            }
            Field::Position => {
                dup(b.has_position, "position");
                v.numbers(&mut b.position)?;
                b.has_position = true;
            }
            Field::Velocity => {
                dup(b.has_velocity, "velocity");
                v.numbers(&mut b.velocity)?;
                b.has_velocity = true;
            }
            Field::Other => v.skip()?,
        }
        Ok(())
    }
}

/// The serde_json side of [`Values`].
struct SerdeValues<'m, 'de, A>(&'m mut A, std::marker::PhantomData<&'de ()>);

impl<'de, A: MapAccess<'de>> Values for SerdeValues<'_, 'de, A> {
    type Error = A::Error;
    fn string(&mut self, into: &mut String) -> Result<(), A::Error> {
        self.0.next_value_seed(StrInto(into))
    }
    fn word(&mut self, into: &mut Vec<u8>) -> Result<(), A::Error> {
        let mut text = String::new();
        self.0.next_value_seed(StrInto(&mut text))?;
        into.clear();
        into.extend_from_slice(text.as_bytes());
        Ok(())
    }
    fn number(&mut self) -> Result<f64, A::Error> {
        self.0.next_value()
    }
    fn numbers(&mut self, into: &mut Vec<f64>) -> Result<(), A::Error> {
        self.0.next_value_seed(VecInto(into))
    }
    fn points(&mut self, into: &mut Vec<[f64; 3]>) -> Result<(), A::Error> {
        self.0.next_value_seed(VecInto(into))
    }
    fn skip(&mut self) -> Result<(), A::Error> {
        self.0.next_value::<IgnoredAny>().map(|_| ())
    }
}

struct FieldSeed<'b>(&'b mut Vec<u8>);

impl<'de> DeserializeSeed<'de> for FieldSeed<'_> {
    type Value = Field;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<Field, D::Error> {
        d.deserialize_str(self)
    }
}

impl<'de> Visitor<'de> for FieldSeed<'_> {
    type Value = Field;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a field name")
    }
    fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<Field, E> {
        Ok(Field::of(v.as_bytes(), self.0))
    }
}

struct StrInto<'b>(&'b mut String);

impl<'de> DeserializeSeed<'de> for StrInto<'_> {
    type Value = ();
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        d.deserialize_str(self)
    }
}

impl<'de> Visitor<'de> for StrInto<'_> {
    type Value = ();
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a string")
    }
    fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<(), E> {
        self.0.clear();
        self.0.push_str(v);
        Ok(())
    }
}

struct VecInto<'b, T>(&'b mut Vec<T>);

impl<'de, T: serde::Deserialize<'de>> DeserializeSeed<'de> for VecInto<'_, T> {
    type Value = ();
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        d.deserialize_seq(self)
    }
}

impl<'de, T: serde::Deserialize<'de>> Visitor<'de> for VecInto<'_, T> {
    type Value = ();
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("an array")
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
        self.0.clear();
        while let Some(x) = seq.next_element::<T>()? {
            self.0.push(x);
        }
        Ok(())
    }
}

struct LineSeed<'b>(&'b mut LineBuffers);

impl<'de> DeserializeSeed<'de> for LineSeed<'_> {
    type Value = ();
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        d.deserialize_map(self)
    }
}

impl<'de> Visitor<'de> for LineSeed<'_> {
    type Value = ();
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a JSON object")
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<(), A::Error> {
        let b = self.0;
        while let Some(field) = map.next_key_seed(FieldSeed(&mut b.unknown_field))? {
            b.take(field, &mut SerdeValues(&mut map, std::marker::PhantomData))?;
        }
        Ok(())
    }
}

/// Whether the fast scanner and serde_json read `line` alike: where the scanner takes the line,
/// serde_json takes it too and every buffer holds the same value (bit for bit: compared by
/// their `Debug` text, which tells `-0.0` from `0.0`). Lines the scanner does not take are left
/// to serde_json and always agree. For tests and the `jsonl` fuzz target.
#[doc(hidden)]
pub fn fast_path_agrees(line: &str) -> bool {
    let mut fast = LineBuffers::default();
    if !fast::parse_line(line.as_bytes(), &mut fast) {
        return true;
    }
    let mut slow = LineBuffers::default();
    let mut de = serde_json::Deserializer::from_str(line);
    let ok = LineSeed(&mut slow)
        .deserialize(&mut de)
        .and_then(|()| de.end())
        .is_ok();
    ok && format!("{fast:?}") == format!("{slow:?}")
}

/// The fast scanner's value of the JSON number `text` (`None` if it does not take it). For
/// tests.
#[doc(hidden)]
pub fn fast_path_value(text: &str) -> Option<f64> {
    fast::number(text)
}

/// Whether the fast scanner takes `line` (for tests: the cases must reach it).
#[doc(hidden)]
pub fn fast_path_takes(line: &str) -> bool {
    fast::parse_line(line.as_bytes(), &mut LineBuffers::default())
}

/// Streaming reader of a JSON Lines log (see `docs/log-format.md`).
pub struct JsonlReader<R: BufRead> {
    file: String,
    input: R,
    line: String,
    line_no: u64,
    header: Header,
    bufs: LineBuffers,
}

impl<R: BufRead> JsonlReader<R> {
    /// Read and check the header (first non-blank line). `file` names the input in errors.
    pub fn new(file: &str, mut input: R) -> Result<Self, LogError> {
        let mut line = String::new();
        let mut line_no = 0u64;
        loop {
            line.clear();
            let n = read_line(file, &mut input, &mut line, line_no + 1)?;
            if n == 0 {
                return Err(LogError::input(
                    file,
                    Location::File,
                    "missing header: the file is empty",
                ));
            }
            line_no += 1;
            if !line.trim().is_empty() {
                break;
            }
        }
        let loc = Location::Line(line_no);
        if line.starts_with('\u{feff}') {
            return Err(LogError::input(
                file,
                loc,
                if line_no == 1 {
                    "the file starts with a UTF-8 byte order mark (EF BB BF); JSON Lines logs are UTF-8 without BOM: remove it"
                } else {
                    "the line starts with a UTF-8 byte order mark (EF BB BF); JSON Lines logs are UTF-8 without BOM: remove it"
                },
            ));
        }
        let value: serde_json::Value = serde_json::from_str(&line).map_err(|e| {
            let e = pacs_models::describe_json_error(&line, &e);
            LogError::input(file, loc, format!("invalid JSON: {e}"))
        })?;
        if value.get("type").and_then(|t| t.as_str()) != Some("header") {
            return Err(LogError::input(
                file,
                loc,
                "missing header: the first record must have \"type\": \"header\"",
            ));
        }
        let header = Header::checked(file, loc, Ok(value))?;
        Ok(Self {
            file: file.to_string(),
            input,
            line,
            line_no,
            header,
            bufs: LineBuffers::default(),
        })
    }
}

/// Append the next line of `input` to `line` (through its `\n`, or to the end of the input) and
/// return its length in bytes (0 at the end), as `BufRead::read_line`; the line end is found with
/// `memchr` (vectorized) in the reader's buffer, and the line is refused if it is not UTF-8.
fn read_line<R: BufRead>(
    file: &str,
    input: &mut R,
    line: &mut String,
    line_no: u64,
) -> Result<usize, LogError> {
    let io = |e: std::io::Error| LogError::Io {
        file: file.to_string(),
        source: e,
    };
    let mut bytes = std::mem::take(line).into_bytes();
    let start = bytes.len();
    loop {
        let buf = match input.fill_buf() {
            Ok(buf) => buf,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(io(e)),
        };
        if buf.is_empty() {
            break;
        }
        match memchr::memchr(b'\n', buf) {
            Some(i) => {
                bytes.extend_from_slice(&buf[..=i]);
                input.consume(i + 1);
                break;
            }
            None => {
                let n = buf.len();
                bytes.extend_from_slice(buf);
                input.consume(n);
            }
        }
    }
    let n = bytes.len() - start;
    match String::from_utf8(bytes) {
        Ok(s) => {
            *line = s;
            Ok(n)
        }
        Err(e) => {
            let mut bytes = e.into_bytes();
            bytes.truncate(start);
            // The bytes kept were a `String`'s.
            *line = String::from_utf8(bytes).unwrap_or_default();
            Err(LogError::input(
                file,
                Location::Line(line_no),
                "line is not valid UTF-8",
            ))
        }
    }
}

impl<R: BufRead> RecordReader for JsonlReader<R> {
    fn header(&self) -> &Header {
        &self.header
    }

    fn file(&self) -> &str {
        &self.file
    }

    fn location(&self) -> Location {
        Location::Line(self.line_no)
    }

    fn next_record(&mut self) -> Result<Option<Record<'_>>, LogError> {
        if !self.scan_in_place()? {
            if !self.read_record_line()? {
                return Ok(None);
            }
            let b = &mut self.bufs;
            b.reset();
            if !fast::parse_line(self.line.as_bytes(), b) {
                // Not a line the fast scanner takes (or not JSON): serde_json decides, with its
                // error message.
                b.reset();
                let mut de = serde_json::Deserializer::from_str(&self.line);
                LineSeed(b)
                    .deserialize(&mut de)
                    .and_then(|()| de.end())
                    .map_err(|e| {
                        let e = pacs_models::describe_json_error(&self.line, &e);
                        LogError::input(
                            &self.file,
                            Location::Line(self.line_no),
                            format!("invalid JSON record: {e}"),
                        )
                    })?;
            }
        }
        let loc = Location::Line(self.line_no);
        let file = self.file.as_str();
        let err = |p: String| LogError::input(file, loc, p);
        let b = &mut self.bufs;
        if let Some(d) = b.duplicate {
            return Err(err(format!("field `{d}` appears twice")));
        }
        let kind = b
            .kind
            .ok_or_else(|| err("record has no `type` field".into()))?;
        if kind == Kind::Header {
            return Err(err("a second header record".into()));
        }
        let t =
            b.t.ok_or_else(|| err(format!("{} record has no `t` field", b.kind_text())))?;
        check_fields(b, kind, self.header.version, &err)?;
        record_of(b, kind, t, &err).map(Some)
    }
}

impl<R: BufRead> JsonlReader<R> {
    /// The common case without copying: if the next line lies whole in the input's buffer and
    /// the fast scanner takes it, it is read into the buffers in place and consumed (true).
    /// Otherwise nothing is consumed (false) and [`Self::read_record_line`] reads the line as
    /// before — a blank line, a line across the buffer's end, one with a byte outside ASCII or
    /// one the scanner does not take. A line the scanner takes is ASCII, so it is UTF-8 as
    /// [`read_line`] requires, and it ends with its newline (a last line without one is left
    /// to be refused).
    fn scan_in_place(&mut self) -> Result<bool, LogError> {
        let buf = match self.input.fill_buf() {
            Ok(buf) => buf,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => return Ok(false),
            Err(e) => {
                return Err(LogError::Io {
                    file: self.file.clone(),
                    source: e,
                });
            }
        };
        let Some(end) = memchr::memchr(b'\n', buf) else {
            return Ok(false);
        };
        self.bufs.reset();
        if !fast::parse_line(&buf[..=end], &mut self.bufs) {
            return Ok(false);
        }
        self.input.consume(end + 1);
        self.line_no += 1;
        Ok(true)
    }

    /// Read the next line that is not blank into `self.line`; false at the end of the file. The
    /// last line of a file must be complete: a writer killed mid-line leaves a prefix that may
    /// still parse (e.g. a shortened number), so an unterminated line is refused.
    fn read_record_line(&mut self) -> Result<bool, LogError> {
        loop {
            self.line.clear();
            let n = read_line(
                &self.file,
                &mut self.input,
                &mut self.line,
                self.line_no + 1,
            )?;
            if n == 0 {
                return Ok(false);
            }
            self.line_no += 1;
            if !self.line.trim().is_empty() {
                break;
            }
        }
        if !self.line.ends_with('\n') {
            return Err(LogError::input(
                &self.file,
                Location::Line(self.line_no),
                "truncated line (no newline at the end of the file)",
            ));
        }
        Ok(true)
    }
}

/// Refuse a field a record of `kind` does not have (in format `version`); `shield` records
/// (diagnostics) may carry any.
fn check_fields(
    b: &LineBuffers,
    kind: Kind,
    version: u32,
    err: &impl Fn(String) -> LogError,
) -> Result<(), LogError> {
    let allowed: &[&str] = match kind {
        Kind::Robot => &["q", "dq", "ddq"],
        Kind::Human if version >= 2 => &["t_meas", "id", "positions"],
        Kind::Human => &["t_meas", "positions"],
        Kind::Object => &["t_meas", "id", "position", "velocity"],
        Kind::Event => &["name"],
        Kind::Shield => return Ok(()),
        Kind::Unknown | Kind::Header => {
            return Err(err(format!("unknown record type `{}`", b.kind_text())));
        }
    };
    if !b.unknown_field.is_empty() {
        return Err(err(format!(
            "unknown field `{}` in a {} record",
            String::from_utf8_lossy(&b.unknown_field),
            b.kind_text()
        )));
    }
    let present = [
        ("t_meas", b.t_meas.is_some()),
        ("q", b.has_q),
        ("dq", b.has_dq),
        ("ddq", b.has_ddq),
        ("positions", b.has_positions),
        ("name", b.has_name),
        ("id", b.has_id),
        ("position", b.has_position),
        ("velocity", b.has_velocity),
    ];
    if let Some((f, _)) = present.iter().find(|(f, p)| *p && !allowed.contains(f)) {
        return Err(err(format!(
            "unknown field `{f}` in a {} record",
            b.kind_text()
        )));
    }
    Ok(())
}

/// The record of `kind` at `t` (s) the buffers hold; errors name a missing field or an object
/// vector of the wrong length.
fn record_of<'b>(
    b: &'b LineBuffers,
    kind: Kind,
    t: f64,
    err: &impl Fn(String) -> LogError,
) -> Result<Record<'b>, LogError> {
    Ok(match kind {
        Kind::Robot => {
            if !b.has_q {
                return Err(err("robot record has no `q` field".into()));
            }
            Record::Robot {
                t,
                q: &b.q,
                dq: b.has_dq.then_some(&b.dq[..]),
                ddq: b.has_ddq.then_some(&b.ddq[..]),
            }
        }
        Kind::Human => {
            if !b.has_positions {
                return Err(err("human record has no `positions` field".into()));
            }
            Record::Human {
                t,
                t_meas: b.t_meas.unwrap_or(t),
                person: b.has_id.then_some(b.id.as_str()),
                positions: &b.positions,
            }
        }
        Kind::Object => {
            if !b.has_id {
                return Err(err("object record has no `id` field".into()));
            }
            let vec3 = |field: &str, v: &[f64]| -> Result<[f64; 3], LogError> {
                <[f64; 3]>::try_from(v).map_err(|_| {
                    err(format!(
                        "object record: `{field}` needs 3 values (m, m/s), found {}",
                        v.len()
                    ))
                })
            };
            if !b.has_position {
                return Err(err("object record has no `position` field".into()));
            }
            let position = vec3("position", &b.position)?;
            let velocity = if b.has_velocity {
                Some(vec3("velocity", &b.velocity)?)
            } else {
                None
            };
            Record::Object {
                t,
                t_meas: b.t_meas.unwrap_or(t),
                id: &b.id,
                position,
                velocity,
            }
        }
        Kind::Event => {
            if !b.has_name {
                return Err(err("event record has no `name` field".into()));
            }
            Record::Event { t, name: &b.name }
        }
        _ => Record::Shield { t },
    })
}
