//! A writer of ROS 2 recordings (MCAP, the `mcap` crate's writer, CDR little-endian) for tests
//! that need recordings no recorder would write on purpose: hostile frame names, broken tf
//! chains, loops, repeated stamps, compression bombs. Shared by the library's and the command
//! line's tests (the latter include this file by path).

#![allow(dead_code)] // Each test file uses its own part.

use std::borrow::Cow;
use std::collections::HashMap;
use std::io::BufWriter;
use std::path::Path;
use std::sync::Arc;

use nalgebra::{IsometryMatrix3, UnitQuaternion, Vector3};

/// A pose as the messages carry it.
pub type Pose = IsometryMatrix3<f64>;

/// `tf2_msgs/msg/TFMessage`.
pub const TF_MESSAGE: &str = "tf2_msgs/msg/TFMessage";
/// `geometry_msgs/msg/PoseStamped`.
pub const POSE_STAMPED: &str = "geometry_msgs/msg/PoseStamped";
/// `geometry_msgs/msg/TransformStamped`.
pub const TRANSFORM_STAMPED: &str = "geometry_msgs/msg/TransformStamped";

/// Stamps near 2023-11-14, as a real recording has, nanoseconds.
pub const T0_NS: i64 = 1_700_000_000_000_000_000;

/// One transform of a `TFMessage`: `parent_from_child` at `stamp_ns`.
#[derive(Debug, Clone)]
pub struct Tf {
    pub parent: String,
    pub child: String,
    pub stamp_ns: i64,
    pub pose: Pose,
}

/// `Tf` from its parts.
pub fn tf(parent: &str, child: &str, stamp_ns: i64, pose: Pose) -> Tf {
    Tf {
        parent: parent.into(),
        child: child.into(),
        stamp_ns,
        pose,
    }
}

/// A CDR (XCDR1) little-endian message under construction.
struct Cdr(Vec<u8>);

impl Cdr {
    fn new() -> Self {
        Self(vec![0, 1, 0, 0])
    }

    fn align(&mut self, to: usize) {
        while !(self.0.len() - 4).is_multiple_of(to) {
            self.0.push(0);
        }
    }

    fn u32(&mut self, v: u32) {
        self.align(4);
        self.0.extend(v.to_le_bytes());
    }

    fn f64(&mut self, v: f64) {
        self.align(8);
        self.0.extend(v.to_le_bytes());
    }

    fn string(&mut self, s: &str) {
        self.u32(s.len() as u32 + 1);
        self.0.extend(s.as_bytes());
        self.0.push(0);
    }

    fn header(&mut self, stamp_ns: i64, frame: &str) {
        self.u32(stamp_ns.div_euclid(1_000_000_000) as i32 as u32);
        self.u32(stamp_ns.rem_euclid(1_000_000_000) as u32);
        self.string(frame);
    }

    fn pose(&mut self, p: &Pose) {
        let q = UnitQuaternion::from_rotation_matrix(&p.rotation);
        let t = p.translation.vector;
        for v in [t.x, t.y, t.z, q.i, q.j, q.k, q.w] {
            self.f64(v);
        }
    }

    fn transform_stamped(&mut self, t: &Tf) {
        self.header(t.stamp_ns, &t.parent);
        self.string(&t.child);
        self.pose(&t.pose);
    }
}

/// A serialised `TFMessage`.
pub fn tf_message(transforms: &[Tf]) -> Vec<u8> {
    let mut c = Cdr::new();
    c.u32(transforms.len() as u32);
    for t in transforms {
        c.transform_stamped(t);
    }
    c.0
}

/// A serialised `PoseStamped`: the pose of something in `frame`.
pub fn pose_stamped(frame: &str, stamp_ns: i64, pose: &Pose) -> Vec<u8> {
    let mut c = Cdr::new();
    c.header(stamp_ns, frame);
    c.pose(pose);
    c.0
}

/// A serialised `TransformStamped`.
pub fn transform_stamped(t: &Tf) -> Vec<u8> {
    let mut c = Cdr::new();
    c.transform_stamped(t);
    c.0
}

/// An MCAP recording being written.
pub struct BagWriter {
    writer: mcap::Writer<BufWriter<std::fs::File>>,
    channels: HashMap<(String, String), Arc<mcap::Channel<'static>>>,
    sequence: u32,
    /// Whether messages are numbered (a bomb repeats one message, its number too).
    numbered: bool,
}

impl BagWriter {
    /// A new file at `path`, in zstd chunks of `chunk_size` bytes (the writer's default when
    /// `None`) or uncompressed.
    pub fn create(path: &Path, zstd: bool, chunk_size: Option<u64>) -> Self {
        let mut options = mcap::WriteOptions::new()
            .compression(zstd.then_some(mcap::Compression::Zstd))
            .profile("ros2");
        if chunk_size.is_some() {
            options = options.chunk_size(chunk_size);
        }
        Self::with_options(path, options)
    }

