//! A small, bounds-checked decoder (and the matching encoder) of the OMG CDR (XCDR1) encoding ROS 2
//! uses for message payloads, covering the three message types the MCAP reader needs:
//! `sensor_msgs/msg/JointState`, `geometry_msgs/msg/PoseArray` and `std_msgs/msg/String`.
//!
//! Layout rules: a 4-byte encapsulation header (`00 00` big-endian CDR, `00 01` little-endian CDR,
//! then two option bytes), then the body; every primitive of size `k` is aligned to a multiple of
//! `k` counted from the start of the body; strings are a `u32` length that counts the terminating
//! NUL, the bytes and the NUL; sequences are a `u32` element count followed by the elements.
//! Every length is checked against the remaining bytes before anything is allocated, so a
//! malformed length is an error, never a panic or a large allocation.

use thiserror::Error;

/// Why a CDR payload could not be decoded. `at` is the byte position in the payload.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum CdrError {
    /// The payload is shorter than the 4-byte encapsulation header.
    #[error("CDR payload of {0} bytes is shorter than the 4-byte encapsulation header")]
    NoEncapsulation(usize),
    /// The encapsulation kind is not plain CDR (e.g. parameter lists or XCDR2).
    #[error(
        "CDR encapsulation 0x{0:04x} is not supported (expected 0x0000 CDR_BE or 0x0001 CDR_LE)"
    )]
    Encapsulation(u16),
    /// A field runs past the end of the payload.
    #[error("field `{field}` at byte {at} needs {need} bytes, only {have} remain (truncated)")]
    Truncated {
        /// Field being read.
        field: &'static str,
        /// Position in the payload.
        at: usize,
        /// Bytes needed.
        need: u64,
        /// Bytes remaining.
        have: usize,
    },
    /// A string does not end with NUL, has length 0 or is not UTF-8.
    #[error("field `{field}` at byte {at}: {problem}")]
    BadString {
        /// Field being read.
        field: &'static str,
        /// Position in the payload.
        at: usize,
        /// What is wrong.
        problem: &'static str,
    },
    /// A time stamp's nanoseconds are not below 10⁹ (`builtin_interfaces/Time.nanosec` counts
    /// the fraction of a second: a larger value would shift the stamp by up to 3.3 s).
    #[error("field `header.stamp.nanosec`: {0} is not below 1000000000")]
    BadNanosec(u32),
    /// More bytes follow the message than alignment padding explains.
    #[error("{0} unexpected bytes after the end of the message")]
    Trailing(usize),
}

/// A cursor over a CDR payload (after the encapsulation header).
pub struct CdrReader<'a> {
    body: &'a [u8],
    pos: usize,
    little: bool,
}

impl<'a> CdrReader<'a> {
    /// Read the encapsulation header of `data` and position the cursor at the body.
    pub fn new(data: &'a [u8]) -> Result<Self, CdrError> {
        let (head, body) = data
            .split_first_chunk::<4>()
            .ok_or(CdrError::NoEncapsulation(data.len()))?;
        let kind = u16::from_be_bytes([head[0], head[1]]);
        let little = match kind {
            0x0000 => false,
            0x0001 => true,
            k => return Err(CdrError::Encapsulation(k)),
        };
        Ok(Self {
            body,
            pos: 0,
            little,
        })
    }

    /// Bytes left after the cursor.
    pub fn remaining(&self) -> usize {
        self.body.len() - self.pos
    }

    /// The absolute payload position of the cursor (including the 4 header bytes).
    fn at(&self) -> usize {
        self.pos + 4
    }

