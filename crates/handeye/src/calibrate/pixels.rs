//! `calibrate --method reprojection`: hand–eye calibration on the pixels of the detections
//! ([`crate::solve::reprojection`]), the jobs' [`Input::Pixels`](crate::calibrate::Input::Pixels),
//! with the same report as the pose-based job and its own checks:
//! 1. the reading of the robot poses is checked on the pixels, not on PnP poses: a planar target's
//!    PnP poses flip (the planar ambiguity), which the pose-based readings doctor takes for
//!    inverted poses. The recording is solved as given and with the robot poses inverted; the
//!    inverted reading refuses the as-given one only when it fits the pixels far better;
//! 2. a fit whose pixels stay far above detection noise is refused ([`Error::PixelsUnfit`]),
//!    naming a unit mismatch of target and robot when the target read in another unit fits;
//! 3. the uncertainty is the solve's own (Gauss–Newton with the per-frame sandwich), judged by the
//!    same bounds as the bootstrap's; `at_point` is placed through it.

use serde::{Deserialize, Serialize};

use crate::calibrate::batch::{
    Assessment, Fix, Options, Outliers, ReadingReport, Report, Spread, Units,
    refuse_if_undetermined, working_distance,
};
use crate::calibrate::robot_world::{
    PoseResidualSummary, RobotWorldOptions, RobotWorldReport, TargetReport,
};
use crate::calibrate::verify::{
    FramePixels, PixelComparison, SavedX, Verification, cannot_tell, compared, setup_notes,
    unit_scale,
};
use crate::check::outliers::{PoseResiduals, translation_scale};
use crate::check::quality::quality_report;
use crate::check::uncertainty::{median_target, summarise, warn_weak};
use crate::model::camera::{Frame, Intrinsics};
use crate::model::error::{Degeneracy, Error, Result};
use crate::model::findings::{OutlierPose, Reading};
use crate::model::motion::{PosePair, Setup};
use crate::model::pose::{Transform, TransformJson, rotation_angle_between};
use crate::model::warning::Warning;
use crate::solve::motions::AllPairs;
use crate::solve::reprojection::{
    PixelOptions, PixelSolution, RefinedIntrinsics, check_determined, reprojection,
    reprojection_leaving_out, start_camera_poses, target_with_x,
};
use crate::solve::{Method, RobotWorldMethod, pose_residuals, target_frame};

mod online;
pub use online::OnlinePixels;

/// The robust sigma (pixels, per coordinate) above which the detections do not fit: detectors
/// give 0.05–1 px; a wrong unit, wrong intrinsics or robot poses of other images give tens.
pub const REFUSE_SIGMA_PX: f64 = 3.0;

/// Another reading refuses the as-given one when the as-given sigma is this many times its own.
const BETTER_READING: f64 = 3.0;

/// The fit on the pixels in a [`Report`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReprojectionSummary {
    /// RMS reprojection error over the detections kept, pixels.
    pub rms_px: f64,
    /// Each frame's RMS over all of its detections, in input order.
    pub per_frame: Vec<FrameRms>,
    /// Robust sigma of one pixel coordinate, pixels.
    pub sigma_px: f64,
    /// Detections used in all.
    pub detections: usize,
    /// Detections left out as mis-detections (beyond 5 robust sigmas), (frame name, point index).
    pub outlier_detections: Vec<(String, usize)>,
    /// Frames whose start pose was the other pose of the planar ambiguity than PnP's
    /// smaller-residual one: chosen by the robot's motion.
    pub flips_resolved: usize,
    /// The target's pose Y solved with X, and its frame name.
    pub target_frame: String,
    /// Y (`translation`, `quaternion_xyzw`, `matrix`).
    pub target: TransformJson,
    /// How the reading of the robot poses was checked.
    pub reading_check: String,
    /// The intrinsics refined with X (`--refine-intrinsics`), with their sigmas; absent when the
    /// given intrinsics were used as they are.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub intrinsics: Option<RefinedIntrinsics>,
    /// Every detection's residual where it is in the image, for a figure (the HTML report's):
    /// not in the JSON, whose size it would make grow with the detections.
    #[serde(skip)]
    pub corners: Vec<CornerResidual>,
    /// The camera pose the solve started from for each frame of the input (the outlier frames
    /// left out too), in input order, under the reading `reading.applied` says (the robot poses
    /// inverted for [`Reading::RobotInverted`]): the PnP pose chosen by the robot's motion, or the
    /// record's own `camera_from_target` where it fits the pixels better. The camera poses a
    /// report page or a unit guess should use for records that carry detections only; a frame
    /// that cannot be posed has its own `camera_from_target`, or the identity. Not in the JSON.
    #[serde(skip)]
    pub start_poses: Vec<Transform>,
}

