//! The fast scanner of JSON Lines records.
//!
//! Most lines of a log are robot and shield records: one flat JSON object of numbers, arrays of
//! numbers and plain strings. This scanner reads exactly such lines, straight into the reader's
//! buffers, through the same field logic as the serde_json path ([`LineBuffers::take`]). It
//! accepts a subset of JSON and gives up ([`Bail`]) on anything else — a string with an escape, a
//! control character or a byte outside ASCII, a number out of range, nesting deeper than [`MAX_DEPTH`], any syntax
//! error — and the line is then parsed again by serde_json, which decides (with its error
//! message). So a line the scanner takes is one serde_json also takes, with the same values:
//!
//! - the number grammar is JSON's (`-?(0|[1-9][0-9]*)(\.[0-9]+)?([eE][+-]?[0-9]+)?`), checked
//!   here before the standard library converts the text (correctly rounded, as serde_json with
//!   `float_roundtrip`, which the workspace enables; `-0` is `-0.0` in both);
//! - whitespace is JSON's (space, tab, line feed, carriage return), before and after any token;
//! - nothing but whitespace may follow the object.
//!
//! `fast_path_agrees` (tests and the `jsonl` fuzz target) checks the claim line by line.

use super::{Field, LineBuffers, Values};

/// Nesting depth up to which skipped values (unknown fields) are scanned here; deeper values
/// are left to serde_json.
const MAX_DEPTH: usize = 32;

/// Significant decimal digits a mantissa keeps in a `u64` (10¹⁹ − 1 < 2⁶⁴).
const MAX_SIG_DIGITS: u32 = 19;

/// `10^k` for `k = 0..=22`: every one is a double exactly (`5^22 < 2⁵³`).
const POW10_EXACT: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// The significant digits of a number as they are scanned: the first [`MAX_SIG_DIGITS`] (leading
/// zeros excluded by the caller) in `mant`; `inexact` once one more did not fit.
#[derive(Default)]
struct Mantissa {
    mant: u64,
    sig: u32,
    inexact: bool,
}

impl Mantissa {
    /// Scan the decimal digits of `s` from `i` on into the mantissa (eight at a time while they
    /// fit); returns the index after the last digit.
    #[inline]
    fn digits(&mut self, s: &[u8], mut i: usize) -> usize {
        while self.sig + 8 <= MAX_SIG_DIGITS {
            let Some(chunk) = s.get(i..i + 8) else { break };
            let mut word = [0u8; 8];
            word.copy_from_slice(chunk);
            let v = u64::from_le_bytes(word);
            if !eight_digits(v) {
                break;
            }
            self.mant = self.mant * 100_000_000 + eight_digits_value(v);
            self.sig += 8;
            i += 8;
        }
        while let Some(&c @ b'0'..=b'9') = s.get(i) {
            if self.sig < MAX_SIG_DIGITS {
                self.mant = self.mant * 10 + u64::from(c - b'0');
                self.sig += 1;
            } else {
                self.inexact = true;
            }
            i += 1;
        }
        i
    }
}

/// Whether all eight bytes of `v` (little endian) are ASCII digits: no byte is below `'0'`
/// (subtracting 0x30 would borrow into its top bit) or above `'9'` (adding 0x46 would set it).
#[inline(always)]
fn eight_digits(v: u64) -> bool {
    let below = v.wrapping_sub(0x3030_3030_3030_3030);
    let above = v.wrapping_add(0x4646_4646_4646_4646);
    (below | above) & 0x8080_8080_8080_8080 == 0
}

/// The value of eight ASCII digits (first digit in the lowest byte, the most significant),
/// combined pairwise in three multiplications: digits → two-digit → four-digit → eight-digit
/// groups. `eight_digits(v)` must hold.
#[inline(always)]
fn eight_digits_value(v: u64) -> u64 {
    let d = v - 0x3030_3030_3030_3030;
    // Bytes 2k: 10·digit(2k) + digit(2k+1) (each < 100, no carry into the next byte).
    let pairs = (d * 10 + (d >> 8)) & 0x00FF_00FF_00FF_00FF;
    // 16-bit lanes 2k: 100·pair(2k) + pair(2k+1) (< 10⁴).
    let quads = (pairs * 100 + (pairs >> 16)) & 0x0000_FFFF_0000_FFFF;
    // 10⁴·quad(0) + quad(1).
    (quads & 0xFFFF) * 10_000 + (quads >> 32)
}

