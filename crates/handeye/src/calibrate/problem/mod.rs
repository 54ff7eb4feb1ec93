//! The problems: each turns the poses (or the pixels) the pipeline read into a solution, never a
//! report. `motions`: the hand–eye problem, A X = X B over the pairing's motions; `poses`: the
//! robot-world problem, A X = Z B over every pose once; `pixels`: either problem on the target's
//! detections.

pub mod motions;
pub mod pixels;
pub mod poses;
