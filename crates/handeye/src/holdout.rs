//! A held-out check of a calibration: each camera observation predicted from the others.
//!
//! For pose i, X and the fixed frame Y (the target in the base eye-in-hand, on the gripper
//! eye-to-hand) are solved from every other pose (all-pairs Andreff, [`PoseAccumulator`]), and the
//! observation is predicted as Ĉ_i = X⁻¹ H_i⁻¹ Y. The gap between Ĉ_i and the recorded C_i, in
//! degrees and in the input's unit (where the camera sees the target against where it should),
//! says how well the calibration predicts data it was not fitted to; a pose whose gap is far above
//! the others' is a frame paired with the wrong robot pose or a failed detection. Up to
//! [`EXACT_UP_TO`] poses each is left out exactly (O(n²)); beyond, one pose moves X by less than
//! 1/300 of the data and the all-pose solution stands in for the others'.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::accumulate::PoseAccumulator;
use crate::consistency::{OUTLIER_FACTOR, median};
use crate::motion::{PosePair, Setup};
use crate::pose::{Transform, rotation_angle_between};

/// Poses up to which each is left out exactly.
pub const EXACT_UP_TO: usize = 300;

/// The held-out gap of one pose.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct HeldOutPose {
    /// Index of the pose in the input.
    pub pose: usize,
    /// Rotation between the predicted and the recorded observation, degrees.
    pub rotation_deg: f64,
    /// Distance between the predicted and the recorded target position in the camera, input
    /// units.
    pub translation: f64,
}

/// The held-out check of a set of poses.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HeldOutCheck {
    /// Every pose's gap, in input order.
    pub poses: Vec<HeldOutPose>,
    /// Median gaps: the calibration's typical prediction error.
    pub median_rotation_deg: f64,
    /// See `median_rotation_deg`.
    pub median_translation: f64,
    /// Whether each pose was left out exactly (`false` beyond [`EXACT_UP_TO`] poses).
    pub exact: bool,
    /// Indices of the poses whose gap is above 6 times the median (rotation or translation).
    pub disagree: Vec<usize>,
}

/// The held-out check (module documentation); `None` when fewer than four poses, or when the
/// others do not determine X for some pose.
pub fn leave_one_out(poses: &[PosePair], setup: Setup) -> Option<HeldOutCheck> {
    let n = poses.len();
    if n < 4 {
        return None;
    }
    let exact = n <= EXACT_UP_TO;
    let all = solved(poses.iter(), setup);
    // Each pose's gap is its own solve: the poses are spread over the threads, and collected in
    // input order (the same result on any number of threads).
    let gaps: Vec<HeldOutPose> = poses
        .par_iter()
        .enumerate()
        .map(|(i, pose)| {
            let (x, y) = if exact {
                solved(
                    poses
                        .iter()
                        .enumerate()
                        .filter(|(k, _)| *k != i)
                        .map(|(_, p)| p),
                    setup,
                )?
            } else {
                all?
            };
            let hand = setup.hand_pose(&pose.base_from_gripper);
            let predicted: Transform = x.inverse() * hand.inverse() * y;
            Some(HeldOutPose {
                pose: i,
                rotation_deg: rotation_angle_between(
                    &predicted.rotation,
                    &pose.camera_from_target.rotation,
                )
                .to_degrees(),
                translation: (predicted.translation.vector
                    - pose.camera_from_target.translation.vector)
                    .norm(),
            })
        })
        .collect::<Option<_>>()?;
    let median_rotation_deg = median(gaps.iter().map(|g| g.rotation_deg).collect());
    let median_translation = median(gaps.iter().map(|g| g.translation).collect());
    let disagree = gaps
        .iter()
        .filter(|g| {
            g.rotation_deg > OUTLIER_FACTOR * median_rotation_deg.max(1e-9)
                || g.translation > OUTLIER_FACTOR * median_translation.max(1e-12)
        })
        .map(|g| g.pose)
        .collect();
    Some(HeldOutCheck {
        poses: gaps,
        median_rotation_deg,
        median_translation,
        exact,
        disagree,
    })
}

/// X and Y from the poses.
fn solved<'a>(
    poses: impl Iterator<Item = &'a PosePair>,
    setup: Setup,
) -> Option<(Transform, Transform)> {
    let mut acc = PoseAccumulator::new(setup);
    poses.for_each(|p| acc.add(p));
    let x = acc.estimate()?.x;
    Some((x, acc.residual_scatter(&x)?.y))
}
