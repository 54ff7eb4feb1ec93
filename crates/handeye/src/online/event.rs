//! The paper's calibrations as a run reports them ([`Event`]), and their JSON line.

use serde::Serialize;

use crate::model::pose::{Transform, TransformJson};
use crate::online::OPTIMAL_WINDOW;
use crate::online::select::Thresholds;

/// rmsR and rmsT of a calibration, from the configured [`ErrorSource`](crate::ErrorSource): against the truth, or
/// the residual form ([`crate::check::quality::ResidualRms`], the same type).
pub type Rms = crate::check::quality::ResidualRms;

/// The optimal method's estimate at one calibration (SPEC sec. 4.5).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OptimalEstimate {
    /// Number of this optimal result (1 at the first calibration with five selected motions).
    pub number: usize,
    /// X refined over the last five selected motions.
    pub x: Transform,
    /// The five motions as pose-number pairs, oldest first.
    pub motions: [[usize; 2]; OPTIMAL_WINDOW],
    /// Wall time of the refinement, including its Andreff start, seconds (not in the line).
    pub seconds: f64,
}

/// One calibration of an online run; serialised (serde) as its JSON line (SPEC sec. 7), the one
/// output of every face: `calibration`, `poses`, `thresholds` (adaptive and fixed selection),
/// `rms_r`, `rms_t`, X (`translation`, `quaternion_xyzw`, `matrix`), `conditioning`, `optimal`
/// (X, `number`, `motions`) when enabled, `seconds`; and `time_offset_s` when set.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Event {
    /// Number of this calibration (1, 2, …).
    pub calibration: usize,
    /// Pose numbers (a, i, j) of A' = Q_a⁻¹ Q_i and A'' = Q_i⁻¹ Q_j.
    pub poses: [usize; 3],
    /// Thresholds in force when the pair was accepted (adaptive only).
    pub thresholds: Option<Thresholds>,
    /// X from Andreff's method on (A', A'').
    pub x: Transform,
    /// rmsR and rmsT of X from the error source.
    pub rms: Rms,
    /// Conditioning of the two-motion rotation system.
    pub conditioning: f64,
    /// Wall time of the calibration (solve, errors, threshold update), seconds.
    pub seconds: f64,
    /// The optimal method's X, when enabled and five motions have been selected.
    pub optimal: Option<OptimalEstimate>,
    /// The clock offset applied to a second stream (camera − robot), seconds: set by the face
    /// that paired two streams; `None` from the calibrator.
    pub time_offset_s: Option<f64>,
}

impl Event {
    /// The event's JSON line as a value (its serde form).
    pub fn json(&self) -> serde_json::Value {
        serde_json::to_value(self).unwrap_or_default()
    }
}

impl Serialize for Event {
    fn serialize<S: serde::Serializer>(
        &self,
        serializer: S,
    ) -> std::result::Result<S::Ok, S::Error> {
        EventLine {
            calibration: self.calibration,
            poses: self.poses,
            thresholds: self.thresholds,
            rms_r: self.rms.rms_r,
            rms_t: self.rms.rms_t,
            x: TransformJson::from(&self.x),
            conditioning: self.conditioning,
            optimal: self.optimal.as_ref().map(|o| OptimalLine {
                x: TransformJson::from(&o.x),
                number: o.number,
                motions: o.motions,
            }),
            seconds: self.seconds,
            time_offset_s: self.time_offset_s,
        }
        .serialize(serializer)
    }
}

/// The field order and names of an [`Event`]'s line (its serde form), not a second model.
#[derive(Serialize)]
struct EventLine {
    calibration: usize,
    poses: [usize; 3],
    #[serde(skip_serializing_if = "Option::is_none")]
    thresholds: Option<Thresholds>,
    rms_r: f64,
    rms_t: f64,
    #[serde(flatten)]
    x: TransformJson,
    conditioning: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    optimal: Option<OptimalLine>,
    seconds: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    time_offset_s: Option<f64>,
}

/// The optimal method's part of an [`Event`]'s line.
#[derive(Serialize)]
struct OptimalLine {
    #[serde(flatten)]
    x: TransformJson,
    number: usize,
    motions: [[usize; 2]; OPTIMAL_WINDOW],
}
