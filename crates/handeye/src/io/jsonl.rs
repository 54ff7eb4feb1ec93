//! Pose pairs as JSON Lines: one object per line with a robot pose, a camera pose and an optional
//! `stamp`.

use std::io::BufRead;

use serde_json::{Map, Value};

use crate::io::json_text::repeated_key;
use crate::io::jsonl_fast::scan;
use crate::io::lines::Lines;
use crate::io::transform::TransformNumbers;
use crate::io::transform::read_transform_json_as;
use crate::io::{
    CAMERA_FRAMES, Conventions, DegreeAngles, Projections, ROBOT_FRAMES, StampedPosePair,
    check_stamp, parse_error, written_as,
};
use crate::model::camera::{Detections, Frame, MIN_DETECTIONS};
use crate::model::error::{Error, Result};
use crate::model::findings::{Written, WrittenAs};
use crate::model::kinematics::MAX_JOINTS;
use crate::model::motion::PosePair;
use crate::model::pose::ReadTransform;
use crate::model::rotation::{RotationConvention, Rotations};
use crate::model::warning::Remedy;

/// Streaming reader of JSON Lines pose pairs (blank lines and `#` comments are skipped).
///
/// Yields one [`StampedPosePair`] per record as soon as its line has been read, or an
/// [`crate::model::error::Error::Parse`] naming the file, the line (from 1) and the field of a bad record, and then goes
/// on with the next line. A read error of the input itself ([`crate::model::error::Error::Io`]) ends the iteration.
pub struct JsonlPairs<R: BufRead> {
    lines: Lines<R>,
    source: String,
    projections: Projections,
    conventions: Conventions,
    degrees: DegreeAngles,
    /// How many joint angles the first record gave (0: none), and its line: every later record
    /// gives as many.
    first_joints: Option<(usize, usize)>,
}

impl<R: BufRead> JsonlPairs<R> {
    /// A reader of `input`, named `source` in messages.
    #[cfg(test)]
    pub fn new(input: R, source: &str) -> Self {
        Self::from_lines(Lines::new(input), source, Conventions::default())
    }

    /// A reader going on from `lines`, each side's rotations in the convention `conventions`
    /// names (a rotation field of another convention is refused), or as its fields say.
    pub(crate) fn from_lines(lines: Lines<R>, source: &str, conventions: Conventions) -> Self {
        Self {
            lines,
            source: source.to_string(),
            projections: Projections::default(),
            conventions,
            degrees: DegreeAngles::default(),
            first_joints: None,
        }
    }

    /// `record` when its joint angles agree with the first record's (as many, or none when it
    /// gave none); otherwise the error naming its line and `joints`. The same rule in batch and
    /// online: the reader applies it as it reads, in one pass over any input.
    fn same_joints(&mut self, record: StampedPosePair) -> Result<StampedPosePair> {
        let (count, first) = *self
            .first_joints
            .get_or_insert((record.joint_count, record.line));
        if record.joint_count == count {
            return Ok(record);
        }
        let message = match (count, record.joint_count) {
            (0, n) => format!(
                "{n} joint angles, and the first record (line {first}) gives none: give them on every record or on none"
            ),
            (c, 0) => format!(
                "missing: the first record (line {first}) gives {c} joint angles, so every record must"
            ),
            (c, n) => format!("{n} joint angles, the first record (line {first}) gives {c}"),
        };
        Err(parse_error(&self.source, record.line, "joints", message))
    }

    /// The rotation matrices projected onto SO(3) so far (see [`Projections`]).
    pub fn projections(&self) -> Projections {
        self.projections
    }

    /// The largest angles in degrees read so far (see [`DegreeAngles`]).
    pub fn degree_angles(&self) -> DegreeAngles {
        self.degrees
    }
}

