//! What a job calibrates from: pose pairs, or the target's detections with the camera.

use crate::model::camera::{Frame, Intrinsics};
use crate::model::motion::PosePair;

/// What [`calibrate`](crate::calibrate()) (every [`Problem`](crate::Problem)) and
/// [`verify`](crate::verify) calibrate from: the pose pairs, or the target's detections with
/// the camera's intrinsics (the solve on the pixels: the recording's kind, not a method; its report
/// says [`Method::Reprojection`]).
///
/// A slice or a `Vec` of pose pairs is an input as it is (`calibrate(&poses, …)`).
///
/// [`Method::Reprojection`]: crate::Method::Reprojection
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Input<'a> {
    /// Pose pairs: the robot's pose and the camera's pose of the target, by any PnP.
    Poses(&'a [PosePair]),
    /// The robot's pose and the target's detections of each image, and the camera that made them:
    /// X and the target's pose fitted to the pixels, with the checks of the pixels (each job's
    /// section "On the pixels"; SPEC sec. 3, `reprojection`, and sec. 9 for the records).
    Pixels {
        /// The records: robot pose and detections (and a PnP pose where the recording gives one).
        frames: &'a [Frame],
        /// The camera's intrinsics.
        camera: &'a Intrinsics,
    },
}

impl<'a> From<&'a [PosePair]> for Input<'a> {
    fn from(poses: &'a [PosePair]) -> Self {
        Input::Poses(poses)
    }
}

impl<'a> From<&'a Vec<PosePair>> for Input<'a> {
    fn from(poses: &'a Vec<PosePair>) -> Self {
        Input::Poses(poses)
    }
}

impl<'a, const N: usize> From<&'a [PosePair; N]> for Input<'a> {
    fn from(poses: &'a [PosePair; N]) -> Self {
        Input::Poses(poses)
    }
}
