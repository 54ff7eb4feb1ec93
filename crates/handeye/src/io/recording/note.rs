//! What reading an input found worth telling ([`Note`]), in the command line's words.

use std::fmt;

use super::CameraMount;
use crate::io::sync::FoundOffset;
use crate::io::{Preamble, Projections};

/// What reading an input found worth telling, in the words the command line prints (see
/// `Display`).
#[derive(Debug, Clone, PartialEq)]
pub enum Note {
    /// Lines skipped before the first pose record of `source`.
    Preamble {
        /// The file (`-` for standard input).
        source: String,
        /// What was skipped.
        preamble: Preamble,
    },
    /// Rotation matrices of `source` projected onto the nearest rotation.
    Projections {
        /// The file.
        source: String,
        /// How many, and the largest deviation.
        projections: Projections,
    },
    /// Samples of a stream out of time order, put in order.
    Reordered {
        /// The stream's file.
        file: String,
        /// How many samples.
        count: usize,
    },
    /// The clock offset found by `auto` (or by default).
    TimeOffset {
        /// The offset used, seconds: the correlation's, refined by the paired poses' agreement.
        offset: f64,
        /// Its one-sigma, seconds.
        sigma: f64,
        /// Where the angular speeds correlate best, seconds.
        correlated_at: f64,
        /// Their correlation there.
        correlation: f64,
    },
    /// The clock offset could not be estimated (by default): the streams are paired at 0 s.
    NoTimeOffset {
        /// Why the search failed.
        why: String,
    },
    /// Camera samples of two streams that found no robot pose.
    Dropped {
        /// Outside the robot stream's time span.
        outside: usize,
        /// In its gaps longer than `max_gap`.
        gap: usize,
        /// The longest gap interpolated across, seconds.
        max_gap: f64,
    },
    /// Every angle one side of `source` gave in degrees (a convention in degrees) is within ±2π:
    /// radians given to a convention in degrees, most likely (every angle within a turn of a whole recording).
    SmallDegrees {
        /// The file.
        source: String,
        /// `robot` or `camera`.
        side: &'static str,
        /// The largest angle given, in size.
        largest: f64,
    },
    /// The pose pairs a ROS 2 recording gave.
    BagPairs {
        /// The recording.
        path: String,
        /// Pose pairs made.
        pairs: usize,
        /// Observations of the target read.
        observations: usize,
        /// Where the target's pose came from.
        target_source: String,
        /// Observations outside the robot's transforms.
        outside: usize,
        /// Observations in the robot's transforms' gaps longer than `max_gap`.
        gap: usize,
        /// The longest gap interpolated across, seconds.
        max_gap: f64,
        /// Observations at a stamp an earlier one has (the first of each stamp kept).
        repeated: usize,
        /// Samples of the robot's transforms at a stamp an earlier one has (the first kept).
        robot_repeated: usize,
    },
    /// The camera frame of a ROS 2 recording has a parent in its tf: X found for it is published
    /// for the root of the camera's subtree, or not at all when the camera is placed in the
    /// robot's tree already.
    CameraMount {
        /// The recording.
        path: String,
        /// Where tf places the camera frame.
        mount: CameraMount,
    },
    /// The joint angles a ROS 2 recording gave (a `sensor_msgs/msg/JointState` topic), or why
    /// they are not used.
    BagJoints {
        /// The recording.
        path: String,
        /// The topic read.
        topic: String,
        /// The joints, in the order of the angles.
        joints: Vec<String>,
        /// Whether every pose pair has its angles (else none are used).
        used: bool,
        /// Messages skipped and why (topic and message number), and why the angles are not used.
        skipped: Vec<String>,
    },
    /// The images of a tag a ROS 2 recording gave (an `apriltag_msgs/msg/AprilTagDetectionArray`
    /// topic), for a calibration on the pixels.
    BagTags {
        /// The recording.
        path: String,
        /// The detections topic.
        topic: String,
        /// The tag id used.
        id: i32,
        /// Images kept.
        frames: usize,
        /// Messages of the topic.
        messages: usize,
        /// Detections of other tag ids left out.
        other_tags: usize,
        /// Images outside the robot's transforms or in their gaps.
        dropped: usize,
        /// Messages skipped and why (topic and message number).
        skipped: Vec<String>,
        /// The camera_info topic the intrinsics were read from, if any.
        intrinsics_topic: Option<String>,
    },
}

