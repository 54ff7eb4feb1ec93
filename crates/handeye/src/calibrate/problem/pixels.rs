//! The problem on the pixels of the detections ([`crate::solve::reprojection`]): X and the
//! target's pose fitted to the detections, the input's kind
//! ([`Input::Pixels`](crate::Input::Pixels)) whatever the problem, with its own checks; the
//! pipeline words the report:
//! 1. the reading of the robot poses is checked on the pixels, not on PnP poses: a planar target's
//!    PnP poses flip (the planar ambiguity), which the pose-based readings doctor takes for
//!    inverted poses. The recording is solved as given and with the robot poses inverted; the
//!    inverted reading refuses the as-given one only when it fits the pixels far better;
//! 2. a fit whose pixels stay far above detection noise is refused ([`Error::PixelsUnfit`]),
//!    naming a unit mismatch of target and robot when the target read in another unit fits;
//! 3. the uncertainty is the solve's own (Gauss–Newton with the per-frame sandwich), judged by the
//!    same bounds as the bootstrap's; `at_point` is placed through it.

mod camera;

use nalgebra::Matrix6;

use crate::calibrate::options::Fix;
use crate::calibrate::problem::motions::refuse_if_undetermined;
use crate::check::outliers::{translation_scale, working_distance};
use crate::check::uncertainty::{Uncertainty, median_target, summarise};
use crate::model::camera::{Frame, Intrinsics};
use crate::model::error::{Degeneracy, Error, Result};
use crate::model::findings::Reading;
use crate::model::motion::{PosePair, Setup};
use crate::model::pose::{Transform, rotation_angle_between};
use crate::model::warning::Warning;
use crate::solve::reprojection::{PixelOptions, PixelSolution, check_determined, reprojection};
use camera::{CameraFit, focal_check, k1_check};

/// The robust sigma (pixels, per coordinate) above which the detections do not fit: detectors
/// give 0.05–1 px; a wrong unit, wrong intrinsics or robot poses of other images give tens.
pub const REFUSE_SIGMA_PX: f64 = 3.0;

/// Another reading refuses the as-given one when the as-given sigma is this many times its own.
const BETTER_READING: f64 = 3.0;

/// The parameters of the fit on the pixels: X's and the target's rotation and translation.
pub(crate) const PIXEL_PARAMETERS: usize = 12;

/// Refuses the options the pixel solve does not take, rather than answer without them: a prior
/// (the pixel solve has no low-DOF form: X's free component would come from the data's noise,
/// not from the prior the user gave) and `reject_outliers` (mis-detected corners are left out,
/// and listed, by the solve itself).
pub(crate) fn not_on_pixels(
    reject_outliers: bool,
    priors: &[crate::model::prior::Prior],
    robot_model: Option<&crate::model::kinematics::Kinematics>,
) -> Result<()> {
    if robot_model.is_some() {
        return Err(Error::InvalidParameter {
            name: "robot-model",
            message: "the robot's table feeds the systematic-error test, which runs on the poses' residuals, not on the pixels: calibrate without `--method reprojection` for it".into(),
        });
    }
    if reject_outliers {
        return Err(Error::InvalidParameter {
            name: "reject_outliers",
            message: "not offered on the pixels: mis-detected corners are left out (and listed) by the solve itself".into(),
        });
    }
    if !priors.is_empty() {
        return Err(Error::InvalidParameter {
            name: "prior",
            message: "a prior is not taken on the pixels (yet): calibrate the PnP poses with it instead (without `--method reprojection`)".into(),
        });
    }
    Ok(())
}

/// The robot poses with the camera poses the solve started from (the PnP pose of each frame
/// chosen by the robot's motion).
pub fn pose_pairs(frames: &[Frame], start_poses: &[Transform]) -> Vec<PosePair> {
    frames
        .iter()
        .zip(start_poses)
        .map(|(f, c)| PosePair {
            base_from_gripper: f.base_from_gripper,
            camera_from_target: *c,
        })
        .collect()
}

