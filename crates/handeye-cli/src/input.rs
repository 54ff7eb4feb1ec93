//! Where the pose pairs come from: a pose-pair file (or stdin), two timestamped streams, or a ROS 2
//! recording.

use std::cell::RefCell;
use std::fs::File;
use std::io::{BufRead, BufReader, Read};
use std::path::PathBuf;
use std::rc::Rc;
use std::sync::mpsc::{Receiver, TryRecvError, sync_channel};
use std::thread::JoinHandle;

use anyhow::Result;
use clap::Args as ClapArgs;
use handeye::io::rosbag::is_bag;
use handeye::io::{
    BagFrames, CameraMount, Format, Note, PoseStream, Recording, RecordingOptions, Source,
    StampedPosePair, TimeOffset,
};
use handeye::{Reading, Rotations, Setup};

/// The help heading of the ROS 2 recording's flags.
const BAG_HEADING: &str = "ROS 2 recording (INPUT a rosbag2 directory, .mcap or .db3)";

/// Input options shared by `calibrate` and `online`.
#[derive(ClapArgs, Debug, Clone)]
pub struct InputArgs {
    /// Pose-pair file (JSON Lines, CSV, OpenCV-YAML pairs, moveit JSON; a directory of ViSP pose
    /// files; `-` for standard input), or a ROS 2 recording (a rosbag2 directory, an `.mcap` or a
    /// `.db3` file; with --base-frame …). Not with --robot/--camera.
    #[arg(value_name = "INPUT", required_unless_present = "robot")]
    pub input: Option<PathBuf>,
    /// Format of INPUT.
    #[arg(long, default_value_t = Format::Auto, value_parser = crate::values::named::<Format>())]
    pub format: Format,
    /// Robot stream `t x y z qx qy qz qw` (base_from_gripper), ethz-asl / TUM layout.
    #[arg(long, requires = "camera", conflicts_with = "input")]
    pub robot: Option<PathBuf>,
    /// Camera stream `t x y z qx qy qz qw` (target_from_camera), paired with --robot.
    #[arg(long, requires = "robot")]
    pub camera: Option<PathBuf>,
    /// Camera clock minus robot clock, seconds, or `auto` to estimate it (an error when the
    /// streams cannot tell). Default: estimated when the streams allow it, else 0 (said on stderr).
    #[arg(long, value_parser = crate::values::time_offset)]
    pub time_offset: Option<TimeOffset>,
    /// Drop camera samples in gaps of the robot stream longer than this, seconds [default: 0.1].
    #[arg(long, value_parser = crate::values::max_gap)]
    pub max_gap: Option<f64>,
    /// ROS 2 recording: the robot's base frame in /tf (e.g. base_link).
    #[arg(
        long,
        help_heading = BAG_HEADING
    )]
    pub base_frame: Option<String>,
    /// ROS 2 recording: the gripper's frame (e.g. tool0); base_from_gripper is composed along the
    /// tf tree, static and dynamic transforms alike.
    #[arg(
        long,
        help_heading = BAG_HEADING
    )]
    pub gripper_frame: Option<String>,
    /// ROS 2 recording: the camera frame X is found for: the root of the camera's subtree in tf
    /// (e.g. camera_link, under which the camera driver publishes its optical frames). For a
    /// frame with a parent there (camera_color_optical_frame), X is its own but is published for
    /// the root (tf gives a frame one parent), with a warning; for a camera placed in the robot's
    /// tree already (calibrated before), X is compared with tf's, not published.
    #[arg(
        long,
        help_heading = BAG_HEADING
    )]
    pub camera_frame: Option<String>,
    /// ROS 2 recording: the target's frame in /tf (e.g. board); with --target-topic of
    /// TransformStamped its child_frame_id must be it.
    #[arg(
        long,
        help_heading = BAG_HEADING
    )]
    pub target_frame: Option<String>,
    /// ROS 2 recording: a geometry_msgs/PoseStamped or TransformStamped topic of the target's
    /// pose, its header naming the camera frame (or a frame tf relates to it). Without it the
    /// target's pose is taken from /tf.
    #[arg(
        long,
        help_heading = BAG_HEADING
    )]
    pub target_topic: Option<String>,
    /// ROS 2 recording, with --method reprojection and a --target-topic of
    /// apriltag_msgs/AprilTagDetectionArray (apriltag_ros): the side of the tag's black square,
    /// metres. Its corners are placed in AprilTag's order: (−s/2, s/2), (s/2, s/2), (s/2, −s/2),
    /// (−s/2, −s/2) in the tag's frame.
    #[arg(
        long,
        value_name = "METRES",
        help_heading = BAG_HEADING
    )]
    pub tag_size: Option<f64>,
    /// ROS 2 recording, with --tag-size: the id of the tag that is the target (detections of
    /// other ids are left out). Default: the only id the topic shows.
    #[arg(
        long,
        value_name = "ID",
        help_heading = BAG_HEADING
    )]
    pub tag_id: Option<i32>,
    /// ROS 2 recording, with --tag-size: a sensor_msgs/CameraInfo topic for the intrinsics
    /// (--intrinsics FILE overrides it). Default: the recording's one topic named `…camera_info`.
    #[arg(
        long,
        value_name = "TOPIC",
        help_heading = BAG_HEADING
    )]
    pub camera_info_topic: Option<String>,
    /// Camera on the gripper (X = gripper_from_camera) or fixed (X = base_from_camera)
    /// [default: eye-in-hand]
    #[arg(long, value_parser = crate::values::named::<Setup>())]
    pub setup: Option<Setup>,
    /// How the input writes rotations, where its numbers cannot say: the --robot/--camera
    /// streams (`t x y z` and the convention's numbers) and CSV columns (`<frame>_x, _y, _z` and
    /// the convention's, e.g. `_a, _b, _c` for kuka-abc); JSON fields name their own
    /// (`kuka_abc_deg`, `rvec`, …) and need no flag. NAME for every pose, or robot=NAME /
    /// camera=NAME for one side (repeatable). NAME (numbers; unit; R): quaternion-xyzw (qx qy qz
    /// qw; the default), quaternion-wxyz (q1 q2 q3 q4, w first: ABB), rvec (rx ry rz; radians;
    /// OpenCV, Universal Robots), kuka-abc (a b c; degrees; Rz(A)·Ry(B)·Rx(C)), mitsubishi-abc (a
    /// b c; degrees; Rz(C)·Ry(B)·Rx(A)), fanuc-wpr (w p r; degrees; Rz(R)·Ry(P)·Rx(W)),
    /// yaskawa-rxryrz (rx ry rz; degrees; Rz(Rz)·Ry(Ry)·Rx(Rx)), staubli-xyz (rx ry rz; degrees;
    /// Rx(Rx)·Ry(Ry)·Rz(Rz)), kawasaki-oat (o a t; degrees; Rz(O)·Ry(A)·Rz(T)), rpy (roll pitch
    /// yaw; radians; Rz(yaw)·Ry(pitch)·Rx(roll), ROS), rpy-deg (the same in degrees).
    #[arg(long, value_name = "NAME|robot=NAME|camera=NAME", value_parser = crate::values::rotation)]
    pub rotation: Vec<String>,
}