    /// `n` bytes after the padding to a multiple of `align` (1, 2, 4 or 8: a power of two, so
    /// that the padding is `(−pos) mod align`, a mask rather than a division).
    #[inline]
    fn take(&mut self, field: &'static str, n: usize, align: usize) -> Result<&'a [u8], CdrError> {
        debug_assert!(align.is_power_of_two());
        let pad = self.pos.wrapping_neg() & (align - 1);
        let need = pad as u64 + n as u64;
        if need > self.remaining() as u64 {
            return Err(CdrError::Truncated {
                field,
                at: self.at(),
                need,
                have: self.remaining(),
            });
        }
        let start = self.pos + pad;
        self.pos = start + n;
        Ok(&self.body[start..start + n])
    }

    #[inline]
    fn array<const N: usize>(&mut self, field: &'static str) -> Result<[u8; N], CdrError> {
        let s = self.take(field, N, N)?;
        let mut a = [0u8; N];
        a.copy_from_slice(s);
        if self.little {
            Ok(a)
        } else {
            a.reverse();
            Ok(a)
        }
    }

    /// A `uint32`.
    pub fn u32(&mut self, field: &'static str) -> Result<u32, CdrError> {
        Ok(u32::from_le_bytes(self.array(field)?))
    }

    /// An `int32`.
    pub fn i32(&mut self, field: &'static str) -> Result<i32, CdrError> {
        Ok(i32::from_le_bytes(self.array(field)?))
    }

    /// A `float64`.
    pub fn f64(&mut self, field: &'static str) -> Result<f64, CdrError> {
        Ok(f64::from_le_bytes(self.array(field)?))
    }

    /// A `string`: returns the text without its NUL terminator.
    pub fn string(&mut self, field: &'static str) -> Result<&'a str, CdrError> {
        let at = self.at();
        let text = self.string_bytes(field)?;
        utf8(text, field, at)
    }

    /// A string's bytes without its NUL, checked as [`Self::string`] except for UTF-8 (for a
    /// caller that compares them with a string it holds before validating them: bytes equal to a
    /// `str`'s are valid UTF-8).
    pub fn string_bytes(&mut self, field: &'static str) -> Result<&'a [u8], CdrError> {
        let at = self.at();
        let len = self.u32(field)? as usize;
        if len == 0 {
            return Err(CdrError::BadString {
                field,
                at,
                problem: "string length 0 (a CDR string counts its NUL terminator)",
            });
        }
        let bytes = self.take(field, len, 1)?;
        let (text, nul) = bytes.split_at(len - 1);
        if nul != [0] {
            return Err(CdrError::BadString {
                field,
                at,
                problem: "string does not end with NUL",
            });
        }
        Ok(text)
    }

    /// A sequence length, checked against the remaining bytes given the smallest encoded element
    /// size `min_elem` (≥ 1), so that callers may reserve `count` elements.
    pub fn seq_len(&mut self, field: &'static str, min_elem: usize) -> Result<usize, CdrError> {
        let at = self.at();
        let count = self.u32(field)?;
        let need = u64::from(count) * min_elem as u64;
        if need > self.remaining() as u64 {
            return Err(CdrError::Truncated {
                field,
                at,
                need,
                have: self.remaining(),
            });
        }
        Ok(count as usize)
    }

    /// A `float64[]` appended to `out` (cleared first).
    pub fn f64_seq(&mut self, field: &'static str, out: &mut Vec<f64>) -> Result<(), CdrError> {
        out.clear();
        let n = self.seq_len(field, 8)?;
        if n == 0 {
            return Ok(());
        }
        // The 8-byte alignment padding may make the elements not fit even though `8n` bytes remain.
        let bytes = self.take(field, n * 8, 8)?;
        // One loop per byte order, each an exact-size extend (no capacity test per element).
        let word = |c: &[u8]| {
            let mut a = [0u8; 8];
            a.copy_from_slice(c);
            a
        };
        if self.little {
            out.extend(bytes.chunks_exact(8).map(|c| f64::from_le_bytes(word(c))));
        } else {
            out.extend(bytes.chunks_exact(8).map(|c| f64::from_be_bytes(word(c))));
        }
        Ok(())
    }

    /// Accept the end of the message: at most 7 bytes of padding may follow.
    pub fn finish(&self) -> Result<(), CdrError> {
        match self.remaining() {
            0..8 => Ok(()),
            n => Err(CdrError::Trailing(n)),
        }
    }
}

/// `std_msgs/msg/Header`: stamp (sec, nanosec) and frame id.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Stamp {
    /// Seconds.
    pub sec: i32,
    /// Nanoseconds.
    pub nanosec: u32,
}

impl Stamp {
    /// The stamp in nanoseconds (exact).
    pub fn nanos(&self) -> i128 {
        i128::from(self.sec) * 1_000_000_000 + i128::from(self.nanosec)
    }
}

fn header<'a>(r: &mut CdrReader<'a>) -> Result<(Stamp, &'a str), CdrError> {
    let sec = r.i32("header.stamp.sec")?;
    let nanosec = r.u32("header.stamp.nanosec")?;
    if nanosec >= 1_000_000_000 {
        return Err(CdrError::BadNanosec(nanosec));
    }
    let frame = r.string("header.frame_id")?;
    Ok((Stamp { sec, nanosec }, frame))
}

/// A decoded `sensor_msgs/msg/JointState`, in buffers reused across messages.
#[derive(Debug, Default, Clone)]
pub struct JointStateMsg {
    /// `header.stamp`.
    pub stamp: Stamp,
    /// `name` (joint names; may be empty).
    pub names: Vec<String>,
    /// `position` (rad).
    pub position: Vec<f64>,
    /// `velocity` (rad/s; may be empty).
    pub velocity: Vec<f64>,
    /// `effort` (ignored by the audit).
    pub effort: Vec<f64>,
    /// The encoded `name` sequence of the last message decoded (count, strings, padding), where
    /// it started in the body and the byte order: a message repeating those bytes at that place
    /// in that order has the same names (the decoding reads nothing else), so it is not decoded
    /// again. Empty while `names` does not hold a whole decoded sequence.
    names_raw: Vec<u8>,
    names_at: usize,
    names_little: bool,
    /// Incremented whenever `names` is decoded anew ([`Self::names_version`]).
    names_version: u64,
}

/// `text` as a `str`, or the error of a string `field` at byte `at` that is not UTF-8.
fn utf8<'a>(text: &'a [u8], field: &'static str, at: usize) -> Result<&'a str, CdrError> {
    std::str::from_utf8(text).map_err(|_| CdrError::BadString {
        field,
        at,
        problem: "string is not valid UTF-8",
    })
}

impl JointStateMsg {
    /// Decode `data` (a CDR `JointState`) into `self`, reusing its buffers.
    pub fn decode(&mut self, data: &[u8]) -> Result<(), CdrError> {
        let mut r = CdrReader::new(data)?;
        let (stamp, _) = header(&mut r)?;
        self.stamp = stamp;
        let start = r.pos;
        let end = start + self.names_raw.len();
        if !self.names_raw.is_empty()
            && start == self.names_at
            && r.little == self.names_little
            && r.body.get(start..end) == Some(&self.names_raw[..])
        {
            r.pos = end;
        } else {
            self.names_raw.clear();
            self.names_version = self.names_version.wrapping_add(1);
            self.decode_names(&mut r)?;
            self.names_raw.extend_from_slice(&r.body[start..r.pos]);
            (self.names_at, self.names_little) = (start, r.little);
        }
        r.f64_seq("position", &mut self.position)?;
        r.f64_seq("velocity", &mut self.velocity)?;
        r.f64_seq("effort", &mut self.effort)?;
        r.finish()
    }

