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

/// Other projects' data, read in place from the shared folder: the tests' one rule, here at the
/// bottom layer so that every layer's unit tests may use it (`tests/shared_data/mod.rs`).
#[cfg(test)]
#[path = "../../tests/shared_data/mod.rs"]
pub(crate) mod shared_data;