impl<R: BufRead> Iterator for JsonlPairs<R> {
    type Item = Result<StampedPosePair>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            // A failing input (a directory, a broken pipe) would fail again: the line reader
            // ends after its error.
            let (number, text) = match self.lines.next_record(&self.source)? {
                Ok(record) => record,
                Err(e) => return Some(Err(e)),
            };
            let Ok(text) = std::str::from_utf8(text) else {
                return Some(Err(parse_error(
                    &self.source,
                    number,
                    "-",
                    "the line is not valid UTF-8 text",
                )));
            };
            // The fast path reads `quaternion_xyzw` and matrices only: with another convention
            // named, every record goes the general way, which refuses a field of another one.
            let xyzw = |c: Option<RotationConvention>| {
                c.is_none_or(|c| c == RotationConvention::QuaternionXyzw)
            };
            if self.conventions.read_as == Rotations::default()
                && xyzw(self.conventions.named.robot)
                && xyzw(self.conventions.named.camera)
                && let Some(record) = fast_record(text, number, &mut self.projections)
            {
                return Some(self.same_joints(record));
            }
            let text = text.trim();
            if text.is_empty() || text.starts_with('#') {
                continue;
            }
            return Some(
                parse_record(
                    text,
                    (&self.source, number),
                    self.conventions,
                    (&mut self.projections, &mut self.degrees),
                )
                .and_then(|record| self.same_joints(record)),
            );
        }
    }
}

/// The record of a line of the common shape (see [`jsonl_fast`](crate::io::jsonl_fast)) whose
/// stamp and transforms are all valid; `None` leaves the line to [`parse_record`], which reads
/// every other line and names the problem of a bad one.
fn fast_record(text: &str, line: usize, projections: &mut Projections) -> Option<StampedPosePair> {
    // Joint angles are read by the full parser.
    if text.contains("\"joints\"") {
        return None;
    }
    let scanned = scan(text)?;
    let stamp = scanned.stamp.map(check_stamp).transpose().ok()?;
    let read = |(numbers, inverted): (TransformNumbers, bool)| {
        let read = numbers.read()?;
        Some(if inverted {
            ReadTransform {
                transform: read.transform.inverse(),
                ..read
            }
        } else {
            read
        })
    };
    let written = Written {
        robot: written_as(scanned.robot.1),
        camera: written_as(scanned.camera.1),
        frames: false,
    };
    let robot = read(scanned.robot)?;
    let camera = read(scanned.camera)?;
    projections.add(&robot);
    projections.add(&camera);
    Some(StampedPosePair::new(
        line,
        stamp,
        PosePair {
            base_from_gripper: robot.transform,
            camera_from_target: camera.transform,
        },
        written,
    ))
}

/// Parses one JSON Lines record (line number `line` of `source`): exactly one of
/// `base_from_gripper` / `gripper_from_base`, exactly one of `camera_from_target` /
/// `target_from_camera`, each a transform (SPEC sec. 7) or a bare 4×4 array, and an optional
/// numeric `stamp` in seconds. The pair is returned in our directions (Q = `base_from_gripper`,
/// `camera_from_target`), inverting what the file gives in the other direction. Other keys are
/// ignored; a key repeated in one object is refused (a JSON parser keeps only one of the two).
pub fn parse_pose_line(text: &str, source: &str, line: usize) -> Result<StampedPosePair> {
    let mut projections = Projections::default();
    match fast_record(text, line, &mut projections) {
        Some(record) => Ok(record),
        None => parse_record(
            text,
            (source, line),
            Conventions::default(),
            (&mut projections, &mut DegreeAngles::default()),
        ),
    }
}

/// The words of a JSON syntax error on a one-line record: a `NaN` or `Infinity` where it stopped
/// (Python's `json.dumps` writes them, JSON has no such number) is named as itself.
pub(crate) fn malformed(text: &str, e: &serde_json::Error) -> String {
    let at = text.get(e.column().saturating_sub(1)..).unwrap_or("");
    let word = ["NaN", "-NaN", "Infinity", "-Infinity"]
        .into_iter()
        .filter(|w| at.starts_with(w))
        .max_by_key(|w| w.len());
    match word {
        Some(w) => format!(
            "{w} at column {}: a number that is not finite (JSON has no {w}; a pose with one cannot be solved)",
            e.column()
        ),
        None => format!("malformed JSON: {e}"),
    }
}

