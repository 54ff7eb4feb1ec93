//! Pose pairs as CSV: a header naming an optional `stamp` and 7 columns per pose,
//! `<frame>_x, _y, _z, _qx, _qy, _qz, _qw` (translation and quaternion x y z w).

use std::io::BufRead;

use crate::error::{Error, Result};
use crate::io::{CAMERA_FRAMES, ROBOT_FRAMES, StampedPosePair, check_stamp, parse_error};
use crate::motion::PosePair;
use crate::pose::{Transform, check_translation, transform_from_xyz_quat_xyzw};

/// The column suffixes of one pose, in order.
const SUFFIXES: [&str; 7] = ["x", "y", "z", "qx", "qy", "qz", "qw"];

/// Where a pose's columns are, and whether the file's direction is the inverse of ours.
#[derive(Debug, Clone)]
struct PoseColumns {
    name: &'static str,
    columns: [usize; 7],
    inverted: bool,
}

/// Streaming reader of CSV pose pairs.
///
/// The header names an optional `stamp` (seconds) and the 7 columns of exactly one robot pose
/// (`base_from_gripper` or `gripper_from_base`) and exactly one camera pose (`camera_from_target`
/// or `target_from_camera`), in any order; any other column is refused. Rows are yielded one at
/// a time in our directions (Q = `base_from_gripper`, `camera_from_target`), or as an
/// [`Error::Parse`](crate::Error::Parse) naming the file, the line and the column, after which
/// the next row is read. Blank lines and lines starting with `#` are skipped.
pub struct CsvPairs<R: BufRead> {
    reader: csv::Reader<CommentsAsBlank<R>>,
    source: String,
    /// Lines consumed before the reader started, added to the CSV reader's line numbers.
    line_offset: usize,
    header: Vec<String>,
    stamp: Option<usize>,
    robot: PoseColumns,
    camera: PoseColumns,
    record: csv::StringRecord,
    finished: bool,
}

impl<R: BufRead> CsvPairs<R> {
    /// Reads the header of `input` (named `source` in messages) and finds the pose columns.
    pub fn new(input: R, source: &str) -> Result<Self> {
        Self::after_lines(input, source, 0)
    }

    /// As [`CsvPairs::new`] for an input whose first `lines` lines have already been consumed:
    /// line numbers go on from there.
    pub(crate) fn after_lines(input: R, source: &str, lines: usize) -> Result<Self> {
        let mut reader = csv::ReaderBuilder::new()
            .trim(csv::Trim::All)
            .from_reader(CommentsAsBlank::new(input));
        let header = reader.headers().cloned();
        // The csv crate reports the header at line 1 whatever precedes it.
        let header_line = lines + reader.get_ref().first_content_line.unwrap_or(1);
        let header = header.map_err(|e| {
            parse_error(
                source,
                header_line,
                "-",
                format!("cannot read the CSV header: {e}"),
            )
        })?;
        let names: Vec<&str> = header.iter().collect();
        let known = |n: &str| {
            n == "stamp"
                || ROBOT_FRAMES
                    .iter()
                    .chain(&CAMERA_FRAMES)
                    .any(|(f, _)| SUFFIXES.iter().any(|s| n == format!("{f}_{s}")))
        };
        if let Some(k) = names.iter().position(|n| !known(n)) {
            let field = match names[k] {
                "" => format!("column {}", k + 1),
                name => name.to_string(),
            };
            return Err(parse_error(
                source,
                header_line,
                field,
                "unknown column: expected `stamp` and `<frame>_x … <frame>_qw` with frame base_from_gripper, gripper_from_base, camera_from_target or target_from_camera",
            ));
        }
        if let Some((k, twice)) = names
            .iter()
            .enumerate()
            .find(|(k, n)| names[..*k].contains(n))
        {
            return Err(parse_error(
                source,
                header_line,
                *twice,
                format!(
                    "column given twice (columns {} and {})",
                    names[..k]
                        .iter()
                        .position(|n| n == twice)
                        .map_or(0, |p| p + 1),
                    k + 1
                ),
            ));
        }
        let stamp = names.iter().position(|n| *n == "stamp");
        let robot = pose_columns(&names, &ROBOT_FRAMES, source, header_line)?;
        let camera = pose_columns(&names, &CAMERA_FRAMES, source, header_line)?;
        Ok(Self {
            source: source.to_string(),
            line_offset: lines,
            header: names.iter().map(|n| n.to_string()).collect(),
            stamp,
            robot,
            camera,
            record: csv::StringRecord::new(),
            finished: false,
            reader,
        })
    }

