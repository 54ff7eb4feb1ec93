//! A bounded line reader: the lines of a stream one at a time, each at most [`MAX_LINE`] bytes.
//!
//! A longer line (or an input without newlines, such as `/dev/zero`) is not buffered: the reader
//! reports it as [`Line::TooLong`] with its number as soon as it passes the limit, and skips to
//! the next newline before it reads the next line, so memory stays bounded whatever the input and
//! the line is told about before the rest of it is read (which may never end). A UTF-8 byte order mark at the start of the input is dropped.

use std::io::{BufRead, ErrorKind, Read};

/// Longest line kept, bytes (without its line end): 64 KiB, far more than any pose record.
pub const MAX_LINE: usize = 64 * 1024;

/// The UTF-8 byte order mark.
const BOM: &[u8] = b"\xef\xbb\xbf";

/// One line of the input.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Line<'a> {
    /// The line's bytes, without the line end (`\n` or `\r\n`).
    Text(&'a [u8]),
    /// A line longer than [`MAX_LINE`] bytes; its bytes were skipped.
    TooLong,
}

/// Reads the lines of an input with a bounded buffer, counting them from 1.
pub(crate) struct Lines<R> {
    input: R,
    buffer: Vec<u8>,
    /// Number of the line in `buffer`, from 1 (0 before the first).
    number: usize,
    too_long: bool,
    /// The rest of an over-long line is still to be skipped.
    skipping: bool,
    /// The next call yields the line in `buffer` again.
    replay: bool,
    finished: bool,
}

impl<R: BufRead> Lines<R> {
    pub(crate) fn new(input: R) -> Self {
        Self {
            input,
            buffer: Vec::new(),
            number: 0,
            too_long: false,
            skipping: false,
            replay: false,
            finished: false,
        }
    }

    /// Makes the next [`Lines::next_line`] yield the last line again.
    pub(crate) fn unread(&mut self) {
        if self.number > 0 {
            self.replay = true;
        }
    }

    /// The next line with its number, `None` at the end of the input, or the input's error (after
    /// which the reader yields `None`: a failing input would fail again).
    /// The next line as a record's text with its number, or the error of a failing input (an
    /// [`Error::Io`](crate::model::error::Error::Io) naming `source`) or of an over-long line; `None` at the
    /// end.
    pub(crate) fn next_record(
        &mut self,
        source: &str,
    ) -> Option<crate::model::error::Result<(usize, &[u8])>> {
        Some(match self.next_line()? {
            Ok((number, Line::Text(text))) => Ok((number, text)),
            Ok((number, Line::TooLong)) => Err(super::too_long(source, number)),
            Err(e) => Err(crate::model::error::Error::Io {
                file: source.to_string(),
                source: e,
            }),
        })
    }

    pub(crate) fn next_line(&mut self) -> Option<std::io::Result<(usize, Line<'_>)>> {
        if self.replay {
            self.replay = false;
        } else {
            if self.finished {
                return None;
            }
            match self.read_line() {
                Ok(true) => self.number += 1,
                Ok(false) => {
                    self.finished = true;
                    return None;
                }
                Err(e) => {
                    self.finished = true;
                    return Some(Err(e));
                }
            }
        }
        let line = if self.too_long {
            Line::TooLong
        } else {
            let mut text = &self.buffer[..];
            if self.number == 1 {
                text = text.strip_prefix(BOM).unwrap_or(text);
            }
            Line::Text(text)
        };
        Some(Ok((self.number, line)))
    }

