//! A small, bounds-checked reader of OMG CDR (XCDR1), the serialisation of ROS 2 messages.
//!
//! A serialised message starts with a 4-byte encapsulation header: `00 00` big-endian CDR or
//! `00 01` little-endian CDR, then two option bytes. Primitives are aligned to their size (8 for
//! `float64`) relative to the end of that header; a string is a `uint32` length that counts its
//! terminating NUL, then the bytes. Nothing is allocated from a length read from the data before
//! it is checked against the bytes that remain.

/// What went wrong, with the byte offset (from the start of the message) and the field.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct CdrError {
    /// Offset of the read that failed, from the start of the message (header included).
    pub offset: usize,
    /// What was being read and why it failed.
    pub message: String,
}

impl std::fmt::Display for CdrError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} (byte {})", self.message, self.offset)
    }
}

/// Length of the encapsulation header.
const HEADER: usize = 4;

/// A cursor over one serialised message.
pub(crate) struct CdrReader<'a> {
    /// The bytes after the encapsulation header.
    body: &'a [u8],
    pos: usize,
    little: bool,
}

impl<'a> CdrReader<'a> {
    /// A reader of `bytes`, after checking its encapsulation header.
    pub fn new(bytes: &'a [u8]) -> Result<Self, CdrError> {
        if bytes.len() < HEADER {
            return Err(CdrError {
                offset: 0,
                message: format!(
                    "{} byte(s): too short for the 4-byte CDR encapsulation header",
                    bytes.len()
                ),
            });
        }
        let little = match (bytes[0], bytes[1]) {
            (0, 0) => false,
            (0, 1) => true,
            (a, b) => {
                return Err(CdrError {
                    offset: 0,
                    message: format!(
                        "encapsulation {a:02x} {b:02x} is not plain CDR (00 00 big-endian or 00 01 little-endian)"
                    ),
                });
            }
        };
        Ok(Self {
            body: &bytes[HEADER..],
            pos: 0,
            little,
        })
    }

    fn error(&self, message: String) -> CdrError {
        CdrError {
            offset: HEADER + self.pos,
            message,
        }
    }

    /// Bytes left after the cursor.
    pub fn remaining(&self) -> usize {
        self.body.len() - self.pos
    }

