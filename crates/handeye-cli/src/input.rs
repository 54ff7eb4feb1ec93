//! Where the pose pairs come from: a pose-pair file (or stdin), two timestamped streams, or a ROS 2
//! recording.

use std::cell::RefCell;
use std::fs::File;
use std::io::{BufRead, BufReader, Read};
use std::path::PathBuf;
use std::rc::Rc;
use std::sync::mpsc::{Receiver, TryRecvError, sync_channel};
use std::thread::JoinHandle;

use anyhow::{Context, Result};
use clap::Args as ClapArgs;
use handeye::io::rosbag::{BagOptions, BagPairs, is_bag, read_bag_pairs};
use handeye::io::sync::{
    OffsetOptions, StampedPose, TimeOffset, estimate_time_offset, pair_stream_files,
    refine_time_offset,
};
use handeye::io::{
    Format, PoseInput, PoseReader, Projections, StampedPosePair, open_pose_stream, open_poses,
};
use handeye::{PosePair, Setup};

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
    /// Camera clock minus robot clock, seconds, or `auto` to estimate it from the angular speeds.
    #[arg(long, default_value = "0", value_parser = crate::values::time_offset)]
    pub time_offset: String,
    /// Drop camera samples in gaps of the robot stream longer than this, seconds.
    #[arg(long, default_value_t = 0.1, value_parser = crate::values::positive)]
    pub max_gap: f64,
    /// ROS 2 recording: the robot's base frame in /tf (e.g. base_link).
    #[arg(
        long,
        help_heading = "ROS 2 recording (INPUT a rosbag2 directory, .mcap or .db3)"
    )]
    pub base_frame: Option<String>,
    /// ROS 2 recording: the gripper's frame (e.g. tool0); base_from_gripper is composed along the
    /// tf tree, static and dynamic transforms alike.
    #[arg(
        long,
        help_heading = "ROS 2 recording (INPUT a rosbag2 directory, .mcap or .db3)"
    )]
    pub gripper_frame: Option<String>,
    /// ROS 2 recording: the camera frame X is found for (e.g. camera_color_optical_frame).
    #[arg(
        long,
        help_heading = "ROS 2 recording (INPUT a rosbag2 directory, .mcap or .db3)"
    )]
    pub camera_frame: Option<String>,
    /// ROS 2 recording: the target's frame in /tf (e.g. board); with --target-topic of
    /// TransformStamped its child_frame_id must be it.
    #[arg(
        long,
        help_heading = "ROS 2 recording (INPUT a rosbag2 directory, .mcap or .db3)"
    )]
    pub target_frame: Option<String>,
    /// ROS 2 recording: a geometry_msgs/PoseStamped or TransformStamped topic of the target's
    /// pose, its header naming the camera frame (or a frame tf relates to it). Without it the
    /// target's pose is taken from /tf.
    #[arg(
        long,
        help_heading = "ROS 2 recording (INPUT a rosbag2 directory, .mcap or .db3)"
    )]
    pub target_topic: Option<String>,
    /// Camera on the gripper (X = gripper_from_camera) or fixed (X = base_from_camera).
    #[arg(long, default_value_t = Setup::EyeInHand, value_parser = crate::values::named::<Setup>())]
    pub setup: Setup,
}

impl InputArgs {
    /// The setup.
    pub fn setup(&self) -> Setup {
        self.setup
    }

    /// Whether INPUT is a ROS 2 recording.
    pub fn is_bag(&self) -> bool {
        self.input
            .as_ref()
            .is_some_and(|p| p.as_os_str() != "-" && is_bag(p))
    }
}

