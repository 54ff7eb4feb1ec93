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
//! A [`Recording`](crate::io::Recording) of a [`Source::Bag`](crate::io::Source::Bag) gives, at
//! each stamp of the target's pose, `base_from_gripper` from the tf tree (composed along its path,
//! every dynamic transform interpolated in time) and `camera_from_target`: the pose pairs a pose
//! file gives, for either setup (for eye-to-hand the camera is fixed and the target rides on the
//! gripper; the setup is applied afterwards). [`inspect_bag`] lists the topics and the tf tree.

mod cdr;
mod joints;
mod live;
mod mount;
mod msg;
mod pairs;
mod storage;
mod tags;
mod tf;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::model::error::{Error, Result};
use crate::model::pose::{Transform, transform_from_xyz_quat_xyzw};

pub(crate) use msg::{POSE_STAMPED, TF_MESSAGE, TRANSFORM_STAMPED};
// Read through `io::Recording`, and on their own.
pub use live::{LiveOutcome, LivePairs, LiveTransform};
pub use pairs::{BagOptions, BagPairs, read_bag_pairs};
pub use storage::Storage;
pub(crate) use tags::read_bag_tags;
pub use tags::{BagTags, TAG_CORNERS};
pub use tf::TfEdge;
pub use tf::tree_steps;

use msg::RawPose;
use storage::{Message, Topics, bag_error, scan};
use tf::TfBuffer;

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

/// A `sensor_msgs/msg/JointState` message of a joint-state topic ([`is_joints_topic`]), or why
/// it could not be read.
struct JointSample {
    topic: String,
    index: usize,
    decoded: std::result::Result<msg::JointState, String>,
}

/// A message of a detections topic (`apriltag_msgs/msg/AprilTagDetectionArray`), or why it could
/// not be read.
struct TagSample {
    index: usize,
    decoded: std::result::Result<msg::TagDetections, String>,
}

/// A `sensor_msgs/msg/CameraInfo` message, or why it could not be read.
struct InfoSample {
    topic: String,
    index: usize,
    decoded: std::result::Result<msg::CameraInfo, String>,
}

/// What a recording holds for a calibration.
struct Loaded {
    tf: TfBuffer,
    topics: Topics,
    target: Vec<Observation>,
    tags: Vec<TagSample>,
    infos: Vec<InfoSample>,
    joints: Vec<JointSample>,
    messages: usize,
}

/// Which camera_info topics [`load`] reads.
#[derive(Clone, Copy)]
enum InfoTopics<'a> {
    /// None.
    None,
    /// This one.
    Named(&'a str),
    /// Every topic named `…camera_info`.
    Any,
}

/// The topic of the robot's joint states (`robot_state_publisher`'s input).
pub(crate) const JOINT_STATES_TOPIC: &str = "/joint_states";

/// Whether the joint angles are read from `topic`: `/joint_states`, or a namespaced one
/// (`/arm/joint_states`).
fn is_joints_topic(topic: &str) -> bool {
    topic == JOINT_STATES_TOPIC || topic.ends_with(JOINT_STATES_TOPIC)
}

fn at(topic: &str, index: usize) -> Option<String> {
    Some(format!("topic {topic}, message {index}"))
}

fn transform_of(raw: &RawPose) -> std::result::Result<Transform, String> {
    transform_from_xyz_quat_xyzw(raw.translation, raw.quaternion_xyzw).map_err(|p| p.to_string())
}