    /// Takes `n` bytes aligned to `align`, or says which field ran past the end.
    fn take(&mut self, n: usize, align: usize, field: &str) -> Result<&'a [u8], CdrError> {
        let start = self.pos.div_ceil(align) * align;
        match start.checked_add(n) {
            Some(end) if end <= self.body.len() => {
                self.pos = end;
                Ok(&self.body[start..end])
            }
            _ => Err(self.error(format!(
                "the message ends before `{field}` ({} byte(s) left, {n} needed)",
                self.body.len().saturating_sub(start)
            ))),
        }
    }

    /// A `uint32`.
    pub fn u32(&mut self, field: &str) -> Result<u32, CdrError> {
        let b: [u8; 4] = self.take(4, 4, field)?.try_into().unwrap_or([0; 4]);
        Ok(if self.little {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        })
    }

    /// An `int32`.
    pub fn i32(&mut self, field: &str) -> Result<i32, CdrError> {
        let b: [u8; 4] = self.take(4, 4, field)?.try_into().unwrap_or([0; 4]);
        Ok(if self.little {
            i32::from_le_bytes(b)
        } else {
            i32::from_be_bytes(b)
        })
    }

    /// A `float32`.
    pub fn f32(&mut self, field: &str) -> Result<f32, CdrError> {
        let b: [u8; 4] = self.take(4, 4, field)?.try_into().unwrap_or([0; 4]);
        Ok(if self.little {
            f32::from_le_bytes(b)
        } else {
            f32::from_be_bytes(b)
        })
    }

    /// A `float64`.
    pub fn f64(&mut self, field: &str) -> Result<f64, CdrError> {
        let b: [u8; 8] = self.take(8, 8, field)?.try_into().unwrap_or([0; 8]);
        Ok(if self.little {
            f64::from_le_bytes(b)
        } else {
            f64::from_be_bytes(b)
        })
    }

    /// A string: its length (NUL included) is checked against the bytes left before anything is
    /// taken; the NUL is dropped, invalid UTF-8 is an error.
    pub fn string(&mut self, field: &str) -> Result<String, CdrError> {
        let n = self.u32(field)? as usize;
        if n > self.remaining() {
            return Err(self.error(format!(
                "`{field}` claims {n} byte(s), only {} left",
                self.remaining()
            )));
        }
        let bytes = self.take(n, 1, field)?;
        let text = match bytes.split_last() {
            None => &[][..],
            Some((0, text)) => text,
            Some(_) => {
                return Err(self.error(format!("`{field}` is not terminated by a NUL byte")));
            }
        };
        String::from_utf8(text.to_vec())
            .map_err(|_| self.error(format!("`{field}` is not valid UTF-8")))
    }

    /// The length of a sequence whose elements take at least `min_element` bytes each, checked
    /// against the bytes left.
    pub fn sequence_len(&mut self, field: &str, min_element: usize) -> Result<usize, CdrError> {
        let n = self.u32(field)? as usize;
        if n.saturating_mul(min_element.max(1)) > self.remaining() {
            return Err(self.error(format!(
                "`{field}` claims {n} element(s) of at least {min_element} bytes, only {} byte(s) left",
                self.remaining()
            )));
        }
        Ok(n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A little- or big-endian message: header, u32 7, string "ab", f64 1.5.
    fn message(little: bool) -> Vec<u8> {
        let mut b = vec![0, u8::from(little), 0, 0];
        let u32b = |v: u32| {
            if little {
                v.to_le_bytes()
            } else {
                v.to_be_bytes()
            }
        };
        b.extend(u32b(7));
        b.extend(u32b(3));
        b.extend(b"ab\0");
        b.extend([0; 5]); // 4 + 4 + 3 = 11 → align 8 → 16
        b.extend(if little {
            1.5f64.to_le_bytes()
        } else {
            1.5f64.to_be_bytes()
        });
        b
    }

    #[test]
    fn reads_both_byte_orders_with_alignment_after_the_header() {
        for little in [true, false] {
            let bytes = message(little);
            let mut r = CdrReader::new(&bytes).unwrap();
            assert_eq!(r.u32("a").unwrap(), 7);
            assert_eq!(r.string("s").unwrap(), "ab");
            assert_eq!(r.f64("x").unwrap(), 1.5);
            assert_eq!(r.remaining(), 0);
        }
    }

    #[test]
    fn every_truncation_is_an_error_naming_the_field() {
        let bytes = message(true);
        for cut in 0..bytes.len() {
            let short = &bytes[..cut];
            let result = CdrReader::new(short).and_then(|mut r| {
                r.u32("a")?;
                r.string("s")?;
                r.f64("x")
            });
            let e = result.unwrap_err();
            assert!(e.offset <= cut.max(HEADER), "{cut}: {e}");
        }
    }

    #[test]
    fn lengths_from_the_data_are_checked_before_use() {
        let mut bytes = vec![0, 1, 0, 0];
        bytes.extend(u32::MAX.to_le_bytes());
        bytes.extend(b"abc\0");
        let e = CdrReader::new(&bytes)
            .unwrap()
            .string("frame_id")
            .unwrap_err();
        assert!(e.message.contains("claims 4294967295"), "{e}");
        let e = CdrReader::new(&bytes)
            .unwrap()
            .sequence_len("transforms", 72)
            .unwrap_err();
        assert!(e.message.contains("transforms"), "{e}");
        // Not NUL-terminated, not UTF-8, not plain CDR.
        let mut b = vec![0, 1, 0, 0, 2, 0, 0, 0];
        b.extend(b"ab");
        assert!(CdrReader::new(&b).unwrap().string("s").is_err());
        let mut b = vec![0, 1, 0, 0, 2, 0, 0, 0];
        b.extend([0xff, 0]);
        assert!(CdrReader::new(&b).unwrap().string("s").is_err());
        assert!(CdrReader::new(&[0, 3, 0, 0]).is_err());
        // The empty string (length 0) and "" (length 1) both read as "".
        let b = [0, 1, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0];
        let mut r = CdrReader::new(&b).unwrap();
        assert_eq!(r.string("a").unwrap(), "");
        assert_eq!(r.string("b").unwrap(), "");
    }
}