impl InputArgs {
    /// The setup: the one given, else eye-in-hand.
    pub fn setup(&self) -> Setup {
        self.setup.unwrap_or_default()
    }

    /// The setup given with `--setup`, if any (`verify` takes the saved X's otherwise).
    pub fn given_setup(&self) -> Option<Setup> {
        self.setup
    }

    /// The rotation conventions named by `--rotation`.
    pub fn rotations(&self) -> handeye::Result<Rotations> {
        Rotations::parse(&self.rotation)
    }

    /// Whether INPUT is a ROS 2 recording.
    pub fn is_bag(&self) -> bool {
        self.input
            .as_ref()
            .is_some_and(|p| p.as_os_str() != "-" && is_bag(p))
    }
}

/// The source of a ROS 2 recording and its frames, or `None` when INPUT is not one (and no
/// recording flag is given).
fn bag_source(args: &InputArgs) -> Result<Option<Source>> {
    let flags = [
        ("--base-frame", &args.base_frame),
        ("--gripper-frame", &args.gripper_frame),
        ("--camera-frame", &args.camera_frame),
        ("--target-frame", &args.target_frame),
        ("--target-topic", &args.target_topic),
    ];
    let Some(path) = args.input.as_ref().filter(|_| args.is_bag()) else {
        if let Some((flag, _)) = flags.iter().find(|(_, v)| v.is_some()) {
            return Err(handeye::Error::InvalidParameter {
                name: "input",
                message: format!(
                    "{flag} is for a ROS 2 recording (a rosbag2 directory, an .mcap or a .db3 file), and INPUT is not one"
                ),
            }
            .into());
        }
        return Ok(None);
    };
    let missing: Vec<&str> = flags[..3]
        .iter()
        .filter(|(_, v)| v.is_none())
        .map(|(f, _)| *f)
        .chain(
            (args.target_frame.is_none() && args.target_topic.is_none())
                .then_some("--target-frame (or --target-topic)"),
        )
        .collect();
    if !missing.is_empty() {
        return Err(handeye::Error::InvalidParameter {
            name: "input",
            message: format!(
                "{} is a ROS 2 recording: name its frames with {} (`handeye inspect {}` lists the frames and topics)",
                path.display(),
                missing.join(", "),
                path.display()
            ),
        }
        .into());
    }
    let frames = BagFrames {
        base: args.base_frame.clone().unwrap_or_default(),
        gripper: args.gripper_frame.clone().unwrap_or_default(),
        camera: args.camera_frame.clone().unwrap_or_default(),
        target: args.target_frame.clone(),
        target_topic: args.target_topic.clone(),
        tags: None,
    };
    Ok(Some(Source::Bag {
        path: path.clone(),
        frames,
    }))
}