/// Which frames of the input a solve on the pixels used, and those it named as outlier poses.
#[derive(Debug, Clone, PartialEq, Default)]
pub(crate) struct FrameChoice {
    /// The input index of each frame used, in order.
    pub kept: Vec<usize>,
    /// The outlier poses: input index and reprojection RMS (every detection) in the solve over
    /// every frame, pixels.
    pub outliers: Vec<(usize, f64)>,
    /// Whether they were left out (not when too few frames would be left).
    pub rejected: bool,
    /// The same frames solved with the focal length that fits best ([`focal_check`]); none with
    /// the intrinsics refined, or when no scale solves.
    pub focal: Option<CameraFit>,
    /// The same with the radial distortion k1 that fits best ([`k1_check`]).
    pub k1: Option<CameraFit>,
    /// The camera pose the solve started from for each frame of the input
    /// ([`ReprojectionSummary::start_poses`]).
    pub start_poses: Vec<Transform>,
}

/// The χ² (one degree of freedom) a better fit at another focal length must pass: p = 0.001.
/// The detections of one frame share its robot pose's error, so the coordinates are not
/// independent and the statistic runs above χ²₁ on exact intrinsics (measured: 3 of 80 simulated
/// recordings above it); [`FOCAL_MATERIAL`] keeps those out.
const FOCAL_CHI2: f64 = 10.83;

/// The least focal-length error warned, relative: below it the scale found is within the noise
/// of the check itself (the 3 of 80 recordings above: 0.4% and less) and of a camera
/// calibration's own (a few tenths of a percent).
const FOCAL_MATERIAL: f64 = 0.01;

/// The least change of k1 warned: a calibration's own uncertainty on k1 is a few thousandths.
const K1_MATERIAL: f64 = 0.005;

/// How far X must move between the two fits, in its sigmas, for the warning: the given
/// intrinsics' X is then off by that much and by its own noise besides (measured: a k1 off by
/// 0.04 moved X by 1.6–2.6 sigma while X was 3.4 sigma from the truth; a gate of 3 left it
/// silent).
const MOVED_SIGMAS: f64 = 2.0;

/// The warning of intrinsics that disagree with the detections: the fit at the best focal length,
/// or at the best k1, is significantly better (the drop in the sum of squares over the `n`
/// coordinates kept, over its residual variance: a likelihood-ratio test of one parameter), the
/// parameter moved materially, and X moves by more than [`MOVED_SIGMAS`] between the two. Of the
/// two, the one that fits better by more. `fit` is the robust sigma and the RMS with the given
/// intrinsics.
pub(crate) fn intrinsics_warning(
    choice: &FrameChoice,
    (sigma_px, rms_px): (f64, f64),
    coordinates: usize,
    x: &Transform,
    uncertainty: &crate::check::uncertainty::Uncertainty,
) -> Option<Warning> {
    let n = coordinates as f64;
    // A refit that passes the gates, `material` its parameter's own: its likelihood ratio and how
    // far X moves with it (degrees, input unit, sigmas).
    let judged = |fit: &CameraFit, material: bool| {
        let chi2 = n * (rms_px.powi(2) - fit.rms_px.powi(2)) / fit.rms_px.powi(2).max(1e-300);
        let rotation_deg = rotation_angle_between(&x.rotation, &fit.x.rotation).to_degrees();
        let translation = (fit.x.translation.vector - x.translation.vector).norm();
        let sigmas = (rotation_deg / uncertainty.rotation_deg.max(1e-300))
            .max(translation / uncertainty.translation.max(1e-300));
        (chi2 > FOCAL_CHI2 && material && sigmas > MOVED_SIGMAS).then_some((
            chi2,
            rotation_deg,
            translation,
            sigmas,
        ))
    };
    let focal = choice.focal.as_ref().and_then(|fit| {
        let material = fit.value.ln().abs() > FOCAL_MATERIAL.ln_1p();
        let (chi2, rotation_deg, translation, sigmas) = judged(fit, material)?;
        let warning = Warning::IntrinsicsDisagree {
            focal_scale: fit.value,
            sigma_px,
            scaled_sigma_px: fit.sigma_px,
            rotation_deg,
            translation,
            sigmas,
        };
        Some((chi2, warning))
    });
    let k1 = choice.k1.as_ref().and_then(|fit| {
        let material = (fit.value - fit.given).abs() > K1_MATERIAL;
        let (chi2, rotation_deg, translation, sigmas) = judged(fit, material)?;
        let warning = Warning::DistortionDisagrees {
            k1: fit.given,
            k1_best: fit.value,
            sigma_px,
            refit_sigma_px: fit.sigma_px,
            rotation_deg,
            translation,
            sigmas,
        };
        Some((chi2, warning))
    });
    [focal, k1]
        .into_iter()
        .flatten()
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, w)| w)
}

