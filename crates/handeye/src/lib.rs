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
//!
//! # Entry points
//! - Batch: [`calibration::calibrate`] (readings, outliers, uncertainty, held-out check: the
//!   report every face prints) on top of [`solve()`] with a [`Method`] over
//!   [`motion_pairs`].
//! - Online: [`online::OnlineCalibrator`] (the paper's selection, and with
//!   [`online::Estimator::Accumulate`] the [`tracking::Tracker`]).
//! - Robot-world (X and the target pose together, A X = Z B): [`robot_world::calibrate_robot_world`]
//!   on top of [`solve::shah`], [`solve::li`], [`solve::refine_robot_world`]; online, the sums of
//!   [`accumulate::RobotWorldAccumulator`] in every [`tracking::Tracker`] report.
//! - What to record next: [`advice::advise`]. Reading files: [`io`]; two streams:
//!   [`sync::pair_stream_files`].
//!
//! # The paper in the code
//! Zhang, Shi, Liu, "Adaptive motion selection for online hand–eye calibration":
//!
//! | the paper | where |
//! |---|---|
//! | Eq. (1): initial thresholds, means of the first N motions | `select::InitialStats::means`, Main Algorithm step 1 in `select/adaptive.rs` (`AdaptiveSelector::initial`) |
//! | Main Algorithm steps 2–7: the search for A′ and its relaxation | `AdaptiveSelector::search_first` (`select/adaptive.rs`) |
//! | steps 8–13: the search for A″ with the axis test | `AdaptiveSelector::search_second` |
//! | step 14: Andreff on (A′, A″), rmsR and rmsT | `OnlineCalibrator::calibrate` ([`online`]), [`andreff`] (`solve/andreff.rs`), [`metrics`] |
//! | step 15: the prediction after four calibrations | `AdaptiveSelector::record` → [`select::predict`] |
//! | steps 16–17: A′ ← A″ | `AdaptiveSelector::search_second` |
//! | Eq. (2)–(5): the cubic regression and its normal equations | [`select::fit`] (`select/regression.rs`) |
//! | Algorithms I, II, III: sin α₀, β₀, d₀ from rmsR / rmsT | [`select::predict`] (`select/adaptive.rs`) |
//! | sec. 2 (Shi et al.): fixed thresholds | `select::FixedSelector` (`select/fixed.rs`) |
//! | sec. 4.1: the conventional method (no selection) | `select::ConventionalSelector` (`select/conventional.rs`) |
//! | sec. 4.1: the simulation protocol | [`sim::simulate`] |
//! | sec. 4.1.1–4.1.3: accuracy, adaptability, real-time tests | [`experiment::run_experiment`] |
//! | sec. 4.1.3 / 4.5: the optimal method (refine over five motions) | `OnlineCalibrator::optimal`, [`solve::refine_from`] |
//! | sec. 4.2: residual errors on real data (no truth) | [`online::ErrorSource::Residual`], [`metrics::residual_rms`] |
//!
//! Beyond the paper: [`accumulate`] (all pairs in O(1) per pose), [`tracking`] (gating, change,
//! schedule), [`uncertainty`], [`consistency`], [`conventions`], [`holdout`], [`advice`].
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod calibrate;
pub mod check;
pub mod io;
pub mod model;
pub mod online;
pub mod sim;
pub mod solve;
pub mod track;

pub use model::error::{Degeneracy, Error, Result, TransformProblem};
pub use model::motion::{MotionFeatures, MotionPair, Pairing, PosePair, Setup, motion_pairs};
pub use model::pose::Transform;
pub use model::warning::Warning;
pub use solve::motions::{AllPairs, MotionSource};
pub use solve::{
    Calibration, Method, andreff, andreff_joint, daniilidis, horaud, park, refine, solve, tsai,
};

/// The README's Rust examples, compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../../../README.md")]
pub struct ReadmeDoctests;
