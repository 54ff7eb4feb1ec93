//! Hand–eye calibration on the pixels: X and the target's pose that minimise the reprojection error
//! of the detections, the robot poses as given.
//!
//! Every frame i gives the camera's view of the target through the robot:
//! ```text
//! camera_from_target_i = X⁻¹ M_i Y
//! ```
//! with, eye-in-hand, X = `gripper_from_camera`, M_i = Q_i⁻¹ = `gripper_from_base`, Y =
//! `base_from_target`; eye-to-hand, X = `base_from_camera`, M_i = Q_i = `base_from_gripper`, Y =
//! `gripper_from_target`. A target point P projects to π(X⁻¹ M_i Y P) (the camera model of
//! [`Intrinsics`]); the residual is that pixel minus its detection. Levenberg–Marquardt
//! (`levenberg_marquardt`) over the 12 parameters of X and Y minimises a robust (Cauchy) cost of
//! the residuals, then plain least squares over the detections it kept (those within
//! [`INLIER_SIGMAS`] of the robust noise level), whose Jacobian gives the covariance.
//!
//! The start comes from the pose-based solution: a camera pose per frame (the recording's
//! `camera_from_target`, and the two poses of a planar target that fit the pixels, the planar
//! ambiguity), the pose of each frame chosen by its agreement with the robot's motion (not by the
//! smaller residual alone), Andreff's X over every pair of frames, and Y averaged over the frames.
//!
//! # References
//! R. Horaud, F. Dornaika, "Hand-eye calibration", IJRR 14(3), 1995 (reprojection form, sec. 6);
//! K. H. Strobl, G. Hirzinger, "Optimal hand-eye calibration", IROS 2006; T. Collins, A. Bartoli,
//! "Infinitesimal Plane-Based Pose Estimation", IJCV 109, 2014 (the two poses of a planar target);
//! R. Hartley, A. Zisserman, "Multiple View Geometry", 2nd ed., alg. 4.2 (normalised DLT).

use nalgebra::{Matrix3, Matrix6, SMatrix, SVector, SymmetricEigen, Vector2, Vector3, Vector6};
use serde::{Deserialize, Serialize};

#[cfg(test)]
use crate::model::camera::Detections;
use crate::model::camera::{Frame, Intrinsics, MIN_DETECTIONS};
use crate::model::error::{Error, Result};
use crate::model::motion::{PosePair, Setup};
use crate::model::pose::{Transform, exp_so3, log_so3, proj_so3, transform_from_parts};
use crate::model::station::{SAME_STATION, Stations};
use crate::solve::lm::{
    LeastSquares, Linearisation, RefineOptions, Termination, levenberg_marquardt,
};
use crate::solve::motions::AllPairs;
use crate::solve::{Calibration, Method, solve};

mod intrinsics;
pub use intrinsics::IntrinsicsSigma;
pub use intrinsics::RefinedIntrinsics;
pub(crate) use intrinsics::check_determined;

/// Settings of [`reprojection`]; `Default` gives the values documented on each field.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PixelOptions {
    /// Scale of the Cauchy loss of the first pass, pixels: a detection this far off weighs half.
    /// Default 4.
    pub cauchy_px: f64,
    /// Levenberg–Marquardt settings of both passes. Default: `RefineOptions::default` but a
    /// relative cost tolerance of 1e-12 (a pixel cost's last digits move X by far less than its
    /// noise).
    pub lm: RefineOptions,
    /// Refine fx, fy, cx, cy, k1, k2, p1, p2 with X and the target's pose (k3 held at the given
    /// value), after checking that the frames determine them (they reach the image's corners and
    /// tilt the target about both image axes). Default false.
    #[serde(default)]
    pub refine_intrinsics: bool,
}

impl Default for PixelOptions {
    fn default() -> Self {
        Self {
            cauchy_px: CAUCHY_PX,
            lm: RefineOptions {
                cost_tolerance: 1e-12,
                ..RefineOptions::default()
            },
            refine_intrinsics: false,
        }
    }
}

/// Default [`PixelOptions::cauchy_px`]: well above detection noise (0.1–1 px), well below a
/// mis-detected corner (tens of pixels).
pub const CAUCHY_PX: f64 = 4.0;

/// A detection is kept for the final least squares when its residual after the robust pass is
/// within this many robust sigmas (per coordinate; 2-D Gaussian noise leaves e^(−25/2) ≈ 4e-6 out).
pub const INLIER_SIGMAS: f64 = 5.0;

/// Floor of the inlier threshold, pixels: noise-free data keeps every detection.
const INLIER_FLOOR_PX: f64 = 0.5;

/// A point behind the camera costs as a residual of this many pixels (its Jacobian is zero).
const BEHIND_PX: f64 = 1e3;

/// The result of [`reprojection`].
#[derive(Debug, Clone, PartialEq)]
pub struct PixelSolution {
    /// X, with the method [`Method::Reprojection`].
    pub calibration: Calibration,
    /// Y: `base_from_target` eye-in-hand, `gripper_from_target` eye-to-hand.
    pub target: Transform,
    /// Covariance of X (left rotation increment `exp([δ]×) R_x` in radians, then t_x, input unit),
    /// from the Jacobian of the kept detections, the residual noise per frame (a frame's
    /// detections share its robot pose's error: the sandwich over frames) and never below the
    /// Gauss–Newton one; `None` when the normal matrix is singular.
    pub covariance: Option<Matrix6<f64>>,
    /// Covariance of Y (left rotation increment `exp([δ]×) R_y`, then t_y), from the same
    /// Jacobian and the same choice (the larger of the Gauss–Newton and the sandwich one, by Y's
    /// own trace); `None` when the normal matrix is singular.
    pub target_covariance: Option<Matrix6<f64>>,
    /// RMS reprojection error over the kept detections, pixels.
    pub rms_px: f64,
    /// RMS reprojection error of each frame (every detection of it), pixels.
    pub per_frame_rms_px: Vec<f64>,
    /// Detections left out of the final least squares as outliers, (frame, point) each.
    pub outliers: Vec<(usize, usize)>,
    /// Each detection's residual, the detected pixel less the projected one, pixels, as (frame,
    /// point, residual); a point behind the camera is left out.
    pub residuals_px: Vec<(usize, usize, [f64; 2])>,
    /// The camera pose chosen per frame for the start.
    pub start_poses: Vec<Transform>,
    /// Frames whose start pose was not the one with the smaller pixel residual (the planar
    /// ambiguity resolved by the robot's motion).
    pub flips_resolved: usize,
    /// The robot poses among the frames (frames within 1e-4 rad and 1e-4 of the distance to the
    /// target of one another are one pose, a station): the images of one station share its robot
    /// error, so the covariance counts stations, not frames.
    pub stations: usize,
    /// Robust sigma of one pixel coordinate after the robust pass, pixels.
    pub sigma_px: f64,
    /// Iterations of both passes.
    pub iterations: usize,
    /// Why the final pass stopped.
    pub termination: Termination,
    /// The intrinsics refined with X (with [`PixelOptions::refine_intrinsics`]); the covariances
    /// above then account for their being estimated.
    pub intrinsics: Option<RefinedIntrinsics>,
}

