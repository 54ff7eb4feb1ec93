//! The readings check on the first poses of a stream: what `calibrate` checks on a whole
//! recording, for an online calibrator that has only its first poses.

use serde::{Deserialize, Serialize};

use crate::check::outliers::{axis_scatter, pose_outliers};
use crate::check::readings::{DEGENERATE_SCATTER, check_readings};
use crate::model::findings::Written;
use crate::model::motion::{PosePair, Setup};
use crate::model::warning::Warning;

/// What the first poses of a stream say about how they were read: the checks `calibrate` makes
/// on a whole recording, for an online calibrator that has only its first poses.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum StreamReading {
    /// Every rotation of the first `poses` poses is about one axis: X's rotation about it, and
    /// its translation along it, are not determined by them.
    OneAxis {
        /// The poses checked.
        poses: usize,
    },
    /// The poses fit far better read another way: what to do.
    ReadWrongly(String),
    /// The poses fit as given, with sizes the setup makes unlikely.
    UnlikelySizes(Warning),
}

/// The words every face prints (the command line adds where `calibrate` checks the same).
impl std::fmt::Display for StreamReading {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::OneAxis { poses } => write!(
                f,
                "every rotation of the first {poses} poses is about one axis: X's rotation about it, and its translation along it, are not determined by them, whatever the calibrations say; rotate the gripper about other axes"
            ),
            Self::ReadWrongly(advice) => {
                write!(f, "the calibrations are from data read wrongly: {advice}")
            }
            Self::UnlikelySizes(w) => write!(f, "{w}"),
        }
    }
}

/// The readings check of a stream, as every face runs it: on the first [`StreamReadings::SAMPLE`]
/// poses, or at the end on a shorter stream of at least [`StreamReadings::MIN_POSES`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StreamReadings {
    setup: Setup,
    first: Vec<PosePair>,
    done: bool,
}

impl StreamReadings {
    /// The poses the check reads.
    pub const SAMPLE: usize = 64;
    /// The fewest poses a check at the end of a stream reads.
    pub const MIN_POSES: usize = 16;

    /// A check of a stream in `setup`.
    pub fn new(setup: Setup) -> Self {
        Self {
            setup,
            first: Vec::with_capacity(Self::SAMPLE),
            done: false,
        }
    }

    /// Takes the next pose; at the [`Self::SAMPLE`]-th, what the check found.
    pub fn push(&mut self, pose: &PosePair) -> Option<StreamReading> {
        if self.done {
            return None;
        }
        self.first.push(*pose);
        if self.first.len() < Self::SAMPLE {
            return None;
        }
        self.finish()
    }

    /// At the end of the stream: what the check found, if it has not run yet and the stream has
    /// at least [`Self::MIN_POSES`] poses. It runs once.
    pub fn finish(&mut self) -> Option<StreamReading> {
        if std::mem::replace(&mut self.done, true) || self.first.len() < Self::MIN_POSES {
            return None;
        }
        let first = std::mem::take(&mut self.first);
        check_stream_readings(&first, self.setup)
    }
}

/// Checks the first poses of a stream as `calibrate` checks a recording: the axis spread, then
/// the readings on the poses that agree with the others (as batch does).
pub(crate) fn check_stream_readings(poses: &[PosePair], setup: Setup) -> Option<StreamReading> {
    if axis_scatter(poses, setup) < DEGENERATE_SCATTER {
        return Some(StreamReading::OneAxis { poses: poses.len() });
    }
    let outliers = pose_outliers(poses, setup, 3.0).indices();
    let kept: Vec<PosePair> = (0..poses.len())
        .filter(|i| !outliers.contains(i))
        .map(|i| poses[i])
        .collect();
    let check = check_readings(&kept, setup, Written::NAMED);
    if let Some(advice) = check.advice(setup) {
        Some(StreamReading::ReadWrongly(advice))
    } else {
        check.size_warning(setup).map(StreamReading::UnlikelySizes)
    }
}
