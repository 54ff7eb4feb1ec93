//! A batch robot-world–hand-eye calibration: X and the target's pose together, how far to trust
//! both, and the per-pose residuals.
//!
//! [`calibrate_robot_world`] is what `handeye calibrate --robot-world` and the Python
//! `calibrate(..., robot_world=True)` run, and [`RobotWorldReport`] is what both print:
//! 1. the readings a user may have meant are tried, and the poses that break the screw invariants
//!    of their motions found, as in [`crate::calibrate::batch::calibrate`] ([`Error::Misread`] unless
//!    [`Fix`] says otherwise; outliers named in a warning, or left out with `reject_outliers`; a
//!    refusal names them);
//! 2. the method ([`RobotWorldMethod`]) solves Q_i X C_i = Y from every pose once
//!    ([`crate::solve::shah`], [`crate::solve::li`], [`crate::solve::refine_robot_world`]);
//! 3. the uncertainty of **X** is the hand–eye report's bootstrap ([`crate::check::uncertainty::bootstrap`]:
//!    every pose rebuilt to agree with X̂ and the mean target pose, its own residual put back with a
//!    random sign, re-solved by the *same* robot-world method); the uncertainty of the **target
//!    pose** is the first-order covariance of the joint per-pose residual problem at the solution
//!    ([`crate::solve::joint_covariance`]: `s² (JᵀJ)⁻¹`, each residual block's noise estimated from
//!    its own residuals; `replicates` 0 says so). A direction of X or of the target that either
//!    leaves undetermined refuses the result ([`Degeneracy::Undetermined`]), a weak one of X is a
//!    warning. The first-order covariance is close to the truth on well-posed data (kinhec: median
//!    error/σ 1.0) but underestimates nearly degenerate directions (3–4° where the bootstrap
//!    says 22–23° on single-joint recordings), which is why X's refusal rests on the bootstrap;
//! 4. the residuals per pose: the angle between R_Y and R_Q R_X R_C (degrees) and how far pose i
//!    puts the target's origin from Y's (input units).

use std::collections::BTreeMap;

use nalgebra::{Matrix3, Matrix6};
use serde::{Deserialize, Serialize};

use crate::calibrate::Input;
use crate::calibrate::batch::{
    Fix, Options, Outliers, ReadingReport, Units, check_joints, explained, first_what_motions_lack,
    outlier_report, outlier_warning, plausible, read_poses, systematic_test,
    widened_for_systematic, without, working_distance,
};
use crate::calibrate::low_dof::{self, LowDofReport, Plan};
use crate::check::outliers::translation_scale;
use crate::check::quality::OUTLIER_DEG;
use crate::check::systematic::Systematic;
use crate::check::uncertainty::{
    Uncertainty, bootstrap, check_replicates, median_target, summarise, warn_weak,
};
use crate::model::error::{Degeneracy, Error, Result};
use crate::model::findings::{Assessment, Part, Verdict, Written};
use crate::model::motion::{Pairing, PosePair, Setup};
use crate::model::pose::TransformJson;
use crate::model::pose::{Transform, rotation_matrix};
use crate::model::prior::{Prior, PriorsUsed, check_priors};
use crate::solve::{
    JointCovariance, PoseResidual, RobotWorldMethod, joint_covariance, joint_covariance_given,
    pose_residuals, robot_world, target_frame,
};

/// How to calibrate X and the target together.
#[derive(Debug, Clone, PartialEq)]
pub struct RobotWorldOptions {
    /// The solver. Default [`RobotWorldMethod::Refine`].
    pub method: RobotWorldMethod,
    /// What to do about a better reading of the input. Default [`Fix::Refuse`].
    pub fix: Fix,
    /// Bootstrap replicates for X's uncertainty, within
    /// [`Options::REPLICATES_RANGE`](crate::Options::REPLICATES_RANGE). Default 40, as
    /// [`Options`]'.
    pub replicates: usize,
    /// Leave out the outlier poses (found as in the hand–eye report, by the screw invariants of
    /// their motions). Default false: they are kept and named in a warning.
    pub reject_outliers: bool,
    /// A pose whose median rotation-angle gap is above this (degrees) is an outlier. Default 3,
    /// as [`Options`]'.
    pub outlier_deg: f64,
    /// How each pose is named in messages (e.g. `file:line`), by input index. Default empty
    /// (`pose i`).
    pub pose_names: Vec<String>,
    /// The directions in which the input wrote its poses (see `Options::written`).
    pub written: Written,
    /// The point (camera frame, input unit) of X's `uncertainty.at_point`. Default `None`: the
    /// median target position seen by the camera.
    pub point: Option<[f64; 3]>,
    /// The joint angles of each pose by input index (radians), as in the hand–eye options.
    pub joints: Vec<Vec<f64>>,
    /// The robot's DH table (`--robot-model`), where given with the joint angles: the
    /// systematic-error test then also asks whether the residuals lie along what an error of its
    /// parameters does (`check::identification`). Default none.
    pub robot_model: Option<crate::model::kinematics::Kinematics>,
    /// Priors on components of X's translation, as in the hand–eye options (`--prior`): a
    /// low-DOF recording's free component of X comes from its prior, and the target's coupled
    /// component follows from it. Default empty.
    pub priors: Vec<Prior>,
    /// Refine the camera's intrinsics with X on the pixels (`--refine-intrinsics`; only with the
    /// calibration on the pixels, refused elsewhere). Default false.
    pub refine_intrinsics: bool,
}