/// The scanner does not take the line: serde_json decides.
pub(super) struct Bail;

struct Scanner<'a> {
    /// The line's bytes (any bytes: only ASCII is taken outside strings, and a string with a
    /// byte ≥ 0x80 is left to serde_json, so every string the scanner takes is UTF-8).
    s: &'a [u8],
    i: usize,
}

/// Each byte of `v` (eight bytes, little endian) that is `"`, `\\`, a control character
/// (< 0x20) or not ASCII (≥ 0x80) has its top bit set in the result, and the lowest set bit
/// lies in the first such byte: the bytes a plain string stops at. (The classic zero-byte test
/// `(x − 0x01…) & !x & 0x80…` flags every zero byte and, through borrows, only bytes above a
/// flagged one; likewise for `x < 0x20`.)
#[inline(always)]
fn string_stops(v: u64) -> u64 {
    const ONES: u64 = 0x0101_0101_0101_0101;
    const HIGH: u64 = 0x8080_8080_8080_8080;
    let zero = |x: u64| x.wrapping_sub(ONES) & !x & HIGH;
    let quote = zero(v ^ (ONES * u64::from(b'"')));
    let backslash = zero(v ^ (ONES * u64::from(b'\\')));
    let control = v.wrapping_sub(ONES * 0x20) & !v & HIGH;
    quote | backslash | control | (v & HIGH)
}

impl<'a> Scanner<'a> {
    #[inline]
    fn ws(&mut self) {
        // Most tokens follow no whitespace: one test (every JSON whitespace byte is ≤ b' ').
        if self.s.get(self.i).is_some_and(|&c| c > b' ') {
            return;
        }
        while let Some(&c) = self.s.get(self.i) {
            if matches!(c, b' ' | b'\t' | b'\n' | b'\r') {
                self.i += 1;
            } else {
                break;
            }
        }
    }

    /// Skip whitespace, then consume `c` if it is next.
    #[inline]
    fn eat(&mut self, c: u8) -> bool {
        self.ws();
        if self.s.get(self.i) == Some(&c) {
            self.i += 1;
            true
        } else {
            false
        }
    }