impl fmt::Display for Note {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Preamble { source, preamble } => write!(f, "{source}: {}", preamble.note()),
            Self::Projections {
                source,
                projections,
            } => write!(f, "{source}: {}", projections.note().unwrap_or_default()),
            Self::Reordered { file, count } => {
                write!(
                    f,
                    "{file}: {count} sample(s) out of time order, put in order"
                )
            }
            Self::TimeOffset {
                offset,
                sigma,
                correlated_at,
                correlation,
            } => write!(
                f,
                "time offset: {offset:.4} s ± {:.1} ms (camera clock minus robot clock; angular speeds correlate best at {correlated_at:.4} s, {correlation:.3}; refined by the agreement of the paired poses; `--time-offset SECONDS` sets it)",
                1e3 * sigma
            ),
            Self::NoTimeOffset { why } => write!(
                f,
                "time offset: not estimated ({why}): paired at 0 s; give `--time-offset SECONDS` if the clocks differ"
            ),
            Self::Dropped {
                outside,
                gap,
                max_gap,
            } => write!(
                f,
                "dropped {outside} camera sample(s) outside the robot stream and {gap} in gaps longer than {max_gap} s"
            ),
            Self::SmallDegrees {
                source,
                side,
                largest,
            } => write!(
                f,
                "{source}: every {side} angle given in degrees is within ±{largest:.2}, so the {side} poses turn by a few degrees at most: if these are radians, convert them to degrees (× 180/π)"
            ),
            Self::BagPairs { .. } => self.fmt_bag_pairs(f),
            Self::BagTags {
                path,
                topic,
                id,
                frames,
                messages,
                other_tags,
                dropped,
                skipped,
                intrinsics_topic,
            } => {
                write!(
                    f,
                    "{path}: {frames} image(s) of tag {id} from {messages} message(s) of {topic}"
                )?;
                if let Some(t) = intrinsics_topic {
                    write!(f, "; intrinsics from {t}")?;
                }
                if *other_tags > 0 {
                    write!(f, "; {other_tags} detection(s) of other tags left out")?;
                }
                if *dropped > 0 {
                    write!(
                        f,
                        "; dropped {dropped} outside the robot's transforms or in their gaps"
                    )?;
                }
                for why in skipped {
                    write!(f, "; skipped {why}")?;
                }
                Ok(())
            }
            Self::CameraMount { path, mount } => mount.fmt_note(path, f),
            Self::BagJoints {
                path,
                topic,
                joints,
                used,
                skipped,
            } => {
                if *used {
                    write!(
                        f,
                        "{path}: joint angles from {topic} at every pose pair ({} joint(s): {})",
                        joints.len(),
                        joints.join(", ")
                    )?;
                } else {
                    write!(f, "{path}: joint angles of {topic} not used")?;
                }
                for why in skipped {
                    write!(f, "; {why}")?;
                }
                Ok(())
            }
        }
    }
}

impl Note {
    /// The notes of the angles in degrees of `source` that look like radians.
    pub fn small_degrees(source: &str, degrees: &crate::io::DegreeAngles) -> Vec<Self> {
        degrees
            .within_a_radian_turn()
            .into_iter()
            .map(|(side, largest)| Self::SmallDegrees {
                source: source.to_string(),
                side,
                largest,
            })
            .collect()
    }

    /// The note of an offset found by the search.
    pub(crate) fn time_offset(found: &FoundOffset) -> Self {
        Self::TimeOffset {
            offset: found.offset,
            sigma: found.sigma,
            correlated_at: found.correlated.offset,
            correlation: found.correlated.correlation,
        }
    }

    /// [`Note::BagPairs`] in words.
    fn fmt_bag_pairs(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let Self::BagPairs {
            path,
            pairs,
            observations,
            target_source,
            outside,
            gap,
            max_gap,
            repeated,
            robot_repeated,
        } = self
        else {
            return Ok(());
        };
        write!(
            f,
            "{path}: {pairs} pose pair(s) from {observations} observation(s) of the target ({target_source})"
        )?;
        if outside + gap > 0 {
            write!(
                f,
                "; dropped {outside} outside the robot's transforms and {gap} in their gaps longer than {max_gap} s"
            )?;
        }
        if *repeated > 0 {
            write!(
                f,
                "; dropped {repeated} observation(s) stamped like an earlier one (one pose per stamp: the first read, as tf2 keeps)"
            )?;
        }
        if *robot_repeated > 0 {
            write!(
                f,
                "; dropped {robot_repeated} sample(s) of the robot's transforms stamped like an earlier one (the first read kept, as tf2 does)"
            )?;
        }
        Ok(())
    }
}
