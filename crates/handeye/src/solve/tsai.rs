//! Placeholder while the solver is written.

use crate::error::Result;
use crate::motion::MotionPair;
use crate::solve::Calibration;

/// Options of Tsai–Lenz.
#[derive(Debug, Clone, Copy, Default)]
pub struct TsaiOptions {}

/// Not yet implemented.
pub fn tsai(motions: &[MotionPair]) -> Result<Calibration> {
    tsai_with(motions, &TsaiOptions::default())
}

/// Not yet implemented.
pub fn tsai_with(motions: &[MotionPair], options: &TsaiOptions) -> Result<Calibration> {
    let _ = (motions, options);
    todo!()
}
