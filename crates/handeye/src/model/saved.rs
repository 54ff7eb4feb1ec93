//! An X that a calibration saved, as `verify` compares it with a recording: plain data, read by
//! `io` (`SavedX::read`, the JSON `calibrate --output json` writes and the YAML of
//! `--output yaml` and easy_handeye2), taken by `calibrate::verify`.

use crate::model::error::{Error, Result};
use crate::model::motion::Setup;
use crate::model::pose::Transform;
use crate::model::prior::LengthUnit;

/// An X that a calibration saved: `calibrate --output json` or `--output yaml`.
#[derive(Debug, Clone, PartialEq)]
pub struct SavedX {
    /// X.
    pub x: Transform,
    /// The setup it was calibrated for, when the file says.
    pub setup: Option<Setup>,
    /// Its covariance, (rotation vector in radians, translation) in [`Uncertainty`]'s convention
    /// and in the file's unit, when the file carries one.
    ///
    /// [`Uncertainty`]: crate::check::uncertainty::Uncertainty
    pub covariance: Option<[[f64; 6]; 6]>,
    /// The unit of its translation, when the file tells it (a ROS file: easy_handeye2's YAML is
    /// in metres); `None` for the unit of the recording it came from, not told (`calibrate`'s
    /// JSON).
    pub unit: Option<LengthUnit>,
}

impl SavedX {
    /// The setup to verify this X in: the one `given` (`--setup`), else the one the file declares,
    /// else eye-in-hand. A setup given that is not the file's is an error naming both: X is
    /// `gripper_from_camera` in one and `base_from_camera` in the other, and comparing them says
    /// nothing.
    pub fn setup_for(&self, given: Option<Setup>) -> Result<Setup> {
        match (given, self.setup) {
            (Some(g), Some(s)) if g != s => Err(conflict(g, s)),
            (Some(g), _) => Ok(g),
            (None, s) => Ok(s.unwrap_or_default()),
        }
    }
}

/// The error of a setup given against the saved X's own.
pub(crate) fn conflict(given: Setup, saved: Setup) -> Error {
    Error::InvalidParameter {
        name: "setup",
        message: format!(
            "the recording is to be read as {} (--setup {}), but the saved X is for {} (X = {}): give --setup {} or leave it out to take the saved X's, or verify against an X saved for {}",
            given.name(),
            given.name(),
            saved.name(),
            saved.x_frame(),
            saved.name(),
            given.name()
        ),
    }
}
