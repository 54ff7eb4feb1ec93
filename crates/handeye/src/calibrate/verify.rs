//! Does a saved X still fit? `handeye verify`: a new recording against the X a calibration wrote.
//!
//! The recording is calibrated as [`calibrate`](crate::calibrate()) does it (same method and pairing), and the two X
//! are compared with the covariance of their difference: the recording's bootstrap covariance plus
//! the saved X's own when the file has one. The squared Mahalanobis distance d² = eᵀ C⁻¹ e of the
//! difference e = (log(R_saved R_newᵀ), t_saved − t_new) follows χ² with 6 degrees of freedom when
//! both X describe the same rig; beyond its [`LEVEL`] quantile (d > 4.74 sigmas) the saved X does not
//! fit. The choice and its measurements are in `docs/DECISIONS.md` ("verify").
//!
//! A recording that cannot determine X (degenerate motions), or that determines it so weakly that a
//! difference of a degree would pass, cannot tell: the verdict is then `undetermined`.

use nalgebra::{Matrix6, SymmetricEigen, Vector3, Vector6};
use serde::{Deserialize, Serialize};
use statrs::distribution::{ChiSquared, ContinuousCDF};

use crate::calibrate::input::Input;
use crate::calibrate::low_dof;
use crate::calibrate::options::{Options, Problem};
use crate::calibrate::pipeline::{hand_eye_on_pixels, hand_eye_on_poses};
use crate::calibrate::problem::pixels::{not_on_pixels, pose_pairs, solved};
use crate::calibrate::report::HandEyeReport;
use crate::check::outliers::working_distance;
use crate::model::camera::{Frame, Intrinsics};
use crate::model::error::{Error, Result};
use crate::model::findings::Assessment;
use crate::model::findings::{Sizes, Verdict};
use crate::model::motion::{PosePair, Setup};
use crate::model::pose::{Transform, TransformJson, log_so3};
use crate::model::prior::{Component, LengthUnit, Prior};
use crate::model::warning::Warning;
use crate::solve::reprojection::{PixelOptions, start_camera_poses, target_with_x};
use crate::solve::{RobotWorldMethod, joint_covariance, robot_world};

/// The probability of the χ² test's acceptance region for a saved X of the same rig: one
/// same-rig recording in a thousand is refused.
pub const LEVEL: f64 = 0.999;

pub use crate::model::saved::SavedX;

/// The verdict of [`verify`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Consistency {
    /// The saved X fits the recording within the uncertainty of both.
    Consistent,
    /// It does not: the camera moved, the rig is another, or the saved X was wrong.
    Inconsistent,
    /// The recording cannot tell (too little motion).
    Undetermined,
}

crate::named_enum!(Consistency, "verify verdict", "verdict" {
    Consistent => "consistent",
    Inconsistent => "inconsistent",
    Undetermined => "undetermined",
});

/// What [`verify`] found: the verdict, the difference, its one-sigma and the words.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Verification {
    /// `consistent`, `inconsistent` or `undetermined`.
    pub verdict: Consistency,
    /// The saved X minus the recording's: the rotation angle between them (degrees) and the
    /// distance between their translations (the recording's unit).
    pub difference: Sizes,
    /// One sigma of that difference: √trace of the rotation and translation blocks of the
    /// combined covariance (the recording's, plus the saved X's when known).
    pub sigma: Sizes,
    /// The smallest change of X this recording would call inconsistent: a saved X that differs from
    /// the recording's by more than this rotation, or by more than this translation (whatever the
    /// other part and the direction), is beyond the test's limit; smaller changes along the
    /// recording's weakest direction may pass unseen. √ of the largest eigenvalue of the rotation
    /// (translation) block of the combined covariance times the limit, and below [`SHAPE_POSES`]
    /// poses at least [`SIZE_LIMIT`] one-sigmas. Infinite when the recording cannot tell at all.
    pub detectable: Sizes,
    /// The tolerance asked for ([`Verification::within`], `verify --tolerance DEG,LENGTH`): the
    /// change that matters to the user, in degrees and the recording's unit.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tolerance: Option<Sizes>,
    /// The difference in sigmas: the Mahalanobis distance √(eᵀ C⁻¹ e) over the six parameters.
    pub distance_sigmas: f64,
    /// The largest distance of a consistent X: √ of χ²₆'s 0.999 quantile (4.74).
    pub limit_sigmas: f64,
    /// Whether the saved X's own uncertainty counted (the file carried one).
    pub saved_uncertainty: bool,
    /// The saved X, in the recording's unit.
    pub saved: TransformJson,
    /// The recording's length unit, as told by the size of its poses: `m`, `mm`, or `unknown`.
    pub length_unit: String,
    /// The factor the saved translation was multiplied by to be in the recording's unit (1000:
    /// metres to millimetres).
    pub unit_scale: f64,
    /// The quality of the recording's own calibration: `good`, or `questionable` while a caution
    /// of `recording.warnings` stands.
    pub quality: Assessment,
    /// What the verdict means and what to do, in words.
    pub message: String,
    /// Notes on how the comparison was made (a unit conversion, a saved X without uncertainty).
    pub notes: Vec<String>,
    /// The recording's own calibration (absent when it was refused).
    pub recording: Option<HandEyeReport>,
    /// On the pixels (`verify --intrinsics`): the reprojection error of the recording's
    /// detections with the saved X and with the recording's own, the target's pose fitted to each.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pixels: Option<PixelComparison>,
    /// On the pixels: the camera pose each record's solve started from, in input order, under the
    /// reading of `recording` (as given when it was refused), as
    /// [`ReprojectionSummary::start_poses`](crate::ReprojectionSummary::start_poses) gives them;
    /// empty on pose pairs. Not in the JSON.
    #[serde(skip)]
    pub start_poses: Vec<Transform>,
}

