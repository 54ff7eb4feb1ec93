//! An X that a calibration saved, as `verify` compares it with a recording: plain data, read by
//! `io` (`SavedX::read`, the JSON `calibrate --output json` writes and the YAML of
//! `--output yaml` and easy_handeye2), taken by `calibrate::verify`.

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
