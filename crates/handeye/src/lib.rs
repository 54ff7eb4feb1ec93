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
//! - **Errors against truth** (`check::quality`): `‖R̂ − R‖_F`, the angle of R̂ᵀR in degrees, and
//!   `‖t − t̂‖ / ‖t‖`; rmsR = `‖R̂ − R‖_F / 3`. Without truth, the A X − X B residuals.
//!
//! # Entry points
//! - Batch: [`calibrate()`], the one job (readings, outliers, the problem's solve, uncertainty,
//!   checks: the [`Report`] every face prints) for every [`Problem`] of [`Options`]: hand–eye on
//!   top of [`solve()`] with a [`Method`] over [`motion_pairs`], or robot-world; from pose pairs
//!   or, on the pixels, from the target's detections with the camera's intrinsics ([`Input`]), as
//!   is [`verify()`].
//! - Online: [`OnlineCalibrator`], the one online calibrator every face drives (the paper's
//!   selection, with [`Estimator::Accumulate`] the `track::Tracker`, and on the pixels
//!   ([`OnlineCalibrator::on_pixels`]) the batch calibration on a doubling schedule).
//! - Robot-world (X and the target pose together, A X = Z B):
//!   [`calibrate()`] with [`Problem::RobotWorld`] on top of `solve::shah`, `solve::li`,
//!   `solve::refine_robot_world`; online, the sums of
//!   `solve::robot_world_accumulate::RobotWorldAccumulator` in every `track::Tracker` report.
//! - What to record next: [`advise`]. Reading any input (a pose file, two stamped streams, a
//!   ROS 2 recording): [`io::Recording`]; the readers of each format: [`io`].
//!
//! # Layers
//! The folders are the layers, each a public module: the toolbox, where a solver, a check or a
//! simulator is reached by its path (`handeye::solve::park`); the jobs and every type they return
//! are re-exported here, the facade a newcomer reads first. Each layer uses only itself and the
//! layers above it in this table (unit tests included; `tests/layers.rs` fails on an import that
//! climbs or crosses to a sibling). Errors and warnings carry plain data of the bottom layer, so no layer needs the
//! types of the one that raised them.
//!
//! | rank | layer | what it holds |
//! |---|---|---|
//! | 0 | `model/` | poses, motions, the setup; errors, warnings and the findings they carry; named enums |
//! | 1 | [`sim`] | the paper's simulation (model only), so every layer's tests can use it |
//! | 2 | `solve/` | [`Method`] and [`solve()`], every solver, the motion sources, the residuals, the accumulated all-pairs sums |
//! | 3 | `check/` | readings, outliers, the bootstrap uncertainty, held-out poses, the motions' quality |
//! | 4 | `track/` | the accumulating estimator on a stream: gating, change detection, reports |
//! | 5 | `calibrate/` | the batch jobs: poses and pixels, robot-world, verify and advice |
//! | 5 | [`rig`] | several cameras and targets in one calibration: the pose graph, what it determines, the joint solve, the loops |
//! | 6 | `online/` | the online calibrator both faces drive: the paper's selection, the accumulating estimator, the pixels on a doubling schedule |
//! | 7 | [`io`], [`experiment`] | files, two streams and their clock, ROS 2 recordings, truth files; the simulated studies (the paper's experiments, tracking, the advice's closed loop) |
//! | 8 | [`detect`] | from images to detections: the target's spec, ViSP's image folders, the points found in an image (feature `images`) and the camera's pose of them |
//!
//! # The paper in the code
//! Zhang, Shi, Liu, "Adaptive motion selection for online hand–eye calibration":
//!
//! | the paper | where |
//! |---|---|
//! | Eq. (1): initial thresholds, means of the first N motions | `select::InitialStats::means`, Main Algorithm step 1 in `online/select/adaptive.rs` (`AdaptiveSelector::initial`) |
//! | Main Algorithm steps 2–7: the search for A′ and its relaxation | `AdaptiveSelector::search_first` (`online/select/adaptive.rs`) |
//! | steps 8–13: the search for A″ with the axis test | `AdaptiveSelector::search_second` |
//! | step 14: Andreff on (A′, A″), rmsR and rmsT | `OnlineCalibrator::calibrate` (`online/`), `andreff` (`solve/andreff.rs`), `check::quality` |
//! | step 15: the prediction after four calibrations | `AdaptiveSelector::record` → `online::select::predict` |
//! | steps 16–17: A′ ← A″ | `AdaptiveSelector::search_second` |
//! | Eq. (2)–(5): the cubic regression and its normal equations | `online::select::fit` (`online/select/regression.rs`) |
//! | Algorithms I, II, III: sin α₀, β₀, d₀ from rmsR / rmsT | `online::select::predict` (`online/select/adaptive.rs`) |
//! | sec. 2 (Shi et al.): fixed thresholds | `select::FixedSelector` (`online/select/fixed.rs`) |
//! | sec. 4.1: the conventional method (no selection) | `select::ConventionalSelector` (`online/select/conventional.rs`) |
//! | sec. 4.1: the simulation protocol | [`sim::simulate`] |
//! | sec. 4.1.1–4.1.3: accuracy, adaptability, real-time tests | [`experiment::run_experiment`] |
//! | sec. 4.1.3 / 4.5: the optimal method (refine over five motions) | `OnlineCalibrator::optimal`, `solve::refine_from` |
//! | sec. 4.2: residual errors on real data (no truth) | [`ErrorSource::Residual`], `check::quality::residual_rms` |
//!
//! Beyond the paper: `solve::accumulate` (all pairs in O(1) per pose), `track/` (gating,
//! change, schedule), `check/` (readings, outliers, uncertainty, held-out poses),
//! `calibrate::advice`.
#![forbid(unsafe_code)]
#![deny(missing_docs)]

