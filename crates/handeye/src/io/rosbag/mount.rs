//! Where the tf tree places the camera frame ([`CameraMount`]): the frames above it up to the
//! root of its subtree, and whether that root hangs in the robot's tree.

use std::collections::HashSet;

use super::tf::TfBuffer;
use crate::io::sync::Lookup;
use crate::io::{CameraMount, MountFrame};
use crate::model::pose::Transform;

/// Where `tf` places `camera` when it gives it a parent; `robot` is the base and gripper frames,
/// `x_parent` the one of them X is relative to. None for a camera frame without a parent (or in
/// a loop, which the lookups refuse).
pub(super) fn camera_mount(
    tf: &TfBuffer,
    camera: &str,
    robot: [&str; 2],
    x_parent: &str,
) -> Option<CameraMount> {
    let chain = tf.ancestors(camera).ok()?;
    if chain.len() < 2 {
        return None;
    }
    let robot_side = robot_side(tf, robot);
    // The camera's subtree ends below the first frame above the camera's in the robot's tree.
    let end = chain
        .iter()
        .skip(1)
        .position(|f| robot_side.contains(f))
        .map(|k| k + 1);
    let placed_under = end.map(|k| chain[k].clone());
    let tf_x = placed_under
        .as_ref()
        .and_then(|_| static_between(tf, x_parent, camera));
    Some(CameraMount {
        camera: camera.to_string(),
        above: frames_above(tf, &chain[..end.unwrap_or(chain.len())]),
        placed_under,
        x_parent: x_parent.to_string(),
        tf_x,
    })
}

/// The frames of the robot's tree that X's parent could be under: the base's and the gripper's
/// and their ancestors.
fn robot_side(tf: &TfBuffer, robot: [&str; 2]) -> HashSet<String> {
    robot
        .iter()
        .filter_map(|f| tf.ancestors(f).ok())
        .flatten()
        .collect()
}

/// The frames of `chain` (the camera frame, then its ancestors) above the camera's, each with
/// `frame_from_camera` while every transform below it is static.
fn frames_above(tf: &TfBuffer, chain: &[String]) -> Vec<MountFrame> {
    let mut frame_from_camera = Some(Transform::identity());
    chain
        .windows(2)
        .map(|w| {
            let (child, parent) = (&w[0], &w[1]);
            // parent_from_camera = parent_from_child · child_from_camera.
            frame_from_camera = frame_from_camera.zip(tf.static_edge(child)).map(
                |(child_from_camera, parent_from_child)| parent_from_child * child_from_camera,
            );
            MountFrame {
                frame: parent.clone(),
                frame_from_camera,
            }
        })
        .collect()
}

