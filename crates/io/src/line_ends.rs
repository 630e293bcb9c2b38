//! Line ends of text records: a bare carriage return (the line end of old Mac files, or of a
//! stretch pasted from one) is read as a line end, so each such line is its own row instead of
//! one long line that the CSV reader would take for an unclosed quote. `\r\n` is left as it is.

use std::io::Read;

/// A byte source that yields every `\r` not followed by `\n` as `\n`. A `\r` at the end of a
/// read is held back until the next byte says which it is (on a live feed with bare-CR line
/// ends, a line is thus passed on when the next byte arrives).
pub(crate) struct BareCrAsLf<R> {
    inner: R,
    /// Converted bytes not yet passed on: `buf[pos..end]`.
    buf: Box<[u8]>,
    pos: usize,
    end: usize,
    /// A `\r` held back from the previous read.
    held_cr: bool,
}

impl<R> BareCrAsLf<R> {
    /// Wraps `inner`.
    pub(crate) fn new(inner: R) -> Self {
        Self { inner, buf: vec![0; 8192].into_boxed_slice(), pos: 0, end: 0, held_cr: false }
    }
}

impl<R: Read> BareCrAsLf<R> {
    /// Refills `buf` with converted bytes; `false` at the end of the source.
    fn fill(&mut self) -> std::io::Result<bool> {
        loop {
            let start = usize::from(self.held_cr);
            let n = self.inner.read(&mut self.buf[start..])?;
            let buf = &mut self.buf;
            if self.held_cr {
                buf[0] = if n > 0 && buf[1] == b'\n' { b'\r' } else { b'\n' };
                self.held_cr = false;
            }
            let mut len = start + n;
            if n > 0 && buf[len - 1] == b'\r' {
                self.held_cr = true;
                len -= 1;
            }
            for i in 0..len.saturating_sub(1) {
                if buf[i] == b'\r' && buf[i + 1] != b'\n' {
                    buf[i] = b'\n';
                }
            }
            (self.pos, self.end) = (0, len);
            // Only a held `\r` was read: read on (an empty fill would end the source).
            if len > 0 || n == 0 {
                return Ok(len > 0);
            }
        }
    }
}

impl<R: Read> Read for BareCrAsLf<R> {
    fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
        if out.is_empty() || (self.pos == self.end && !self.fill()?) {
            return Ok(0);
        }
        let n = out.len().min(self.end - self.pos);
        out[..n].copy_from_slice(&self.buf[self.pos..self.pos + n]);
        self.pos += n;
        Ok(n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reads `input` through the adapter in chunks of `chunk` bytes.
    fn through(input: &[u8], chunk: usize) -> Vec<u8> {
        struct Chunks<'a>(&'a [u8], usize);
        impl Read for Chunks<'_> {
            fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
                let n = self.0.len().min(self.1).min(buf.len());
                buf[..n].copy_from_slice(&self.0[..n]);
                self.0 = &self.0[n..];
                Ok(n)
            }
        }
        let mut out = Vec::new();
        BareCrAsLf::new(Chunks(input, chunk)).read_to_end(&mut out).unwrap();
        out
    }

    #[test]
    fn bare_cr_becomes_lf_and_crlf_is_kept_at_any_chunking() {
        let input = b"a,b\r1,2\r\n3,4\r5,6\r";
        for chunk in 1..=input.len() {
            assert_eq!(through(input, chunk), b"a,b\n1,2\r\n3,4\n5,6\n", "chunk {chunk}");
        }
    }
}
