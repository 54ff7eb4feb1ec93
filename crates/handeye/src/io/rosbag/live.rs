//! The pose pairs of a live ROS 2 system ([`LivePairs`]): transforms and observations of the
//! target taken one message at a time, each observation paired with the robot's pose at its
//! stamp by the rules of [`read_bag_pairs`](super::read_bag_pairs) (the same tf buffer, its
//! interpolation and gaps, the same frames and optical-frame rule), as soon as the robot's
//! transforms reach past it.

use std::collections::VecDeque;

use super::msg::{NS, frame_name};
use super::pairs::{BagOptions, DEFAULT_MAX_GAP, camera_mount, required_frame};
use super::tf::{TfBuffer, TfPath, seconds};
use crate::io::sync::{Lookup, MAX_TIME_OFFSET};
use crate::io::{CameraMount, StampedPosePair};
use crate::model::error::{Error, Result};
use crate::model::findings::Written;
use crate::model::motion::PosePair;
use crate::model::pose::{Transform, transform_from_xyz_quat_xyzw};

/// How long the buffer keeps the robot's transforms before the newest, nanoseconds (tf2's cache
/// keeps 10 s).
const KEEP_NS: i64 = 10 * NS;

/// Observations waiting for the robot's transforms to reach their stamp, at most; beyond, the
/// oldest is dropped.
const MAX_WAITING: usize = 10_000;

/// One transform as a message carries it: `parent_from_child` at `stamp_ns`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LiveTransform<'a> {
    /// `header.frame_id` (a leading `/` is dropped, as tf2 does).
    pub parent: &'a str,
    /// `child_frame_id`.
    pub child: &'a str,
    /// `header.stamp`, nanoseconds.
    pub stamp_ns: i64,
    /// The translation, metres.
    pub translation: [f64; 3],
    /// The rotation, `[x, y, z, w]`; normalised when its norm is within 1e-3 of 1, refused
    /// otherwise.
    pub quaternion_xyzw: [f64; 4],
}

/// What became of an observation of the target.
#[derive(Debug, Clone, PartialEq)]
pub enum LiveOutcome {
    /// Paired with the robot's pose at its stamp: a pose pair of the calibration (`line` is the
    /// observation's number, from 1; `stamp` its header stamp, seconds).
    Pair(Box<StampedPosePair>),
    /// Dropped, and why (the robot's pose at its stamp is unknown, a frame is missing, …).
    Dropped {
        /// The observation's number, from 1.
        number: usize,
        /// Its stamp, seconds.
        stamp: f64,
        /// Why.
        why: String,
    },
}

/// An observation of the target waiting for its pairing.
#[derive(Debug, Clone)]
struct Observation {
    number: usize,
    stamp_ns: i64,
    /// The frame the pose is given in, and `frame_from_target`; none for a target in `/tf`
    /// (looked up from the camera frame).
    given: Option<(String, Transform)>,
}

/// A live tf buffer that pairs each observation of the target with the robot's pose.
///
/// Transforms ([`LivePairs::transform`]) and observations ([`LivePairs::observation`]) are given
/// as they arrive, in any order; [`LivePairs::ready`] returns the observations whose pairing is
/// decided: an observation waits while the robot's transforms have not yet reached its stamp
/// (tf2's message filter does the same), and is dropped when its stamp lies before them or in
/// one of their gaps longer than `max_gap`.
///
/// # Example
/// ```
/// use handeye::io::rosbag::{BagOptions, LiveOutcome, LivePairs, LiveTransform};
///
/// let mut live = LivePairs::new(&BagOptions {
///     base_frame: "base_link".into(),
///     gripper_frame: "tool0".into(),
///     camera_frame: "camera".into(),
///     target_topic: Some("/board_pose".into()),
///     ..BagOptions::default()
/// })?;
/// let robot = |stamp_ns, x| LiveTransform {
///     parent: "base_link",
///     child: "tool0",
///     stamp_ns,
///     translation: [x, 0.0, 0.5],
///     quaternion_xyzw: [0.0, 0.0, 0.0, 1.0],
/// };
/// live.transform(robot(0, 0.0), false).unwrap();
/// live.observation("camera", None, 40_000_000, [0.0, 0.0, 0.4], [0.0, 0.0, 0.0, 1.0]).unwrap();
/// assert!(live.ready().is_empty()); // the robot's transforms have not reached t = 0.04 s
/// live.transform(robot(80_000_000, 0.1), false).unwrap();
/// let ready = live.ready();
/// let LiveOutcome::Pair(pair) = &ready[0] else { panic!("{ready:?}") };
/// assert!((pair.pose.base_from_gripper.translation.vector.x - 0.05).abs() < 1e-12);
/// # Ok::<(), handeye::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct LivePairs {
    base: String,
    gripper: String,
    camera: String,
    target_frame: Option<String>,
    /// Whether the target's pose comes on a topic (else in `/tf`).
    target_topic: bool,
    offset_ns: i64,
    max_gap_ns: i64,
    setup: crate::model::motion::Setup,
    tf: TfBuffer,
    /// Samples added since the buffer was last sorted.
    unsorted: bool,
    /// The robot's path, while the tree's shape is unchanged.
    robot_path: Option<TfPath>,
    waiting: VecDeque<Observation>,
    observations: usize,
    /// Observations dropped because too many waited.
    overflow: Vec<LiveOutcome>,
}