/// The saved X and the recording's own on the pixels: the target's pose fitted with each X held
/// fixed, over the detections the recording's solve kept.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PixelComparison {
    /// RMS reprojection error with the saved X, pixels.
    pub saved_rms_px: f64,
    /// RMS reprojection error with the recording's own X, pixels.
    pub own_rms_px: f64,
    /// Per frame, in input order.
    pub per_frame: Vec<FramePixels>,
}

/// One frame's reprojection RMS with each X.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FramePixels {
    /// The frame's name (`file:line` from the command line).
    pub name: String,
    /// With the saved X, pixels.
    pub saved_px: f64,
    /// With the recording's own X, pixels.
    pub own_px: f64,
}

/// Checks a saved X against a recording (see the module docs): pose pairs, or the target's
/// detections with the camera's intrinsics ([`Input::Pixels`]).
///
/// On the pixels the recording is calibrated as [`calibrate`](crate::calibrate()) does it there,
/// and its X compared with the saved one by the same test and words (the covariance is the pixel
/// solve's); `pixels` adds the reprojection error of the recording's detections with the saved X
/// and with the recording's own, the target's pose fitted to each with X held fixed: how much worse
/// the saved X explains the pixels, frame by frame. `refine_intrinsics` is refused there (a saved X
/// is checked with the intrinsics it was calibrated with).
///
/// Errors: those of [`calibrate`](crate::calibrate()) but a refusal for degenerate motions or too
/// few motions, which is the verdict `undetermined`; a `setup` that is not the one the saved file
/// declares ([`SavedX::setup_for`] chooses it from the file when none is given).
pub fn verify<'a>(
    saved: &SavedX,
    input: impl Into<Input<'a>>,
    setup: Setup,
    options: &Options,
) -> Result<Verification> {
    if let Problem::RobotWorld(_) = options.problem {
        return Err(Error::InvalidParameter {
            name: "problem",
            message: "verify checks an X calibrated as hand–eye (A X = X B): the robot-world problem is not offered".into(),
        });
    }
    match input.into() {
        Input::Poses(poses) => verify_poses(saved, poses, setup, options),
        Input::Pixels { frames, camera } => verify_on_pixels(saved, frames, camera, setup, options),
    }
}

/// [`verify`] on pose pairs.
fn verify_poses(
    saved: &SavedX,
    poses: &[PosePair],
    setup: Setup,
    options: &Options,
) -> Result<Verification> {
    same_setup(saved, setup)?;
    let mut notes = Vec::new();
    let report = match hand_eye_on_poses(poses, setup, options) {
        Err(e) => match low_dof::wants_prior(&e) {
            Some(free) => with_saved_prior(saved, poses, setup, options, free, &mut notes),
            None => Err(e),
        },
        ok => ok,
    };
    let report = match report {
        Ok(r) => r,
        Err(e @ (Error::Degenerate { .. } | Error::TooFewMotions { .. })) => {
            return Ok(cannot_tell(saved, poses, &e, notes));
        }
        Err(e) => return Err(e),
    };
    let own = recording_covariance(poses, setup, &report);
    Ok(compared(saved, poses, report, own, notes))
}