impl Default for RobotWorldOptions {
    fn default() -> Self {
        Self {
            method: RobotWorldMethod::Refine,
            fix: Fix::Refuse,
            replicates: crate::check::uncertainty::REPLICATES,
            reject_outliers: false,
            outlier_deg: OUTLIER_DEG,
            pose_names: Vec::new(),
            written: Written::NAMED,
            point: None,
            joints: Vec::new(),
            robot_model: None,
            priors: Vec::new(),
            refine_intrinsics: false,
        }
    }
}

/// The target's pose in a [`RobotWorldReport`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TargetReport {
    /// `base_from_target` (eye-in-hand) or `gripper_from_target` (eye-to-hand).
    pub frame: String,
    /// The pose (`translation`, `quaternion_xyzw`, `matrix` in the JSON object itself).
    #[serde(flatten)]
    pub pose: TransformJson,
    /// One-sigma uncertainty (first-order covariance; axes in the target pose's reference frame,
    /// the robot base or the gripper).
    pub uncertainty: Uncertainty,
}

/// The per-pose residuals of Q_i X C_i = Y, summarised.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PoseResidualSummary {
    /// RMS over the poses of the rotation residual, degrees.
    pub rotation_deg_rms: f64,
    /// The largest rotation residual, degrees.
    pub rotation_deg_max: f64,
    /// RMS over the poses of the translation residual, input units.
    pub translation_rms: f64,
    /// The largest translation residual, input units.
    pub translation_max: f64,
    /// Per pose, in input order; printed as `{"rotation_deg", "translation"}` (the angle and the
    /// distance), so that a report read back keeps these two, not the directions: its rotations
    /// and translations lie along x.
    #[serde(with = "printed")]
    pub per_pose: Vec<PoseResidual>,
}

impl PoseResidualSummary {
    /// The summary of the per-pose residuals.
    pub(crate) fn of(per_pose: Vec<PoseResidual>) -> Self {
        let n = per_pose.len().max(1) as f64;
        let rms = |f: fn(&PoseResidual) -> f64| {
            (per_pose.iter().map(|r| f(r).powi(2)).sum::<f64>() / n).sqrt()
        };
        let max = |f: fn(&PoseResidual) -> f64| per_pose.iter().map(f).fold(0.0, f64::max);
        Self {
            rotation_deg_rms: rms(PoseResidual::angle_deg),
            rotation_deg_max: max(PoseResidual::angle_deg),
            translation_rms: rms(PoseResidual::distance),
            translation_max: max(PoseResidual::distance),
            per_pose,
        }
    }
}

/// A pose's residual as a report prints it: its angle and its distance.
#[derive(Serialize, Deserialize)]
struct Printed {
    rotation_deg: f64,
    translation: f64,
}

/// `serde(with)` of [`PoseResidualSummary::per_pose`].
mod printed {
    use nalgebra::Vector3;
    use serde::{Deserialize, Deserializer, Serializer};

    use super::{PoseResidual, Printed};

    pub(super) fn serialize<S: Serializer>(
        rows: &[PoseResidual],
        serializer: S,
    ) -> Result<S::Ok, S::Error> {
        serializer.collect_seq(rows.iter().map(|r| Printed {
            rotation_deg: r.angle_deg(),
            translation: r.distance(),
        }))
    }

    pub(super) fn deserialize<'de, D: Deserializer<'de>>(
        deserializer: D,
    ) -> Result<Vec<PoseResidual>, D::Error> {
        let rows = Vec::<Printed>::deserialize(deserializer)?;
        Ok(rows
            .into_iter()
            .map(|p| {
                let angle = p.rotation_deg.to_radians();
                PoseResidual {
                    rotation: Vector3::x() * angle,
                    angle,
                    translation: Vector3::x() * p.translation,
                }
            })
            .collect())
    }
}

