//! Pose pairs as CSV: a header naming an optional `stamp` and 7 columns per pose,
//! `<frame>_x, _y, _z, _qx, _qy, _qz, _qw` (translation and quaternion x y z w).

use std::io::BufRead;

use crate::error::Result;
use crate::io::{CAMERA_FRAMES, ROBOT_FRAMES, StampedPosePair, parse_error};
use crate::motion::PosePair;
use crate::pose::{Transform, transform_from_xyz_quat_xyzw};

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
pub struct CsvPairs<R: BufRead> {
    reader: csv::Reader<R>,
    source: String,
    stamp: Option<usize>,
    robot: PoseColumns,
    camera: PoseColumns,
    record: csv::StringRecord,
}

impl<R: BufRead> CsvPairs<R> {
    /// Reads the header of `input` (named `source` in messages) and finds the pose columns.
    pub fn new(input: R, source: &str) -> Result<Self> {
        let mut reader = csv::ReaderBuilder::new()
            .trim(csv::Trim::All)
            .comment(Some(b'#'))
            .from_reader(input);
        let header = reader
            .headers()
            .map_err(|e| parse_error(source, 1, "-", format!("cannot read the CSV header: {e}")))?
            .clone();
        let names: Vec<&str> = header.iter().collect();
        let known = |n: &str| {
            n == "stamp"
                || ROBOT_FRAMES
                    .iter()
                    .chain(&CAMERA_FRAMES)
                    .any(|(f, _)| SUFFIXES.iter().any(|s| n == format!("{f}_{s}")))
        };
        if let Some(unknown) = names.iter().find(|n| !known(n)) {
            return Err(parse_error(
                source,
                1,
                *unknown,
                "unknown column: expected `stamp` and `<frame>_x … <frame>_qw` with frame base_from_gripper, gripper_from_base, camera_from_target or target_from_camera",
            ));
        }
        let stamp = names.iter().position(|n| *n == "stamp");
        let robot = pose_columns(&names, &ROBOT_FRAMES, source)?;
        let camera = pose_columns(&names, &CAMERA_FRAMES, source)?;
        Ok(Self {
            reader,
            source: source.to_string(),
            stamp,
            robot,
            camera,
            record: csv::StringRecord::new(),
        })
    }

    fn parse(&self, line: usize) -> Result<StampedPosePair> {
        let stamp = self
            .stamp
            .map(|k| self.number(k, "stamp", line))
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
            v[k] = self.number(*c, &format!("{}_{s}", p.name), line)?;
        }
        let t = transform_from_xyz_quat_xyzw([v[0], v[1], v[2]], [v[3], v[4], v[5], v[6]])
            .map_err(|e| parse_error(&self.source, line, format!("{}_q", p.name), e.to_string()))?;
        Ok(if p.inverted { t.inverse() } else { t })
    }
}

/// Finds the 7 columns of exactly one of two alternative frame names.
fn pose_columns(
    names: &[&str],
    frames: &[(&'static str, bool); 2],
    source: &str,
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
                        1,
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
            1,
            format!("{}_x", frames[0].0),
            format!(
                "missing: give the `{}_*` or `{}_*` columns",
                frames[0].0, frames[1].0
            ),
        )),
        _ => Err(parse_error(
            source,
            1,
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
        let mut record = std::mem::take(&mut self.record);
        let outcome = self.reader.read_record(&mut record);
        self.record = record;
        let line = self.record.position().map_or(0, |p| p.line() as usize);
        match outcome {
            Ok(false) => None,
            Ok(true) => Some(self.parse(line)),
            Err(e) => {
                let line = e.position().map_or(line, |p| p.line() as usize);
                let message = match e.kind() {
                    csv::ErrorKind::UnequalLengths {
                        expected_len, len, ..
                    } => {
                        format!("{len} columns where the header has {expected_len}")
                    }
                    _ => e.to_string(),
                };
                Some(Err(parse_error(&self.source, line, "-", message)))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::Error;

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
            (5, "base_from_gripper_q".to_string())
        );
        assert_eq!(
            field_of(r[4].as_ref().unwrap_err()),
            (6, "target_from_camera_qw".to_string())
        );
    }

    #[test]
    fn bad_headers_are_refused() {
        let e = read("stamp,foo\n").err().unwrap();
        assert_eq!(field_of(&e), (1, "foo".to_string()));
        let missing = HEADER.replace(",base_from_gripper_qw", "");
        let e = read(&format!("{missing}\n")).err().unwrap();
        assert_eq!(field_of(&e), (1, "base_from_gripper_qw".to_string()));
    }
}