/// Checks a saved X against a recording with detections (`verify --intrinsics`): the recording is
/// calibrated on the pixels as [`calibrate`](crate::calibrate()) does it, and its X compared with
/// the saved one by the same test and words as [`verify`](crate::verify) (the covariance is the
/// pixel solve's). `pixels` adds the reprojection error of the recording's detections with the
/// saved X and with the recording's own, the target's pose fitted to each with X held fixed
/// (`target_with_x`): how much worse the saved X explains the pixels, frame by frame; `start_poses`
/// are the camera poses the solve started from, under the reading applied (as given when the solve
/// itself was refused).
///
/// Errors: those of [`calibrate`](crate::calibrate()) on the pixels but a refusal for degenerate or
/// too few motions, which is the verdict `undetermined`.
fn verify_on_pixels(
    saved: &SavedX,
    frames: &[Frame],
    camera: &Intrinsics,
    setup: Setup,
    options: &Options,
) -> Result<Verification> {
    not_on_pixels(
        options.reject_outliers,
        &options.priors,
        options.robot_model.as_ref(),
    )?;
    if options.refine_intrinsics {
        return Err(Error::InvalidParameter {
            name: "refine_intrinsics",
            message: "not offered by verify: a saved X is checked with the intrinsics it was calibrated with (give the refined ones with --intrinsics)".into(),
        });
    }
    same_setup(saved, setup)?;
    let notes = Vec::new();
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
    let report = match hand_eye_on_pixels(
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
    let own = Matrix6::from_fn(|i, j| report.uncertainty.covariance[i][j]);
    let mut v = compared(saved, &poses, report, own, notes);
    v.start_poses = choice.start_poses;
    v.pixels = Some(PixelComparison {
        saved_rms_px: with_saved.rms_px,
        own_rms_px: with_own.rms_px,
        per_frame,
    });
    Ok(v)
}

/// The setup the recording is read in must be the saved X's, when the file says (see
/// [`SavedX::setup_for`]).
fn same_setup(saved: &SavedX, setup: Setup) -> Result<()> {
    saved.setup_for(Some(setup)).map(|_| ())
}

/// The covariance of the recording's X that the comparison counts, on pose pairs: the report's
/// bootstrap covariance, raised to the first-order covariance of the per-pose problem
/// (`solve::joint_covariance` at X and the target robot-world finds) along every direction where
/// that is larger. The bootstrap's sizes are honest, but its shape from a few stations is not: on
/// noisy copies of kinhec's station recordings (`cargo run --release -p handeye --example
/// verify_power`) the true X was more than the limit away from the estimate in 2–11 of 60 copies
/// with the bootstrap alone, 0–4 with both. The bootstrap alone where the report's poses are not the
/// input's (another reading, outliers left out) or a prior or the low-DOF form holds a component.
fn recording_covariance(poses: &[PosePair], setup: Setup, report: &HandEyeReport) -> Matrix6<f64> {
    let bootstrap = Matrix6::from_fn(|i, j| report.uncertainty.covariance[i][j]);
    if report.reading.applied != crate::model::findings::Reading::AsGiven
        || report.outliers.rejected
        || !report.prior.is_empty()
        || report.low_dof.is_some()
    {
        return bootstrap;
    }
    match first_order(poses, setup, &report.transform) {
        Some(a) => envelope(&bootstrap, &a),
        None => bootstrap,
    }
}

/// X's first-order covariance from `poses` at `x` (the target from the refined robot-world
/// solve), in the bootstrap's convention (the rotation as a left rotation vector); `None` when
/// either is not found or not finite.
fn first_order(poses: &[PosePair], setup: Setup, x: &Transform) -> Option<Matrix6<f64>> {
    let target = robot_world(RobotWorldMethod::Refine, poses, setup)
        .ok()?
        .target;
    let joint = joint_covariance(poses, setup, x, &target)?;
    let block: Matrix6<f64> = joint.fixed_view::<6, 6>(0, 0).into_owned();
    let mut m = Matrix6::identity();
    m.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(x.rotation.matrix());
    let c = m * block * m.transpose();
    c.iter().all(|v| v.is_finite()).then_some(c)
}

/// The smallest covariance at least `b` and at least `a` along every direction: in `b`'s
/// whitened frame, `a`'s eigenvalues raised to 1.
fn envelope(b: &Matrix6<f64>, a: &Matrix6<f64>) -> Matrix6<f64> {
    let eb = SymmetricEigen::new(*b);
    if eb.eigenvalues.min() <= 0.0 {
        return *b;
    }
    let half = eb.eigenvectors
        * Matrix6::from_diagonal(&eb.eigenvalues.map(f64::sqrt))
        * eb.eigenvectors.transpose();
    let Some(inverse) = half.try_inverse() else {
        return *b;
    };
    let w = SymmetricEigen::new(inverse * a * inverse.transpose());
    let raised = w.eigenvectors
        * Matrix6::from_diagonal(&w.eigenvalues.map(|l| l.max(1.0)))
        * w.eigenvectors.transpose();
    half * raised * half.transpose()
}

/// The saved X against the recording's own calibration `report` (the poses give the recording's
/// unit and working distance), with `own` the covariance of the recording's X: the χ² test of the
/// module docs, its verdict and words.
fn compared(
    saved: &SavedX,
    poses: &[PosePair],
    report: HandEyeReport,
    own: Matrix6<f64>,
    mut notes: Vec<String>,
) -> Verification {
    let new = report.transform;
    let scale = unit_scale(saved, poses, &new, &mut notes);
    let mut x = saved.x;
    x.translation.vector *= scale;
    let e = difference(&x, &new);
    let mut cov = own;
    match &saved.covariance {
        Some(c) => {
            let factor = |i: usize| if i < 3 { 1.0 } else { scale };
            cov += Matrix6::from_fn(|i, j| c[i][j] * factor(i) * factor(j));
        }
        None => notes
            .push("the saved X carries no uncertainty: the recording's alone counts".to_string()),
    }
    let length = x
        .translation
        .vector
        .norm()
        .max(new.translation.vector.norm())
        .max(working_distance(poses));
    let distance = mahalanobis(&e, &cov, length);
    let limit = limit_sigmas();
    let difference = Sizes {
        rotation_deg: e.fixed_rows::<3>(0).norm().to_degrees(),
        translation: e.fixed_rows::<3>(3).norm(),
    };
    let sigma = Sizes {
        rotation_deg: trace3(&cov, 0).sqrt().to_degrees(),
        translation: trace3(&cov, 3).sqrt(),
    };
    let detectable = detectable(&cov, limit, &sigma, poses.len());
    let (verdict, message) = judged(
        &report,
        Judged {
            difference: &difference,
            sigma: &sigma,
            detectable: &detectable,
            distance,
            limit,
            length,
            poses: poses.len(),
        },
        recording_unit(poses),
    );
    let unit = recording_unit(poses);
    Verification {
        verdict,
        difference,
        sigma,
        detectable,
        tolerance: None,
        distance_sigmas: distance,
        limit_sigmas: limit,
        saved_uncertainty: saved.covariance.is_some(),
        saved: TransformJson::from(&x),
        length_unit: unit_name(unit).into(),
        unit_scale: scale,
        quality: report.verdict,
        message,
        notes,
        recording: Some(report),
        pixels: None,
        start_poses: Vec::new(),
    }
}

/// What the recording's detections prefer to the intrinsics given, in words (the focal length's
/// scale or k1), and how far that moves its own X (degrees, length, sigmas), when its report warns
/// of it.
fn preferred_intrinsics(report: &HandEyeReport) -> Option<(String, f64, f64, f64)> {
    report.warnings.iter().find_map(|w| match w {
        Warning::IntrinsicsDisagree {
            focal_scale,
            rotation_deg,
            translation,
            sigmas,
            ..
        } => Some((
            format!("the focal length scaled by {focal_scale:.3}"),
            *rotation_deg,
            *translation,
            *sigmas,
        )),
        Warning::DistortionDisagrees {
            k1_best,
            rotation_deg,
            translation,
            sigmas,
            ..
        } => Some((
            format!("the radial distortion k1 = {k1_best:.4}"),
            *rotation_deg,
            *translation,
            *sigmas,
        )),
        _ => None,
    })
}

/// What the χ² test's numbers say about the saved X: the verdict and its words.
struct Judged<'a> {
    /// The saved X minus the recording's, its one sigma, and the smallest change the test sees.
    difference: &'a Sizes,
    sigma: &'a Sizes,
    detectable: &'a Sizes,
    /// The Mahalanobis distance and its limit, sigmas.
    distance: f64,
    limit: f64,
    /// The largest length of the comparison (translations, working distance).
    length: f64,
    /// The recording's poses.
    poses: usize,
}

