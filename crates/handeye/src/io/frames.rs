//! A recording on the pixels: JSON Lines records with a robot pose and the detections of the
//! target (SPEC sec. 9), read whole for `calibrate --method reprojection`.

use std::io::BufRead;
use std::path::Path;

use crate::io::jsonl::parse_frame_record;
use crate::io::lines::Lines;
use crate::io::parse_error;
use crate::model::camera::Frame;
use crate::model::error::Result;

/// The frames of a recording on the pixels, with the line of each.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameSeries {
    /// The frames in file order.
    pub frames: Vec<Frame>,
    /// Their line numbers, from 1.
    pub lines: Vec<usize>,
}

/// Reads the frames of a JSON Lines file (`-` for standard input); blank lines and `#` comments
/// are skipped. The first bad record ends the reading with its [`Error::Parse`](crate::Error::Parse) (file, line,
/// field): a calibration on a recording with a bad record is refused, not made without it.
pub fn read_frames(path: &Path) -> Result<FrameSeries> {
    let source = path.display().to_string();
    if source == "-" {
        return frames_of(std::io::stdin().lock(), &source);
    }
    frames_of(crate::io::open(path)?, &source)
}

/// [`read_frames`] on any input, named `source` in messages.
pub fn frames_of<R: BufRead>(input: R, source: &str) -> Result<FrameSeries> {
    let mut series = FrameSeries {
        frames: Vec::new(),
        lines: Vec::new(),
    };
    for record in frame_records(input, source) {
        let (number, frame) = record?;
        series.frames.push(frame);
        series.lines.push(number);
    }
    Ok(series)
}

/// The records of a recording on the pixels one at a time:
/// [`FrameRecording::records`](crate::io::FrameRecording::records).
pub(crate) fn frame_records<R: BufRead>(
    input: R,
    source: &str,
) -> impl Iterator<Item = Result<(usize, Frame)>> + use<'_, R> {
    let mut lines = Lines::new(input);
    std::iter::from_fn(move || {
        loop {
            let (number, text) = match lines.next_record(source)? {
                Ok(record) => record,
                Err(e) => return Some(Err(e)),
            };
            let Ok(text) = std::str::from_utf8(text) else {
                return Some(Err(parse_error(
                    source,
                    number,
                    "-",
                    "the line is not valid UTF-8 text",
                )));
            };
            let text = text.trim();
            if text.is_empty() || text.starts_with('#') {
                continue;
            }
            return Some(parse_frame_record(text, source, number).map(|f| (number, f)));
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::error::Error;

    const Q: &str =
        r#""base_from_gripper": {"translation": [0.1, 0, 0.3], "quaternion_xyzw": [0, 0, 0, 1]}"#;
    const D: &str = r#""detections": {"target": [[0,0,0],[0.06,0,0],[0.06,0.06,0],[0,0.06,0]], "pixels": [[600,300],[650,301],[651,350],[599,352]]}"#;

    fn field_of(record: &str) -> (usize, String) {
        match frames_of(format!("# c\n{record}\n").as_bytes(), "r.jsonl") {
            Err(Error::Parse { line, field, .. }) => (line, field),
            other => panic!("{record}: {other:?}"),
        }
    }

    #[test]
    fn reads_frames_with_or_without_the_camera_pose() {
        let text = format!(
            "{{{Q}, {D}}}\n\n{{{Q}, \"camera_from_target\": {{\"translation\": [0, 0, 0.5], \"quaternion_xyzw\": [1, 0, 0, 0]}}, {D}}}\n"
        );
        let s = frames_of(text.as_bytes(), "r.jsonl").unwrap();
        assert_eq!(s.lines, vec![1, 3]);
        assert!(s.frames[0].camera_from_target.is_none());
        assert!(s.frames[1].camera_from_target.is_some());
        assert_eq!(s.frames[0].detections.pixels[2], [651.0, 350.0]);
    }

    #[test]
    fn bad_detections_name_the_line_and_the_field() {
        let cases = [
            (format!("{{{Q}}}"), "detections"),
            (
                format!("{{{Q}, {}}}", D.replace("[599,352]]", "[599,352],[1,2]]")),
                "detections.pixels",
            ),
            (
                format!("{{{Q}, {}}}", D.replace("[651,350]", "[651,\"NaN\"]")),
                "detections.pixels[2][1]",
            ),
            (
                format!("{{{Q}, {}}}", D.replace("[651,350]", "[651]")),
                "detections.pixels[2]",
            ),
            (
                format!("{{{Q}, {}}}", D.replace("[0.06,0,0],", "[0.06,0],")),
                "detections.target[1]",
            ),
            (
                format!("{{{Q}, {}}}", D.replace("\"target\"", "\"points\"")),
                "detections.target",
            ),
            (
                format!(
                    "{{{Q}, {}}}",
                    D.replace(",[0,0.06,0]]", "]").replace(",[599,352]]", "]")
                ),
                "detections.target",
            ),
            (format!("{{{}}}", D), "base_from_gripper|gripper_from_base"),
            (format!("{{{Q}, {D}, {D}}}"), "detections"),
            (format!("{{{Q}, \"detections\": 3}}"), "detections"),
        ];
        for (record, field) in cases {
            assert_eq!(field_of(&record), (2, field.to_string()), "{record}");
        }
    }

    /// The pose reader refuses a record without a camera pose, and says what reads it: the
    /// pixels, as a typed remedy each face words in its own flags.
    #[test]
    fn the_pose_reader_points_detections_only_records_to_the_pixels() {
        let e = crate::io::parse_pose_line(&format!("{{{Q}, {D}}}"), "r.jsonl", 1).unwrap_err();
        assert_eq!(
            e.remedy(),
            Some(crate::model::warning::Remedy::Pixels),
            "{e}"
        );
        assert!(e.to_string().contains("calibrated on its pixels"), "{e}");
    }
}