/// X and Y from the pixels (see the module docs).
///
/// Errors: [`Error::InvalidParameter`] for a frame whose detections cannot be used (fewer than
/// `MIN_DETECTIONS` points, counts that differ, a non-planar target without `camera_from_target`),
/// the errors of Andreff's solve on the start (degenerate motions).
///
/// # Example
/// ```
/// use handeye::sim::pixels::{PixelSimConfig, simulate_pixels};
/// use handeye::solve::reprojection::{PixelOptions, reprojection};
/// let sim = simulate_pixels(&PixelSimConfig::board().noise_free(), 3);
/// let s = reprojection(&sim.frames, &sim.intrinsics, sim.setup, &PixelOptions::default())?;
/// let gap = s.calibration.x.inverse() * sim.x;
/// let identity = nalgebra::Matrix3::identity();
/// assert!((gap.rotation.matrix() - identity).norm() < 1e-9 && gap.translation.vector.norm() < 1e-9);
/// # Ok::<(), handeye::Error>(())
/// ```
pub fn reprojection(
    frames: &[Frame],
    camera: &Intrinsics,
    setup: Setup,
    options: &PixelOptions,
) -> Result<PixelSolution> {
    solve_pixels(frames, camera, setup, options, None)
}

/// [`reprojection`] with the detections its final pass leaves out given (`left_out`, (frame,
/// point) each: another solve's [`PixelSolution::outliers`]) instead of chosen by this solve's
/// robust pass: fits of the same detections under other intrinsics, whose RMS compare as a
/// likelihood ratio (a solve that left out more detections would fit fewer, and look better).
pub(crate) fn reprojection_leaving_out(
    frames: &[Frame],
    camera: &Intrinsics,
    setup: Setup,
    options: &PixelOptions,
    left_out: &[(usize, usize)],
) -> Result<PixelSolution> {
    solve_pixels(frames, camera, setup, options, Some(left_out))
}

/// The solve of [`reprojection`]; `left_out` as in [`reprojection_leaving_out`].
fn solve_pixels(
    frames: &[Frame],
    camera: &Intrinsics,
    setup: Setup,
    options: &PixelOptions,
    left_out: Option<&[(usize, usize)]>,
) -> Result<PixelSolution> {
    check_frames(frames)?;
    let start = start_poses(frames, camera, setup)?;
    let span = if options.refine_intrinsics {
        Some(intrinsics::check_span(frames, camera, &start.poses)?)
    } else {
        None
    };
    let unit = length_unit(&start.poses);
    let data = Data::new(frames, camera, setup, unit);
    let x0 = scaled(&start.x, 1.0 / unit);
    let y0 = scaled(&start.y, 1.0 / unit);
    let state0 = (
        *x0.rotation.matrix(),
        x0.translation.vector,
        *y0.rotation.matrix(),
        y0.translation.vector,
    );
    let robust = Bundle {
        data: &data,
        loss: Loss::Cauchy(options.cauchy_px),
        keep: None,
    };
    let first = levenberg_marquardt(&robust, state0, &options.lm);
    let residuals = data.residual_norms(&first.state);
    let sigma_px = robust_sigma(&residuals);
    let threshold = (INLIER_SIGMAS * sigma_px).max(INLIER_FLOOR_PX);
    let keep: Vec<bool> = match left_out {
        Some(left_out) => data.index.iter().map(|i| !left_out.contains(i)).collect(),
        None => residuals.iter().map(|r| *r <= threshold).collect(),
    };
    let plain = Bundle {
        data: &data,
        loss: Loss::Squared,
        keep: Some(&keep),
    };
    let last = levenberg_marquardt(&plain, first.state, &options.lm);
    if let Some(span) = span {
        let refined = intrinsics::refine(&data, last.state, span, options.cauchy_px, &options.lm);
        return Ok(solution(
            frames,
            &data,
            start,
            unit,
            Fitted {
                state: refined.state,
                camera: refined.camera,
                keep: refined.keep,
                covariance: refined.covariance,
                sigma_px: refined.sigma_px,
                iterations: first.iterations + last.iterations + refined.iterations,
                termination: refined.termination,
                intrinsics: Some(refined.intrinsics),
            },
        ));
    }
    let covariance = plain.covariance(&last.state);
    Ok(solution(
        frames,
        &data,
        start,
        unit,
        Fitted {
            state: last.state,
            camera: *camera,
            keep,
            covariance,
            sigma_px,
            iterations: first.iterations + last.iterations,
            termination: last.termination,
            intrinsics: None,
        },
    ))
}

/// The end of a solve: X, Y, their covariances (solve unit), the camera, the detections kept.
struct Fitted {
    state: State,
    camera: Intrinsics,
    keep: Vec<bool>,
    covariance: Option<(Matrix6<f64>, Matrix6<f64>)>,
    sigma_px: f64,
    iterations: usize,
    termination: Termination,
    intrinsics: Option<RefinedIntrinsics>,
}

/// The solution of a fit, in the input's unit.
fn solution(frames: &[Frame], data: &Data, start: Start, unit: f64, fit: Fitted) -> PixelSolution {
    let Fitted {
        state,
        camera,
        keep,
        covariance,
        sigma_px,
        iterations,
        termination,
        intrinsics,
    } = fit;
    let vectors = intrinsics::residual_vectors(data, &(state, camera));
    let residuals = intrinsics::norms_of(&vectors);
    let (rms_px, per_frame_rms_px) = data.rms(&residuals, &keep);
    let residuals_px = data
        .index
        .iter()
        .zip(&vectors)
        .filter_map(|(&(f, k), r)| r.map(|r| (f, k, [r.x, r.y])))
        .collect();
    let mut outliers: Vec<(usize, usize)> = data
        .index
        .iter()
        .zip(&keep)
        .filter(|(_, k)| !**k)
        .map(|(i, _)| *i)
        .chain(data.unseeable.iter().copied())
        .collect();
    outliers.sort_unstable();
    let (covariance, target_covariance) = match covariance {
        Some((x, y)) => (Some(in_unit(x, unit)), Some(in_unit(y, unit))),
        None => (None, None),
    };
    let x = transform_from_parts(&state.0, &(state.1 * unit));
    let target = transform_from_parts(&state.2, &(state.3 * unit));
    PixelSolution {
        calibration: Calibration {
            x,
            method: Method::Reprojection,
            motions: frames.len(),
            conditioning: start.conditioning,
            warnings: start.warnings,
        },
        target,
        covariance,
        target_covariance,
        rms_px,
        per_frame_rms_px,
        outliers,
        residuals_px,
        start_poses: start.poses,
        flips_resolved: start.flips_resolved,
        stations: data.stations.count,
        sigma_px,
        iterations,
        termination,
        intrinsics,
    }
}

