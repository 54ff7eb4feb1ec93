//! One entry for reading every input: a pose file (any [`Format`], a ViSP directory, standard
//! input), two stamped streams, or a ROS 2 recording, read into a [`Recording`] of pose pairs with
//! their names, stamps, the clock offset used and the notes a face shows; the same [`Source`]
//! read into a [`FrameRecording`] for a calibration on the pixels (a JSON Lines file of records
//! with `detections`, a ROS 2 recording of a tag's detections).

use std::io::BufRead;
use std::path::{Path, PathBuf};

use crate::io::sync::{MAX_TIME_OFFSET, TimeOffset, pair_stream_files};
use crate::io::{
    Conventions, DegreeAngles, Format, PoseInput, PoseReader, PoseSeries, Projections,
    StampedPosePair, at_least_two_pairs, open_poses_as, parse_error, read_records,
};
use crate::model::error::{Error, Result};
use crate::model::findings::{Reading, Written, WrittenAs};
use crate::model::motion::{PosePair, Setup};
use crate::model::rotation::Rotations;

#[cfg(feature = "rosbag")]
mod bag;
mod convention;
mod frames;
mod mount;
mod note;

pub use frames::FrameRecording;
pub use mount::{CameraMount, MountFrame};
pub use note::Note;

/// Where a [`Recording`] is read from.
#[derive(Debug, Clone, PartialEq)]
pub enum Source {
    /// A pose-pair file in `format` (JSON Lines, CSV, OpenCV-YAML pairs, moveit JSON), a
    /// directory of ViSP pose files, or `-` for standard input.
    File {
        /// The file or directory; `-` reads standard input.
        path: PathBuf,
        /// Its format ([`Format::Auto`]: by extension, else by content).
        format: Format,
    },
    /// Two stamped streams `t x y z qx qy qz qw` (the ethz-asl and TUM layout), paired at the
    /// camera's stamps.
    Streams {
        /// The robot stream (`base_from_gripper`).
        robot: PathBuf,
        /// The camera stream (`target_from_camera`).
        camera: PathBuf,
    },
    /// A ROS 2 recording (a rosbag2 directory, an `.mcap` or a `.db3` file) and its frames.
    #[cfg(feature = "rosbag")]
    Bag {
        /// The recording.
        path: PathBuf,
        /// The frames (and target topic) the pose pairs are made of.
        frames: BagFrames,
    },
}

/// The frames of a ROS 2 recording that make the pose pairs.
#[cfg(feature = "rosbag")]
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BagFrames {
    /// The robot's base frame in `/tf` (e.g. `base_link`).
    pub base: String,
    /// The gripper's frame (e.g. `tool0`).
    pub gripper: String,
    /// The camera frame X is found for: the root of the camera's subtree in tf (e.g.
    /// `camera_link`), or a frame below it (an optical frame), for which [`Recording::camera_mount`]
    /// says where tf places it and so what to publish.
    pub camera: String,
    /// The target's frame in `/tf` (e.g. `board`); with a `TransformStamped` target topic its
    /// `child_frame_id` must be it.
    pub target: Option<String>,
    /// A `geometry_msgs/msg/PoseStamped` or `TransformStamped` topic of the target's pose; none:
    /// the target is in `/tf`. With `tags`, an `apriltag_msgs/msg/AprilTagDetectionArray` topic
    /// of the tag's detections.
    pub target_topic: Option<String>,
    /// The tag whose detections `target_topic` carries, for a calibration on the pixels
    /// ([`FrameRecording::read`]); none: the target topic (or tf) gives the target's pose.
    pub tags: Option<crate::io::rosbag::BagTags>,
}