/// One detection's reprojection residual.
#[derive(Debug, Clone, PartialEq)]
pub struct CornerResidual {
    /// Its frame: the index in [`ReprojectionSummary::per_frame`], which names it.
    pub frame: usize,
    /// Where it was detected, pixels (u, v).
    pub pixel: [f64; 2],
    /// The detected pixel less the projected one under the solved X and target pose, pixels.
    pub residual_px: [f64; 2],
    /// Whether the solve kept it (not a mis-detection).
    pub kept: bool,
}

/// One frame's reprojection RMS.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrameRms {
    /// The frame's name (`file:line` from the command line).
    pub name: String,
    /// RMS over its detections, pixels.
    pub rms_px: f64,
}

/// The parameters of the fit on the pixels: X's and the target's rotation and translation.
const PIXEL_PARAMETERS: usize = 12;

/// [`calibrate`](crate::calibrate()) on the pixels (see the module docs and its section "On the
/// pixels").
pub(crate) fn calibrate_on_pixels(
    frames: &[Frame],
    camera: &Intrinsics,
    setup: Setup,
    options: &Options,
) -> Result<Report> {
    not_on_pixels(options.reject_outliers, &options.priors)?;
    let (used, solution, applied, reading_check, choice) = solved(
        frames,
        camera,
        setup,
        options.fix,
        options.refine_intrinsics,
    )?;
    report(
        &used,
        setup,
        options,
        solution,
        (applied, reading_check),
        &choice,
    )
}

