//! The ROS 2 messages a calibration needs, decoded from CDR: `tf2_msgs/msg/TFMessage`,
//! `geometry_msgs/msg/TransformStamped` and `geometry_msgs/msg/PoseStamped`, and the joint angles
//! of `sensor_msgs/msg/JointState`.

use super::cdr::{CdrError, CdrReader};

/// `tf2_msgs/msg/TFMessage`.
pub(crate) const TF_MESSAGE: &str = "tf2_msgs/msg/TFMessage";
/// `geometry_msgs/msg/TransformStamped`.
pub(crate) const TRANSFORM_STAMPED: &str = "geometry_msgs/msg/TransformStamped";
/// `geometry_msgs/msg/PoseStamped`.
pub(crate) const POSE_STAMPED: &str = "geometry_msgs/msg/PoseStamped";

/// `apriltag_msgs/msg/AprilTagDetectionArray` (apriltag_ros, ROS 2): the corners of the tags
/// seen in one image.
pub(crate) const APRILTAG_DETECTIONS: &str = "apriltag_msgs/msg/AprilTagDetectionArray";
/// `sensor_msgs/msg/CameraInfo`: the camera's intrinsics.
pub(crate) const CAMERA_INFO: &str = "sensor_msgs/msg/CameraInfo";

/// `sensor_msgs/msg/JointState`.
pub(crate) const JOINT_STATE: &str = "sensor_msgs/msg/JointState";

/// Nanoseconds in a second.
pub(crate) const NS: i64 = 1_000_000_000;

/// `std_msgs/msg/Header`: the stamp in nanoseconds and the frame.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Header {
    /// `stamp.sec · 10⁹ + stamp.nanosec`.
    pub stamp_ns: i64,
    /// `frame_id`, a leading `/` dropped.
    pub frame_id: String,
}

/// A pose as a message gives it: translation (or position) and quaternion `x y z w`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct RawPose {
    pub translation: [f64; 3],
    pub quaternion_xyzw: [f64; 4],
}

/// `geometry_msgs/msg/TransformStamped`: `header.frame_id`_from_`child_frame_id`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct TransformStamped {
    pub header: Header,
    pub child_frame_id: String,
    pub transform: RawPose,
}

/// `geometry_msgs/msg/PoseStamped`: the pose of something in `header.frame_id`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct PoseStamped {
    pub header: Header,
    pub pose: RawPose,
}

/// Smallest serialised TransformStamped: stamp 8, two string lengths 8, seven float64 56.
const MIN_TRANSFORM_STAMPED: usize = 72;

/// A frame name as tf2 keys it: without a leading `/`.
pub(crate) fn frame_name(name: &str) -> String {
    name.strip_prefix('/').unwrap_or(name).to_string()
}

fn header(r: &mut CdrReader<'_>, field: &str) -> Result<Header, CdrError> {
    let sec = r.i32(&format!("{field}.stamp.sec"))?;
    let nanosec = r.u32(&format!("{field}.stamp.nanosec"))?;
    if i64::from(nanosec) >= NS {
        return Err(CdrError {
            offset: 0,
            message: format!("`{field}.stamp.nanosec` is {nanosec}, not below 10^9"),
        });
    }
    let frame_id = frame_name(&r.string(&format!("{field}.frame_id"))?);
    Ok(Header {
        stamp_ns: i64::from(sec) * NS + i64::from(nanosec),
        frame_id,
    })
}

fn raw_pose(r: &mut CdrReader<'_>, field: &str, names: [&str; 2]) -> Result<RawPose, CdrError> {
    let mut translation = [0.0; 3];
    for (v, c) in translation.iter_mut().zip(["x", "y", "z"]) {
        *v = r.f64(&format!("{field}.{}.{c}", names[0]))?;
    }
    let mut quaternion_xyzw = [0.0; 4];
    for (v, c) in quaternion_xyzw.iter_mut().zip(["x", "y", "z", "w"]) {
        *v = r.f64(&format!("{field}.{}.{c}", names[1]))?;
    }
    Ok(RawPose {
        translation,
        quaternion_xyzw,
    })
}

fn transform_stamped(r: &mut CdrReader<'_>, field: &str) -> Result<TransformStamped, CdrError> {
    let header = header(r, &format!("{field}header"))?;
    let child_frame_id = frame_name(&r.string(&format!("{field}child_frame_id"))?);
    let transform = raw_pose(r, &format!("{field}transform"), ["translation", "rotation"])?;
    Ok(TransformStamped {
        header,
        child_frame_id,
        transform,
    })
}