    fn parse(&self, line: usize) -> Result<StampedPosePair> {
        let stamp = self
            .stamp
            .map(|k| {
                let v = self.number(k, "stamp", line)?;
                check_stamp(v).map_err(|m| parse_error(&self.source, line, "stamp", m))
            })
            .transpose()?;
        let base_from_gripper = self.pose(&self.robot, line)?;
        let camera_from_target = self.pose(&self.camera, line)?;
        Ok(StampedPosePair {
            line,
            stamp,
            pose: PosePair {
                base_from_gripper,
                camera_from_target,
            },
        })
    }

    fn number(&self, column: usize, field: &str, line: usize) -> Result<f64> {
        let text = self.record.get(column).unwrap_or("");
        text.parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| {
                parse_error(
                    &self.source,
                    line,
                    field,
                    format!("expected a finite number, found `{text}`"),
                )
            })
    }

    fn pose(&self, p: &PoseColumns, line: usize) -> Result<Transform> {
        let mut v = [0.0; 7];
        for (k, (c, s)) in p.columns.iter().zip(SUFFIXES).enumerate() {
            let field = format!("{}_{s}", p.name);
            v[k] = self.number(*c, &field, line)?;
            if k < 3 {
                check_translation(v[k])
                    .map_err(|e| parse_error(&self.source, line, field, e.to_string()))?;
            }
        }
        let t = transform_from_xyz_quat_xyzw([v[0], v[1], v[2]], [v[3], v[4], v[5], v[6]])
            .map_err(|e| {
                parse_error(
                    &self.source,
                    line,
                    format!("{}_qx..qw", p.name),
                    e.to_string(),
                )
            })?;
        Ok(if p.inverted { t.inverse() } else { t })
    }
}

/// An input whose `#` comment lines are turned into blank lines (which the csv reader skips),
/// passed on one line per read and counted.
///
/// One line per read keeps the reader streaming (a record is yielded as soon as its line has
/// arrived) and makes [`CommentsAsBlank::lines`] the line number of the record just read: the
/// csv crate's own positions are wrong after comment or blank lines and with CRLF endings.
struct CommentsAsBlank<R> {
    input: R,
    line: Vec<u8>,
    /// Bytes of `line` already handed out.
    given: usize,
    /// Lines read so far.
    lines: usize,
    /// The number of the first line that is neither blank nor a comment: the header's.
    first_content_line: Option<usize>,
}

impl<R: BufRead> CommentsAsBlank<R> {
    fn new(input: R) -> Self {
        Self {
            input,
            line: Vec::new(),
            given: 0,
            lines: 0,
            first_content_line: None,
        }
    }
}

impl<R: BufRead> std::io::Read for CommentsAsBlank<R> {
    fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
        if self.given >= self.line.len() {
            self.line.clear();
            self.given = 0;
            if self.input.read_until(b'\n', &mut self.line)? == 0 {
                return Ok(0);
            }
            self.lines += 1;
            match self.line.iter().find(|b| !b.is_ascii_whitespace()) {
                Some(b'#') => {
                    self.line.clear();
                    self.line.push(b'\n');
                }
                Some(_) if self.first_content_line.is_none() => {
                    self.first_content_line = Some(self.lines);
                }
                _ => {}
            }
        }
        let n = out.len().min(self.line.len() - self.given);
        out[..n].copy_from_slice(&self.line[self.given..self.given + n]);
        self.given += n;
        Ok(n)
    }
}