/// The target's pose fitted to the pixels with X held fixed ([`target_with_x`]).
#[derive(Debug, Clone, PartialEq)]
pub struct TargetFit {
    /// Y fitted with X fixed.
    pub target: Transform,
    /// RMS reprojection error over the detections the solve kept, pixels.
    pub rms_px: f64,
    /// Each frame's RMS over its detections the solve kept (0 for a frame with none), pixels.
    pub per_frame_rms_px: Vec<f64>,
}

/// Fits only the target's pose Y to the pixels with X fixed at `x`, over the detections `solved`
/// kept (its mis-detections left out), started from `solved`'s Y: how well a given X (a saved one)
/// explains the pixels of a recording, against [`PixelSolution`]'s own X. Plain least squares
/// with the Levenberg–Marquardt settings of `options`.
pub fn target_with_x(
    frames: &[Frame],
    camera: &Intrinsics,
    setup: Setup,
    x: &Transform,
    solved: &PixelSolution,
    options: &PixelOptions,
) -> TargetFit {
    let unit = length_unit(&solved.start_poses);
    let data = Data::new(frames, camera, setup, unit);
    let keep: Vec<bool> = data
        .index
        .iter()
        .map(|i| !solved.outliers.contains(i))
        .collect();
    let problem = TargetOnly {
        bundle: Bundle {
            data: &data,
            loss: Loss::Squared,
            keep: Some(&keep),
        },
        x: (*x.rotation.matrix(), x.translation.vector / unit),
    };
    let y0 = scaled(&solved.target, 1.0 / unit);
    let end = levenberg_marquardt(
        &problem,
        (*y0.rotation.matrix(), y0.translation.vector),
        &options.lm,
    );
    let state = (problem.x.0, problem.x.1, end.state.0, end.state.1);
    let residuals = data.residual_norms(&state);
    let (rms_px, _) = data.rms(&residuals, &keep);
    let per_frame_rms_px = data
        .starts
        .windows(2)
        .map(|w| {
            let kept: Vec<f64> = (w[0]..w[1])
                .filter(|k| keep[*k])
                .map(|k| residuals[k])
                .collect();
            let n = kept.len().max(1) as f64;
            (kept.iter().map(|r| r * r).sum::<f64>() / n).sqrt()
        })
        .collect();
    TargetFit {
        target: transform_from_parts(&end.state.0, &(end.state.1 * unit)),
        rms_px,
        per_frame_rms_px,
    }
}

/// Refuses frames whose detections cannot be used, naming the frame.
fn check_frames(frames: &[Frame]) -> Result<()> {
    for (i, f) in frames.iter().enumerate() {
        let d = &f.detections;
        let problem = if d.target.len() != d.pixels.len() {
            Some(format!(
                "{} target points but {} pixels",
                d.target.len(),
                d.pixels.len()
            ))
        } else if d.target.len() < MIN_DETECTIONS {
            Some(format!(
                "{} detections, at least {MIN_DETECTIONS} needed",
                d.target.len()
            ))
        } else if d
            .target
            .iter()
            .flatten()
            .chain(d.pixels.iter().flatten())
            .any(|v| !v.is_finite())
        {
            Some("a number that is not finite".into())
        } else {
            None
        };
        if let Some(p) = problem {
            return Err(Error::InvalidParameter {
                name: "detections",
                message: format!("frame {i}: {p}"),
            });
        }
    }
    Ok(())
}

/// M_i of a frame: `gripper_from_base` eye-in-hand, `base_from_gripper` eye-to-hand.
fn motion_of(setup: Setup, base_from_gripper: &Transform) -> Transform {
    match setup {
        Setup::EyeInHand => base_from_gripper.inverse(),
        Setup::EyeToHand => *base_from_gripper,
    }
}

/// A transform with its translation multiplied by `s`.
fn scaled(t: &Transform, s: f64) -> Transform {
    transform_from_parts(t.rotation.matrix(), &(t.translation.vector * s))
}

/// The length unit of the solve: the median distance from the camera to the target.
fn length_unit(poses: &[Transform]) -> f64 {
    let mut d: Vec<f64> = poses.iter().map(|p| p.translation.vector.norm()).collect();
    d.sort_by(f64::total_cmp);
    let m = d.get(d.len() / 2).copied().unwrap_or(1.0);
    if m.is_finite() && m > 0.0 { m } else { 1.0 }
}

/// A covariance of (δ, t) with t in units of `unit`, in the input's unit.
fn in_unit(c: Matrix6<f64>, unit: f64) -> Matrix6<f64> {
    let u = Matrix6::from_diagonal(&Vector6::new(1.0, 1.0, 1.0, unit, unit, unit));
    u * c * u
}

/// σ of one pixel coordinate from the residual norms: for 2-D Gaussian noise of σ per coordinate
/// the norm's median is σ √(2 ln 2).
fn robust_sigma(norms: &[f64]) -> f64 {
    let mut n: Vec<f64> = norms.to_vec();
    n.sort_by(f64::total_cmp);
    let median = n.get(n.len() / 2).copied().unwrap_or(0.0);
    median / (2.0 * std::f64::consts::LN_2).sqrt()
}

// ---------------------------------------------------------------------------------------------
// The start: a camera pose per frame, chosen by the robot's motion.
// ---------------------------------------------------------------------------------------------

/// The start of the bundle: X, Y, the camera pose chosen per frame.
struct Start {
    x: Transform,
    y: Transform,
    poses: Vec<Transform>,
    flips_resolved: usize,
    conditioning: f64,
    warnings: Vec<crate::model::warning::Warning>,
}

/// Rounds of choosing each frame's pose by its agreement with the robot and re-solving.
const CHOICE_ROUNDS: usize = 6;

fn start_poses(frames: &[Frame], camera: &Intrinsics, setup: Setup) -> Result<Start> {
    let candidates: Vec<Vec<(Transform, f64)>> = frames
        .iter()
        .enumerate()
        .map(|(i, f)| candidates(f, camera).map_err(|m| frame_error(i, m)))
        .collect::<Result<_>>()?;
    // First the pose with the smaller residual in each frame, then the one closest to what the
    // robot's motion and the current X, Y predict, until the choice settles.
    let smallest: Vec<usize> = candidates
        .iter()
        .map(|c| {
            (0..c.len())
                .min_by(|&a, &b| c[a].1.total_cmp(&c[b].1))
                .unwrap_or(0)
        })
        .collect();
    let mut chosen = smallest.clone();
    let mut solved = solve_start(frames, &candidates, &chosen, setup)?;
    for _ in 0..CHOICE_ROUNDS {
        let next: Vec<usize> = frames
            .iter()
            .zip(&candidates)
            .map(|(f, c)| {
                let predicted =
                    solved.0.x.inverse() * motion_of(setup, &f.base_from_gripper) * solved.1;
                (0..c.len())
                    .min_by(|&a, &b| {
                        pose_gap(&c[a].0, &predicted).total_cmp(&pose_gap(&c[b].0, &predicted))
                    })
                    .unwrap_or(0)
            })
            .collect();
        if next == chosen {
            break;
        }
        chosen = next;
        solved = solve_start(frames, &candidates, &chosen, setup)?;
    }
    let poses: Vec<Transform> = chosen
        .iter()
        .zip(&candidates)
        .map(|(&k, c)| c[k].0)
        .collect();
    let flips_resolved = chosen
        .iter()
        .zip(&smallest)
        .zip(&candidates)
        .filter(|((a, b), c)| a != b && !same_pose(&c[**a].0, &c[**b].0))
        .count();
    let (calibration, y) = solved;
    Ok(Start {
        x: calibration.x,
        y,
        poses,
        flips_resolved,
        conditioning: calibration.conditioning,
        warnings: calibration.warnings,
    })
}