/// The frames most of whose detections the solve left out as mis-fits (more than half beyond
/// [`INLIER_SIGMAS`](crate::solve::reprojection::INLIER_SIGMAS) robust sigmas): the frame, not a
/// corner, is wrong (its robot pose, or an image paired with another pose). A mis-detected corner
/// leaves out that corner; a frame whose robot pose is off moves all of its corners together.
fn outlier_frames(frames: &[Frame], solution: &PixelSolution) -> Vec<usize> {
    let mut left_out = vec![0usize; frames.len()];
    for (f, _) in &solution.outliers {
        if let Some(n) = left_out.get_mut(*f) {
            *n += 1;
        }
    }
    frames
        .iter()
        .zip(&left_out)
        .enumerate()
        .filter(|(_, (f, n))| 2 * **n > f.detections.pixels.len())
        .map(|(i, _)| i)
        .collect()
}

/// The solve on the pixels with its checks: the frames used (the robot poses inverted when that
/// reading was applied; the outlier poses left out), the solution, the reading, how it was
/// checked, and which frames were used.
pub(crate) fn solved(
    frames: &[Frame],
    camera: &Intrinsics,
    setup: Setup,
    fix: Fix,
    refine_intrinsics: bool,
) -> Result<(Vec<Frame>, PixelSolution, Reading, String, FrameChoice)> {
    camera
        .check()
        .map_err(|(field, message)| Error::InvalidParameter {
            name: "intrinsics",
            message: format!("{field}: {message}"),
        })?;
    // X's covariance takes the sandwich over the robot's stations with the factor S/(S − 12) (12
    // parameters): fewer than 13 frames have no honest uncertainty, and are refused here, by
    // count, rather than after the solve as if the motions were degenerate (and fewer than 13
    // stations after it, by the same error).
    if frames.len() <= PIXEL_PARAMETERS {
        return Err(Error::TooFewMotions {
            got: frames.len().saturating_sub(1),
            need: PIXEL_PARAMETERS,
        });
    }
    let pixel_options = PixelOptions {
        refine_intrinsics,
        ..PixelOptions::default()
    };
    let (applied, used, solution, reading_check) =
        read_on_pixels(frames, camera, setup, fix, &pixel_options)?;
    let (used, solution, mut choice) =
        without_outlier_frames(used, solution, camera, setup, &pixel_options)?;
    if solution.sigma_px > REFUSE_SIGMA_PX {
        return Err(unfit(&solution, &used, camera, setup, &pixel_options));
    }
    // Images at 12 robot poses or fewer have no honest uncertainty, however many there are:
    // refused before the focal-length check's solves.
    if solution.stations <= PIXEL_PARAMETERS {
        return Err(Error::TooFewMotions {
            got: solution.stations.saturating_sub(1),
            need: PIXEL_PARAMETERS,
        });
    }
    if let Some(k) = &solution.intrinsics {
        check_determined(k, camera)?;
    } else {
        choice.focal = focal_check(&used, camera, setup, &pixel_options, &solution);
        choice.k1 = k1_check(&used, camera, setup, &pixel_options, &solution);
    }
    Ok((used, solution, applied, reading_check, choice))
}

