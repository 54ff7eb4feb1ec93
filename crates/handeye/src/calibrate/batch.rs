//! A batch calibration that is right within the uncertainty it reports, or refused, or flagged.
//!
//! [`calibrate`] is what `handeye calibrate` and the Python `calibrate` run, and [`Report`] is what
//! both print:
//! 1. the readings a user may have meant are tried ([`crate::check::readings`]): a reading that fits
//!    far better refuses the as-given one ([`Error::Misread`]) unless [`Fix`] says otherwise;
//! 2. poses that break the screw invariants are found ([`crate::check::outliers::pose_outliers`]) and,
//!    with `reject_outliers`, left out;
//! 3. the method solves X from the pairing's motions;
//! 4. the bootstrap over the poses' own errors gives the uncertainty ([`crate::check::uncertainty`]); a
//!    direction of X it leaves undetermined refuses the result ([`Degeneracy::Undetermined`]), a
//!    weakly determined one is a warning naming it;
//! 5. the residuals and the spread of the motions ([`crate::check::quality::quality_report`]).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::calibrate::Input;
use crate::calibrate::low_dof::{self, LowDofReport};
use crate::check::holdout::{HeldOutCheck, leave_one_out};
pub(crate) use crate::check::outliers::working_distance;
use crate::check::outliers::{PoseOutliers, PoseResiduals, pose_outliers, translation_scale};
use crate::check::quality::{MotionQuality, QualityReport, ResidualSummary, quality_report};
use crate::check::readings::{ReadingCheck, check_readings};
use crate::check::systematic::Systematic;
pub(crate) use crate::check::systematic::{systematic_test, widened_for_systematic};
use crate::check::uncertainty::{
    Uncertainty, bootstrap, check_replicates, median_target, warn_weak,
};
use crate::model::error::{Degeneracy, Error, Result};
use crate::model::findings::OutlierPose;
use crate::model::findings::{Part, Verdict};
use crate::model::findings::{Reading, Written};
use crate::model::motion::{Pairing, PosePair, Setup, motion_pairs};
use crate::model::pose::TransformJson;
use crate::model::pose::{MAX_TRANSLATION, Transform, check_translation};
use crate::model::prior::{Prior, PriorValue, PriorsUsed, check_priors};
use crate::model::warning::{SHOWN, Warning};
use crate::solve::accumulate::PoseAccumulator;
use crate::solve::motions::{AllPairs, MotionSource};
use crate::solve::{Calibration, Method, RefineOptions, TsaiOptions, refine_from, solve};

/// Per-motion details (`quality.per_motion`) are kept up to this many motions. With every pair of
/// poses the default, 10,000 made a 40-pose report list 780 motions (a 150-pose one 11,175 would
/// not, the cut being arbitrary anyway): a report stays readable, and `--pairs consecutive` lists
/// the motions of up to 500 poses.
const MAX_PER_MOTION: usize = 500;

/// The median per-pose translation residual above which a warning is given, as a fraction of the
/// scene's size (the RMS spread of the hand positions).
pub const WARN_TRANSLATION_RESIDUAL: f64 = 0.05;

/// What to do about a reading of the input that fits far better than the as-given one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Fix {
    /// Refuse with the finding ([`Error::Misread`]).
    #[default]
    Refuse,
    /// Read the input this way (no check); [`Reading::AsGiven`] keeps it as given and turns the
    /// refusal into a warning.
    Read(Reading),
    /// Apply the better reading when one is found, and say so.
    Auto,
}

impl Fix {
    /// Every fix: `refuse`, `auto`, then each [`Reading`] (its name reads the input that way).
    pub const ALL: [Fix; 2 + Reading::ALL.len()] = {
        let mut all = [Fix::Refuse; 2 + Reading::ALL.len()];
        all[1] = Fix::Auto;
        let mut i = 0;
        while i < Reading::ALL.len() {
            all[2 + i] = Fix::Read(Reading::ALL[i]);
            i += 1;
        }
        all
    };

    /// The reading this fix reads the input as, before any check: the named one, else as given.
    pub fn reading(self) -> Reading {
        match self {
            Fix::Read(r) => r,
            Fix::Refuse | Fix::Auto => Reading::AsGiven,
        }
    }