/// The verdict of the comparison [`compared`] measured, and its words: inconsistent beyond the
/// limit (with a reliable shape or sizes beyond [`SIZE_LIMIT`]) unless the recording's own
/// detections disagree with the intrinsics; undetermined when the recording determines X weakly.
fn judged(
    report: &HandEyeReport,
    j: Judged<'_>,
    unit: Option<LengthUnit>,
) -> (Consistency, String) {
    let Judged {
        difference,
        sigma,
        detectable,
        distance,
        limit,
        length,
        ..
    } = j;
    let weak = report.uncertainty.verdict() != Verdict::Determined;
    let len = |v: f64| length_words(v, unit);
    // The sizes' test, which holds whatever the covariance's shape: a bootstrap over a few poses
    // gives a covariance of unreliable shape, thin in some direction, and the distance alone
    // then calls the same rig inconsistent (at 4–6 poses, up to 18 sigmas for a difference of
    // a fifth of the sizes).
    let sizes = (difference.rotation_deg / sigma.rotation_deg)
        .max(difference.translation / sigma.translation);
    let shape_reliable = j.poses >= SHAPE_POSES;
    // What the recording's detections prefer (in words), and how far that moves its own X.
    let intrinsics = preferred_intrinsics(report);
    if !bounded(sigma, distance, length) {
        // The invariant: never consistent (nor inconsistent) on a sigma that is infinite, missing
        // or larger than the rig itself.
        (
            Consistency::Undetermined,
            format!(
                "this recording cannot tell: the uncertainty of the comparison (one sigma {:.3}° and {}) is as large as the rig itself ({}), so no difference would show; check the saved X's covariance",
                sigma.rotation_deg,
                len(sigma.translation),
                len(length)
            ),
        )
    } else if distance > limit
        && (shape_reliable || sizes > SIZE_LIMIT)
        && let Some((preferred, rotation_deg, translation, sigmas)) = intrinsics
    {
        // The recording's own X depends on intrinsics its detections disagree with: a
        // difference is no evidence that the camera moved.
        (
            Consistency::Undetermined,
            format!(
                "this recording cannot tell: the saved X differs by {:.3}° and {} ({distance:.1} sigmas), but the recording's detections and robot motions agree better with {preferred}, which moves the recording's own X by {rotation_deg:.3}° and {} ({sigmas:.1} sigmas): check the intrinsics (this camera's, at this resolution, zoom and focus) and the target's size, then verify again",
                difference.rotation_deg,
                len(difference.translation),
                len(translation),
            ),
        )
    } else if distance > limit && (shape_reliable || sizes > SIZE_LIMIT) {
        (
            Consistency::Inconsistent,
            inconsistent_words(difference, distance, length, unit),
        )
    } else if distance > limit {
        (
            Consistency::Undetermined,
            format!(
                "this recording cannot tell: the saved X differs by {:.3}° and {}, within the sizes of the uncertainty ({:.2} of them), but {distance:.1} sigmas along the directions this recording determines best; with {} poses the shape of its uncertainty is not reliable: record more poses (10 or more, rotating the hand about different axes) to tell",
                difference.rotation_deg,
                len(difference.translation),
                sizes,
                j.poses
            ),
        )
    } else if weak && !report.outliers.poses.is_empty() && !report.outliers.rejected {
        (
            Consistency::Undetermined,
            format!(
                "this recording cannot tell: {} of its poses disagree with the others and blur X (one sigma {:.3}° and {}), so a difference of up to {:.2}° or {} would pass; pass `--reject-outliers` to leave them out",
                report.outliers.poses.len(),
                sigma.rotation_deg,
                len(sigma.translation),
                limit * sigma.rotation_deg,
                len(limit * sigma.translation)
            ),
        )
    } else if weak {
        (
            Consistency::Undetermined,
            format!(
                "this recording cannot tell: it determines X only weakly (one sigma {:.3}° and {}), so a difference of up to {:.2}° or {} would pass; record motions that rotate the hand about several different axes (20° or more each) and move it across the working volume",
                sigma.rotation_deg,
                len(sigma.translation),
                limit * sigma.rotation_deg,
                len(limit * sigma.translation)
            ),
        )
    } else {
        (
            Consistency::Consistent,
            format!(
                "{}; {}",
                fits_words(difference, distance, limit, unit),
                unseen_words(detectable, unit)
            ),
        )
    }
}