/// The result of [`calibrate_robot_world`]: X, the target's pose, how far to trust both.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RobotWorldReport {
    /// The verdict: `good`, or `questionable` while a caution of `warnings` stands (as the
    /// hand–eye report's).
    pub verdict: Assessment,
    /// The solver.
    pub method: RobotWorldMethod,
    /// The setup.
    pub setup: Setup,
    /// Always `robot-world` (the formulation; the hand–eye report says `pairing` instead).
    pub formulation: String,
    /// X's frame name (`gripper_from_camera` or `base_from_camera`).
    pub frame: String,
    /// X (`translation`, `quaternion_xyzw`, `matrix` in the JSON object itself).
    #[serde(flatten)]
    pub x: TransformJson,
    /// One-sigma uncertainty of X (first-order covariance; axes in X's reference frame).
    pub uncertainty: Uncertainty,
    /// The target's pose and its uncertainty.
    pub target: TargetReport,
    /// Poses used.
    pub poses: usize,
    /// Conditioning of Andreff's rotation system over the consecutive motions (1 is ideal).
    pub conditioning: f64,
    /// The reading of the input.
    pub reading: ReadingReport,
    /// Poses that disagree with the others (as in the hand–eye report).
    pub outliers: Outliers,
    /// The per-pose residuals (degrees; input units).
    pub residual: PoseResidualSummary,
    /// Cautions, each with its code, its words and the option that fixes it, if one does.
    #[serde(serialize_with = "crate::model::warning::described")]
    pub warnings: Vec<crate::model::warning::Warning>,
    /// The units of the numbers.
    pub units: Units,
    /// X as a transform (not serialised).
    #[serde(skip)]
    pub transform: Transform,
    /// The target pose as a transform (not serialised).
    #[serde(skip)]
    pub target_transform: Transform,
    /// The test for an error that follows the robot's configuration, as in the hand–eye report.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub systematic: Option<Systematic>,
    /// The fit on the pixels, when X and the target were solved on the detections
    /// ([`Input::Pixels`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reprojection: Option<crate::calibrate::pixels::ReprojectionSummary>,
    /// The components of X's translation that came from a prior, as in the hand–eye report
    /// (`"prior": {"tz": {"value", "sigma"}}`); absent when none did.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub prior: PriorsUsed,
    /// A low-DOF recording, as in the hand–eye report; absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub low_dof: Option<LowDofReport>,
}

/// Calibrates X and the target's pose from `poses` (see the module docs for the steps).
///
/// Errors: [`Error::Misread`], [`Error::TooFewMotions`] (fewer than 3 poses),
/// [`Error::Degenerate`] when the poses do not determine X or Y.
///
/// # Example
/// ```
/// use handeye::calibrate::robot_world::{RobotWorldOptions, calibrate_robot_world};
/// use handeye::sim::{SimConfig, simulate};
/// use handeye::Setup;
/// let series = simulate(&SimConfig { poses: 30, ..SimConfig::default() }, 7, 0);
/// let report = calibrate_robot_world(&series.poses, Setup::EyeInHand, &RobotWorldOptions::default())?;
/// assert_eq!(report.target.frame, "base_from_target");
/// assert!(report.uncertainty.rotation_deg < 1.0);
/// # Ok::<(), handeye::Error>(())
/// ```
///
/// # On the pixels
/// With [`Input::Pixels`], X and the target's pose are fitted to the detections with the checks of
/// [`calibrate`](crate::calibrate()) on the pixels (the reading of the robot poses on the pixels, a fit
/// far above noise refused), in the same result shape: one result for every face. Both
/// uncertainties are the pixel solve's own (X's and the target's blocks of one covariance, the
/// larger of the Gauss–Newton and the per-frame sandwich one), judged by the same bounds;
/// `residual` is Q_i X C_i = Y over the PnP poses the solve started from (their noise, not X's
/// error: X and the target were fitted to the pixels), and `reprojection` the fit on the pixels.
/// `options.method` is ignored (this is [`RobotWorldMethod::Reprojection`]), as are
/// `replicates`, `written`, `outlier_deg` and `joints` (no bootstrap, no systematic-error test on
/// the pixels); `fix` may force `as-given` or `robot-inverted`; `point` places `at_point`;
/// `pose_names` names the frames. Errors: those of [`calibrate`](crate::calibrate()) on the
/// pixels.
pub fn calibrate_robot_world<'a>(
    input: impl Into<Input<'a>>,
    setup: Setup,
    options: &RobotWorldOptions,
) -> Result<RobotWorldReport> {
    match input.into() {
        Input::Poses(poses) => robot_world_on_poses(poses, setup, options),
        Input::Pixels { frames, camera } => {
            crate::calibrate::pixels::calibrate_robot_world_on_pixels(
                frames, camera, setup, options,
            )
        }
    }
}

