//! Online hand–eye calibration with adaptive motion selection, and the classical AX = XB solvers.
//!
//! # Conventions
//! - **Transforms** are [`Transform`] (`nalgebra::IsometryMatrix3<f64>`: rotation matrix and translation) named `a_from_b` (T_a_b): the pose
//!   of frame b in frame a, mapping b-coordinates into a (`p_a = a_from_b * p_b`), so products chain
//!   visibly: `a_from_c = a_from_b * b_from_c`.
//! - **Robot pose** Q_i = `base_from_gripper` (OpenCV: `R/t_gripper2base`). **Camera observation**
//!   `camera_from_target` (what PnP returns; OpenCV: `R/t_target2cam`); the paper's
//!   P_i = `target_from_camera` is its inverse.
//! - **Motions** between poses a and b: A = Q_a⁻¹ Q_b (gripper), B = P_a⁻¹ P_b (camera), and
//!   **A X = X B** ([`MotionPair`]).
//! - **X** = `gripper_from_camera` for eye-in-hand (OpenCV: `cam2gripper`). For eye-to-hand (camera
//!   fixed, target on the gripper) `gripper_from_base` takes the place of `base_from_gripper` and X is
//!   `base_from_camera` ([`Setup`]).
//! - **Units**: rotations in radians; degrees only where a name says `_deg`. Lengths in the input's
//!   unit (parameters such as `d_max` too).
//! - **Quaternions** in files are `x y z w` (ROS/TUM order); nalgebra's `Quaternion::new` takes
//!   `w, x, y, z`. Matrices in files are row-major.
//! - **Errors against truth** ([`metrics`]): `‖R̂ − R‖_F`, the angle of R̂ᵀR in degrees, and
//!   `‖t − t̂‖ / ‖t‖`; rmsR = `‖R̂ − R‖_F / 3`. Without truth, the A X − X B residuals.
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod accumulate;
pub mod calibration;
pub mod consistency;
pub mod conventions;
mod error;
pub mod experiment;
pub mod io;
pub mod metrics;
mod motion;
pub mod online;
pub mod pose;
pub mod robot_world;
pub mod select;
pub mod sim;
pub mod solve;
pub mod sync;
pub mod tracking;
pub mod uncertainty;

pub use error::{Degeneracy, Error, Result, TransformProblem};
pub use motion::{
    AllPairs, MotionFeatures, MotionPair, MotionSource, Pairing, PosePair, Setup, motion_pairs,
};
pub use pose::Transform;
pub use solve::{
    Calibration, Method, Warning, andreff, andreff_joint, daniilidis, horaud, park, refine, solve,
    tsai,
};

/// The README's Rust examples, compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../../../README.md")]
pub struct ReadmeDoctests;