    /// The name on the command line and in the Python bindings: `refuse`, `auto`, or the
    /// reading's name (`as-given`, `robot-inverted`, …).
    pub fn name(self) -> &'static str {
        match self {
            Fix::Refuse => "refuse",
            Fix::Auto => "auto",
            Fix::Read(r) => r.name(),
        }
    }
}

impl crate::model::names::Named for Fix {
    const WHAT: &'static str = "fix";
    const PARAM: &'static str = "fix";
    const ALL: &'static [Self] = &Fix::ALL;

    fn name(self) -> &'static str {
        Fix::name(self)
    }
}

impl std::fmt::Display for Fix {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Fix {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self> {
        <Fix as crate::model::names::Named>::parse_name(s)
    }
}

/// How to calibrate.
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    /// The solver.
    pub method: Method,
    /// Which pose pairs become motions.
    pub pairing: Pairing,
    /// Tsai's options (with [`Method::Tsai`]).
    pub tsai: TsaiOptions,
    /// Leave out the outlier poses.
    pub reject_outliers: bool,
    /// A pose whose median rotation-angle gap is above this (degrees) is an outlier, whatever the
    /// data's noise level.
    pub outlier_deg: f64,
    /// What to do about a better reading of the input.
    pub fix: Fix,
    /// Bootstrap replicates for the uncertainty (within [`Options::REPLICATES_RANGE`]).
    pub replicates: usize,
    /// How each pose is named in messages (e.g. `file:line`), by input index; `pose i` when
    /// shorter than the input.
    pub pose_names: Vec<String>,
    /// The directions in which the input wrote its poses (`io::PoseSeries::written`, or
    /// [`Written::NAMED`] for poses given as handeye names them), where a quaternion-order reading
    /// undoes the mix-up.
    pub written: Written,
    /// The point (camera frame, input unit) whose error through X `uncertainty.at_point` gives;
    /// `None`: the median target position seen by the camera (per coordinate, over
    /// `camera_from_target`'s translations).
    pub point: Option<[f64; 3]>,
    /// The joint angles of each pose (radians, the robot's joint order), by input index, where the
    /// input gives them: the configuration the systematic-error test orders the poses by, and
    /// the joint it names. Empty: the hand poses order them.
    pub joints: Vec<Vec<f64>>,
    /// The robot's DH table (`--robot-model`), where given with the joint angles: the
    /// systematic-error test then also asks whether the residuals lie along what an error of its
    /// parameters does (`check::identification`). Default none.
    pub robot_model: Option<crate::model::kinematics::Kinematics>,
    /// Priors on components of X's translation (SPEC sec. 9, `--prior`): a low-DOF recording's
    /// free component comes from its prior; a prior on a component the motions determine is
    /// checked against the data (the data's value is kept). Default none.
    pub priors: Vec<Prior>,
    /// Refine the camera's intrinsics with X on the pixels (`--refine-intrinsics`; only with the
    /// calibration on the pixels, refused elsewhere). Default false.
    pub refine_intrinsics: bool,
}

impl Options {
    /// The bootstrap replicates a calibration accepts (`replicates`, here and in
    /// [`RobotWorldOptions`](crate::RobotWorldOptions)): fewer than 8 give no usable one-sigma, and
    /// more than 100,000 only cost memory and time (each keeps an X).
    pub const REPLICATES_RANGE: std::ops::RangeInclusive<usize> =
        crate::check::uncertainty::REPLICATES_RANGE;
}

impl Default for Options {
    fn default() -> Self {
        Self {
            method: Method::Andreff,
            pairing: Pairing::Consecutive,
            tsai: TsaiOptions::default(),
            reject_outliers: false,
            outlier_deg: crate::check::quality::OUTLIER_DEG,
            fix: Fix::Refuse,
            replicates: crate::check::uncertainty::REPLICATES,
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

/// Refuses `refine_intrinsics` on poses: the intrinsics are refined on the pixels only.
pub(crate) fn not_without_pixels(refine_intrinsics: bool) -> Result<()> {
    if refine_intrinsics {
        return Err(Error::InvalidParameter {
            name: "refine_intrinsics",
            message: "the intrinsics are refined on the pixels only: --method reprojection with a JSON Lines file with `detections` and --intrinsics FILE".into(),
        });
    }
    Ok(())
}

/// The outliers in a [`Report`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Outliers {
    /// The outlier poses.
    pub poses: Vec<OutlierPose>,
    /// Whether they were left out of the solve.
    pub rejected: bool,
    /// The angle-gap threshold used, degrees.
    pub angle_threshold_deg: f64,
    /// The pitch-gap threshold used, input units.
    pub pitch_threshold: f64,
}

/// The readings tried, in a [`Report`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReadingReport {
    /// The reading the result was solved under.
    pub applied: Reading,
    /// What the check found (absent when a reading was forced).
    pub check: Option<ReadingCheck>,
}

/// The spread of the motions, in a [`Report`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Spread {
    /// Largest angle between a motion's rotation axis and the dominant axis, degrees.
    pub axis_spread_deg: f64,
    /// Smallest and largest rotation angle of the motions, degrees.
    pub rotation_range_deg: [f64; 2],
    /// Per motion pair, in order (absent above 10,000 motions).
    pub per_motion: Option<Vec<MotionQuality>>,
}

