//! A recording on the pixels read into a [`FrameRecording`]: a JSON Lines file of records with
//! `detections`, or the tag detections of a ROS 2 recording, through the [`Source`] that names
//! a [`Recording`](super::Recording)'s input.

use std::io::BufRead;

use super::{CameraMount, Note, RecordingOptions, Source, check_options};
use crate::io::{Format, FrameSeries, frame_records, read_frames};
use crate::model::camera::{Frame, Intrinsics};
use crate::model::error::{Error, Result};

/// The frames of a calibration on the pixels (robot pose and detections), as
/// [`Recording`](super::Recording) holds
/// the pose pairs of one on the poses.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameRecording {
    /// The frames, in the recording's order.
    pub frames: Vec<Frame>,
    /// Each frame's line (a file) or message number in the detections topic (a ROS 2
    /// recording), from 1.
    pub lines: Vec<usize>,
    /// A name for each frame: `file:line`, or topic, message number and stamp.
    pub names: Vec<String>,
    /// The intrinsics the recording carries (a ROS 2 recording's `sensor_msgs/msg/CameraInfo`
    /// topic); none from a file, whose intrinsics are given apart.
    pub intrinsics: Option<Intrinsics>,
    /// Where tf places the camera frame, when it gives it a parent (a ROS 2 recording).
    pub camera_mount: Option<CameraMount>,
    /// The clock offset used (camera − robot), seconds; none for a file, whose records are
    /// paired already.
    pub time_offset: Option<f64>,
    /// What reading found worth telling, in order.
    pub notes: Vec<Note>,
}

impl FrameRecording {
    /// Reads the frames of a calibration on the pixels from `source`: a JSON Lines file of
    /// records with `detections` (SPEC sec. 9; `-` reads standard input), or a ROS 2 recording
    /// whose `BagFrames::tags` names the tag its target topic
    /// detects (robot poses from tf at each image's stamp less the clock offset, the intrinsics
    /// of its `CameraInfo` topic). A file's first bad record ends the reading with its
    /// [`Error::Parse`] (file, line, field); in a recording one bad message costs that message
    /// (told in a [`Note::BagTags`]).
    ///
    /// Errors: two pose streams (they carry no detections), a pose-file format named other than
    /// JSON Lines, a clock offset for a file (its records are paired), a recording without its
    /// tag, and the readers' own ([`Recording::read`](super::Recording::read)).
    pub fn read(source: &Source, options: &RecordingOptions) -> Result<Self> {
        check_options(options)?;
        match source {
            Source::File { path, format } => {
                if !matches!(format, Format::Auto | Format::Jsonl) {
                    return Err(Error::InvalidParameter {
                        name: "format",
                        message: format!(
                            "records with `detections` are JSON Lines; `{}` carries poses only",
                            format.name()
                        ),
                    });
                }
                if options.time_offset.is_some() {
                    return Err(Error::InvalidParameter {
                        name: "time_offset",
                        message: "a clock offset pairs a ROS 2 recording; a file of records gives each robot pose with its image's detections already".into(),
                    });
                }
                let FrameSeries { frames, lines } = read_frames(path)?;
                let names = lines
                    .iter()
                    .map(|l| format!("{}:{l}", path.display()))
                    .collect();
                Ok(Self {
                    frames,
                    lines,
                    names,
                    intrinsics: None,
                    camera_mount: None,
                    time_offset: None,
                    notes: Vec::new(),
                })
            }
            Source::Streams { .. } => Err(Error::InvalidParameter {
                name: "input",
                message: "two pose streams carry no detections: a calibration on the pixels reads a JSON Lines file of records with `detections`, or a ROS 2 recording of a tag's detections".into(),
            }),
            #[cfg(feature = "rosbag")]
            Source::Bag { path, frames } => {
                let Some(tags) = &frames.tags else {
                    return Err(Error::InvalidParameter {
                        name: "tags",
                        message: "a ROS 2 recording is calibrated on the pixels from a tag's detections: name the tag (its size) whose detections the target topic carries".into(),
                    });
                };
                super::bag::read_bag_frames(path, frames, tags, options)
            }
        }
    }

    /// The records of a recording on the pixels one at a time, as they come (a stream: `handeye
    /// online --intrinsics`), each with its line number, from `input` named `source` in
    /// messages: the reader of [`FrameRecording::read`] record by record. A bad record is its
    /// own [`Error::Parse`] (file, line, field) and the reading goes on with the next line;
    /// blank lines and `#` comments are skipped; a failing input ends it after its error.
    pub fn records<R: BufRead>(
        input: R,
        source: &str,
    ) -> impl Iterator<Item = Result<(usize, Frame)>> + use<'_, R> {
        frame_records(input, source)
    }
}