/// The camera pose of each frame that [`reprojection`] starts from: the PnP pose (or the record's
/// own `camera_from_target`) chosen by the robot's motion. Where that choice cannot be made (the
/// motions do not determine X), each frame's pose with the smaller pixel residual; where a frame
/// has no usable detections, its own `camera_from_target`, or the identity.
pub fn start_camera_poses(frames: &[Frame], camera: &Intrinsics, setup: Setup) -> Vec<Transform> {
    if let Ok(start) = start_poses(frames, camera, setup) {
        return start.poses;
    }
    frames
        .iter()
        .map(|f| {
            candidates(f, camera)
                .ok()
                .and_then(|c| c.into_iter().min_by(|a, b| a.1.total_cmp(&b.1)))
                .map(|(pose, _)| pose)
                .or(f.camera_from_target)
                .unwrap_or_default()
        })
        .collect()
}

fn frame_error(i: usize, message: String) -> Error {
    Error::InvalidParameter {
        name: "detections",
        message: format!("frame {i}: {message}"),
    }
}

/// The gap between two poses of the target seen by the camera: rotation angle (radians) plus the
/// distance of the origins relative to the distance from the camera.
fn pose_gap(a: &Transform, b: &Transform) -> f64 {
    let r = log_so3(&(a.rotation.matrix() * b.rotation.matrix().transpose())).norm();
    let d = (a.translation.vector - b.translation.vector).norm()
        / b.translation.vector.norm().max(f64::MIN_POSITIVE);
    r + d
}

fn same_pose(a: &Transform, b: &Transform) -> bool {
    pose_gap(a, b) < 1e-6
}

/// Andreff's X over every pair of frames with the chosen poses, and Y averaged over the frames.
fn solve_start(
    frames: &[Frame],
    candidates: &[Vec<(Transform, f64)>],
    chosen: &[usize],
    setup: Setup,
) -> Result<(Calibration, Transform)> {
    let poses: Vec<PosePair> = frames
        .iter()
        .zip(chosen.iter().zip(candidates))
        .map(|(f, (&k, c))| PosePair {
            base_from_gripper: f.base_from_gripper,
            camera_from_target: c[k].0,
        })
        .collect();
    let calibration = solve(Method::Andreff, &AllPairs::new(&poses, setup))?;
    // Y_i = M_i⁻¹ X C_i; Y = the rotation nearest their mean, the mean translation.
    let mut r = Matrix3::zeros();
    let mut t = Vector3::zeros();
    for (f, p) in frames.iter().zip(&poses) {
        let y =
            motion_of(setup, &f.base_from_gripper).inverse() * calibration.x * p.camera_from_target;
        r += y.rotation.matrix();
        t += y.translation.vector;
    }
    let y = transform_from_parts(&proj_so3(&r), &(t / frames.len() as f64));
    Ok((calibration, y))
}

/// The camera poses a frame may have: the recording's own, and the two poses of a planar target
/// that fit its pixels, each with its pixel cost ½Σ|r|².
/// The camera's candidate poses of a frame's target, each with its pixel cost: the recording's own
/// `camera_from_target` if any, and the planar target's two poses that fit its pixels
/// ([`planar_poses`]); an error when none can be had.
pub fn candidates(
    frame: &Frame,
    camera: &Intrinsics,
) -> std::result::Result<Vec<(Transform, f64)>, String> {
    // The detections a camera could have made: a pixel beyond is a mis-detection, which the
    // bundle leaves out too.
    let (points, pixels): (Vec<Vector3<f64>>, Vec<Vector2<f64>>) = frame
        .detections
        .target
        .iter()
        .zip(&frame.detections.pixels)
        .filter(|(_, u)| camera.could_see(u))
        .map(|(p, u)| (Vector3::from(*p), Vector2::from(*u)))
        .unzip();
    if points.len() < MIN_DETECTIONS && frame.camera_from_target.is_none() {
        return Err(format!(
            "{} of its {} detections within the image, at least {MIN_DETECTIONS} needed",
            points.len(),
            frame.detections.pixels.len()
        ));
    }
    let mut out = Vec::new();
    if let Some(given) = frame.camera_from_target {
        out.push((given, pose_cost(&given, &points, &pixels, camera)));
    }
    match planar_poses(&points, &pixels, camera) {
        Ok(poses) => out.extend(poses),
        Err(e) if out.is_empty() => return Err(e),
        Err(_) => {}
    }
    Ok(out)
}

/// ½Σ|π(C P) − u|² of a camera pose.
fn pose_cost(
    c: &Transform,
    points: &[Vector3<f64>],
    pixels: &[Vector2<f64>],
    camera: &Intrinsics,
) -> f64 {
    points
        .iter()
        .zip(pixels)
        .map(|(p, u)| {
            let q = c * nalgebra::Point3::from(*p);
            match camera.project(&q.coords) {
                Some(pr) => 0.5 * (pr.pixel - u).norm_squared(),
                None => 0.5 * BEHIND_PX * BEHIND_PX,
            }
        })
        .sum()
}

/// Smallest over largest singular value of the target's centred points below which it is planar.
const PLANAR: f64 = 1e-3;

/// Why a target whose points are on one line has no pose.
pub(crate) const ON_ONE_LINE: &str =
    "the target's points are all on one line: a pose needs points that span a plane";

/// The centre of the points, the eigen-decomposition of their scatter, and its eigenvalues'
/// order, largest first.
fn spread(
    points: &[Vector3<f64>],
) -> (Vector3<f64>, SymmetricEigen<f64, nalgebra::U3>, [usize; 3]) {
    let n = points.len().max(1) as f64;
    let centre = points.iter().fold(Vector3::zeros(), |a, p| a + p) / n;
    let mut scatter = Matrix3::zeros();
    for p in points {
        let d = p - centre;
        scatter += d * d.transpose();
    }
    let eigen = SymmetricEigen::new(scatter);
    let mut order = [0, 1, 2];
    order.sort_by(|&a, &b| eigen.eigenvalues[b].total_cmp(&eigen.eigenvalues[a]));
    (centre, eigen, order)
}