/// The pose pairs of a ROS 2 recording, or `None` when INPUT is not one.
pub fn bag(args: &InputArgs) -> Result<Option<(BagPairs, Option<f64>)>> {
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
    let mut options = BagOptions {
        base_frame: args.base_frame.clone().unwrap_or_default(),
        gripper_frame: args.gripper_frame.clone().unwrap_or_default(),
        camera_frame: args.camera_frame.clone().unwrap_or_default(),
        target_frame: args.target_frame.clone(),
        target_topic: args.target_topic.clone(),
        time_offset: 0.0,
        max_gap: args.max_gap,
    };
    let time_offset = if args.time_offset == "auto" {
        // Stamped by another clock (a detector that stamps on arrival, say): find the offset on
        // the streams of the recording read as it is, then read it again with that offset.
        let first = read_bag_pairs(path, &options)?;
        auto_offset(
            &first.robot_stream,
            &first.camera_stream,
            args,
            &format!(
                "the robot's tf and {} in {}",
                first.target_source,
                path.display()
            ),
        )?
    } else {
        args.time_offset
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| handeye::Error::InvalidParameter {
                name: "time_offset",
                message: format!(
                    "expected `auto` or seconds (camera clock minus robot clock), found `{}`",
                    args.time_offset
                ),
            })?
    };
    options.time_offset = time_offset;
    let pairs = read_bag_pairs(path, &options)?;
    eprintln!(
        "{}: {} pose pair(s) from {} observation(s) of the target ({}){}",
        path.display(),
        pairs.pairs.len(),
        pairs.observations,
        pairs.target_source,
        if pairs.dropped_outside + pairs.dropped_gap > 0 {
            format!(
                "; dropped {} outside the robot's transforms and {} in their gaps longer than {} s",
                pairs.dropped_outside, pairs.dropped_gap, args.max_gap
            )
        } else {
            String::new()
        }
    );
    // The offset is reported when one was asked for.
    Ok(Some((
        pairs,
        (args.time_offset != "0").then_some(time_offset),
    )))
}

/// Pose pairs from two streams, with what the pairing did.
pub struct Synced {
    /// The pairs.
    pub pairs: Vec<StampedPosePair>,
    /// Offset used, seconds.
    pub time_offset: f64,
    /// With `--time-offset auto`: the angular speeds' correlation at each offset searched.
    pub offset_curve: Option<Vec<[f64; 2]>>,
}

/// Reads and pairs the two streams of `args`.
pub fn synced(args: &InputArgs) -> Result<Option<Synced>> {
    let (Some(robot_path), Some(camera_path)) = (&args.robot, &args.camera) else {
        return Ok(None);
    };
    let offset = if args.time_offset == "auto" {
        TimeOffset::Auto
    } else {
        TimeOffset::Fixed(
            args.time_offset
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .with_context(|| {
                    format!(
                        "--time-offset: expected `auto` or seconds, found `{}`",
                        args.time_offset
                    )
                })?,
        )
    };
    let pairing = pair_stream_files(robot_path, camera_path, args.setup(), offset, args.max_gap)
        .map_err(|e| match e {
            // The offset search's own refusals say nothing of the files: name them.
            handeye::Error::InvalidParameter { .. } => anyhow::Error::new(e).context(format!(
                "--time-offset auto on {} and {}",
                robot_path.display(),
                camera_path.display()
            )),
            e => e.into(),
        })?;
    for (name, count) in [robot_path, camera_path].iter().zip(pairing.reordered) {
        if count > 0 {
            eprintln!(
                "{}: {count} sample(s) out of time order, put in order",
                name.display()
            );
        }
    }
    let time_offset = pairing.time_offset;
    let offset_curve = pairing.correlated.as_ref().map(|e| e.curve.clone());
    if let Some(e) = pairing.correlated {
        eprintln!(
            "time offset: {time_offset:.4} s (angular speeds correlate best at {:.4} s, {:.3}; refined by the agreement of the paired poses)",
            e.offset, e.correlation
        );
    }
    let s = pairing.synced;
    if s.dropped_outside + s.dropped_gap > 0 {
        eprintln!(
            "dropped {} camera sample(s) outside the robot stream and {} in gaps longer than {} s",
            s.dropped_outside, s.dropped_gap, args.max_gap
        );
    }
    if s.pairs.len() < 2 {
        // The camera stamps decide the pairs: name that file (not `-`, there is no INPUT).
        return Err(handeye::Error::Parse {
            file: camera_path.display().to_string(),
            line: 0,
            field: "t".into(),
            message: format!(
                "{} camera sample(s) within the robot stream {} ({} outside it, {} in its gaps longer than {} s): at least 2 pose pairs are needed",
                s.pairs.len(),
                robot_path.display(),
                s.dropped_outside,
                s.dropped_gap,
                args.max_gap
            ),
        }
        .into());
    }
    let pairs = s
        .pairs
        .iter()
        .zip(&s.stamps)
        .enumerate()
        .map(|(k, (p, t))| StampedPosePair {
            line: k + 1,
            stamp: Some(*t),
            pose: *p,
        })
        .collect();
    Ok(Some(Synced {
        pairs,
        time_offset,
        offset_curve,
    }))
}

