//! A recording on the pixels from a ROS 2 recording: the corners of an AprilTag
//! (`apriltag_msgs/msg/AprilTagDetectionArray`, apriltag_ros) at each image, the robot's pose
//! looked up in the tf tree at its stamp, and the camera's intrinsics from a
//! `sensor_msgs/msg/CameraInfo` topic.
//!
//! # Corner order
//! apriltag_ros copies the corners of the AprilTag library (`apriltag_detection_t::p`), which
//! wrap counter-clockwise in the image; the library's own pose estimate
//! (`apriltag_pose.c`) places them, for a tag of side `s`, at ([`TAG_CORNERS`] × `s`)
//! ```text
//! corner 0: (−s/2, +s/2, 0)   corner 1: (+s/2, +s/2, 0)
//! corner 2: (+s/2, −s/2, 0)   corner 3: (−s/2, −s/2, 0)
//! ```
//! in the tag's frame (origin at its centre, z into the tag). The target's pose Y and
//! `camera_from_target` are of that frame.

use std::collections::BTreeMap;
use std::path::Path;

use super::msg::{APRILTAG_DETECTIONS, CAMERA_INFO, NS, frame_name};
use super::pairs::{BagOptions, DEFAULT_MAX_GAP, robot_path};
use super::storage::bag_error;
use super::tf::seconds;
use super::{Bag, InfoTopics, at, load, topic_list};
use crate::io::intrinsics::intrinsics_of_camera_info;
use crate::io::sync::Lookup;
use crate::model::camera::{Detections, Frame, Intrinsics};
use crate::model::error::{Error, Result};

/// The corners of a tag of side 1 in its frame, in the detector's order (see the module docs).
pub const TAG_CORNERS: [[f64; 3]; 4] = [
    [-0.5, 0.5, 0.0],
    [0.5, 0.5, 0.0],
    [0.5, -0.5, 0.0],
    [-0.5, -0.5, 0.0],
];

/// The largest tag side accepted, in the input unit (metres: 100 m).
const MAX_TAG_SIZE: f64 = 100.0;

/// At most this many skipped messages are named one by one in [`TagFrames::skipped`].
const NAMED_SKIPS: usize = 10;

/// The tag that is the target of a recording on the pixels, and where its intrinsics are;
/// `Default` gives the values on each field.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BagTags {
    /// The side of the tag's black square, input unit (metres). No default: required.
    pub size: f64,
    /// The tag's id: detections of other ids are left out (and counted). Default none: the
    /// recording must show one id only.
    pub id: Option<i32>,
    /// A `sensor_msgs/msg/CameraInfo` topic for the intrinsics. Default none: a topic whose name
    /// ends in `camera_info`, when the recording has exactly one.
    pub camera_info_topic: Option<String>,
}

/// The frames of a recording on the pixels read from a ROS 2 recording.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct TagFrames {
    /// The frames, in time order (`camera_from_target` none: the detections only).
    pub frames: Vec<Frame>,
    /// Each frame's message number in its topic, from 1.
    pub lines: Vec<usize>,
    /// Each frame's header stamp, seconds.
    pub stamps: Vec<f64>,
    /// A name for each frame: topic, message number and stamp.
    pub names: Vec<String>,
    /// The intrinsics of the first `CameraInfo` message that decodes, and its topic.
    pub intrinsics: Option<(String, Intrinsics)>,
    /// The tag id used.
    pub id: i32,
    /// Messages of the detections topic read.
    pub messages: usize,
    /// Messages skipped, each a reason (the first few named by topic and number, then counted).
    pub skipped: Vec<String>,
    /// Detections of other tag ids left out.
    pub other_tags: usize,
    /// Images outside the robot's transforms or in their gaps.
    pub dropped: usize,
    /// Where tf places the camera frame, when it gives it a parent.
    pub camera_mount: Option<crate::io::CameraMount>,
}