/// Whether the target's points are all on one line (or one point), so that no pose fits them:
/// the second singular value of the centred points below [`PLANAR`] of the first.
pub(crate) fn on_one_line(points: &[Vector3<f64>]) -> bool {
    let (_, eigen, order) = spread(points);
    let largest = eigen.eigenvalues[order[0]];
    largest.is_nan() || largest <= 0.0 || eigen.eigenvalues[order[1]] <= PLANAR * PLANAR * largest
}

/// The two poses of a planar target that fit the pixels (the planar ambiguity), each refined on
/// the pixels, with its cost.
///
/// The homography of the plane to the undistorted image (normalised DLT, Hartley and Zisserman
/// alg. 4.2) gives the first pose; the second is its mirror in the line of sight: the target's
/// normal reflected about the direction from the camera to the target's centre (the two poses
/// of IPPE, Collins and Bartoli 2014, sec. 4, to first order). Both are refined by
/// Levenberg–Marquardt on the pixels.
pub fn planar_poses(
    points: &[Vector3<f64>],
    pixels: &[Vector2<f64>],
    camera: &Intrinsics,
) -> std::result::Result<Vec<(Transform, f64)>, String> {
    let (centre, eigen, order) = spread(points);
    let (largest, smallest) = (eigen.eigenvalues[order[0]], eigen.eigenvalues[order[2]]);
    if on_one_line(points) {
        return Err(ON_ONE_LINE.into());
    }
    if smallest.max(0.0).sqrt() > PLANAR * largest.sqrt() {
        return Err(
            "the target is not planar: give `camera_from_target` with its detections (handeye computes the pose of planar targets only)"
                .into(),
        );
    }
    // target_from_plane: the plane's x, y axes are the two largest directions, z their cross.
    let ex = eigen.eigenvectors.column(order[0]).into_owned();
    let ey = eigen.eigenvectors.column(order[1]).into_owned();
    let r_tp = Matrix3::from_columns(&[ex, ey, ex.cross(&ey)]);
    let target_from_plane = transform_from_parts(&r_tp, &centre);
    let plane: Vec<Vector2<f64>> = points
        .iter()
        .map(|p| {
            let q = r_tp.transpose() * (p - centre);
            Vector2::new(q.x, q.y)
        })
        .collect();
    let image: Vec<Vector2<f64>> = pixels.iter().map(|u| camera.normalised(u)).collect();
    let h = homography(&plane, &image).ok_or("the pixels do not determine a homography")?;
    let camera_from_plane = pose_from_homography(&h);
    let first = camera_from_plane * target_from_plane.inverse();
    let first = refine_pose(&first, points, pixels, camera);
    let second = mirrored(&first, &(first * nalgebra::Point3::from(centre)).coords);
    let second = refine_pose(&second, points, pixels, camera);
    Ok([first, second]
        .into_iter()
        .map(|c| (c, pose_cost(&c, points, pixels, camera)))
        .collect())
}

/// The pose of a planar target mirrored in the line of sight to its centre `c` (camera frame):
/// the rotation turning its normal n to 2(n·v)v − n, v = c/|c|, applied about the centre.
fn mirrored(camera_from_target: &Transform, c: &Vector3<f64>) -> Transform {
    let r = camera_from_target.rotation.matrix();
    // The normal: the least-spread direction, the plane's z (any target: the rotation of the
    // pose carries the target's plane normal; use the third column of target_from_plane's image,
    // recovered as the axis that the pixels see edge-on least).
    let v = c.normalize();
    let n = r.column(2).into_owned();
    let n = if n.dot(&v) > 0.0 { n } else { -n };
    let reflected = 2.0 * n.dot(&v) * v - n;
    let axis = n.cross(&reflected);
    let angle = axis.norm().atan2(n.dot(&reflected));
    let turn = if axis.norm() > 0.0 {
        exp_so3(&(axis.normalize() * angle))
    } else {
        Matrix3::identity()
    };
    let rotation = turn * r;
    // Keep the centre where it is: C' P = R' P + t', with C' c_t = c.
    let c_t = camera_from_target.inverse() * nalgebra::Point3::from(*c);
    let t = c - rotation * c_t.coords;
    transform_from_parts(&rotation, &t)
}

/// The homography from plane points to image points (normalised DLT).
fn homography(from: &[Vector2<f64>], to: &[Vector2<f64>]) -> Option<Matrix3<f64>> {
    let (nf, tf) = normalising(from)?;
    let (nt, tt) = normalising(to)?;
    let mut ata = SMatrix::<f64, 9, 9>::zeros();
    for (a, b) in tf.iter().zip(&tt) {
        let rows = [
            [a.x, a.y, 1.0, 0.0, 0.0, 0.0, -b.x * a.x, -b.x * a.y, -b.x],
            [0.0, 0.0, 0.0, a.x, a.y, 1.0, -b.y * a.x, -b.y * a.y, -b.y],
        ];
        for row in rows {
            let r = SVector::<f64, 9>::from(row);
            ata += r * r.transpose();
        }
    }
    let eigen = SymmetricEigen::new(ata);
    let h = eigen
        .eigenvectors
        .column(eigen.eigenvalues.imin())
        .into_owned();
    let hn = Matrix3::new(h[0], h[1], h[2], h[3], h[4], h[5], h[6], h[7], h[8]);
    let h = nt.try_inverse()? * hn * nf;
    h.iter().all(|v| v.is_finite()).then_some(h)
}

/// Hartley's normalisation: centroid to the origin, mean distance √2; the matrix and the points.
fn normalising(p: &[Vector2<f64>]) -> Option<(Matrix3<f64>, Vec<Vector2<f64>>)> {
    let n = p.len() as f64;
    let c = p.iter().fold(Vector2::zeros(), |a, q| a + q) / n;
    let mean = p.iter().map(|q| (q - c).norm()).sum::<f64>() / n;
    if mean <= 0.0 || !mean.is_finite() {
        return None;
    }
    let s = std::f64::consts::SQRT_2 / mean;
    let m = Matrix3::new(s, 0.0, -s * c.x, 0.0, s, -s * c.y, 0.0, 0.0, 1.0);
    Some((m, p.iter().map(|q| (q - c) * s).collect()))
}

/// camera_from_plane from H ~ [r1 r2 t] (Zhang 2000, sec. 3.1), the target in front (t_z > 0).
fn pose_from_homography(h: &Matrix3<f64>) -> Transform {
    let h1 = h.column(0).into_owned();
    let h2 = h.column(1).into_owned();
    let h3 = h.column(2).into_owned();
    let mut lambda = 2.0 / (h1.norm() + h2.norm());
    if h3.z * lambda < 0.0 {
        lambda = -lambda;
    }
    let r1 = h1 * lambda;
    let r2 = h2 * lambda;
    let r = proj_so3(&Matrix3::from_columns(&[r1, r2, r1.cross(&r2)]));
    transform_from_parts(&r, &(h3 * lambda))
}