impl LivePairs {
    /// A buffer for the frames and options of `options` (its `target_topic` says only whether
    /// the target's pose comes on a topic of its own; without one, every `/tf` transform whose
    /// child is the target frame is an observation).
    ///
    /// Errors: an empty frame name; no target frame and no target topic; a time offset or gap
    /// that is not a usable time.
    pub fn new(options: &BagOptions) -> Result<Self> {
        let frame = required_frame;
        let target_frame = options
            .target_frame
            .as_deref()
            .map(|t| frame("target_frame", t))
            .transpose()?;
        let target_topic = options.target_topic.is_some();
        if !target_topic && target_frame.is_none() {
            return Err(Error::InvalidParameter {
                name: "target_frame",
                message: "the target's frame is needed when its pose is in /tf (or name the topic of its pose)".into(),
            });
        }
        let max_gap = if options.max_gap > 0.0 {
            options.max_gap
        } else {
            DEFAULT_MAX_GAP
        };
        let ns = |name: &'static str, value: f64, most: f64| {
            if !(value.is_finite() && value.abs() <= most) {
                return Err(Error::InvalidParameter {
                    name,
                    message: format!(
                        "{value:e} s is not a usable time (finite, at most {most:e} s in size)"
                    ),
                });
            }
            Ok((value * NS as f64).round() as i64)
        };
        Ok(Self {
            base: frame("base_frame", &options.base_frame)?,
            gripper: frame("gripper_frame", &options.gripper_frame)?,
            camera: frame("camera_frame", &options.camera_frame)?,
            target_frame,
            target_topic,
            offset_ns: ns("time_offset", options.time_offset, MAX_TIME_OFFSET)?,
            max_gap_ns: ns("max_gap", max_gap, 1e6)?,
            setup: options.setup,
            tf: TfBuffer::default(),
            unsorted: false,
            robot_path: None,
            waiting: VecDeque::new(),
            observations: 0,
            overflow: Vec::new(),
        })
    }

    /// Takes one transform of `/tf` (`is_static` false) or `/tf_static`. Without a target
    /// topic, a `/tf` transform whose child is the target frame is also an observation.
    ///
    /// Errors (the message is dropped, nothing else changes): a quaternion not of unit norm or a
    /// number not finite, an empty frame name, a frame given a second parent, a transform in
    /// both topics.
    pub fn transform(&mut self, t: LiveTransform<'_>, is_static: bool) -> Result<(), String> {
        let parent = frame_name(t.parent);
        let child = frame_name(t.child);
        let parent_from_child = transform_from_xyz_quat_xyzw(t.translation, t.quaternion_xyzw)
            .map_err(|p| format!("transform `{parent}` → `{child}`: {p}"))?;
        let new_edge = self.tf.parent_of(&child).is_none();
        self.tf
            .add(&parent, &child, t.stamp_ns, parent_from_child, is_static)?;
        if new_edge {
            self.robot_path = None;
        }
        self.unsorted |= !is_static;
        if !self.target_topic && !is_static && self.target_frame.as_deref() == Some(&child) {
            self.push(t.stamp_ns, None);
        }
        Ok(())
    }

    /// Takes one observation of the target: its pose in `frame_id` (`frame_from_target`) at
    /// `stamp_ns`; `child` is a `TransformStamped`'s `child_frame_id`, which must be the target
    /// frame when one is given.
    ///
    /// Errors (the message is dropped): a pose not valid as [`LivePairs::transform`] says, a
    /// child frame that is not the target frame, an empty frame.
    pub fn observation(
        &mut self,
        frame_id: &str,
        child: Option<&str>,
        stamp_ns: i64,
        translation: [f64; 3],
        quaternion_xyzw: [f64; 4],
    ) -> Result<(), String> {
        let frame = frame_name(frame_id);
        if frame.is_empty() {
            return Err("header.frame_id is empty: the target's pose must name its frame".into());
        }
        if let (Some(child), Some(target)) = (child, &self.target_frame)
            && frame_name(child) != *target
        {
            return Err(format!(
                "child_frame_id is `{child}`, not the target frame `{target}`"
            ));
        }
        let frame_from_target = transform_from_xyz_quat_xyzw(translation, quaternion_xyzw)
            .map_err(|p| format!("the target's pose: {p}"))?;
        self.push(stamp_ns, Some((frame, frame_from_target)));
        Ok(())
    }

    fn push(&mut self, stamp_ns: i64, given: Option<(String, Transform)>) {
        self.observations += 1;
        self.waiting.push_back(Observation {
            number: self.observations,
            stamp_ns,
            given,
        });
        if self.waiting.len() > MAX_WAITING
            && let Some(o) = self.waiting.pop_front()
        {
            self.overflow.push(LiveOutcome::Dropped {
                number: o.number,
                stamp: seconds(o.stamp_ns),
                why: format!(
                    "more than {MAX_WAITING} observations waited for the robot's transforms (do they still arrive?)"
                ),
            });
        }
    }

    /// Observations taken so far.
    pub fn observations(&self) -> usize {
        self.observations
    }

    /// Observations still waiting for the robot's transforms.
    pub fn waiting(&self) -> usize {
        self.waiting.len()
    }

    /// Where tf places the camera frame (see
    /// [`BagPairs::camera_mount`](super::BagPairs::camera_mount)): X is published for the root
    /// of the camera's subtree.
    pub fn camera_mount(&self) -> Option<CameraMount> {
        camera_mount(
            &self.tf,
            &self.camera,
            [&self.base, &self.gripper],
            self.setup,
        )
    }

    /// The observations whose pairing is now decided, in the order taken: each a pose pair or
    /// dropped with the reason. With `end` (no more messages will come), every waiting
    /// observation is decided.
    pub fn ready(&mut self) -> Vec<LiveOutcome> {
        self.decide(false)
    }

    /// Every waiting observation decided: the end of the stream.
    pub fn finish(&mut self) -> Vec<LiveOutcome> {
        self.decide(true)
    }

    fn decide(&mut self, end: bool) -> Vec<LiveOutcome> {
        let mut out = std::mem::take(&mut self.overflow);
        // Nothing waits and nothing came: nothing to decide or to prune.
        if self.waiting.is_empty() && !self.unsorted {
            return out;
        }
        if self.unsorted {
            self.tf.finish();
            self.unsorted = false;
        }
        if self.robot_path.is_none() {
            let whole = |message: String| Error::InvalidParameter {
                name: "base_frame",
                message,
            };
            match super::pairs::robot_path(&self.tf, &self.base, &self.gripper, &whole) {
                Ok(p) => self.robot_path = Some(p),
                Err(e) => {
                    if end {
                        let why = format!("{e}");
                        out.extend(self.waiting.drain(..).map(|o| LiveOutcome::Dropped {
                            number: o.number,
                            stamp: seconds(o.stamp_ns),
                            why: why.clone(),
                        }));
                    }
                    return out;
                }
            }
        }
        let Some(robot_path) = self.robot_path.clone() else {
            return out;
        };
        let robot_edges = self.tf.dynamic_on(&robot_path);
        // The newest stamp every dynamic transform of the robot has reached.
        let reached = robot_edges
            .iter()
            .map(|e| self.tf.newest(e).unwrap_or(i64::MIN))
            .min()
            .unwrap_or(i64::MIN);
        while let Some(o) = self.waiting.front() {
            let robot_t = o.stamp_ns.saturating_sub(self.offset_ns);
            if robot_t > reached && !end {
                break;
            }
            let Some(o) = self.waiting.pop_front() else {
                break;
            };
            out.push(self.pair(o, robot_t, &robot_path));
        }
        // Keep the last seconds before the oldest stamp still needed.
        let needed = self
            .waiting
            .front()
            .map_or(reached, |o| o.stamp_ns.saturating_sub(self.offset_ns))
            .min(reached);
        self.tf.prune(needed.saturating_sub(KEEP_NS));
        out
    }

    fn pair(&self, o: Observation, robot_t: i64, robot_path: &TfPath) -> LiveOutcome {
        let dropped = |why: String| LiveOutcome::Dropped {
            number: o.number,
            stamp: seconds(o.stamp_ns),
            why,
        };
        let camera_from_target = match &o.given {
            Some((frame, frame_from_target)) if *frame == self.camera => {
                Lookup::Pose(*frame_from_target)
            }
            given => {
                let (to, frame_from_target) = match given {
                    Some((frame, t)) => (frame.as_str(), *t),
                    None => (
                        self.target_frame.as_deref().unwrap_or_default(),
                        Transform::identity(),
                    ),
                };
                match self.tf.path(&self.camera, to) {
                    Ok(p) => match self.tf.lookup(&p, o.stamp_ns, self.max_gap_ns) {
                        Lookup::Pose(camera_from_frame) => {
                            Lookup::Pose(camera_from_frame * frame_from_target)
                        }
                        other => other,
                    },
                    Err(e) => {
                        return dropped(format!(
                            "the target's pose is given in `{to}`, not in the camera frame `{}`, and tf cannot relate them: {e}",
                            self.camera
                        ));
                    }
                }
            }
        };
        let robot = self.tf.lookup(robot_path, robot_t, self.max_gap_ns);
        match (robot, camera_from_target) {
            (Lookup::Pose(base_from_gripper), Lookup::Pose(camera_from_target)) => {
                LiveOutcome::Pair(Box::new(StampedPosePair::new(
                    o.number,
                    Some(seconds(o.stamp_ns)),
                    PosePair {
                        base_from_gripper,
                        camera_from_target,
                    },
                    Written::NAMED,
                )))
            }
            (Lookup::Gap, _) | (_, Lookup::Gap) => dropped(format!(
                "a transform it needs has a gap longer than {} s at its stamp",
                seconds(self.max_gap_ns)
            )),
            _ => dropped(
                "its stamp is outside the transforms it needs (before the oldest kept, or after the newest)".into(),
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: i64 = 1_000_000;

    fn options(target_topic: bool) -> BagOptions {
        BagOptions {
            base_frame: "base_link".into(),
            gripper_frame: "tool0".into(),
            camera_frame: "camera_optical".into(),
            target_frame: Some("board".into()),
            target_topic: target_topic.then(|| "/board_pose".into()),
            ..BagOptions::default()
        }
    }

    fn robot(stamp_ns: i64, x: f64) -> LiveTransform<'static> {
        LiveTransform {
            parent: "base_link",
            child: "tool0",
            stamp_ns,
            translation: [x, 0.0, 0.5],
            quaternion_xyzw: [0.0, 0.0, (0.1f64).sin(), (0.1f64).cos()],
        }
    }

    const IDENTITY: [f64; 4] = [0.0, 0.0, 0.0, 1.0];

    #[test]
    fn an_observation_waits_for_the_robot_then_pairs_at_its_stamp() {
        let mut live = LivePairs::new(&options(true)).unwrap();
        live.observation("camera_optical", None, 150 * MS, [0.0, 0.0, 0.4], IDENTITY)
            .unwrap();
        // No robot yet: it waits.
        assert!(live.ready().is_empty());
        live.transform(robot(100 * MS, 0.1), false).unwrap();
        assert!(live.ready().is_empty());
        assert_eq!(live.waiting(), 1);
        // Out of order: the later sample first.
        live.transform(robot(200 * MS, 0.3), false).unwrap();
        let ready = live.ready();
        assert_eq!(ready.len(), 1);
        let LiveOutcome::Pair(pair) = &ready[0] else {
            panic!("{ready:?}")
        };
        assert!((pair.pose.base_from_gripper.translation.vector.x - 0.2).abs() < 1e-12);
        assert!((pair.pose.camera_from_target.translation.vector.z - 0.4).abs() < 1e-12);
        assert_eq!(pair.line, 1);
        assert_eq!(live.waiting(), 0);
    }

    #[test]
    fn a_bad_message_is_refused_and_the_buffer_carries_on() {
        let mut live = LivePairs::new(&options(true)).unwrap();
        let mut nan = robot(0, 0.0);
        nan.quaternion_xyzw = [f64::NAN, 0.0, 0.0, 1.0];
        let why = live.transform(nan, false).unwrap_err();
        assert!(why.contains("finite"), "{why}");
        let mut long = robot(0, 0.0);
        long.quaternion_xyzw = [0.0, 0.0, 0.0, 2.0];
        let why = live.transform(long, false).unwrap_err();
        assert!(why.contains("norm"), "{why}");
        let why = live
            .observation("camera_optical", None, 0, [0.0; 3], [0.0, 0.0, 0.0, 0.5])
            .unwrap_err();
        assert!(why.contains("norm"), "{why}");
        let why = live
            .observation("camera_optical", Some("marker"), 0, [0.0; 3], IDENTITY)
            .unwrap_err();
        assert!(why.contains("`marker`"), "{why}");
        live.transform(robot(0, 0.0), false).unwrap();
        let mut second = robot(0, 0.0);
        second.parent = "world";
        let why = live.transform(second, false).unwrap_err();
        assert!(why.contains("two parents"), "{why}");
        // The good ones still pair.
        live.transform(robot(100 * MS, 0.1), false).unwrap();
        live.observation("camera_optical", None, 50 * MS, [0.0; 3], IDENTITY)
            .unwrap();
        assert!(matches!(live.ready()[..], [LiveOutcome::Pair(_)]));
    }

    #[test]
    fn an_unknown_frame_or_a_stamp_before_the_robot_is_dropped_with_why() {
        let mut live = LivePairs::new(&options(true)).unwrap();
        live.transform(robot(100 * MS, 0.1), false).unwrap();
        live.transform(robot(200 * MS, 0.2), false).unwrap();
        live.observation("nowhere", None, 150 * MS, [0.0; 3], IDENTITY)
            .unwrap();
        live.observation("camera_optical", None, 50 * MS, [0.0; 3], IDENTITY)
            .unwrap();
        let ready = live.ready();
        assert_eq!(ready.len(), 2, "{ready:?}");
        let LiveOutcome::Dropped { why, number, .. } = &ready[0] else {
            panic!("{ready:?}")
        };
        assert_eq!(*number, 1);
        assert!(why.contains("`nowhere`"), "{why}");
        let LiveOutcome::Dropped { why, .. } = &ready[1] else {
            panic!("{ready:?}")
        };
        assert!(why.contains("outside"), "{why}");
        // A gap longer than max_gap (0.1 s).
        live.transform(robot(500 * MS, 0.5), false).unwrap();
        live.observation("camera_optical", None, 300 * MS, [0.0; 3], IDENTITY)
            .unwrap();
        let ready = live.ready();
        let LiveOutcome::Dropped { why, .. } = &ready[0] else {
            panic!("{ready:?}")
        };
        assert!(why.contains("gap"), "{why}");
    }

    #[test]
    fn a_target_in_tf_is_observed_at_each_of_its_transforms_and_the_mount_is_the_bags() {
        let mut live = LivePairs::new(&options(false)).unwrap();
        // The optical frame under camera_link (static): X is published for camera_link.
        live.transform(
            LiveTransform {
                parent: "camera_link",
                child: "camera_optical",
                stamp_ns: 0,
                translation: [0.0; 3],
                quaternion_xyzw: [-0.5, 0.5, -0.5, 0.5],
            },
            true,
        )
        .unwrap();
        for k in 0..3 {
            live.transform(robot(k * 100 * MS, 0.1 * k as f64), false)
                .unwrap();
        }
        live.transform(
            LiveTransform {
                parent: "camera_optical",
                child: "board",
                stamp_ns: 100 * MS,
                translation: [0.0, 0.0, 0.4],
                quaternion_xyzw: IDENTITY,
            },
            false,
        )
        .unwrap();
        let ready = live.ready();
        let LiveOutcome::Pair(pair) = &ready[0] else {
            panic!("{ready:?}")
        };
        assert!((pair.pose.base_from_gripper.translation.vector.x - 0.1).abs() < 1e-12);
        assert!((pair.pose.camera_from_target.translation.vector.z - 0.4).abs() < 1e-12);
        let mount = live.camera_mount().expect("a mount");
        assert_eq!(mount.root(), "camera_link");
        assert!(mount.placed_under.is_none());
    }

    #[test]
    fn the_buffer_keeps_ten_seconds() {
        let mut live = LivePairs::new(&options(true)).unwrap();
        for k in 0..2000 {
            live.transform(robot(k * 10 * MS, 0.0), false).unwrap();
            if k % 100 == 0 {
                live.observation("camera_optical", None, k * 10 * MS, [0.0; 3], IDENTITY)
                    .unwrap();
                assert!(matches!(live.ready()[..], [LiveOutcome::Pair(_)]));
            }
        }
        // 20 s of samples at 100 Hz; about the last 10 s kept.
        let kept = live.tf.stamps_of("tool0").len();
        assert!((1000..=1101).contains(&kept), "{kept}");
    }
}
