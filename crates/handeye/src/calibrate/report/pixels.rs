//! The report's section on the pixels: the fit of X and the target's pose to the detections.

use serde::{Deserialize, Serialize};

use crate::model::pose::{Transform, TransformJson};
use crate::solve::reprojection::RefinedIntrinsics;

/// The fit on the pixels in a [`Report`](crate::Report).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReprojectionSummary {
    /// RMS reprojection error over the detections kept, pixels.
    pub rms_px: f64,
    /// Each frame's RMS over all of its detections, in input order.
    pub per_frame: Vec<FrameRms>,
    /// Robust sigma of one pixel coordinate, pixels.
    pub sigma_px: f64,
    /// Detections used in all.
    pub detections: usize,
    /// Detections left out as mis-detections (beyond 5 robust sigmas), (frame name, point index).
    pub outlier_detections: Vec<(String, usize)>,
    /// Frames whose start pose was the other pose of the planar ambiguity than PnP's
    /// smaller-residual one: chosen by the robot's motion.
    pub flips_resolved: usize,
    /// The target's pose Y solved with X, and its frame name.
    pub target_frame: String,
    /// Y (`translation`, `quaternion_xyzw`, `matrix`).
    pub target: TransformJson,
    /// How the reading of the robot poses was checked.
    pub reading_check: String,
    /// The intrinsics refined with X (`--refine-intrinsics`), with their sigmas; absent when the
    /// given intrinsics were used as they are.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub intrinsics: Option<RefinedIntrinsics>,
    /// Every detection's residual where it is in the image, for a figure (the HTML report's):
    /// not in the JSON, whose size it would make grow with the detections.
    #[serde(skip)]
    pub corners: Vec<CornerResidual>,
    /// The camera pose the solve started from for each frame of the input (the outlier frames
    /// left out too), in input order, under the reading `reading.applied` says (the robot poses
    /// inverted for [`Reading::RobotInverted`](crate::Reading::RobotInverted)): the PnP pose chosen by the robot's motion, or the
    /// record's own `camera_from_target` where it fits the pixels better. The camera poses a
    /// report page or a unit guess should use for records that carry detections only; a frame
    /// that cannot be posed has its own `camera_from_target`, or the identity. Not in the JSON.
    #[serde(skip)]
    pub start_poses: Vec<Transform>,
}

/// One detection's reprojection residual.
#[derive(Debug, Clone, PartialEq)]
pub struct CornerResidual {
    /// Its frame: the index in [`ReprojectionSummary::per_frame`], which names it.
    pub frame: usize,
    /// Where it was detected, pixels (u, v).
    pub pixel: [f64; 2],
    /// The detected pixel less the projected one under the solved X and target pose, pixels.
    pub residual_px: [f64; 2],
    /// Whether the solve kept it (not a mis-detection).
    pub kept: bool,
}

/// One frame's reprojection RMS.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrameRms {
    /// The frame's name (`file:line` from the command line).
    pub name: String,
    /// RMS over its detections, pixels.
    pub rms_px: f64,
}
