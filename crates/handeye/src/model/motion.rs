//! Pose pairs, the motion pairs (A, B) built from them, and the motion features θ, k, ‖t‖.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::model::pose::{Transform, axis_angle};

/// Where the camera is mounted; decides which robot pose enters the gripper motion A.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Setup {
    /// Camera on the gripper, target fixed in the world. X = `gripper_from_camera`.
    #[default]
    EyeInHand,
    /// Camera fixed in the world, target on the gripper. `gripper_from_base` takes the place of
    /// `base_from_gripper` (SPEC sec. 1) and X = `base_from_camera`.
    EyeToHand,
}

impl Setup {
    /// The other setup.
    pub fn other(self) -> Setup {
        match self {
            Setup::EyeInHand => Setup::EyeToHand,
            Setup::EyeToHand => Setup::EyeInHand,
        }
    }

    /// The frame name of X for this setup: `gripper_from_camera` or `base_from_camera`.
    pub fn x_frame(self) -> &'static str {
        match self {
            Self::EyeInHand => "gripper_from_camera",
            Self::EyeToHand => "base_from_camera",
        }
    }

    /// What X's and the target pose's translations measure, in words: the camera's distance from
    /// the gripper and the target's from the robot base (eye-in-hand), or the camera's from the
    /// base and the target's from the gripper (eye-to-hand).
    pub fn distances_in_words(self) -> (&'static str, &'static str) {
        match self {
            Self::EyeInHand => (
                "the camera's distance from the gripper",
                "the target's distance from the robot base",
            ),
            Self::EyeToHand => (
                "the camera's distance from the robot base",
                "the target's distance from the gripper",
            ),
        }
    }

    /// The paper's Q for this setup: `base_from_gripper` itself (eye-in-hand) or its inverse
    /// `gripper_from_base` (eye-to-hand).
    pub fn hand_pose(self, base_from_gripper: &Transform) -> Transform {
        match self {
            Self::EyeInHand => *base_from_gripper,
            Self::EyeToHand => base_from_gripper.inverse(),
        }
    }
}

crate::named_enum!(Setup, "setup", "setup" {
    EyeInHand => "eye-in-hand",
    EyeToHand => "eye-to-hand",
});

/// One synchronised measurement: the robot's pose and the camera's observation of the target.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PosePair {
    /// Gripper pose in the robot base frame (the paper's Q_i; OpenCV's `gripper2base`).
    pub base_from_gripper: Transform,
    /// Target pose in the camera frame, as PnP returns it (OpenCV's `target2cam`; the paper's
    /// P_i is its inverse `target_from_camera`).
    pub camera_from_target: Transform,
}

/// A motion pair (A, B) that satisfies A X = X B.
///
/// For poses a → b: A = Q_a⁻¹ Q_b = `gripper_a_from_gripper_b` and
/// B = P_a⁻¹ P_b = `camera_a_from_camera_b` (SPEC sec. 1). In eye-to-hand, Q is `gripper_from_base`,
/// so A = `base_a_from_base_b` in the same algebra.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MotionPair {
    /// Gripper (hand) motion A.
    pub a: Transform,
    /// Camera (eye) motion B.
    pub b: Transform,
}

impl MotionPair {
    /// The motion from pose `from` to pose `to`: A = Q_from⁻¹ Q_to, B = P_from⁻¹ P_to.
    pub fn between(setup: Setup, from: &PosePair, to: &PosePair) -> Self {
        let q_from = setup.hand_pose(&from.base_from_gripper);
        let q_to = setup.hand_pose(&to.base_from_gripper);
        Self {
            a: q_from.inverse() * q_to,
            // P⁻¹ = camera_from_target, so B = camera_from_target_from * target_from_camera_to.
            b: from.camera_from_target * to.camera_from_target.inverse(),
        }
    }

    /// The motion pair with both motions reversed (A⁻¹, B⁻¹); it satisfies the same equation.
    pub fn inverse(&self) -> Self {
        Self {
            a: self.a.inverse(),
            b: self.b.inverse(),
        }
    }
}

/// Which pose pairs become motions in a batch solve.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Pairing {
    /// Pose i to pose i + 1: n − 1 motions (default).
    #[default]
    Consecutive,
    /// Every pair i < j: n(n − 1)/2 motions, built as OpenCV's `calibrateHandEye` builds them
    /// (from pose j to pose i, `Hg_j⁻¹ Hg_i`), so that the same method gives OpenCV's answer.
    All,
}

impl Pairing {
    /// Number of motions this pairing makes from `n` poses.
    pub fn motion_count(self, n: usize) -> usize {
        match self {
            Self::Consecutive => n.saturating_sub(1),
            Self::All => n * n.saturating_sub(1) / 2,
        }
    }
}

crate::named_enum!(Pairing, "pairing", "pairs" {
    Consecutive => "consecutive",
    All => "all",
});

/// Builds the motion pairs of a pose sequence.
///
/// # Example
/// ```
/// use handeye::{PosePair, Pairing, Setup, Transform, motion_pairs};
/// let p = PosePair { base_from_gripper: Transform::identity(), camera_from_target: Transform::identity() };
/// assert_eq!(motion_pairs(&[p; 4], Pairing::Consecutive, Setup::EyeInHand).len(), 3);
/// assert_eq!(motion_pairs(&[p; 4], Pairing::All, Setup::EyeInHand).len(), 6);
/// ```
pub fn motion_pairs(poses: &[PosePair], pairing: Pairing, setup: Setup) -> Vec<MotionPair> {
    let mut out = Vec::with_capacity(pairing.motion_count(poses.len()));
    match pairing {
        Pairing::Consecutive => {
            out.extend(
                poses
                    .windows(2)
                    .map(|w| MotionPair::between(setup, &w[0], &w[1])),
            );
        }
        Pairing::All => {
            for (i, pi) in poses.iter().enumerate() {
                for pj in &poses[i + 1..] {
                    out.push(MotionPair::between(setup, pj, pi));
                }
            }
        }
    }
    out
}

/// The features the paper's selection rules test on a gripper motion A = (R_a, t_a).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MotionFeatures {
    /// Rotation angle θ ∈ [0, π], radians.
    pub angle: f64,
    /// Unit rotation axis k; `None` when θ < 1e-12 (SPEC sec. 1).
    pub axis: Option<Vector3<f64>>,
    /// Translation length d = ‖t_a‖, input units.
    pub translation_norm: f64,
}

impl MotionFeatures {
    /// Features of a motion `a_from_b`: θ and k by Rodrigues' formula (`axis_angle`).
    pub fn of(motion: &Transform) -> Self {
        let (angle, axis) = axis_angle(motion.rotation.matrix());
        Self {
            angle,
            axis,
            translation_norm: motion.translation.vector.norm(),
        }
    }

    /// The angle ∠(k₁, k₂) between this motion's axis and another's, radians (0 if either has none).
    pub fn axis_angle_to(&self, other: &Self) -> f64 {
        crate::model::pose::axis_angle_between(self.axis.as_ref(), other.axis.as_ref())
    }
}