/// Whether a comparison's sigma and distance can mean something: finite, the rotation's one sigma
/// at most 180° and the translation's at most the comparison's `length`.
fn bounded(sigma: &Sizes, distance: f64, length: f64) -> bool {
    distance.is_finite()
        && sigma.rotation_deg <= 180.0
        && sigma.translation <= length
        && sigma.translation.is_finite()
}

/// The largest ratio of a difference's size to its one sigma (√trace of its block) that the same
/// rig gives at 0.999, whatever the shape of the covariance: √χ²₁(0.999) = 3.29, the tail of an
/// error all along one direction (an isotropic one gives at most 2.33). Measured on subsets of
/// 4–15 poses of three realistic recordings: at most 2.01.
pub const SIZE_LIMIT: f64 = 3.29;

/// Poses from which the shape of the recording's covariance is trusted (twice X's six
/// parameters): below, a difference counts as inconsistent only when its sizes also exceed
/// [`SIZE_LIMIT`]. Measured on subsets of three realistic recordings: the distance of the same
/// rig reached 18 sigmas at 4 poses, 6.2 at 6 and 4.7 at 8; at most 3.8 from 10 on.
pub const SHAPE_POSES: usize = 12;

/// The verdict of a recording whose own calibration was refused by `refusal`.
/// A low-DOF recording (every motion turns about one axis) never determines X's translation along
/// that axis (the component `free`): it is taken from the saved X, in the recording's unit and
/// exactly (the difference there is then none, and the saved X's own sigma counts in the
/// comparison), and the rest of X is checked.
fn with_saved_prior(
    saved: &SavedX,
    poses: &[PosePair],
    setup: Setup,
    options: &Options,
    free: Component,
    notes: &mut Vec<String>,
) -> Result<HandEyeReport> {
    let solve = |scale: f64| {
        let mut with_prior = options.clone();
        with_prior.priors.push(Prior {
            component: free,
            value: saved.x.translation.vector[free.index()] * scale,
            sigma: 0.0,
            // In the recording's unit, which is then taken as said (a camera at the flange's
            // height is no unit mix-up).
            unit: crate::check::units::length_unit(poses),
        });
        hand_eye_on_poses(poses, setup, &with_prior)
    };
    // The saved X's unit: told by the file, else guessed by its size, then judged on the
    // components the recording determines (the free one is the saved X's, whatever its unit).
    let size = saved.x.translation.vector.norm();
    let guess = match (told_scale(saved, poses), recording_unit(poses)) {
        (Some((scale, _)), _) => scale,
        (None, Some(LengthUnit::Metre)) if size > NOT_METRES => 1e-3,
        (None, Some(LengthUnit::Millimetre)) if size < NOT_MILLIMETRES => 1000.0,
        _ => 1.0,
    };
    let first = solve(guess)?;
    let i = free.index();
    let mut across = saved.clone();
    across.x.translation.vector[i] = 0.0;
    let mut new_across = first.transform;
    new_across.translation.vector[i] = 0.0;
    let scale = unit_scale(&across, poses, &new_across, &mut Vec::new());
    let report = if scale == guess { first } else { solve(scale)? };
    notes.push(format!(
        "every motion of the recording turns about one axis (a low-DOF robot), so it cannot check X's {}: that component was taken from the saved X, and the rest of X is checked",
        free.name()
    ));
    Ok(report)
}

