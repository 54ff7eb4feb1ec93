//! ROS 2 recordings (rosbag2): the pose pairs of a calibration read straight from `/tf`,
//! `/tf_static` and a target topic, in both storages (MCAP and SQLite3).
//!
//! A recording is a rosbag2 directory (its `metadata.yaml` beside one or more `.mcap` or `.db3`
//! files, read in the order of their split number) or a single `.mcap` / `.db3` file. Messages are
//! CDR-serialised (`tf2_msgs/msg/TFMessage`, `geometry_msgs/msg/PoseStamped`,
//! `geometry_msgs/msg/TransformStamped`), decoded by a small bounds-checked reader.
//!
//! ROS frame convention: a transform with `header.frame_id` = P and `child_frame_id` = C is
//! `P_from_C` (the pose of C in P); a `PoseStamped` whose header names the camera frame is
//! `camera_from_target`. Stamps are the messages' header stamps (`sec`, `nanosec`).
//!
//! [`read_bag_pairs`] gives, at each stamp of the target's pose, `base_from_gripper` looked up in
//! the tf tree (composed along the tree path, every dynamic transform interpolated in time) and
//! `camera_from_target`: the same pose pairs a pose file gives, for either setup (for eye-to-hand
//! the camera is fixed and the target rides on the gripper; the setup is applied afterwards, as for
//! any input). [`inspect_bag`] lists the topics and the tf tree.

mod cdr;
mod msg;
mod storage;
mod tf;

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::io::StampedPosePair;
use crate::io::sync::{Lookup, StampedPose};
use crate::model::error::{Error, Result};
use crate::model::motion::PosePair;
use crate::model::pose::{Transform, transform_from_xyz_quat_xyzw};

pub(crate) use msg::{POSE_STAMPED, TF_MESSAGE, TRANSFORM_STAMPED};
pub use storage::Storage;
pub use tf::TfEdge;

use msg::{NS, RawPose, frame_name};
use storage::{Message, TopicInfo, bag_error, scan};
use tf::{TfBuffer, TfError, seconds};

/// The topic of dynamic transforms.
pub(crate) const TF_TOPIC: &str = "/tf";
/// The topic of static transforms.
pub(crate) const TF_STATIC_TOPIC: &str = "/tf_static";

/// Whether `path` is a ROS 2 recording: a directory holding a `metadata.yaml` or an `.mcap` /
/// `.db3` file, or a file with one of these extensions.
pub fn is_bag(path: &Path) -> bool {
    if path.is_dir() {
        path.join("metadata.yaml").is_file()
            || std::fs::read_dir(path).is_ok_and(|entries| {
                entries
                    .flatten()
                    .any(|e| e.path().is_file() && Storage::of(&e.path()).is_some())
            })
    } else {
        Storage::of(path).is_some()
    }
}

/// The files of a recording, in reading order, and their storage.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Bag {
    /// The path given.
    pub path: PathBuf,
    /// The storage files: the path itself, or those of the directory by split number.
    pub files: Vec<PathBuf>,
    /// Their storage.
    pub storage: Storage,
}

