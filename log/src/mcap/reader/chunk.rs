//! A chunk record read whole: its header checked, its records decompressed in one call (per zstd
//! frame; writers put one in a chunk) into a buffer kept between chunks, the uncompressed CRC
//! checked before any record is handed over, and the records inside it walked with every length
//! checked against the chunk.
//!
//! `mcap`'s linear reader can decompress a chunk as a stream, one record's bytes at a time; that
//! costs a call into the decoder per record (about a fifth of the decoding of a ROS 2
//! recording's small messages, and a CRC that is only known to be wrong after the chunk's
//! messages were used). Here the reader is asked for whole chunk records (`emit_chunks`) and this
//! module does the rest. A chunk and its uncompressed records are each limited to
//! [`RECORD_LIMIT`] bytes.

use crate::mcap::RECORD_LIMIT;
use crate::mcap::fields::{FieldError, Fields};
use std::io::Read;

/// The first bytes of a zstd frame (RFC 8878).
const ZSTD_MAGIC: [u8; 4] = [0x28, 0xb5, 0x2f, 0xfd];

/// Why a chunk cannot be read.
#[derive(Debug, thiserror::Error)]
pub(super) enum ChunkError {
    #[error("invalid MCAP chunk: {0}")]
    Field(#[from] FieldError),
    #[error(
        "invalid MCAP chunk: {size} bytes of records uncompressed, more than the limit of {RECORD_LIMIT}"
    )]
    TooLarge { size: u64 },
    #[error("unsupported MCAP chunk compression `{0}` (supported: none, `zstd`, `lz4`)")]
    Compression(String),
    #[error("invalid MCAP chunk: {compression} data cannot be decompressed: {source}")]
    Decompress {
        compression: &'static str,
        source: std::io::Error,
    },
    #[error(
        "invalid MCAP chunk: the header declares {declared} bytes of records uncompressed, the data holds {found}"
    )]
    Size { declared: u64, found: u64 },
    #[error(
        "invalid MCAP chunk: CRC of the records 0x{calculated:08x}, the header says 0x{saved:08x} (damaged file)"
    )]
    Crc { saved: u32, calculated: u32 },
    #[error(
        "invalid MCAP chunk: a record inside it at byte {at} of its records runs past the chunk's end ({left} bytes left, the record needs {need})"
    )]
    RecordPastEnd { at: usize, left: usize, need: u64 },
    #[error(
        "invalid MCAP chunk: zstd frames follow its declared {declared} bytes of records (the header does not describe the chunk)"
    )]
    FramesBeyondSize { declared: u64 },
}

/// The records of the chunk being read, and the decoders kept between chunks.
#[derive(Default)]
pub(super) struct Chunk {
    /// The chunk's records, uncompressed.
    records: Vec<u8>,
    /// Where the next record starts in `records`.
    at: usize,
    zstd: Option<zstd::bulk::Decompressor<'static>>,
    /// A later zstd frame's output, before it joins `records`.
    spare: Vec<u8>,
}

impl Chunk {
    /// Read the body of a chunk record (everything after its opcode and length): the records
    /// it holds are then handed over by [`Chunk::next_record`]. On error no record of the chunk
    /// is handed over.
    pub(super) fn open(&mut self, body: &[u8]) -> Result<(), ChunkError> {
        self.at = 0;
        let r = self.fill(body);
        if r.is_err() {
            self.records.clear();
        }
        r
    }