fn cannot_tell(
    saved: &SavedX,
    poses: &[PosePair],
    refusal: &Error,
    notes: Vec<String>,
) -> Verification {
    Verification {
        verdict: Consistency::Undetermined,
        difference: Sizes {
            rotation_deg: f64::NAN,
            translation: f64::NAN,
        },
        sigma: Sizes {
            rotation_deg: f64::INFINITY,
            translation: f64::INFINITY,
        },
        detectable: Sizes {
            rotation_deg: f64::INFINITY,
            translation: f64::INFINITY,
        },
        tolerance: None,
        distance_sigmas: f64::NAN,
        limit_sigmas: limit_sigmas(),
        saved_uncertainty: saved.covariance.is_some(),
        saved: TransformJson::from(&saved.x),
        length_unit: unit_name(recording_unit(poses)).into(),
        unit_scale: 1.0,
        quality: Assessment::Questionable,
        message: format!(
            "this recording cannot tell whether the saved X fits: it does not determine X ({refusal}){}",
            if low_dof::missing(refusal).is_some() {
                // The refusal says what a low-DOF robot can record; a 6-DOF robot that turned one
                // joint can do more.
                "; if the robot can turn about other axes, record motions that rotate the hand about several different axes (20° or more each)"
            } else {
                "; record motions that rotate the hand about several different axes (20° or more each) and move it across the working volume"
            }
        ),
        notes,
        recording: None,
        pixels: None,
        start_poses: Vec::new(),
    }
}

/// The smallest change the comparison sees (see [`Verification::detectable`]): `limit` times the
/// largest one-sigma of the rotation and of the translation block of `cov` (whatever the
/// translation does, a rotation beyond it is beyond the limit: the Mahalanobis distance of a
/// difference is at least that of its rotation part alone), and below [`SHAPE_POSES`] poses at
/// least [`SIZE_LIMIT`] times the sizes of `sigma`, which the verdict also asks there.
fn detectable(cov: &Matrix6<f64>, limit: f64, sigma: &Sizes, poses: usize) -> Sizes {
    let largest = |from: usize| {
        let block = cov.fixed_view::<3, 3>(from, from).into_owned();
        SymmetricEigen::new(block).eigenvalues.max().max(0.0).sqrt()
    };
    let mut d = Sizes {
        rotation_deg: limit * largest(0).to_degrees(),
        translation: limit * largest(3),
    };
    if poses < SHAPE_POSES {
        d.rotation_deg = d.rotation_deg.max(SIZE_LIMIT * sigma.rotation_deg);
        d.translation = d.translation.max(SIZE_LIMIT * sigma.translation);
    }
    d
}