impl Bag {
    /// Finds the storage files of a recording.
    pub fn open(path: &Path) -> Result<Self> {
        let bag_err = |message: String| bag_error(path, None, message);
        if !path.exists() {
            return Err(Error::Io {
                file: path.display().to_string(),
                source: std::io::Error::new(
                    std::io::ErrorKind::NotFound,
                    "no such file or directory",
                ),
            });
        }
        if !path.is_dir() {
            let storage = Storage::of(path).ok_or_else(|| {
                bag_err(
                    "not a ROS 2 recording: expected a directory, an .mcap or a .db3 file".into(),
                )
            })?;
            return Ok(Self {
                path: path.to_path_buf(),
                files: vec![path.to_path_buf()],
                storage,
            });
        }
        let entries = std::fs::read_dir(path).map_err(|e| Error::Io {
            file: path.display().to_string(),
            source: e,
        })?;
        let mut files: Vec<(Storage, PathBuf)> = entries
            .flatten()
            .map(|e| e.path())
            .filter(|p| p.is_file())
            .filter_map(|p| Storage::of(&p).map(|s| (s, p)))
            .collect();
        if files.is_empty() {
            let compressed = std::fs::read_dir(path).is_ok_and(|entries| {
                entries.flatten().any(|e| {
                    let name = e.file_name().to_string_lossy().to_ascii_lowercase();
                    name.ends_with(".zstd") || name.ends_with(".zst")
                })
            });
            return Err(bag_err(if compressed {
                "the recording's files are compressed as a whole (.zstd): decompress them first (`ros2 bag decompress`, or `zstd -d`); MCAP's own chunk compression is read as it is".into()
            } else {
                "no .mcap or .db3 file in the directory".into()
            }));
        }
        let storage = files[0].0;
        if files.iter().any(|f| f.0 != storage) {
            return Err(bag_err(
                "the directory holds both .mcap and .db3 files: one recording has one storage"
                    .into(),
            ));
        }
        // bag_0.mcap, bag_1.mcap, …, bag_10.mcap: by split number, then by name.
        let split = |p: &Path| {
            let stem = p.file_stem().and_then(|s| s.to_str()).unwrap_or("");
            let digits: String = stem
                .chars()
                .rev()
                .take_while(char::is_ascii_digit)
                .collect::<Vec<_>>()
                .into_iter()
                .rev()
                .collect();
            digits.parse::<u64>().unwrap_or(0)
        };
        files.sort_by(|a, b| (split(&a.1), &a.1).cmp(&(split(&b.1), &b.1)));
        Ok(Self {
            path: path.to_path_buf(),
            files: files.into_iter().map(|f| f.1).collect(),
            storage,
        })
    }
}

/// Which frames and topics make the pose pairs; `Default` gives the values on each field.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BagOptions {
    /// The robot's base frame (e.g. `base_link`). No default: required.
    pub base_frame: String,
    /// The gripper's frame (e.g. `tool0`). No default: required.
    pub gripper_frame: String,
    /// The camera frame whose pose X is (e.g. `camera_color_optical_frame`). No default:
    /// required.
    pub camera_frame: String,
    /// The target's frame (e.g. `board`): needed when the target is in `/tf`; with a
    /// `TransformStamped` topic its `child_frame_id` must be it. Default none.
    pub target_frame: Option<String>,
    /// A `geometry_msgs/msg/PoseStamped` or `TransformStamped` topic of the target's pose
    /// (e.g. `/board_pose`); none: the target is in `/tf`. Default none.
    pub target_topic: Option<String>,
    /// Camera clock minus robot clock, seconds: the robot is looked up at t − offset for a target
    /// stamped t. Default 0.
    pub time_offset: f64,
    /// A dynamic transform is not interpolated across a gap between samples longer than this,
    /// seconds (the observation is dropped). Default 0 counts as 0.1.
    pub max_gap: f64,
}

/// Default `max_gap`, seconds.
pub(crate) const DEFAULT_MAX_GAP: f64 = 0.1;

/// The pose pairs of a recording.
#[derive(Debug, Clone, PartialEq)]
pub struct BagPairs {
    /// The pairs (`base_from_gripper`, `camera_from_target`) in time order; `line` is the
    /// target's message number in its topic (or its sample number in `/tf`), from 1, and `stamp`
    /// its header stamp, seconds.
    pub pairs: Vec<StampedPosePair>,
    /// A name for each pair, for messages: topic, message number and stamp.
    pub names: Vec<String>,
    /// Where the target's pose came from (`/board_pose`, or `/tf camera → board`).
    pub target_source: String,
    /// Observations of the target read.
    pub observations: usize,
    /// Observations whose stamp lies outside a dynamic transform they need.
    pub dropped_outside: usize,
    /// Observations in a gap, longer than `max_gap`, of a dynamic transform they need.
    pub dropped_gap: usize,
    /// `base_from_gripper` at every stamp of the robot's dynamic transforms (robot clock), for an
    /// estimate of the clock offset ([`crate::io::sync::estimate_time_offset`]).
    pub robot_stream: Vec<StampedPose>,
    /// `camera_from_target` at every observation (camera clock), in time order.
    pub camera_stream: Vec<StampedPose>,
}

impl BagPairs {
    /// The pose pairs alone.
    pub fn poses(&self) -> Vec<PosePair> {
        self.pairs.iter().map(|p| p.pose).collect()
    }
}

/// An observation of the target: where it is in the recording and `frame_from_target`.
struct Observation {
    index: usize,
    stamp_ns: i64,
    /// The frame the pose is given in (the camera frame, or another one of the tf tree).
    frame: String,
    /// The `child_frame_id` of a `TransformStamped`.
    child: Option<String>,
    frame_from_target: Transform,
}