/// The flags of a tag's detections in a ROS 2 recording, given.
fn tag_flags(args: &InputArgs) -> Option<&'static str> {
    [
        ("--tag-size", args.tag_size.is_some()),
        ("--tag-id", args.tag_id.is_some()),
        ("--camera-info-topic", args.camera_info_topic.is_some()),
    ]
    .into_iter()
    .find(|(_, given)| *given)
    .map(|(flag, _)| flag)
}

/// The frames of a calibration on the pixels from a ROS 2 recording (`--target-topic` of tag
/// detections, `--tag-size`), its notes told on stderr; `None` when INPUT is not a recording.
pub fn read_bag_pixels(args: &InputArgs) -> Result<Option<handeye::io::FrameRecording>> {
    let Some(Source::Bag { path, mut frames }) = bag_source(args)? else {
        return Ok(None);
    };
    let Some(size) = args.tag_size else {
        return Err(handeye::Error::InvalidParameter {
            name: "tag_size",
            message: "a ROS 2 recording is calibrated on the pixels from a tag's detections: give --target-topic (apriltag_msgs/AprilTagDetectionArray) and --tag-size METRES".into(),
        }
        .into());
    };
    frames.tags = Some(handeye::io::rosbag::BagTags {
        size,
        id: args.tag_id,
        camera_info_topic: args.camera_info_topic.clone(),
    });
    let read = handeye::io::FrameRecording::read(
        &Source::Bag { path, frames },
        &options(args, Reading::AsGiven)?,
    )?;
    for note in &read.notes {
        match note {
            Note::CameraMount { .. } => crate::tell!("warning: {note}"),
            _ => crate::tell!("{note}"),
        }
    }
    Ok(Some(read))
}

/// The options of [`Recording::read`] from the flags, for poses to be solved read as `reading`.
fn options(args: &InputArgs, reading: Reading) -> Result<RecordingOptions> {
    Ok(RecordingOptions {
        setup: args.setup(),
        time_offset: args.time_offset,
        reading,
        max_gap: args.max_gap.unwrap_or(DEFAULT_MAX_GAP),
        rotations: args.rotations()?,
    })
}