/// Finds the 7 columns of exactly one of two alternative frame names.
fn pose_columns(
    names: &[&str],
    frames: &[(&'static str, bool); 2],
    source: &str,
    header_line: usize,
) -> Result<PoseColumns> {
    let mut found = Vec::new();
    for &(frame, inverted) in frames {
        let columns: Vec<Option<usize>> = SUFFIXES
            .iter()
            .map(|s| names.iter().position(|n| *n == format!("{frame}_{s}")))
            .collect();
        if columns.iter().any(Option::is_some) {
            let mut out = [0; 7];
            for (k, c) in columns.iter().enumerate() {
                out[k] = c.ok_or_else(|| {
                    parse_error(
                        source,
                        header_line,
                        format!("{frame}_{}", SUFFIXES[k]),
                        "missing column",
                    )
                })?;
            }
            found.push(PoseColumns {
                name: frame,
                columns: out,
                inverted,
            });
        }
    }
    match found.len() {
        1 => Ok(found.remove(0)),
        0 => Err(parse_error(
            source,
            header_line,
            format!("{}_x", frames[0].0),
            format!(
                "missing: give the `{}_*` or `{}_*` columns",
                frames[0].0, frames[1].0
            ),
        )),
        _ => Err(parse_error(
            source,
            header_line,
            frames[0].0,
            format!(
                "both `{}_*` and `{}_*` columns given: give one",
                frames[0].0, frames[1].0
            ),
        )),
    }
}

impl<R: BufRead> Iterator for CsvPairs<R> {
    type Item = Result<StampedPosePair>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.finished {
            return None;
        }
        let mut record = std::mem::take(&mut self.record);
        let outcome = self.reader.read_record(&mut record);
        self.record = record;
        // The input is handed to the csv reader one line per read, so the last line read is the
        // record's (the csv crate's own line numbers go wrong after blank lines and with CRLF).
        let line = self.line_offset + self.reader.get_ref().lines;
        match outcome {
            Ok(false) => {
                self.finished = true;
                None
            }
            Ok(true) => Some(self.parse(line)),
            Err(e) => {
                let (field, message) = match e.kind() {
                    csv::ErrorKind::UnequalLengths {
                        expected_len, len, ..
                    } => (
                        "-".to_string(),
                        format!("{len} columns where the header has {expected_len}"),
                    ),
                    csv::ErrorKind::Utf8 { err, .. } => (
                        self.header
                            .get(err.field())
                            .cloned()
                            .unwrap_or_else(|| "-".to_string()),
                        "not valid UTF-8 text".to_string(),
                    ),
                    csv::ErrorKind::Io(io) => {
                        // A failing input would fail again: stop here.
                        self.finished = true;
                        return Some(Err(Error::Io {
                            file: self.source.clone(),
                            source: std::io::Error::new(io.kind(), io.to_string()),
                        }));
                    }
                    _ => ("-".to_string(), e.to_string()),
                };
                Some(Err(parse_error(&self.source, line, field, message)))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEADER: &str = "stamp,base_from_gripper_x,base_from_gripper_y,base_from_gripper_z,base_from_gripper_qx,base_from_gripper_qy,base_from_gripper_qz,base_from_gripper_qw,target_from_camera_x,target_from_camera_y,target_from_camera_z,target_from_camera_qx,target_from_camera_qy,target_from_camera_qz,target_from_camera_qw";

    fn read(text: &str) -> Result<Vec<Result<StampedPosePair>>> {
        Ok(CsvPairs::new(text.as_bytes(), "p.csv")?.collect())
    }

    #[test]
    fn reads_rows() {
        let text =
            format!("{HEADER}\n0.5,1,2,3,0,0,0,1,0,0,1,0,0,0,1\n1.0,1,2,3,0,0,0,1,0,0,2,0,0,0,1\n");
        let r = read(&text).unwrap();
        let first = r[0].as_ref().unwrap();
        assert_eq!(first.stamp, Some(0.5));
        assert_eq!(first.line, 2);
        // target_from_camera inverted: camera_from_target translation −1 in z.
        assert_eq!(first.pose.camera_from_target.translation.vector.z, -1.0);
        assert_eq!(r.len(), 2);
    }

    fn field_of(e: &Error) -> (usize, String) {
        match e {
            Error::Parse {
                line, field, file, ..
            } => {
                assert_eq!(file, "p.csv");
                (*line, field.clone())
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn bad_rows_name_line_and_field() {
        let text = format!(
            "{HEADER}\n0.5,1,2,3,0,0,0,1,0,0,1,0,0,0,1\n0.6,1,2,3,0,0,0,1,0,0,1,0,0,0\n0.7,1,2,x,0,0,0,1,0,0,1,0,0,0,1\n0.8,1,2,3,0,0,0,2,0,0,1,0,0,0,1\n0.9,1,2,3,0,0,0,1,0,0,1,0,0,0,NaN\n"
        );
        let r = read(&text).unwrap();
        assert!(r[0].is_ok());
        assert_eq!(field_of(r[1].as_ref().unwrap_err()), (3, "-".to_string()));
        assert_eq!(
            field_of(r[2].as_ref().unwrap_err()),
            (4, "base_from_gripper_z".to_string())
        );
        assert_eq!(
            field_of(r[3].as_ref().unwrap_err()),
            (5, "base_from_gripper_qx..qw".to_string())
        );
        assert_eq!(
            field_of(r[4].as_ref().unwrap_err()),
            (6, "target_from_camera_qw".to_string())
        );
    }

    #[test]
    fn line_numbers_count_blank_comment_and_crlf_lines() {
        let text = format!(
            "# recorded by hand\r\n\r\n{HEADER}\r\n0.5,1,2,3,0,0,0,1,0,0,1,0,0,0,1\r\n\r\n# pause\r\n  # indented\r\n1.0,1,2,3,0,0,0,1,0,0,1,0,0,0,1\r\n1.5,1,2,3,0,0,0,1,0,0,1,0,0,0"
        );
        let r = read(&text).unwrap();
        assert_eq!(r.len(), 3);
        assert_eq!(r[0].as_ref().unwrap().line, 4);
        assert_eq!(r[1].as_ref().unwrap().line, 8);
        // The last line, without its line end, is one column short.
        assert_eq!(field_of(r[2].as_ref().unwrap_err()), (9, "-".to_string()));
    }

    #[test]
    fn bad_headers_are_refused() {
        let e = read("stamp,foo\n").err().unwrap();
        assert_eq!(field_of(&e), (1, "foo".to_string()));
        let missing = HEADER.replace(",base_from_gripper_qw", "");
        let e = read(&format!("{missing}\n")).err().unwrap();
        assert_eq!(field_of(&e), (1, "base_from_gripper_qw".to_string()));
        let e = read(&format!("# comment\n\n{HEADER},stamp\n"))
            .err()
            .unwrap();
        assert_eq!(field_of(&e), (3, "stamp".to_string()));
        let both = format!(
            "{HEADER},{}",
            HEADER
                .replace("target_from", "camera_from")
                .replace("from_camera", "from_target")
                .split(',')
                .skip(8)
                .collect::<Vec<_>>()
                .join(",")
        );
        let e = read(&format!("{both}\n")).err().unwrap();
        assert_eq!(field_of(&e), (1, "camera_from_target".to_string()));
        let no_camera: Vec<&str> = HEADER.split(',').take(8).collect();
        let e = read(&format!("{}\n", no_camera.join(","))).err().unwrap();
        assert_eq!(field_of(&e), (1, "camera_from_target_x".to_string()));
        assert!(read("").is_err());
    }
}