    /// [`Self::open`] but for emptying the records on error.
    fn fill(&mut self, body: &[u8]) -> Result<(), ChunkError> {
        self.records.clear();
        let mut f = Fields { b: body };
        f.u64("message start time")?;
        f.u64("message end time")?;
        let size = f.u64("uncompressed size")?;
        let crc = f.u32("uncompressed crc")?;
        let compression = f.str("compression")?;
        let n = f.u64("records")?;
        // Bytes after the records are padding (`mcap`'s reader skips them too).
        let data = f.take(n, "records")?;
        if size > RECORD_LIMIT as u64 {
            return Err(ChunkError::TooLarge { size });
        }
        let size_usize = size as usize;
        match compression {
            "" => self.records.extend_from_slice(data),
            "zstd" => self.zstd_frames(data, size_usize)?,
            "lz4" => {
                let dec = lz4::Decoder::new(data).map_err(|e| ChunkError::Decompress {
                    compression: "lz4",
                    source: e,
                })?;
                self.records.reserve(size_usize);
                dec.take(size + 1)
                    .read_to_end(&mut self.records)
                    .map_err(|e| ChunkError::Decompress {
                        compression: "lz4",
                        source: e,
                    })?;
            }
            other => return Err(ChunkError::Compression(other.to_string())),
        }
        let found = self.records.len() as u64;
        if found != size {
            return Err(ChunkError::Size {
                declared: size,
                found,
            });
        }
        if crc != 0 {
            let calculated = crc32fast::hash(&self.records);
            if calculated != crc {
                return Err(ChunkError::Crc {
                    saved: crc,
                    calculated,
                });
            }
        }
        Ok(())
    }

    /// The zstd frames of `data` decompressed into the records, each in one call, until `size`
    /// bytes are out; bytes after that are padding (as `mcap`'s streaming reader treats bytes a
    /// compressor leaves after its last frame), unless they start another zstd frame (records the
    /// declared size would leave unread: an error). Output beyond `size` or a frame that does not
    /// decode is an error. The buffers are reserved, not filled, before decoding (a chunk that
    /// declares a large size but holds little data costs no writes).
    fn zstd_frames(&mut self, mut data: &[u8], size: usize) -> Result<(), ChunkError> {
        let bad = |e: std::io::Error| ChunkError::Decompress {
            compression: "zstd",
            source: e,
        };
        let z = match &mut self.zstd {
            Some(z) => z,
            None => self
                .zstd
                .insert(zstd::bulk::Decompressor::new().map_err(bad)?),
        };
        // Room for one byte more than declared, to see a frame that holds more.
        self.records.reserve(size + 1);
        let mut first = true;
        while !data.is_empty() && (first || self.records.len() < size) {
            let frame = zstd::zstd_safe::find_frame_compressed_size(data)
                .map_err(|c| bad(std::io::Error::other(zstd::zstd_safe::get_error_name(c))))?;
            let frame = frame.min(data.len());
            if first {
                // Written from the buffer's start into its capacity (≥ size + 1).
                z.decompress_to_buffer(&data[..frame], &mut self.records)
                    .map_err(bad)?;
                first = false;
            } else {
                self.spare.clear();
                self.spare.reserve(size + 1 - self.records.len());
                z.decompress_to_buffer(&data[..frame], &mut self.spare)
                    .map_err(bad)?;
                self.records.extend_from_slice(&self.spare);
            }
            data = &data[frame..];
        }
        if self.records.len() == size && data.starts_with(&ZSTD_MAGIC) {
            return Err(ChunkError::FramesBeyondSize {
                declared: size as u64,
            });
        }
        Ok(())
    }