    /// Reads one line into `buffer` (without its line end); false at the end of the input. The
    /// newline is found by the standard library's `read_until` (a word-at-a-time search), on at
    /// most the longest line kept: a longer one is skipped to its newline, not kept.
    fn read_line(&mut self) -> std::io::Result<bool> {
        if self.skipping {
            self.skip_line()?;
            self.skipping = false;
        }
        self.buffer.clear();
        self.too_long = false;
        // The BOM and a `\r` before the newline do not count towards the limit.
        let most = MAX_LINE + BOM.len() + 1;
        let read = (&mut self.input)
            .take(most as u64 + 1)
            .read_until(b'\n', &mut self.buffer)?;
        if read == 0 {
            return Ok(false);
        }
        if self.buffer.last() == Some(&b'\n') {
            self.buffer.pop();
        } else if self.buffer.len() > most {
            // Told now; the rest is skipped before the next line.
            self.skipping = true;
            self.too_long = true;
            self.buffer = Vec::new();
        }
        if self.buffer.last() == Some(&b'\r') {
            self.buffer.pop();
        }
        let limit = MAX_LINE
            + if self.number == 0 && self.buffer.starts_with(BOM) {
                BOM.len()
            } else {
                0
            };
        if self.buffer.len() > limit {
            self.too_long = true;
            self.buffer = Vec::new();
        }
        Ok(true)
    }

    /// Skips the input up to and with the next newline, keeping nothing.
    fn skip_line(&mut self) -> std::io::Result<()> {
        loop {
            let chunk = match self.input.fill_buf() {
                Ok(c) => c,
                Err(e) if e.kind() == ErrorKind::Interrupted => continue,
                Err(e) => return Err(e),
            };
            if chunk.is_empty() {
                return Ok(());
            }
            match chunk.iter().position(|&b| b == b'\n') {
                Some(k) => {
                    self.input.consume(k + 1);
                    return Ok(());
                }
                None => {
                    let all = chunk.len();
                    self.input.consume(all);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn all(input: &[u8], capacity: usize) -> Vec<(usize, Option<Vec<u8>>)> {
        let mut lines = Lines::new(std::io::BufReader::with_capacity(capacity, input));
        let mut out = Vec::new();
        while let Some(r) = lines.next_line() {
            let (n, line) = r.unwrap();
            out.push((
                n,
                match line {
                    Line::Text(t) => Some(t.to_vec()),
                    Line::TooLong => None,
                },
            ));
        }
        out
    }

    #[test]
    fn lines_are_counted_bom_and_line_ends_dropped() {
        for capacity in [1, 3, 8192] {
            let got = all(b"\xef\xbb\xbfa\r\n\nb\xef\xbb\xbf\nc", capacity);
            let want: Vec<(usize, Option<Vec<u8>>)> = vec![
                (1, Some(b"a".to_vec())),
                (2, Some(vec![])),
                (3, Some(b"b\xef\xbb\xbf".to_vec())),
                (4, Some(b"c".to_vec())),
            ];
            assert_eq!(got, want, "capacity {capacity}");
        }
    }

    #[test]
    fn long_lines_are_skipped_not_kept() {
        let mut input = vec![b'x'; MAX_LINE];
        input.push(b'\n');
        input.extend(vec![b'y'; MAX_LINE + 1]);
        input.extend_from_slice(b"\r\nz\n");
        input.extend(vec![0u8; 3 * MAX_LINE]);
        let got = all(&input, 8192);
        assert_eq!(got.len(), 4);
        assert_eq!(got[0].1.as_ref().map(Vec::len), Some(MAX_LINE));
        assert_eq!(got[1], (2, None));
        assert_eq!(got[2], (3, Some(b"z".to_vec())));
        assert_eq!(got[3], (4, None));
    }

    #[test]
    fn an_unread_line_comes_again() {
        let mut lines = Lines::new(&b"a\nb\n"[..]);
        lines.unread();
        assert_eq!(lines.next_line().unwrap().unwrap(), (1, Line::Text(b"a")));
        lines.unread();
        assert_eq!(lines.next_line().unwrap().unwrap(), (1, Line::Text(b"a")));
        assert_eq!(lines.next_line().unwrap().unwrap(), (2, Line::Text(b"b")));
        assert!(lines.next_line().is_none());
    }
}