/// What a recording holds for a calibration.
struct Loaded {
    tf: TfBuffer,
    topics: BTreeMap<String, TopicInfo>,
    target: Vec<Observation>,
    messages: usize,
}

fn at(topic: &str, index: usize) -> Option<String> {
    Some(format!("topic {topic}, message {index}"))
}

fn transform_of(raw: &RawPose) -> std::result::Result<Transform, String> {
    transform_from_xyz_quat_xyzw(raw.translation, raw.quaternion_xyzw).map_err(|p| p.to_string())
}

/// Reads the tf tree and, when `target_topic` is given, the target's poses.
fn load(bag: &Bag, target_topic: Option<&str>) -> Result<Loaded> {
    let mut tf = TfBuffer::default();
    let mut target = Vec::new();
    let mut topics: BTreeMap<String, TopicInfo> = BTreeMap::new();
    let mut index: HashMap<String, usize> = HashMap::new();
    let mut messages = 0usize;
    let wanted =
        |topic: &str| topic == TF_TOPIC || topic == TF_STATIC_TOPIC || Some(topic) == target_topic;
    for file in &bag.files {
        let mut on_message = |m: Message<'_>| -> Result<()> {
            let k = index.entry(m.topic.to_string()).or_insert(0);
            *k += 1;
            let k = *k;
            let err = |message: String| bag_error(file, at(m.topic, k), message);
            if m.encoding != "cdr" {
                return Err(err(format!(
                    "serialised as `{}`, not `cdr` (ROS 2's default)",
                    m.encoding
                )));
            }
            if m.topic == TF_TOPIC || m.topic == TF_STATIC_TOPIC {
                if m.msg_type != TF_MESSAGE {
                    return Err(err(format!(
                        "has type `{}`, expected `{TF_MESSAGE}`",
                        m.msg_type
                    )));
                }
                let is_static = m.topic == TF_STATIC_TOPIC;
                let transforms = msg::decode_tf_message(m.data)
                    .map_err(|e| err(format!("cannot decode `{TF_MESSAGE}`: {e}")))?;
                for (j, t) in transforms.iter().enumerate() {
                    let name = format!(
                        "transforms[{j}] (`{}` → `{}`)",
                        t.header.frame_id, t.child_frame_id
                    );
                    let pose =
                        transform_of(&t.transform).map_err(|e| err(format!("{name}: {e}")))?;
                    tf.add(
                        &t.header.frame_id,
                        &t.child_frame_id,
                        t.header.stamp_ns,
                        pose,
                        is_static,
                    )
                    .map_err(|e| err(format!("{name}: {e}")))?;
                }
                return Ok(());
            }
            let (header, child, raw) = match m.msg_type {
                POSE_STAMPED => {
                    let p = msg::decode_pose_stamped(m.data)
                        .map_err(|e| err(format!("cannot decode `{POSE_STAMPED}`: {e}")))?;
                    (p.header, None, p.pose)
                }
                TRANSFORM_STAMPED => {
                    let t = msg::decode_transform_stamped(m.data)
                        .map_err(|e| err(format!("cannot decode `{TRANSFORM_STAMPED}`: {e}")))?;
                    (t.header, Some(t.child_frame_id), t.transform)
                }
                other => {
                    return Err(err(format!(
                        "has type `{other}`; a target topic must be `{POSE_STAMPED}` or `{TRANSFORM_STAMPED}`"
                    )));
                }
            };
            if header.frame_id.is_empty() {
                return Err(err(
                    "header.frame_id is empty: the frame the target's pose is given in must be named"
                        .into(),
                ));
            }
            let frame_from_target = transform_of(&raw).map_err(|e| err(format!("pose: {e}")))?;
            target.push(Observation {
                index: k,
                stamp_ns: header.stamp_ns,
                frame: header.frame_id,
                child,
                frame_from_target,
            });
            Ok(())
        };
        for (name, info) in scan(file, bag.storage, &wanted, &mut on_message)? {
            messages += info.count;
            match topics.get_mut(&name) {
                Some(known) => known.count += info.count,
                None => {
                    topics.insert(name, info);
                }
            }
        }
    }
    tf.finish();
    Ok(Loaded {
        tf,
        topics,
        target,
        messages,
    })
}

