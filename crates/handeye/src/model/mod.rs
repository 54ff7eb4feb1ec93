//! The model: poses, motions, the setup, and what errors and warnings carry. The bottom layer:
//! it imports nothing else of the crate.

pub mod camera;
pub mod error;
pub mod findings;
pub mod kinematics;
pub mod motion;
pub mod names;
pub mod pose;
pub mod prior;
pub mod rotation;
pub mod saved;
pub(crate) mod station;
pub mod warning;
