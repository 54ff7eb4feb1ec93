//! Pose pairs as CSV: a header naming an optional `stamp` and 7 columns per pose,
//! `<frame>_x, _y, _z, _qx, _qy, _qz, _qw` (translation and quaternion x y z w).

use std::io::BufRead;

use crate::io::lines::{Line, Lines};
use crate::io::{
    CAMERA_FRAMES, ROBOT_FRAMES, StampedPosePair, check_stamp, parse_error, too_long, written_as,
};
use crate::model::error::{Error, Result};
use crate::model::findings::Written;
use crate::model::motion::PosePair;
use crate::model::pose::{Transform, check_translation, transform_from_xyz_quat_xyzw};

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
/// [`Error::Parse`](crate::model::error::Error::Parse) naming the file, the line and the column, after which
/// the next row is read. Blank lines and lines starting with `#` are skipped.
pub struct CsvPairs<R: BufRead> {
    lines: Lines<R>,
    source: String,
    header: Vec<String>,
    stamp: Option<usize>,
    robot: PoseColumns,
    camera: PoseColumns,
    record: Vec<String>,
}

/// The fields of one line read as a CSV record (quotes allowed within the line, trimmed), or why
/// not. Each line is read on its own, so that a stray quote costs its line only.
fn split_line(line: &[u8]) -> std::result::Result<csv::ByteRecord, csv::Error> {
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .trim(csv::Trim::All)
        .buffer_capacity(line.len() + 1)
        .from_reader(line);
    let mut record = csv::ByteRecord::new();
    reader.read_byte_record(&mut record)?;
    Ok(record)
}

impl<R: BufRead> CsvPairs<R> {
    /// Reads the header of `input` (named `source` in messages) and finds the pose columns.
    #[cfg(test)]
    pub fn new(input: R, source: &str) -> Result<Self> {
        Self::from_lines(Lines::new(input), source)
    }

    /// As [`CsvPairs::new`], going on from `lines`: the header is the next line that is neither
    /// blank nor a `#` comment.
    pub(crate) fn from_lines(mut lines: Lines<R>, source: &str) -> Result<Self> {
        let (header_line, names) = loop {
            let (number, line) = match lines.next_line() {
                None => {
                    return Err(parse_error(
                        source,
                        1,
                        "-",
                        "cannot read the CSV header: the input is empty",
                    ));
                }
                Some(Err(e)) => {
                    return Err(Error::Io {
                        file: source.to_string(),
                        source: e,
                    });
                }
                Some(Ok(l)) => l,
            };
            let text = match line {
                Line::TooLong => return Err(too_long(source, number)),
                Line::Text(t) => t,
            };
            match text.iter().find(|b| !b.is_ascii_whitespace()) {
                None | Some(b'#') => continue,
                Some(_) => {}
            }
            let record = split_line(text).map_err(|e| {
                parse_error(
                    source,
                    number,
                    "-",
                    format!("cannot read the CSV header: {e}"),
                )
            })?;
            let names = record
                .iter()
                .map(|f| String::from_utf8(f.to_vec()))
                .collect::<std::result::Result<Vec<String>, _>>()
                .map_err(|_| {
                    parse_error(
                        source,
                        number,
                        "-",
                        "cannot read the CSV header: not valid UTF-8 text",
                    )
                })?;
            break (number, names);
        };
        let names: Vec<&str> = names.iter().map(String::as_str).collect();
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
            header: names.iter().map(|n| n.to_string()).collect(),
            stamp,
            robot,
            camera,
            record: Vec::new(),
            lines,
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
            written: Written {
                robot: written_as(self.robot.inverted),
                camera: written_as(self.camera.inverted),
                frames: false,
            },
        })
    }

    fn number(&self, column: usize, field: &str, line: usize) -> Result<f64> {
        let text = self.record.get(column).map_or("", String::as_str);
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
        loop {
            // A failing input (a directory, a broken pipe) would fail again: the line reader
            // ends after its error.
            let (number, text) = match self.lines.next_record(&self.source)? {
                Ok(record) => record,
                Err(e) => return Some(Err(e)),
            };
            match text.iter().find(|b| !b.is_ascii_whitespace()) {
                None | Some(b'#') => continue,
                Some(_) => {}
            }
            let fields = match split_line(text) {
                Ok(f) => f,
                Err(e) => {
                    return Some(Err(parse_error(
                        &self.source,
                        number,
                        "-",
                        format!("not a CSV record: {e}"),
                    )));
                }
            };
            if fields.len() != self.header.len() {
                return Some(Err(parse_error(
                    &self.source,
                    number,
                    "-",
                    format!(
                        "{} columns where the header has {}",
                        fields.len(),
                        self.header.len()
                    ),
                )));
            }
            self.record.clear();
            for (k, f) in fields.iter().enumerate() {
                match std::str::from_utf8(f) {
                    Ok(t) => self.record.push(t.to_string()),
                    Err(_) => {
                        return Some(Err(parse_error(
                            &self.source,
                            number,
                            self.header[k].clone(),
                            "not valid UTF-8 text",
                        )));
                    }
                }
            }
            return Some(self.parse(number));
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
