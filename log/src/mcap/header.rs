//! The pacs header of an MCAP log: parsed from JSON text or a side file, or found in the `pacs`
//! metadata record (through the summary's metadata index, or in the linear pass).

use super::fields::{FieldError, Fields};
use super::{MAGIC, METADATA_KEY, METADATA_NAME, RECORD_LIMIT};
use crate::error::{HeaderError, Location, LogError};
use crate::format::Header;
use mcap::records::op;
use std::io::{Read, Seek, SeekFrom};

/// Parse a pacs header from JSON text (the JSON Lines header object); the error names the problem.
pub fn parse_header_json(text: &str) -> Result<Header, HeaderError> {
    let value: serde_json::Value =
        serde_json::from_str(text).map_err(|e| HeaderError::Json(e.to_string()))?;
    header_from_value(value)
}

/// A header from a parsed JSON value: [`Header::from_value`], the one header validation.
pub fn header_from_value(value: serde_json::Value) -> Result<Header, HeaderError> {
    Header::from_value(value)
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
    let mut h = header_from_value(value)
        .map_err(|p| LogError::input(&name, Location::File, p.to_string()))?;
    // A {urdf, side} robot's relative paths are relative to this header file.
    h.robot.rebase(&crate::format::dir_of(path));
    Ok(h)
}

/// The `pacs` header a metadata record holds, or why it holds none.
#[derive(Debug, thiserror::Error)]
pub(super) enum MetadataHeaderError {
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

/// Look for the `pacs` metadata record through the summary's metadata index. A missing or
/// unreadable summary gives `None` (the linear pass then looks for the record, and reports a
/// damaged file); a `pacs` index entry pointing at an invalid record is an error.
pub(super) fn header_from_summary<R: Read + Seek>(
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
pub(super) fn parse_metadata(
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
