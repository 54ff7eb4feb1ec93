//! Placeholder while the solver is written.

use crate::error::Result;
use crate::motion::MotionPair;
use crate::solve::Calibration;

/// Not yet implemented.
pub fn park(motions: &[MotionPair]) -> Result<Calibration> {
    let _ = motions;
    todo!()
}