/// The first solve, over every input frame, under the reading `fix` asks for or the pixels choose:
/// the reading applied, the frames so read, the solution and how the reading was checked.
fn read_on_pixels(
    frames: &[Frame],
    camera: &Intrinsics,
    setup: Setup,
    fix: Fix,
    pixel_options: &PixelOptions,
) -> Result<(Reading, Vec<Frame>, PixelSolution, String)> {
    let inverted: Vec<Frame> = frames
        .iter()
        .map(|f| Frame {
            base_from_gripper: f.base_from_gripper.inverse(),
            ..f.clone()
        })
        .collect();
    let (applied, solution, reading_check) = match fix {
        Fix::Read(Reading::AsGiven) => (
            Reading::AsGiven,
            reprojection(frames, camera, setup, pixel_options)?,
            "not checked (--fix as-given)".to_string(),
        ),
        Fix::Read(Reading::RobotInverted) => (
            Reading::RobotInverted,
            reprojection(&inverted, camera, setup, pixel_options)?,
            "not checked (--fix robot-inverted)".to_string(),
        ),
        Fix::Read(other) => {
            return Err(Error::InvalidParameter {
                name: "fix",
                message: format!(
                    "`{}` is not offered on the pixels: as-given or robot-inverted",
                    other.name()
                ),
            });
        }
        Fix::Refuse | Fix::Auto => {
            checked_reading(frames, &inverted, camera, setup, fix, pixel_options)?
        }
    };
    let used = if applied == Reading::RobotInverted {
        inverted
    } else {
        frames.to_vec()
    };
    Ok((applied, used, solution, reading_check))
}

/// The outlier frames of the first solve ([`outlier_frames`]) named, and left out and solved
/// again on the others when enough frames remain for an honest uncertainty. `used` is every
/// input frame under the reading applied.
fn without_outlier_frames(
    mut used: Vec<Frame>,
    mut solution: PixelSolution,
    camera: &Intrinsics,
    setup: Setup,
    pixel_options: &PixelOptions,
) -> Result<(Vec<Frame>, PixelSolution, FrameChoice)> {
    let input_frames = used.len();
    // The camera poses this first solve, over every input frame under the reading applied,
    // started from: the report's `start_poses`, whatever frames are left out below.
    let mut choice = FrameChoice {
        kept: (0..input_frames).collect(),
        start_poses: solution.start_poses.clone(),
        ..FrameChoice::default()
    };
    let outliers = outlier_frames(&used, &solution);
    if !outliers.is_empty() {
        choice.outliers = outliers
            .iter()
            .map(|&i| {
                (
                    i,
                    solution
                        .per_frame_rms_px
                        .get(i)
                        .copied()
                        .unwrap_or(f64::NAN),
                )
            })
            .collect();
        // Left out, and solved again on the others, when enough frames remain for an honest
        // uncertainty; else named only.
        if input_frames - outliers.len() > PIXEL_PARAMETERS {
            choice.kept.retain(|i| !outliers.contains(i));
            used = choice.kept.iter().map(|&i| used[i].clone()).collect();
            solution = reprojection(&used, camera, setup, pixel_options)?;
            choice.rejected = true;
        }
    }
    Ok((used, solution, choice))
}

/// The reading on the pixels: as given, unless the robot poses inverted fit far better (then a
/// refusal, or with [`Fix::Auto`] that reading).
fn checked_reading(
    frames: &[Frame],
    inverted: &[Frame],
    camera: &Intrinsics,
    setup: Setup,
    fix: Fix,
    pixel_options: &PixelOptions,
) -> Result<(Reading, PixelSolution, String)> {
    let as_given = reprojection(frames, camera, setup, pixel_options);
    let flipped = reprojection(inverted, camera, setup, pixel_options).ok();
    let as_given_sigma = as_given.as_ref().map_or(f64::INFINITY, |s| s.sigma_px);
    let words = |other: Option<f64>| match other {
        Some(o) => format!(
            "on the pixels: as given {as_given_sigma:.3} px, robot poses inverted {o:.3} px (sigma per coordinate); PnP poses are not judged (a planar target's flip is not an inversion)"
        ),
        None => format!(
            "on the pixels: as given {as_given_sigma:.3} px; the robot poses inverted do not solve"
        ),
    };
    match flipped {
        Some(f)
            if f.sigma_px <= REFUSE_SIGMA_PX
                && as_given_sigma > BETTER_READING * f.sigma_px.max(0.05) =>
        {
            let text = words(Some(f.sigma_px));
            if fix == Fix::Auto {
                return Ok((Reading::RobotInverted, f, text));
            }
            let fit = format!(
                "reprojection sigma {:.2} px instead of {as_given_sigma:.2} px",
                f.sigma_px
            );
            Err(Error::Misread {
                finding: format!(
                    "the detections fit far better with the robot poses inverted ({fit})"
                ),
                fit,
                readings: vec![Reading::RobotInverted],
                setup,
                other_setup: false,
                frames: false,
            })
        }
        other => {
            let text = words(other.map(|f| f.sigma_px));
            as_given.map(|s| (Reading::AsGiven, s, text))
        }
    }
}

