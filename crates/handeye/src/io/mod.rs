//! Readers and writers of the file formats: pose pairs as JSON Lines or CSV (SPEC sec. 7), truth
//! files, and timestamped pose streams (TUM / ethz-asl layout).
//!
//! Every reader reports bad input as [`Error::Parse`] naming the file, the line (from 1) and the
//! field, and never panics. Pose pairs are normalised to [`PosePair`]
//! (`base_from_gripper`, `camera_from_target`) whichever direction the file gives.

mod csv_pairs;
mod format;
mod frames;
mod intrinsics;
mod json_text;
mod jsonl;
mod jsonl_fast;
mod kinematics;
mod lines;
mod peer;
mod pose_reader;
mod recording;
mod rig;
#[cfg(feature = "rosbag")]
pub mod rosbag;
mod saved;
mod series;
mod stamped;
mod stream;
pub mod sync;
mod transform;
mod truth;
mod yaml_tree;

use std::fs::File;
use std::io::{BufRead, BufReader, Chain, Cursor, Read};
use std::path::Path;

use crate::model::error::{Error, Result};
use crate::model::findings::{Written, WrittenAs};
use crate::model::motion::PosePair;
use crate::model::rotation::Rotations;
use lines::{Line, Lines};

// One entry for every input (`Recording`: a pose file, two streams, a ROS 2 recording;
// `FrameRecording` for the pixels of the same sources), one reader for every pose-file format
// (`read_pose_file`, `open_poses`, `PoseReader`) for streaming, the truth files, and `rosbag`'s
// `is_bag` and `inspect_bag`; the two-stream pairing (`sync`).
pub use frames::FrameSeries;
pub(crate) use frames::frame_records;
pub use frames::read_frames;
#[cfg(feature = "rosbag")]
pub use recording::BagFrames;
pub use recording::{
    CameraMount, FrameRecording, MountFrame, Note, Recording, RecordingOptions, Source,
};
pub use stream::PoseStream;
// The pose-file readers behind `PoseStream` and `Recording`.
pub use format::Format;
pub use peer::{ImageRecord, read_visp_images};
pub use pose_reader::{
    DegreeAngles, PoseInput, PoseReader, Preamble, open_pose_stream, open_poses, read_joints,
    read_pose_file,
};
pub(crate) use pose_reader::{at_least_two_pairs, open_poses_as, read_records};
pub use rig::{is_rig_file, is_rig_text, parse_rig, read_rig};
pub use series::{DeclaredSetup, PoseSeries, Projections};
pub use sync::TimeOffset;
pub(crate) use transform::Conventions;
pub use truth::Truth;
// The parsers of text behind the file readers (`parse_intrinsics`, `parse_saved_x`, `frames_of`,
// the joints of a pose file); each format's own reader and the io helpers are crate-internal.
use csv_pairs::CsvPairs;
use jsonl::JsonlPairs;
pub use transform::FieldProblem;
pub(crate) use transform::read_transform_json;
pub use {
    frames::frames_of,
    intrinsics::parse_intrinsics,
    jsonl::parse_pose_line,
    lines::MAX_LINE,
    saved::parse_saved_x,
    stamped::{StampedStream, read_camera_stream, read_stamped_poses},
    transform::transform_from_json,
    truth::{parse_truth, write_truth},
};

/// The names a pose may have in a file, and whether the file's transform is the inverse of ours.
pub(crate) const ROBOT_FRAMES: [(&str, bool); 2] =
    [("base_from_gripper", false), ("gripper_from_base", true)];
/// See [`ROBOT_FRAMES`].
pub(crate) const CAMERA_FRAMES: [(&str, bool); 2] =
    [("camera_from_target", false), ("target_from_camera", true)];

/// The direction of a transform the file gave inverted (`true`) or as named.
pub(crate) fn written_as(inverted: bool) -> WrittenAs {
    if inverted {
        WrittenAs::Inverse
    } else {
        WrittenAs::Named
    }
}

/// One pose pair read from a file, with its place.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StampedPosePair {
    /// Line number in the file, from 1.
    pub line: usize,
    /// Time stamp, seconds, if the file gives one.
    pub stamp: Option<f64>,
    /// The pose pair.
    pub pose: PosePair,
    /// The directions in which the record wrote its two poses.
    pub written: Written,
    /// The robot's joint angles at the pose (radians, its joint order), where the record gives
    /// them (JSON Lines `joints`, a ROS 2 recording's `/joint_states`): the first `joint_count`
    /// numbers (at most [`MAX_JOINTS`](crate::model::kinematics::MAX_JOINTS), as many as a DH
    /// table has; a JSON Lines record of more is refused, a bag's message of more keeps none
    /// here). Inline, so that a record stays `Copy` and a stream allocates nothing for it.
    pub joints: [f64; RECORD_JOINTS],
    /// How many of `joints` the record gives (0: none).
    pub joint_count: usize,
}