/// One JSON Lines record as an object: malformed JSON, another value, or a key given twice is
/// refused with the line (and the repeated key's path).
pub(crate) fn json_object(text: &str, source: &str, line: usize) -> Result<Map<String, Value>> {
    let value: Value = serde_json::from_str(text)
        .map_err(|e| parse_error(source, line, "-", malformed(text, &e)))?;
    let Value::Object(object) = value else {
        return Err(parse_error(
            source,
            line,
            "-",
            "expected a JSON object per line",
        ));
    };
    if let Some(repeated) = repeated_key(text) {
        return Err(parse_error(
            source,
            line,
            repeated.path.clone(),
            repeated.message(),
        ));
    }
    Ok(object)
}

/// [`parse_pose_line`], counting the rotation matrices projected onto SO(3) into `projections`.
fn parse_record(
    text: &str,
    (source, line): (&str, usize),
    conventions: Conventions,
    (projections, degrees): (&mut Projections, &mut DegreeAngles),
) -> Result<StampedPosePair> {
    let object = json_object(text, source, line)?;
    let stamp = match object.get("stamp") {
        None | Some(Value::Null) => None,
        Some(v) => Some(
            v.as_f64()
                .ok_or_else(|| format!("expected a finite number of seconds, found {v}"))
                .and_then(check_stamp)
                .map_err(|message| parse_error(source, line, "stamp", message))?,
        ),
    };
    let (robot, robot_written) =
        frame(&object, (&ROBOT_FRAMES, true), (source, line), conventions)?;
    let (camera, camera_written) = frame(
        &object,
        (&CAMERA_FRAMES, false),
        (source, line),
        conventions,
    )?;
    projections.add(&robot);
    projections.add(&camera);
    degrees.add(true, robot.degrees);
    degrees.add(false, camera.degrees);
    let (base_from_gripper, camera_from_target) = (robot.transform, camera.transform);
    let joints = match object.get("joints") {
        None | Some(Value::Null) => Vec::new(),
        Some(v) => joint_angles(v, source, line)?,
    };
    Ok(StampedPosePair::new(
        line,
        stamp,
        PosePair {
            base_from_gripper,
            camera_from_target,
        },
        Written {
            robot: robot_written,
            camera: camera_written,
            frames: false,
        },
    )
    .with_joints(&joints))
}

/// The joint angles of one record: a non-empty list of at most
/// [`MAX_JOINTS`](crate::model::kinematics::MAX_JOINTS) finite numbers (radians).
fn joint_angles(v: &Value, source: &str, line: usize) -> Result<Vec<f64>> {
    let list = v.as_array().filter(|a| !a.is_empty()).ok_or_else(|| {
        parse_error(
            source,
            line,
            "joints",
            format!("expected a list of joint angles in radians, found {v}"),
        )
    })?;
    if list.len() > MAX_JOINTS {
        return Err(parse_error(
            source,
            line,
            "joints",
            format!(
                "{} joint angles: at most {MAX_JOINTS} (the most joints a DH table has)",
                list.len()
            ),
        ));
    }
    list.iter()
        .enumerate()
        .map(|(k, q)| {
            q.as_f64().filter(|q| q.is_finite()).ok_or_else(|| {
                parse_error(
                    source,
                    line,
                    format!("joints[{k}]"),
                    format!("expected a finite angle in radians, found {q}"),
                )
            })
        })
        .collect()
}