/// Refuses the options the pixel solve does not take, rather than answer without them: a prior
/// (the pixel solve has no low-DOF form: X's free component would come from the data's noise,
/// not from the prior the user gave) and `reject_outliers` (mis-detected corners are left out,
/// and listed, by the solve itself).
fn not_on_pixels(reject_outliers: bool, priors: &[crate::model::prior::Prior]) -> Result<()> {
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

/// X and the target's pose on the pixels, with the same checks as [`calibrate_on_pixels`]:
/// [`calibrate_robot_world`](crate::calibrate_robot_world) on the pixels (see its section "On
/// the pixels").
pub(crate) fn calibrate_robot_world_on_pixels(
    frames: &[Frame],
    camera: &Intrinsics,
    setup: Setup,
    options: &RobotWorldOptions,
) -> Result<RobotWorldReport> {
    not_on_pixels(options.reject_outliers, &options.priors)?;
    let (used, solution, applied, reading_check, choice) = solved(
        frames,
        camera,
        setup,
        options.fix,
        options.refine_intrinsics,
    )?;
    let hand_eye = Options {
        fix: options.fix,
        point: options.point,
        pose_names: options.pose_names.clone(),
        ..Options::default()
    };
    let target = solution.target;
    let target_covariance = solution.target_covariance;
    let poses = pose_pairs(&used, &solution.start_poses);
    let Report {
        verdict,
        x,
        uncertainty,
        conditioning,
        reading,
        outliers,
        warnings,
        units,
        transform,
        reprojection,
        ..
    } = report(
        &used,
        setup,
        &hand_eye,
        solution,
        (applied, reading_check),
        &choice,
    )?;
    let scene = translation_scale(&poses, setup).max(working_distance(&poses));
    let Some(target_covariance) = target_covariance else {
        return Err(Error::Degenerate {
            reason: Degeneracy::IllConditioned,
            conditioning,
        });
    };
    let target_uncertainty = summarise(target_covariance, 0, 0, scene);
    refuse_if_undetermined(&target_uncertainty, setup, conditioning)?;
    let residual = PoseResidualSummary::of(pose_residuals(&poses, setup, &transform, &target));
    Ok(RobotWorldReport {
        verdict,
        method: RobotWorldMethod::Reprojection,
        setup,
        formulation: "robot-world".into(),
        frame: setup.x_frame().into(),
        x,
        uncertainty,
        target: TargetReport {
            frame: target_frame(setup).into(),
            pose: TransformJson::from(&target),
            uncertainty: target_uncertainty,
        },
        poses: used.len(),
        conditioning,
        reading,
        outliers,
        residual,
        warnings,
        units,
        transform,
        target_transform: target,
        systematic: None,
        reprojection,
        prior: Default::default(),
        low_dof: None,
    })
}

/// Checks a saved X against a recording with detections (`verify --intrinsics`): the recording is
/// calibrated on the pixels as [`calibrate_on_pixels`] does it, and its X compared with the saved
/// one by the same test and words as [`verify`](crate::verify) (the covariance is the pixel
/// solve's). `pixels` adds the reprojection error of the recording's detections with the saved X
/// and with the recording's own, the target's pose fitted to each with X held fixed
/// (`target_with_x`): how much worse the saved X explains the pixels, frame by frame;
/// `start_poses` are the camera poses the solve started from, under the reading applied (as given
/// when the solve itself was refused).
///
/// Errors: those of [`calibrate_on_pixels`] but a refusal for degenerate or too few motions, which
/// is the verdict `undetermined`.
pub(crate) fn verify_on_pixels(
    saved: &SavedX,
    frames: &[Frame],
    camera: &Intrinsics,
    setup: Setup,
    options: &Options,
) -> Result<Verification> {
    not_on_pixels(options.reject_outliers, &options.priors)?;
    if options.refine_intrinsics {
        return Err(Error::InvalidParameter {
            name: "refine_intrinsics",
            message: "not offered by verify: a saved X is checked with the intrinsics it was calibrated with (give the refined ones with --intrinsics)".into(),
        });
    }
    let notes = setup_notes(saved, setup);
    let (used, solution, applied, reading_check, choice) =
        match solved(frames, camera, setup, options.fix, false) {
            Ok(s) => s,
            Err(e @ (Error::Degenerate { .. } | Error::TooFewMotions { .. })) => {
                let start_poses = start_camera_poses(frames, camera, setup);
                let poses = pose_pairs(frames, &start_poses);
                return Ok(Verification {
                    start_poses,
                    ..cannot_tell(saved, &poses, &e, notes)
                });
            }
            Err(e) => return Err(e),
        };
    let poses = pose_pairs(&used, &solution.start_poses);
    let own = solution.calibration.x;
    let mut x = saved.x;
    x.translation.vector *= unit_scale(saved, &poses, &own, &mut Vec::new());
    let pixel_options = PixelOptions::default();
    let with_saved = target_with_x(&used, camera, setup, &x, &solution, &pixel_options);
    let with_own = target_with_x(&used, camera, setup, &own, &solution, &pixel_options);
    let report = match report(
        &used,
        setup,
        options,
        solution,
        (applied, reading_check),
        &choice,
    ) {
        Ok(r) => r,
        Err(e @ Error::Degenerate { .. }) => {
            return Ok(Verification {
                start_poses: choice.start_poses,
                ..cannot_tell(saved, &poses, &e, notes)
            });
        }
        Err(e) => return Err(e),
    };
    let names = report.reprojection.as_ref().map(|r| {
        r.per_frame
            .iter()
            .map(|f| f.name.clone())
            .collect::<Vec<_>>()
    });
    let per_frame = with_saved
        .per_frame_rms_px
        .iter()
        .zip(&with_own.per_frame_rms_px)
        .enumerate()
        .map(|(i, (s, o))| FramePixels {
            name: names
                .as_ref()
                .and_then(|n| n.get(i).cloned())
                .unwrap_or_else(|| format!("frame {i}")),
            saved_px: *s,
            own_px: *o,
        })
        .collect();
    let mut v = compared(saved, &poses, report, notes);
    v.start_poses = choice.start_poses;
    v.pixels = Some(PixelComparison {
        saved_rms_px: with_saved.rms_px,
        own_rms_px: with_own.rms_px,
        per_frame,
    });
    Ok(v)
}

/// The robot poses with the camera poses the solve started from (the PnP pose of each frame
/// chosen by the robot's motion).
fn pose_pairs(frames: &[Frame], start_poses: &[Transform]) -> Vec<PosePair> {
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

/// A solve of the frames used with one of the camera's parameters changed: the focal length's
/// scale (fx and fy together), or k1.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct CameraFit {
    /// The parameter's value: the focal length's scale, or k1.
    pub value: f64,
    /// Its value as given: 1 for the scale, the camera's k1.
    pub given: f64,
    /// The robust reprojection sigma with it, pixels.
    pub sigma_px: f64,
    /// The RMS over the detections kept with it, pixels.
    pub rms_px: f64,
    /// X with it.
    pub x: Transform,
}

/// The range of the focal length's scale searched by [`focal_check`]: a focal length off by a
/// factor of two is another camera or resolution, which the fit at the given one refuses.
const FOCAL_RANGE: (f64, f64) = (0.5, 2.0);

/// The focal length's scale that fits the detections best (the least RMS over the detections
/// `solved` kept, on its logarithm over [`FOCAL_RANGE`], to 0.1%: the maximum likelihood under
/// Gaussian detection noise) with X and the target's pose solved anew at each: the robot's metric
/// motions fix the depth that a focal length trades against, so wrong intrinsics show as a better
/// fit at another scale. The detections fitted are `solved`'s at every scale: a solve free to
/// leave out more would fit fewer and look better (measured: 54 of 1024 left out at ×0.5, RMS
/// 0.36 px against 1.02 px at ×1 on the same frames). Brent's minimisation ([`brent_minimum`])
/// from scale 1, `solved` itself: about 8 solves where the intrinsics are the camera's.
fn focal_check(
    frames: &[Frame],
    camera: &Intrinsics,
    setup: Setup,
    options: &PixelOptions,
    solved: &PixelSolution,
) -> Option<CameraFit> {
    let at = |log_scale: f64| {
        let scale = log_scale.exp();
        let scaled = Intrinsics {
            fx: camera.fx * scale,
            fy: camera.fy * scale,
            ..*camera
        };
        (scale, scaled)
    };
    let bracket = (FOCAL_RANGE.0.ln(), FOCAL_RANGE.1.ln());
    refit(
        (frames, setup, options, solved),
        at,
        (bracket, 0.0, 2.5e-4),
        1.0,
    )
}

/// The best fit over one camera parameter: `at` gives, at a point of the search, the parameter's
/// value and the camera with it; Brent's minimisation of the RMS over `bracket` from `start` (the
/// given camera, whose RMS is `solved`'s) to `tolerance`; every solve fits the detections `solved`
/// kept. `None` when no value fits better than `given`, the parameter as given.
fn refit(
    (frames, setup, options, solved): (&[Frame], Setup, &PixelOptions, &PixelSolution),
    at: impl Fn(f64) -> (f64, Intrinsics),
    (bracket, start, tolerance): ((f64, f64), f64, f64),
    given: f64,
) -> Option<CameraFit> {
    let mut best: Option<CameraFit> = None;
    let mut rms = |point: f64| {
        let (value, camera) = at(point);
        let Ok(s) = reprojection_leaving_out(frames, &camera, setup, options, &solved.outliers)
        else {
            return f64::INFINITY;
        };
        if best.as_ref().is_none_or(|b| s.rms_px < b.rms_px) {
            best = Some(CameraFit {
                value,
                given,
                sigma_px: s.sigma_px,
                rms_px: s.rms_px,
                x: s.calibration.x,
            });
        }
        s.rms_px
    };
    brent_minimum(&mut rms, bracket, (start, solved.rms_px), tolerance);
    best.filter(|b| b.rms_px < solved.rms_px)
}

/// How far from the given k1 [`k1_check`] searches, either way: at the corner of a typical image
/// (normalised radius 0.8, 900 px focal length) 0.5 moves a point by 230 px, another lens.
const K1_RANGE: f64 = 0.5;

/// The radial distortion k1 that fits the detections best, as [`focal_check`] finds the focal
/// length's scale (the same detections at every k1, X and the target's pose solved anew, Brent's
/// minimisation from the given k1 to 1e-4): a wrong k1 bends the image's outer detections, which
/// the robot's motions do not follow, so it shows as a better fit at another k1. The other
/// coefficients stay as given (k1 is the one a wrong calibration or model gets most wrong).
fn k1_check(
    frames: &[Frame],
    camera: &Intrinsics,
    setup: Setup,
    options: &PixelOptions,
    solved: &PixelSolution,
) -> Option<CameraFit> {
    let k1 = camera.distortion[0];
    let at = |value: f64| {
        let mut changed = *camera;
        changed.distortion[0] = value;
        (value, changed)
    };
    let bracket = (k1 - K1_RANGE, k1 + K1_RANGE);
    refit(
        (frames, setup, options, solved),
        at,
        (bracket, k1, 1e-4),
        k1,
    )
}

/// The minimum of `f` on `(a, b)` by Brent's method (R. P. Brent, *Algorithms for Minimization
/// without Derivatives*, 1973, ch. 5: parabolic interpolation through the three best points,
/// golden-section steps where it does not shrink the bracket fast enough), from `(x, f(x))`
/// inside the bracket, to an absolute `tolerance` on x. Returns the best x and f(x). An
/// infinite value (a solve that fails) is taken as worse, never interpolated through.
fn brent_minimum(
    f: &mut impl FnMut(f64) -> f64,
    (mut a, mut b): (f64, f64),
    (x0, f0): (f64, f64),
    tolerance: f64,
) -> (f64, f64) {
    let golden = (3.0 - 5f64.sqrt()) / 2.0;
    let (mut x, mut w, mut v) = (x0, x0, x0);
    let (mut fx, mut fw, mut fv) = (f0, f0, f0);
    // d: the last step; e: the step before it (a parabolic step must be less than half of it).
    let (mut d, mut e) = (0.0_f64, 0.0_f64);
    loop {
        let middle = 0.5 * (a + b);
        let tol1 = 1e-8 * x.abs() + tolerance;
        let tol2 = 2.0 * tol1;
        if (x - middle).abs() <= tol2 - 0.5 * (b - a) {
            return (x, fx);
        }
        let mut parabolic = None;
        if e.abs() > tol1 && fx.is_finite() && fw.is_finite() && fv.is_finite() {
            let r = (x - w) * (fx - fv);
            let q = (x - v) * (fx - fw);
            let mut p = (x - v) * q - (x - w) * r;
            let mut q = 2.0 * (q - r);
            if q > 0.0 {
                p = -p;
            } else {
                q = -q;
            }
            if p.abs() < (0.5 * q * e).abs() && p > q * (a - x) && p < q * (b - x) {
                parabolic = Some(p / q);
            }
        }
        match parabolic {
            Some(step) => {
                e = d;
                d = step;
                let u = x + d;
                if u - a < tol2 || b - u < tol2 {
                    d = if x < middle { tol1 } else { -tol1 };
                }
            }
            None => {
                e = if x < middle { b - x } else { a - x };
                d = golden * e;
            }
        }
        let u = x + if d.abs() >= tol1 { d } else { tol1.copysign(d) };
        let fu = f(u);
        if fu <= fx {
            if u < x {
                b = x;
            } else {
                a = x;
            }
            (v, fv, w, fw, x, fx) = (w, fw, x, fx, u, fu);
        } else {
            if u < x {
                a = u;
            } else {
                b = u;
            }
            if fu <= fw || w == x {
                (v, fv, w, fw) = (w, fw, u, fu);
            } else if fu <= fv || v == x || v == w {
                (v, fv) = (u, fu);
            }
        }
    }
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
fn intrinsics_warning(
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
fn solved(
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
            reprojection(frames, camera, setup, &pixel_options)?,
            "not checked (--fix as-given)".to_string(),
        ),
        Fix::Read(Reading::RobotInverted) => (
            Reading::RobotInverted,
            reprojection(&inverted, camera, setup, &pixel_options)?,
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
            checked_reading(frames, &inverted, camera, setup, fix, &pixel_options)?
        }
    };
    let mut used = if applied == Reading::RobotInverted {
        inverted
    } else {
        frames.to_vec()
    };
    let mut solution = solution;
    // The camera poses this first solve, over every input frame under the reading applied,
    // started from: the report's `start_poses`, whatever frames are left out below.
    let mut choice = FrameChoice {
        kept: (0..frames.len()).collect(),
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
        if frames.len() - outliers.len() > PIXEL_PARAMETERS {
            choice.kept.retain(|i| !outliers.contains(i));
            used = choice.kept.iter().map(|&i| used[i].clone()).collect();
            solution = reprojection(&used, camera, setup, &pixel_options)?;
            choice.rejected = true;
        }
    }
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
            Err(Error::Misread {
                finding: format!(
                    "the detections fit far better with the robot poses inverted (reprojection sigma {:.2} px instead of {as_given_sigma:.2} px)",
                    f.sigma_px
                ),
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

/// The report of a solution on the pixels.
fn report(
    frames: &[Frame],
    setup: Setup,
    options: &Options,
    solution: PixelSolution,
    (applied, reading_check): (Reading, String),
    choice: &FrameChoice,
) -> Result<Report> {
    let x = solution.calibration.x;
    let poses = pose_pairs(frames, &solution.start_poses);
    let scene = translation_scale(&poses, setup).max(working_distance(&poses));
    let conditioning = solution.calibration.conditioning;
    let Some(covariance) = solution.covariance else {
        return Err(Error::Degenerate {
            reason: Degeneracy::IllConditioned,
            conditioning,
        });
    };
    let mut uncertainty = summarise(covariance, 0, 0, scene);
    uncertainty.at_point =
        Some(uncertainty.place(&x, options.point.unwrap_or_else(|| median_target(&poses))));
    refuse_if_undetermined(&uncertainty, setup, conditioning)?;
    let mut warnings = solution.calibration.warnings.clone();
    warn_weak(&uncertainty, setup, None, &mut warnings);
    let detections: usize = frames.iter().map(|f| f.detections.pixels.len()).sum();
    let coordinates = 2 * detections.saturating_sub(solution.outliers.len());
    warnings.extend(intrinsics_warning(
        choice,
        (solution.sigma_px, solution.rms_px),
        coordinates,
        &x,
        &uncertainty,
    ));
    let quality = quality_report(&AllPairs::new(&poses, setup), &x, 0);
    let residuals = PoseResiduals::at(&poses, setup, &x);
    // The name of input frame i.
    let input_name = |i: usize| {
        options
            .pose_names
            .get(i)
            .cloned()
            .unwrap_or_else(|| format!("frame {i}"))
    };
    // The name of used frame i.
    let name = |i: usize| input_name(choice.kept.get(i).copied().unwrap_or(i));
    let left_out: std::collections::HashSet<(usize, usize)> =
        solution.outliers.iter().copied().collect();
    let summary = ReprojectionSummary {
        rms_px: solution.rms_px,
        per_frame: solution
            .per_frame_rms_px
            .iter()
            .enumerate()
            .map(|(i, r)| FrameRms {
                name: name(i),
                rms_px: *r,
            })
            .collect(),
        sigma_px: solution.sigma_px,
        detections: frames.iter().map(|f| f.detections.pixels.len()).sum(),
        outlier_detections: solution
            .outliers
            .iter()
            .map(|(f, k)| (name(*f), *k))
            .collect(),
        flips_resolved: solution.flips_resolved,
        target_frame: match setup {
            Setup::EyeInHand => "base_from_target",
            Setup::EyeToHand => "gripper_from_target",
        }
        .into(),
        target: TransformJson::from(&solution.target),
        reading_check,
        intrinsics: solution.intrinsics.clone(),
        corners: solution
            .residuals_px
            .iter()
            .map(|&(f, k, residual_px)| CornerResidual {
                frame: f,
                pixel: frames[f].detections.pixels[k],
                residual_px,
                kept: !left_out.contains(&(f, k)),
            })
            .collect(),
        start_poses: choice.start_poses.clone(),
    };
    warnings.sort_by_key(|w| w.remedy().is_none());
    Ok(Report {
        verdict: Assessment::of(&warnings),
        method: Method::Reprojection,
        setup,
        pairing: options.pairing,
        frame: setup.x_frame().into(),
        x: TransformJson::from(&x),
        poses: frames.len(),
        motions: solution.calibration.motions,
        conditioning,
        uncertainty,
        reading: ReadingReport {
            applied,
            check: None,
        },
        outliers: Outliers {
            poses: choice
                .outliers
                .iter()
                .map(|&(i, rms_px)| OutlierPose {
                    pose: i,
                    name: input_name(i),
                    angle_gap_deg: 0.0,
                    pitch_gap: 0.0,
                    rms_px: Some(rms_px),
                })
                .collect(),
            rejected: choice.rejected,
            angle_threshold_deg: 0.0,
            pitch_threshold: 0.0,
        },
        residual: quality.residual,
        translation_residual_rel: residuals.median_translation() / scene.max(f64::MIN_POSITIVE),
        quality: Spread {
            axis_spread_deg: quality.axis_spread_deg,
            rotation_range_deg: quality.rotation_range_deg,
            per_motion: None,
        },
        warnings,
        units: Units::default(),
        transform: x,
        held_out: None,
        reprojection: Some(summary),
        systematic: None,
        prior: Default::default(),
        low_dof: None,
    })
}

#[cfg(test)]
mod tests {
    use super::{brent_minimum, start_camera_poses};
    use crate::calibrate::batch::{Fix, Options};
    use crate::model::findings::Reading;
    use crate::model::motion::Setup;
    use crate::model::pose::Transform;
    use crate::sim::pixels::{PixelSimConfig, simulate_pixels};

    #[test]
    fn the_start_poses_are_every_input_frames_under_the_reading_applied() {
        for setup in [Setup::EyeInHand, Setup::EyeToHand] {
            let sim = simulate_pixels(&PixelSimConfig::tag().with_setup(setup), 7100);
            let camera = &sim.intrinsics;
            let start = |frames: &[crate::model::camera::Frame], fix: Fix| {
                let options = Options {
                    fix,
                    ..Options::default()
                };
                let r = super::calibrate_on_pixels(frames, camera, setup, &options).unwrap();
                let applied = r.reading.applied;
                let rejected = r.outliers.rejected;
                let poses = r.reprojection.unwrap().start_poses;
                assert_eq!(poses.len(), frames.len());
                // PnP on each input frame, the robot poses as the reading applied reads them.
                let read: Vec<_> = frames
                    .iter()
                    .map(|f| crate::model::camera::Frame {
                        base_from_gripper: match applied {
                            Reading::RobotInverted => f.base_from_gripper.inverse(),
                            _ => f.base_from_gripper,
                        },
                        ..f.clone()
                    })
                    .collect();
                assert_eq!(poses, start_camera_poses(&read, camera, setup));
                (applied, rejected)
            };
            assert_eq!(start(&sim.frames, Fix::Refuse), (Reading::AsGiven, false));
            // Two frames left out: still every input frame's start pose.
            let mut frames = sim.frames.clone();
            frames[4].base_from_gripper *= Transform::new(
                nalgebra::Vector3::new(0.02, -0.01, 0.0),
                nalgebra::Vector3::new(0.0, 2f64.to_radians(), 0.0),
            );
            frames[19].base_from_gripper = frames[20].base_from_gripper;
            assert_eq!(start(&frames, Fix::Refuse), (Reading::AsGiven, true));
            // The robot poses read inverted.
            let inverted: Vec<_> = sim
                .frames
                .iter()
                .map(|f| crate::model::camera::Frame {
                    base_from_gripper: f.base_from_gripper.inverse(),
                    ..f.clone()
                })
                .collect();
            assert_eq!(start(&inverted, Fix::Auto), (Reading::RobotInverted, false));
        }
    }

    /// Finds `f`'s minimum on the focal check's bracket from 0, counting evaluations.
    fn minimum(f: impl Fn(f64) -> f64) -> (f64, usize) {
        let mut count = 0;
        let mut counted = |x: f64| {
            count += 1;
            f(x)
        };
        let (low, high) = (0.5f64.ln(), 2f64.ln());
        let (x, _) = brent_minimum(&mut counted, (low, high), (0.0, f(0.0)), 2.5e-4);
        (x, count)
    }

    #[test]
    fn brent_finds_the_minimum_to_the_tolerance_in_fewer_steps_than_golden_section() {
        // Golden section on the same bracket to 1e-3 takes 17 evaluations; these take 4 to 8.
        for centre in [-0.6, -0.2, -0.01, 0.0, 0.004, 0.05, 0.3, 0.65] {
            let (x, count) = minimum(|x| 1.0 + (x - centre).powi(2) + 0.3 * (x - centre).powi(4));
            assert!((x - centre).abs() < 1e-3, "{centre}: {x}");
            assert!(count <= 10, "{centre}: {count} evaluations");
        }
        // A kink (|x − c|: no parabola fits) still converges, by golden-section steps.
        let (x, count) = minimum(|x| 1.0 + (x - 0.21).abs());
        assert!((x - 0.21).abs() < 1e-3 && count <= 40, "{x} {count}");
    }

    #[test]
    fn failed_solves_are_worse_never_interpolated() {
        // Solves fail beyond 0.4: the minimum at 0.5 is out of reach, the best is at the edge.
        let f = |x: f64| {
            if x > 0.4 {
                f64::INFINITY
            } else {
                (x - 0.5).powi(2)
            }
        };
        let (x, _) = minimum(f);
        assert!((x - 0.4).abs() < 2e-3, "{x}");
        // All fail but the start: the start is kept.
        let (x, _) = minimum(|x| if x == 0.0 { 1.0 } else { f64::INFINITY });
        assert_eq!(x, 0.0);
    }
}
