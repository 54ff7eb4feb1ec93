//! The one calibration job: [`calibrate`] takes a recording (pose pairs or the target's
//! detections, [`Input`]), one [`Options`] (the [`Problem`] a field) and returns one [`Report`].
//! Every problem runs the same steps, written here once, and only here is a report worded:
//! 1. the reading of the input: the readings a user may have meant are tried
//!    ([`crate::check::readings`]): a reading that fits far better refuses the as-given one
//!    ([`Error::Misread`]) unless [`Fix`](crate::Fix) says otherwise (on the pixels, the reading
//!    of the robot poses is checked on the pixels);
//! 2. the outliers: poses that break the screw invariants are found
//!    ([`crate::check::outliers::pose_outliers`]) and, with `reject_outliers`, left out (on the
//!    pixels, the frames the fit leaves out);
//! 3. the problem's solve (`problem/`: the motions' hand–eye X, the robot-world X and target, the
//!    fit to the pixels), each returning a solution, never a report;
//! 4. the uncertainty: the bootstrap over the poses' own errors ([`crate::check::uncertainty`]), or the
//!    pixel fit's own covariance; a direction of X it leaves undetermined refuses the result
//!    ([`Degeneracy::Undetermined`]), a weakly determined one is a warning naming it;
//! 5. the checks: residuals, the spread of the motions
//!    ([`crate::check::quality::quality_report`]), held-out poses, systematic error;
//! 6. the report.
//!
//! [`Degeneracy::Undetermined`]: crate::Degeneracy::Undetermined

use crate::calibrate::advice::check_goal;
use crate::calibrate::input::Input;
use crate::calibrate::low_dof::{self, Plan};
use crate::calibrate::options::{Options, Problem, check_joints, check_point, not_without_pixels};
use crate::calibrate::problem::motions::{
    self, method_at_fault, motions_determine, quality_of, refuse_if_undetermined,
};
use crate::calibrate::problem::pixels::{self, FrameChoice, intrinsics_warning, pose_pairs};
use crate::calibrate::problem::poses;
use crate::calibrate::reading::{explained, outlier_report, outlier_warning, read_poses, without};
use crate::calibrate::report::Report;
use crate::calibrate::report::hand_eye::{
    HandEyeReport, HeldOutName, HeldOutSummary, Outliers, ReadingReport, Spread, Units,
};
use crate::calibrate::report::pixels::{CornerResidual, FrameRms, ReprojectionSummary};
use crate::calibrate::report::robot_world::{PoseResidualSummary, RobotWorldReport, TargetReport};
use crate::check::holdout::{HeldOutCheck, leave_one_out};
use crate::check::order::order_change;
use crate::check::outliers::{PoseOutliers, PoseResiduals, translation_scale, working_distance};
use crate::check::quality::quality_report;
use crate::check::systematic::{Systematic, Untested, systematic_test, widened_for_systematic};
use crate::check::uncertainty::{
    Uncertainty, bootstrap, check_replicates, median_target, warn_weak,
};
use crate::model::camera::{Frame, Intrinsics};
use crate::model::error::{Degeneracy, Error, Result};
use crate::model::findings::{Assessment, GoalCheck, OutlierPose, Reading, Sizes};
use crate::model::motion::{Pairing, PosePair, Setup};
use crate::model::pose::{MAX_TRANSLATION, Transform, TransformJson, check_translation};
use crate::model::prior::{Prior, PriorsUsed, check_priors};
use crate::model::warning::{SHOWN, Warning};
use crate::solve::motions::AllPairs;
use crate::solve::reprojection::PixelSolution;
use crate::solve::{Calibration, Method, RobotWorldMethod, pose_residuals, target_frame};

/// The median per-pose translation residual above which a warning is given, as a fraction of the
/// scene's size (the RMS spread of the hand positions).
pub const WARN_TRANSLATION_RESIDUAL: f64 = 0.05;