/// Parses one JSON Lines record of a recording on the pixels (SPEC sec. 9): a robot pose as in
/// [`parse_pose_line`], `detections: {"target": [[x, y, z], …], "pixels": [[u, v], …]}` (the same
/// count, at least [`MIN_DETECTIONS`], every number finite), and optionally the camera pose.
/// Errors name the line and the field (`detections.pixels[3][1]`). The arrays are those of the
/// line itself (at most [`crate::io::MAX_LINE`] bytes): nothing is allocated by a number the line
/// gives.
pub(crate) fn parse_frame_record(text: &str, source: &str, line: usize) -> Result<Frame> {
    let object = json_object(text, source, line)?;
    let none = Conventions::default();
    let (robot, _) = frame(&object, (&ROBOT_FRAMES, true), (source, line), none)?;
    let camera = if CAMERA_FRAMES.iter().any(|(n, _)| object.contains_key(*n)) {
        Some(
            frame(&object, (&CAMERA_FRAMES, false), (source, line), none)?
                .0
                .transform,
        )
    } else {
        None
    };
    let detections = match object.get("detections") {
        Some(d) => detections(d).map_err(|(field, message)| {
            parse_error(source, line, format!("detections{field}"), message)
        })?,
        None => {
            return Err(parse_error(
                source,
                line,
                "detections",
                "missing: calibration on the pixels needs each record's `detections` ({\"target\": [[x, y, z], …], \"pixels\": [[u, v], …]})",
            ));
        }
    };
    Ok(Frame {
        base_from_gripper: robot.transform,
        camera_from_target: camera,
        detections,
    })
}

/// The detections of a record, or the place (below `detections`) and the problem.
fn detections(v: &Value) -> std::result::Result<Detections, (String, String)> {
    let Value::Object(o) = v else {
        return Err((
            String::new(),
            "expected {\"target\": [[x, y, z], …], \"pixels\": [[u, v], …]}".into(),
        ));
    };
    let target = points::<3>(o.get("target"), ".target")?;
    let pixels = points::<2>(o.get("pixels"), ".pixels")?;
    if target.len() != pixels.len() {
        return Err((
            ".pixels".into(),
            format!(
                "{} pixels for {} target points: give one pixel per point, in the same order",
                pixels.len(),
                target.len()
            ),
        ));
    }
    if target.len() < MIN_DETECTIONS {
        return Err((
            ".target".into(),
            format!(
                "{} points, at least {MIN_DETECTIONS} needed (a planar target's pose)",
                target.len()
            ),
        ));
    }
    let on_target: Vec<nalgebra::Vector3<f64>> = target.iter().map(|p| (*p).into()).collect();
    if crate::solve::reprojection::on_one_line(&on_target) {
        return Err((
            ".target".into(),
            crate::solve::reprojection::ON_ONE_LINE.into(),
        ));
    }
    Ok(Detections { target, pixels })
}

/// A list of N-vectors of finite numbers, or the place and the problem.
fn points<const N: usize>(
    v: Option<&Value>,
    name: &str,
) -> std::result::Result<Vec<[f64; N]>, (String, String)> {
    let Some(Value::Array(items)) = v else {
        return Err((
            name.into(),
            format!(
                "missing or not a list: expected [[{}], …]",
                ["x", "y", "z"][..N].join(", ")
            ),
        ));
    };
    items
        .iter()
        .enumerate()
        .map(|(i, item)| {
            let at = |j: Option<usize>| match j {
                Some(j) => format!("{name}[{i}][{j}]"),
                None => format!("{name}[{i}]"),
            };
            let Value::Array(xs) = item else {
                return Err((
                    at(None),
                    format!("expected a list of {N} numbers, got {item}"),
                ));
            };
            if xs.len() != N {
                return Err((at(None), format!("{} numbers, expected {N}", xs.len())));
            }
            let mut out = [0.0; N];
            for (j, (o, x)) in out.iter_mut().zip(xs).enumerate() {
                *o = x
                    .as_f64()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| (at(Some(j)), format!("expected a finite number, got {x}")))?;
            }
            Ok(out)
        })
        .collect()
}