    /// The next record of the chunk (opcode and body), `None` after the last.
    pub(super) fn next_record(&mut self) -> Result<Option<(u8, &[u8])>, ChunkError> {
        let at = self.at;
        let left = self.records.len() - at;
        if left == 0 {
            return Ok(None);
        }
        let rest = &self.records[at..];
        if left < 9 {
            self.at = self.records.len();
            return Err(ChunkError::RecordPastEnd { at, left, need: 9 });
        }
        let op = rest[0];
        let mut len = [0u8; 8];
        len.copy_from_slice(&rest[1..9]);
        let len = u64::from_le_bytes(len);
        if len > (left - 9) as u64 {
            self.at = self.records.len();
            return Err(ChunkError::RecordPastEnd {
                at,
                left,
                need: len.saturating_add(9),
            });
        }
        let end = 9 + len as usize;
        self.at = at + end;
        Ok(Some((op, &rest[9..end])))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    /// The body of a chunk record holding `records` (already framed) compressed with
    /// `compression`; `crc` computed unless `None`.
    fn chunk_body(records: &[u8], compression: &str, crc: Option<u32>) -> Vec<u8> {
        let data = match compression {
            "" => records.to_vec(),
            "zstd" => zstd::bulk::compress(records, 3).unwrap(),
            "lz4" => {
                let mut e = lz4::EncoderBuilder::new().build(Vec::new()).unwrap();
                e.write_all(records).unwrap();
                let (v, r) = e.finish();
                r.unwrap();
                v
            }
            other => other.as_bytes().to_vec(),
        };
        let mut b = Vec::new();
        b.extend_from_slice(&7u64.to_le_bytes());
        b.extend_from_slice(&9u64.to_le_bytes());
        b.extend_from_slice(&(records.len() as u64).to_le_bytes());
        let crc = crc.unwrap_or_else(|| crc32fast::hash(records));
        b.extend_from_slice(&crc.to_le_bytes());
        b.extend_from_slice(&(compression.len() as u32).to_le_bytes());
        b.extend_from_slice(compression.as_bytes());
        b.extend_from_slice(&(data.len() as u64).to_le_bytes());
        b.extend_from_slice(&data);
        b
    }

    fn framed(records: &[(u8, Vec<u8>)]) -> Vec<u8> {
        let mut b = Vec::new();
        for (op, body) in records {
            b.push(*op);
            b.extend_from_slice(&(body.len() as u64).to_le_bytes());
            b.extend_from_slice(body);
        }
        b
    }

    fn read_all(c: &mut Chunk) -> Result<Vec<(u8, Vec<u8>)>, ChunkError> {
        let mut v = Vec::new();
        while let Some((op, body)) = c.next_record()? {
            v.push((op, body.to_vec()));
        }
        Ok(v)
    }

    /// Random lists of records (empty ones and up to 3 KB each) come back exactly, in order,
    /// through each compression, with one `Chunk` reused for every chunk (its buffer then holds
    /// more capacity than a smaller chunk needs).
    #[test]
    fn records_come_back_through_every_compression() {
        let mut rnd = pacs_testkit::xorshift(41);
        let mut c = Chunk::default();
        for case in 0..300 {
            let n = (rnd() % 12) as usize;
            let records: Vec<(u8, Vec<u8>)> = (0..n)
                .map(|_| {
                    let len = match rnd() % 4 {
                        0 => 0,
                        1 => (rnd() % 16) as usize,
                        _ => (rnd() % 3000) as usize,
                    };
                    let body = (0..len).map(|_| (rnd() % 7) as u8).collect();
                    ((rnd() % 16) as u8, body)
                })
                .collect();
            let compression = ["", "zstd", "lz4"][case % 3];
            c.open(&chunk_body(&framed(&records), compression, None))
                .unwrap();
            assert_eq!(read_all(&mut c).unwrap(), records, "case {case}");
        }
    }

    #[test]
    fn damaged_chunks_are_refused_before_any_record() {
        let records = framed(&[(5, vec![1, 2, 3]), (6, vec![4; 40])]);
        let mut c = Chunk::default();
        for compression in ["", "zstd", "lz4"] {
            // A wrong CRC.
            let body = chunk_body(&records, compression, Some(0xdead_beef));
            let e = c.open(&body).unwrap_err();
            assert!(
                matches!(
                    e,
                    ChunkError::Crc {
                        saved: 0xdead_beef,
                        ..
                    }
                ),
                "{e}"
            );
            assert!(c.next_record().unwrap().is_none(), "nothing handed over");
            // CRC 0: not checked.
            c.open(&chunk_body(&records, compression, Some(0))).unwrap();
            assert_eq!(read_all(&mut c).unwrap().len(), 2);
            // The declared size one more or one less than the data.
            for delta in [1i64, -1] {
                let mut body = chunk_body(&records, compression, None);
                let size = records.len() as i64 + delta;
                body[16..24].copy_from_slice(&(size as u64).to_le_bytes());
                let e = c.open(&body).unwrap_err();
                assert!(
                    matches!(e, ChunkError::Size { .. } | ChunkError::Decompress { .. }),
                    "{compression:?} {delta}: {e}"
                );
                assert!(c.next_record().unwrap().is_none());
            }
            // A size beyond the limit is refused before anything is allocated.
            let mut body = chunk_body(&records, compression, None);
            body[16..24].copy_from_slice(&(RECORD_LIMIT as u64 + 1).to_le_bytes());
            assert!(matches!(c.open(&body), Err(ChunkError::TooLarge { .. })));
        }
        // Records data shorter than its declared length.
        let mut body = chunk_body(&records, "", None);
        body.pop();
        assert!(matches!(c.open(&body), Err(ChunkError::Field(_))));
        // An unknown compression.
        let e = c.open(&chunk_body(&records, "brotli", None)).unwrap_err();
        assert_eq!(
            e.to_string(),
            "unsupported MCAP chunk compression `brotli` (supported: none, `zstd`, `lz4`)"
        );
        // Bytes after the records are padding.
        let mut body = chunk_body(&records, "zstd", None);
        body.extend_from_slice(&[0; 5]);
        c.open(&body).unwrap();
        assert_eq!(read_all(&mut c).unwrap().len(), 2);
    }

    /// zstd data of several frames is read frame by frame; bytes after the declared size's worth
    /// of frames are padding (as a compressor may leave them, and `mcap`'s streaming reader
    /// skipped them); frames holding more than the declared size are refused.
    #[test]
    fn zstd_frames_and_padding() {
        let records = framed(&[(5, vec![1, 2, 3]), (6, vec![4; 400]), (7, vec![9; 50])]);
        let cut = 12 + 3 + 9 + 200;
        let mut two = zstd::bulk::compress(&records[..cut], 1).unwrap();
        two.extend(zstd::bulk::compress(&records[cut..], 1).unwrap());
        let with_header = |data: &[u8], size: usize| {
            let mut b = chunk_body(&[], "", Some(0));
            b.truncate(28);
            b[16..24].copy_from_slice(&(size as u64).to_le_bytes());
            b.extend_from_slice(&4u32.to_le_bytes());
            b.extend_from_slice(b"zstd");
            b.extend_from_slice(&(data.len() as u64).to_le_bytes());
            b.extend_from_slice(data);
            b
        };
        let mut c = Chunk::default();
        c.open(&with_header(&two, records.len())).unwrap();
        assert_eq!(read_all(&mut c).unwrap().len(), 3);
        let mut padded = two.clone();
        padded.extend_from_slice(&[0xAB; 7]);
        c.open(&with_header(&padded, records.len())).unwrap();
        assert_eq!(read_all(&mut c).unwrap().len(), 3);
        // Declared exactly the first frame's worth: the second frame would go unread.
        let e = c.open(&with_header(&two, cut)).unwrap_err();
        assert!(matches!(e, ChunkError::FramesBeyondSize { .. }), "{e}");
        // Declared less than the first frame holds.
        let e = c.open(&with_header(&two, cut - 1)).unwrap_err();
        assert!(
            matches!(e, ChunkError::Decompress { .. } | ChunkError::Size { .. }),
            "{e}"
        );
        assert!(c.next_record().unwrap().is_none());
    }

    /// A record inside a chunk whose length runs past the chunk's records, or a record header
    /// cut short, is an error naming where it starts; the records before it are handed over.
    #[test]
    fn records_running_past_the_chunk_are_refused() {
        let mut records = framed(&[(5, vec![1, 2, 3])]);
        let at = records.len();
        records.push(6);
        records.extend_from_slice(&100u64.to_le_bytes());
        records.extend_from_slice(&[0; 99]);
        let mut c = Chunk::default();
        for compression in ["", "zstd", "lz4"] {
            c.open(&chunk_body(&records, compression, None)).unwrap();
            assert_eq!(c.next_record().unwrap(), Some((5, &[1u8, 2, 3][..])));
            let e = c.next_record().unwrap_err();
            assert!(
                matches!(e, ChunkError::RecordPastEnd { at: a, left: 108, need: 109 } if a == at),
                "{e}"
            );
            assert!(c.next_record().unwrap().is_none(), "the chunk is left");
            // A header of fewer than 9 bytes.
            let cut = &records[..at + 5];
            c.open(&chunk_body(cut, compression, None)).unwrap();
            c.next_record().unwrap();
            assert!(matches!(
                c.next_record(),
                Err(ChunkError::RecordPastEnd {
                    left: 5,
                    need: 9,
                    ..
                })
            ));
        }
    }
}