/// The clock offset (camera − robot, seconds) of two streams: the angular speeds' correlation,
/// refined by how well the paired poses agree on one X. `what` names the streams in messages.
fn auto_offset(
    robot: &[StampedPose],
    camera: &[StampedPose],
    args: &InputArgs,
    what: &str,
) -> Result<f64> {
    let e = estimate_time_offset(robot, camera, &OffsetOptions::default())
        .with_context(|| format!("--time-offset auto on {what}"))?;
    let max_offset = OffsetOptions::default().max_offset;
    let refined = refine_time_offset(
        robot,
        camera,
        args.setup(),
        e.offset,
        max_offset,
        args.max_gap,
    );
    eprintln!(
        "time offset: {refined:.4} s (angular speeds correlate best at {:.4} s, {:.3}; refined by the agreement of the paired poses)",
        e.offset, e.correlation
    );
    Ok(refined)
}

/// All pose pairs of the input (a batch solve), each pose's name for messages (`file:line`, or
/// the camera stream's file and time stamp), and the time offset used for streams.
pub fn read_all(args: &InputArgs) -> Result<(Vec<PosePair>, Vec<String>, Option<f64>)> {
    if let Some((b, offset)) = bag(args)? {
        return Ok((b.poses(), b.names, offset));
    }
    if let Some(s) = synced(args)? {
        let camera = args.camera.as_ref().map(|p| p.display().to_string());
        let names = s
            .pairs
            .iter()
            .map(|p| {
                format!(
                    "{} at t = {:.3} s",
                    camera.as_deref().unwrap_or("camera"),
                    p.stamp.unwrap_or(f64::NAN)
                )
            })
            .collect();
        return Ok((
            s.pairs.iter().map(|p| p.pose).collect(),
            names,
            Some(s.time_offset),
        ));
    }
    let path = args.input.clone().unwrap_or_else(|| PathBuf::from("-"));
    let source = path.display().to_string();
    let name = |line: usize| format!("{source}:{line}");
    let (mut pairs, mut names) = (Vec::new(), Vec::new());
    let mut take = |r: StampedPosePair| {
        pairs.push(r.pose);
        names.push(name(r.line));
    };
    if path.as_os_str() == "-" {
        let mut reader = PoseReader::new(std::io::stdin().lock(), "-", args.format)?;
        preamble(&reader, "-");
        for r in reader.by_ref() {
            take(r?);
        }
        note("-", &reader.projections());
    } else {
        match open_poses(&path, args.format)? {
            PoseInput::Whole(series) => {
                note(&source, &series.projections);
                let names = series.lines.iter().map(|&l| name(l)).collect();
                return Ok((series.pairs, names, None));
            }
            PoseInput::Stream(mut reader) => {
                preamble(&reader, &source);
                for r in reader.by_ref() {
                    take(r?);
                }
                note(&source, &reader.projections());
            }
        }
    }
    if pairs.len() < 2 {
        return Err(handeye::Error::Parse {
            file: source,
            line: 0,
            field: "-".to_string(),
            message: format!(
                "{} pose pair(s): at least 2 are needed to make a motion",
                pairs.len()
            ),
        }
        .into());
    }
    Ok((pairs, names, None))
}

/// Tells on stderr the lines skipped before the first record, if any was not blank nor a comment.
fn preamble<R: BufRead>(reader: &PoseReader<R>, source: &str) {
    if let Some(p) = reader.preamble() {
        eprintln!("{source}: {}", p.note());
    }
}