/// [`calibrate_robot_world`] on pose pairs.
fn robot_world_on_poses(
    poses: &[PosePair],
    setup: Setup,
    options: &RobotWorldOptions,
) -> Result<RobotWorldReport> {
    crate::calibrate::batch::not_without_pixels(options.refine_intrinsics)?;
    check_replicates(options.replicates)?;
    check_joints(&options.joints, poses.len())?;
    check_priors(&options.priors)?;
    let priors = crate::check::units::in_poses_unit(&options.priors, poses)?;
    let mut warnings = Vec::new();
    let (applied, check, read, found) = read_poses(
        poses,
        setup,
        (options.fix, options.written),
        options.outlier_deg,
        &mut warnings,
    )?;
    crate::calibrate::batch::check_robot_model(
        options.robot_model.as_ref(),
        &read,
        &options.joints,
    )?;
    let outliers = outlier_report(
        &found,
        &Options {
            reject_outliers: options.reject_outliers,
            pose_names: options.pose_names.clone(),
            ..Options::default()
        },
    );
    let kept_outliers = (!outliers.poses.is_empty() && !options.reject_outliers)
        .then(|| outlier_warning(&outliers));
    let used = if options.reject_outliers {
        without(&read, &found)
    } else {
        read
    };
    let explain = |e: Error| explained(e, &warnings, kept_outliers.as_ref());
    // A low-DOF robot (every motion about one axis) leaves X's component along the axis and the
    // target's coupled one free: refused without a prior on it, in the hand–eye refusal's words.
    let plan = match low_dof::plan(&used, setup, Pairing::All, &priors) {
        Err(e) if low_dof::wants_prior(&e).is_some() => {
            return Err(first_what_motions_lack(
                poses,
                setup,
                &Options {
                    pairing: Pairing::All,
                    fix: options.fix,
                    written: options.written,
                    outlier_deg: options.outlier_deg,
                    reject_outliers: options.reject_outliers,
                    pose_names: options.pose_names.clone(),
                    priors: priors.clone(),
                    replicates: options.replicates,
                    ..Options::default()
                },
                e,
            ));
        }
        other => other.map_err(explain)?,
    };
    let solved = match &plan {
        Some(plan) => {
            let (x, target, conditioning) =
                low_dof::solve_robot_world(plan, &used, setup, options.method).map_err(explain)?;
            crate::solve::RobotWorld {
                x,
                target,
                method: options.method,
                poses: used.len(),
                conditioning,
                warnings: Vec::new(),
            }
        }
        None => robot_world(options.method, &used, setup).map_err(explain)?,
    };
    plausible(&solved.x, "X")?;
    plausible(&solved.target, "the target's pose")?;
    let undetermined = |conditioning| Error::Degenerate {
        reason: Degeneracy::IllConditioned,
        conditioning,
    };
    let cov = match &plan {
        Some(plan) => joint_covariance_given(
            &used,
            setup,
            (&solved.x, &solved.target),
            plan.prior.component.index(),
        ),
        None => joint_covariance(&used, setup, &solved.x, &solved.target),
    }
    .ok_or_else(|| explain(undetermined(solved.conditioning)))?;
    let scene = translation_scale(&used, setup).max(working_distance(&used));
    let method = options.method;
    let solve_x = |p: &[PosePair]| match &plan {
        Some(plan) => low_dof::solve_replicate(plan, p, setup, Pairing::All),
        None => robot_world(method, p, setup).map(|r| r.x),
    };
    let mut x_unc = bootstrap(&used, setup, &solved.x, &solve_x, options.replicates, scene);
    x_unc.at_point = Some(x_unc.place(
        &solved.x,
        options.point.unwrap_or_else(|| median_target(&used)),
    ));
    let y_unc = summarise(left_block(&cov, 6, &solved.target), 0, 0, scene);
    // As in the hand–eye calibration: the test waits for kept outliers, and a flagged result's
    // uncertainty is resampled by workspace region and covers the halves' disagreement.
    let kept: Vec<usize> = (0..poses.len())
        .filter(|i| !(options.reject_outliers && found.poses.iter().any(|g| g.pose == *i)))
        .collect();
    let systematic = systematic_test(
        (&used, setup, &solved.x),
        (&options.joints, &kept, poses.len()),
        options.robot_model.as_ref(),
        !options.reject_outliers && !found.poses.is_empty(),
        &solve_x,
        scene,
    );
    let (x_unc, systematic_found) = widened_for_systematic(
        x_unc,
        systematic.as_ref(),
        (&used, setup, &solved.x),
        &solve_x,
        (options.replicates, scene),
    );
    // Refused when undetermined, the widened uncertainty included: a systematic error the poses
    // cannot separate from X leaves X undetermined too. A low-DOF recording's part is judged
    // without the prior's sigma, and refused for what its motions lack.
    for u in [&x_unc, &y_unc] {
        refuse_if_undetermined(u, setup, solved.conditioning)
            .map_err(|e| match &plan {
                Some(plan) => low_dof::undetermined(plan, setup),
                None => e,
            })
            .map_err(explain)?;
    }
    warnings.extend(systematic_found);
    warnings.extend(solved.warnings.iter().cloned());
    warn_weak(&x_unc, setup, plan.as_ref().map(Plan::axis), &mut warnings);
    let (x_unc, y_unc, prior) = match &plan {
        Some(plan) => with_prior(plan, (x_unc, y_unc), (&used, setup), scene),
        None => (x_unc, y_unc, PriorsUsed::new()),
    };
    low_dof::check_determined(&priors, &prior, &solved.x, &x_unc, &mut warnings);
    warnings.extend(kept_outliers);
    let residual = PoseResidualSummary::of(pose_residuals(&used, setup, &solved.x, &solved.target));
    Ok(RobotWorldReport {
        verdict: Assessment::of(&warnings),
        method: options.method,
        setup,
        formulation: "robot-world".into(),
        frame: setup.x_frame().into(),
        x: TransformJson::from(&solved.x),
        uncertainty: x_unc,
        target: TargetReport {
            frame: target_frame(setup).into(),
            pose: TransformJson::from(&solved.target),
            uncertainty: y_unc,
        },
        poses: used.len(),
        conditioning: solved.conditioning,
        reading: ReadingReport { applied, check },
        outliers,
        residual,
        warnings,
        units: Units::default(),
        transform: solved.x,
        systematic,
        target_transform: solved.target,
        reprojection: None,
        prior,
        low_dof: plan.map(|p| p.report(solved.conditioning)),
    })
}

