//! A ROS 2 recording read into a [`Recording`].

use std::path::Path;

use super::{BagFrames, Note, Notes, Recording, RecordingOptions};
use crate::io::rosbag::{BagOptions, read_bag_pairs};
use crate::io::sync::{
    OffsetOptions, StampedPose, TimeOffset, estimate_time_offset, refine_time_offset,
};
use crate::model::error::{Error, Result};

/// The clock offset (camera − robot, seconds) of two streams: the angular speeds' correlation,
/// refined by how well the paired poses agree on one X, with its note and the correlation curve.
/// `streams` names them in an error.
fn auto_offset(
    robot: &[StampedPose],
    camera: &[StampedPose],
    options: &RecordingOptions,
    streams: impl FnOnce() -> String,
    notes: &mut Notes<'_>,
) -> Result<(f64, Vec<[f64; 2]>)> {
    let search = OffsetOptions::default();
    let e = estimate_time_offset(robot, camera, &search).map_err(|e| Error::TimeOffset {
        streams: streams(),
        source: Box::new(e),
    })?;
    let refined = refine_time_offset(
        robot,
        camera,
        options.setup,
        e.offset,
        search.max_offset,
        options.max_gap,
    );
    notes.add(Note::TimeOffset {
        offset: refined,
        correlated_at: e.offset,
        correlation: e.correlation,
    });
    Ok((refined, e.curve))
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
    };
    let (time_offset, offset_curve) = match options.time_offset {
        None => (0.0, None),
        Some(TimeOffset::Fixed(t)) => (t, None),
        Some(TimeOffset::Auto) => {
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
            let (offset, curve) = auto_offset(
                &first.robot_stream,
                &first.camera_stream,
                options,
                streams,
                notes,
            )?;
            (offset, Some(curve))
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
    });
    Ok(Recording {
        poses: pairs.poses(),
        lines: pairs.pairs.iter().map(|p| p.line).collect(),
        stamps: pairs.pairs.iter().map(|p| p.stamp).collect(),
        names: pairs.names,
        time_offset: options.time_offset.map(|_| time_offset),
        offset_curve,
        target_source: Some(pairs.target_source),
        notes: Vec::new(),
    })
}