/// The topics of a recording as `name (type)`, for messages.
fn topic_list(topics: &BTreeMap<String, TopicInfo>) -> String {
    if topics.is_empty() {
        return "(none)".into();
    }
    topics
        .iter()
        .map(|(name, info)| format!("{name} ({})", info.msg_type))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Seconds as nanoseconds, for an offset or a gap given in seconds.
fn nanoseconds(name: &'static str, value: f64) -> Result<i64> {
    if !(value.is_finite() && value.abs() <= 1e6) {
        return Err(Error::InvalidParameter {
            name,
            message: format!("{value} s is not a usable time (finite, at most 1e6 s in size)"),
        });
    }
    Ok((value * NS as f64).round() as i64)
}

/// The pose pairs of a recording: at each stamp of the target's pose, `base_from_gripper` from
/// the tf tree and `camera_from_target` (see the [module](self) documentation).
///
/// Errors ([`Error::Bag`], naming the file and, for a message, its topic and number): a file that
/// is not a complete recording, a message that does not decode, a frame that is in no transform
/// (the frames that are are listed), frames in different trees, a target topic that is missing or
/// of another type, fewer than 2 pose pairs.
///
/// # Example
/// ```
/// use handeye::io::rosbag::{BagOptions, read_bag_pairs};
/// use handeye::{Method, Pairing, Setup, motion_pairs, solve};
///
/// let bag = concat!(env!("CARGO_MANIFEST_DIR"), "/../../testdata/rosbag/eih_tf_mcap");
/// let pairs = read_bag_pairs(
///     std::path::Path::new(bag),
///     &BagOptions {
///         base_frame: "base_link".into(),
///         gripper_frame: "tool0".into(),
///         camera_frame: "camera_link".into(),
///         target_frame: Some("board".into()),
///         ..BagOptions::default()
///     },
/// )?;
/// assert_eq!(pairs.pairs.len(), 80);
/// let motions = motion_pairs(&pairs.poses(), Pairing::All, Setup::EyeInHand);
/// let x = solve(Method::Andreff, &motions)?.x; // tool0_from_camera_link
/// assert!((x.translation.vector.z - 0.08).abs() < 1e-9);
/// # Ok::<(), handeye::Error>(())
/// ```
pub fn read_bag_pairs(path: &Path, options: &BagOptions) -> Result<BagPairs> {
    let bag = Bag::open(path)?;
    let frame = |name: &'static str, value: &str| {
        let f = frame_name(value.trim());
        if f.is_empty() {
            Err(Error::InvalidParameter {
                name,
                message: "a frame name is needed to read a ROS 2 recording".into(),
            })
        } else {
            Ok(f)
        }
    };
    let base = frame("base_frame", &options.base_frame)?;
    let gripper = frame("gripper_frame", &options.gripper_frame)?;
    let camera = frame("camera_frame", &options.camera_frame)?;
    let target_frame = options
        .target_frame
        .as_deref()
        .map(|t| frame("target_frame", t))
        .transpose()?;
    let target_topic = options.target_topic.as_deref().map(str::trim);
    let offset_ns = nanoseconds("time_offset", options.time_offset)?;
    let max_gap = if options.max_gap > 0.0 {
        options.max_gap
    } else {
        DEFAULT_MAX_GAP
    };
    let max_gap_ns = nanoseconds("max_gap", max_gap)?;
    let loaded = load(&bag, target_topic)?;
    let whole = |message: String| bag_error(path, None, message);
    let tf_error = |what: &str, e: TfError| whole(format!("{what}: {e}"));
    let tf = &loaded.tf;

    if !loaded.topics.contains_key(TF_TOPIC) && !loaded.topics.contains_key(TF_STATIC_TOPIC) {
        return Err(whole(format!(
            "no /tf or /tf_static topic; the topics are: {}",
            topic_list(&loaded.topics)
        )));
    }
    let robot_path = tf
        .path(&base, &gripper)
        .map_err(|e| tf_error("the robot's pose", e))?;
    if tf.dynamic_on(&robot_path).is_empty() {
        return Err(whole(format!(
            "the pose of `{gripper}` in `{base}` never changes: every transform between them is in /tf_static (is the gripper frame right?)"
        )));
    }

    // The target's observations: (number, stamp, camera_from_target or why not).
    let mut observations: Vec<(usize, i64, Lookup)> = Vec::new();
    let target_source;
    match target_topic {
        Some(topic) => {
            match loaded.topics.get(topic) {
                None => {
                    let names: Vec<String> = loaded.topics.keys().cloned().collect();
                    let near = tf::nearest(topic, &names)
                        .map_or(String::new(), |n| format!(" (did you mean `{n}`?)"));
                    return Err(whole(format!(
                        "no topic `{topic}` in the recording{near}; the topics are: {}",
                        topic_list(&loaded.topics)
                    )));
                }
                Some(info)
                    if info.msg_type != POSE_STAMPED && info.msg_type != TRANSFORM_STAMPED =>
                {
                    return Err(whole(format!(
                        "topic `{topic}` has type `{}`; a target topic must be `{POSE_STAMPED}` or `{TRANSFORM_STAMPED}`",
                        info.msg_type
                    )));
                }
                Some(_) => {}
            }
            target_source = topic.to_string();
            let mut paths: HashMap<String, tf::TfPath> = HashMap::new();
            for o in &loaded.target {
                if let (Some(child), Some(target)) = (&o.child, &target_frame)
                    && frame_name(child) != *target
                {
                    return Err(bag_error(
                        path,
                        at(topic, o.index),
                        format!("child_frame_id is `{child}`, not the target frame `{target}`"),
                    ));
                }
                let camera_from_target = if o.frame == camera {
                    Lookup::Pose(o.frame_from_target)
                } else {
                    if !paths.contains_key(&o.frame) {
                        let p = tf.path(&camera, &o.frame).map_err(|e| {
                            bag_error(
                                path,
                                at(topic, o.index),
                                format!(
                                    "the target's pose is given in `{}`, not in the camera frame `{camera}`, and tf cannot relate them: {e}",
                                    o.frame
                                ),
                            )
                        })?;
                        paths.insert(o.frame.clone(), p);
                    }
                    match tf.lookup(&paths[&o.frame], o.stamp_ns, max_gap_ns) {
                        Lookup::Pose(camera_from_frame) => {
                            Lookup::Pose(camera_from_frame * o.frame_from_target)
                        }
                        other => other,
                    }
                };
                observations.push((o.index, o.stamp_ns, camera_from_target));
            }
        }
        None => {
            let Some(target) = &target_frame else {
                return Err(Error::InvalidParameter {
                    name: "target_frame",
                    message: "the target's frame is needed when its pose is in /tf (or name the topic of its pose)".into(),
                });
            };
            let target_path = tf
                .path(&camera, target)
                .map_err(|e| tf_error("the target's pose", e))?;
            let Some(edge) = tf.dynamic_on(&target_path).into_iter().next() else {
                return Err(whole(format!(
                    "the pose of `{target}` in `{camera}` never changes: every transform between them is in /tf_static (is the target published on a topic of its own?)"
                )));
            };
            let parent = tf.parent_of(&edge).unwrap_or_default();
            target_source = format!("/tf `{parent}` → `{edge}`");
            for (k, t) in tf.stamps_of(&edge).into_iter().enumerate() {
                observations.push((k + 1, t, tf.lookup(&target_path, t, max_gap_ns)));
            }
        }
    }
    observations.sort_by_key(|o| o.1);

    let mut robot_stamps: Vec<i64> = tf
        .dynamic_on(&robot_path)
        .iter()
        .flat_map(|edge| tf.stamps_of(edge))
        .collect();
    robot_stamps.sort_unstable();
    robot_stamps.dedup();
    let robot_stream = robot_stamps
        .into_iter()
        .filter_map(|t| match tf.lookup(&robot_path, t, max_gap_ns) {
            Lookup::Pose(pose) => Some(StampedPose {
                stamp: seconds(t),
                pose,
            }),
            _ => None,
        })
        .collect();
    let camera_stream = observations
        .iter()
        .filter_map(|(_, t, o)| match o {
            Lookup::Pose(pose) => Some(StampedPose {
                stamp: seconds(*t),
                pose: *pose,
            }),
            _ => None,
        })
        .collect();
    let mut out = BagPairs {
        pairs: Vec::new(),
        names: Vec::new(),
        target_source: target_source.clone(),
        observations: observations.len(),
        dropped_outside: 0,
        dropped_gap: 0,
        robot_stream,
        camera_stream,
    };
    for (index, stamp_ns, camera_from_target) in observations {
        let robot = tf.lookup(&robot_path, stamp_ns.saturating_sub(offset_ns), max_gap_ns);
        match (robot, camera_from_target) {
            (Lookup::Pose(base_from_gripper), Lookup::Pose(camera_from_target)) => {
                let stamp = seconds(stamp_ns);
                out.pairs.push(StampedPosePair {
                    line: index,
                    stamp: Some(stamp),
                    pose: PosePair {
                        base_from_gripper,
                        camera_from_target,
                    },
                });
                out.names
                    .push(format!("{target_source} #{index} (t = {stamp:.3} s)"));
            }
            (Lookup::Gap, _) | (_, Lookup::Gap) => out.dropped_gap += 1,
            _ => out.dropped_outside += 1,
        }
    }
    if out.pairs.len() < 2 {
        return Err(whole(format!(
            "{} observation(s) of the target ({target_source}), {} within the robot's transforms ({} outside them, {} in their gaps longer than {max_gap} s): at least 2 pose pairs are needed",
            out.observations,
            out.pairs.len(),
            out.dropped_outside,
            out.dropped_gap
        )));
    }
    Ok(out)
}

