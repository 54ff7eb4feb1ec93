//! The pose pairs of a recording ([`read_bag_pairs`]): the target's observations, the robot's
//! pose looked up in the tf tree at each of their stamps.

use std::collections::HashMap;
use std::path::Path;

use super::msg::{NS, POSE_STAMPED, TRANSFORM_STAMPED, frame_name};
use super::storage::bag_error;
use super::tf::{self, TfError, seconds};
use super::{Bag, TF_STATIC_TOPIC, TF_TOPIC, at, load, topic_list};
use crate::io::sync::{Lookup, MAX_TIME_OFFSET, StampedPose};
use crate::io::{CameraMount, StampedPosePair};
use crate::model::error::{Error, Result};
use crate::model::findings::Written;
use crate::model::motion::{PosePair, Setup};

/// Which frames and topics make the pose pairs; `Default` gives the values on each field.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BagOptions {
    /// The robot's base frame (e.g. `base_link`). No default: required.
    pub base_frame: String,
    /// The gripper's frame (e.g. `tool0`). No default: required.
    pub gripper_frame: String,
    /// The camera frame whose pose X is (e.g. `camera_link`, or an optical frame below it; see
    /// [`BagPairs::camera_mount`]). No default: required.
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
    /// The setup, which makes X's parent frame the gripper's (eye-in-hand) or the base's
    /// (eye-to-hand), for [`BagPairs::camera_mount`]. Default eye-in-hand.
    pub setup: Setup,
}

/// Default `max_gap`, seconds.
pub(crate) const DEFAULT_MAX_GAP: f64 = 0.1;

/// The longest `max_gap`, seconds (11.6 days).
const MAX_GAP: f64 = 1e6;

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
    /// Observations at a stamp an earlier observation has: one is kept per stamp, the first read
    /// (as tf2 does with the samples of a transform), whether the target is in `/tf` or a topic.
    pub dropped_repeated: usize,
    /// Samples of the robot's dynamic transforms dropped for the same reason.
    pub robot_repeated: usize,
    /// `base_from_gripper` at every stamp of the robot's dynamic transforms (robot clock), for an
    /// estimate of the clock offset ([`crate::io::sync::estimate_time_offset`]). Stamps are seconds
    /// from the robot's first stamp, so that they keep their nanoseconds (seconds since the epoch
    /// resolve to 2.4e-7 s in f64).
    pub robot_stream: Vec<StampedPose>,
    /// `camera_from_target` at every observation (camera clock), in time order; stamps from the
    /// same origin as `robot_stream`'s.
    pub camera_stream: Vec<StampedPose>,
    /// Where tf places the camera frame, when it gives it a parent (an optical frame under
    /// `camera_link`): X is then published for the root of the camera's subtree.
    pub camera_mount: Option<CameraMount>,
    /// The joint angles at each pair, from a `sensor_msgs/msg/JointState` topic
    /// (`/joint_states`), where every pair has them.
    pub(crate) joints: super::joints::BagJoints,
}

impl BagPairs {
    /// The pose pairs alone.
    pub fn poses(&self) -> Vec<PosePair> {
        self.pairs.iter().map(|p| p.pose).collect()
    }
}

/// Seconds as nanoseconds, for an offset or a gap given in seconds.
fn nanoseconds(name: &'static str, value: f64, most: f64) -> Result<i64> {
    if !(value.is_finite() && value.abs() <= most) {
        return Err(Error::InvalidParameter {
            name,
            message: format!(
                "{value:e} s is not a usable time (finite, at most {most:e} s in size)"
            ),
        });
    }
    Ok((value * NS as f64).round() as i64)
}

/// Where `tf` places the camera frame, X's parent frame being the gripper's or the base's by
/// `setup`.
pub(super) fn camera_mount(
    tf: &tf::TfBuffer,
    camera: &str,
    [base, gripper]: [&str; 2],
    setup: Setup,
) -> Option<CameraMount> {
    let x_parent = match setup {
        Setup::EyeInHand => gripper,
        Setup::EyeToHand => base,
    };
    super::mount::camera_mount(tf, camera, [base, gripper], x_parent)
}