/// The most joint angles a [`StampedPosePair`] holds.
pub(crate) const RECORD_JOINTS: usize = crate::model::kinematics::MAX_JOINTS;

impl StampedPosePair {
    /// A record without joint angles.
    pub(crate) fn new(line: usize, stamp: Option<f64>, pose: PosePair, written: Written) -> Self {
        Self {
            line,
            stamp,
            pose,
            written,
            joints: [0.0; RECORD_JOINTS],
            joint_count: 0,
        }
    }

    /// The same with `joints` (none kept when there are more than [`RECORD_JOINTS`]).
    pub(crate) fn with_joints(mut self, joints: &[f64]) -> Self {
        if joints.len() <= RECORD_JOINTS {
            self.joints[..joints.len()].copy_from_slice(joints);
            self.joint_count = joints.len();
        }
        self
    }
}

/// The error of a line longer than [`MAX_LINE`] bytes.
pub(crate) fn too_long(source: &str, line: usize) -> Error {
    parse_error(
        source,
        line,
        "-",
        format!("line longer than {MAX_LINE} bytes: skipped"),
    )
}

/// The largest input read whole, bytes (OpenCV YAML, moveit and easy_handeye2 files, ViSP pose
/// files, the stamped streams, truth and saved-X files): 256 MiB, about 800,000 poses of
/// OpenCV YAML or 3 million samples of a stamped stream. Larger is refused before it is read
/// (a regular file) or once it passes the bound (a pipe), never held whole.
pub(crate) const MAX_WHOLE_FILE: u64 = 256 << 20;

/// Reads a whole text file, naming it in the error: a regular file or a pipe (`<(…)`) of at most
/// [`MAX_WHOLE_FILE`] bytes; a device (`/dev/zero`), a socket or a directory is refused before it
/// is read. Text that is not UTF-8 is a parse error on the line of its first invalid byte; a
/// leading byte order mark is dropped.
pub(crate) fn read_text(path: &Path) -> Result<String> {
    let file = path.display().to_string();
    let io_error = |e| Error::Io {
        file: file.clone(),
        source: e,
    };
    let meta = std::fs::metadata(path).map_err(io_error)?;
    whole_file_kind(&meta, &file)?;
    not_empty(&meta, &file)?;
    File::open(path)
        .map_err(io_error)
        .and_then(|f| read_whole(f, &file))
}

/// Refuses what cannot be read whole: anything but a regular file or a pipe, or a regular file
/// larger than [`MAX_WHOLE_FILE`].
pub(crate) fn whole_file_kind(meta: &std::fs::Metadata, file: &str) -> Result<()> {
    let kind = meta.file_type();
    #[cfg(unix)]
    let pipe = std::os::unix::fs::FileTypeExt::is_fifo(&kind);
    #[cfg(not(unix))]
    let pipe = false;
    if !(kind.is_file() || pipe) {
        let what = if kind.is_dir() {
            "a directory"
        } else {
            "a device or a socket"
        };
        return Err(parse_error(
            file,
            0,
            "-",
            format!("{what}, not a file: this format is read whole, from a file or a pipe"),
        ));
    }
    if kind.is_file() && meta.len() > MAX_WHOLE_FILE {
        return Err(too_large(file));
    }
    Ok(())
}

/// The error of an input read whole that is larger than [`MAX_WHOLE_FILE`].
fn too_large(file: &str) -> Error {
    parse_error(
        file,
        0,
        "-",
        format!(
            "larger than {} MiB: this format is read whole, and no pose file of it is that large",
            MAX_WHOLE_FILE >> 20
        ),
    )
}

/// All of `input` as text (see [`text_of`]), at most [`MAX_WHOLE_FILE`] bytes.
pub(crate) fn read_whole(input: impl Read, file: &str) -> Result<String> {
    let mut bytes = Vec::new();
    input
        .take(MAX_WHOLE_FILE + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| Error::Io {
            file: file.to_string(),
            source: e,
        })?;
    if bytes.len() as u64 > MAX_WHOLE_FILE {
        return Err(too_large(file));
    }
    text_of(bytes, file)
}

