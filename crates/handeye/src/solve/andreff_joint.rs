//! Placeholder while the solver is written.

use crate::error::Result;
use crate::motion::MotionPair;
use crate::solve::Calibration;

/// Not yet implemented.
pub fn andreff_joint(motions: &[MotionPair]) -> Result<Calibration> {
    let _ = motions;
    todo!()
}