/// How a [`Recording`] is read; `Default` gives the values on each field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RecordingOptions {
    /// Camera on the gripper or fixed: the `auto` offset search pairs the poses for it. Default
    /// eye-in-hand.
    pub setup: Setup,
    /// The clock offset (camera clock − robot clock) of two streams or a recording. None (the
    /// default): estimated as with [`TimeOffset::Auto`] when the streams allow it, else 0 s with
    /// a note saying why ([`Note::NoTimeOffset`]); an unnoticed offset of a few tens of
    /// milliseconds moves X by millimetres. Refused for a pose file, whose pairs are made.
    pub time_offset: Option<TimeOffset>,
    /// A camera sample in a gap of the robot's poses longer than this is dropped, seconds.
    /// Default 0.1.
    pub max_gap: f64,
    /// The reading the poses will be solved under (a `fix`): the clock offset is searched on the
    /// streams so read, since a quaternion order mixed up changes their angular speeds. The poses
    /// returned are as the input gives them. Default [`Reading::AsGiven`].
    pub reading: Reading,
    /// How each side writes its rotations, where the numbers do not say (stamped streams, CSV
    /// columns; in JSON a field of another convention is then refused). Default: none named
    /// (`x y z w` quaternions, or the JSON fields' own). A ROS 2 recording and the formats of
    /// other tools fix their own, and refuse a name.
    pub rotations: Rotations,
}

impl Default for RecordingOptions {
    fn default() -> Self {
        Self {
            setup: Setup::EyeInHand,
            time_offset: None,
            max_gap: 0.1,
            reading: Reading::AsGiven,
            rotations: Rotations::default(),
        }
    }
}

/// The pose pairs of an input, read whole, with what a face needs to name and report them.
///
/// # Example
/// ```
/// use handeye::io::{Format, Recording, RecordingOptions, Source};
///
/// let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../testdata/opencv/opencv_eye-in-hand_exact_10_11.jsonl");
/// let source = Source::File { path: path.into(), format: Format::Auto };
/// let recording = Recording::read(&source, &RecordingOptions::default())?;
/// assert!(recording.poses.len() >= 2);
/// assert!(recording.names[0].ends_with(".jsonl:1"));
/// # Ok::<(), handeye::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Recording {
    /// The pose pairs (`base_from_gripper`, `camera_from_target`), in input order.
    pub poses: Vec<PosePair>,
    /// A name for each pair, for messages: `file:line`, `camera at t = … s`, or the recording's
    /// topic, message number and stamp.
    pub names: Vec<String>,
    /// Each pair's place: its line in a file, its sample number among the paired camera samples
    /// (from 1), or its message number in the recording's target topic.
    pub lines: Vec<usize>,
    /// Each pair's time stamp, seconds, where the input gives one.
    pub stamps: Vec<Option<f64>>,
    /// The clock offset used (camera − robot, seconds): always for two streams and a recording,
    /// never for a pose file.
    pub time_offset: Option<f64>,
    /// Its one-sigma, seconds, when it was estimated.
    pub time_offset_sigma: Option<f64>,
    /// When it was estimated: how well the poses paired at it agree on one X
    /// ([`FoundOffset::agreement_deg`](crate::io::sync::FoundOffset::agreement_deg)), degrees.
    pub time_offset_agreement_deg: Option<f64>,
    /// With `auto`: the angular speeds' correlation at each offset searched,
    /// `[offset s, correlation]`.
    pub offset_curve: Option<Vec<[f64; 2]>>,
    /// For a ROS 2 recording: where the target's pose came from (`/board_pose`, or
    /// `/tf camera → board`).
    pub target_source: Option<String>,
    /// For a ROS 2 recording whose tf gives the camera frame a parent: where it places it, and
    /// so the frame X is to be published for (also told as [`Note::CameraMount`]).
    pub camera_mount: Option<CameraMount>,
    /// What reading found worth telling, in order.
    pub notes: Vec<Note>,
    /// The directions in which the input wrote its poses (`Options::written` of a calibration).
    pub written: Written,
    /// Each pair's joint angles (radians, the robot's joint order), where a JSON Lines file gives
    /// every record's (`"joints"`, SPEC sec. 9; `Options::joints` of a calibration); else empty.
    pub joints: Vec<Vec<f64>>,
}