    /// A string of ASCII without escapes or control characters (its bytes between the quotes),
    /// scanned eight bytes at a time.
    #[inline]
    fn plain_str(&mut self) -> Result<&'a [u8], Bail> {
        if !self.eat(b'"') {
            return Err(Bail);
        }
        let s = self.s;
        let start = self.i;
        let mut i = start;
        loop {
            if let Some(chunk) = s.get(i..i + 8) {
                let mut word = [0u8; 8];
                word.copy_from_slice(chunk);
                let stops = string_stops(u64::from_le_bytes(word));
                if stops == 0 {
                    i += 8;
                    continue;
                }
                i += (stops.trailing_zeros() / 8) as usize;
            }
            // The byte at `i` is the first one the word flagged, or one past the last whole word.
            match *s.get(i).ok_or(Bail)? {
                b'"' => break,
                b'\\' | 0..=0x1f | 0x80.. => return Err(Bail),
                _ => i += 1,
            }
        }
        self.i = i + 1;
        Ok(&s[start..i])
    }

    /// A JSON number, finite as an f64, read in one pass: the grammar is checked while the
    /// significant digits accumulate (at most [`MAX_SIG_DIGITS`], leading zeros not counted) and
    /// the decimal exponent is counted. Then:
    ///
    /// - **exact fast path** (Clinger): with a mantissa `m ≤ 2⁵³` and a decimal exponent
    ///   `|e| ≤ 22`, both `m` and `10^|e|` are doubles exactly, so the one IEEE multiplication or
    ///   division `m·10^e` rounds the exact value once, to nearest: the correctly rounded result,
    ///   the same bits as the standard library's parse;
    /// - **wide product** (`decimal::to_f64`): a mantissa of at most 19 digits with a decimal
    ///   exponent in [−54, 55] times a 128-bit power of five, rounded from both ends of its
    ///   error bracket; taken where both ends give the same double (the correctly rounded one);
    /// - every other number (more significant digits, a larger exponent, an undecided bracket,
    ///   a subnormal or overflowing result) goes to the standard library's correctly rounded
    ///   parse of its text.
    ///
    /// Both give what serde_json gives with `float_roundtrip` (tests
    /// `random_doubles_read_correctly_rounded` and
    /// `the_exact_fast_path_agrees_with_the_standard_parse`).
    #[inline(always)]
    fn num(&mut self) -> Result<f64, Bail> {
        self.ws();
        let s = self.s;
        let start = self.i;
        let mut i = start;
        let neg = s.get(i) == Some(&b'-');
        if neg {
            i += 1;
        }
        let mut acc = Mantissa::default();
        match s.get(i) {
            Some(b'0') => i += 1,
            Some(b'1'..=b'9') => i = acc.digits(s, i),
            _ => return Err(Bail),
        }
        let mut exp: i64 = 0;
        if s.get(i) == Some(&b'.') {
            i += 1;
            let first = i;
            if acc.mant == 0 {
                // Leading zeros of the fraction: no significant digit.
                while s.get(i) == Some(&b'0') {
                    i += 1;
                }
            }
            i = acc.digits(s, i);
            if i == first {
                return Err(Bail);
            }
            exp -= (i - first) as i64;
        }
        if matches!(s.get(i), Some(b'e' | b'E')) {
            i += 1;
            let eneg = match s.get(i) {
                Some(b'-') => {
                    i += 1;
                    true
                }
                Some(b'+') => {
                    i += 1;
                    false
                }
                _ => false,
            };
            let first = i;
            let mut e: i64 = 0;
            while let Some(&c @ b'0'..=b'9') = s.get(i) {
                // Saturates far outside the fast path's range.
                e = (e * 10 + i64::from(c - b'0')).min(1 << 20);
                i += 1;
            }
            if i == first {
                return Err(Bail);
            }
            exp += if eneg { -e } else { e };
        }
        self.i = i;
        let mant = acc.mant;
        if !acc.inexact && mant <= (1 << 53) && (-22..=22).contains(&exp) {
            // `|exp| ≤ 22`: the index is in bounds.
            let p = POW10_EXACT[exp.unsigned_abs() as usize];
            let x = if exp >= 0 {
                mant as f64 * p
            } else {
                mant as f64 / p
            };
            return Ok(if neg { -x } else { x });
        }
        // At most 19 significant digits: one wide product, where it decides.
        if !acc.inexact
            && let Some(x) = super::decimal::to_f64(mant, exp)
        {
            return Ok(if neg { -x } else { x });
        }
        // The grammar was checked: ASCII digits, signs, `.` and `e`.
        let x: f64 = std::str::from_utf8(&s[start..i])
            .map_err(|_| Bail)?
            .parse()
            .map_err(|_| Bail)?;
        if !x.is_finite() {
            return Err(Bail);
        }
        Ok(x)
    }

    /// Any JSON value this scanner takes, validated and dropped.
    fn skip_value(&mut self, depth: usize) -> Result<(), Bail> {
        if depth > MAX_DEPTH {
            return Err(Bail);
        }
        self.ws();
        match *self.s.get(self.i).ok_or(Bail)? {
            b'"' => self.plain_str().map(|_| ()),
            b'[' => {
                self.i += 1;
                if self.eat(b']') {
                    return Ok(());
                }
                loop {
                    self.skip_value(depth + 1)?;
                    if self.eat(b',') {
                        continue;
                    }
                    return if self.eat(b']') { Ok(()) } else { Err(Bail) };
                }
            }
            b'{' => {
                self.i += 1;
                if self.eat(b'}') {
                    return Ok(());
                }
                loop {
                    self.plain_str()?;
                    if !self.eat(b':') {
                        return Err(Bail);
                    }
                    self.skip_value(depth + 1)?;
                    if self.eat(b',') {
                        continue;
                    }
                    return if self.eat(b'}') { Ok(()) } else { Err(Bail) };
                }
            }
            b't' => self.literal(b"true"),
            b'f' => self.literal(b"false"),
            b'n' => self.literal(b"null"),
            _ => self.skip_num(),
        }
    }

    /// A JSON number whose value is not needed (a skipped field): its grammar is checked as in
    /// [`Self::num`] and nothing is converted. serde_json ignores such a number the same way
    /// (`IgnoredAny` checks the grammar, not the range: `1e400` in a skipped field is taken by
    /// both).
    fn skip_num(&mut self) -> Result<(), Bail> {
        self.ws();
        let s = self.s;
        // The index after the run of ASCII digits from `i` (eight bytes at a time, then one).
        let digits = |mut i: usize| {
            while let Some(chunk) = s.get(i..i + 8) {
                let mut word = [0u8; 8];
                word.copy_from_slice(chunk);
                if !eight_digits(u64::from_le_bytes(word)) {
                    break;
                }
                i += 8;
            }
            while let Some(b'0'..=b'9') = s.get(i) {
                i += 1;
            }
            i
        };
        let mut i = self.i;
        if s.get(i) == Some(&b'-') {
            i += 1;
        }
        i = match s.get(i) {
            Some(b'0') => i + 1,
            Some(b'1'..=b'9') => digits(i),
            _ => return Err(Bail),
        };
        if s.get(i) == Some(&b'.') {
            let end = digits(i + 1);
            if end == i + 1 {
                return Err(Bail);
            }
            i = end;
        }
        if matches!(s.get(i), Some(b'e' | b'E')) {
            i += 1;
            if matches!(s.get(i), Some(b'-' | b'+')) {
                i += 1;
            }
            let end = digits(i);
            if end == i {
                return Err(Bail);
            }
            i = end;
        }
        self.i = i;
        Ok(())
    }

    fn literal(&mut self, word: &[u8]) -> Result<(), Bail> {
        if self.s[self.i..].starts_with(word) {
            self.i += word.len();
            Ok(())
        } else {
            Err(Bail)
        }
    }
}