/// The tf path from the base to the gripper, refused when the two frames are swapped (the base
/// below the gripper) or when no transform on it moves.
pub(super) fn robot_path(
    tf: &tf::TfBuffer,
    base: &str,
    gripper: &str,
    whole: &dyn Fn(String) -> Error,
) -> Result<tf::TfPath> {
    let robot_path = tf
        .path(base, gripper)
        .map_err(|e| whole(format!("the robot's pose: {e}")))?;
    // A robot's tf tree runs from its base down to its tool (robot_state_publisher publishes each
    // link under its parent): a base frame below the gripper frame is the two flags swapped, told
    // by the tree itself, whatever the poses fit (issue 33 item 13).
    if robot_path.down.is_empty() && !robot_path.up.is_empty() {
        let chain = std::iter::once(gripper)
            .chain(robot_path.up.iter().rev().map(String::as_str))
            .collect::<Vec<_>>()
            .join(" → ");
        return Err(whole(format!(
            "the base frame `{base}` is below the gripper frame `{gripper}` in the tf tree ({chain}, parent to child): the two frame names are swapped; swap the two frame flags, `--base-frame {gripper} --gripper-frame {base}` (`base_frame=\"{gripper}\", gripper_frame=\"{base}\"` in Python); tf's directions are the recording's own, and inverting the poses is not the fix"
        )));
    }
    if tf.dynamic_on(&robot_path).is_empty() {
        return Err(whole(format!(
            "the pose of `{gripper}` in `{base}` never changes: every transform between them is in /tf_static (is the gripper frame right?)"
        )));
    }

    Ok(robot_path)
}

/// The frame `value` names (the flag or field `name`), as tf2 keys it; refused when empty.
pub(crate) fn required_frame(name: &'static str, value: &str) -> Result<String> {
    let f = frame_name(value.trim());
    if f.is_empty() {
        return Err(Error::InvalidParameter {
            name,
            message: "a frame name is needed to read a ROS 2 recording".into(),
        });
    }
    Ok(f)
}

