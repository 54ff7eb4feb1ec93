//! The batch jobs: hand–eye calibration ([`batch`]), robot-world calibration ([`robot_world`]),
//! and what to record next ([`advice`]). Each strings a solver and the checks together and
//! returns a typed report.

pub mod advice;
pub mod batch;
pub mod low_dof;
pub mod robot_world;
pub mod verify;
pub mod pixels;