    /// A number that changes whenever `names` may have changed (a decoding that read the `name`
    /// sequence anew): a caller that derived something from `names` at one version may keep it
    /// while the version stays the same.
    pub fn names_version(&self) -> u64 {
        self.names_version
    }

    /// The `name` sequence at the cursor into `names`.
    fn decode_names(&mut self, r: &mut CdrReader<'_>) -> Result<(), CdrError> {
        // Each string needs at least its 4-byte length and a NUL.
        let n = r.seq_len("name", 5)?;
        self.names.truncate(n);
        for i in 0..n {
            // The names repeat from message to message: bytes equal to the name held are
            // valid UTF-8 and need neither validation nor a copy.
            let at = r.at();
            let bytes = r.string_bytes("name")?;
            match self.names.get_mut(i) {
                Some(slot) if slot.as_bytes() == bytes => {}
                Some(slot) => {
                    let s = utf8(bytes, "name", at)?;
                    slot.clear();
                    slot.push_str(s);
                }
                None => self.names.push(utf8(bytes, "name", at)?.to_string()),
            }
        }
        Ok(())
    }
}

/// A decoded `geometry_msgs/msg/PoseArray`: the stamp and the pose positions (orientations are
/// read and ignored).
#[derive(Debug, Default, Clone)]
pub struct PoseArray {
    /// `header.stamp`.
    pub stamp: Stamp,
    /// `poses[i].position` (m).
    pub positions: Vec<[f64; 3]>,
}

impl PoseArray {
    /// Decode `data` (a CDR `PoseArray`) into `self`, reusing its buffers.
    pub fn decode(&mut self, data: &[u8]) -> Result<(), CdrError> {
        let mut r = CdrReader::new(data)?;
        let (stamp, _) = header(&mut r)?;
        self.stamp = stamp;
        self.positions.clear();
        let n = r.seq_len("poses", 56)?;
        self.positions.reserve(n);
        for _ in 0..n {
            let p = [
                r.f64("poses.position.x")?,
                r.f64("poses.position.y")?,
                r.f64("poses.position.z")?,
            ];
            for f in [
                "poses.orientation.x",
                "poses.orientation.y",
                "poses.orientation.z",
                "poses.orientation.w",
            ] {
                r.f64(f)?;
            }
            self.positions.push(p);
        }
        r.finish()
    }
}

/// A decoded `geometry_msgs/msg/PoseStamped` (orientation read and ignored).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PoseStamped {
    /// `header.stamp`.
    pub stamp: Stamp,
    /// `pose.position` (m).
    pub position: [f64; 3],
}