/// Tells on stderr how many rotation matrices of `source` were projected onto SO(3), if any.
fn note(source: &str, projections: &Projections) {
    if let Some(note) = projections.note() {
        eprintln!("{source}: {note}");
    }
}

/// A streaming reader that tells its note (see [`note`]) when it ends.
struct NotingReader<R: BufRead> {
    reader: PoseReader<R>,
    source: String,
    told: bool,
}

impl<R: BufRead> Iterator for NotingReader<R> {
    type Item = handeye::Result<StampedPosePair>;

    fn next(&mut self) -> Option<Self::Item> {
        let next = self.reader.next();
        if next.is_none() && !self.told {
            self.told = true;
            note(&self.source, &self.reader.projections());
        }
        next
    }
}

/// Pose pairs one at a time, each with its place, or the error of a bad record.
pub type Records = Box<dyn Iterator<Item = handeye::Result<StampedPosePair>>>;

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
pub fn records(
    args: &InputArgs,
    before_wait: Rc<dyn Fn()>,
) -> Result<(Records, String, Option<Offset>)> {
    if let Some((b, offset)) = bag(args)? {
        let source = format!(
            "{} {}",
            args.input
                .as_ref()
                .map_or(String::new(), |p| p.display().to_string()),
            b.target_source
        );
        let offset = offset.map(|seconds| Offset {
            seconds,
            curve: None,
        });
        return Ok((Box::new(b.pairs.into_iter().map(Ok)), source, offset));
    }
    if let Some(s) = synced(args)? {
        let camera = args
            .camera
            .as_ref()
            .map_or("camera".to_string(), |p| p.display().to_string());
        let offset = Offset {
            seconds: s.time_offset,
            curve: s.offset_curve,
        };
        return Ok((Box::new(s.pairs.into_iter().map(Ok)), camera, Some(offset)));
    }
    let path = args.input.clone().unwrap_or_else(|| PathBuf::from("-"));
    let source = path.display().to_string();
    if path.as_os_str() == "-" {
        let stdin = WaitHook::new(std::io::stdin().lock(), before_wait);
        let reader = PoseReader::new(stdin, "-", args.format)?;
        preamble(&reader, &source);
        let records = NotingReader {
            reader,
            source: source.clone(),
            told: false,
        };
        return Ok((Box::new(records), source, None));
    }
    let format = args.format;
    let records = if format == Format::Visp || path.is_dir() {
        file_records(open_poses(&path, format)?, &source)
    } else {
        let file = File::open(&path).map_err(|e| handeye::Error::Io {
            file: source.clone(),
            source: e,
        })?;
        let input = WaitHook::new(file, before_wait);
        file_records(open_pose_stream(input, &source, format)?, &source)
    };
    Ok((records, source, None))
}

/// The records of a file opened by [`open_poses`] or [`open_pose_stream`].
fn file_records<R: BufRead + 'static>(input: PoseInput<R>, source: &str) -> Records {
    match input {
        PoseInput::Whole(series) => {
            note(source, &series.projections);
            let records = series.pairs.into_iter().enumerate().map(|(k, pose)| {
                Ok(StampedPosePair {
                    line: k + 1,
                    stamp: None,
                    pose,
                })
            });
            Box::new(records.collect::<Vec<_>>().into_iter())
        }
        PoseInput::Stream(reader) => {
            preamble(&reader, source);
            Box::new(NotingReader {
                reader,
                source: source.to_string(),
                told: false,
            })
        }
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

/// [`records`] read ahead on a second thread ([`ReadAhead`]): the same records, source name and
/// clock offset, and the same error when the input cannot be opened.
pub fn read_ahead(
    args: &InputArgs,
    before_wait: Rc<dyn Fn()>,
) -> Result<(ReadAhead, String, Option<Offset>)> {
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
            Ok((records, source, offset)) => {
                let _ = opened.send(Ok((source, offset)));
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
        Ok(Ok((source, offset))) => Ok((
            ReadAhead {
                batches: received,
                batch: Vec::new().into_iter(),
                before_wait,
                reader: Some(reader),
            },
            source,
            offset,
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
