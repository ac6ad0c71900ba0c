//! A check of the top-level records and of uncompressed chunks before the linear pass: every
//! record ends within the file, a chunk's records within the chunk, and every record inside an
//! uncompressed chunk within the chunk. The `mcap` crate (0.26.0, `sans_io/linear_reader.rs`)
//! streams a chunk's records and subtracts a record's length from the chunk's remaining bytes
//! without checking it: a record running past the end of an uncompressed chunk underflows that
//! count (a panic in debug builds; in release the bytes after the chunk are then parsed as
//! records of the chunk), also when the chunk itself is cut short by the end of the file (a
//! fuzzer's 356-byte input, `audit/tests/data/mcap_fuzz_chunk_past_end.mcap`). This walk refuses
//! such a file first, naming the offset. It reads only the records' 9-byte headers and skips their
//! bodies (through the buffered input), and stops at the footer or wherever the file stops making
//! sense otherwise (the linear pass then reports that).
//!
//! The reader takes whole chunk records from the linear pass and walks their records itself
//! (`reader/chunk.rs`, every length checked against the chunk); this walk also names a record cut
//! short by the end of the file before any record is read.

use crate::error::{Location, LogError};
use std::io::{Read, Seek, SeekFrom};

const CHUNK: u8 = 0x06;
const FOOTER: u8 = 0x02;

/// Skip `n` bytes of `r` (false at the end of the input).
fn skip<R: Read>(r: &mut R, n: u64) -> bool {
    matches!(std::io::copy(&mut r.by_ref().take(n), &mut std::io::sink()), Ok(k) if k == n)
}

fn read_u64<R: Read>(r: &mut R) -> Option<u64> {
    let mut b = [0u8; 8];
    r.read_exact(&mut b).ok()?;
    Some(u64::from_le_bytes(b))
}

fn read_u32<R: Read>(r: &mut R) -> Option<u32> {
    let mut b = [0u8; 4];
    r.read_exact(&mut b).ok()?;
    Some(u32::from_le_bytes(b))
}

/// Walk the top-level records from just after the magic; an uncompressed chunk whose records
/// overrun it is an error naming the offset of the offending record. Leaves `r` anywhere (the
/// caller seeks back).
pub(super) fn check_chunk_records<R: Read + Seek>(
    file: &str,
    r: &mut R,
    size: u64,
) -> Result<(), LogError> {
    // Not an MCAP file (the linear pass names the bad magic): nothing to walk.
    let mut magic = [0u8; 8];
    if r.seek(SeekFrom::Start(0)).is_err()
        || r.read_exact(&mut magic).is_err()
        || magic[..] != *super::MAGIC
    {
        return Ok(());
    }
    let mut pos = 8u64;
    while pos + 9 <= size {
        let mut op = [0u8; 1];
        if r.read_exact(&mut op).is_err() {
            return Ok(());
        }
        let Some(len) = read_u64(r) else {
            return Ok(());
        };
        let body = pos + 9;
        if op[0] == FOOTER {
            return Ok(());
        }
        let left = size.saturating_sub(body);
        if len > left {
            return Err(LogError::input(
                file,
                Location::Offset(pos),
                format!(
                    "truncated file: the record at offset {pos} (opcode 0x{:02x}) declares {len} bytes, the file holds {left} after its header",
                    op[0]
                ),
            ));
        }
        if op[0] == CHUNK {
            // start time, end time, uncompressed size (u64 each), uncompressed crc (u32),
            // compression (u32 length + bytes), records length (u64), records.
            let mut used = 0u64;
            let ok = skip(r, 28);
            used += 28;
            let Some(clen) = ok.then(|| read_u32(r)).flatten() else {
                return Ok(());
            };
            used += 4;
            let mut compression = vec![0u8; (clen as usize).min(64)];
            if clen as usize > compression.len() || r.read_exact(&mut compression).is_err() {
                return Ok(());
            }
            used += u64::from(clen);
            let Some(records) = read_u64(r) else {
                return Ok(());
            };
            used += 8;
            if used > len || records > len - used {
                return Err(LogError::input(
                    file,
                    Location::Offset(pos),
                    format!(
                        "invalid MCAP: the chunk at offset {pos} declares {records} bytes of records, {} fit in its {len} bytes",
                        len.saturating_sub(used)
                    ),
                ));
            }
            if compression.is_empty() {
                let start = body + used;
                let mut at = 0u64;
                while at < records {
                    let left = records - at;
                    let header_fits = left >= 9;
                    let inner_len = if header_fits {
                        let mut h = [0u8; 9];
                        if r.read_exact(&mut h).is_err() {
                            return Ok(());
                        }
                        u64::from_le_bytes(h[1..].try_into().expect("8 bytes"))
                    } else {
                        u64::MAX
                    };
                    if !header_fits || inner_len > left - 9 {
                        return Err(LogError::input(
                            file,
                            Location::Offset(start + at),
                            format!(
                                "invalid MCAP: a record inside the uncompressed chunk at offset {pos} runs past the chunk's end ({} bytes left in the chunk, the record needs {})",
                                left,
                                if header_fits {
                                    format!("{}", 9u128 + u128::from(inner_len))
                                } else {
                                    "a 9-byte header".into()
                                }
                            ),
                        ));
                    }
                    if !skip(r, inner_len) {
                        return Ok(());
                    }
                    at += 9 + inner_len;
                }
                used += records;
            }
            if !skip(r, len - used) {
                return Ok(());
            }
        } else if !skip(r, len) {
            return Ok(());
        }
        pos = body + len;
    }
    Ok(())
}
