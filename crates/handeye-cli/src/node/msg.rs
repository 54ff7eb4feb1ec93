//! The ROS 2 messages the node reads and writes, with the field layouts of their `.msg` files:
//! serialised as plain CDR (XCDR1, little-endian) by the DDS layer, as rmw_cyclonedds and
//! rmw_fastrtps send them. DDS type names are `package::msg::dds_::Name_`.

use serde::{Deserialize, Serialize};

/// `builtin_interfaces/msg/Time`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Time {
    /// Seconds.
    pub sec: i32,
    /// Nanoseconds, below 10⁹.
    pub nanosec: u32,
}

impl Time {
    /// The stamp in nanoseconds; a `nanosec` of 10⁹ or more is refused.
    pub fn ns(&self) -> Result<i64, String> {
        if self.nanosec >= 1_000_000_000 {
            return Err(format!(
                "header.stamp.nanosec is {} (at most 999999999)",
                self.nanosec
            ));
        }
        Ok(i64::from(self.sec) * 1_000_000_000 + i64::from(self.nanosec))
    }
}

/// `std_msgs/msg/Header`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Header {
    /// The stamp.
    pub stamp: Time,
    /// The frame.
    pub frame_id: String,
}

/// `geometry_msgs/msg/Vector3` (and `Point`, the same layout).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Vector3 {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
}

/// `geometry_msgs/msg/Quaternion`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Quaternion {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
    /// w.
    pub w: f64,
}

impl Quaternion {
    /// `[x, y, z, w]`.
    pub fn xyzw(&self) -> [f64; 4] {
        [self.x, self.y, self.z, self.w]
    }
}

/// `geometry_msgs/msg/Transform`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Transform {
    /// The translation.
    pub translation: Vector3,
    /// The rotation.
    pub rotation: Quaternion,
}

/// `geometry_msgs/msg/TransformStamped`: `header.frame_id`_from_`child_frame_id`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TransformStamped {
    /// The parent frame and the stamp.
    pub header: Header,
    /// The child frame.
    pub child_frame_id: String,
    /// `parent_from_child`.
    pub transform: Transform,
}

impl ros2_client::Message for TransformStamped {}

/// `tf2_msgs/msg/TFMessage`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TfMessage {
    /// The transforms.
    pub transforms: Vec<TransformStamped>,
}

impl ros2_client::Message for TfMessage {}

/// `geometry_msgs/msg/Pose`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    /// The position.
    pub position: Vector3,
    /// The orientation.
    pub orientation: Quaternion,
}

/// `geometry_msgs/msg/PoseStamped`: the pose of the target in `header.frame_id`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PoseStamped {
    /// The frame and the stamp.
    pub header: Header,
    /// The pose.
    pub pose: Pose,
}

impl ros2_client::Message for PoseStamped {}

/// `std_msgs/msg/String`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StringMsg {
    /// The text.
    pub data: String,
}

impl ros2_client::Message for StringMsg {}

/// A transform as a message carries it, from `parent_from_child`.
pub fn transform(t: &handeye::Transform) -> Transform {
    let v = t.translation.vector;
    let [x, y, z, w] = handeye::TransformJson::from(t).quaternion_xyzw;
    Transform {
        translation: Vector3 {
            x: v.x,
            y: v.y,
            z: v.z,
        },
        rotation: Quaternion { x, y, z, w },
    }
}