/// The default of `--max-gap`, seconds.
const DEFAULT_MAX_GAP: f64 = 0.1;

/// Refuses `--time-offset` and `--max-gap` on a pose file: they pair two streams or a recording,
/// and a pose file's pairs are made (they would be ignored without a word).
fn pose_file_flags(args: &InputArgs) -> Result<()> {
    let given = [
        ("--time-offset", args.time_offset.is_some()),
        ("--max-gap", args.max_gap.is_some()),
    ];
    if let Some((flag, _)) = given.iter().find(|(_, given)| *given) {
        return Err(handeye::Error::InvalidParameter {
            name: "input",
            message: format!(
                "{flag} pairs two stamped streams (--robot, --camera) or a ROS 2 recording; INPUT is a pose file, whose pose pairs are made already"
            ),
        }
        .into());
    }
    Ok(())
}

/// Reads `source`, telling its notes on stderr as they come (a camera frame that has a parent in
/// a recording's tf as a warning: X published for it breaks tf); a failed `auto` offset search is
/// named by the flag.
fn read(source: &Source, options: &RecordingOptions) -> Result<Recording> {
    let tell = &mut |note: &Note| match note {
        Note::CameraMount { .. } => crate::tell!("warning: {note}"),
        _ => crate::tell!("{note}"),
    };
    Recording::read_telling(source, options, tell).map_err(|e| match e {
        handeye::Error::TimeOffset { streams, source } => {
            anyhow::Error::new(*source).context(format!("--time-offset auto on {streams}"))
        }
        e => e.into(),
    })
}

/// The ROS 2 recording or the two streams of `args` read whole, or `None` for a pose file (or
/// stdin).
fn read_recorded(args: &InputArgs, reading: Reading) -> Result<Option<Recording>> {
    if let Some(flag) = tag_flags(args) {
        return Err(handeye::Error::InvalidParameter {
            name: "input",
            message: format!(
                "{flag} reads a tag's detections in a ROS 2 recording, calibrated on the pixels: it needs `calibrate --method reprojection`"
            ),
        }
        .into());
    }
    if let Some(source) = bag_source(args)? {
        return read(&source, &options(args, reading)?).map(Some);
    }
    let (Some(robot), Some(camera)) = (&args.robot, &args.camera) else {
        pose_file_flags(args)?;
        return Ok(None);
    };
    let source = Source::Streams {
        robot: robot.clone(),
        camera: camera.clone(),
    };
    read(&source, &options(args, reading)?).map(Some)
}

/// All pose pairs of the input (a batch solve), each pose's name for messages (`file:line`, or
/// the camera stream's file and time stamp), and the time offset used for streams.
pub fn read_all(args: &InputArgs, reading: Reading) -> Result<Recording> {
    let recording = match read_recorded(args, reading)? {
        Some(recording) => recording,
        None => {
            let source = Source::File {
                path: args.input.clone().unwrap_or_else(|| PathBuf::from("-")),
                format: args.format,
            };
            read(&source, &options(args, reading)?)?
        }
    };
    Ok(recording)
}

/// A pose stream that tells its notes on stderr: those of its opening at once, the rest when it
/// ends.
struct NotingStream(PoseStream);

impl NotingStream {
    fn new(stream: PoseStream) -> Self {
        let mut noting = Self(stream);
        noting.tell();
        noting
    }

    fn tell(&mut self) {
        for note in self.0.notes() {
            crate::tell!("{note}");
        }
    }
}

impl Iterator for NotingStream {
    type Item = handeye::Result<StampedPosePair>;

    fn next(&mut self) -> Option<Self::Item> {
        let next = self.0.next();
        if next.is_none() {
            self.tell();
        }
        next
    }
}

/// Pose pairs one at a time, each with its place, or the error of a bad record.
pub type Records = Box<dyn Iterator<Item = handeye::Result<StampedPosePair>>>;