/// One camera pose refined on the pixels: Levenberg–Marquardt over `exp([δ]×) R`, t.
fn refine_pose(
    start: &Transform,
    points: &[Vector3<f64>],
    pixels: &[Vector2<f64>],
    camera: &Intrinsics,
) -> Transform {
    let problem = SinglePose {
        points,
        pixels,
        camera,
    };
    // A start only: the bundle refines it; a relative cost change of 1e-10 is far below noise.
    let options = RefineOptions {
        max_iterations: 20,
        cost_tolerance: 1e-10,
        step_tolerance: 1e-12,
        ..RefineOptions::default()
    };
    let end = levenberg_marquardt(
        &problem,
        (*start.rotation.matrix(), start.translation.vector),
        &options,
    );
    transform_from_parts(&end.state.0, &end.state.1)
}

/// The pose of the target seen by the camera, on one frame's pixels.
struct SinglePose<'a> {
    points: &'a [Vector3<f64>],
    pixels: &'a [Vector2<f64>],
    camera: &'a Intrinsics,
}

impl LeastSquares<6> for SinglePose<'_> {
    type State = (Matrix3<f64>, Vector3<f64>);

    fn linearise(&self, (r, t): &Self::State) -> Linearisation<6> {
        let mut lin = Linearisation {
            jtj: Matrix6::zeros(),
            jtr: Vector6::zeros(),
            cost: 0.0,
        };
        for (p, u) in self.points.iter().zip(self.pixels) {
            let rp = r * p;
            let Some(pr) = self.camera.project(&(rp + t)) else {
                lin.cost += 0.5 * BEHIND_PX * BEHIND_PX;
                continue;
            };
            let res = pr.pixel - u;
            // ∂p/∂δ = −[R P]×, ∂p/∂t = I.
            let mut j = SMatrix::<f64, 2, 6>::zeros();
            j.fixed_view_mut::<2, 3>(0, 0)
                .copy_from(&(pr.jacobian * -rp.cross_matrix()));
            j.fixed_view_mut::<2, 3>(0, 3).copy_from(&pr.jacobian);
            lin.jtj += j.transpose() * j;
            lin.jtr += j.transpose() * res;
            lin.cost += 0.5 * res.norm_squared();
        }
        lin
    }

    fn step(&self, (r, t): &Self::State, delta: &Vector6<f64>) -> Self::State {
        let w: Vector3<f64> = delta.fixed_rows::<3>(0).into_owned();
        (proj_so3(&(exp_so3(&w) * r)), t + delta.fixed_rows::<3>(3))
    }

    fn cost_drop(&self, _: &Self::State, to: &Self::State, cost: f64) -> f64 {
        let c = transform_from_parts(&to.0, &to.1);
        cost - pose_cost(&c, self.points, self.pixels, self.camera)
    }

    fn size(&self, (_, t): &Self::State) -> f64 {
        1.0 + t.norm()
    }
}

// ---------------------------------------------------------------------------------------------
// The bundle: X and Y on every frame's pixels.
// ---------------------------------------------------------------------------------------------

/// The data of the bundle, lengths in the solve's unit: per frame M_i, per detection its frame,
/// point and pixel.
struct Data<'a> {
    camera: &'a Intrinsics,
    /// M_i (rotation, translation) per frame.
    motions: Vec<(Matrix3<f64>, Vector3<f64>)>,
    /// The first detection of each frame, and one past the last.
    starts: Vec<usize>,
    points: Vec<Vector3<f64>>,
    pixels: Vec<Vector2<f64>>,
    /// (frame, point within the frame) of each detection.
    index: Vec<(usize, usize)>,
    /// (frame, point) of the detections no camera could have made ([`Intrinsics::could_see`]):
    /// not in the fit, listed with its outliers.
    unseeable: Vec<(usize, usize)>,
    /// The robot pose of each frame ([`Stations`]): frames at one pose share its error.
    stations: Stations,
}

/// The middle of the sandwich covariance, Σ_s g_s g_sᵀ over stations (g_s the sum of the
/// per-frame Jᵀr of a station's frames: their errors are one), and the number of stations.
pub(super) fn station_meat<const N: usize>(
    per_frame: &[SVector<f64, N>],
    stations: &Stations,
) -> (SMatrix<f64, N, N>, usize) {
    let count = stations.count;
    let mut sums = vec![SVector::<f64, N>::zeros(); count];
    for (g, &s) in per_frame.iter().zip(&stations.of) {
        sums[s] += g;
    }
    let meat = sums
        .iter()
        .fold(SMatrix::<f64, N, N>::zeros(), |m, g| m + g * g.transpose());
    (meat, count)
}

/// X (R_x, t_x) and Y (R_y, t_y).
type State = (Matrix3<f64>, Vector3<f64>, Matrix3<f64>, Vector3<f64>);

impl<'a> Data<'a> {
    fn new(frames: &[Frame], camera: &'a Intrinsics, setup: Setup, unit: f64) -> Self {
        let total: usize = frames.iter().map(|f| f.detections.target.len()).sum();
        let mut data = Data {
            camera,
            motions: Vec::with_capacity(frames.len()),
            starts: Vec::with_capacity(frames.len() + 1),
            points: Vec::with_capacity(total),
            pixels: Vec::with_capacity(total),
            index: Vec::with_capacity(total),
            unseeable: Vec::new(),
            stations: Stations {
                of: Vec::new(),
                count: 0,
            },
        };
        for (i, f) in frames.iter().enumerate() {
            let m = motion_of(setup, &f.base_from_gripper);
            data.motions
                .push((*m.rotation.matrix(), m.translation.vector / unit));
            data.starts.push(data.points.len());
            for (k, (p, u)) in f
                .detections
                .target
                .iter()
                .zip(&f.detections.pixels)
                .enumerate()
            {
                if !camera.could_see(u) {
                    data.unseeable.push((i, k));
                    continue;
                }
                data.points.push(Vector3::from(*p) / unit);
                data.pixels.push(Vector2::from(*u));
                data.index.push((i, k));
            }
        }
        data.starts.push(data.points.len());
        // The solve's unit is the median distance to the target: the tolerance is SAME_STATION of it.
        data.stations = Stations::of_motions(&data.motions, SAME_STATION);
        data
    }