/// "the saved X fits this recording: it differs by 0.012° and 0.31 mm, 1.2 sigmas (at most 4.74
/// for the same rig)".
fn fits_words(difference: &Sizes, distance: f64, limit: f64, unit: Option<LengthUnit>) -> String {
    format!(
        "the saved X fits this recording: it differs by {:.3}° and {}, {distance:.1} sigmas (at most {limit:.2} for the same rig)",
        difference.rotation_deg,
        length_words(difference.translation, unit)
    )
}

/// "no change larger than 0.40° / 9.00 mm; smaller ones cannot be seen in this recording".
fn unseen_words(detectable: &Sizes, unit: Option<LengthUnit>) -> String {
    format!(
        "no change larger than {:.2}° / {}; smaller ones cannot be seen in this recording",
        detectable.rotation_deg,
        length_words(detectable.translation, unit)
    )
}

impl Verification {
    /// The verdict against the change that matters to the user (`verify --tolerance DEG,LENGTH`,
    /// the length in the recording's unit): a consistent X whose recording could not have seen a
    /// change of that size ([`Verification::detectable`] beyond the tolerance in either part) is
    /// `undetermined`, with words saying what the recording can see and what to record. Other
    /// verdicts stand (an inconsistent X moved, whatever the tolerance; a note says when the
    /// difference is within it).
    ///
    /// Errors: a tolerance that is not two positive finite sizes.
    pub fn within(mut self, tolerance: Sizes) -> Result<Verification> {
        let fine = |v: f64| v.is_finite() && v > 0.0;
        if !fine(tolerance.rotation_deg) || !fine(tolerance.translation) {
            return Err(Error::InvalidParameter {
                name: "tolerance",
                message: format!(
                    "expected two positive sizes (degrees, and a length in the recording's unit), found {} and {}",
                    tolerance.rotation_deg, tolerance.translation
                ),
            });
        }
        let unit = LengthUnit::from_suffix(&self.length_unit);
        let asked = format!(
            "{:.2}° / {}",
            tolerance.rotation_deg,
            length_words(tolerance.translation, unit)
        );
        match self.verdict {
            Consistency::Consistent if !self.detectable.within(&tolerance) => {
                self.verdict = Consistency::Undetermined;
                self.message = format!(
                    "this recording cannot tell whether the saved X is within your tolerance of {asked}: it differs by {:.3}° and {} ({:.1} sigmas), but a change smaller than {:.2}° / {} could not have been seen in it; record more poses, rotating the hand about several different axes (20° or more each) and moving it across the working volume, or verify with a larger tolerance",
                    self.difference.rotation_deg,
                    length_words(self.difference.translation, unit),
                    self.distance_sigmas,
                    self.detectable.rotation_deg,
                    length_words(self.detectable.translation, unit)
                );
            }
            Consistency::Consistent => {
                self.message = format!(
                    "{}; no change larger than your tolerance of {asked} (this recording sees changes larger than {:.2}° / {})",
                    fits_words(
                        &self.difference,
                        self.distance_sigmas,
                        self.limit_sigmas,
                        unit
                    ),
                    self.detectable.rotation_deg,
                    length_words(self.detectable.translation, unit)
                );
            }
            Consistency::Inconsistent if self.difference.within(&tolerance) => {
                self.notes.push(format!(
                    "the difference is within your tolerance of {asked}, but more than this recording's uncertainty allows: the camera moved (a little)"
                ));
            }
            _ => {}
        }
        self.tolerance = Some(tolerance);
        Ok(self)
    }
}

/// The words of an inconsistent X: by how much, and the likely cause.
fn inconsistent_words(d: &Sizes, distance: f64, length: f64, unit: Option<LengthUnit>) -> String {
    let cause = if d.rotation_deg > LARGE_ROTATION_DEG || d.translation > LARGE_TRANSLATION * length
    {
        "far more than a bump moves a camera: a different rig or setup, or a saved X that was wrong"
    } else {
        "the camera moved on its mount since X was saved (a bump, a re-mount), or the saved X was calibrated from poor data"
    };
    format!(
        "the saved X does not fit this recording: it differs by {:.3}° and {} ({distance:.1} sigmas); likely cause: {cause}; recalibrate from this recording",
        d.rotation_deg,
        length_words(d.translation, unit)
    )
}

fn unit_name(unit: Option<LengthUnit>) -> &'static str {
    unit.map_or("unknown", LengthUnit::suffix)
}

