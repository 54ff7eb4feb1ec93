//! Rig recordings (SPEC sec. 10): JSON Lines, one robot pose per record with the observations of
//! any camera of any target made at it:
//!
//! `{"base_from_gripper": T, "observations": [{"camera": "wrist", "target": "board",
//! "camera_from_target": T}, …]}`
//!
//! The robot pose may be given as `gripper_from_base` and an observation as `target_from_camera`
//! (each inverted on reading, as for one camera). An observation with `detections` or `image` in
//! place of its pose is refused: rigs are calibrated on poses only, so far.

use std::path::Path;

use serde_json::{Map, Value};

use crate::io::jsonl::{frame, json_object};
use crate::io::transform::Conventions;
use crate::io::{CAMERA_FRAMES, ROBOT_FRAMES, parse_error, read_text};
use crate::model::error::{Error, Result};
use crate::model::pose::Transform;
use crate::rig::{Observation, RigRecording};

/// Whether a JSON Lines text is a rig recording: its first record has `observations`.
pub fn is_rig_text(text: &str) -> bool {
    text.lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('#'))
        .and_then(|l| serde_json::from_str::<Value>(l).ok())
        .is_some_and(|v| v.get("observations").is_some())
}

/// Whether the file at `path` is a rig recording ([`is_rig_text`] on its first record); `false`
/// when it cannot be read (the ordinary reader then says why).
pub fn is_rig_file(path: &Path) -> bool {
    use std::io::Read;
    let Ok(file) = std::fs::File::open(path) else {
        return false;
    };
    // The first record is within the first megabyte of any recording worth sniffing; a binary
    // file (a ROS 2 recording) is not read further.
    let mut head = Vec::new();
    if file.take(1 << 20).read_to_end(&mut head).is_err() {
        return false;
    }
    let text = String::from_utf8_lossy(&head);
    let first = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('#'));
    first.is_some_and(is_rig_text)
}

/// Reads a rig recording from a file, read as every whole file is (a regular file or a pipe,
/// bounded in size, UTF-8 text without a NUL).
pub fn read_rig(path: &Path) -> Result<RigRecording> {
    parse_rig(&read_text(path)?, &path.display().to_string())
}

/// Reads a rig recording from its text, named `source` in messages: every bad record is refused
/// with the file, the line (from 1) and the field.
pub fn parse_rig(text: &str, source: &str) -> Result<RigRecording> {
    let mut recording = RigRecording::default();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let t = raw.trim();
        if t.is_empty() || t.starts_with('#') {
            continue;
        }
        let object = json_object(t, source, line)?;
        let q = transform(&object, &ROBOT_FRAMES, (source, line), "", true)?;
        let pose = recording.poses.len();
        let Some(list) = object.get("observations") else {
            return Err(parse_error(
                source,
                line,
                "observations",
                "missing: a rig recording gives `observations` with every robot pose (an empty list when nothing was seen)",
            ));
        };
        let Value::Array(list) = list else {
            return Err(parse_error(
                source,
                line,
                "observations",
                "expected a list of {\"camera\", \"target\", \"camera_from_target\"} objects",
            ));
        };
        let mut seen: Vec<(String, String)> = Vec::new();
        for (j, o) in list.iter().enumerate() {
            let at = format!("observations[{j}]");
            let Value::Object(o) = o else {
                return Err(parse_error(
                    source,
                    line,
                    at,
                    "expected an object {\"camera\", \"target\", \"camera_from_target\"}",
                ));
            };
            let name = |key: &str| -> Result<String> {
                match o.get(key) {
                    Some(Value::String(s)) if !s.trim().is_empty() => Ok(s.clone()),
                    Some(v) => Err(parse_error(
                        source,
                        line,
                        format!("{at}.{key}"),
                        format!("expected a non-empty name, found {v}"),
                    )),
                    None => Err(parse_error(
                        source,
                        line,
                        format!("{at}.{key}"),
                        format!("missing: the {key}'s name"),
                    )),
                }
            };
            let camera = name("camera")?;
            let target = name("target")?;
            let has_pose = CAMERA_FRAMES.iter().any(|(n, _)| o.contains_key(*n));
            for key in ["detections", "image"] {
                if o.contains_key(key) && !has_pose {
                    return Err(parse_error(
                        source,
                        line,
                        format!("{at}.{key}"),
                        format!(
                            "`{key}` is not yet supported on rigs: give each observation's `camera_from_target` (`handeye detect` finds it for one camera's records)"
                        ),
                    ));
                }
            }
            let c = transform(o, &CAMERA_FRAMES, (source, line), &at, false)?;
            if seen.contains(&(camera.clone(), target.clone())) {
                return Err(parse_error(
                    source,
                    line,
                    at,
                    format!(
                        "camera `{camera}` sees `{target}` twice in one record: give one observation per camera and target"
                    ),
                ));
            }
            seen.push((camera.clone(), target.clone()));
            recording.observations.push(Observation {
                pose,
                camera,
                target,
                camera_from_target: c,
            });
        }
        recording.poses.push(q);
        recording.names.push(format!("{source}:{line}"));
    }
    if recording.poses.is_empty() {
        return Err(parse_error(source, 0, "-", "no records"));
    }
    Ok(recording)
}