    /// Visits every detection of every frame with its frame, its number, the point in the
    /// camera, and the Jacobian of the point in the camera with respect to the 12 parameters
    /// (when `jacobian`).
    fn each(
        &self,
        s: &State,
        jacobian: bool,
        mut visit: impl FnMut(usize, usize, &Vector3<f64>, &SMatrix<f64, 3, 12>),
    ) {
        let (r_x, t_x, r_y, t_y) = s;
        let r_xt = r_x.transpose();
        let mut j = SMatrix::<f64, 3, 12>::zeros();
        for (i, (r_m, t_m)) in self.motions.iter().enumerate() {
            // p_c = R_xᵀ (R_m (R_y P + t_y) + t_m − t_x)
            let a = r_xt * r_m;
            let b = r_xt * (t_m - t_x);
            if jacobian {
                j.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-r_xt));
                j.fixed_view_mut::<3, 3>(0, 9).copy_from(&a);
            }
            for k in self.starts[i]..self.starts[i + 1] {
                let ryp = r_y * self.points[k];
                let w = ryp + t_y;
                let p_c = a * w + b;
                if jacobian {
                    // ∂p/∂α = R_xᵀ [q − t_x]×, q − t_x = R_x p_c; ∂p/∂ε = −A [R_y P]×.
                    let q = r_x * p_c;
                    j.fixed_view_mut::<3, 3>(0, 0)
                        .copy_from(&(r_xt * q.cross_matrix()));
                    j.fixed_view_mut::<3, 3>(0, 6)
                        .copy_from(&(-a * ryp.cross_matrix()));
                }
                visit(i, k, &p_c, &j);
            }
        }
    }

    /// |π(p) − u| per detection, pixels (a point behind the camera: [`BEHIND_PX`]).
    fn residual_norms(&self, s: &State) -> Vec<f64> {
        let mut out = Vec::with_capacity(self.points.len());
        self.each(s, false, |_, k, p, _| {
            out.push(if p.z > 0.0 {
                (self.camera.pixel(p) - self.pixels[k]).norm()
            } else {
                BEHIND_PX
            });
        });
        out
    }

    /// RMS over the kept detections, and per frame over all of its detections.
    fn rms(&self, norms: &[f64], keep: &[bool]) -> (f64, Vec<f64>) {
        let (mut sum, mut count) = (0.0, 0usize);
        for (r, k) in norms.iter().zip(keep) {
            if *k {
                sum += r * r;
                count += 1;
            }
        }
        let per_frame = self
            .starts
            .windows(2)
            .map(|w| {
                let n = (w[1] - w[0]).max(1) as f64;
                (norms[w[0]..w[1]].iter().map(|r| r * r).sum::<f64>() / n).sqrt()
            })
            .collect();
        ((sum / count.max(1) as f64).sqrt(), per_frame)
    }
}

/// The loss of a residual's squared norm s: ½s, or Cauchy's ½c² ln(1 + s/c²).
#[derive(Clone, Copy)]
enum Loss {
    Squared,
    Cauchy(f64),
}

impl Loss {
    /// ρ(s) and the weight 2ρ'(s) of the iteratively reweighted normal equations.
    fn of(self, s: f64) -> (f64, f64) {
        match self {
            Loss::Squared => (0.5 * s, 1.0),
            Loss::Cauchy(c) => {
                let c2 = c * c;
                (0.5 * c2 * (s / c2).ln_1p(), 1.0 / (1.0 + s / c2))
            }
        }
    }
}

/// The bundle as a problem of the Levenberg–Marquardt loop.
struct Bundle<'a> {
    data: &'a Data<'a>,
    loss: Loss,
    /// The detections that count (all when `None`).
    keep: Option<&'a [bool]>,
}

impl Bundle<'_> {
    fn counts(&self, k: usize) -> bool {
        self.keep.is_none_or(|keep| keep[k])
    }

    fn cost(&self, s: &State) -> f64 {
        let mut cost = 0.0;
        self.data.each(s, false, |_, k, p, _| {
            if !self.counts(k) {
                return;
            }
            cost += if p.z > 0.0 {
                self.loss
                    .of((self.data.camera.pixel(p) - self.data.pixels[k]).norm_squared())
                    .0
            } else {
                self.loss.of(BEHIND_PX * BEHIND_PX).0
            };
        });
        cost
    }

    /// Per frame Jᵀr, and the whole JᵀJ and ½Σr² (squared loss: the final pass).
    fn gradients(&self, s: &State) -> (Vec<SVector<f64, 12>>, SMatrix<f64, 12, 12>, f64, usize) {
        let mut per_frame = vec![SVector::<f64, 12>::zeros(); self.data.motions.len()];
        let mut jtj = SMatrix::<f64, 12, 12>::zeros();
        let mut cost = 0.0;
        let mut count = 0;
        self.data.each(s, true, |i, k, p, j| {
            if !self.counts(k) {
                return;
            }
            let Some(pr) = self.data.camera.project(p) else {
                return;
            };
            let r = pr.pixel - self.data.pixels[k];
            let jp: SMatrix<f64, 2, 12> = pr.jacobian * j;
            jtj += jp.transpose() * jp;
            per_frame[i] += jp.transpose() * r;
            cost += 0.5 * r.norm_squared();
            count += 1;
        });
        (per_frame, jtj, cost, count)
    }

    /// Covariances of X's and of Y's 6 parameters: each the larger (by its trace) of the
    /// Gauss–Newton one, s² (JᵀJ)⁻¹ with s² = Σr²/(m − 12), and the sandwich over the robot's
    /// stations, H⁻¹ (Σ_s g_s g_sᵀ) H⁻¹ · S/(S − 12) with g_s = Σ_{f∈s} J_fᵀ r_f (a frame's
    /// detections share its robot pose's error, which the Gauss–Newton covariance takes as
    /// independent pixel noise; the frames of one station share it too: [`stations`]).
    fn covariance(&self, s: &State) -> Option<(Matrix6<f64>, Matrix6<f64>)> {
        let (per_frame, jtj, cost, count) = self.gradients(s);
        let (meat, stations) = station_meat(&per_frame, &self.data.stations);
        if count <= 12 || stations <= 12 {
            return None;
        }
        let inv = jtj.try_inverse()?;
        let s2 = 2.0 * cost / (count - 12) as f64;
        let classic = inv * s2;
        let sandwich = inv * meat * inv * (stations as f64 / (stations - 12) as f64);
        let scale = |c: &Matrix6<f64>| {
            c.fixed_view::<3, 3>(0, 0).trace() * 1e4 + c.fixed_view::<3, 3>(3, 3).trace()
        };
        let block = |at: usize| {
            let a: Matrix6<f64> = classic.fixed_view::<6, 6>(at, at).into_owned();
            let b: Matrix6<f64> = sandwich.fixed_view::<6, 6>(at, at).into_owned();
            let c = if scale(&b) > scale(&a) { b } else { a };
            c.iter().all(|v| v.is_finite()).then_some(c)
        };
        Some((block(0)?, block(6)?))
    }
}

/// The bundle with X held fixed: Y's 6 parameters only.
struct TargetOnly<'a> {
    bundle: Bundle<'a>,
    /// X (R_x, t_x), in the solve's unit.
    x: (Matrix3<f64>, Vector3<f64>),
}

impl TargetOnly<'_> {
    fn with_x(&self, (r_y, t_y): &(Matrix3<f64>, Vector3<f64>)) -> State {
        (self.x.0, self.x.1, *r_y, *t_y)
    }
}

