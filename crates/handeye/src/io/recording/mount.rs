//! Where a recording's tf places the camera frame X is found for ([`CameraMount`]), and the words
//! of its note.

use std::fmt;

use crate::model::pose::Transform;

/// Where a ROS 2 recording's tf already places the camera frame X is found for, when it gives it
/// a parent (an optical frame under `camera_link`; [`super::Note::CameraMount`]).
///
/// tf gives a frame one parent, so X published for such a frame gives it a second. X is then
/// published for the root of the camera's subtree (the top of `above`):
/// `parent_from_root = X · camera_from_root`. When that root hangs in the robot's tree itself
/// (`placed_under`: the camera was calibrated before), nothing is to be published beside it:
/// X is compared with tf's (`tf_x`).
#[derive(Debug, Clone, PartialEq)]
pub struct CameraMount {
    /// The camera frame (`camera_color_optical_frame`).
    pub camera: String,
    /// The frames above it, its parent first, up to the root of the camera's subtree (the last);
    /// empty when the camera frame's own parent is in the robot's tree.
    pub above: Vec<MountFrame>,
    /// The frame of the robot's tree (the base, the gripper or one of their ancestors) the root
    /// hangs from, if it does (`tool0`).
    pub placed_under: Option<String>,
    /// X's parent frame in the recording: the gripper's (eye-in-hand) or the base's
    /// (eye-to-hand).
    pub x_parent: String,
    /// X as tf has it, `x_parent_from_camera`, when the camera is placed in the robot's tree and
    /// every transform between them is static.
    pub tf_x: Option<Transform>,
}

/// A frame above the camera frame in tf, and the camera's pose in it.
#[derive(Debug, Clone, PartialEq)]
pub struct MountFrame {
    /// The frame (`camera_link`).
    pub frame: String,
    /// `frame_from_camera`, composed of the transforms between them when all are static (in
    /// `/tf_static`); none when one of them moves (in `/tf`).
    pub frame_from_camera: Option<Transform>,
}

impl CameraMount {
    /// The root of the camera's subtree: the frame X is published for (the camera frame itself
    /// when its parent is in the robot's tree).
    pub fn root(&self) -> &str {
        self.above.last().map_or(&self.camera, |f| &f.frame)
    }

    /// `frame_from_camera` for the camera frame or a frame above it, when the transforms between
    /// them are static; none for a frame that is neither.
    pub fn frame_from_camera(&self, frame: &str) -> Option<Transform> {
        if frame == self.camera {
            return Some(Transform::identity());
        }
        self.above
            .iter()
            .find(|f| f.frame == frame)
            .and_then(|f| f.frame_from_camera)
    }

    /// The chain from the top (the frame the root hangs from, else the root) down to the camera
    /// frame: `` `camera_link` → `camera_color_optical_frame` ``.
    fn chain_words(&self) -> String {
        let above = self.above.iter().rev().map(|f| f.frame.as_str());
        self.placed_under
            .iter()
            .map(String::as_str)
            .chain(above)
            .chain([self.camera.as_str()])
            .map(|f| format!("`{f}`"))
            .collect::<Vec<_>>()
            .join(" → ")
    }

    /// The note's words for the recording at `path`.
    pub(super) fn fmt_note(&self, path: &str, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (camera, root, parent) = (&self.camera, self.root(), &self.x_parent);
        let chain = self.chain_words();
        if self.placed_under.is_some() {
            return write!(
                f,
                "{path}: the camera frame `{camera}` is placed in the robot's tf already ({chain}): the camera was calibrated before, and publishing X beside that transform would give `{root}` a second parent (tf allows one) or close a loop; compare X with tf's {parent}_from_{camera} instead (`handeye verify --x SAVED` checks a saved calibration against a recording)"
            );
        }
        write!(
            f,
            "{path}: the camera frame `{camera}` has a parent in tf already ({chain}), and tf gives a frame one parent: X is found for `{camera}`"
        )?;
        match self.frame_from_camera(root) {
            Some(_) => write!(
                f,
                "; publish it for `{root}`, the root of the camera's subtree, as {parent}_from_{root} = X · {camera}_from_{root} (from /tf_static)"
            ),
            None => write!(
                f,
                ", and publishing it would give it a second parent; a transform between it and `{root}`, the root of the camera's subtree, is in /tf (it moves), so no static transform for `{root}` can be offered either"
            ),
        }
    }
}