/// The units of a [`Report`]'s numbers.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Units {
    /// Rotations.
    pub rotation: String,
    /// Lengths.
    pub length: String,
}

impl Default for Units {
    fn default() -> Self {
        Self {
            rotation: "degrees where a name says _deg, radians in the covariance".into(),
            length: "the input's length unit".into(),
        }
    }
}

pub use crate::model::findings::Assessment;

/// The result of [`calibrate`]: X, how far to trust it, and why.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Report {
    /// The verdict: `good`, or `questionable` while a caution of `warnings` stands.
    pub verdict: Assessment,
    /// The solver.
    pub method: Method,
    /// The setup.
    pub setup: Setup,
    /// The pairing.
    pub pairing: Pairing,
    /// X's frame name (`gripper_from_camera` or `base_from_camera`).
    pub frame: String,
    /// X (`translation`, `quaternion_xyzw`, `matrix` in the JSON object itself).
    #[serde(flatten)]
    pub x: TransformJson,
    /// Poses used.
    pub poses: usize,
    /// Motions used.
    pub motions: usize,
    /// Conditioning of Andreff's rotation system (1 is ideal).
    pub conditioning: f64,
    /// One-sigma uncertainty of X from the bootstrap over the poses' own errors.
    pub uncertainty: Uncertainty,
    /// The reading of the input.
    pub reading: ReadingReport,
    /// Poses that disagree with the others.
    pub outliers: Outliers,
    /// The A X − X B residuals over the motions (degrees; input units).
    pub residual: ResidualSummary,
    /// Median per-pose translation residual over the scene's size (the larger of the hand's spread
    /// and the camera's working distance), unit-free.
    pub translation_residual_rel: f64,
    /// The spread of the motions.
    pub quality: Spread,
    /// Cautions, each with its code, its words and the option that fixes it, if one does.
    #[serde(serialize_with = "crate::model::warning::described")]
    pub warnings: Vec<Warning>,
    /// The units of the numbers.
    pub units: Units,
    /// X as a transform (not serialised: `x` carries it).
    #[serde(skip)]
    pub transform: Transform,
    /// The held-out check: each camera observation predicted from the other poses
    /// (`crate::holdout`); `None` with fewer than four poses.
    pub held_out: Option<HeldOutSummary>,
    /// The test for an error that follows the robot's configuration (`check::systematic`);
    /// absent with fewer than 12 poses.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub systematic: Option<Systematic>,
    /// The components of X's translation that came from a prior, not from the data (`"prior":
    /// {"tz": {"value", "sigma"}}`); absent when none did.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub prior: BTreeMap<String, PriorValue>,
    /// A low-DOF recording (every motion rotates about one axis): the axis and the component
    /// taken from the prior; absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub low_dof: Option<LowDofReport>,
    /// The fit on the pixels (`--method reprojection`); absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reprojection: Option<crate::calibrate::pixels::ReprojectionSummary>,
}

/// The held-out check in a [`Report`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HeldOutSummary {
    /// Median gap between the predicted and the recorded observation, degrees.
    pub median_rotation_deg: f64,
    /// Median gap in the target's position seen by the camera, input units.
    pub median_translation: f64,
    /// Each pose left out exactly or not (always, since the check is O(n); up to 300 poses before).
    pub exact: bool,
    /// The poses the others predict poorly (6 times the median or more), by name.
    pub disagree: Vec<HeldOutName>,
}

/// One poorly predicted pose.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HeldOutName {
    /// Its name (`file:line` from the CLI).
    pub name: String,
    /// Its gaps: degrees and input units.
    pub rotation_deg: f64,
    /// See `rotation_deg`.
    pub translation: f64,
}