impl Recording {
    /// The refusal of an offset searched that pairs the poses into no agreement on one X
    /// ([`Error::OffsetNotFound`]): a solve on such pairs is not an answer. Asked after the
    /// readings are checked (a misread input disagrees at every offset, and is said as itself).
    pub fn failed_offset(&self) -> Option<Error> {
        let (offset, agreement_deg) = (self.time_offset?, self.time_offset_agreement_deg?);
        crate::io::sync::offset_failed(offset, agreement_deg).then_some(Error::OffsetNotFound {
            offset,
            at_edge: crate::io::sync::at_search_edge(offset),
            agreement_deg,
            searched: crate::io::sync::OffsetOptions::default().max_offset,
            limit_deg: crate::io::sync::OFFSET_AGREEMENT_DEG,
        })
    }

    /// `result`, a job's answer on these poses, judged by the clock offset searched: when the
    /// search failed ([`Recording::failed_offset`]) the answer, or a refusal of it, is replaced by
    /// [`Error::OffsetNotFound`] (a solve on pairs no offset agrees on says nothing of the
    /// motions), except a misreading, which disagrees at every offset and is said as itself.
    /// Every job on a recording of two streams (`calibrate`, `verify`, `advise`) passes its
    /// answer through here.
    pub fn offset_checked<T>(&self, result: Result<T>) -> Result<T> {
        match (self.failed_offset(), result) {
            (None, result) | (Some(_), result @ Err(Error::Misread { .. })) => result,
            (Some(failed), _) => Err(failed),
        }
    }

    /// Reads `source` whole.
    ///
    /// Errors: the reader's own (file, line and field named); fewer than 2 pose pairs in a pose
    /// file read as a stream or in two streams; an `auto` offset that cannot be found
    /// ([`Error::TimeOffset`], naming the streams); a non-finite offset or a `max_gap` not above 0.
    pub fn read(source: &Source, options: &RecordingOptions) -> Result<Self> {
        Self::read_telling(source, options, &mut |_| {})
    }

    /// [`Recording::read`], telling each note to `tell` as it is found: a face shows the notes
    /// found before an error too.
    ///
    /// With a rotation convention named (`options.rotations`) and poses that fit poorly, the same
    /// numbers are read in each other convention of as many numbers and the same unit, and the
    /// input is refused ([`Error::Misread`], naming the convention) when one of them fits far
    /// better.
    pub fn read_telling(
        source: &Source,
        options: &RecordingOptions,
        tell: &mut dyn FnMut(&Note),
    ) -> Result<Self> {
        let named = Conventions::named(options.rotations);
        let recording = read_source(source, options, named, tell)?;
        convention::check_named(source, options, &recording)?;
        Ok(recording)
    }

    /// The pose pairs with their places and stamps, as a pose file's reader gives them.
    pub fn records(&self) -> Vec<StampedPosePair> {
        self.poses
            .iter()
            .zip(&self.lines)
            .zip(&self.stamps)
            .enumerate()
            .map(|(k, ((&pose, &line), &stamp))| {
                let record = StampedPosePair::new(line, stamp, pose, self.written);
                match self.joints.get(k) {
                    Some(q) => record.with_joints(q),
                    None => record,
                }
            })
            .collect()
    }
}

/// Reads `source`, its numbers read as `conventions` says, telling each note as it is found.
fn read_source(
    source: &Source,
    options: &RecordingOptions,
    conventions: Conventions,
    tell: &mut dyn FnMut(&Note),
) -> Result<Recording> {
    check_options(options)?;
    if let (Source::File { .. }, Some(_)) = (source, options.time_offset) {
        return Err(Error::InvalidParameter {
            name: "time_offset",
            message: "a clock offset pairs two stamped streams or a ROS 2 recording; a pose file gives its pose pairs already paired, and no offset would change them".into(),
        });
    }
    let mut notes = Notes {
        tell,
        notes: Vec::new(),
    };
    let mut recording = match source {
        Source::File { path, format } => {
            read_file(path, *format, (options, conventions), &mut notes)?
        }
        Source::Streams { robot, camera } => {
            let options = RecordingOptions {
                rotations: read_as(conventions),
                ..*options
            };
            read_streams(robot, camera, &options, &mut notes)?
        }
        #[cfg(feature = "rosbag")]
        Source::Bag { path, frames } => {
            if frames.tags.is_some() {
                return Err(Error::InvalidParameter {
                    name: "tags",
                    message: "a tag's detections carry no target pose: they are calibrated on their pixels, with the camera's intrinsics (FrameRecording::read)".into(),
                });
            }
            crate::io::pose_reader::no_rotations(
                options.rotations,
                &path.display().to_string(),
                "a ROS 2 recording (tf and pose messages: x, y, z, w quaternions)",
            )?;
            bag::read_bag(path, frames, options, &mut notes)?
        }
    };
    recording.notes = notes.notes;
    Ok(recording)
}

