//! The one report of [`calibrate`](crate::calibrate()): the problem's own ([`HandEyeReport`],
//! [`RobotWorldReport`]), each printed as it always was, and the sections they share.

pub mod hand_eye;
pub mod pixels;
pub mod robot_world;

use serde::{Deserialize, Serialize};

pub use hand_eye::{HandEyeReport, Outliers, ReadingReport};
pub use pixels::ReprojectionSummary;
pub use robot_world::RobotWorldReport;

use crate::check::uncertainty::Uncertainty;
use crate::model::findings::Assessment;
use crate::model::motion::Setup;
use crate::model::pose::Transform;
use crate::model::warning::Warning;

/// What [`calibrate`](crate::calibrate()) returns: the report of the problem
/// [`Options::problem`](crate::Options::problem) named, serialised as that report alone (the
/// JSON of each problem is its report's object, with no tag).
// Both variants are kilobytes of report, made once per job: a box would only add a pointer.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Report {
    /// X from the motions ([`Problem::HandEye`](crate::Problem::HandEye)).
    HandEye(HandEyeReport),
    /// X and the target's pose ([`Problem::RobotWorld`](crate::Problem::RobotWorld)).
    RobotWorld(RobotWorldReport),
}

impl Report {
    /// The hand–eye report, or `None` for another problem's.
    pub fn hand_eye(&self) -> Option<&HandEyeReport> {
        match self {
            Report::HandEye(r) => Some(r),
            Report::RobotWorld(_) => None,
        }
    }

    /// The robot-world report, or `None` for another problem's.
    pub fn robot_world(&self) -> Option<&RobotWorldReport> {
        match self {
            Report::RobotWorld(r) => Some(r),
            Report::HandEye(_) => None,
        }
    }

    /// The hand–eye report, or `None` for another problem's.
    pub fn into_hand_eye(self) -> Option<HandEyeReport> {
        match self {
            Report::HandEye(r) => Some(r),
            Report::RobotWorld(_) => None,
        }
    }

    /// The robot-world report, or `None` for another problem's.
    pub fn into_robot_world(self) -> Option<RobotWorldReport> {
        match self {
            Report::RobotWorld(r) => Some(r),
            Report::HandEye(_) => None,
        }
    }

    /// The verdict: `good`, or `questionable` while a caution of the warnings stands.
    pub fn verdict(&self) -> Assessment {
        match self {
            Report::HandEye(r) => r.verdict,
            Report::RobotWorld(r) => r.verdict,
        }
    }

    /// X as a transform.
    pub fn transform(&self) -> &Transform {
        match self {
            Report::HandEye(r) => &r.transform,
            Report::RobotWorld(r) => &r.transform,
        }
    }

    /// X's one-sigma uncertainty.
    pub fn uncertainty(&self) -> &Uncertainty {
        match self {
            Report::HandEye(r) => &r.uncertainty,
            Report::RobotWorld(r) => &r.uncertainty,
        }
    }

    /// The setup.
    pub fn setup(&self) -> Setup {
        match self {
            Report::HandEye(r) => r.setup,
            Report::RobotWorld(r) => r.setup,
        }
    }

    /// The reading of the input.
    pub fn reading(&self) -> &ReadingReport {
        match self {
            Report::HandEye(r) => &r.reading,
            Report::RobotWorld(r) => &r.reading,
        }
    }

    /// Poses that disagree with the others.
    pub fn outliers(&self) -> &Outliers {
        match self {
            Report::HandEye(r) => &r.outliers,
            Report::RobotWorld(r) => &r.outliers,
        }
    }

    /// Poses used.
    pub fn poses(&self) -> usize {
        match self {
            Report::HandEye(r) => r.poses,
            Report::RobotWorld(r) => r.poses,
        }
    }

    /// The cautions.
    pub fn warnings(&self) -> &[Warning] {
        match self {
            Report::HandEye(r) => &r.warnings,
            Report::RobotWorld(r) => &r.warnings,
        }
    }

    /// The fit on the pixels, when the input was the detections.
    pub fn reprojection(&self) -> Option<&ReprojectionSummary> {
        match self {
            Report::HandEye(r) => r.reprojection.as_ref(),
            Report::RobotWorld(r) => r.reprojection.as_ref(),
        }
    }
}

impl From<HandEyeReport> for Report {
    fn from(r: HandEyeReport) -> Self {
        Report::HandEye(r)
    }
}

impl From<RobotWorldReport> for Report {
    fn from(r: RobotWorldReport) -> Self {
        Report::RobotWorld(r)
    }
}