/// The refusal of a fit that leaves the pixels far above noise, naming a unit mismatch when the
/// target read in another unit fits.
fn unfit(
    solution: &PixelSolution,
    frames: &[Frame],
    camera: &Intrinsics,
    setup: Setup,
    options: &PixelOptions,
) -> Error {
    let rescaled = |s: f64| -> Vec<Frame> {
        frames
            .iter()
            .map(|f| {
                let mut f = f.clone();
                for p in &mut f.detections.target {
                    for v in p.iter_mut() {
                        *v *= s;
                    }
                }
                f.camera_from_target = None;
                f
            })
            .collect()
    };
    let unit = [(1e-3, "1000 times smaller"), (1e3, "1000 times larger")]
        .into_iter()
        .find(|(s, _)| {
            reprojection(&rescaled(*s), camera, setup, options)
                .is_ok_and(|r| r.sigma_px <= REFUSE_SIGMA_PX)
        });
    let hint = match unit {
        Some((_, words)) => format!(
            "the target's points {words} fit: give the target's points and the robot's translations in one unit (a target in mm with a robot in m?)"
        ),
        None => "check that the target's points and the robot's translations share one unit, that the intrinsics are this camera's, that each record's robot pose is the one at its image, and the setup (--setup)".into(),
    };
    Error::PixelsUnfit {
        sigma_px: solution.sigma_px,
        rms_px: solution.rms_px,
        hint,
    }
}

/// X's one-sigma uncertainty on the pixels: the solve's own covariance (none: the motions do not
/// determine X), judged by the bootstrap's bounds, with `at_point` placed at `point` (the median
/// target position seen by the camera when `None`); `poses` are the robot poses with the camera
/// poses the solve started from.
pub(crate) fn uncertainty(
    poses: &[PosePair],
    setup: Setup,
    point: Option<[f64; 3]>,
    solution: &PixelSolution,
) -> Result<Uncertainty> {
    let x = solution.calibration.x;
    let scene = scene(poses, setup);
    let conditioning = solution.calibration.conditioning;
    let Some(covariance) = solution.covariance else {
        return Err(Error::Degenerate {
            reason: Degeneracy::IllConditioned,
            conditioning,
        });
    };
    let mut uncertainty = summarise(covariance, 0, 0, scene);
    uncertainty.at_point =
        Some(uncertainty.place(&x, point.unwrap_or_else(|| median_target(poses))));
    refuse_if_undetermined(&uncertainty, setup, conditioning)?;
    Ok(uncertainty)
}

/// The target's one-sigma uncertainty on the pixels: its block of the solve's covariance
/// (`target_covariance`; none: the frames do not determine it), judged by the same bounds.
pub(crate) fn target_uncertainty(
    poses: &[PosePair],
    setup: Setup,
    target_covariance: Option<Matrix6<f64>>,
    conditioning: f64,
) -> Result<Uncertainty> {
    let Some(target_covariance) = target_covariance else {
        return Err(Error::Degenerate {
            reason: Degeneracy::IllConditioned,
            conditioning,
        });
    };
    let target_uncertainty = summarise(target_covariance, 0, 0, scene(poses, setup));
    refuse_if_undetermined(&target_uncertainty, setup, conditioning)?;
    Ok(target_uncertainty)
}

/// The scene's size: the larger of the hand's spread and the camera's working distance.
pub(crate) fn scene(poses: &[PosePair], setup: Setup) -> f64 {
    translation_scale(poses, setup).max(working_distance(poses))
}