/// The conventions positional numbers (stamped streams) are read in: those to read them as, where
/// given, else those named.
fn read_as(conventions: Conventions) -> Rotations {
    Rotations {
        robot: conventions.read_as.robot.or(conventions.named.robot),
        camera: conventions.read_as.camera.or(conventions.named.camera),
    }
}

/// Refuses a time offset that is not finite or beyond [`MAX_TIME_OFFSET`] in size, and a
/// `max_gap` not above 0.
fn check_options(options: &RecordingOptions) -> Result<()> {
    if let Some(TimeOffset::Fixed(t)) = options.time_offset
        && !(t.is_finite() && t.abs() <= MAX_TIME_OFFSET)
    {
        return Err(Error::InvalidParameter {
            name: "time_offset",
            message: format!(
                "expected a finite number of seconds of at most {MAX_TIME_OFFSET:e} in size (127 years), found {t:e}"
            ),
        });
    }
    if !(options.max_gap > 0.0 && options.max_gap.is_finite()) {
        return Err(Error::InvalidParameter {
            name: "max_gap",
            message: format!("expected seconds above 0, found {}", options.max_gap),
        });
    }
    Ok(())
}

/// The notes found so far, each told as it is added.
struct Notes<'a> {
    tell: &'a mut dyn FnMut(&Note),
    notes: Vec<Note>,
}

impl Notes<'_> {
    fn add(&mut self, note: Note) {
        (self.tell)(&note);
        self.notes.push(note);
    }

    /// Lines skipped before the first record of a stream, if any was not blank nor a comment.
    fn preamble<R: BufRead>(&mut self, reader: &PoseReader<R>, source: &str) {
        if let Some(p) = reader.preamble() {
            self.add(Note::Preamble {
                source: source.to_string(),
                preamble: p.clone(),
            });
        }
    }

    /// Angles in degrees that look like radians, if any.
    fn degrees(&mut self, source: &str, degrees: &DegreeAngles) {
        for note in Note::small_degrees(source, degrees) {
            self.add(note);
        }
    }

    /// Rotation matrices projected, if any.
    fn projections(&mut self, source: &str, projections: Projections) {
        if projections.note().is_some() {
            self.add(Note::Projections {
                source: source.to_string(),
                projections,
            });
        }
    }
}

/// A pose file, a ViSP directory or standard input (`-`).
fn read_file(
    path: &Path,
    format: Format,
    (options, conventions): (&RecordingOptions, Conventions),
    notes: &mut Notes<'_>,
) -> Result<Recording> {
    let setup = options.setup;
    let source = path.display().to_string();
    let series = if path.as_os_str() == "-" {
        let reader =
            PoseReader::with_conventions(std::io::stdin().lock(), "-", format, conventions)?;
        read_stream(reader, &source, notes)?
    } else {
        match open_poses_as(path, format, conventions)? {
            PoseInput::Whole(series) => {
                series.check_setup(setup, &source)?;
                // Read whole: as many pairs as the file has, the count checked by the solver.
                notes.projections(&source, series.projections);
                return Ok(file_recording(series, &source));
            }
            // The joint angles come with the pairs, in the same single pass (a pipe is read once).
            PoseInput::Stream(reader) => read_stream(reader, &source, notes)?,
        }
    };
    at_least_two_pairs(series.pairs.len(), source.clone())?;
    Ok(file_recording(series, &source))
}

/// Every record of a streaming reader, the first bad one an error.
fn read_stream<R: BufRead>(
    mut reader: PoseReader<R>,
    source: &str,
    notes: &mut Notes<'_>,
) -> Result<PoseSeries> {
    notes.preamble(&reader, source);
    let series = read_records(&mut reader)?;
    notes.projections(source, reader.projections());
    notes.degrees(source, &reader.degree_angles());
    Ok(series)
}