/// A topic of a recording.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct TopicSummary {
    /// Its name.
    pub topic: String,
    /// Its message type (`tf2_msgs/msg/TFMessage` …).
    #[serde(rename = "type")]
    pub msg_type: String,
    /// Its serialisation (`cdr`).
    pub encoding: String,
    /// How many messages it has.
    pub count: usize,
}

/// What a recording holds: its topics and its tf tree, so that the frames and the target topic
/// can be chosen.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BagSummary {
    /// The path given.
    pub path: String,
    /// Its storage.
    pub storage: Storage,
    /// Its storage files.
    pub files: Vec<String>,
    /// Messages in all.
    pub messages: usize,
    /// Every topic, by name.
    pub topics: Vec<TopicSummary>,
    /// Every frame of /tf and /tf_static, sorted.
    pub frames: Vec<String>,
    /// The frames without a parent: one per tree.
    pub roots: Vec<String>,
    /// Every edge of the tf tree.
    pub tf: Vec<TfEdge>,
    /// The topics that can hold the target's pose (`PoseStamped`, `TransformStamped`).
    pub target_topics: Vec<String>,
}

/// Lists the topics and the tf tree of a recording.
pub fn inspect_bag(path: &Path) -> Result<BagSummary> {
    let bag = Bag::open(path)?;
    let loaded = load(&bag, None)?;
    let topics: Vec<TopicSummary> = loaded
        .topics
        .iter()
        .map(|(name, info)| TopicSummary {
            topic: name.clone(),
            msg_type: info.msg_type.clone(),
            encoding: info.encoding.clone(),
            count: info.count,
        })
        .collect();
    Ok(BagSummary {
        path: path.display().to_string(),
        storage: bag.storage,
        files: bag.files.iter().map(|f| f.display().to_string()).collect(),
        messages: loaded.messages,
        target_topics: topics
            .iter()
            .filter(|t| t.msg_type == POSE_STAMPED || t.msg_type == TRANSFORM_STAMPED)
            .map(|t| t.topic.clone())
            .collect(),
        topics,
        frames: loaded.tf.frames(),
        roots: loaded.tf.roots(),
        tf: loaded.tf.summary(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_directory_is_read_by_split_number_in_one_storage() {
        let dir = std::env::temp_dir().join(format!("handeye-bag-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for name in [
            "metadata.yaml",
            "run_10.mcap",
            "run_2.mcap",
            "run_0.mcap",
            "notes.txt",
        ] {
            std::fs::write(dir.join(name), b"").unwrap();
        }
        assert!(is_bag(&dir));
        let bag = Bag::open(&dir).unwrap();
        let names: Vec<String> = bag
            .files
            .iter()
            .map(|f| f.file_name().unwrap().to_string_lossy().into_owned())
            .collect();
        assert_eq!(names, ["run_0.mcap", "run_2.mcap", "run_10.mcap"]);
        assert_eq!(bag.storage, Storage::Mcap);
        std::fs::write(dir.join("run_3.db3"), b"").unwrap();
        let mixed = Bag::open(&dir).unwrap_err().to_string();
        for f in ["run_0.mcap", "run_2.mcap", "run_10.mcap", "run_3.db3"] {
            std::fs::remove_file(dir.join(f)).unwrap();
        }
        std::fs::write(dir.join("run_0.mcap.zstd"), b"").unwrap();
        let compressed = Bag::open(&dir).unwrap_err().to_string();
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(mixed.contains("both .mcap and .db3"), "{mixed}");
        assert!(compressed.contains("decompress"), "{compressed}");
    }
}