impl Report {
    /// What OpenCV's Tsai motion filter dropped, in words, when `tsai` applied it and it dropped
    /// motions ([`TsaiOptions::opencv_filter_note`]); each face adds how it keeps every motion.
    pub fn tsai_filter_note(&self, tsai: TsaiOptions) -> Option<String> {
        if !tsai.opencv_filter || self.method != Method::Tsai {
            return None;
        }
        TsaiOptions::opencv_filter_note(self.motions, self.pairing.motion_count(self.poses))
    }
}

/// Refuses a solved transform (`what`: X, or the target's pose) whose translation is beyond the
/// bound every input translation is held to ([`MAX_TRANSLATION`]): inputs at the edge of that
/// bound (every translation 9.9e8) solve to an X beyond it (2e9), a length no unit makes.
pub(crate) fn plausible(x: &Transform, what: &str) -> Result<()> {
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

/// Calibrates X from pose pairs (see the module docs for the steps), or on the pixels of the
/// target's detections ([`Input::Pixels`]: see below).
///
/// Errors: [`Error::Misread`] when another reading fits far better (and [`Fix::Refuse`]),
/// [`Error::Degenerate`] when the motions do not determine X, [`Error::TooFewMotions`].
///
/// # On the pixels
/// X and the target's pose are fitted to the detections, with the same report and its own
/// checks: the reading of the robot poses is checked on the pixels (a planar target's PnP poses
/// flip, which the readings check on poses would take for inverted poses), a fit whose pixels
/// stay far above detection noise is refused ([`Error::PixelsUnfit`]), and the uncertainty is the
/// solve's own. `options.method` is ignored (this is [`Method::Reprojection`]); `options.fix` may
/// force `as-given` or `robot-inverted`; `options.point` places `at_point`;
/// `options.pose_names` names the frames; `options.refine_intrinsics` refines the intrinsics with
/// X. The report's `reprojection` says the fit on the pixels.
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
    match input.into() {
        Input::Poses(poses) => calibrate_poses(poses, setup, options),
        Input::Pixels { frames, camera } => {
            crate::calibrate::pixels::calibrate_on_pixels(frames, camera, setup, options)
        }
    }
}