/// What opening a record stream told besides its records.
pub struct Opened {
    /// Its name for messages.
    pub source: String,
    /// The clock offset two streams (or a recording) were paired with.
    pub offset: Option<Offset>,
    /// A recording's: where its tf places the camera frame, when it gives it a parent.
    pub camera_mount: Option<CameraMount>,
}

/// The clock offset two streams (or a recording) were paired with.
pub struct Offset {
    /// Camera clock minus robot clock, seconds.
    pub seconds: f64,
    /// With `--time-offset auto` on two streams: the correlation curve, `[offset s, correlation]`.
    pub curve: Option<Vec<[f64; 2]>>,
}

/// Bytes read from stdin or a file at a time by [`records`].
const READ_BUFFER: usize = 64 * 1024;

/// A buffered reader that calls `before_wait` whenever its buffer is empty, before it reads (and
/// perhaps waits for) more input: `online` writes out its buffered output lines there.
struct WaitHook<R> {
    input: BufReader<R>,
    before_wait: Rc<dyn Fn()>,
}

impl<R: Read> WaitHook<R> {
    fn new(input: R, before_wait: Rc<dyn Fn()>) -> Self {
        Self {
            input: BufReader::with_capacity(READ_BUFFER, input),
            before_wait,
        }
    }
}

impl<R: Read> Read for WaitHook<R> {
    fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
        if self.input.buffer().is_empty() {
            (self.before_wait)();
        }
        self.input.read(out)
    }
}

impl<R: Read> BufRead for WaitHook<R> {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        if self.input.buffer().is_empty() {
            (self.before_wait)();
        }
        self.input.fill_buf()
    }

    fn consume(&mut self, amount: usize) {
        self.input.consume(amount);
    }
}

/// A record stream for `online`: from stdin, a file, or paired streams, with the name of its
/// source for messages. A file is opened once (a FIFO cannot be read twice). `before_wait` is
/// called before each read of stdin or of the file, which may wait for input.
pub fn records(args: &InputArgs, before_wait: Rc<dyn Fn()>) -> Result<(Records, Opened)> {
    if let Some(recording) = read_recorded(args, Reading::AsGiven)? {
        let source = match (&recording.target_source, &args.camera) {
            (Some(target), _) => format!(
                "{} {target}",
                args.input
                    .as_ref()
                    .map_or(String::new(), |p| p.display().to_string())
            ),
            (None, camera) => camera
                .as_ref()
                .map_or("camera".to_string(), |p| p.display().to_string()),
        };
        let offset = recording.time_offset.map(|seconds| Offset {
            seconds,
            // The correlation curve of two streams only: a recording's is not drawn (yet).
            curve: recording
                .offset_curve
                .clone()
                .filter(|_| recording.target_source.is_none()),
        });
        let records = Box::new(recording.records().into_iter().map(Ok));
        let camera_mount = recording.camera_mount;
        return Ok((
            records,
            Opened {
                source,
                offset,
                camera_mount,
            },
        ));
    }
    let path = args.input.clone().unwrap_or_else(|| PathBuf::from("-"));
    let source = path.display().to_string();
    let (format, rotations, setup) = (args.format, args.rotations()?, args.setup());
    let stream = if path.as_os_str() == "-" {
        let stdin = WaitHook::new(std::io::stdin().lock(), before_wait);
        PoseStream::from_reader(stdin, "-", format, rotations, setup)?
    } else if format == Format::Visp || path.is_dir() {
        PoseStream::open(&path, format, rotations, setup)?
    } else {
        let file = File::open(&path).map_err(|e| handeye::Error::Io {
            file: source.clone(),
            source: e,
        })?;
        PoseStream::from_reader(
            WaitHook::new(file, before_wait),
            &source,
            format,
            rotations,
            setup,
        )?
    };
    Ok((Box::new(NotingStream::new(stream)), opened(source)))
}

/// A pose file's: its name alone.
fn opened(source: String) -> Opened {
    Opened {
        source,
        offset: None,
        camera_mount: None,
    }
}