/// `bytes` as text without a leading byte order mark, or a parse error on the line of the first
/// invalid byte (UTF-16 text said to be so).
fn text_of(bytes: Vec<u8>, file: &str) -> Result<String> {
    if let Some(e) = utf16(&bytes, file) {
        return Err(e);
    }
    let mut text = String::from_utf8(bytes).map_err(|e| {
        let valid = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        let line = 1 + valid.iter().filter(|&&b| b == b'\n').count();
        let column = 1 + valid.iter().rev().take_while(|&&b| b != b'\n').count();
        parse_error(
            file,
            line,
            "-",
            format!("not valid UTF-8 text (byte {column} of the line)"),
        )
    })?;
    // A NUL is no text's: the YAML and XML parsers would stop or read past it, and keep part of
    // the file without a word.
    if let Some(at) = text.find('\0') {
        let line = 1 + text[..at].matches('\n').count();
        return Err(parse_error(
            file,
            line,
            "-",
            "a NUL byte: not a text file (or one cut by a binary write)",
        ));
    }
    if text.starts_with('\u{feff}') {
        text.drain(..'\u{feff}'.len_utf8());
    }
    Ok(text)
}

/// The error of text encoded as UTF-16 (a byte order mark `FF FE` or `FE FF`, or ASCII with a NUL
/// in every other byte), which is read as UTF-8 only: `None` for any other start.
pub(crate) fn utf16(head: &[u8], file: &str) -> Option<Error> {
    let little =
        head.starts_with(&[0xff, 0xfe]) || matches!(head, [a, 0, b, 0, ..] if *a != 0 && *b != 0);
    let big =
        head.starts_with(&[0xfe, 0xff]) || matches!(head, [0, a, 0, b, ..] if *a != 0 && *b != 0);
    let order = match (little, big) {
        (true, _) => "little-endian",
        (_, true) => "big-endian",
        _ => return None,
    };
    Some(parse_error(
        file,
        1,
        "-",
        format!(
            "the text is UTF-16 ({order}), and pose files are read as UTF-8: convert it (`iconv -f UTF-16 -t UTF-8`, or save it as UTF-8)"
        ),
    ))
}

/// Opens a file for reading, naming it in the error; an empty regular file is refused as such.
pub(crate) fn open(path: &Path) -> Result<BufReader<File>> {
    let file = path.display().to_string();
    let io_error = |e| Error::Io {
        file: file.clone(),
        source: e,
    };
    let opened = File::open(path).map_err(io_error)?;
    not_empty(&opened.metadata().map_err(io_error)?, &file)?;
    Ok(BufReader::new(opened))
}

/// An empty regular file is refused before it is read: "FILE: the file is empty" (a pipe's size
/// says nothing, and is read).
fn not_empty(meta: &std::fs::Metadata, file: &str) -> Result<()> {
    if meta.is_file() && meta.len() == 0 {
        return Err(parse_error(file, 0, "-", "the file is empty"));
    }
    Ok(())
}

/// An input whose head was read to tell its format, and is read again before the rest.
pub(crate) type Sniffed<R> = Chain<Cursor<Vec<u8>>, R>;

/// Tells the format of `input` from its head: `%YAML` first or `!!opencv-matrix` in the first
/// content lines is OpenCV YAML, a JSON list (`[` then `[`, `{` or `]`) is moveit,
/// `effector_wrt_world:` is moveit's YAML, a first line `parameters:` or `samples:` is
/// easy_handeye2's samples; otherwise [`Format::Auto`] (decided per
/// record by [`PoseReader`]). The head read (up to the first line that is neither blank nor a `#`
/// comment, or up to two more after YAML `---` or `key:` lines; at most 2 × [`MAX_LINE`] bytes) is
/// returned chained before the rest of `input`, so that nothing is lost and nothing reopened.
pub(crate) fn sniff_format<R: BufRead>(mut input: R, source: &str) -> Result<(Format, Sniffed<R>)> {
    let mut head = Vec::new();
    // Start of the line being read, in `head`.
    let mut start = 0;
    // Content lines seen (neither blank nor comments).
    let mut content = 0;
    loop {
        let chunk = match input.fill_buf() {
            Ok(c) => c,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => {
                return Err(Error::Io {
                    file: source.to_string(),
                    source: e,
                });
            }
        };
        if chunk.is_empty() {
            break;
        }
        let room = 2 * MAX_LINE - head.len();
        let end = chunk.iter().take(room).position(|&b| b == b'\n');
        let take = end.map_or(chunk.len().min(room), |k| k + 1);
        head.extend_from_slice(&chunk[..take]);
        input.consume(take);
        if end.is_none() {
            if head.len() >= 2 * MAX_LINE {
                break;
            }
            continue;
        }
        let line = &head[start..];
        let line = line
            .strip_prefix(b"\xef\xbb\xbf")
            .unwrap_or(line)
            .trim_ascii();
        if !line.is_empty() && !line.starts_with(b"#") {
            let more = content < 2 && (line == b"---" || line.ends_with(b":"));
            content += 1;
            if !more {
                break;
            }
        }
        start = head.len();
    }
    if let Some(e) = utf16(&head, source) {
        return Err(e);
    }
    let text = String::from_utf8_lossy(&head);
    let trimmed = text.trim_start_matches('\u{feff}').trim_start();
    let format = Format::sniffed(&format::Head {
        text: &text,
        trimmed,
    });
    Ok((format, Cursor::new(head).chain(input)))
}