impl LeastSquares<6> for TargetOnly<'_> {
    type State = (Matrix3<f64>, Vector3<f64>);

    fn linearise(&self, y: &Self::State) -> Linearisation<6> {
        let full = self.bundle.linearise(&self.with_x(y));
        Linearisation {
            jtj: full.jtj.fixed_view::<6, 6>(6, 6).into_owned(),
            jtr: full.jtr.fixed_rows::<6>(6).into_owned(),
            cost: full.cost,
        }
    }

    fn step(&self, (r_y, t_y): &Self::State, d: &Vector6<f64>) -> Self::State {
        let e: Vector3<f64> = d.fixed_rows::<3>(0).into_owned();
        (proj_so3(&(exp_so3(&e) * r_y)), t_y + d.fixed_rows::<3>(3))
    }

    fn cost_drop(&self, _: &Self::State, to: &Self::State, cost: f64) -> f64 {
        cost - self.bundle.cost(&self.with_x(to))
    }

    fn size(&self, (_, t_y): &Self::State) -> f64 {
        1.0 + self.x.1.norm() + t_y.norm()
    }
}

impl LeastSquares<12> for Bundle<'_> {
    type State = State;

    fn linearise(&self, s: &State) -> Linearisation<12> {
        let mut lin = Linearisation {
            jtj: SMatrix::<f64, 12, 12>::zeros(),
            jtr: SVector::<f64, 12>::zeros(),
            cost: 0.0,
        };
        self.data.each(s, true, |_, k, p, j| {
            if !self.counts(k) {
                return;
            }
            let Some(pr) = self.data.camera.project(p) else {
                lin.cost += self.loss.of(BEHIND_PX * BEHIND_PX).0;
                return;
            };
            let r = pr.pixel - self.data.pixels[k];
            let (rho, weight) = self.loss.of(r.norm_squared());
            let jp: SMatrix<f64, 2, 12> = pr.jacobian * j;
            let jpt = jp.transpose();
            lin.jtj += (jpt * weight) * jp;
            lin.jtr += jpt * (r * weight);
            lin.cost += rho;
        });
        lin
    }

    fn step(&self, (r_x, t_x, r_y, t_y): &State, d: &SVector<f64, 12>) -> State {
        let a: Vector3<f64> = d.fixed_rows::<3>(0).into_owned();
        let e: Vector3<f64> = d.fixed_rows::<3>(6).into_owned();
        (
            proj_so3(&(exp_so3(&a) * r_x)),
            t_x + d.fixed_rows::<3>(3),
            proj_so3(&(exp_so3(&e) * r_y)),
            t_y + d.fixed_rows::<3>(9),
        )
    }

    fn cost_drop(&self, _: &State, to: &State, cost: f64) -> f64 {
        cost - self.cost(to)
    }

    fn size(&self, (_, t_x, _, t_y): &State) -> f64 {
        1.0 + t_x.norm() + t_y.norm()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bundle's analytic Jacobian agrees with central differences of the pixels.
    #[test]
    fn bundle_jacobian_matches_central_differences() {
        let camera = Intrinsics {
            fx: 900.0,
            fy: 902.0,
            cx: 640.0,
            cy: 360.0,
            distortion: [-0.2, 0.08, 0.001, -0.0005, -0.01],
            width: 1280,
            height: 720,
        };
        let x = transform_from_parts(
            &exp_so3(&Vector3::new(0.1, -0.2, 0.3)),
            &Vector3::new(0.05, 0.02, 0.1),
        );
        let y = transform_from_parts(
            &exp_so3(&Vector3::new(2.9, 0.1, 0.0)),
            &Vector3::new(0.1, 0.05, 0.6),
        );
        let frame = Frame {
            base_from_gripper: transform_from_parts(
                &exp_so3(&Vector3::new(-0.1, 0.05, 0.2)),
                &Vector3::new(0.02, -0.03, 0.01),
            ),
            camera_from_target: None,
            detections: Detections {
                target: vec![
                    [0.0, 0.0, 0.0],
                    [0.05, 0.0, 0.0],
                    [0.0, 0.04, 0.0],
                    [0.05, 0.04, 0.01],
                ],
                pixels: vec![[0.0, 0.0]; 4],
            },
        };
        let data = Data::new(std::slice::from_ref(&frame), &camera, Setup::EyeInHand, 1.0);
        let s: State = (
            *x.rotation.matrix(),
            x.translation.vector,
            *y.rotation.matrix(),
            y.translation.vector,
        );
        let bundle = Bundle {
            data: &data,
            loss: Loss::Squared,
            keep: None,
        };
        let pixels_at = |s: &State| {
            let mut out = Vec::new();
            data.each(s, false, |_, _, p, _| out.push(camera.pixel(p)));
            out
        };
        let mut analytic = Vec::new();
        data.each(&s, true, |_, _, p, j| {
            analytic.push(camera.project(p).unwrap().jacobian * j);
        });
        let h = 1e-7;
        for d in 0..12 {
            let mut delta = SVector::<f64, 12>::zeros();
            delta[d] = h;
            let plus = pixels_at(&bundle.step(&s, &delta));
            delta[d] = -h;
            let minus = pixels_at(&bundle.step(&s, &delta));
            for (k, a) in analytic.iter().enumerate() {
                let numeric = (plus[k] - minus[k]) / (2.0 * h);
                for r in 0..2 {
                    let scale = a[(r, d)].abs().max(1.0);
                    assert!(
                        (numeric[r] - a[(r, d)]).abs() < 1e-4 * scale,
                        "param {d} point {k}: {} vs {}",
                        numeric[r],
                        a[(r, d)]
                    );
                }
            }
        }
    }

    #[test]
    fn a_planar_pose_is_recovered_with_its_mirror() {
        let camera = Intrinsics::pinhole(900.0, 900.0, 640.0, 360.0);
        let truth = transform_from_parts(
            &exp_so3(&Vector3::new(2.8, 0.3, 0.1)),
            &Vector3::new(0.02, -0.01, 0.7),
        );
        let points: Vec<Vector3<f64>> = [
            [-0.03, -0.03, 0.0],
            [0.03, -0.03, 0.0],
            [0.03, 0.03, 0.0],
            [-0.03, 0.03, 0.0],
        ]
        .iter()
        .map(|p| Vector3::from(*p))
        .collect();
        let pixels: Vec<Vector2<f64>> = points
            .iter()
            .map(|p| camera.pixel(&(truth * nalgebra::Point3::from(*p)).coords))
            .collect();
        let poses = planar_poses(&points, &pixels, &camera).unwrap();
        let best = poses.iter().min_by(|a, b| a.1.total_cmp(&b.1)).unwrap();
        assert!(best.1 < 1e-16, "{}", best.1);
        assert!(
            pose_gap(&best.0, &truth) < 1e-9,
            "{}",
            pose_gap(&best.0, &truth)
        );
        let other = poses.iter().max_by(|a, b| a.1.total_cmp(&b.1)).unwrap();
        assert!(
            pose_gap(&other.0, &truth) > 1e-3,
            "the mirror is another pose"
        );
    }
}
