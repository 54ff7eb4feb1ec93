//! The robot-world problem's report: X, the target's pose, how far to trust both.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::calibrate::low_dof::LowDofReport;
use crate::calibrate::report::hand_eye::{Outliers, ReadingReport, Units};
use crate::calibrate::report::pixels::ReprojectionSummary;
use crate::check::systematic::Systematic;
use crate::check::uncertainty::Uncertainty;
use crate::model::findings::Assessment;
use crate::model::motion::Setup;
use crate::model::pose::{Transform, TransformJson};
use crate::model::prior::PriorsUsed;
use crate::solve::{PoseResidual, RobotWorldMethod};

/// The target's pose in a [`RobotWorldReport`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TargetReport {
    /// `base_from_target` (eye-in-hand) or `gripper_from_target` (eye-to-hand).
    pub frame: String,
    /// The pose (`translation`, `quaternion_xyzw`, `matrix` in the JSON object itself).
    #[serde(flatten)]
    pub pose: TransformJson,
    /// One-sigma uncertainty (first-order covariance; axes in the target pose's reference frame,
    /// the robot base or the gripper).
    pub uncertainty: Uncertainty,
}

/// The per-pose residuals of Q_i X C_i = Y, summarised.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PoseResidualSummary {
    /// RMS over the poses of the rotation residual, degrees.
    pub rotation_deg_rms: f64,
    /// The largest rotation residual, degrees.
    pub rotation_deg_max: f64,
    /// RMS over the poses of the translation residual, input units.
    pub translation_rms: f64,
    /// The largest translation residual, input units.
    pub translation_max: f64,
    /// Per pose, in input order; printed as `{"rotation_deg", "translation"}` (the angle and the
    /// distance), so that a report read back keeps these two, not the directions: its rotations
    /// and translations lie along x.
    #[serde(with = "printed")]
    pub per_pose: Vec<PoseResidual>,
}

impl PoseResidualSummary {
    /// The summary of the per-pose residuals.
    pub(crate) fn of(per_pose: Vec<PoseResidual>) -> Self {
        let n = per_pose.len().max(1) as f64;
        let rms = |f: fn(&PoseResidual) -> f64| {
            (per_pose.iter().map(|r| f(r).powi(2)).sum::<f64>() / n).sqrt()
        };
        let max = |f: fn(&PoseResidual) -> f64| per_pose.iter().map(f).fold(0.0, f64::max);
        Self {
            rotation_deg_rms: rms(PoseResidual::angle_deg),
            rotation_deg_max: max(PoseResidual::angle_deg),
            translation_rms: rms(PoseResidual::distance),
            translation_max: max(PoseResidual::distance),
            per_pose,
        }
    }
}

/// A pose's residual as a report prints it: its angle and its distance.
#[derive(Serialize, Deserialize)]
struct Printed {
    rotation_deg: f64,
    translation: f64,
}

/// `serde(with)` of [`PoseResidualSummary::per_pose`].
mod printed {
    use nalgebra::Vector3;
    use serde::{Deserialize, Deserializer, Serializer};

    use crate::calibrate::report::robot_world::Printed;
    use crate::solve::PoseResidual;

    pub(super) fn serialize<S: Serializer>(
        rows: &[PoseResidual],
        serializer: S,
    ) -> Result<S::Ok, S::Error> {
        serializer.collect_seq(rows.iter().map(|r| Printed {
            rotation_deg: r.angle_deg(),
            translation: r.distance(),
        }))
    }

    pub(super) fn deserialize<'de, D: Deserializer<'de>>(
        deserializer: D,
    ) -> Result<Vec<PoseResidual>, D::Error> {
        let rows = Vec::<Printed>::deserialize(deserializer)?;
        Ok(rows
            .into_iter()
            .map(|p| {
                let angle = p.rotation_deg.to_radians();
                PoseResidual {
                    rotation: Vector3::x() * angle,
                    angle,
                    translation: Vector3::x() * p.translation,
                }
            })
            .collect())
    }
}

/// The report of the robot-world problem ([`Problem::RobotWorld`](crate::Problem::RobotWorld)),
/// one of [`Report`](crate::Report)'s: X, the target's pose, how far to trust both.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RobotWorldReport {
    /// The verdict: `good`, or `questionable` while a caution of `warnings` stands (as the
    /// hand–eye report's).
    pub verdict: Assessment,
    /// The solver.
    pub method: RobotWorldMethod,
    /// The setup.
    pub setup: Setup,
    /// Always `robot-world` (the formulation; the hand–eye report says `pairing` instead).
    pub formulation: String,
    /// X's frame name (`gripper_from_camera` or `base_from_camera`).
    pub frame: String,
    /// X (`translation`, `quaternion_xyzw`, `matrix` in the JSON object itself).
    #[serde(flatten)]
    pub x: TransformJson,
    /// One-sigma uncertainty of X (first-order covariance; axes in X's reference frame).
    pub uncertainty: Uncertainty,
    /// The target's pose and its uncertainty.
    pub target: TargetReport,
    /// Poses used.
    pub poses: usize,
    /// Conditioning of Andreff's rotation system over the consecutive motions (1 is ideal).
    pub conditioning: f64,
    /// The reading of the input.
    pub reading: ReadingReport,
    /// Poses that disagree with the others (as in the hand–eye report).
    pub outliers: Outliers,
    /// The per-pose residuals (degrees; input units).
    pub residual: PoseResidualSummary,
    /// Cautions, each with its code, its words and the option that fixes it, if one does.
    #[serde(serialize_with = "crate::model::warning::described")]
    pub warnings: Vec<crate::model::warning::Warning>,
    /// The units of the numbers.
    pub units: Units,
    /// X as a transform (not serialised).
    #[serde(skip)]
    pub transform: Transform,
    /// The target pose as a transform (not serialised).
    #[serde(skip)]
    pub target_transform: Transform,
    /// The test for an error that follows the robot's configuration, as in the hand–eye report.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub systematic: Option<Systematic>,
    /// Why the systematic-error test did not run (`check::systematic::Untested`, in words);
    /// absent where it ran.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub systematic_untested: Option<String>,
    /// The fit on the pixels, when X and the target were solved on the detections
    /// ([`Input::Pixels`](crate::Input::Pixels)).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reprojection: Option<ReprojectionSummary>,
    /// The components of X's translation that came from a prior, as in the hand–eye report
    /// (`"prior": {"tz": {"value", "sigma"}}`); absent when none did.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub prior: PriorsUsed,
    /// A low-DOF recording, as in the hand–eye report; absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub low_dof: Option<LowDofReport>,
    /// X's uncertainty against the goal given, as in the hand–eye report; absent without one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub goal: Option<crate::model::findings::GoalCheck>,
}
