//! Little-endian CDR, as ROS 2 serializes messages (`CDR_LE`, the
//! encapsulation header `00 01 00 00`): a reader and a writer shared by the
//! message types a bag is read from ([`super::pointcloud2`],
//! [`super::livox_custom`]).
//!
//! A primitive of `n` bytes is aligned to `n` (an `uint64` to 8, an
//! `uint32`/`float32` to 4), the alignment counted from the start of the
//! payload, after the 4-byte encapsulation header. A string is its length
//! (`uint32`, the terminating NUL included) then its bytes; a sequence is
//! its length (`uint32`) then its elements; a fixed array is its elements
//! alone.

/// A little-endian CDR reader (alignment relative to the payload start).
/// Every read checks its bounds: a truncated message is an error, never a
/// panic.
pub(crate) struct CdrReader<'a> {
    buf: &'a [u8],
    pos: usize,
}

impl<'a> CdrReader<'a> {
    /// The reader of the message `data` (encapsulation header first); an
    /// error for big-endian CDR or a missing or unknown header.
    pub(crate) fn new(data: &'a [u8]) -> Result<Self, String> {
        match data.split_first_chunk::<4>() {
            Some(([0, 1, _, _], buf)) => Ok(Self { buf, pos: 0 }),
            Some(([0, 0, _, _], _)) => Err("big-endian CDR is not supported".into()),
            _ => Err("not a CDR message (bad encapsulation header)".into()),
        }
    }

    /// The next `n` bytes after aligning to `align`; an error naming
    /// `what` when the message ends first.
    pub(crate) fn take_named(
        &mut self,
        n: usize,
        align: usize,
        what: &str,
    ) -> Result<&'a [u8], String> {
        let start = self.pos.div_ceil(align) * align;
        let slice = start
            .checked_add(n)
            .and_then(|end| self.buf.get(start..end))
            .ok_or_else(|| {
                format!(
                    "message is truncated: {what} needs {n} bytes at byte {start} of a {}-byte payload",
                    self.buf.len()
                )
            })?;
        self.pos = start + n;
        Ok(slice)
    }

    /// The next `n` bytes after aligning to `align`.
    pub(crate) fn take(&mut self, n: usize, align: usize) -> Result<&'a [u8], String> {
        self.take_named(n, align, "the next value")
    }

    /// The next `N` bytes after aligning to `N` (a primitive of `N`
    /// bytes), named `what` in the error.
    fn array<const N: usize>(&mut self, what: &str) -> Result<[u8; N], String> {
        let b = self.take_named(N, N, what)?;
        let mut out = [0; N];
        out.copy_from_slice(b);
        Ok(out)
    }

    /// An `uint8`.
    pub(crate) fn u8(&mut self) -> Result<u8, String> {
        self.u8_named("an uint8")
    }

    /// An `uint8` named `what` in the error.
    pub(crate) fn u8_named(&mut self, what: &str) -> Result<u8, String> {
        Ok(self.array::<1>(what)?[0])
    }

    /// An `uint32`.
    pub(crate) fn u32(&mut self) -> Result<u32, String> {
        self.u32_named("an uint32")
    }

    /// An `uint32` named `what` in the error.
    pub(crate) fn u32_named(&mut self, what: &str) -> Result<u32, String> {
        Ok(u32::from_le_bytes(self.array(what)?))
    }

    /// An `uint64` (aligned to 8) named `what` in the error.
    pub(crate) fn u64_named(&mut self, what: &str) -> Result<u64, String> {
        Ok(u64::from_le_bytes(self.array(what)?))
    }

    /// A `float32` named `what` in the error.
    pub(crate) fn f32_named(&mut self, what: &str) -> Result<f32, String> {
        Ok(f32::from_le_bytes(self.array(what)?))
    }

    /// A string (its terminating NUL dropped; invalid UTF-8 replaced).
    pub(crate) fn string(&mut self) -> Result<String, String> {
        let n = self.u32_named("a string's length")? as usize;
        let b = self.take_named(n, 1, "a string")?;
        let b = b.strip_suffix(&[0]).unwrap_or(b);
        Ok(String::from_utf8_lossy(b).into_owned())
    }

    /// Payload bytes not read yet (after the current position).
    pub(crate) fn remaining(&self) -> usize {
        self.buf.len().saturating_sub(self.pos)
    }
}

/// A little-endian CDR writer (alignment relative to the payload start);
/// [`CdrWriter::finish`] puts the encapsulation header in front.
#[derive(Default)]
pub(crate) struct CdrWriter {
    buf: Vec<u8>,
}

impl CdrWriter {
    /// Pad with zeros to a multiple of `a`.
    pub(crate) fn align(&mut self, a: usize) {
        while !self.buf.len().is_multiple_of(a) {
            self.buf.push(0);
        }
    }
    /// An `uint8`.
    pub(crate) fn u8(&mut self, v: u8) {
        self.buf.push(v);
    }
    /// An `uint32`, aligned to 4.
    pub(crate) fn u32(&mut self, v: u32) {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }
    /// An `uint64`, aligned to 8.
    pub(crate) fn u64(&mut self, v: u64) {
        self.align(8);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }
    /// A `float32`, aligned to 4.
    pub(crate) fn f32(&mut self, v: f32) {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }
    /// A string: its length with the NUL, its bytes, the NUL.
    pub(crate) fn string(&mut self, s: &str) {
        self.u32(s.len() as u32 + 1);
        self.buf.extend_from_slice(s.as_bytes());
        self.buf.push(0);
    }
    /// Raw bytes (an `uint8[]`'s body, after its length).
    pub(crate) fn bytes(&mut self, b: &[u8]) {
        self.buf.extend_from_slice(b);
    }
    /// The message: the little-endian encapsulation header, then the
    /// payload.
    pub(crate) fn finish(self) -> Vec<u8> {
        let mut out = Vec::with_capacity(4 + self.buf.len());
        out.extend_from_slice(&[0, 1, 0, 0]);
        out.extend_from_slice(&self.buf);
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An `uint64` after an `uint32` is aligned to 8 from the payload
    /// start (not from the buffer's, which has the 4-byte header).
    #[test]
    fn alignment_counts_from_the_payload_start() {
        let mut w = CdrWriter::default();
        w.u32(7);
        w.u64(0x0102_0304_0506_0708);
        w.u8(9);
        w.f32(1.5);
        let data = w.finish();
        assert_eq!(data.len(), 4 + 4 + 4 + 8 + 1 + 3 + 4);
        let mut r = CdrReader::new(&data).unwrap();
        assert_eq!(r.u32().unwrap(), 7);
        assert_eq!(r.u64_named("x").unwrap(), 0x0102_0304_0506_0708);
        assert_eq!(r.u8().unwrap(), 9);
        assert_eq!(r.f32_named("x").unwrap(), 1.5);
        assert_eq!(r.remaining(), 0);
        let err = r.u32_named("the answer").unwrap_err();
        assert!(err.contains("the answer"), "{err}");
    }
}
