//! Pose pairs as CSV: a header naming an optional `stamp` and the columns of each pose,
//! `<frame>_x, _y, _z` and the rotation's: `_qx, _qy, _qz, _qw` (a quaternion x y z w), or, with
//! its convention named ([`Rotations`]), that convention's components (`_a, _b, _c` for KUKA
//! A, B, C, …: [`RotationConvention::components`]).

use std::io::BufRead;

use crate::io::lines::{Line, Lines};
use crate::io::{
    CAMERA_FRAMES, Conventions, DegreeAngles, ROBOT_FRAMES, StampedPosePair, check_stamp,
    parse_error, too_long, written_as,
};
use crate::model::error::{Error, Result};
use crate::model::findings::Written;
use crate::model::motion::PosePair;
use crate::model::pose::{Transform, check_translation, transform_from_parts};
use crate::model::rotation::{RotationConvention, Rotations};
use nalgebra::Vector3;

/// The column suffixes of a pose's translation, in order.
const TRANSLATION: [&str; 3] = ["x", "y", "z"];

/// Whether `suffix` is a column suffix of some pose: a translation's or some rotation
/// convention's component.
fn known_suffix(suffix: &str) -> bool {
    TRANSLATION.contains(&suffix)
        || RotationConvention::ALL
            .iter()
            .any(|c| c.components().contains(&suffix))
}

/// Where a pose's columns are (translation, then the rotation's components), in which rotation
/// convention, and whether the file's direction is the inverse of ours.
#[derive(Debug, Clone)]
struct PoseColumns {
    name: &'static str,
    translation: [usize; 3],
    rotation: Vec<usize>,
    convention: RotationConvention,
    /// The convention the rotation's numbers are read as (`convention`, unless a check reads
    /// them as another).
    read_as: RotationConvention,
    inverted: bool,
}