/// [`calibrate`] on pose pairs.
fn calibrate_poses(poses: &[PosePair], setup: Setup, options: &Options) -> Result<Report> {
    not_without_pixels(options.refine_intrinsics)?;
    check_replicates(options.replicates)?;
    check_joints(&options.joints, poses.len())?;
    check_priors(&options.priors)?;
    let options = &Options {
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
    let read_len = read.len();
    let used: Vec<PosePair> = if options.reject_outliers {
        without(&read, &found)
    } else {
        read
    };
    let plan = match low_dof::plan(&used, setup, options.pairing, &options.priors) {
        Err(e) if low_dof::wants_prior(&e).is_some() => {
            return Err(first_what_motions_lack(poses, setup, options, e));
        }
        other => other.map_err(|e| explained(e, &warnings, None))?,
    };
    let calibration = match &plan {
        Some(plan) => low_dof::solve(plan, &used, setup, options.pairing, options.method)?,
        None => options.solve(&used, setup)?,
    };
    plausible(&calibration.x, "X")?;
    let solve_x = |p: &[PosePair]| match &plan {
        Some(plan) => low_dof::solve_replicate(plan, p, setup, options.pairing),
        None => solve_replicate(p, setup, options),
    };
    // Translation verdicts are relative to the larger of the hand's spread and the camera's
    // working distance: motions that barely translate (a wrist turning) still fix X's offset.
    let scene = translation_scale(&used, setup).max(working_distance(&used));
    // The bootstrap and the checks of the solution (residuals, quality, held-out) are
    // independent: they run side by side, each with the result it would have alone.
    let (uncertainty, (quality, residuals, held_out)) = rayon::join(
        || {
            bootstrap(
                &used,
                setup,
                &calibration.x,
                &solve_x,
                options.replicates,
                scene,
            )
        },
        || {
            (
                quality_of(&used, setup, options.pairing, &calibration),
                PoseResiduals::at(&used, setup, &calibration.x),
                leave_one_out(&used, setup),
            )
        },
    );
    let kept: Vec<usize> = (0..read_len)
        .filter(|i| !(options.reject_outliers && found.poses.iter().any(|g| g.pose == *i)))
        .collect();
    let systematic = systematic_test(
        (&used, setup, &calibration.x),
        (&options.joints, &kept, read_len),
        options.robot_model.as_ref(),
        !options.reject_outliers && !found.poses.is_empty(),
        &solve_x,
        scene,
    );
    let outliers = outlier_report(&found, options);
    let kept_outliers = (!outliers.poses.is_empty() && !options.reject_outliers)
        .then(|| outlier_warning(&outliers));
    // The motions' part is judged on its own: a low-DOF recording by what it determines (the
    // prior's sigma is the user's to give), any other by every check of the motions.
    match &plan {
        Some(plan) => refuse_if_undetermined(&uncertainty, setup, calibration.conditioning)
            .map_err(|_| low_dof::undetermined(plan, setup))
            .map_err(|e| explained(e, &warnings, kept_outliers.as_ref()))?,
        None => refuse_if_undetermined(&uncertainty, setup, calibration.conditioning)
            .and_then(|()| {
                motions_determine(&used, setup, options, scene, calibration.conditioning)
            })
            .map_err(|e| method_at_fault(e, &used, setup, options, scene))
            .map_err(|e| explained(e, &warnings, kept_outliers.as_ref()))?,
    }
    let (mut uncertainty, caution) = widened_for_systematic(
        uncertainty,
        systematic.as_ref(),
        (&used, setup, &calibration.x),
        &solve_x,
        (options.replicates, scene),
    );
    warnings.extend(caution);
    uncertainty.at_point = Some(uncertainty.place(
        &calibration.x,
        options.point.unwrap_or_else(|| median_target(&used)),
    ));
    // The directions the motions leave weak are judged without the prior's sigma.
    let data_uncertainty = uncertainty.clone();
    let (uncertainty, prior) = match &plan {
        Some(plan) => low_dof::with_prior(plan, &uncertainty, scene),
        None => (uncertainty, PriorsUsed::new()),
    };
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
        plan.as_ref().map(low_dof::Plan::axis),
        &mut warnings,
    );
    if translation_residual_rel > WARN_TRANSLATION_RESIDUAL {
        warnings.push(Warning::TranslationResiduals {
            relative: translation_residual_rel,
        });
    }
    warnings.extend(kept_outliers);
    let used_names: Vec<String> = kept
        .iter()
        .map(|&i| {
            options
                .pose_names
                .get(i)
                .cloned()
                .unwrap_or_else(|| format!("pose {i}"))
        })
        .collect();
    let held_out = held_out.map(|check| held_out_of(&check, &used_names, &mut warnings));
    // The cautions that one option fixes come first (the outliers' `--reject-outliers`, a
    // reading's `--fix`), the others after them, each group in the order found.
    warnings.sort_by_key(|w| w.remedy().is_none());
    Ok(Report {
        verdict: Assessment::of(&warnings),
        method: options.method,
        setup,
        pairing: options.pairing,
        frame: setup.x_frame().into(),
        x: TransformJson::from(&calibration.x),
        poses: used.len(),
        motions: calibration.motions,
        conditioning: calibration.conditioning,
        uncertainty,
        reading: ReadingReport { applied, check },
        outliers,
        residual: quality.residual,
        translation_residual_rel,
        quality: Spread {
            axis_spread_deg: quality.axis_spread_deg,
            rotation_range_deg: quality.rotation_range_deg,
            per_motion: (quality.per_motion.len() == calibration.motions)
                .then_some(quality.per_motion),
        },
        warnings,
        units: Units::default(),
        transform: calibration.x,
        held_out,
        systematic,
        prior,
        low_dof: plan.map(|p| p.report(calibration.conditioning)),
        reprojection: None,
    })
}