    /// A compression bomb's file: zstd chunks of 64 MB, without the message indexes (16 bytes a
    /// message) that would give its size away, and every message numbered 0.
    pub fn bomb(path: &Path) -> Self {
        let options = mcap::WriteOptions::new()
            .compression(Some(mcap::Compression::Zstd))
            .chunk_size(Some(64 << 20))
            .emit_message_indexes(false)
            .profile("ros2");
        Self {
            numbered: false,
            ..Self::with_options(path, options)
        }
    }

    /// A new file at `path` written with `options`.
    pub fn with_options(path: &Path, options: mcap::WriteOptions) -> Self {
        let file = BufWriter::new(std::fs::File::create(path).unwrap());
        Self {
            writer: options.create(file).unwrap(),
            channels: HashMap::new(),
            sequence: 0,
            numbered: true,
        }
    }

    /// Writes serialised `data` on `topic` of type `msg_type`, logged at `log_ns`. A topic
    /// written with two types gets two channels.
    pub fn write(&mut self, topic: &str, msg_type: &str, log_ns: i64, data: Vec<u8>) {
        let next_id = self.channels.len() as u16;
        let channel = self
            .channels
            .entry((topic.to_string(), msg_type.to_string()))
            .or_insert_with(|| {
                Arc::new(mcap::Channel {
                    id: next_id,
                    topic: topic.to_string(),
                    schema: Some(Arc::new(mcap::Schema {
                        id: next_id + 1,
                        name: msg_type.to_string(),
                        encoding: "ros2msg".into(),
                        data: Cow::Borrowed(b""),
                    })),
                    message_encoding: "cdr".into(),
                    metadata: Default::default(),
                })
            })
            .clone();
        self.sequence += u32::from(self.numbered);
        self.writer
            .write(&mcap::Message {
                channel,
                sequence: self.sequence,
                log_time: log_ns as u64,
                publish_time: log_ns as u64,
                data: Cow::Owned(data),
            })
            .unwrap();
    }

    /// A `TFMessage` on `/tf`, logged at the first transform's stamp.
    pub fn tf(&mut self, transforms: &[Tf]) {
        let log = transforms.first().map_or(T0_NS, |t| t.stamp_ns);
        self.write("/tf", TF_MESSAGE, log, tf_message(transforms));
    }

    /// A `TFMessage` on `/tf_static`.
    pub fn tf_static(&mut self, transforms: &[Tf]) {
        self.write("/tf_static", TF_MESSAGE, T0_NS, tf_message(transforms));
    }

    /// Closes the file.
    pub fn finish(mut self) {
        self.writer.finish().unwrap();
    }
}

/// The pose of the robot's flange in its base at sample `k`: a smooth motion turning tens of
/// degrees about changing axes.
pub fn robot_pose(k: usize) -> Pose {
    let s = k as f64 * 0.01;
    Pose::new(
        Vector3::new(0.4 + 0.1 * (0.7 * s).sin(), 0.1 * (1.1 * s).cos(), 0.5),
        Vector3::new(0.6 * (0.9 * s).sin(), 0.5 * (1.3 * s).cos(), 0.4 * s.sin()),
    )
}

/// The true X of [`eye_in_hand`]: `tool0_from_camera`.
pub fn true_x() -> Pose {
    Pose::new(
        Vector3::new(0.03, -0.05, 0.08),
        Vector3::new(0.1, -0.2, 1.4),
    )
}

/// The board's fixed pose in the base of [`eye_in_hand`].
pub fn base_from_board() -> Pose {
    Pose::new(Vector3::new(0.6, 0.0, -0.1), Vector3::new(3.0, 0.1, 0.0))
}

/// An eye-in-hand recording's messages: `/tf` `base_link → tool0` at 100 Hz for `seconds`, and
/// every 10th of its stamps the target's pose `camera → board` (exact: the robot is not
/// interpolated), as `(stamp, camera_from_board)`.
pub fn eye_in_hand(seconds: usize) -> (Vec<Tf>, Vec<(i64, Pose)>) {
    let n = seconds * 100;
    let robot: Vec<Tf> = (0..=n)
        .map(|k| {
            tf(
                "base_link",
                "tool0",
                T0_NS + k as i64 * 10_000_000,
                robot_pose(k),
            )
        })
        .collect();
    let target = robot
        .iter()
        .step_by(10)
        .skip(1)
        .map(|r| {
            let camera_from_board = (r.pose * true_x()).inverse() * base_from_board();
            (r.stamp_ns, camera_from_board)
        })
        .collect();
    (robot, target)
}

/// Writes the robot's samples of [`eye_in_hand`], one `TFMessage` each.
pub fn write_robot(bag: &mut BagWriter, robot: &[Tf]) {
    for r in robot {
        bag.tf(std::slice::from_ref(r));
    }
}