// The layers (see "# Layers" above), each a public module: the toolbox a user reaches into for a
// solver, a check or a simulator by its path (`handeye::solve::park`); the root re-exports below
// are the jobs and the types every face receives.
pub mod calibrate;
pub mod check;
pub mod detect;
pub mod experiment;
pub mod io;
pub mod model;
pub mod online;
pub mod rig;
pub mod sim;
pub mod solve;
pub mod track;

// # The public surface, layer by layer.
// Model: poses, motions, the setup, errors, warnings and what they carry.
pub use model::camera::{Detections, Frame, Intrinsics};
pub use model::error::{Degeneracy, Error, LowDofMissing, Result};
pub use model::findings::{GoalCheck, Part, Reading, Sizes, Verdict, Written, WrittenAs};
pub use model::kinematics::{DhConvention, Kinematics};
pub use model::motion::{MotionFeatures, MotionPair, Pairing, PosePair, Setup, motion_pairs};
pub use model::names::Named;
pub use model::pose::{Transform, TransformJson, TransformProblem, transform_from_matrix4};
pub use model::prior::{Component, LengthUnit, Prior, PriorValue};
pub use model::rotation::{RotationConvention, Rotations};
pub use model::saved::SavedX;
pub use model::warning::{Remedy, Warning};
// Solve: one entry, `solve(Method, motions)`.
pub use solve::motions::AllPairs;
pub use solve::{Calibration, Method, RobotWorldMethod, TsaiOptions, solve};
// Check.
pub use check::holdout::leave_one_out;
pub use check::outliers::PoseResiduals;
pub use check::quality::errors_against_truth;
pub use check::stream::StreamReading;
pub use check::systematic::{Systematic, Untested};
pub use check::uncertainty::Uncertainty;
// The jobs: batch, robot-world, advice.
pub use calibrate::advice::{Advice, AdviseOptions, Pivot, advise};
pub use calibrate::input::Input;
pub use calibrate::low_dof::LowDofReport;
pub use calibrate::options::{Fix, Options, Problem};
pub use calibrate::pipeline::calibrate;
pub use calibrate::report::{HandEyeReport, Report, ReprojectionSummary, RobotWorldReport};
pub use calibrate::verify::{Consistency, Verification, verify};
pub use model::findings::Assessment;
// Online: the paper's calibrator and the accumulating estimator.
pub use online::select::{AdaptiveParams, Selection, Thresholds};
pub use online::{AlphaMin, OnlineSettings};
pub use online::{ChangeFound, HeldOutPose, Name, Observed, Outputs, Record, Tell, Thinning};
pub use online::{ErrorSource, Estimator, Event, OnlineCalibrator, OnlineConfig, Unit, UnitTold};
pub use online::{Summary, Tracked};
pub use track::{Change, HeldOut, Pending, Report as TrackReport, Step, TrackOptions};

/// The README's Rust examples, compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../../../README.md")]
pub struct ReadmeDoctests;