/// Calibrates the problem `options.problem` names from `input`: X from the motions between pose
/// pairs (hand–eye), or X and the target's pose together (robot-world); on pose pairs or, on the
/// pixels of the target's detections ([`Input::Pixels`]: see below). The steps are the module's;
/// the report is the problem's ([`Report::HandEye`], [`Report::RobotWorld`]).
///
/// Errors: [`Error::Misread`] when another reading fits far better (and
/// [`Fix::Refuse`](crate::Fix::Refuse)), [`Error::Degenerate`] when the motions do not determine
/// X (or the target), [`Error::TooFewMotions`] (robot-world: fewer than 3 poses).
///
/// # Example
/// ```
/// use handeye::sim::{SimConfig, simulate};
/// use handeye::{Options, Problem, Setup, calibrate};
/// let series = simulate(&SimConfig { poses: 30, ..SimConfig::default() }, 7, 0);
/// let options = Options { problem: Problem::ROBOT_WORLD, ..Options::default() };
/// let report = calibrate(&series.poses, Setup::EyeInHand, &options)?;
/// let report = report.robot_world().expect("the robot-world problem's report");
/// assert_eq!(report.target.frame, "base_from_target");
/// assert!(report.uncertainty.rotation_deg < 1.0);
/// # Ok::<(), handeye::Error>(())
/// ```
///
/// # On the pixels
/// X and the target's pose are fitted to the detections, with the problem's report and the
/// pixels' own checks: the reading of the robot poses is checked on the pixels (a planar target's
/// PnP poses flip, which the readings check on poses would take for inverted poses), a fit whose
/// pixels stay far above detection noise is refused ([`Error::PixelsUnfit`]), and the uncertainty
/// is the solve's own (the robot-world problem's target: its block of the same covariance). The
/// problem's method is ignored (the report's is [`Method::Reprojection`] or
/// [`RobotWorldMethod::Reprojection`]), as are `replicates`, `written`, `outlier_deg` and `joints`
/// (no bootstrap, no systematic-error test on the pixels); `options.fix` may force `as-given` or
/// `robot-inverted`; `options.point` places `at_point`; `options.pose_names` names the frames;
/// `options.refine_intrinsics` refines the intrinsics with X. The report's `reprojection` says
/// the fit on the pixels; the robot-world report's `residual` is Q_i X C_i = Y over the PnP poses
/// the solve started from.
///
/// Errors on the pixels: [`Error::Misread`] when the robot poses inverted fit the pixels far
/// better, [`Error::PixelsUnfit`], [`Error::Degenerate`] (motions or covariance that do not
/// determine X), [`Error::TooFewMotions`] for fewer than 13 frames, [`Error::InvalidParameter`]
/// for unusable detections or intrinsics, a prior or `reject_outliers` (not taken on the pixels).
pub fn calibrate<'a>(
    input: impl Into<Input<'a>>,
    setup: Setup,
    options: &Options,
) -> Result<Report> {
    check_goal(options.goal)?;
    let report = match (input.into(), options.problem) {
        (Input::Poses(poses), Problem::HandEye(_)) => hand_eye_on_poses(poses, setup, options)
            .map(Report::HandEye)
            .map_err(|e| with_shifted_pairing(e, poses, setup, options)),
        (Input::Poses(poses), Problem::RobotWorld(method)) => {
            robot_world_on_poses(poses, setup, options, method).map(Report::RobotWorld)
        }
        (Input::Pixels { frames, camera }, problem) => {
            on_pixels(frames, camera, setup, options, problem)
        }
    }?;
    let report = finite_or_refused(report)?;
    Ok(match options.goal {
        Some(goal) => against_goal(report, goal),
        None => report,
    })
}

/// The invariant under every verdict (issue 59): an X, or a target, whose one-sigma uncertainty
/// is not a finite number is no answer, whatever path made it. The bounds on what comes in (a
/// prior's sigma, a point, a saved covariance) keep such a sigma out; this says so where the
/// verdict is decided, so that no later path can call an unbounded X `good`.
fn finite_or_refused(report: Report) -> Result<Report> {
    let (sizes, conditioning) = match &report {
        Report::HandEye(r) => (
            vec![r.uncertainty.rotation_deg, r.uncertainty.translation],
            r.conditioning,
        ),
        Report::RobotWorld(r) => (
            vec![
                r.uncertainty.rotation_deg,
                r.uncertainty.translation,
                r.target.uncertainty.rotation_deg,
                r.target.uncertainty.translation,
            ],
            r.conditioning,
        ),
    };
    if sizes.iter().all(|s| s.is_finite()) {
        Ok(report)
    } else {
        Err(Error::Degenerate {
            reason: Degeneracy::IllConditioned,
            conditioning,
        })
    }
}

/// The report judged against the user's goal: a one-sigma uncertainty above it in either size is
/// a caution (`Warning::GoalMissed`, after the others), and the verdict says so.
fn against_goal(mut report: Report, goal: Sizes) -> Report {
    let u = report.uncertainty();
    let sigma = Sizes {
        rotation_deg: u.rotation_deg,
        translation: u.translation,
    };
    let met = sigma.within(&goal);
    let (warnings, verdict, check) = match &mut report {
        Report::HandEye(r) => (&mut r.warnings, &mut r.verdict, &mut r.goal),
        Report::RobotWorld(r) => (&mut r.warnings, &mut r.verdict, &mut r.goal),
    };
    if !met {
        warnings.push(Warning::GoalMissed { goal, sigma });
    }
    *verdict = Assessment::of(warnings);
    *check = Some(GoalCheck { goal, met });
    report
}

/// A refusal of the motions (degenerate, undetermined) led by a pairing off by a record, where
/// the camera poses shifted by one or two records fit far better ([`shifted_pairing`]).
fn with_shifted_pairing(e: Error, poses: &[PosePair], setup: Setup, options: &Options) -> Error {
    let of_motions = match &e {
        Error::Degenerate { .. } => true,
        Error::Untrusted { refusal, .. } => refusal
            .as_deref()
            .is_some_and(|r| matches!(r, Error::Degenerate { .. })),
        _ => false,
    };
    if !of_motions {
        return e;
    }
    let Some(shifted) = shifted_pairing(poses, setup, options) else {
        return e;
    };
    match e {
        Error::Untrusted { refusal, mut why } => {
            why.insert(0, shifted);
            Error::Untrusted { refusal, why }
        }
        e => Error::Untrusted {
            refusal: Some(Box::new(e)),
            why: vec![shifted],
        },
    }
}