/// The frames of a recording on the pixels: at each message of `options.target_topic` (an
/// `AprilTagDetectionArray`) that holds the tag `tags.id`, the robot's pose from the tf tree at
/// its stamp (less `options.time_offset`) and the tag's four corners placed at [`TAG_CORNERS`]
/// × `tags.size`.
///
/// One bad message costs that message: a message that does not decode (truncated, another
/// definition of the type), that holds the tag twice, or that lacks it, is skipped and named in
/// [`TagFrames::skipped`]. Errors ([`Error::Bag`], [`Error::InvalidParameter`]): a tag size that
/// is not a positive length, a topic that is missing or of another type, detections given in
/// another frame than the camera's, several tag ids and none chosen, a chosen id never seen,
/// fewer than 2 frames, a camera_info topic named but absent or never decoded.
pub(crate) fn read_bag_tags(
    path: &Path,
    options: &BagOptions,
    tags: &BagTags,
) -> Result<TagFrames> {
    if !(tags.size.is_finite() && tags.size > 0.0 && tags.size <= MAX_TAG_SIZE) {
        return Err(Error::InvalidParameter {
            name: "tag_size",
            message: format!(
                "{} is not a tag side: a positive length in the robot's unit (metres), at most {MAX_TAG_SIZE}",
                tags.size
            ),
        });
    }
    let bag = Bag::open(path)?;
    let frame = super::pairs::required_frame;
    let base = frame("base_frame", &options.base_frame)?;
    let gripper = frame("gripper_frame", &options.gripper_frame)?;
    let camera = frame("camera_frame", &options.camera_frame)?;
    let Some(topic) = options.target_topic.as_deref().map(str::trim) else {
        return Err(Error::InvalidParameter {
            name: "target_topic",
            message: format!(
                "the topic of the tag's detections (`{APRILTAG_DETECTIONS}`) is needed"
            ),
        });
    };
    if !(options.time_offset.is_finite() && options.time_offset.abs() <= 4e9) {
        return Err(Error::InvalidParameter {
            name: "time_offset",
            message: format!("{:e} s is not a usable time", options.time_offset),
        });
    }
    let offset_ns = (options.time_offset * NS as f64).round() as i64;
    let max_gap = if options.max_gap > 0.0 && options.max_gap <= 1e6 {
        options.max_gap
    } else {
        DEFAULT_MAX_GAP
    };
    let max_gap_ns = (max_gap * NS as f64).round() as i64;
    let info_topics = match tags.camera_info_topic.as_deref() {
        Some(t) => InfoTopics::Named(t.trim()),
        None => InfoTopics::Any,
    };
    let loaded = load(&bag, Some(topic), info_topics)?;
    let whole = |message: String| bag_error(path, None, message);
    let types = super::topic_types(&loaded.topics, topic, whole)?;
    if !types.contains(&APRILTAG_DETECTIONS) {
        return Err(whole(format!(
            "topic `{topic}` has type `{}`; the detections of a tag are `{APRILTAG_DETECTIONS}` (a pose topic is calibrated without `--method reprojection`)",
            types.join("`, `")
        )));
    }
    let tf = &loaded.tf;
    let robot = robot_path(tf, &base, &gripper, &whole)?;

    let mut skipped = Vec::new();
    let mut skips = 0usize;
    let mut skip = |index: usize, why: String| {
        skips += 1;
        if skipped.len() < NAMED_SKIPS {
            skipped.push(format!("topic {topic}, message {index}: {why}"));
        }
    };
    // The tag ids seen, with the messages that hold each.
    let mut ids: BTreeMap<i32, usize> = BTreeMap::new();
    for sample in &loaded.tags {
        if let Ok(d) = &sample.decoded {
            if frame_name(&d.header.frame_id) != camera {
                return Err(bag_error(
                    path,
                    at(topic, sample.index),
                    format!(
                        "the detections are in `{}` (header.frame_id), not in the camera frame `{camera}`: give the frame of the image, `--camera-frame {}`",
                        d.header.frame_id, d.header.frame_id
                    ),
                ));
            }
            for t in &d.detections {
                *ids.entry(t.id).or_insert(0) += 1;
            }
        }
    }
    let seen = || {
        ids.iter()
            .map(|(id, n)| format!("{id} ({n} detection(s))"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let id = match tags.id {
        Some(id) if ids.contains_key(&id) => id,
        Some(id) => {
            return Err(whole(format!(
                "tag id {id} is in no detection of `{topic}`; the ids seen are: {}",
                if ids.is_empty() {
                    "none".into()
                } else {
                    seen()
                }
            )));
        }
        None => match ids.keys().copied().collect::<Vec<_>>()[..] {
            [id] => id,
            [] => {
                return Err(whole(format!(
                    "no detection in `{topic}` ({} message(s), none with a tag that decodes)",
                    loaded.tags.len()
                )));
            }
            _ => {
                return Err(Error::InvalidParameter {
                    name: "tag_id",
                    message: format!(
                        "`{topic}` shows several tags, {}: name the one that is the target (`--tag-id ID`)",
                        seen()
                    ),
                });
            }
        },
    };

    let mut samples: Vec<(usize, i64, [[f64; 2]; 4])> = Vec::new();
    let mut other_tags = 0;
    for sample in &loaded.tags {
        let d = match &sample.decoded {
            Ok(d) => d,
            Err(why) => {
                skip(sample.index, why.clone());
                continue;
            }
        };
        let mine: Vec<_> = d.detections.iter().filter(|t| t.id == id).collect();
        other_tags += d.detections.len() - mine.len();
        match mine[..] {
            [t] => {
                if let Some(c) = t.corners.iter().flatten().find(|c| !c.is_finite()) {
                    skip(sample.index, format!("a corner of tag {id} is {c}"));
                    continue;
                }
                samples.push((sample.index, d.header.stamp_ns, t.corners));
            }
            [] => skip(sample.index, format!("no detection of tag {id}")),
            _ => skip(
                sample.index,
                format!("tag {id} detected {} times in one image", mine.len()),
            ),
        }
    }
    // One image per stamp, the first read.
    samples.sort_by_key(|s| s.1);
    let before = samples.len();
    samples.dedup_by_key(|s| s.1);
    skips += before - samples.len();
    if before > samples.len() {
        skipped.push(format!(
            "{} message(s) stamped like an earlier one (the first read kept)",
            before - samples.len()
        ));
    }
    if skips > skipped.len() {
        skipped.push(format!("{} message(s) skipped in all", skips));
    }

    let target: Vec<[f64; 3]> = TAG_CORNERS
        .iter()
        .map(|c| [c[0] * tags.size, c[1] * tags.size, c[2] * tags.size])
        .collect();
    let mut out = TagFrames {
        frames: Vec::new(),
        lines: Vec::new(),
        stamps: Vec::new(),
        names: Vec::new(),
        intrinsics: None,
        id,
        messages: loaded.tags.len(),
        skipped,
        other_tags,
        dropped: 0,
        camera_mount: super::pairs::camera_mount(tf, &camera, [&base, &gripper], options.setup),
    };
    for (index, stamp_ns, corners) in samples {
        match tf.lookup(&robot, stamp_ns.saturating_sub(offset_ns), max_gap_ns) {
            Lookup::Pose(base_from_gripper) => {
                let stamp = seconds(stamp_ns);
                out.frames.push(Frame {
                    base_from_gripper,
                    camera_from_target: None,
                    detections: Detections {
                        target: target.clone(),
                        pixels: corners.to_vec(),
                    },
                });
                out.lines.push(index);
                out.stamps.push(stamp);
                out.names
                    .push(format!("{topic} #{index} (t = {stamp:.3} s)"));
            }
            _ => out.dropped += 1,
        }
    }
    if out.frames.len() < 2 {
        return Err(whole(format!(
            "{} message(s) in `{topic}`, {} image(s) of tag {id} within the robot's transforms ({} outside them or in their gaps longer than {max_gap} s): at least 2 are needed",
            out.messages,
            out.frames.len(),
            out.dropped
        )));
    }
    out.intrinsics = intrinsics(path, &loaded.infos, tags, &loaded.topics)?;
    Ok(out)
}

/// The intrinsics of the first `CameraInfo` message that decodes and describes a camera.
fn intrinsics(
    path: &Path,
    infos: &[super::InfoSample],
    tags: &BagTags,
    topics: &super::storage::Topics,
) -> Result<Option<(String, Intrinsics)>> {
    let topic = match tags.camera_info_topic.as_deref().map(str::trim) {
        Some(t) => {
            if !topics.has(t) {
                return Err(bag_error(
                    path,
                    None,
                    format!(
                        "no topic `{t}` in the recording; the topics are: {}",
                        topic_list(topics)
                    ),
                ));
            }
            t.to_string()
        }
        None => {
            let mut found: Vec<&str> = infos.iter().map(|i| i.topic.as_str()).collect();
            found.dedup();
            match found[..] {
                [] => return Ok(None),
                [t] => t.to_string(),
                _ => {
                    return Err(Error::InvalidParameter {
                        name: "camera_info_topic",
                        message: format!(
                            "the recording has several `{CAMERA_INFO}` topics ({}): name the camera's (`--camera-info-topic`)",
                            found.join(", ")
                        ),
                    });
                }
            }
        }
    };
    let mut last = None;
    for info in infos.iter().filter(|i| i.topic == topic) {
        let why = match &info.decoded {
            Ok(c) => match intrinsics_of_camera_info(
                &c.k,
                &c.d,
                &c.distortion_model,
                (c.width, c.height),
            ) {
                Ok(k) => return Ok(Some((topic, k))),
                Err(why) => why,
            },
            Err(why) => why.clone(),
        };
        last = Some(bag_error(path, at(&topic, info.index), why));
    }
    Err(last.unwrap_or_else(|| {
        bag_error(
            path,
            None,
            format!("topic `{topic}` holds no `{CAMERA_INFO}` message"),
        )
    }))
}
