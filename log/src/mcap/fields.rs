//! Checked little-endian field reading of MCAP record bodies.

/// A field of an MCAP record body that cannot be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub(super) enum FieldError {
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

/// Little-endian field reader over one MCAP record body; every length is checked against the
/// remaining bytes before use (`mcap`'s own record parser reserves a string's declared length
/// before checking it, so the records the audit needs are parsed here).
pub(super) struct Fields<'a> {
    pub(super) b: &'a [u8],
}

impl<'a> Fields<'a> {
    pub(super) fn take(&mut self, n: u64, what: &'static str) -> Result<&'a [u8], FieldError> {
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
    pub(super) fn u16(&mut self, what: &'static str) -> Result<u16, FieldError> {
        Ok(u16::from_le_bytes(self.int(what)?))
    }
    pub(super) fn u32(&mut self, what: &'static str) -> Result<u32, FieldError> {
        Ok(u32::from_le_bytes(self.int(what)?))
    }
    pub(super) fn u64(&mut self, what: &'static str) -> Result<u64, FieldError> {
        Ok(u64::from_le_bytes(self.int(what)?))
    }
    pub(super) fn bytes(&mut self, what: &'static str) -> Result<&'a [u8], FieldError> {
        let n = self.u32(what)?;
        self.take(u64::from(n), what)
    }
    pub(super) fn str(&mut self, what: &'static str) -> Result<&'a str, FieldError> {
        std::str::from_utf8(self.bytes(what)?).map_err(|_| FieldError::Utf8(what))
    }
    /// A `Map<string, string>` (byte length, then key/value pairs); visits each pair.
    pub(super) fn map(
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
