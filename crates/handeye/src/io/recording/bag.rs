//! A ROS 2 recording read into a [`Recording`].

use std::path::Path;

use super::{BagFrames, FrameRecording, Note, Notes, Recording, RecordingOptions};
use crate::io::rosbag::{BagOptions, BagTags, read_bag_pairs, read_bag_tags};
use crate::io::sync::{FoundOffset, StampedPose, TimeOffset, find_time_offset, read_as};
use crate::model::error::{Error, Result};
use crate::model::findings::Written;

/// The clock offset (camera − robot, seconds) of two streams, its sigma and the correlation
/// curve ([`find_time_offset`]), with its note. `streams` names them in an error.
fn auto_offset(
    robot: &[StampedPose],
    camera: &[StampedPose],
    options: &RecordingOptions,
    streams: impl FnOnce() -> String,
    notes: &mut Notes<'_>,
) -> Result<FoundOffset> {
    let (robot, camera) = read_as(options.reading, Written::NAMED, robot, camera);
    let found = find_time_offset(&robot, &camera, options.setup, options.max_gap).map_err(|e| {
        Error::TimeOffset {
            streams: streams(),
            source: Box::new(e),
        }
    })?;
    notes.add(Note::time_offset(&found));
    Ok(found)
}

/// A ROS 2 recording: with `auto`, read once as it is to find the offset, then with it.
pub(super) fn read_bag(
    path: &Path,
    frames: &BagFrames,
    options: &RecordingOptions,
    notes: &mut Notes<'_>,
) -> Result<Recording> {
    let mut bag_options = BagOptions {
        base_frame: frames.base.clone(),
        gripper_frame: frames.gripper.clone(),
        camera_frame: frames.camera.clone(),
        target_frame: frames.target.clone(),
        target_topic: frames.target_topic.clone(),
        time_offset: 0.0,
        max_gap: options.max_gap,
        setup: options.setup,
    };
    let (time_offset, found) = match options.time_offset {
        Some(TimeOffset::Fixed(t)) => (t, None),
        requested => {
            // Stamped by another clock (a detector that stamps on arrival, say): find the offset
            // on the streams of the recording read as it is.
            let first = read_bag_pairs(path, &bag_options)?;
            let streams = || {
                format!(
                    "the robot's tf and {} in {}",
                    first.target_source,
                    path.display()
                )
            };
            match auto_offset(
                &first.robot_stream,
                &first.camera_stream,
                options,
                streams,
                notes,
            ) {
                Ok(found) => (found.offset, Some(found)),
                // By default, a recording that does not tell its offset is paired at 0 s.
                Err(Error::TimeOffset { source, .. }) if requested.is_none() => {
                    notes.add(Note::NoTimeOffset {
                        why: match *source {
                            Error::InvalidParameter { message, .. } => message,
                            e => e.to_string(),
                        },
                    });
                    (0.0, None)
                }
                Err(e) => return Err(e),
            }
        }
    };
    bag_options.time_offset = time_offset;
    let pairs = read_bag_pairs(path, &bag_options)?;
    notes.add(Note::BagPairs {
        path: path.display().to_string(),
        pairs: pairs.pairs.len(),
        observations: pairs.observations,
        target_source: pairs.target_source.clone(),
        outside: pairs.dropped_outside,
        gap: pairs.dropped_gap,
        max_gap: options.max_gap,
        repeated: pairs.dropped_repeated,
        robot_repeated: pairs.robot_repeated,
    });
    if let Some(topic) = &pairs.joints.topic {
        notes.add(Note::BagJoints {
            path: path.display().to_string(),
            topic: topic.clone(),
            joints: pairs.joints.names.clone(),
            used: !pairs.joints.angles.is_empty(),
            skipped: pairs.joints.skipped.clone(),
        });
    }
    if let Some(mount) = &pairs.camera_mount {
        notes.add(Note::CameraMount {
            path: path.display().to_string(),
            mount: mount.clone(),
        });
    }
    Ok(Recording {
        poses: pairs.poses(),
        lines: pairs.pairs.iter().map(|p| p.line).collect(),
        stamps: pairs.pairs.iter().map(|p| p.stamp).collect(),
        names: pairs.names,
        time_offset: Some(time_offset),
        time_offset_sigma: found.as_ref().map(|f| f.sigma),
        time_offset_agreement_deg: found.as_ref().map(|f| f.agreement_deg),
        offset_curve: found.map(|f| f.correlated.curve),
        target_source: Some(pairs.target_source),
        camera_mount: pairs.camera_mount,
        notes: Vec::new(),
        written: Written::FRAMES,
        joints: pairs.joints.angles,
    })
}

/// Reads the frames of a calibration on the pixels from a ROS 2 recording: the tag `tags` names
/// on `frames.target_topic` (an `apriltag_msgs/msg/AprilTagDetectionArray` topic; corner order in
/// [`TAG_CORNERS`](crate::io::rosbag::TAG_CORNERS)), the robot's pose from tf at each image's stamp
/// (less the clock offset), and the intrinsics of a `CameraInfo` topic.
///
/// One bad message costs that message (told in a [`Note::BagTags`]). The clock offset is
/// `options.time_offset` when fixed, else 0 s (told): the detections carry no pose whose motion
/// could be correlated with the robot's, and `auto` is refused.
///
/// Errors: those of the pose reader ([`Error::Bag`] naming the file, topic and message), a tag
/// size that is not a positive length, several tag ids and none chosen.
pub(super) fn read_bag_frames(
    path: &Path,
    frames: &BagFrames,
    tags: &BagTags,
    options: &RecordingOptions,
) -> Result<FrameRecording> {
    let mut notes = Vec::new();
    let time_offset = match options.time_offset {
        Some(TimeOffset::Fixed(t)) => t,
        Some(TimeOffset::Auto) => {
            return Err(Error::InvalidParameter {
                name: "time_offset",
                message: "`auto` is not offered on tag detections: they carry no pose whose motion could be correlated with the robot's; give the offset in seconds".into(),
            });
        }
        None => {
            notes.push(Note::NoTimeOffset {
                why:
                    "tag detections carry no pose whose motion could be correlated with the robot's"
                        .into(),
            });
            0.0
        }
    };
    let bag_options = BagOptions {
        base_frame: frames.base.clone(),
        gripper_frame: frames.gripper.clone(),
        camera_frame: frames.camera.clone(),
        target_frame: frames.target.clone(),
        target_topic: frames.target_topic.clone(),
        time_offset,
        max_gap: options.max_gap,
        setup: options.setup,
    };
    let read = read_bag_tags(path, &bag_options, tags)?;
    let display = path.display().to_string();
    notes.push(Note::BagTags {
        path: display.clone(),
        topic: frames.target_topic.clone().unwrap_or_default(),
        id: read.id,
        frames: read.frames.len(),
        messages: read.messages,
        other_tags: read.other_tags,
        dropped: read.dropped,
        skipped: read.skipped.clone(),
        intrinsics_topic: read.intrinsics.as_ref().map(|(t, _)| t.clone()),
    });
    if let Some(mount) = &read.camera_mount {
        notes.push(Note::CameraMount {
            path: display,
            mount: mount.clone(),
        });
    }
    Ok(FrameRecording {
        frames: read.frames,
        lines: read.lines,
        names: read.names,
        intrinsics: read.intrinsics.map(|(_, k)| k),
        camera_mount: read.camera_mount,
        time_offset: Some(time_offset),
        notes,
    })
}