/// Reads the tf tree and, when `target_topic` is given, the target's poses (or its detections);
/// and the camera_info topics `infos` names.
fn load(bag: &Bag, target_topic: Option<&str>, info_topics: InfoTopics<'_>) -> Result<Loaded> {
    let mut tf = TfBuffer::default();
    let mut target = Vec::new();
    let mut tags = Vec::new();
    let mut infos = Vec::new();
    let is_info = |topic: &str| match info_topics {
        InfoTopics::None => false,
        InfoTopics::Named(t) => topic == t,
        InfoTopics::Any => topic.ends_with("camera_info"),
    };
    let mut joints = Vec::new();
    let mut topics = Topics::default();
    let mut index: HashMap<String, usize> = HashMap::new();
    let mut messages = 0usize;
    let wanted = |topic: &str| {
        topic == TF_TOPIC
            || topic == TF_STATIC_TOPIC
            || Some(topic) == target_topic
            || is_joints_topic(topic)
            || is_info(topic)
    };
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
            // The joint angles are an extra: a message that does not decode is skipped, and told.
            if is_joints_topic(m.topic) && Some(m.topic) != target_topic {
                if m.msg_type == msg::JOINT_STATE {
                    joints.push(JointSample {
                        topic: m.topic.to_string(),
                        index: k,
                        decoded: msg::decode_joint_state(m.data)
                            .map_err(|e| format!("cannot decode `{}`: {e}", msg::JOINT_STATE)),
                    });
                }
                return Ok(());
            }
            // The intrinsics are read from the first message that decodes; the others are skipped.
            if is_info(m.topic) && Some(m.topic) != target_topic {
                if m.msg_type == msg::CAMERA_INFO {
                    infos.push(InfoSample {
                        topic: m.topic.to_string(),
                        index: k,
                        decoded: msg::decode_camera_info(m.data)
                            .map_err(|e| format!("cannot decode `{}`: {e}", msg::CAMERA_INFO)),
                    });
                }
                return Ok(());
            }
            // Detections: a message that does not decode costs that message (the reader of the
            // pixels names it).
            if m.msg_type == msg::APRILTAG_DETECTIONS {
                tags.push(TagSample {
                    index: k,
                    decoded: msg::decode_tag_detections(m.data)
                        .map_err(|e| format!("cannot decode `{}`: {e}", msg::APRILTAG_DETECTIONS)),
                });
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
                        "has type `{other}`; a target topic must be `{POSE_STAMPED}` or `{TRANSFORM_STAMPED}` (or `{}`, calibrated on the pixels)",
                        msg::APRILTAG_DETECTIONS
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
        let found = scan(file, bag.storage, &wanted, &mut on_message)?;
        messages += found.iter().map(|(_, info)| info.count).sum::<usize>();
        topics.merge(found);
    }
    tf.finish();
    Ok(Loaded {
        tf,
        topics,
        target,
        tags,
        infos,
        joints,
        messages,
    })
}

/// The message types of `topic` in the recording, or what to say when it has none: the nearest
/// topic name when one is near, and every topic with its type (`whole` makes the recording's
/// error).
fn topic_types<'a>(
    topics: &'a Topics,
    topic: &'a str,
    whole: impl Fn(String) -> Error,
) -> Result<Vec<&'a str>> {
    let types: Vec<&str> = topics
        .of(topic)
        .map(|info| info.msg_type.as_str())
        .collect();
    if types.is_empty() {
        let names = topics.names();
        let near =
            tf::nearest(topic, &names).map_or(String::new(), |n| format!(" (did you mean `{n}`?)"));
        return Err(whole(format!(
            "no topic `{topic}` in the recording{near}; the topics are: {}",
            topic_list(topics)
        )));
    }
    Ok(types)
}

/// The topics of a recording as `name (type)`, for messages.
fn topic_list(topics: &Topics) -> String {
    if topics.is_empty() {
        return "(none)".into();
    }
    topics
        .iter()
        .map(|(name, info)| format!("{name} ({})", info.msg_type))
        .collect::<Vec<_>>()
        .join(", ")
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
    /// The loops of parent links (frames that have no root), each as its frames, the parent of
    /// each the next; tf allows none, and no lookup through one can be made.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub loops: Vec<Vec<String>>,
    /// Every edge of the tf tree.
    pub tf: Vec<TfEdge>,
    /// The topics that can hold the target's pose (`PoseStamped`, `TransformStamped`) or its
    /// detections (`apriltag_msgs/msg/AprilTagDetectionArray`).
    pub target_topics: Vec<String>,
}

/// Lists the topics and the tf tree of a recording.
pub fn inspect_bag(path: &Path) -> Result<BagSummary> {
    let bag = Bag::open(path)?;
    let loaded = load(&bag, None, InfoTopics::None)?;
    let topics: Vec<TopicSummary> = loaded
        .topics
        .iter()
        .map(|(name, info)| TopicSummary {
            topic: name.to_string(),
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
            .filter(|t| {
                t.msg_type == POSE_STAMPED
                    || t.msg_type == TRANSFORM_STAMPED
                    || t.msg_type == msg::APRILTAG_DETECTIONS
            })
            .map(|t| t.topic.clone())
            .fold(Vec::new(), |mut names, t| {
                if names.last() != Some(&t) {
                    names.push(t);
                }
                names
            }),
        topics,
        frames: loaded.tf.frames(),
        roots: loaded.tf.roots(),
        loops: loaded.tf.loops(),
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