/// Reads the one transform of a pair of alternative names, inverting when the file gives the
/// other direction, with the direction the file wrote; its rotation in the convention
/// `conventions` names for this side (the robot's when `robot`), if one is.
pub(crate) fn frame(
    object: &Map<String, Value>,
    (names, robot): (&[(&str, bool); 2], bool),
    (source, line): (&str, usize),
    conventions: Conventions,
) -> Result<(ReadTransform, WrittenAs)> {
    let present: Vec<_> = names
        .iter()
        .filter(|(n, _)| object.contains_key(*n))
        .collect();
    let &&(name, inverted) = match present.as_slice() {
        [one] => one,
        [] => {
            let missing = format!("missing: give `{}` or `{}`", names[0].0, names[1].0);
            let field = format!("{}|{}", names[0].0, names[1].0);
            if !object.contains_key("detections") {
                return Err(parse_error(source, line, field, missing));
            }
            // Each face words the call that calibrates it ([`Remedy::Pixels`]).
            return Err(Error::Parse {
                file: source.to_string(),
                line,
                field,
                message: format!(
                    "{missing} (this record has `detections` alone: it is calibrated on its pixels)"
                ),
                remedy: Some(Remedy::Pixels),
            });
        }
        _ => {
            return Err(parse_error(
                source,
                line,
                names[0].0,
                format!("both `{}` and `{}` given: give one", names[0].0, names[1].0),
            ));
        }
    };
    let read = read_transform_json_as(&object[name], (robot, conventions)).map_err(|p| {
        let field = p.path_under(name);
        parse_error(source, line, field, p.message)
    })?;
    let read = if inverted {
        ReadTransform {
            transform: read.transform.inverse(),
            ..read
        }
    } else {
        read
    };
    Ok((read, written_as(inverted)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::error::Error;

    const I: &str = "[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]";

    fn read(text: &str) -> Vec<Result<StampedPosePair>> {
        JsonlPairs::new(text.as_bytes(), "t.jsonl").collect()
    }

    /// A record with `detections` and no camera pose is a bad line whose remedy is typed (each
    /// face words the call that calibrates it on the pixels): the library's words name no flag.
    #[test]
    fn a_record_with_detections_alone_carries_the_pixels_remedy() {
        let detections = r#""detections": {"target": [[0,0,0]], "pixels": [[1,2]]}"#;
        let errors: Vec<_> = [
            format!("{{\"base_from_gripper\": {I}, {detections}}}"),
            format!("{{\"base_from_gripper\": {I}}}"),
        ]
        .iter()
        .map(|line| read(line).remove(0).unwrap_err())
        .collect();
        assert_eq!(errors[0].remedy(), Some(Remedy::Pixels));
        assert_eq!(errors[1].remedy(), None);
        for e in &errors {
            let Error::Parse { line, field, .. } = e else {
                panic!("{e}");
            };
            assert_eq!(
                (*line, field.as_str()),
                (1, "camera_from_target|target_from_camera")
            );
            assert!(!e.to_string().contains("--"), "{e}");
        }
        assert!(errors[0].to_string().contains("pixels"), "{}", errors[0]);
    }

    #[test]
    fn joints_are_read_and_bad_ones_named() {
        let rec =
            |j: &str| format!("{{\"base_from_gripper\": {I}, \"camera_from_target\": {I}{j}}}");
        let text = format!(
            "{}\n\n{}\n",
            rec(", \"joints\": [0.1, -2]"),
            rec(", \"joints\": [0.3, 0.4]")
        );
        let joints = |text: &str| -> Result<Vec<Vec<f64>>> {
            JsonlPairs::new(text.as_bytes(), "f.jsonl")
                .map(|r| r.map(|r| r.joints[..r.joint_count].to_vec()))
                .collect()
        };
        assert_eq!(
            joints(&text).unwrap(),
            vec![vec![0.1, -2.0], vec![0.3, 0.4]]
        );
        // A value "joints" is no joint angles; the key written with an escape is the key.
        let text = format!(
            "{}\n{}\n",
            rec(", \"note\": \"joints\""),
            rec(", \"\\u006aoints\": [0.5]")
        );
        let read: Vec<_> = JsonlPairs::new(text.as_bytes(), "f.jsonl").collect();
        assert_eq!(read[0].as_ref().unwrap().joint_count, 0);
        assert!(
            matches!(&read[1], Err(crate::model::error::Error::Parse { line: 2, field, .. }) if field == "joints"),
            "{:?}",
            read[1]
        );
        let escaped = rec(", \"\\u006aoints\": [0.5]");
        assert_eq!(
            joints(&format!("{escaped}\n{escaped}\n")).unwrap(),
            vec![vec![0.5]; 2]
        );
        let many = format!("[{}]", vec!["0.1"; MAX_JOINTS].join(","));
        let text = format!(
            "{}\n{}\n",
            rec(&format!(", \"joints\": {many}")),
            rec(&format!(", \"joints\": {many}"))
        );
        assert!(joints(&text).unwrap().iter().all(|q| q.len() == MAX_JOINTS));
        let more = format!(
            "{}\n",
            rec(&format!(", \"joints\": [0.1,{}]", &many[1..many.len() - 1]))
        );
        assert!(
            joints(&more)
                .unwrap_err()
                .to_string()
                .contains("at most 64")
        );
        for (second, field) in [
            (rec(", \"joints\": [0.3, \"x\"]"), "joints[1]"),
            (rec(", \"joints\": [0.3]"), "joints"),
            (rec(""), "joints"),
            (rec(", \"joints\": 3"), "joints"),
        ] {
            let text = format!("{}\n{second}\n", rec(", \"joints\": [0.1, 0.2]"));
            match joints(&text) {
                Err(crate::model::error::Error::Parse { line, field: f, .. }) => {
                    assert_eq!((line, f.as_str()), (2, field), "{second}");
                }
                other => panic!("{second}: {other:?}"),
            }
        }
    }

    #[test]
    fn reads_both_directions_and_skips_blank_lines() {
        let text = format!(
            "{{\"stamp\": 1.5, \"base_from_gripper\": {I}, \"camera_from_target\": {I}}}\n\n# comment\n{{\"gripper_from_base\": {{\"translation\": [1,0,0], \"quaternion_xyzw\": [0,0,0,1]}}, \"target_from_camera\": {I}}}\n"
        );
        let r: Vec<_> = read(&text).into_iter().map(|r| r.unwrap()).collect();
        assert_eq!(r.len(), 2);
        assert_eq!(r[0].stamp, Some(1.5));
        assert_eq!(r[1].line, 4);
        // gripper_from_base translated by +1 in x: base_from_gripper by −1.
        assert_eq!(r[1].pose.base_from_gripper.translation.vector.x, -1.0);
    }

    #[test]
    fn bad_records_name_line_and_field() {
        let bad_rot = "[[1,0,0,0],[0,1,0,0],[0,0,2,0],[0,0,0,1]]";
        let cases = [
            ("{not json".to_string(), "-"),
            (
                format!("{{\"camera_from_target\": {I}}}"),
                "base_from_gripper|gripper_from_base",
            ),
            (
                format!(
                    "{{\"base_from_gripper\": {I}, \"gripper_from_base\": {I}, \"camera_from_target\": {I}}}"
                ),
                "base_from_gripper",
            ),
            (
                format!("{{\"base_from_gripper\": {bad_rot}, \"camera_from_target\": {I}}}"),
                "base_from_gripper",
            ),
            (
                format!(
                    "{{\"base_from_gripper\": {I}, \"camera_from_target\": [[1,0,0,0],[0,1,0,0],[0,0,1,\"NaN\"],[0,0,0,1]]}}"
                ),
                "camera_from_target[2][3]",
            ),
            (
                format!(
                    "{{\"stamp\": \"x\", \"base_from_gripper\": {I}, \"camera_from_target\": {I}}}"
                ),
                "stamp",
            ),
            (
                format!(
                    "{{\"stamp\": 1.7e18, \"base_from_gripper\": {I}, \"camera_from_target\": {I}}}"
                ),
                "stamp",
            ),
            (
                format!(
                    "{{\"base_from_gripper\": [[1,0,0,1e308],[0,1,0,0],[0,0,1,0],[0,0,0,1]], \"camera_from_target\": {I}}}"
                ),
                "base_from_gripper[0][3]",
            ),
            (
                format!(
                    "{{\"base_from_gripper\": {I}, \"camera_from_target\": {I}, \"base_from_gripper\": {I}}}"
                ),
                "base_from_gripper",
            ),
            (
                format!(
                    "{{\"base_from_gripper\": {{\"translation\": [0,0,0], \"quaternion_xyzw\": [0,0,0,1], \"translation\": [1,0,0]}}, \"camera_from_target\": {I}}}"
                ),
                "base_from_gripper.translation",
            ),
        ];
        for (text, field) in cases {
            let input = format!("\n{text}\n");
            let r = read(&input);
            match &r[0] {
                Err(Error::Parse {
                    file,
                    line,
                    field: f,
                    ..
                }) => {
                    assert_eq!(file, "t.jsonl");
                    assert_eq!(*line, 2);
                    assert_eq!(f, field, "{text}");
                }
                other => panic!("{text}: {other:?}"),
            }
        }
    }

    /// Every record line of the test data that the fast path takes gives the general path's
    /// record, bit for bit, and its projections; most lines take it.
    #[test]
    fn the_fast_path_reads_as_the_general_path() {
        let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../../testdata");
        let mut files = vec![std::path::PathBuf::from(root)];
        let (mut lines, mut fast) = (0, 0);
        while let Some(path) = files.pop() {
            // testdata/golden holds the CLI's recorded outputs, not pose records.
            if path.is_dir() && !path.ends_with("golden") {
                files.extend(std::fs::read_dir(&path).unwrap().map(|e| e.unwrap().path()));
                continue;
            }
            if path.extension().is_none_or(|e| e != "jsonl") {
                continue;
            }
            let text = std::fs::read_to_string(&path).unwrap();
            for (k, line) in text.lines().enumerate() {
                if !line.trim_start().starts_with('{') {
                    continue;
                }
                // Detections are read by their own pass, and joint angles by the general parser
                // (a record keeps them), on the general path.
                let general_only = line.contains("\"detections\"") || line.contains("\"joints\"");
                if !general_only {
                    lines += 1;
                }
                let (mut p_fast, mut p_general) = (Projections::default(), Projections::default());
                let general = parse_record(
                    line.trim(),
                    ("t", k + 1),
                    Conventions::default(),
                    (&mut p_general, &mut DegreeAngles::default()),
                );
                if let Some(record) = fast_record(line, k + 1, &mut p_fast) {
                    fast += usize::from(!general_only);
                    assert_eq!(
                        Ok(record),
                        general.map_err(|e| e.to_string()),
                        "{path:?}:{k}"
                    );
                    assert_eq!(p_fast, p_general);
                }
            }
        }
        assert!(
            lines > 1000 && fast * 10 > lines * 9,
            "{fast} of {lines} lines"
        );
    }

    #[test]
    fn rounded_matrices_are_counted() {
        let rounded = "[[0.36,0.48,-0.8,0],[-0.8,0.6,0,0],[0.48,0.64,0.6,0],[0,0,0,1]]";
        let exact = "[[0.36,0.48,-0.8,0],[-0.8,0.6,0,0],[0.48,0.64,0.6,0],[0,0,0,1]]";
        let slightly = rounded.replace("0.36", "0.360001");
        let text = format!(
            "{{\"base_from_gripper\": {exact}, \"camera_from_target\": {slightly}}}\n{{\"base_from_gripper\": {slightly}, \"camera_from_target\": {I}}}\n"
        );
        let mut reader = JsonlPairs::new(text.as_bytes(), "t.jsonl");
        assert_eq!(reader.by_ref().filter(Result::is_ok).count(), 2);
        let p = reader.projections();
        assert_eq!(p.count, 2);
        assert!(p.largest_deviation > 1e-7 && p.largest_deviation < 1e-6);
    }
}
