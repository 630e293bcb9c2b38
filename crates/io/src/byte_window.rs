//! A forward-only window over a byte stream, for the binary log readers: they look at the next
//! few bytes (a message header, then its payload), consume them, and never go back, so a log is
//! read in fixed-size chunks instead of whole (a 400 MB log of a topic nobody needs is never
//! held in memory).

use std::io::Read;

/// Bytes read per refill (several messages of either log format).
const CHUNK: usize = 256 * 1024;

/// Forward-only buffered view of `source` with the absolute offset of its first unread byte.
pub(crate) struct ByteWindow<R> {
    source: R,
    buf: Vec<u8>,
    /// Start of the unread bytes in `buf`.
    start: usize,
    /// Absolute offset of `buf[start]` in the stream.
    offset: u64,
    eof: bool,
}

impl<R: Read> ByteWindow<R> {
    pub(crate) fn new(source: R) -> Self {
        Self { source, buf: Vec::new(), start: 0, offset: 0, eof: false }
    }

    /// Absolute offset of the next unread byte.
    pub(crate) fn offset(&self) -> u64 {
        self.offset
    }

    /// The next `n` bytes without consuming them, or `None` if the stream ends before `n`
    /// bytes (the caller then reports a truncation at [`ByteWindow::offset`]).
    ///
    /// # Errors
    /// The source's read errors.
    pub(crate) fn peek(&mut self, n: usize) -> std::io::Result<Option<&[u8]>> {
        while self.buf.len() - self.start < n && !self.eof {
            if self.start > 0 {
                self.buf.drain(..self.start);
                self.start = 0;
            }
            let have = self.buf.len();
            let want = (n - have).max(CHUNK);
            self.buf.resize(have + want, 0);
            let got = loop {
                match self.source.read(&mut self.buf[have..]) {
                    Ok(k) => break k,
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                    Err(e) => {
                        self.buf.truncate(have);
                        return Err(e);
                    }
                }
            };
            self.buf.truncate(have + got);
            if got == 0 {
                self.eof = true;
            }
        }
        Ok(self.buf.get(self.start..self.start + n))
    }

    /// Skips `n` bytes (those peeked, or more: a jump forward to an appended section).
    ///
    /// # Errors
    /// The source's read errors.
    pub(crate) fn consume(&mut self, n: u64) -> std::io::Result<()> {
        let in_buf = (self.buf.len() - self.start) as u64;
        if n <= in_buf {
            self.start += n as usize;
        } else {
            let rest = n - in_buf;
            self.buf.clear();
            self.start = 0;
            std::io::copy(&mut (&mut self.source).take(rest), &mut std::io::sink())?;
        }
        self.offset += n;
        Ok(())
    }

    /// Has the stream ended at the current offset?
    ///
    /// # Errors
    /// The source's read errors.
    pub(crate) fn at_end(&mut self) -> std::io::Result<bool> {
        Ok(self.peek(1)?.is_none())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn analytic_window_peeks_consumes_and_jumps_across_chunks() {
        let data: Vec<u8> = (0..(3 * CHUNK + 7)).map(|i| (i % 251) as u8).collect();
        let mut w = ByteWindow::new(data.as_slice());
        assert_eq!(w.peek(3).unwrap(), Some(&data[..3]));
        w.consume(CHUNK as u64 - 1).unwrap();
        let at = CHUNK - 1;
        assert_eq!(w.peek(10).unwrap(), Some(&data[at..at + 10]));
        w.consume(2 * CHUNK as u64).unwrap();
        let at = 3 * CHUNK - 1;
        assert_eq!(w.offset(), at as u64);
        assert_eq!(w.peek(8).unwrap(), Some(&data[at..at + 8]));
        assert_eq!(w.peek(9).unwrap(), None);
        w.consume(8).unwrap();
        assert!(w.at_end().unwrap());
    }
}