/// The records of [`records`], read and parsed on a second thread while this one calibrates.
///
/// The reader thread sends them in batches of up to [`BATCH`], and a partial batch whenever it
/// is about to wait for input, so a slow stream is not held back; this thread calls
/// `before_wait` (which writes out the buffered output) whenever no batch is ready. At most
/// [`QUEUED_BATCHES`] batches wait in between, so the memory stays constant. The records come in
/// the order read, as from [`records`] itself.
pub struct ReadAhead {
    batches: Receiver<Vec<handeye::Result<StampedPosePair>>>,
    batch: std::vec::IntoIter<handeye::Result<StampedPosePair>>,
    before_wait: Rc<dyn Fn()>,
    reader: Option<JoinHandle<()>>,
}

/// Records per batch sent by [`ReadAhead`]'s reader thread.
const BATCH: usize = 256;

/// Batches [`ReadAhead`]'s reader may have read ahead.
const QUEUED_BATCHES: usize = 8;

/// [`records`] read ahead on a second thread ([`ReadAhead`]): the same records and what opening
/// told, and the same error when the input cannot be opened.
pub fn read_ahead(args: &InputArgs, before_wait: Rc<dyn Fn()>) -> Result<(ReadAhead, Opened)> {
    let args = args.clone();
    let (batches, received) = sync_channel(QUEUED_BATCHES);
    let (opened, head) = sync_channel(1);
    let reader = std::thread::spawn(move || {
        let pending = Rc::new(RefCell::new(Vec::with_capacity(BATCH)));
        let send = {
            let (pending, batches) = (pending.clone(), batches.clone());
            move || {
                let batch =
                    std::mem::replace(&mut *pending.borrow_mut(), Vec::with_capacity(BATCH));
                // A closed channel: the calibrating thread has stopped, and so does this one.
                batch.is_empty() || batches.send(batch).is_ok()
            }
        };
        let records = match records(&args, {
            let send = send.clone();
            Rc::new(move || {
                send();
            })
        }) {
            Ok((records, head)) => {
                let _ = opened.send(Ok(head));
                records
            }
            Err(e) => {
                let _ = opened.send(Err(e));
                return;
            }
        };
        for record in records {
            pending.borrow_mut().push(record);
            if pending.borrow().len() >= BATCH && !send() {
                return;
            }
        }
        send();
    });
    match head.recv() {
        Ok(Ok(head)) => Ok((
            ReadAhead {
                batches: received,
                batch: Vec::new().into_iter(),
                before_wait,
                reader: Some(reader),
            },
            head,
        )),
        Ok(Err(e)) => Err(e),
        // The reader stopped before it opened the input: only a panic does that.
        Err(_) => std::panic::resume_unwind(
            reader
                .join()
                .err()
                .unwrap_or_else(|| Box::new("the input reader stopped before opening the input")),
        ),
    }
}

impl Iterator for ReadAhead {
    type Item = handeye::Result<StampedPosePair>;

    fn next(&mut self) -> Option<Self::Item> {
        if let Some(record) = self.batch.next() {
            return Some(record);
        }
        let batch = match self.batches.try_recv() {
            Ok(batch) => Some(batch),
            Err(TryRecvError::Empty) => {
                (self.before_wait)();
                self.batches.recv().ok()
            }
            Err(TryRecvError::Disconnected) => None,
        };
        let Some(batch) = batch else {
            // The reader is done; a panic of its own is this thread's too, never a short input.
            if let Some(Err(panic)) = self.reader.take().map(JoinHandle::join) {
                std::panic::resume_unwind(panic);
            }
            return None;
        };
        self.batch = batch.into_iter();
        self.batch.next()
    }
}

/// The robot's DH table of `--robot-model` (`calibrate` and `online`), read.
pub fn robot_model(path: Option<&std::path::Path>) -> anyhow::Result<Option<handeye::Kinematics>> {
    Ok(path.map(handeye::Kinematics::read).transpose()?)
}