/// The transform of one of two alternative names (inverted when the second), read as a pose
/// record's ([`crate::io::jsonl`]'s reader), its fields named under `at` in messages.
fn transform(
    object: &Map<String, Value>,
    names: &[(&str, bool); 2],
    (source, line): (&str, usize),
    at: &str,
    robot: bool,
) -> Result<Transform> {
    frame(
        object,
        (names, robot),
        (source, line),
        Conventions::default(),
    )
    .map(|(read, _)| read.transform)
    .map_err(|e| match e {
        Error::Parse {
            file,
            line,
            field,
            message,
            ..
        } if !at.is_empty() => Error::Parse {
            file,
            line,
            field: format!("{at}.{field}"),
            message,
            remedy: None,
        },
        other => other,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const I: &str = "[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]";

    fn field_of(text: &str) -> (usize, String, String) {
        match parse_rig(text, "rig.jsonl") {
            Err(Error::Parse {
                line,
                field,
                message,
                ..
            }) => (line, field, message),
            other => panic!("expected a parse error, got {other:?}"),
        }
    }

    #[test]
    fn reads_poses_and_observations() {
        let text = format!(
            "# a rig\n{{\"base_from_gripper\": {I}, \"observations\": [{{\"camera\": \"a\", \"target\": \"b\", \"camera_from_target\": {I}}}]}}\n\n{{\"gripper_from_base\": {I}, \"observations\": []}}\n"
        );
        assert!(is_rig_text(&text));
        let r = parse_rig(&text, "rig.jsonl").expect("reads");
        assert_eq!(r.poses.len(), 2);
        assert_eq!(r.observations.len(), 1);
        assert_eq!(r.observations[0].camera, "a");
        assert_eq!(r.names[1], "rig.jsonl:4");
    }

    #[test]
    fn bad_records_name_line_and_field() {
        let (line, field, _) = field_of(&format!(
            "{{\"base_from_gripper\": {I}, \"observations\": []}}\n{{\"base_from_gripper\": {I}, \"observations\": [{{\"camera\": \"a\", \"target\": \"b\", \"camera_from_target\": [[1,0,0,0],[0,2,0,0],[0,0,1,0],[0,0,0,1]]}}]}}"
        ));
        assert_eq!(
            (line, field.as_str()),
            (2, "observations[0].camera_from_target")
        );
        let (line, field, _) = field_of(&format!(
            "{{\"base_from_gripper\": {I}, \"observations\": [{{\"target\": \"b\", \"camera_from_target\": {I}}}]}}"
        ));
        assert_eq!((line, field.as_str()), (1, "observations[0].camera"));
        let (_, field, message) = field_of(&format!(
            "{{\"base_from_gripper\": {I}, \"observations\": [{{\"camera\": \"a\", \"target\": \"b\", \"detections\": {{}}}}]}}"
        ));
        assert_eq!(field, "observations[0].detections");
        assert!(message.contains("not yet supported on rigs"), "{message}");
        let (_, field, _) = field_of(&format!("{{\"base_from_gripper\": {I}}}"));
        assert_eq!(field, "observations");
        let (_, field, _) = field_of("{\"observations\": []}");
        assert_eq!(field, "base_from_gripper|gripper_from_base");
        let (_, field, message) = field_of(&format!(
            "{{\"base_from_gripper\": {I}, \"observations\": [{{\"camera\": \"a\", \"target\": \"b\", \"camera_from_target\": {I}}}, {{\"camera\": \"a\", \"target\": \"b\", \"camera_from_target\": {I}}}]}}"
        ));
        assert_eq!(field, "observations[1]");
        assert!(message.contains("twice"));
    }
}