impl Values for Scanner<'_> {
    type Error = Bail;

    fn word(&mut self, into: &mut Vec<u8>) -> Result<(), Bail> {
        let s = self.plain_str()?;
        into.clear();
        into.extend_from_slice(s);
        Ok(())
    }

    fn string(&mut self, into: &mut String) -> Result<(), Bail> {
        // ASCII (`plain_str`): always UTF-8.
        let s = std::str::from_utf8(self.plain_str()?).map_err(|_| Bail)?;
        into.clear();
        into.push_str(s);
        Ok(())
    }

    fn number(&mut self) -> Result<f64, Bail> {
        self.num()
    }

    fn numbers(&mut self, into: &mut Vec<f64>) -> Result<(), Bail> {
        if !self.eat(b'[') {
            return Err(Bail);
        }
        into.clear();
        if self.eat(b']') {
            return Ok(());
        }
        loop {
            into.push(self.num()?);
            if self.eat(b',') {
                continue;
            }
            return if self.eat(b']') { Ok(()) } else { Err(Bail) };
        }
    }

    fn points(&mut self, into: &mut Vec<[f64; 3]>) -> Result<(), Bail> {
        if !self.eat(b'[') {
            return Err(Bail);
        }
        into.clear();
        if self.eat(b']') {
            return Ok(());
        }
        loop {
            if !self.eat(b'[') {
                return Err(Bail);
            }
            let x = self.num()?;
            let y = if self.eat(b',') {
                self.num()?
            } else {
                return Err(Bail);
            };
            let z = if self.eat(b',') {
                self.num()?
            } else {
                return Err(Bail);
            };
            if !self.eat(b']') {
                return Err(Bail);
            }
            into.push([x, y, z]);
            if self.eat(b',') {
                continue;
            }
            return if self.eat(b']') { Ok(()) } else { Err(Bail) };
        }
    }

    fn skip(&mut self) -> Result<(), Bail> {
        self.skip_value(1)
    }
}

/// Read `line` (one record, with its line end) into `b`, which must be reset. False if the
/// scanner does not take the line; `b` is then partly filled and must be reset before the
/// serde_json path reads it. The line need not be UTF-8: a line the scanner takes is ASCII.
pub(super) fn parse_line(line: &[u8], b: &mut LineBuffers) -> bool {
    let mut sc = Scanner { s: line, i: 0 };
    scan(&mut sc, b).is_ok()
}

fn scan(sc: &mut Scanner<'_>, b: &mut LineBuffers) -> Result<(), Bail> {
    if !sc.eat(b'{') {
        return Err(Bail);
    }
    if !sc.eat(b'}') {
        loop {
            let key = sc.plain_str()?;
            if !sc.eat(b':') {
                return Err(Bail);
            }
            let field = Field::of(key, &mut b.unknown_field);
            b.take(field, sc)?;
            if sc.eat(b',') {
                continue;
            }
            if sc.eat(b'}') {
                break;
            }
            return Err(Bail);
        }
    }
    sc.ws();
    if sc.i == sc.s.len() {
        Ok(())
    } else {
        Err(Bail)
    }
}

/// The value of `text` if it is exactly one JSON number the scanner takes.
pub(super) fn number(text: &str) -> Option<f64> {
    let mut sc = Scanner {
        s: text.as_bytes(),
        i: 0,
    };
    let x = sc.num().ok()?;
    (sc.i == text.len()).then_some(x)
}