/// The pose pairs of a recording: at each stamp of the target's pose, `base_from_gripper` from
/// the tf tree and `camera_from_target` (see the [module](super) documentation).
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
    let frame = required_frame;
    let base = frame("base_frame", &options.base_frame)?;
    let gripper = frame("gripper_frame", &options.gripper_frame)?;
    let camera = frame("camera_frame", &options.camera_frame)?;
    let target_frame = options
        .target_frame
        .as_deref()
        .map(|t| frame("target_frame", t))
        .transpose()?;
    let target_topic = options.target_topic.as_deref().map(str::trim);
    let offset_ns = nanoseconds("time_offset", options.time_offset, MAX_TIME_OFFSET)?;
    let max_gap = if options.max_gap > 0.0 {
        options.max_gap
    } else {
        DEFAULT_MAX_GAP
    };
    let max_gap_ns = nanoseconds("max_gap", max_gap, MAX_GAP)?;
    let loaded = load(&bag, target_topic, super::InfoTopics::None)?;
    let whole = |message: String| bag_error(path, None, message);
    let tf_error = |what: &str, e: TfError| whole(format!("{what}: {e}"));
    let tf = &loaded.tf;

    if !loaded.topics.has(TF_TOPIC) && !loaded.topics.has(TF_STATIC_TOPIC) {
        return Err(whole(format!(
            "no /tf or /tf_static topic; the topics are: {}",
            topic_list(&loaded.topics)
        )));
    }
    let robot_path = robot_path(tf, &base, &gripper, &whole)?;

    // The target's observations: (number, stamp, camera_from_target or why not).
    let mut observations: Vec<(usize, i64, Lookup)> = Vec::new();
    // Observations dropped for a stamp an earlier one has.
    let mut dropped_repeated = 0;
    let target_source;
    match target_topic {
        Some(topic) => {
            let types = super::topic_types(&loaded.topics, topic, whole)?;
            if types.contains(&super::msg::APRILTAG_DETECTIONS) {
                return Err(whole(format!(
                    "topic `{topic}` has type `{}`: tag detections are calibrated on the pixels (`--method reprojection --tag-size METRES`)",
                    super::msg::APRILTAG_DETECTIONS
                )));
            }
            if !types
                .iter()
                .any(|t| *t == POSE_STAMPED || *t == TRANSFORM_STAMPED)
            {
                return Err(whole(format!(
                    "topic `{topic}` has type `{}`; a target topic must be `{POSE_STAMPED}` or `{TRANSFORM_STAMPED}`",
                    types.join("`, `")
                )));
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
            dropped_repeated = tf.repeated(&edge);
        }
    }
    // One observation per stamp, the first read (stable sort), as tf2 keeps a transform's.
    observations.sort_by_key(|o| o.1);
    let read = observations.len();
    observations.dedup_by_key(|o| o.1);
    dropped_repeated += read - observations.len();

    let robot_edges = tf.dynamic_on(&robot_path);
    let mut robot_stamps: Vec<i64> = robot_edges
        .iter()
        .flat_map(|edge| tf.stamps_of(edge))
        .collect();
    robot_stamps.sort_unstable();
    robot_stamps.dedup();
    let origin = robot_stamps.first().copied().unwrap_or(0);
    let since_origin = |t: i64| seconds(t.saturating_sub(origin));
    let robot_stream = robot_stamps
        .into_iter()
        .filter_map(|t| match tf.lookup(&robot_path, t, max_gap_ns) {
            Lookup::Pose(pose) => Some(StampedPose {
                stamp: since_origin(t),
                pose,
            }),
            _ => None,
        })
        .collect();
    let camera_stream = observations
        .iter()
        .filter_map(|(_, t, o)| match o {
            Lookup::Pose(pose) => Some(StampedPose {
                stamp: since_origin(*t),
                pose: *pose,
            }),
            _ => None,
        })
        .collect();
    let mut out = BagPairs {
        pairs: Vec::new(),
        names: Vec::new(),
        target_source: target_source.clone(),
        observations: observations.len() + dropped_repeated,
        dropped_outside: 0,
        dropped_gap: 0,
        dropped_repeated,
        robot_repeated: robot_edges.iter().map(|e| tf.repeated(e)).sum(),
        robot_stream,
        camera_stream,
        camera_mount: camera_mount(tf, &camera, [&base, &gripper], options.setup),
        joints: super::joints::BagJoints::default(),
    };
    // The robot clock's stamp of each pair kept, for its joint angles.
    let mut robot_stamps_ns = Vec::new();
    for (index, stamp_ns, camera_from_target) in observations {
        let robot = tf.lookup(&robot_path, stamp_ns.saturating_sub(offset_ns), max_gap_ns);
        match (robot, camera_from_target) {
            (Lookup::Pose(base_from_gripper), Lookup::Pose(camera_from_target)) => {
                let stamp = seconds(stamp_ns);
                out.pairs.push(StampedPosePair::new(
                    index,
                    Some(stamp),
                    PosePair {
                        base_from_gripper,
                        camera_from_target,
                    },
                    Written::NAMED,
                ));
                out.names
                    .push(format!("{target_source} #{index} (t = {stamp:.3} s)"));
                robot_stamps_ns.push(stamp_ns.saturating_sub(offset_ns));
            }
            (Lookup::Gap, _) | (_, Lookup::Gap) => out.dropped_gap += 1,
            _ => out.dropped_outside += 1,
        }
    }
    out.joints = super::joints::joints_at(&loaded.joints, &robot_stamps_ns, max_gap_ns);
    if out.pairs.len() < 2 {
        return Err(whole(format!(
            "{} observation(s) of the target ({target_source}), {} within the robot's transforms ({} outside them, {} in their gaps longer than {max_gap} s{}): at least 2 pose pairs are needed",
            out.observations,
            out.pairs.len(),
            out.dropped_outside,
            out.dropped_gap,
            match out.dropped_repeated {
                0 => String::new(),
                n => format!(", {n} stamped like an earlier one"),
            }
        )));
    }
    Ok(out)
}