/// Decodes a `tf2_msgs/msg/TFMessage`.
pub(crate) fn decode_tf_message(bytes: &[u8]) -> Result<Vec<TransformStamped>, CdrError> {
    let mut r = CdrReader::new(bytes)?;
    let n = r.sequence_len("transforms", MIN_TRANSFORM_STAMPED)?;
    (0..n)
        .map(|k| transform_stamped(&mut r, &format!("transforms[{k}].")))
        .collect()
}

/// Decodes a `geometry_msgs/msg/TransformStamped`.
pub(crate) fn decode_transform_stamped(bytes: &[u8]) -> Result<TransformStamped, CdrError> {
    transform_stamped(&mut CdrReader::new(bytes)?, "")
}

/// Decodes a `geometry_msgs/msg/PoseStamped`.
pub(crate) fn decode_pose_stamped(bytes: &[u8]) -> Result<PoseStamped, CdrError> {
    let mut r = CdrReader::new(bytes)?;
    let header = header(&mut r, "header")?;
    let pose = raw_pose(&mut r, "pose", ["position", "orientation"])?;
    Ok(PoseStamped { header, pose })
}

/// `sensor_msgs/msg/JointState`: the joints' names and positions (velocity and effort are not
/// read).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct JointState {
    pub header: Header,
    pub name: Vec<String>,
    pub position: Vec<f64>,
}

/// Decodes a `sensor_msgs/msg/JointState` (header, `name`, `position`; the rest is left unread).
pub(crate) fn decode_joint_state(bytes: &[u8]) -> Result<JointState, CdrError> {
    let mut r = CdrReader::new(bytes)?;
    let header = header(&mut r, "header")?;
    // A string takes at least its length and its NUL: 5 bytes.
    let n = r.sequence_len("name", 5)?;
    let name = (0..n)
        .map(|k| r.string(&format!("name[{k}]")))
        .collect::<Result<Vec<_>, _>>()?;
    let m = r.sequence_len("position", 8)?;
    let position = (0..m)
        .map(|k| r.f64(&format!("position[{k}]")))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(JointState {
        header,
        name,
        position,
    })
}

/// One tag of an `apriltag_msgs/msg/AprilTagDetection`: its family, id and the pixels of its four
/// corners in the detector's order (AprilTag's: counter-clockwise in the image, see
/// [`super::tags`]). `hamming`, `goodness`, `decision_margin`, `centre` and `homography` are
/// read past.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct TagDetection {
    pub family: String,
    pub id: i32,
    pub corners: [[f64; 2]; 4],
}

/// `apriltag_msgs/msg/AprilTagDetectionArray`: the header of the image and its tags.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct TagDetections {
    pub header: Header,
    pub detections: Vec<TagDetection>,
}

/// Smallest serialised AprilTagDetection: family (4 + 1), id, hamming, goodness, margin (16),
/// centre (16), corners (64), homography (72).
const MIN_TAG_DETECTION: usize = 173;

/// Bytes a message may hold past its last field (CDR pads to at most 8).
const MAX_TRAILING: usize = 7;

/// Refuses a message with bytes left past its last field: another definition of the type (a
/// corner array of another length, the ROS 1 message) read as this one.
fn whole(r: &CdrReader<'_>, what: &str) -> Result<(), CdrError> {
    if r.remaining() > MAX_TRAILING {
        return Err(CdrError {
            offset: 0,
            message: format!(
                "{} byte(s) left past the last field: not a `{what}` as defined (another version of the message?)",
                r.remaining()
            ),
        });
    }
    Ok(())
}

/// Decodes an `apriltag_msgs/msg/AprilTagDetectionArray` (apriltag_msgs 2.x: `Point centre`,
/// `Point[4] corners`, `float64[9] homography`).
pub(crate) fn decode_tag_detections(bytes: &[u8]) -> Result<TagDetections, CdrError> {
    let mut r = CdrReader::new(bytes)?;
    let header = header(&mut r, "header")?;
    let n = r.sequence_len("detections", MIN_TAG_DETECTION)?;
    let mut detections = Vec::with_capacity(n);
    for k in 0..n {
        let f = |name: &str| format!("detections[{k}].{name}");
        let family = r.string(&f("family"))?;
        let id = r.i32(&f("id"))?;
        r.i32(&f("hamming"))?;
        r.f32(&f("goodness"))?;
        r.f32(&f("decision_margin"))?;
        r.f64(&f("centre.x"))?;
        r.f64(&f("centre.y"))?;
        let mut corners = [[0.0; 2]; 4];
        for (j, c) in corners.iter_mut().enumerate() {
            c[0] = r.f64(&f(&format!("corners[{j}].x")))?;
            c[1] = r.f64(&f(&format!("corners[{j}].y")))?;
        }
        for j in 0..9 {
            r.f64(&f(&format!("homography[{j}]")))?;
        }
        detections.push(TagDetection {
            family,
            id,
            corners,
        });
    }
    whole(&r, APRILTAG_DETECTIONS)?;
    Ok(TagDetections { header, detections })
}