/// `a_from_b` when every transform between the two frames is static.
fn static_between(tf: &TfBuffer, a: &str, b: &str) -> Option<Transform> {
    let path = tf.path(a, b).ok()?;
    if !tf.dynamic_on(&path).is_empty() {
        return None;
    }
    match tf.lookup(&path, 0, 0) {
        Lookup::Pose(a_from_b) => Some(a_from_b),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    fn t(x: f64, angle: f64) -> Transform {
        Transform::new(Vector3::new(x, 0.1, -0.2), Vector3::new(0.1, angle, 0.3))
    }

    fn close(a: Option<Transform>, b: Transform) -> bool {
        a.is_some_and(|a| (a.to_homogeneous() - b.to_homogeneous()).abs().max() < 1e-12)
    }

    /// world → base_link (static) → tool0 (dynamic).
    fn robot() -> TfBuffer {
        let mut tf = TfBuffer::default();
        tf.add("world", "base_link", 0, t(1.0, 0.3), true).unwrap();
        tf.add("base_link", "tool0", 0, t(0.5, 0.2), false).unwrap();
        tf.add("base_link", "tool0", 10, t(0.6, 0.1), false)
            .unwrap();
        tf
    }

    const ROBOT: [&str; 2] = ["base_link", "tool0"];

    #[test]
    fn an_optical_frame_under_camera_link_is_carried_to_the_root_of_its_subtree() {
        let mut tf = robot();
        tf.add("camera_link", "color", 0, t(0.01, 0.5), true)
            .unwrap();
        tf.add("color", "optical", 0, t(0.02, -1.0), true).unwrap();
        tf.finish();
        let m = camera_mount(&tf, "optical", ROBOT, "tool0").unwrap();
        assert_eq!(m.root(), "camera_link");
        assert_eq!(m.placed_under, None);
        assert_eq!(m.tf_x, None);
        assert!(close(m.frame_from_camera("color"), t(0.02, -1.0)));
        let link_from_optical = t(0.01, 0.5) * t(0.02, -1.0);
        assert!(close(m.frame_from_camera("camera_link"), link_from_optical));
        assert!(close(m.frame_from_camera("optical"), Transform::identity()));
        assert_eq!(m.frame_from_camera("tool0"), None);
        // The root itself has no parent: nothing to say.
        assert_eq!(camera_mount(&tf, "camera_link", ROBOT, "tool0"), None);
    }

    #[test]
    fn a_camera_placed_in_the_robots_tree_is_compared_with_tfs_x() {
        let mut tf = robot();
        tf.add("tool0", "camera_link", 0, t(0.05, 0.4), true)
            .unwrap();
        tf.add("camera_link", "optical", 0, t(0.02, -1.0), true)
            .unwrap();
        tf.finish();
        let m = camera_mount(&tf, "optical", ROBOT, "tool0").unwrap();
        assert_eq!(
            (m.root(), m.placed_under.as_deref()),
            ("camera_link", Some("tool0"))
        );
        assert!(close(m.tf_x, t(0.05, 0.4) * t(0.02, -1.0)));
        // The camera frame's own parent in the robot's tree: it is its subtree's root.
        let m = camera_mount(&tf, "camera_link", ROBOT, "tool0").unwrap();
        assert_eq!(
            (m.root(), m.placed_under.as_deref()),
            ("camera_link", Some("tool0"))
        );
        assert!(m.above.is_empty() && close(m.tf_x, t(0.05, 0.4)));
        // Eye-to-hand, the camera under the world: tf's X through the base's static transform.
        let mut tf = robot();
        tf.add("world", "camera_link", 0, t(2.0, 0.4), true)
            .unwrap();
        tf.finish();
        let m = camera_mount(&tf, "camera_link", ROBOT, "base_link").unwrap();
        assert_eq!(m.placed_under.as_deref(), Some("world"));
        assert!(close(m.tf_x, t(1.0, 0.3).inverse() * t(2.0, 0.4)));
        // Under the gripper but compared in the base: a dynamic transform between, no tf X.
        let mut tf = robot();
        tf.add("tool0", "camera_link", 0, t(0.05, 0.4), true)
            .unwrap();
        tf.finish();
        let m = camera_mount(&tf, "camera_link", ROBOT, "base_link").unwrap();
        assert_eq!((m.placed_under.as_deref(), m.tf_x), (Some("tool0"), None));
    }

    #[test]
    fn a_moving_transform_in_the_camera_chain_gives_no_static_transform_above_it() {
        let mut tf = robot();
        tf.add("camera_link", "pan", 0, t(0.0, 0.1), false).unwrap();
        tf.add("camera_link", "pan", 10, t(0.0, 0.2), false)
            .unwrap();
        tf.add("pan", "optical", 0, t(0.02, -1.0), true).unwrap();
        tf.finish();
        let m = camera_mount(&tf, "optical", ROBOT, "tool0").unwrap();
        assert_eq!(m.root(), "camera_link");
        assert!(close(m.frame_from_camera("pan"), t(0.02, -1.0)));
        assert_eq!(m.frame_from_camera("camera_link"), None);
    }
}