/// Streaming reader of CSV pose pairs.
///
/// The header names an optional `stamp` (seconds) and the columns of exactly one robot pose
/// (`base_from_gripper` or `gripper_from_base`) and exactly one camera pose (`camera_from_target`
/// or `target_from_camera`), in any order; any other column is refused. A pose's rotation columns
/// are those of its side's convention in [`Rotations`] (`_qx … _qw` when none is named); three
/// angles cannot tell their convention, so columns of one are refused until it is named. Rows are
/// yielded one at a time in our directions (Q = `base_from_gripper`, `camera_from_target`), or as
/// an [`Error::Parse`](crate::model::error::Error::Parse) naming the file, the line and the column,
/// after which the next row is read. Blank lines and lines starting with `#` are skipped.
pub struct CsvPairs<R: BufRead> {
    lines: Lines<R>,
    source: String,
    header: Vec<String>,
    stamp: Option<usize>,
    robot: PoseColumns,
    camera: PoseColumns,
    record: Vec<String>,
    degrees: DegreeAngles,
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
        Self::from_lines(Lines::new(input), source, Conventions::default())
    }

    /// As [`CsvPairs::new`], going on from `lines` (the header is the next line that is neither
    /// blank nor a `#` comment), each side's rotation in the convention `conventions` names (and
    /// read as it says).
    pub(crate) fn from_lines(
        mut lines: Lines<R>,
        source: &str,
        conventions: Conventions,
    ) -> Result<Self> {
        let rotations = conventions.named;
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
                || ROBOT_FRAMES.iter().chain(&CAMERA_FRAMES).any(|(f, _)| {
                    n.strip_prefix(f)
                        .and_then(|n| n.strip_prefix('_'))
                        .is_some_and(known_suffix)
                })
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
                "unknown column: expected `stamp` and `<frame>_x, _y, _z` with the rotation's columns (`<frame>_qx … _qw`, or those of the convention named by `--rotation`) with frame base_from_gripper, gripper_from_base, camera_from_target or target_from_camera",
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
        let header = (source, header_line);
        let mut robot = pose_columns(&names, (&ROBOT_FRAMES, true), rotations.robot, header)?;
        let mut camera = pose_columns(&names, (&CAMERA_FRAMES, false), rotations.camera, header)?;
        robot.read_as = conventions.read_as(true, robot.convention);
        camera.read_as = conventions.read_as(false, camera.convention);
        Ok(Self {
            source: source.to_string(),
            header: names.iter().map(|n| n.to_string()).collect(),
            stamp,
            robot,
            camera,
            record: Vec::new(),
            lines,
            degrees: DegreeAngles::default(),
        })
    }

    /// The largest angles in degrees read so far (see [`DegreeAngles`]).
    pub fn degree_angles(&self) -> DegreeAngles {
        self.degrees
    }

    fn parse(&mut self, line: usize) -> Result<StampedPosePair> {
        let stamp = self
            .stamp
            .map(|k| {
                let v = self.number(k, "stamp", line)?;
                check_stamp(v).map_err(|m| parse_error(&self.source, line, "stamp", m))
            })
            .transpose()?;
        let (base_from_gripper, robot_degrees) = self.pose(&self.robot, line)?;
        let (camera_from_target, camera_degrees) = self.pose(&self.camera, line)?;
        self.degrees.add(true, robot_degrees);
        self.degrees.add(false, camera_degrees);
        Ok(StampedPosePair::new(
            line,
            stamp,
            PosePair {
                base_from_gripper,
                camera_from_target,
            },
            Written {
                robot: written_as(self.robot.inverted),
                camera: written_as(self.camera.inverted),
                frames: false,
            },
        ))
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

    /// The pose of `p`'s columns on this line, with its largest angle when they are degrees.
    fn pose(&self, p: &PoseColumns, line: usize) -> Result<(Transform, Option<f64>)> {
        let mut t = [0.0; 3];
        for (k, (c, s)) in p.translation.iter().zip(TRANSLATION).enumerate() {
            let field = format!("{}_{s}", p.name);
            t[k] = self.number(*c, &field, line)?;
            check_translation(t[k])
                .map_err(|e| parse_error(&self.source, line, field, e.to_string()))?;
        }
        let components = p.convention.components();
        let values = p
            .rotation
            .iter()
            .zip(components)
            .map(|(c, s)| self.number(*c, &format!("{}_{s}", p.name), line))
            .collect::<Result<Vec<f64>>>()?;
        let r = p.read_as.rotation(&values).map_err(|e| {
            let field = match e.component {
                Some(k) => format!("{}_{}", p.name, components[k]),
                None => format!(
                    "{}_{}..{}",
                    p.name,
                    components[0],
                    components[components.len() - 1]
                ),
            };
            parse_error(&self.source, line, field, e.message)
        })?;
        let t = transform_from_parts(&r, &Vector3::from(t));
        let degrees = p
            .read_as
            .in_degrees()
            .then(|| values.iter().fold(0.0f64, |m, v| m.max(v.abs())));
        Ok((if p.inverted { t.inverse() } else { t }, degrees))
    }
}

/// The columns `<frame>_<suffix>` of `names` for each suffix, `None` where missing.
fn columns_of(names: &[&str], frame: &str, suffixes: &[&str]) -> Vec<Option<usize>> {
    suffixes
        .iter()
        .map(|s| names.iter().position(|n| *n == format!("{frame}_{s}")))
        .collect()
}