/// A length in millimetres when the recording's unit is known, else in its own unit.
fn length_words(v: f64, unit: Option<LengthUnit>) -> String {
    match unit {
        Some(LengthUnit::Metre) => format!("{:.2} mm", v * 1e3),
        Some(LengthUnit::Millimetre) => format!("{v:.2} mm"),
        _ => format!("{v:.4} (the input's unit)"),
    }
}

/// A difference above this many degrees is more than a bump.
const LARGE_ROTATION_DEG: f64 = 10.0;
/// A difference above this fraction of the scene's size (X's translation or the working distance)
/// is more than a bump.
const LARGE_TRANSLATION: f64 = 0.25;

/// √ of χ²₆'s [`LEVEL`] quantile.
pub fn limit_sigmas() -> f64 {
    ChiSquared::new(6.0)
        .map(|c| c.inverse_cdf(LEVEL))
        .unwrap_or(22.458)
        .sqrt()
}

/// The factor bringing the saved translation into the recording's unit, with a note when it is
/// not 1.
fn unit_scale(saved: &SavedX, poses: &[PosePair], new: &Transform, notes: &mut Vec<String>) -> f64 {
    let (scale, words) = match (told_scale(saved, poses), saved.unit) {
        (Some(told), _) => told,
        (None, None) => {
            // A file that does not say: the unit whose X is nearer the recording's, when a factor
            // of 1000 brings it ten times nearer.
            let gap = |k: f64| (saved.x.translation.vector * k - new.translation.vector).norm();
            if gap(1000.0) * 10.0 < gap(1.0) {
                (1000.0, "metres (by its size), the recording in millimetres")
            } else if gap(1e-3) * 10.0 < gap(1.0) {
                (1e-3, "millimetres (by its size), the recording in metres")
            } else {
                (1.0, "")
            }
        }
        _ => (1.0, ""),
    };
    if scale != 1.0 {
        notes.push(format!(
            "the saved X is in {words}: its translation was multiplied by {scale}"
        ));
    }
    scale
}

/// The factor to the recording's unit when the saved file tells its own unit and it differs from
/// the recording's, with the words of the note.
fn told_scale(saved: &SavedX, poses: &[PosePair]) -> Option<(f64, &'static str)> {
    match (saved.unit, recording_unit(poses)) {
        (Some(LengthUnit::Metre), Some(LengthUnit::Millimetre)) => {
            Some((1000.0, "metres, the recording in millimetres"))
        }
        (Some(LengthUnit::Millimetre), Some(LengthUnit::Metre)) => {
            Some((1e-3, "millimetres, the recording in metres"))
        }
        _ => None,
    }
}

/// A saved X of unknown unit whose translation is longer than this is not in metres (a camera 20 m
/// from its flange or base is no rig): millimetres, on a recording in metres.
const NOT_METRES: f64 = 20.0;

/// A saved X of unknown unit whose translation is shorter than this is not in millimetres (a camera
/// within 2 mm of the flange's origin): metres, on a recording in millimetres.
const NOT_MILLIMETRES: f64 = 2.0;

/// Metres or millimetres from the size of the poses' translations (the median of each pose's
/// larger translation), `None` when it fits neither.
fn recording_unit(poses: &[PosePair]) -> Option<LengthUnit> {
    crate::check::units::length_unit(poses)
}

/// (log(R_a R_bᵀ), t_a − t_b): the convention of the bootstrap's replicate errors.
fn difference(a: &Transform, b: &Transform) -> Vector6<f64> {
    let dr = log_so3(&(a.rotation.matrix() * b.rotation.matrix().transpose()));
    let dt: Vector3<f64> = a.translation.vector - b.translation.vector;
    Vector6::new(dr.x, dr.y, dr.z, dt.x, dt.y, dt.z)
}

/// √(eᵀ C⁻¹ e), C floored at 1e-9 rad and 1e-9 × `length` one-sigma per coordinate (noise-free
/// data would otherwise make any rounding infinitely many sigmas).
fn mahalanobis(e: &Vector6<f64>, cov: &Matrix6<f64>, length: f64) -> f64 {
    let mut c = *cov;
    for i in 0..6 {
        let floor = if i < 3 {
            1e-9
        } else {
            1e-9 * length.max(f64::MIN_POSITIVE)
        };
        c[(i, i)] += floor * floor;
    }
    let eigen = SymmetricEigen::new(c);
    let mut d2 = 0.0;
    for k in 0..6 {
        let v = eigen.eigenvectors.column(k);
        let lambda = eigen.eigenvalues[k];
        if lambda > 0.0 {
            d2 += v.dot(e).powi(2) / lambda;
        }
    }
    d2.sqrt()
}

fn trace3(c: &Matrix6<f64>, from: usize) -> f64 {
    (from..from + 3).map(|i| c[(i, i)]).sum::<f64>().max(0.0)
}