/// X's and the target's uncertainty with the prior's sigma: along the free direction for X (as
/// the hand–eye report's) and along the coupled direction for the target (its translation moves
/// by k_Y / k_i per unit of the prior's value, [`low_dof::target_axis`]); and the report's
/// `prior`.
fn with_prior(
    plan: &Plan,
    (x_unc, y_unc): (Uncertainty, Uncertainty),
    (poses, setup): (&[PosePair], Setup),
    scene: f64,
) -> (Uncertainty, Uncertainty, PriorsUsed) {
    let (x_unc, used) = low_dof::with_prior(plan, &x_unc, scene);
    let k = plan.axis.hand[plan.prior.component.index()];
    let gain = low_dof::target_axis(plan, poses, setup) / k;
    let y_unc = y_unc.with_prior(&gain, plan.prior.sigma, scene);
    (x_unc, y_unc, used)
}

/// The 6×6 covariance of one transform (at `offset` 0 for X, 6 for Y) with its rotation turned
/// from the right increment R exp([δ]×) into the left one exp([R δ]×) R, so that its axes lie in
/// the transform's reference frame as the hand–eye report's do.
fn left_block(cov: &JointCovariance, offset: usize, t: &Transform) -> Matrix6<f64> {
    let block: Matrix6<f64> = cov.fixed_view::<6, 6>(offset, offset).into_owned();
    let r: Matrix3<f64> = rotation_matrix(t);
    let mut m = Matrix6::identity();
    m.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
    m * block * m.transpose()
}

fn refuse_if_undetermined(u: &Uncertainty, setup: Setup, conditioning: f64) -> Result<()> {
    let (part, d) = if u.weakest_rotation.verdict == Verdict::Undetermined {
        (Part::Rotation, &u.weakest_rotation)
    } else if u.weakest_translation.verdict == Verdict::Undetermined {
        (Part::Translation, &u.weakest_translation)
    } else {
        return Ok(());
    };
    Err(Error::Degenerate {
        reason: Degeneracy::Undetermined {
            part,
            axis: d.axis,
            sigma: d.sigma,
            setup,
        },
        conditioning,
    })
}