/// `sensor_msgs/msg/CameraInfo`: what the intrinsics are made of (`r`, `p`, binning and the
/// region of interest are not read).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct CameraInfo {
    pub header: Header,
    pub height: u32,
    pub width: u32,
    pub distortion_model: String,
    pub d: Vec<f64>,
    pub k: [f64; 9],
}

/// Decodes a `sensor_msgs/msg/CameraInfo` up to `k`.
pub(crate) fn decode_camera_info(bytes: &[u8]) -> Result<CameraInfo, CdrError> {
    let mut r = CdrReader::new(bytes)?;
    let header = header(&mut r, "header")?;
    let height = r.u32("height")?;
    let width = r.u32("width")?;
    let distortion_model = r.string("distortion_model")?;
    let n = r.sequence_len("d", 8)?;
    let d = (0..n)
        .map(|j| r.f64(&format!("d[{j}]")))
        .collect::<Result<Vec<_>, _>>()?;
    let mut k = [0.0; 9];
    for (j, v) in k.iter_mut().enumerate() {
        *v = r.f64(&format!("k[{j}]"))?;
    }
    Ok(CameraInfo {
        header,
        height,
        width,
        distortion_model,
        d,
        k,
    })
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Serialises a TransformStamped (little- or big-endian) as rclcpp does, for tests.
    pub(crate) fn encode_transform(
        out: &mut Vec<u8>,
        little: bool,
        t: &TransformStamped,
        sec: i32,
        nanosec: u32,
    ) {
        let pad = |out: &mut Vec<u8>, a: usize| {
            while !(out.len() - 4).is_multiple_of(a) {
                out.push(0);
            }
        };
        let u32b = |v: u32| {
            if little {
                v.to_le_bytes()
            } else {
                v.to_be_bytes()
            }
        };
        pad(out, 4);
        out.extend(if little {
            sec.to_le_bytes()
        } else {
            sec.to_be_bytes()
        });
        out.extend(u32b(nanosec));
        for s in [&t.header.frame_id, &t.child_frame_id] {
            pad(out, 4);
            out.extend(u32b(s.len() as u32 + 1));
            out.extend(s.as_bytes());
            out.push(0);
        }
        for v in t
            .transform
            .translation
            .iter()
            .chain(&t.transform.quaternion_xyzw)
        {
            pad(out, 8);
            out.extend(if little {
                v.to_le_bytes()
            } else {
                v.to_be_bytes()
            });
        }
    }

    fn sample() -> TransformStamped {
        TransformStamped {
            header: Header {
                stamp_ns: 1_700_000_000 * NS + 5,
                frame_id: "base_link".into(),
            },
            child_frame_id: "flange".into(),
            transform: RawPose {
                translation: [0.1, -0.2, 0.3],
                quaternion_xyzw: [0.0, 0.0, 0.6, 0.8],
            },
        }
    }

    #[test]
    fn tf_messages_round_trip_in_both_byte_orders() {
        for little in [true, false] {
            let t = sample();
            let mut bytes = vec![0, u8::from(little), 0, 0];
            bytes.extend(if little {
                2u32.to_le_bytes()
            } else {
                2u32.to_be_bytes()
            });
            encode_transform(&mut bytes, little, &t, 1_700_000_000, 5);
            encode_transform(&mut bytes, little, &t, 1_700_000_000, 5);
            let got = decode_tf_message(&bytes).unwrap();
            assert_eq!(got, vec![t.clone(), t.clone()]);
            // Every truncation is an error, never a panic.
            for cut in 0..bytes.len() {
                assert!(decode_tf_message(&bytes[..cut]).is_err(), "{cut}");
            }
        }
    }

    fn fixture(name: &str) -> Vec<u8> {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../testdata/rosbag/cdr")
            .join(name);
        std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
    }

    #[test]
    fn messages_of_an_independent_writer_decode_in_both_byte_orders() {
        // Serialised by the `rosbags` package (testdata/rosbag/make_bags.py).
        let tf = decode_tf_message(&fixture("tf_message_le.cdr")).unwrap();
        assert_eq!(
            tf,
            decode_tf_message(&fixture("tf_message_be.cdr")).unwrap()
        );
        assert_eq!(tf.len(), 2);
        assert_eq!(tf[0].header.stamp_ns, 1_700_000_000_123_456_789);
        assert_eq!(
            (
                tf[0].header.frame_id.as_str(),
                tf[0].child_frame_id.as_str()
            ),
            ("base_link", "flange")
        );
        assert_eq!(tf[0].transform.translation, [0.4, -0.5, 0.6]);
        let q = [
            0.049_708_843_324_859_49,
            -0.099_417_686_649_718_95,
            0.149_126_529_974_578_45,
            0.982_550_982_155_258_9,
        ];
        for (a, b) in tf[0].transform.quaternion_xyzw.iter().zip(q) {
            assert!((a - b).abs() < 1e-15);
        }
        // A leading `/` is dropped, as tf2 does.
        assert_eq!(
            (
                tf[1].header.frame_id.as_str(),
                tf[1].child_frame_id.as_str()
            ),
            ("odom", "tool")
        );
        assert_eq!(tf[1].header.stamp_ns, 5);
        let p = decode_pose_stamped(&fixture("pose_stamped_le.cdr")).unwrap();
        assert_eq!(
            p,
            decode_pose_stamped(&fixture("pose_stamped_be.cdr")).unwrap()
        );
        assert_eq!(p.header.frame_id, "camera_color_optical_frame");
        // sec = −2, nanosec = 999 999 999.
        assert_eq!(p.header.stamp_ns, -1_000_000_001);
        assert_eq!(p.pose.translation, [0.25, 0.5, 1.5]);
        assert!((p.pose.quaternion_xyzw[3] - 0.982_550_982_155_258_9).abs() < 1e-15);
    }

    #[test]
    fn a_nanosecond_field_of_a_second_or_more_is_refused() {
        let mut bytes = vec![0, 1, 0, 0];
        encode_transform(&mut bytes, true, &sample(), 1, 1_000_000_000);
        let e = decode_transform_stamped(&bytes).unwrap_err();
        assert!(e.message.contains("nanosec"), "{e}");
    }

    /// An `AprilTagDetectionArray` of one tag, little-endian, with `corners` corners.
    fn tag_message(corners: usize) -> Vec<u8> {
        let mut b = vec![0, 1, 0, 0];
        let pad = |b: &mut Vec<u8>, a: usize| {
            while !(b.len() - 4).is_multiple_of(a) {
                b.push(0);
            }
        };
        b.extend(7i32.to_le_bytes());
        b.extend(9u32.to_le_bytes());
        b.extend(7u32.to_le_bytes());
        b.extend(b"camera\0");
        pad(&mut b, 4);
        b.extend(1u32.to_le_bytes());
        b.extend(6u32.to_le_bytes());
        b.extend(b"36h11\0");
        pad(&mut b, 4);
        b.extend(3i32.to_le_bytes());
        b.extend(0i32.to_le_bytes());
        b.extend(0f32.to_le_bytes());
        b.extend(50f32.to_le_bytes());
        pad(&mut b, 8);
        let values = (0..2 + 2 * corners)
            .map(|k| 100.0 + k as f64)
            .chain([0.0; 9]);
        for v in values {
            b.extend(v.to_le_bytes());
        }
        b
    }

    #[test]
    fn tag_detections_decode_and_every_truncation_or_extra_corner_is_an_error() {
        let bytes = tag_message(4);
        let d = decode_tag_detections(&bytes).unwrap();
        assert_eq!(d.header.stamp_ns, 7 * NS + 9);
        assert_eq!(d.header.frame_id, "camera");
        assert_eq!(d.detections.len(), 1);
        assert_eq!(
            (d.detections[0].family.as_str(), d.detections[0].id),
            ("36h11", 3)
        );
        assert_eq!(d.detections[0].corners[0], [102.0, 103.0]);
        assert_eq!(d.detections[0].corners[3], [108.0, 109.0]);
        for cut in 0..bytes.len() {
            assert!(decode_tag_detections(&bytes[..cut]).is_err(), "{cut}");
        }
        let e = decode_tag_detections(&tag_message(5)).unwrap_err();
        assert!(e.message.contains("16 byte(s) left"), "{e}");
        assert!(decode_tag_detections(&tag_message(3)).is_err());
    }

    proptest::proptest! {
        /// No bytes make a decoder panic.
        #[test]
        fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..300)) {
            let mut b = vec![0, 1, 0, 0];
            b.extend(&bytes);
            let _ = decode_tf_message(&b);
            let _ = decode_pose_stamped(&b);
            let _ = decode_transform_stamped(&b);
            let _ = decode_tag_detections(&b);
            let _ = decode_camera_info(&b);
        }
    }
}