impl PoseStamped {
    /// Decode `data` (a CDR `PoseStamped`).
    pub fn decode(data: &[u8]) -> Result<Self, CdrError> {
        let mut r = CdrReader::new(data)?;
        let (stamp, _) = header(&mut r)?;
        let position = [
            r.f64("pose.position.x")?,
            r.f64("pose.position.y")?,
            r.f64("pose.position.z")?,
        ];
        for f in [
            "pose.orientation.x",
            "pose.orientation.y",
            "pose.orientation.z",
            "pose.orientation.w",
        ] {
            r.f64(f)?;
        }
        r.finish()?;
        Ok(Self { stamp, position })
    }
}

/// Decode a CDR `std_msgs/msg/String` into `out`.
pub fn decode_string(data: &[u8], out: &mut String) -> Result<(), CdrError> {
    let mut r = CdrReader::new(data)?;
    let s = r.string("data")?;
    out.clear();
    out.push_str(s);
    r.finish()
}

/// A little-endian CDR encoder (for writing MCAP logs and tests).
#[derive(Debug, Clone)]
pub struct CdrWriter {
    buf: Vec<u8>,
}

impl Default for CdrWriter {
    fn default() -> Self {
        Self::new()
    }
}

impl CdrWriter {
    /// A payload with the CDR_LE encapsulation header.
    pub fn new() -> Self {
        Self {
            buf: vec![0, 1, 0, 0],
        }
    }

    fn align(&mut self, k: usize) {
        while !(self.buf.len() - 4).is_multiple_of(k) {
            self.buf.push(0);
        }
    }

    /// A `uint32`.
    pub fn u32(&mut self, v: u32) -> &mut Self {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
        self
    }

    /// An `int32`.
    pub fn i32(&mut self, v: i32) -> &mut Self {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
        self
    }

    /// A `float64`.
    pub fn f64(&mut self, v: f64) -> &mut Self {
        self.align(8);
        self.buf.extend_from_slice(&v.to_le_bytes());
        self
    }

    /// A `string`.
    pub fn string(&mut self, s: &str) -> &mut Self {
        self.u32(s.len() as u32 + 1);
        self.buf.extend_from_slice(s.as_bytes());
        self.buf.push(0);
        self
    }

    /// A `float64[]`.
    pub fn f64_seq(&mut self, v: &[f64]) -> &mut Self {
        self.u32(v.len() as u32);
        for x in v {
            self.f64(*x);
        }
        self
    }

    /// A `std_msgs/msg/Header`.
    pub fn header(&mut self, stamp: Stamp, frame_id: &str) -> &mut Self {
        self.i32(stamp.sec).u32(stamp.nanosec).string(frame_id)
    }

    /// The encoded bytes.
    pub fn into_bytes(self) -> Vec<u8> {
        self.buf
    }

    /// A `sensor_msgs/msg/JointState`.
    pub fn joint_state(
        stamp: Stamp,
        names: &[&str],
        position: &[f64],
        velocity: &[f64],
        effort: &[f64],
    ) -> Vec<u8> {
        let mut w = Self::new();
        w.header(stamp, "").u32(names.len() as u32);
        for n in names {
            w.string(n);
        }
        w.f64_seq(position).f64_seq(velocity).f64_seq(effort);
        w.into_bytes()
    }

    /// A `geometry_msgs/msg/PoseArray` with identity orientations.
    pub fn pose_array(stamp: Stamp, frame_id: &str, positions: &[[f64; 3]]) -> Vec<u8> {
        let mut w = Self::new();
        w.header(stamp, frame_id).u32(positions.len() as u32);
        for p in positions {
            w.f64(p[0]).f64(p[1]).f64(p[2]);
            w.f64(0.0).f64(0.0).f64(0.0).f64(1.0);
        }
        w.into_bytes()
    }