/// The columns of one pose given under `frame`, its rotation's in the convention `named` (a
/// quaternion `_qx … _qw` when none is); the problem (field and message) when they are not there.
fn frame_columns(
    names: &[&str],
    (frame, inverted): (&'static str, bool),
    named: Option<RotationConvention>,
    robot: bool,
) -> std::result::Result<PoseColumns, (String, String)> {
    let convention = named.unwrap_or(RotationConvention::QuaternionXyzw);
    let given: Vec<&str> = names
        .iter()
        .filter_map(|n| n.strip_prefix(frame)?.strip_prefix('_'))
        .filter(|s| !TRANSLATION.contains(s))
        .collect();
    let column = |s: &str| format!("{frame}_{s}");
    let list = |c: RotationConvention| {
        let parts = c.components();
        format!("`{}`, `_{}`", column(parts[0]), parts[1..].join("`, `_"))
    };
    let translation = columns_of(names, frame, &TRANSLATION);
    if let Some(k) = translation.iter().position(Option::is_none) {
        return Err((column(TRANSLATION[k]), "missing column".into()));
    }
    let rotation = columns_of(names, frame, convention.components());
    let exact = rotation.iter().all(Option::is_some) && given.len() == rotation.len();
    if !exact {
        let candidates = RotationConvention::with_components(&given);
        let side = if robot { "robot" } else { "camera" };
        if !candidates.is_empty() && !candidates.contains(&convention) {
            let first = column(candidates[0].components()[0]);
            let message = match named {
                None if candidates == [RotationConvention::QuaternionWxyz] => format!(
                    "columns {} are a quaternion w first (ABB's q1 … q4) only when named so: {} (`robot=` or `camera=` for these poses only); a header of `_qx, _qy, _qz, _qw` needs no name",
                    list(candidates[0]),
                    Rotations::flag(RotationConvention::QuaternionWxyz, None),
                ),
                None => format!(
                    "columns {} cannot tell their rotation convention ({}): name it, {} (`{side}=NAME` for these poses only)",
                    list(candidates[0]),
                    candidates
                        .iter()
                        .map(|c| format!("{}: {}", c.name(), c.describe()))
                        .collect::<Vec<_>>()
                        .join("; or "),
                    candidates
                        .iter()
                        .map(|&c| Rotations::flag(c, None))
                        .collect::<Vec<_>>()
                        .join(" or "),
                ),
                Some(named) => format!(
                    "columns {} are {} ({}), and the rotations of these poses are named {}, which reads {}: name the convention the file uses, or give its columns",
                    list(candidates[0]),
                    candidates
                        .iter()
                        .map(|c| c.describe())
                        .collect::<Vec<_>>()
                        .join(", or "),
                    candidates
                        .iter()
                        .map(|c| c.name())
                        .collect::<Vec<_>>()
                        .join(" or "),
                    named.name(),
                    list(named),
                ),
            };
            return Err((first, message));
        }
        let in_named = |message: &str| match named {
            None => message.to_string(),
            Some(named) => format!("{message}: {} reads {}", named.name(), list(named)),
        };
        if let Some(k) = rotation.iter().position(Option::is_none) {
            return Err((
                column(convention.components()[k]),
                in_named("missing column"),
            ));
        }
        let extra = given
            .iter()
            .find(|s| !convention.components().contains(s))
            .map_or_else(|| column("?"), |s| column(s));
        return Err((extra, in_named("not a column of this pose's rotation")));
    }
    Ok(PoseColumns {
        name: frame,
        translation: [
            translation[0].unwrap_or(0),
            translation[1].unwrap_or(0),
            translation[2].unwrap_or(0),
        ],
        rotation: rotation.into_iter().flatten().collect(),
        convention,
        read_as: convention,
        inverted,
    })
}

/// Finds the columns of exactly one of two alternative frame names (the robot's when `robot`),
/// the rotation's in the convention `named`.
fn pose_columns(
    names: &[&str],
    (frames, robot): (&[(&'static str, bool); 2], bool),
    named: Option<RotationConvention>,
    (source, header_line): (&str, usize),
) -> Result<PoseColumns> {
    let mut found = Vec::new();
    for &frame in frames {
        let given = names
            .iter()
            .any(|n| n.strip_prefix(frame.0).is_some_and(|n| n.starts_with('_')));
        if given {
            found.push(
                frame_columns(names, frame, named, robot)
                    .map_err(|(field, message)| parse_error(source, header_line, field, message))?,
            );
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
