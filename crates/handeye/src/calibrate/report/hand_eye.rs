//! The hand–eye problem's report, and the sections every report shares (the reading, the
//! outliers, the units).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::calibrate::low_dof::LowDofReport;
use crate::calibrate::report::pixels::ReprojectionSummary;
use crate::check::quality::{MotionQuality, ResidualSummary};
use crate::check::readings::ReadingCheck;
use crate::check::systematic::Systematic;
use crate::check::uncertainty::Uncertainty;
use crate::model::findings::{OutlierPose, Reading};
use crate::model::motion::{Pairing, Setup};
use crate::model::pose::{Transform, TransformJson};
use crate::model::prior::PriorValue;
use crate::model::warning::Warning;
use crate::solve::{Method, TsaiOptions};

/// The outliers in a [`HandEyeReport`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Outliers {
    /// The outlier poses.
    pub poses: Vec<OutlierPose>,
    /// Whether they were left out of the solve.
    pub rejected: bool,
    /// The angle-gap threshold used, degrees.
    pub angle_threshold_deg: f64,
    /// The pitch-gap threshold used, input units.
    pub pitch_threshold: f64,
}

/// The readings tried, in a [`HandEyeReport`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReadingReport {
    /// The reading the result was solved under.
    pub applied: Reading,
    /// What the check found (absent when a reading was forced).
    pub check: Option<ReadingCheck>,
}

/// The spread of the motions, in a [`HandEyeReport`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Spread {
    /// Largest angle between a motion's rotation axis and the dominant axis, degrees.
    pub axis_spread_deg: f64,
    /// Smallest and largest rotation angle of the motions, degrees.
    pub rotation_range_deg: [f64; 2],
    /// Per motion pair, in order (absent above 10,000 motions).
    pub per_motion: Option<Vec<MotionQuality>>,
    /// Over every pair of more than [`crate::check::quality::EXACT_POSES`] poses, the poses whose
    /// pairs the spread, the range and the largest residuals were taken over
    /// ([`crate::check::quality::QualityReport::sampled_poses`]); absent where every motion was
    /// gone through.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sampled_poses: Option<usize>,
}

/// The units of a [`HandEyeReport`]'s numbers.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Units {
    /// Rotations.
    pub rotation: String,
    /// Lengths.
    pub length: String,
}

impl Default for Units {
    fn default() -> Self {
        Self {
            rotation: "degrees where a name says _deg, radians in the covariance".into(),
            length: "the input's length unit".into(),
        }
    }
}

pub use crate::model::findings::Assessment;

/// The report of the hand–eye problem ([`Problem::HandEye`](crate::Problem::HandEye)), one of
/// [`Report`](crate::Report)'s: X, how far to trust it, and why.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HandEyeReport {
    /// The verdict: `good`, or `questionable` while a caution of `warnings` stands.
    pub verdict: Assessment,
    /// The solver.
    pub method: Method,
    /// The setup.
    pub setup: Setup,
    /// The pairing.
    pub pairing: Pairing,
    /// X's frame name (`gripper_from_camera` or `base_from_camera`).
    pub frame: String,
    /// X (`translation`, `quaternion_xyzw`, `matrix` in the JSON object itself).
    #[serde(flatten)]
    pub x: TransformJson,
    /// Poses used.
    pub poses: usize,
    /// Motions used.
    pub motions: usize,
    /// Conditioning of Andreff's rotation system (1 is ideal).
    pub conditioning: f64,
    /// One-sigma uncertainty of X from the bootstrap over the poses' own errors.
    pub uncertainty: Uncertainty,
    /// The reading of the input.
    pub reading: ReadingReport,
    /// Poses that disagree with the others.
    pub outliers: Outliers,
    /// The A X − X B residuals over the motions (degrees; input units).
    pub residual: ResidualSummary,
    /// Median per-pose translation residual over the scene's size (the larger of the hand's spread
    /// and the camera's working distance), unit-free.
    pub translation_residual_rel: f64,
    /// The spread of the motions.
    pub quality: Spread,
    /// Cautions, each with its code, its words and the option that fixes it, if one does.
    #[serde(serialize_with = "crate::model::warning::described")]
    pub warnings: Vec<Warning>,
    /// The units of the numbers.
    pub units: Units,
    /// X as a transform (not serialised: `x` carries it).
    #[serde(skip)]
    pub transform: Transform,
    /// The held-out check: each camera observation predicted from the other poses
    /// (`crate::holdout`); `None` with fewer than four poses.
    pub held_out: Option<HeldOutSummary>,
    /// The test for an error that follows the robot's configuration (`check::systematic`);
    /// absent where it did not run (`systematic_untested` says why).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub systematic: Option<Systematic>,
    /// Why the systematic-error test did not run (`check::systematic::Untested`, in words);
    /// absent where it ran.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub systematic_untested: Option<String>,
    /// The components of X's translation that came from a prior, not from the data (`"prior":
    /// {"tz": {"value", "sigma"}}`); absent when none did.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub prior: BTreeMap<String, PriorValue>,
    /// A low-DOF recording (every motion rotates about one axis): the axis and the component
    /// taken from the prior; absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub low_dof: Option<LowDofReport>,
    /// The fit on the pixels (`--method reprojection`); absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reprojection: Option<ReprojectionSummary>,
    /// X's uncertainty against the goal given (`Options::goal`); absent without one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub goal: Option<crate::model::findings::GoalCheck>,
}

/// The held-out check in a [`HandEyeReport`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HeldOutSummary {
    /// Median gap between the predicted and the recorded observation, degrees.
    pub median_rotation_deg: f64,
    /// Median gap in the target's position seen by the camera, input units.
    pub median_translation: f64,
    /// Each pose left out exactly or not (always, since the check is O(n); up to 300 poses before).
    pub exact: bool,
    /// The poses the others predict poorly (6 times the median or more), by name.
    pub disagree: Vec<HeldOutName>,
}

/// One poorly predicted pose.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HeldOutName {
    /// Its name (`file:line` from the CLI).
    pub name: String,
    /// Its gaps: degrees and input units.
    pub rotation_deg: f64,
    /// See `rotation_deg`.
    pub translation: f64,
}

impl HandEyeReport {
    /// What OpenCV's Tsai motion filter dropped, in words, when `tsai` applied it and it dropped
    /// motions ([`TsaiOptions::opencv_filter_note`]); each face adds how it keeps every motion.
    pub fn tsai_filter_note(&self, tsai: TsaiOptions) -> Option<String> {
        if !tsai.opencv_filter || self.method != Method::Tsai {
            return None;
        }
        TsaiOptions::opencv_filter_note(self.motions, self.pairing.motion_count(self.poses))
    }
}
