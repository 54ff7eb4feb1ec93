//! The readings check on the first poses of a stream: what `calibrate` checks on a whole
//! recording, for an online calibrator that has only its first poses.

use crate::check::outliers::{axis_scatter, pose_outliers};
use crate::check::readings::{DEGENERATE_SCATTER, check_readings};
use crate::model::motion::{PosePair, Setup};
use crate::model::warning::Warning;

/// What the first poses of a stream say about how they were read: the checks `calibrate` makes
/// on a whole recording, for an online calibrator that has only its first poses.
#[derive(Debug, Clone, PartialEq)]
pub enum StreamReading {
    /// Every rotation is about one axis: X's rotation about it, and its translation along it,
    /// are not determined by these poses.
    OneAxis,
    /// The poses fit far better read another way: what to do.
    ReadWrongly(String),
    /// The poses fit as given, with sizes the setup makes unlikely.
    UnlikelySizes(Warning),
}

/// Checks the first poses of a stream as `calibrate` checks a recording: the axis spread, then
/// the readings on the poses that agree with the others (as batch does).
pub fn check_stream_readings(poses: &[PosePair], setup: Setup) -> Option<StreamReading> {
    if axis_scatter(poses, setup) < DEGENERATE_SCATTER {
        return Some(StreamReading::OneAxis);
    }
    let outliers = pose_outliers(poses, setup, 3.0).indices();
    let kept: Vec<PosePair> = (0..poses.len())
        .filter(|i| !outliers.contains(i))
        .map(|i| poses[i])
        .collect();
    let check = check_readings(&kept, setup);
    if let Some(advice) = check.advice(setup) {
        Some(StreamReading::ReadWrongly(advice))
    } else {
        check.size_warning(setup).map(StreamReading::UnlikelySizes)
    }
}