/// A pose file's recording: each pair named `file:line`.
fn file_recording(series: PoseSeries, source: &str) -> Recording {
    Recording {
        names: series
            .lines
            .iter()
            .map(|line| format!("{source}:{line}"))
            .collect(),
        poses: series.pairs,
        lines: series.lines,
        stamps: series.stamps,
        written: series.written,
        joints: series.joints,
        ..Recording::default()
    }
}

/// Two stamped streams, paired at the camera's stamps.
fn read_streams(
    robot: &Path,
    camera: &Path,
    options: &RecordingOptions,
    notes: &mut Notes<'_>,
) -> Result<Recording> {
    let pair = |offset| {
        pair_stream_files(
            robot,
            camera,
            options.setup,
            (offset, options.reading),
            options.max_gap,
            options.rotations,
        )
    };
    let pairing = match options.time_offset {
        Some(offset) => pair(offset),
        None => match pair(TimeOffset::Auto) {
            // The search's own refusals: the streams do not tell their offset.
            Err(Error::InvalidParameter { message, .. }) => {
                notes.add(Note::NoTimeOffset { why: message });
                pair(TimeOffset::Fixed(0.0))
            }
            result => result,
        },
    }
    .map_err(|e| match e {
        // The offset search's own refusals say nothing of the files: name them.
        Error::InvalidParameter { .. } => Error::TimeOffset {
            streams: format!("{} and {}", robot.display(), camera.display()),
            source: Box::new(e),
        },
        e => e,
    })?;
    for (file, count) in [robot, camera].iter().zip(pairing.reordered) {
        if count > 0 {
            notes.add(Note::Reordered {
                file: file.display().to_string(),
                count,
            });
        }
    }
    let (robot_degrees, camera_degrees) = (
        DegreeAngles {
            camera: None,
            ..pairing.degrees
        },
        DegreeAngles {
            robot: None,
            ..pairing.degrees
        },
    );
    notes.degrees(&robot.display().to_string(), &robot_degrees);
    notes.degrees(&camera.display().to_string(), &camera_degrees);
    if let Some(found) = &pairing.correlated {
        notes.add(Note::time_offset(found));
    }
    let s = pairing.synced;
    if s.dropped_outside + s.dropped_gap > 0 {
        notes.add(Note::Dropped {
            outside: s.dropped_outside,
            gap: s.dropped_gap,
            max_gap: options.max_gap,
        });
    }
    if s.pairs.len() < 2 {
        // The camera stamps decide the pairs: name that file.
        return Err(parse_error(
            &camera.display().to_string(),
            0,
            "t",
            format!(
                "{} camera sample(s) within the robot stream {} ({} outside it, {} in its gaps longer than {} s){}: at least 2 pose pairs are needed",
                s.pairs.len(),
                robot.display(),
                s.dropped_outside,
                s.dropped_gap,
                options.max_gap,
                if pairing.time_offset == 0.0 {
                    String::new()
                } else {
                    format!(
                        ", the camera stamps shifted by the clock offset of {:e} s",
                        pairing.time_offset
                    )
                }
            ),
        ));
    }
    let camera = camera.display().to_string();
    Ok(Recording {
        names: s
            .stamps
            .iter()
            .map(|t| format!("{camera} at t = {t:.3} s"))
            .collect(),
        lines: (1..=s.pairs.len()).collect(),
        stamps: s.stamps.iter().copied().map(Some).collect(),
        poses: s.pairs,
        time_offset: Some(pairing.time_offset),
        time_offset_sigma: pairing.correlated.as_ref().map(|f| f.sigma),
        time_offset_agreement_deg: pairing.correlated.as_ref().map(|f| f.agreement_deg),
        offset_curve: pairing.correlated.map(|f| f.correlated.curve),
        // A camera stream holds `target_from_camera`.
        written: Written {
            robot: WrittenAs::Named,
            camera: WrittenAs::Inverse,
            frames: false,
        },
        ..Recording::default()
    })
}