/// Refuses a robot model (`--robot-model`) that is not the one the poses were reported through,
/// or without every pose's joint angles (`check::identification::check_model`).
pub(crate) fn check_robot_model(
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

/// Joint angles given are every pose's: one list a pose (or none at all).
pub(crate) fn check_joints(joints: &[Vec<f64>], poses: usize) -> Result<()> {
    if joints.is_empty() || joints.len() == poses {
        return Ok(());
    }
    Err(Error::InvalidParameter {
        name: "joints",
        message: format!(
            "{} lists of joint angles for {poses} poses: give every pose's, in order",
            joints.len()
        ),
    })
}

/// A low-DOF recording refused for want of a prior (`refusal`) is refused for what its motions
/// lack instead when, given the prior, they would not determine the rest either (a single joint
/// turning, no translation across the axis): the user is told first what a prior cannot fix. The
/// check calibrates with a stand-in prior of 0 (the component does not enter the motions' fit).
pub(crate) fn first_what_motions_lack(
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
    let mut with_prior = Options {
        method: Method::Andreff,
        ..options.clone()
    };
    with_prior.priors.push(Prior {
        component,
        value: 0.0,
        sigma: 0.0,
        unit: None,
    });
    match calibrate(poses, setup, &with_prior) {
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

impl Options {
    /// X from the poses by these options' method, pairing and Tsai options: what [`calibrate`]
    /// solves before its checks (the readings, outliers, uncertainty and held-out poses), and what
    /// the OpenCV drop-in returns. [`solve`] is the solve of motions a caller made.
    pub fn solve(&self, poses: &[PosePair], setup: Setup) -> Result<Calibration> {
        match self.pairing {
            Pairing::All => solve_motions(&AllPairs::new(poses, setup), self),
            Pairing::Consecutive => {
                solve_motions(&motion_pairs(poses, Pairing::Consecutive, setup), self)
            }
        }
    }
}

/// Bootstrap replicates: the same method and pairing as [`Options::solve`], made cheaper where the
/// answer is the same or bounds it. All-pairs Andreff comes from the O(n) accumulated normal
/// equations ([`PoseAccumulator`], equal to the batch solve to ~1e-12). Refine, Tsai, Park and
/// Horaud over all pairs are bootstrapped by the same O(n) Andreff: their errors over all pairs are
/// Andreff's size, and 40 re-solves over n² motions were 95% of a whole `calibrate` (a minute for
/// refine at 1,000 poses). Measured on 40 simulated series per method
/// (`cargo run --release -p handeye --example uncertainty_check all`): median error/sigma 0.90
/// (park, horaud, as with their own replicates), 1.02 (tsai; 0.81 with its own), every error
/// within 3 sigma. Not andreff-joint and daniilidis: their errors are larger than Andreff's
/// (with Andreff's sigma, median error/sigma 3.3 and only 30% within 3 sigma), so they keep
/// their own replicates. Daniilidis over all pairs is itself O(n) (per-pose sums, the same system
/// as the motions': `daniilidis::pairs_normal`), so its own replicates cost what Andreff's do:
/// median error/sigma 0.89 (rotation), 0.96 (translation), every error within 3 sigma; the whole
/// `calibrate` at 1,000 poses went from 6.7 s to 0.37 s (loaded machine). Consecutive refine
/// starts from the replicate's own Andreff solution (never from X̂, which would hide a direction the data leave free) and takes at most
/// [`REPLICATE_ITERATIONS`] steps.
fn solve_replicate(poses: &[PosePair], setup: Setup, options: &Options) -> Result<Transform> {
    match (options.method, options.pairing) {
        (
            Method::Andreff | Method::Refine | Method::Tsai | Method::Park | Method::Horaud,
            Pairing::All,
        ) => accumulated_andreff(poses, setup),
        (Method::Refine, Pairing::Consecutive) => {
            let motions = motion_pairs(poses, Pairing::Consecutive, setup);
            let start = crate::solve::andreff(&motions)?.x;
            refine_briefly(&motions, &start)
        }
        _ => options.solve(poses, setup).map(|c| c.x),
    }
}

/// Levenberg–Marquardt steps a bootstrap replicate of `refine` takes from its Andreff start.
const REPLICATE_ITERATIONS: usize = 4;

fn refine_briefly(motions: &(impl MotionSource + ?Sized), start: &Transform) -> Result<Transform> {
    let options = RefineOptions {
        max_iterations: REPLICATE_ITERATIONS,
        ..RefineOptions::default()
    };
    refine_from(motions, start, &options).map(|r| r.calibration.x)
}

/// All-pairs Andreff from the accumulated normal equations.
fn accumulated_andreff(poses: &[PosePair], setup: Setup) -> Result<Transform> {
    PoseAccumulator::of(poses, setup)
        .estimate()
        .map(|e| e.x)
        .ok_or(Error::Degenerate {
            reason: Degeneracy::IllConditioned,
            conditioning: 0.0,
        })
}

fn solve_motions(motions: &(impl MotionSource + ?Sized), options: &Options) -> Result<Calibration> {
    if options.method == Method::Tsai {
        options.tsai.solve(motions)
    } else {
        solve(options.method, motions)
    }
}

/// The poses as they are to be read, with the reading chosen, its check and the outliers of the
/// poses so read. The readings are judged on the poses that agree with the others, so that
/// outliers do not make a mirror-image reading look better.
/// `fix` is what to do about a better reading, and the directions the input wrote its poses in.
pub(crate) fn read_poses(
    poses: &[PosePair],
    setup: Setup,
    (fix, written): (Fix, Written),
    outlier_deg: f64,
    warnings: &mut Vec<Warning>,
) -> Result<(Reading, Option<ReadingCheck>, Vec<PosePair>, PoseOutliers)> {
    let as_given = pose_outliers(poses, setup, outlier_deg);
    let (applied, check) =
        choose_reading(&without(poses, &as_given), setup, (fix, written), warnings)?;
    let read = applied.apply(poses, written);
    let found = match applied {
        Reading::AsGiven => as_given,
        _ => pose_outliers(&read, setup, outlier_deg),
    };
    Ok((applied, check, read, found))
}

/// The reading to solve under, and the check behind it.
pub(crate) fn choose_reading(
    poses: &[PosePair],
    setup: Setup,
    (fix, written): (Fix, Written),
    warnings: &mut Vec<Warning>,
) -> Result<(Reading, Option<ReadingCheck>)> {
    if let Fix::Read(r) = fix
        && r != Reading::AsGiven
    {
        if !r.applies_to(written) {
            return Err(Error::InvalidParameter {
                name: "fix",
                message: format!(
                    "`{}` undoes a quaternion order on the poses as the input wrote them, and this input writes them in both directions (some `_from_` names one way, some the other): write every record in one direction",
                    r.name()
                ),
            });
        }
        return Ok((r, None));
    }
    let check = check_readings(poses, setup, written);
    let (Some(finding), Some(better)) = (check.finding(setup), check.better) else {
        warnings.extend(check.size_warning(setup));
        warnings.extend(check.alike_warning(setup));
        return Ok((Reading::AsGiven, Some(check)));
    };
    match fix {
        Fix::Auto if check.unambiguous() => {
            warnings.push(Warning::ReadAs {
                reading: better.reading,
                finding,
            });
            Ok((better.reading, Some(check)))
        }
        Fix::Read(_) => {
            warnings.push(Warning::KeptAsGiven {
                better: better.reading,
                finding,
            });
            Ok((Reading::AsGiven, Some(check)))
        }
        _ => Err(Error::Misread {
            finding,
            readings: check.fitting_better(),
            setup,
            other_setup: check.other_setup(setup),
            frames: check.frames,
        }),
    }
}

/// The poses without the outliers.
pub(crate) fn without(poses: &[PosePair], found: &PoseOutliers) -> Vec<PosePair> {
    let bad = found.indices();
    poses
        .iter()
        .enumerate()
        .filter(|(i, _)| bad.binary_search(i).is_err())
        .map(|(_, p)| *p)
        .collect()
}

/// A refusal with what in the input explains it (outliers kept, a better reading kept as given),
/// when anything does.
pub(crate) fn explained(
    refusal: Error,
    warnings: &[Warning],
    kept_outliers: Option<&Warning>,
) -> Error {
    let why: Vec<Warning> = warnings.iter().chain(kept_outliers).cloned().collect();
    if why.is_empty() {
        return refusal;
    }
    Error::Untrusted {
        refusal: Some(Box::new(refusal)),
        why,
    }
}

/// `andreff`'s bootstrap on the same motions, for a method other than `andreff` (`None` for
/// `andreff` itself, or when it cannot solve them).
fn andreff_uncertainty(
    poses: &[PosePair],
    setup: Setup,
    options: &Options,
    scene: f64,
) -> Option<Uncertainty> {
    if options.method == Method::Andreff {
        return None;
    }
    // `andreff` with the same pairing: the same motions.
    let andreff_options = Options {
        method: Method::Andreff,
        ..options.clone()
    };
    let x = andreff_options.solve(poses, setup).ok()?.x;
    let solve_x = |p: &[PosePair]| solve_replicate(p, setup, &andreff_options);
    Some(bootstrap(
        poses,
        setup,
        &x,
        &solve_x,
        options.replicates,
        scene,
    ))
}

/// Refuses X when the motions leave a direction of it undetermined although the method's own
/// bootstrap did not see it: Daniilidis answered the single-joint recordings (about one axis, which
/// every other method refuses) 113° and 3 m off with a verdict of questionable, its bootstrap
/// blind to the degeneracy. Whether the motions determine X is judged by `andreff`'s bootstrap on
/// the same motions (a linear solve that sees every direction the motions leave free).
fn motions_determine(
    poses: &[PosePair],
    setup: Setup,
    options: &Options,
    scene: f64,
    conditioning: f64,
) -> Result<()> {
    match andreff_uncertainty(poses, setup, options, scene) {
        Some(andreff) if andreff.verdict() == Verdict::Undetermined => {
            refuse_if_undetermined(&andreff, setup, conditioning)
        }
        _ => Ok(()),
    }
}

/// A refusal of X as undetermined by a method other than `andreff` blames the motions ("add
/// motions about …"); when `andreff` determines X from the same motions (the same pairing; its
/// bootstrap judged with the same bounds), the method is at fault instead
/// ([`Degeneracy::MethodUndetermined`]). Measured on testdata's real and realistic sets: 15 of
/// them had andreff-joint, Daniilidis or Tsai refuse with advice to add motions that `andreff`
/// (and most other methods) did not need.
fn method_at_fault(
    refusal: Error,
    poses: &[PosePair],
    setup: Setup,
    options: &Options,
    scene: f64,
) -> Error {
    let Some(andreff) = andreff_uncertainty(poses, setup, options, scene) else {
        return refusal;
    };
    if andreff.verdict() == Verdict::Undetermined {
        return refusal;
    }
    match refusal {
        Error::Degenerate { conditioning, .. } => Error::Degenerate {
            reason: Degeneracy::MethodUndetermined {
                method: options.method.name(),
                rotation_deg: andreff.rotation_deg,
                translation: andreff.translation,
            },
            conditioning,
        },
        other => other,
    }
}

/// Refuses a result whose uncertainty leaves a direction of X undetermined.
pub(crate) fn refuse_if_undetermined(
    u: &Uncertainty,
    setup: Setup,
    conditioning: f64,
) -> Result<()> {
    if u.verdict() != Verdict::Undetermined {
        return Ok(());
    }
    let reason = if u.weakest_rotation.verdict == Verdict::Undetermined {
        undetermined(Part::Rotation, &u.weakest_rotation, setup)
    } else if u.weakest_translation.verdict == Verdict::Undetermined {
        undetermined(Part::Translation, &u.weakest_translation, setup)
    } else {
        Degeneracy::Unstable {
            refused: u.refused,
            tried: u.refused + u.replicates,
        }
    };
    Err(Error::Degenerate {
        reason,
        conditioning,
    })
}

fn undetermined(part: Part, d: &crate::model::findings::Direction, setup: Setup) -> Degeneracy {
    Degeneracy::Undetermined {
        part,
        axis: d.axis,
        sigma: d.sigma,
        setup,
    }
}

/// The quality report over the pairing's motions.
fn quality_of(
    poses: &[PosePair],
    setup: Setup,
    pairing: Pairing,
    c: &Calibration,
) -> QualityReport {
    match pairing {
        Pairing::All => quality_report(&AllPairs::new(poses, setup), &c.x, MAX_PER_MOTION),
        Pairing::Consecutive => {
            quality_report(&motion_pairs(poses, pairing, setup), &c.x, MAX_PER_MOTION)
        }
    }
}

pub(crate) fn outlier_report(found: &PoseOutliers, options: &Options) -> Outliers {
    Outliers {
        poses: found
            .poses
            .iter()
            .map(|g| OutlierPose {
                pose: g.pose,
                name: options
                    .pose_names
                    .get(g.pose)
                    .cloned()
                    .unwrap_or_else(|| format!("pose {}", g.pose)),
                angle_gap_deg: g.angle_gap_deg,
                pitch_gap: g.pitch_gap,
                rms_px: None,
            })
            .collect(),
        rejected: options.reject_outliers,
        angle_threshold_deg: found.angle_threshold_deg,
        pitch_threshold: found.pitch_threshold,
    }
}

pub(crate) fn outlier_warning(o: &Outliers) -> Warning {
    Warning::Outliers {
        count: o.poses.len(),
        shown: o.poses.iter().take(SHOWN).cloned().collect(),
    }
}