/// How much smaller the median rotation residual of a shifted pairing must be than as paired.
const SHIFT_BETTER: f64 = 5.0;

/// The shift of the camera records (±1, ±2) under which the hand–eye calibration answers and the
/// median rotation residual is [`SHIFT_BETTER`] times smaller than as paired, if any: the best.
fn shifted_pairing(poses: &[PosePair], setup: Setup, options: &Options) -> Option<Warning> {
    let residual =
        |p: &[PosePair], x: &Transform| PoseResiduals::at(p, setup, x).median_rotation_deg();
    let given = options
        .solve(poses, setup)
        .map_or(f64::INFINITY, |c| residual(poses, &c.x));
    [1i64, -1, 2, -2]
        .into_iter()
        .filter_map(|shift| {
            let n = poses.len();
            let s = shift.unsigned_abs() as usize;
            if n < s + 3 {
                return None;
            }
            // Robot record i with camera record i + shift, named by the robot's record.
            let robot = if shift > 0 { 0..n - s } else { s..n };
            let shifted: Vec<PosePair> = robot
                .clone()
                .map(|i| PosePair {
                    camera_from_target: poses[(i as i64 + shift) as usize].camera_from_target,
                    ..poses[i]
                })
                .collect();
            let names = robot.map(|i| pose_name(options, i)).collect();
            let shifted_options = Options {
                pose_names: names,
                joints: Vec::new(),
                ..options.clone()
            };
            let report = hand_eye_on_poses(&shifted, setup, &shifted_options).ok()?;
            let r = residual(&shifted, &report.transform);
            (r * SHIFT_BETTER < given).then_some((shift, r))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(shift, r)| Warning::ShiftedPairing {
            shift,
            residual_deg: r,
            given_residual_deg: given,
        })
}

/// The pose pairs as the first steps left them (the reading, the outliers), for every problem.
struct Read {
    /// The options, with the priors in the poses' unit.
    options: Options,
    /// The reading applied and its check.
    reading: ReadingReport,
    /// The outliers found.
    found: PoseOutliers,
    /// The poses used: read, without the outliers when they are rejected.
    used: Vec<PosePair>,
    /// The input index of each pose used.
    kept: Vec<usize>,
    /// The input's poses.
    input: usize,
    /// The outliers' section of the report.
    outliers: Outliers,
    /// The warning naming the outliers kept (not rejected), if any.
    kept_outliers: Option<Warning>,
}

/// Steps 1 and 2 on pose pairs: the options checked, the reading chosen, the outliers found (and
/// left out with `reject_outliers`). Returns the warnings found so far besides.
fn read_input(poses: &[PosePair], setup: Setup, options: &Options) -> Result<(Read, Vec<Warning>)> {
    not_without_pixels(options.refine_intrinsics)?;
    check_replicates(options.replicates)?;
    check_joints(&options.joints, poses.len())?;
    check_point(options.point, poses)?;
    check_priors(&options.priors)?;
    let options = Options {
        priors: crate::check::units::in_poses_unit(&options.priors, poses)?,
        ..options.clone()
    };
    let mut warnings = Vec::new();
    let (applied, check, read, found) = read_poses(
        poses,
        setup,
        (options.fix, options.written),
        options.outlier_deg,
        &mut warnings,
    )?;
    check_robot_model(options.robot_model.as_ref(), &read, &options.joints)?;
    let input = read.len();
    let used: Vec<PosePair> = if options.reject_outliers {
        without(&read, &found)
    } else {
        read
    };
    let kept: Vec<usize> = (0..input)
        .filter(|i| !(options.reject_outliers && found.poses.iter().any(|g| g.pose == *i)))
        .collect();
    let outliers = outlier_report(&found, &options);
    let kept_outliers = (!outliers.poses.is_empty() && !options.reject_outliers)
        .then(|| outlier_warning(&outliers));
    let read = Read {
        options,
        reading: ReadingReport { applied, check },
        found,
        used,
        kept,
        input,
        outliers,
        kept_outliers,
    };
    Ok((read, warnings))
}

/// The low-DOF plan of the poses used (every motion about one axis: X's component along it from
/// its prior), or `None`. A recording that wants a prior is refused for what its motions lack
/// first (judged with `lacking`); another refusal is explained by the warnings (and the outliers
/// kept, with `name_outliers`).
fn plan_of(
    poses: &[PosePair],
    setup: Setup,
    (read, warnings): (&Read, &[Warning]),
    (pairing, lacking): (Pairing, &Options),
    name_outliers: bool,
) -> Result<Option<Plan>> {
    let plan = low_dof::plan(&read.used, setup, pairing, &read.options.priors)
        .map_err(|e| low_dof::with_joints(e, &read.options.joints));
    match plan {
        Err(e) if low_dof::wants_prior(&e).is_some() => {
            Err(first_what_motions_lack(poses, setup, lacking, e))
        }
        other => other.map_err(|e| {
            let outliers = read.kept_outliers.as_ref().filter(|_| name_outliers);
            explained(e, warnings, outliers)
        }),
    }
}

/// The scene's size: the larger of the hand's spread and the camera's working distance (motions
/// that barely translate, a wrist turning, still fix X's offset).
fn scene_of(used: &[PosePair], setup: Setup) -> f64 {
    translation_scale(used, setup).max(working_distance(used))
}

/// Why the pixel path has no systematic-error test: the test orders the poses' residuals.
const ON_THE_PIXELS: &str = "it runs on the poses' residuals, not on the pixels (calibrate without --method reprojection for it)";

/// The systematic-error test of X on the poses used, or why it did not run.
fn systematic_of(
    read: &Read,
    setup: Setup,
    x: &Transform,
    solve_x: &(dyn Fn(&[PosePair]) -> Result<Transform> + Sync),
    scene: f64,
) -> std::result::Result<Systematic, Untested> {
    systematic_test(
        (&read.used, setup, x),
        (&read.options.joints, &read.kept, read.input),
        read.options.robot_model.as_ref(),
        !read.options.reject_outliers && !read.found.poses.is_empty(),
        solve_x,
        scene,
    )
}

/// A change of X over the recording's order (`check::order`), worded: where (the first pose
/// after it, by its name), X before and after, their difference with its one-sigma.
fn order_change_of(
    read: &Read,
    setup: Setup,
    x: &Transform,
    solve_x: &(dyn Fn(&[PosePair]) -> Result<Transform> + Sync),
    scene: f64,
) -> Option<Warning> {
    let found = order_change(&read.used, setup, x, solve_x, scene).filter(|c| c.flagged)?;
    Some(Warning::OrderChange {
        first: pose_name(&read.options, *read.kept.get(found.at)?),
        poses: [found.at, read.used.len() - found.at],
        before: Box::new((&found.before?).into()),
        after: Box::new((&found.after?).into()),
        rotation_deg: found.rotation_deg,
        translation: found.translation,
        rotation_sigma_deg: found.sigma_rotation_deg,
        translation_sigma: found.sigma_translation,
        p_value: found.p_value,
    })
}

/// What the hand–eye problem's solve and checks found, before the words.
struct HandEyeSolved {
    calibration: Calibration,
    plan: Option<Plan>,
    /// X's uncertainty with the prior's sigma, and without it (the data's own).
    uncertainty: Uncertainty,
    data_uncertainty: Uncertainty,
    prior: PriorsUsed,
    quality: crate::check::quality::QualityReport,
    residuals: PoseResiduals,
    held_out: Option<HeldOutCheck>,
    systematic: std::result::Result<Systematic, Untested>,
    scene: f64,
}

/// The hand–eye problem on pose pairs (A X = X B over the pairing's motions).
pub(crate) fn hand_eye_on_poses(
    poses: &[PosePair],
    setup: Setup,
    options: &Options,
) -> Result<HandEyeReport> {
    let (read, mut warnings) = read_input(poses, setup, options)?;
    let options = &read.options;
    let plan = plan_of(
        poses,
        setup,
        (&read, &warnings),
        (options.pairing, options),
        false,
    )?;
    let used = &read.used[..];
    let method = options.hand_eye_method();
    let calibration = match &plan {
        Some(plan) => low_dof::solve(plan, used, setup, options.pairing, method)?,
        None => options.solve(used, setup)?,
    };
    plausible(&calibration.x, "X")?;
    let solve_x = |p: &[PosePair]| match &plan {
        Some(plan) => low_dof::solve_replicate(plan, p, setup, options.pairing),
        None => motions::solve_replicate(p, setup, options),
    };
    let scene = scene_of(used, setup);
    // The bootstrap and the checks of the solution (residuals, quality, held-out) are
    // independent: they run side by side, each with the result it would have alone.
    let (uncertainty, (quality, residuals, held_out)) = rayon::join(
        || {
            bootstrap(
                used,
                setup,
                &calibration.x,
                &solve_x,
                options.replicates,
                scene,
            )
        },
        || {
            (
                quality_of(used, setup, options.pairing, &calibration),
                PoseResiduals::at(used, setup, &calibration.x),
                leave_one_out(used, setup),
            )
        },
    );
    let systematic = systematic_of(&read, setup, &calibration.x, &solve_x, scene);
    let change = order_change_of(&read, setup, &calibration.x, &solve_x, scene);
    // The motions' part is judged on its own: a low-DOF recording by what it determines (the
    // prior's sigma is the user's to give), any other by every check of the motions.
    let explain = |e| explained(e, &warnings, read.kept_outliers.as_ref());
    let conditioning = calibration.conditioning;
    match &plan {
        Some(plan) => refuse_if_undetermined(&uncertainty, setup, conditioning)
            .map_err(|_| low_dof::undetermined(plan, setup))
            .map_err(explain)?,
        None => refuse_if_undetermined(&uncertainty, setup, conditioning)
            .and_then(|()| motions_determine(used, setup, options, scene, conditioning))
            .map_err(|e| method_at_fault(e, used, setup, options, scene))
            .map_err(explain)?,
    }
    let (mut uncertainty, caution) = widened_for_systematic(
        uncertainty,
        systematic.as_ref().ok(),
        (used, setup, &calibration.x),
        &solve_x,
        (options.replicates, scene),
    );
    // A change over the order is named before an error that follows the configuration: a slip
    // leaves residuals that the configuration seems to explain too.
    warnings.extend(change);
    warnings.extend(caution);
    let point = options.point.unwrap_or_else(|| median_target(used));
    uncertainty.at_point = Some(uncertainty.place(&calibration.x, point));
    // The directions the motions leave weak are judged without the prior's sigma.
    let data_uncertainty = uncertainty.clone();
    let (uncertainty, prior) = match &plan {
        Some(plan) => low_dof::with_prior(plan, &uncertainty, scene),
        None => (uncertainty, PriorsUsed::new()),
    };
    let solved = HandEyeSolved {
        calibration,
        plan,
        uncertainty,
        data_uncertainty,
        prior,
        quality,
        residuals,
        held_out,
        systematic,
        scene,
    };
    Ok(hand_eye_report(read, warnings, setup, solved))
}

/// The hand–eye problem's report on pose pairs: its warnings in order, then its sections.
fn hand_eye_report(
    read: Read,
    mut warnings: Vec<Warning>,
    setup: Setup,
    solved: HandEyeSolved,
) -> HandEyeReport {
    let HandEyeSolved {
        calibration,
        plan,
        uncertainty,
        data_uncertainty,
        prior,
        quality,
        residuals,
        held_out,
        systematic,
        scene,
    } = solved;
    let options = &read.options;
    low_dof::check_determined(
        &options.priors,
        &prior,
        &calibration.x,
        &uncertainty,
        &mut warnings,
    );
    let translation_residual_rel = residuals.median_translation() / scene.max(f64::MIN_POSITIVE);
    warnings.extend(calibration.warnings.iter().cloned());
    warnings.extend(
        quality
            .warnings
            .iter()
            .filter(|w| plan.is_none() || !low_dof::handled(w))
            .cloned(),
    );
    warn_weak(
        &data_uncertainty,
        setup,
        plan.as_ref().map(Plan::axis),
        &mut warnings,
    );
    if translation_residual_rel > WARN_TRANSLATION_RESIDUAL {
        warnings.push(Warning::TranslationResiduals {
            relative: translation_residual_rel,
        });
    }
    warnings.extend(read.kept_outliers);
    let used_names: Vec<String> = read.kept.iter().map(|&i| pose_name(options, i)).collect();
    let held_out = held_out.map(|check| held_out_of(&check, &used_names, &mut warnings));
    // The cautions that one option fixes come first (the outliers' `--reject-outliers`, a
    // reading's `--fix`), the others after them, each group in the order found.
    warnings.sort_by_key(|w| w.remedy().is_none());
    HandEyeReport {
        goal: None,
        verdict: Assessment::of(&warnings),
        method: options.hand_eye_method(),
        setup,
        pairing: options.pairing,
        frame: setup.x_frame().into(),
        x: TransformJson::from(&calibration.x),
        poses: read.used.len(),
        motions: calibration.motions,
        conditioning: calibration.conditioning,
        uncertainty,
        reading: read.reading,
        outliers: read.outliers,
        residual: quality.residual,
        translation_residual_rel,
        quality: Spread {
            axis_spread_deg: quality.axis_spread_deg,
            rotation_range_deg: quality.rotation_range_deg,
            per_motion: (quality.per_motion.len() == calibration.motions)
                .then_some(quality.per_motion),
            sampled_poses: quality.sampled_poses,
        },
        warnings,
        units: Units::default(),
        transform: calibration.x,
        held_out,
        systematic_untested: systematic.as_ref().err().map(Untested::to_string),
        systematic: systematic.ok(),
        prior,
        low_dof: plan.map(|p| p.report(calibration.conditioning, setup)),
        reprojection: None,
    }
}

/// The name of input pose `i` (`pose i` where the options name none).
fn pose_name(options: &Options, i: usize) -> String {
    options
        .pose_names
        .get(i)
        .cloned()
        .unwrap_or_else(|| format!("pose {i}"))
}

/// The robot-world problem on pose pairs (A X = Z B over every pose once).
fn robot_world_on_poses(
    poses: &[PosePair],
    setup: Setup,
    options: &Options,
    method: RobotWorldMethod,
) -> Result<RobotWorldReport> {
    let (read, mut warnings) = read_input(poses, setup, options)?;
    let options = &read.options;
    // A low-DOF robot (every motion about one axis) leaves X's component along the axis and the
    // target's coupled one free: refused without a prior on it, in the hand–eye refusal's words.
    let lacking = Options {
        pairing: Pairing::All,
        fix: options.fix,
        written: options.written,
        outlier_deg: options.outlier_deg,
        reject_outliers: options.reject_outliers,
        pose_names: options.pose_names.clone(),
        priors: options.priors.clone(),
        replicates: options.replicates,
        ..Options::default()
    };
    let plan = plan_of(
        poses,
        setup,
        (&read, &warnings),
        (Pairing::All, &lacking),
        true,
    )?;
    let used = &read.used[..];
    let explain = |e| explained(e, &warnings, read.kept_outliers.as_ref());
    let solved = poses::solve(plan.as_ref(), used, setup, method).map_err(explain)?;
    plausible(&solved.x, "X")?;
    plausible(&solved.target, "the target's pose")?;
    let cov = poses::covariance(plan.as_ref(), used, setup, &solved)
        .ok_or_else(|| explain(poses::ill_conditioned(solved.conditioning)))?;
    let scene = scene_of(used, setup);
    let solve_x = |p: &[PosePair]| poses::solve_replicate(plan.as_ref(), p, setup, method);
    let mut x_unc = bootstrap(used, setup, &solved.x, &solve_x, options.replicates, scene);
    let point = options.point.unwrap_or_else(|| median_target(used));
    x_unc.at_point = Some(x_unc.place(&solved.x, point));
    let y_unc = poses::target_uncertainty(&cov, &solved.target, scene);
    // As in the hand–eye calibration: the test waits for kept outliers, and a flagged result's
    // uncertainty is resampled by workspace region and covers the halves' disagreement.
    let systematic = systematic_of(&read, setup, &solved.x, &solve_x, scene);
    let change = order_change_of(&read, setup, &solved.x, &solve_x, scene);
    let (x_unc, systematic_found) = widened_for_systematic(
        x_unc,
        systematic.as_ref().ok(),
        (used, setup, &solved.x),
        &solve_x,
        (options.replicates, scene),
    );
    // Refused when undetermined, the widened uncertainty included: a systematic error the poses
    // cannot separate from X leaves X undetermined too. A low-DOF recording's part is judged
    // without the prior's sigma, and refused for what its motions lack.
    for u in [&x_unc, &y_unc] {
        poses::refuse_if_undetermined(u, setup, solved.conditioning)
            .map_err(|e| match &plan {
                Some(plan) => low_dof::undetermined(plan, setup),
                None => e,
            })
            .map_err(explain)?;
    }
    warnings.extend(change);
    warnings.extend(systematic_found);
    warnings.extend(solved.warnings.iter().cloned());
    warn_weak(&x_unc, setup, plan.as_ref().map(Plan::axis), &mut warnings);
    let (x_unc, y_unc, prior) = match &plan {
        Some(plan) => poses::with_prior(plan, (x_unc, y_unc), (used, setup), scene),
        None => (x_unc, y_unc, PriorsUsed::new()),
    };
    low_dof::check_determined(&options.priors, &prior, &solved.x, &x_unc, &mut warnings);
    let residual = PoseResidualSummary::of(pose_residuals(used, setup, &solved.x, &solved.target));
    let low_dof = plan.map(|p| p.report(solved.conditioning, setup));
    let mut report = robot_world_report(read, warnings, setup, (solved, x_unc, y_unc), residual);
    report.method = method;
    report.systematic_untested = systematic.as_ref().err().map(Untested::to_string);
    report.systematic = systematic.ok();
    report.prior = prior;
    report.low_dof = low_dof;
    Ok(report)
}

/// The robot-world problem's report from its solution and both uncertainties (no systematic-error
/// test, prior or low-DOF section: the caller's to set).
fn robot_world_report(
    read: Read,
    mut warnings: Vec<Warning>,
    setup: Setup,
    (solved, x_unc, y_unc): (crate::solve::RobotWorld, Uncertainty, Uncertainty),
    residual: PoseResidualSummary,
) -> RobotWorldReport {
    warnings.extend(read.kept_outliers);
    RobotWorldReport {
        goal: None,
        verdict: Assessment::of(&warnings),
        method: solved.method,
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
        poses: read.used.len(),
        conditioning: solved.conditioning,
        reading: read.reading,
        outliers: read.outliers,
        residual,
        warnings,
        units: Units::default(),
        transform: solved.x,
        systematic: None,
        systematic_untested: None,
        target_transform: solved.target,
        reprojection: None,
        prior: PriorsUsed::new(),
        low_dof: None,
    }
}

/// Every problem on the pixels: the fit (`problem::pixels`), then the problem's report.
fn on_pixels(
    frames: &[Frame],
    camera: &Intrinsics,
    setup: Setup,
    options: &Options,
    problem: Problem,
) -> Result<Report> {
    pixels::not_on_pixels(
        options.reject_outliers,
        &options.priors,
        options.robot_model.as_ref(),
    )?;
    let (used, solution, applied, reading_check, choice) = pixels::solved(
        frames,
        camera,
        setup,
        options.fix,
        options.refine_intrinsics,
    )?;
    let reading = (applied, reading_check);
    match problem {
        Problem::HandEye(_) => {
            hand_eye_on_pixels(&used, setup, options, solution, reading, &choice)
                .map(Report::HandEye)
        }
        Problem::RobotWorld(_) => {
            robot_world_on_pixels(&used, setup, options, solution, reading, &choice)
                .map(Report::RobotWorld)
        }
    }
}

/// The hand–eye problem's report of a solution on the pixels: X's uncertainty the solve's own,
/// the intrinsics' check, the motions' quality over the PnP poses the solve started from, and the
/// fit on the pixels.
pub(crate) fn hand_eye_on_pixels(
    frames: &[Frame],
    setup: Setup,
    options: &Options,
    solution: PixelSolution,
    (applied, reading_check): (Reading, String),
    choice: &FrameChoice,
) -> Result<HandEyeReport> {
    let x = solution.calibration.x;
    let poses = pose_pairs(frames, &solution.start_poses);
    check_point(options.point, &poses)?;
    let uncertainty = pixels::uncertainty(&poses, setup, options.point, &solution)?;
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
    let scene = pixels::scene(&poses, setup);
    let outliers = frame_outliers(options, choice);
    let summary = reprojection_summary(frames, setup, &solution, reading_check, (options, choice));
    warnings.sort_by_key(|w| w.remedy().is_none());
    Ok(HandEyeReport {
        goal: None,
        verdict: Assessment::of(&warnings),
        method: Method::Reprojection,
        setup,
        pairing: options.pairing,
        frame: setup.x_frame().into(),
        x: TransformJson::from(&x),
        poses: frames.len(),
        motions: solution.calibration.motions,
        conditioning: solution.calibration.conditioning,
        uncertainty,
        reading: ReadingReport {
            applied,
            check: None,
        },
        outliers,
        residual: quality.residual,
        translation_residual_rel: residuals.median_translation() / scene.max(f64::MIN_POSITIVE),
        quality: Spread {
            axis_spread_deg: quality.axis_spread_deg,
            rotation_range_deg: quality.rotation_range_deg,
            per_motion: None,
            sampled_poses: quality.sampled_poses,
        },
        warnings,
        units: Units::default(),
        transform: x,
        held_out: None,
        reprojection: Some(summary),
        systematic: None,
        systematic_untested: Some(ON_THE_PIXELS.into()),
        prior: Default::default(),
        low_dof: None,
    })
}

/// The name of input frame `i` (`frame i` where the options name none).
fn frame_name(options: &Options, i: usize) -> String {
    options
        .pose_names
        .get(i)
        .cloned()
        .unwrap_or_else(|| format!("frame {i}"))
}

/// The outlier frames of a solve on the pixels, as the report's outliers.
fn frame_outliers(options: &Options, choice: &FrameChoice) -> Outliers {
    Outliers {
        poses: choice
            .outliers
            .iter()
            .map(|&(i, rms_px)| OutlierPose {
                pose: i,
                name: frame_name(options, i),
                angle_gap_deg: 0.0,
                pitch_gap: 0.0,
                rms_px: Some(rms_px),
            })
            .collect(),
        rejected: choice.rejected,
        angle_threshold_deg: 0.0,
        pitch_threshold: 0.0,
    }
}

/// The report's section on the pixels: the fit over the frames used, each named by its input
/// frame's name.
fn reprojection_summary(
    frames: &[Frame],
    setup: Setup,
    solution: &PixelSolution,
    reading_check: String,
    (options, choice): (&Options, &FrameChoice),
) -> ReprojectionSummary {
    // The name of used frame i.
    let name = |i: usize| frame_name(options, choice.kept.get(i).copied().unwrap_or(i));
    let left_out: std::collections::HashSet<(usize, usize)> =
        solution.outliers.iter().copied().collect();
    ReprojectionSummary {
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
        target_frame: target_frame(setup).into(),
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
    }
}

/// The robot-world problem's report of a solution on the pixels: the hand–eye report's X and
/// checks, with the target's pose and its uncertainty (its block of the same covariance), and the
/// residuals Q_i X C_i = Y over the PnP poses the solve started from.
fn robot_world_on_pixels(
    frames: &[Frame],
    setup: Setup,
    options: &Options,
    solution: PixelSolution,
    reading: (Reading, String),
    choice: &FrameChoice,
) -> Result<RobotWorldReport> {
    let target = solution.target;
    let target_covariance = solution.target_covariance;
    let poses = pose_pairs(frames, &solution.start_poses);
    let HandEyeReport {
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
    } = hand_eye_on_pixels(frames, setup, options, solution, reading, choice)?;
    let target_uncertainty =
        pixels::target_uncertainty(&poses, setup, target_covariance, conditioning)?;
    let residual = PoseResidualSummary::of(pose_residuals(&poses, setup, &transform, &target));
    Ok(RobotWorldReport {
        goal: None,
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
        poses: frames.len(),
        conditioning,
        reading,
        outliers,
        residual,
        warnings,
        units,
        transform,
        target_transform: target,
        systematic: None,
        systematic_untested: Some(ON_THE_PIXELS.into()),
        reprojection,
        prior: Default::default(),
        low_dof: None,
    })
}

/// Refuses a solved transform (`what`: X, or the target's pose) whose translation is beyond the
/// bound every input translation is held to ([`MAX_TRANSLATION`]): inputs at the edge of that
/// bound (every translation 9.9e8) solve to an X beyond it (2e9), a length no unit makes.
fn plausible(x: &Transform, what: &str) -> Result<()> {
    for &v in x.translation.vector.iter() {
        check_translation(v).map_err(|problem| Error::InvalidTransform {
            what: format!(
                "{what} as solved from these poses (the inputs' translations are within the bound of {MAX_TRANSLATION:e} each, but are not a recording's lengths)"
            ),
            problem,
        })?;
    }
    Ok(())
}

/// Refuses a robot model (`--robot-model`) that is not the one the poses were reported through,
/// or without every pose's joint angles (`check::identification::check_model`).
fn check_robot_model(
    model: Option<&crate::model::kinematics::Kinematics>,
    poses: &[PosePair],
    joints: &[Vec<f64>],
) -> Result<()> {
    let Some(model) = model else {
        return Ok(());
    };
    crate::check::identification::check_model(model, poses, joints).map_err(|message| {
        Error::InvalidParameter {
            name: "robot-model",
            message,
        }
    })
}

/// A low-DOF recording refused for want of a prior (`refusal`) is refused for what its motions
/// lack instead when, given the prior, they would not determine the rest either (a single joint
/// turning, no translation across the axis): the user is told first what a prior cannot fix. The
/// check calibrates with a stand-in prior of 0 (the component does not enter the motions' fit).
fn first_what_motions_lack(
    poses: &[PosePair],
    setup: Setup,
    options: &Options,
    refusal: Error,
) -> Error {
    let Some(component) = low_dof::wants_prior(&refusal) else {
        return refusal;
    };
    // Judged by the linear low-DOF solve (`andreff`), whatever the method: it is the motions'
    // question, as in `motions_determine`.
    let mut with_prior = options.with_method(Method::Andreff);
    with_prior.priors.push(Prior {
        component,
        value: 0.0,
        sigma: 0.0,
        unit: None,
    });
    match hand_eye_on_poses(poses, setup, &with_prior) {
        Err(e) if low_dof::lacks_motions(&e) => e,
        _ => refusal,
    }
}

/// The held-out check of the poses used ([`leave_one_out`]) with their names, and a warning naming
/// the poses the others predict poorly.
fn held_out_of(
    check: &HeldOutCheck,
    names: &[String],
    warnings: &mut Vec<Warning>,
) -> HeldOutSummary {
    let disagree: Vec<HeldOutName> = check
        .disagree
        .iter()
        .map(|&i| HeldOutName {
            name: names.get(i).cloned().unwrap_or_else(|| format!("pose {i}")),
            rotation_deg: check.poses[i].rotation_deg,
            translation: check.poses[i].translation,
        })
        .collect();
    if !disagree.is_empty() {
        warnings.push(Warning::PoorlyPredicted {
            count: disagree.len(),
            median_rotation_deg: check.median_rotation_deg,
            median_translation: check.median_translation,
            shown: disagree
                .iter()
                .take(SHOWN)
                .map(|d| d.name.clone())
                .collect(),
        });
    }
    HeldOutSummary {
        median_rotation_deg: check.median_rotation_deg,
        median_translation: check.median_translation,
        exact: check.exact,
        disagree,
    }
}

#[cfg(test)]
mod tests {
    use crate::calibrate::input::Input;
    use crate::calibrate::options::{Fix, Options};
    use crate::model::findings::Reading;
    use crate::model::motion::Setup;
    use crate::model::pose::Transform;
    use crate::sim::pixels::{PixelSimConfig, simulate_pixels};
    use crate::solve::reprojection::start_camera_poses;

    /// The invariant under the verdict: a report whose X or target has an unbounded one-sigma is
    /// refused, the hand–eye and the robot-world report alike; a finite one passes as it is.
    #[test]
    fn an_unbounded_uncertainty_is_never_an_answer() {
        use crate::calibrate::options::Problem;
        use crate::model::error::{Degeneracy, Error};
        use crate::sim::{SimConfig, simulate};
        let poses = simulate(&SimConfig::default(), 5, 0).poses;
        for problem in [
            Problem::default(),
            Problem::RobotWorld(crate::solve::RobotWorldMethod::Shah),
        ] {
            let options = Options {
                problem,
                ..Options::default()
            };
            let report = super::calibrate(&poses[..], Setup::EyeInHand, &options).unwrap();
            assert!(super::finite_or_refused(report.clone()).is_ok());
            for size in [f64::INFINITY, f64::NAN] {
                let mut bad = report.clone();
                match &mut bad {
                    super::Report::HandEye(r) => r.uncertainty.translation = size,
                    super::Report::RobotWorld(r) => r.target.uncertainty.rotation_deg = size,
                }
                assert!(matches!(
                    super::finite_or_refused(bad),
                    Err(Error::Degenerate {
                        reason: Degeneracy::IllConditioned,
                        ..
                    })
                ));
            }
        }
    }

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
                let r = crate::calibrate::pipeline::calibrate(
                    Input::Pixels { frames, camera },
                    setup,
                    &options,
                )
                .unwrap()
                .into_hand_eye()
                .unwrap();
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
}