    /// A `geometry_msgs/msg/PoseStamped` (identity orientation).
    pub fn pose_stamped(stamp: Stamp, frame_id: &str, position: [f64; 3]) -> Vec<u8> {
        let mut w = Self::new();
        w.header(stamp, frame_id);
        w.f64(position[0]).f64(position[1]).f64(position[2]);
        w.f64(0.0).f64(0.0).f64(0.0).f64(1.0);
        w.into_bytes()
    }

    /// A `std_msgs/msg/String`.
    pub fn string_msg(s: &str) -> Vec<u8> {
        let mut w = Self::new();
        w.string(s);
        w.into_bytes()
    }
}

impl Stamp {
    /// A stamp from nanoseconds since the clock's epoch (`None` if out of the `int32` range).
    pub fn from_nanos(ns: i128) -> Option<Self> {
        let sec = i32::try_from(ns.div_euclid(1_000_000_000)).ok()?;
        let nanosec = ns.rem_euclid(1_000_000_000) as u32;
        Some(Self { sec, nanosec })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A stamp whose nanoseconds are not below 10⁹ is refused (it would shift the time by up to
    /// 3.3 s and make a stale measurement look fresh); 10⁹ − 1 is read exactly.
    #[test]
    fn nanoseconds_of_a_second_or_more_are_refused() {
        let mut js = JointStateMsg::default();
        for (nanosec, ok) in [
            (999_999_999u32, true),
            (1_000_000_000, false),
            (u32::MAX, false),
        ] {
            let st = Stamp { sec: 5, nanosec };
            let data = CdrWriter::joint_state(st, &["j1"], &[0.0], &[], &[]);
            let r = js.decode(&data);
            assert_eq!(r.is_ok(), ok, "{nanosec}: {r:?}");
            if ok {
                assert_eq!(js.stamp.nanos(), 5_999_999_999);
            } else {
                assert_eq!(r.unwrap_err(), CdrError::BadNanosec(nanosec));
            }
        }
    }

    /// `data` fails to decode because its name count does not fit the message (as the names
    /// decoded anew read it).
    fn names_do_not_fit(js: &mut JointStateMsg, data: &[u8]) {
        let r = js.decode(data);
        assert!(
            matches!(r, Err(CdrError::Truncated { field: "name", .. })),
            "{r:?}"
        );
    }

    /// A big-endian `JointState` (encapsulation `00 00`) decodes to the values of the same
    /// message little-endian: the byte order of every field, and the padding before the
    /// `float64` sequences (1 to 7 bytes, with frame ids of every length mod 8).
    #[test]
    fn a_big_endian_joint_state_reads_as_the_little_endian_one() {
        fn be(frame: &str, names: &[&str], pos: &[f64], vel: &[f64]) -> Vec<u8> {
            let mut body: Vec<u8> = Vec::new();
            let align = |b: &mut Vec<u8>, k: usize| {
                while !b.len().is_multiple_of(k) {
                    b.push(0);
                }
            };
            let u32_ = |b: &mut Vec<u8>, v: u32| {
                align(b, 4);
                b.extend_from_slice(&v.to_be_bytes());
            };
            let string = |b: &mut Vec<u8>, t: &str| {
                u32_(b, t.len() as u32 + 1);
                b.extend_from_slice(t.as_bytes());
                b.push(0);
            };
            u32_(&mut body, 7);
            u32_(&mut body, 250_000_000);
            string(&mut body, frame);
            u32_(&mut body, names.len() as u32);
            for n in names {
                string(&mut body, n);
            }
            for seq in [pos, vel, &[][..]] {
                u32_(&mut body, seq.len() as u32);
                for x in seq {
                    align(&mut body, 8);
                    body.extend_from_slice(&x.to_be_bytes());
                }
            }
            let mut out = vec![0, 0, 0, 0];
            out.extend_from_slice(&body);
            out
        }
        let names = ["j1", "joint_2", "j3"];
        let (pos, vel) = ([0.5, -1.25, 3.0e-7], [1.0, -0.0, 2.5]);
        for frame in ["", "a", "ab", "abc", "abcd", "abcde", "abcdef", "abcdefg"] {
            let st = Stamp {
                sec: 7,
                nanosec: 250_000_000,
            };
            let mut w = CdrWriter::new();
            w.header(st, frame).u32(3);
            for n in names {
                w.string(n);
            }
            w.f64_seq(&pos).f64_seq(&vel).f64_seq(&[]);
            let (mut a, mut b) = (JointStateMsg::default(), JointStateMsg::default());
            a.decode(&w.into_bytes()).unwrap();
            b.decode(&be(frame, &names, &pos, &vel)).unwrap();
            assert_eq!((a.stamp, &a.names), (st, &b.names), "{frame:?}");
            assert_eq!(b.stamp, st);
            assert_eq!(a.position, pos);
            assert_eq!(a.velocity, vel);
            for (x, y) in a
                .position
                .iter()
                .chain(&a.velocity)
                .zip(b.position.iter().chain(&b.velocity))
            {
                assert_eq!(x.to_bits(), y.to_bits(), "{frame:?}");
            }
            assert!(b.effort.is_empty());
        }
    }

    /// Names repeated from the message before are taken without decoding them again; names
    /// that change, the same name bytes at another place (another frame id's length) or in the
    /// other byte order, and a message after one whose names failed, are decoded again.
    #[test]
    fn joint_names_are_reused_only_where_the_bytes_mean_the_same() {
        let st = Stamp { sec: 1, nanosec: 0 };
        let mut js = JointStateMsg::default();
        let ab = CdrWriter::joint_state(st, &["a", "b"], &[1.0, 2.0], &[], &[]);
        js.decode(&ab).unwrap();
        assert_eq!(js.names, ["a", "b"]);
        js.decode(&ab).unwrap();
        assert_eq!(js.names, ["a", "b"]);
        assert_eq!(js.position, [1.0, 2.0]);
        let cd = CdrWriter::joint_state(st, &["c", "d"], &[3.0, 4.0], &[], &[]);
        js.decode(&cd).unwrap();
        assert_eq!(js.names, ["c", "d"]);
        // The same name bytes after a longer frame id: decoded where they stand.
        let mut w = CdrWriter::new();
        w.header(st, "base").u32(2).string("c").string("e");
        w.f64_seq(&[5.0, 6.0]).f64_seq(&[]).f64_seq(&[]);
        js.decode(&w.into_bytes()).unwrap();
        assert_eq!(js.names, ["c", "e"]);
        // The bytes of the last names in a big-endian message (everything else big-endian):
        // their count reads as 2²⁵, which does not fit.
        js.decode(&ab).unwrap();
        let names = &ab[4 + 16..4 + 34];
        let mut be = vec![0, 0, 0, 0];
        be.extend_from_slice(&1i32.to_be_bytes());
        be.extend_from_slice(&0u32.to_be_bytes());
        be.extend_from_slice(&1u32.to_be_bytes());
        be.extend_from_slice(&[0, 0, 0, 0]);
        be.extend_from_slice(names);
        be.extend_from_slice(&[0, 0]);
        be.extend_from_slice(&2u32.to_be_bytes());
        be.extend_from_slice(&[0, 0, 0, 0]);
        be.extend_from_slice(&1.0f64.to_be_bytes());
        be.extend_from_slice(&2.0f64.to_be_bytes());
        be.extend_from_slice(&0u32.to_be_bytes());
        be.extend_from_slice(&0u32.to_be_bytes());
        names_do_not_fit(&mut js, &be);
        // The same bytes one further on (a one-character frame id: the names start at body
        // byte 14, not 13): the count is read after two bytes of padding, from the middle of
        // the bytes (2⁹, which does not fit).
        js.decode(&ab).unwrap();
        let raw = &ab[4 + 13..4 + 34];
        assert_eq!(raw[..3], [0, 0, 0]);
        let mut w = CdrWriter::new();
        w.header(st, "x");
        let mut moved = w.into_bytes();
        assert_eq!(moved.len(), 4 + 14);
        moved.extend_from_slice(raw);
        // Body byte 35: one byte of padding, then the position count and values (40 ≡ 0 mod
        // 8), velocity and effort empty.
        moved.push(0);
        moved.extend_from_slice(&2u32.to_le_bytes());
        moved.extend_from_slice(&1.0f64.to_le_bytes());
        moved.extend_from_slice(&2.0f64.to_le_bytes());
        moved.extend_from_slice(&[0; 8]);
        names_do_not_fit(&mut js, &moved);
        // A message whose names fail leaves nothing to reuse: its first name was written
        // over the held ones before the second failed.
        js.decode(&cd).unwrap();
        let mut bad = ab.clone();
        let nul = bad.windows(2).position(|w| w == b"b\0").unwrap() + 1;
        bad[nul] = b'x';
        assert!(js.decode(&bad).is_err());
        js.decode(&cd).unwrap();
        assert_eq!(js.names, ["c", "d"]);
    }
}