/// Largest size of a time stamp accepted, seconds: about 31,700 years (Unix time is near 1.7e9 s;
/// stamps in milli- or nanoseconds are beyond it). Differences of stamps within it cannot overflow.
pub(crate) const MAX_STAMP: f64 = 1e12;

/// Checks a time stamp read from data: finite and at most [`MAX_STAMP`] in size; the message
/// says why not.
pub(crate) fn check_stamp(value: f64) -> std::result::Result<f64, String> {
    if !value.is_finite() {
        Err(format!(
            "expected a finite number of seconds, found {value}"
        ))
    } else if value.abs() > MAX_STAMP {
        Err(format!(
            "stamp {value:e} is not a plausible time in seconds (more than {MAX_STAMP:e} in size: milli- or nanoseconds?)"
        ))
    } else {
        Ok(value)
    }
}

/// Builds an [`Error::Parse`].
pub(crate) fn parse_error(
    file: &str,
    line: usize,
    field: impl Into<String>,
    message: impl Into<String>,
) -> Error {
    Error::Parse {
        file: file.to_string(),
        line,
        field: field.into(),
        message: message.into(),
        remedy: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const I: &str = "[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]";
    const CSV_HEADER: &str = "base_from_gripper_x,base_from_gripper_y,base_from_gripper_z,base_from_gripper_qx,base_from_gripper_qy,base_from_gripper_qz,base_from_gripper_qw,camera_from_target_x,camera_from_target_y,camera_from_target_z,camera_from_target_qx,camera_from_target_qy,camera_from_target_qz,camera_from_target_qw";
    const CSV_ROW: &str = "1,2,3,0,0,0,1,0,0,1,0,0,0,1";

    fn jsonl_line() -> String {
        format!("{{\"base_from_gripper\": {I}, \"camera_from_target\": {I}}}")
    }

    /// (line, field) of a parse error.
    fn place(e: &Error) -> (usize, String) {
        match e {
            Error::Parse { line, field, .. } => (*line, field.clone()),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn formats_parse_from_their_names() {
        for (name, format) in [
            ("auto", Format::Auto),
            ("jsonl", Format::Jsonl),
            ("csv", Format::Csv),
            ("opencv-yaml", Format::OpencvYaml),
            ("moveit", Format::Moveit),
            ("visp", Format::Visp),
        ] {
            assert_eq!(name.parse::<Format>().unwrap(), format);
        }
        assert!(matches!(
            "xml".parse::<Format>(),
            Err(Error::InvalidParameter { name: "format", .. })
        ));
    }

    #[test]
    fn auto_detects_by_extension_then_content_and_keeps_line_numbers() {
        // Tiny buffers, so that the comment lines span several reads.
        let small = |text: &str| {
            std::io::BufReader::with_capacity(3, std::io::Cursor::new(text.to_string()))
        };
        let jsonl = format!(
            "\n# a comment longer than the buffer\n\n  {}\n{}\n",
            jsonl_line(),
            jsonl_line()
        );
        let csv = format!("# recorded 2024\n\n{CSV_HEADER}\n{CSV_ROW}\n# pause\n{CSV_ROW}\n");
        for (text, source, lines) in [
            (jsonl.as_str(), "-", [4, 5]),
            (csv.as_str(), "-", [4, 6]),
            (csv.as_str(), "poses.csv", [4, 6]),
            (jsonl.as_str(), "poses.JSONL", [4, 5]),
        ] {
            let records: Vec<StampedPosePair> = PoseReader::new(small(text), source, Format::Auto)
                .unwrap()
                .collect::<Result<_>>()
                .unwrap();
            let got: Vec<usize> = records.iter().map(|r| r.line).collect();
            assert_eq!(got, lines, "{source}: {text}");
        }
        let csv_reader = PoseReader::new(small(&csv), "-", Format::Auto).unwrap();
        assert_eq!(csv_reader.format(), Format::Csv);
        // Nothing but comments: JSON Lines with no records.
        assert_eq!(
            PoseReader::new(small("# only\n\n"), "-", Format::Auto)
                .unwrap()
                .count(),
            0
        );
        // A CSV header error names the header's own line, after the comments.
        let e = PoseReader::new(small("# c\n\nstamp,foo\n"), "-", Format::Auto)
            .err()
            .unwrap();
        assert_eq!(place(&e), (3, "foo".to_string()));
    }

    #[test]
    fn invalid_utf8_names_the_line_and_reading_goes_on() {
        let mut bytes = format!("{}\n", jsonl_line()).into_bytes();
        bytes.extend_from_slice(b"\xff\xfe\n");
        bytes.extend_from_slice(format!("{}\n", jsonl_line()).as_bytes());
        let r: Vec<_> = PoseReader::new(&bytes[..], "u.jsonl", Format::Auto)
            .unwrap()
            .collect();
        assert_eq!(r.len(), 3);
        assert_eq!(place(r[1].as_ref().unwrap_err()), (2, "-".to_string()));
        assert_eq!(r[2].as_ref().unwrap().line, 3);

        let mut bytes = format!("{CSV_HEADER}\n{CSV_ROW}\n").into_bytes();
        bytes.extend_from_slice(b"1,2,\xff,0,0,0,1,0,0,1,0,0,0,1\n");
        bytes.extend_from_slice(format!("{CSV_ROW}\n").as_bytes());
        let r: Vec<_> = PoseReader::new(&bytes[..], "u.csv", Format::Auto)
            .unwrap()
            .collect();
        assert_eq!(r.len(), 3);
        assert_eq!(
            place(r[1].as_ref().unwrap_err()),
            (3, "base_from_gripper_z".to_string())
        );
        assert_eq!(r[2].as_ref().unwrap().line, 4);
    }

    #[test]
    fn a_failing_input_ends_the_iteration() {
        let dir = std::env::temp_dir();
        for format in [Format::Jsonl, Format::Csv] {
            let reader = open(&dir).map(|r| PoseReader::new(r, "dir", format));
            // Opening a directory fails on some systems, reading it on others: either way an
            // error, and never an endless one.
            if let Ok(Ok(reader)) = reader {
                let records: Vec<_> = reader.take(10).collect();
                assert!(records.len() <= 1, "{format:?}: {records:?}");
                assert!(records.iter().all(Result::is_err));
            }
        }
    }

    proptest::proptest! {
        /// No input makes a reader panic or loop: every record is a pair or an error.
        #[test]
        fn arbitrary_input_never_panics(
            bytes in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..400),
            cut in 0usize..400,
            noise in "[-{}\\[\\],:#\"0-9.eE a-z_\n]{0,40}",
        ) {
            // Raw bytes, and a good record with noise spliced in at `cut`.
            let mut spliced = format!("{}\n{CSV_HEADER}\n{CSV_ROW}\n", jsonl_line()).into_bytes();
            let at = cut.min(spliced.len());
            spliced.splice(at..at, noise.bytes());
            for input in [&bytes, &spliced] {
                for format in [Format::Auto, Format::Jsonl, Format::Csv] {
                    if let Ok(reader) = PoseReader::new(&input[..], "-", format) {
                        let n = reader.take(1000).count();
                        proptest::prop_assert!(n < 1000);
                    }
                }
            }
        }
    }

    #[test]
    fn a_whole_file_needs_two_poses() {
        let dir = std::env::temp_dir().join(format!("handeye-io-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let one = dir.join("one.jsonl");
        std::fs::write(&one, format!("# one pose\n{}\n", jsonl_line())).unwrap();
        let two = dir.join("two");
        std::fs::write(
            &two,
            format!("stamp,{CSV_HEADER}\n0.5,{CSV_ROW}\n1.5,{CSV_ROW}\n"),
        )
        .unwrap();
        let e = read_pose_file(&one, Format::Auto).unwrap_err();
        let series = read_pose_file(&two, Format::Auto).unwrap();
        let missing = read_pose_file(&dir.join("missing.jsonl"), Format::Auto).unwrap_err();
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(place(&e), (0, "-".to_string()));
        assert!(e.to_string().contains("one.jsonl") && e.to_string().contains("at least 2"));
        assert_eq!(series.pairs.len(), 2);
        assert_eq!(series.stamps, [Some(0.5), Some(1.5)]);
        assert_eq!(series.lines, [2, 3]);
        assert_eq!(series.pairs[0].base_from_gripper.translation.vector.z, 3.0);
        assert!(matches!(missing, Error::Io { .. }));
    }
}
