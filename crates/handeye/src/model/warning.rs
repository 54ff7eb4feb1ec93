//! Cautions attached to a result that is returned: each a machine code, the words for a person,
//! and, where one option of the call would fix it, that option.
//!
//! Every face shows the same thing: the JSON of a report lists each warning as
//! `{"code", …its data…, "message", "remedy"?}` ([`described`]), the command line prints the
//! message with the remedy as a flag (`--reject-outliers`), Python as a keyword
//! (`reject_outliers=True`). The messages themselves name no face's spelling.

use std::fmt;

use serde::ser::{SerializeMap, SerializeSeq};
use serde::{Deserialize, Serialize, Serializer};

use crate::model::findings::OutlierPose;
use crate::model::findings::Reading;
use crate::model::findings::{Direction, Part, Verdict, advice, one_axis_advice};
use crate::model::motion::Setup;

/// Poses a warning lists by name before it says "and N more".
pub const SHOWN: usize = 5;

/// A caution about a result that is returned (a result that cannot be trusted is refused with an
/// [`crate::model::error::Error`] instead).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "code", rename_all = "snake_case")]
#[non_exhaustive]
pub enum Warning {
    /// The rotation system is weakly conditioned (axes close to parallel).
    WeakConditioning {
        /// Second-smallest over largest singular value of the rotation system.
        conditioning: f64,
    },
    /// All rotations are small, so noise is amplified.
    SmallRotations {
        /// The largest rotation angle among the motions, degrees.
        largest_deg: f64,
    },
    /// Every rotation axis lies close to one direction.
    OneAxis {
        /// Largest angle between a motion's axis and the dominant one, degrees.
        axis_spread_deg: f64,
    },
    /// The rotation residuals are large: the poses' directions are probably wrong.
    RotationResiduals {
        /// RMS of the per-motion rotation residuals, degrees.
        rms_deg: f64,
    },
    /// The translation residuals are large against the scene's size: units or time pairing.
    TranslationResiduals {
        /// Median per-pose translation residual over the scene's size.
        relative: f64,
    },
    /// Poses disagree with the others and were kept.
    Outliers {
        /// How many.
        count: usize,
        /// The first `SHOWN` of them.
        shown: Vec<OutlierPose>,
    },
    /// Poses the others predict poorly (the held-out check).
    PoorlyPredicted {
        /// How many.
        count: usize,
        /// The median held-out gap: degrees.
        median_rotation_deg: f64,
        /// The median held-out gap: input units.
        median_translation: f64,
        /// The names of the first `SHOWN` of them.
        shown: Vec<String>,
    },
    /// A direction of X is only weakly determined.
    WeakDirection {
        /// Rotation about or translation along the axis.
        part: Part,
        /// The axis in X's reference frame.
        axis: [f64; 3],
        /// One-sigma along it: degrees or input units.
        sigma: f64,
        /// The setup (it names the reference frame).
        setup: Setup,
        /// The axis every motion turns about, in X's reference frame, when they all do (a low-DOF
        /// robot, solved with a prior): the advice is then what such a robot can record, never
        /// turns about other axes.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        one_axis: Option<[f64; 3]>,
    },
    /// The input was read another way, which fits far better (on request).
    ReadAs {
        /// The reading applied.
        reading: Reading,
        /// What was found, in words.
        finding: String,
    },
    /// Another reading fits far better but the input was kept as given (on request).
    KeptAsGiven {
        /// The reading that fits better.
        better: Reading,
        /// What was found, in words.
        finding: String,
    },
    /// X and the target have the sizes the setup makes unlikely: both inputs may be inverted.
    SwappedSizes {
        /// X's translation length.
        x_translation: f64,
        /// The target pose's translation length.
        y_translation: f64,
        /// The setup.
        setup: Setup,
    },
    /// Another reading of the input fits about as well as the as-given one (and gives another
    /// X): the motions are too small or too alike to tell whether the input is read right.
    ReadingsAlike {
        /// The readings that fit as well, the best first.
        readings: Vec<Reading>,
        /// The best one's median rotation residual, degrees, and translation residual over the
        /// motion range.
        fit: [f64; 2],
        /// The same, as given.
        given: [f64; 2],
        /// The poses were looked up between named frames (an inverted reading means frame names
        /// swapped).
        frames: bool,
        /// The setup.
        setup: Setup,
    },
    /// Said with a refusal: the camera poses fit far better paired with the robot pose `shift`
    /// records away (camera record i + shift with robot record i), and so paired X is determined:
    /// the motions are fine, the pairing is off (an export or a time pairing off by a record).
    ShiftedPairing {
        /// The shift of the camera records that fits, in records (+1: each robot pose with the
        /// next record's camera pose).
        shift: i64,
        /// The median rotation residual so paired, degrees.
        residual_deg: f64,
        /// The same as paired in the input.
        given_residual_deg: f64,
    },
    /// X changed over the recording's order (`check::order`): the poses from `first` on agree with
    /// another X than those before it, beyond what the noise allows: the camera slipped on its
    /// mount, or the target was bumped, during the recording. The X of the whole is neither.
    OrderChange {
        /// The first pose after the change, by its name (`file:line`).
        first: String,
        /// Poses before it and from it on.
        poses: [usize; 2],
        /// X of the poses before the change.
        before: Box<crate::model::pose::TransformJson>,
        /// X of the poses from the change on.
        after: Box<crate::model::pose::TransformJson>,
        /// The angle between the two, degrees.
        rotation_deg: f64,
        /// The distance between their translations, input units.
        translation: f64,
        /// The one-sigma of the angle (the two sides' bootstraps in quadrature), degrees.
        rotation_sigma_deg: f64,
        /// The one-sigma of the distance, input units.
        translation_sigma: f64,
        /// The share of random orders of the poses whose residuals change as sharply.
        p_value: f64,
    },
    /// The residuals follow the robot's configuration: an error of the robot's kinematic model,
    /// the TCP or flange offset, or the camera's intrinsics, which more poses do not average out.
    SystematicError {
        /// The neighbour test's p-value (`check::systematic`).
        p_value: f64,
        /// How far X moves between the two halves of the workspace, degrees (when both halves
        /// determine X).
        halves_rotation_deg: Option<f64>,
        /// The same, input units.
        halves_translation: Option<f64>,
        /// The one-sigma of X once the residuals are resampled by workspace region: degrees.
        rotation_sigma_deg: f64,
        /// The same, input units.
        translation_sigma: f64,
        /// The joint (1-based) whose angle the residual follows most, where joint angles are given.
        joint: Option<usize>,
        /// The z-score of the residuals along the robot's DH table's directions, where the table
        /// is given (`--robot-model`; `check::identification`): at most −3, the robot's
        /// kinematics; above, more likely the camera.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        kinematic_z: Option<f64>,
    },
    /// On the pixels: the detections fit significantly better with the camera's focal length
    /// scaled, and X moves beyond its uncertainty between the two fits: intrinsics that are not
    /// this camera's (or a target size or robot kinematics that disagree with the camera on
    /// scale), which X's uncertainty (the given intrinsics taken as exact) does not cover.
    IntrinsicsDisagree {
        /// The focal length's scale that fits best (fx and fy together).
        focal_scale: f64,
        /// The reprojection sigma with the given intrinsics, pixels.
        sigma_px: f64,
        /// The same with the focal length scaled.
        scaled_sigma_px: f64,
        /// How far X moves between the two fits: degrees.
        rotation_deg: f64,
        /// The same, input units.
        translation: f64,
        /// That move over X's one-sigma (the larger of rotation's and translation's).
        sigmas: f64,
    },
    /// On the pixels: the detections and the robot's motions fit significantly better with the
    /// camera's radial distortion k1 changed, and X moves beyond its uncertainty between the two
    /// fits (that uncertainty takes the intrinsics as exact).
    DistortionDisagrees {
        /// k1 as given.
        k1: f64,
        /// The k1 that fits best.
        k1_best: f64,
        /// The reprojection sigma with the given intrinsics, pixels.
        sigma_px: f64,
        /// The same with k1 at its best.
        refit_sigma_px: f64,
        /// How far X moves between the two fits: degrees.
        rotation_deg: f64,
        /// The same, input units.
        translation: f64,
        /// That move over X's one-sigma (the larger of rotation's and translation's).
        sigmas: f64,
    },
    /// A prior names a component of X's translation that the motions determine: the data's value
    /// is kept, and it disagrees with the prior by more than 3 sigma.
    PriorDisagrees {
        /// The component's name (`tx`, `ty`, `tz`).
        component: String,
        /// The prior's value, input unit.
        prior: f64,
        /// The data's value, input unit.
        data: f64,
        /// The difference over the combined one-sigma (the data's and the prior's).
        sigmas: f64,
    },
    /// X's one-sigma uncertainty exceeds the goal the user gave (`--goal`, the same one-sigma
    /// goal as `advise --goal`).
    GoalMissed {
        /// The goal: one-sigma rotation (degrees) and translation (input unit).
        goal: crate::model::findings::Sizes,
        /// X's one-sigma uncertainty.
        sigma: crate::model::findings::Sizes,
    },
    /// A camera or target of a rig that the data cannot determine: it is given no number.
    Undetermined {
        /// Its name.
        part: String,
        /// `camera`, `target`, or `camera or target` (mounted, never observed).
        kind: String,
        /// Why, in words.
        reason: String,
    },
    /// Loops of a rig that do not close: a part does not fit the rest (it moved during the
    /// recording, or its observations are misread).
    LoopMisfit {
        /// The part to blame, or, when none can be singled out, the parts of the failing loops.
        parts: Vec<String>,
        /// Whether `parts` is one part singled out (its every loop fails, the others close).
        singled_out: bool,
        /// The failing loops, each the two parts it compares.
        loops: Vec<String>,
        /// The largest RMS closure over what the noise explains, among them.
        worst_ratio: f64,
        /// The largest change of a closure between the poses before one pose and those after,
        /// among them, in standard errors.
        change_sigmas: f64,
    },
}

/// The one option of the call that would fix what a [`Warning`] describes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Remedy {
    /// Leave the disagreeing poses out (`reject_outliers`).
    RejectOutliers,
    /// Read the input another way (`fix`).
    Fix(Reading),
    /// Read the poses as a recording of this setup (`setup`).
    Setup(Setup),
    /// Calibrate the records on their pixels, with the camera's intrinsics (`intrinsics`): a
    /// record with `detections` and no camera pose. Each face words the call (the command line's
    /// `calibrate` needs `--method reprojection` with `--intrinsics FILE`, `online` the latter).
    Pixels,
}

impl Remedy {
    /// The option's name, as Python spells it (the command line's flag is `--` and the name
    /// with `-` for `_`).
    pub fn option(self) -> &'static str {
        match self {
            Self::RejectOutliers => "reject_outliers",
            Self::Fix(_) => "fix",
            Self::Setup(_) => "setup",
            Self::Pixels => "intrinsics",
        }
    }

    /// The option's value, as JSON (`null` where it is the user's: the intrinsics' file).
    pub fn value(self) -> serde_json::Value {
        match self {
            Self::RejectOutliers => true.into(),
            Self::Fix(reading) => reading.name().into(),
            Self::Setup(setup) => setup.name().into(),
            Self::Pixels => serde_json::Value::Null,
        }
    }

    /// The remedy in the words of both faces, for an error's message (errors are text):
    /// "pass `--reject-outliers` (`reject_outliers=True` in Python) to leave them out".
    pub fn in_words(self) -> String {
        let flag = format!("--{}", self.option().replace('_', "-"));
        let (cli, py) = match self {
            Self::RejectOutliers => (flag, format!("{}=True", self.option())),
            Self::Fix(r) => (
                format!("{flag} {}", r.name()),
                format!("{}=\"{}\"", self.option(), r.name()),
            ),
            Self::Setup(s) => (
                format!("{flag} {}", s.name()),
                format!("{}=\"{}\"", self.option(), s.name()),
            ),
            Self::Pixels => (format!("{flag} FILE"), format!("{}=FILE", self.option())),
        };
        format!("pass `{cli}` (`{py}` in Python) {}", self.purpose())
    }

    /// What it does, in words ("to leave them out").
    pub fn purpose(self) -> &'static str {
        match self {
            Self::RejectOutliers => "to leave them out",
            Self::Fix(_) => "to read the input that way",
            Self::Setup(_) => "to calibrate that setup",
            Self::Pixels => "to calibrate the records on their pixels",
        }
    }
}

impl Serialize for Remedy {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut map = serializer.serialize_map(Some(3))?;
        map.serialize_entry("option", self.option())?;
        map.serialize_entry("value", &self.value())?;
        map.serialize_entry("purpose", self.purpose())?;
        map.end()
    }
}

impl Warning {
    /// The machine code (the JSON's `code`).
    pub fn code(&self) -> &'static str {
        match self {
            Self::WeakConditioning { .. } => "weak_conditioning",
            Self::SmallRotations { .. } => "small_rotations",
            Self::OneAxis { .. } => "one_axis",
            Self::RotationResiduals { .. } => "rotation_residuals",
            Self::TranslationResiduals { .. } => "translation_residuals",
            Self::Outliers { .. } => "outliers",
            Self::PoorlyPredicted { .. } => "poorly_predicted",
            Self::WeakDirection { .. } => "weak_direction",
            Self::ReadAs { .. } => "read_as",
            Self::KeptAsGiven { .. } => "kept_as_given",
            Self::SwappedSizes { .. } => "swapped_sizes",
            Self::SystematicError { .. } => "systematic_error",
            Self::OrderChange { .. } => "order_change",
            Self::ShiftedPairing { .. } => "shifted_pairing",
            Self::ReadingsAlike { .. } => "readings_alike",
            Self::PriorDisagrees { .. } => "prior_disagrees",
            Self::GoalMissed { .. } => "goal_missed",
            Self::IntrinsicsDisagree { .. } => "intrinsics_disagree",
            Self::DistortionDisagrees { .. } => "distortion_disagrees",
            Self::Undetermined { .. } => "undetermined",
            Self::LoopMisfit { .. } => "loop_misfit",
        }
    }

    /// Whether a refusal names it first: a fault of the input one option fixes, or a pairing off
    /// by a record; what the motions lack comes after it.
    pub fn leads(&self) -> bool {
        self.remedy().is_some() || matches!(self, Self::ShiftedPairing { .. })
    }

    /// The option that would fix it, if one would.
    pub fn remedy(&self) -> Option<Remedy> {
        match self {
            Self::Outliers { .. } => Some(Remedy::RejectOutliers),
            Self::KeptAsGiven { better, .. } => Some(Remedy::Fix(*better)),
            Self::SwappedSizes { .. } => Some(Remedy::Fix(Reading::BothInverted)),
            _ => None,
        }
    }
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::WeakConditioning { conditioning } => write!(
                f,
                "weakly conditioned rotation system ({conditioning:.2e}): the rotation axes are nearly parallel; rotate about other axes"
            ),
            Self::SmallRotations { largest_deg } => write!(
                f,
                "all rotations are small (largest {largest_deg:.2}°): noise is amplified; use rotations of 10° or more"
            ),
            Self::OneAxis { axis_spread_deg } => write!(
                f,
                "all rotation axes within {axis_spread_deg:.1}° of one direction: rotate about another axis"
            ),
            Self::RotationResiduals { rms_deg } => write!(
                f,
                "rotation residuals of {rms_deg:.1}° RMS: check the directions of the poses (the setup, base_from_gripper vs gripper_from_base, camera_from_target vs target_from_camera) or leave the outliers out"
            ),
            Self::TranslationResiduals { relative } => write!(
                f,
                "translation residuals of {:.1}% of the scene's size (median per pose, against the hand's spread or the camera's distance): check the units of both inputs and the time pairing",
                100.0 * relative
            ),
            Self::Outliers { count, shown } => {
                let listed: Vec<String> = shown
                    .iter()
                    .map(|p| {
                        format!(
                            "{} (angle gap {:.2}°, pitch gap {:.3})",
                            p.name, p.angle_gap_deg, p.pitch_gap
                        )
                    })
                    .collect();
                write!(
                    f,
                    "{count} pose(s) disagree with the others (a bad detection, a flipped target pose, a wrong time stamp or a typo): {}{}",
                    listed.join(", "),
                    more(*count, shown.len())
                )
            }
            Self::PoorlyPredicted {
                count,
                median_rotation_deg,
                median_translation,
                shown,
            } => write!(
                f,
                "{count} pose(s) are predicted poorly by the others (6× the median gap of {median_rotation_deg:.2}° / {median_translation:.4}): a frame paired with the wrong robot pose, or a failed detection: {}{}",
                shown.join(", "),
                more(*count, shown.len())
            ),
            Self::WeakDirection {
                part,
                axis,
                sigma,
                setup,
                one_axis,
            } => {
                let d = Direction {
                    axis: *axis,
                    sigma: *sigma,
                    verdict: Verdict::Weak,
                };
                match one_axis {
                    None => f.write_str(&advice(*part, &d, *setup)),
                    Some(k) => f.write_str(&one_axis_advice(*part, &d, *setup, k)),
                }
            }
            Self::ReadAs { reading, finding } => {
                write!(f, "read as {} (fix auto): {finding}", reading.name())
            }
            Self::KeptAsGiven { finding, .. } => {
                write!(f, "kept as given (fix as-given), but {finding}")
            }
            Self::IntrinsicsDisagree {
                focal_scale,
                sigma_px,
                scaled_sigma_px,
                rotation_deg,
                translation,
                sigmas,
            } => write!(
                f,
                "the detections and the robot's motions agree better with the focal length scaled by {focal_scale:.3} (reprojection sigma {scaled_sigma_px:.2} px instead of {sigma_px:.2} px), and X moves by {rotation_deg:.3}° and {translation:.4} between the two fits ({sigmas:.1} sigma): X's uncertainty, which takes the intrinsics as exact, does not cover this; check that the intrinsics are this camera's at this resolution, zoom and focus (calibrate them again; refining them with X needs a board that spans the image) and the target's size; a robot whose kinematics are off shows the same way"
            ),
            Self::DistortionDisagrees {
                k1,
                k1_best,
                sigma_px,
                refit_sigma_px,
                rotation_deg,
                translation,
                sigmas,
            } => write!(
                f,
                "the detections and the robot's motions agree better with the radial distortion k1 = {k1_best:.4} than with the {k1:.4} given (reprojection sigma {refit_sigma_px:.2} px instead of {sigma_px:.2} px), and X moves by {rotation_deg:.3}° and {translation:.4} between the two fits ({sigmas:.1} sigma): X's uncertainty, which takes the intrinsics as exact, does not cover this; check that the distortion coefficients are this camera's at this resolution, zoom and focus (calibrate them again; refining them with X needs a board that spans the image)"
            ),
            Self::Undetermined { part, kind, reason } => write!(
                f,
                "{kind} `{part}` is undetermined and given no number: {reason}; record poses in which it is seen while the robot turns about two different axes, or in which it sees (or is seen with) a part that is determined"
            ),
            Self::LoopMisfit {
                parts,
                singled_out,
                loops,
                worst_ratio,
                change_sigmas,
            } => {
                let names: Vec<String> = parts.iter().map(|p| format!("`{p}`")).collect();
                let who = if *singled_out {
                    format!("{} does not fit the rest of the rig", names.join(", "))
                } else {
                    format!(
                        "one of {} does not fit the rest of the rig",
                        names.join(", ")
                    )
                };
                write!(
                    f,
                    "{who}: {} loop(s) do not close ({}; their RMS closure up to {worst_ratio:.1} times what the noise and the parts' uncertainty explain, their mean changing by up to {change_sigmas:.1} standard errors between the poses before one pose and those after): a camera or target moved during the recording, or its observations are misread; calibrate it again on a recording in which it did not move",
                    loops.len(),
                    loops.join(", ")
                )
            }
            Self::PriorDisagrees {
                component,
                prior,
                data,
                sigmas,
            } => write!(
                f,
                "the prior {component}={prior} disagrees with the value the motions determine ({data:.6}) by {sigmas:.1} sigma: the data's value is kept; check the measurement behind the prior, and its unit (the input's)"
            ),
            Self::GoalMissed { goal, sigma } => write!(
                f,
                "X's uncertainty (one sigma: rotation {}°, translation {}) is above your goal ({}° and {}, one sigma): record more motions (`handeye advise --goal {},{}` suggests which), then calibrate again",
                four_digits(sigma.rotation_deg),
                four_digits(sigma.translation),
                goal.rotation_deg,
                goal.translation,
                goal.rotation_deg,
                goal.translation,
            ),
            Self::SwappedSizes {
                x_translation,
                y_translation,
                setup,
            } => {
                let (x_is, y_is) = setup.distances_in_words();
                write!(
                    f,
                    "X puts {x_is} at {x_translation:.3} and {y_is} at {y_translation:.3}, the reverse of what the {} setup usually has: if both inputs give the inverse of the transform they name, the same data fit exactly with X and the target's pose swapped; check the directions",
                    setup.name(),
                )
            }
            Self::ReadingsAlike {
                readings,
                fit,
                given,
                frames,
                setup,
            } => {
                let meaning = |r: Reading| {
                    if *frames {
                        r.meaning_in_frames(*setup)
                    } else {
                        r.meaning(*setup)
                    }
                };
                let read: Vec<String> = readings.iter().map(|r| meaning(*r)).collect();
                let check = if *frames {
                    "the frame names"
                } else {
                    "the directions of the poses"
                };
                write!(
                    f,
                    "the poses fit about as well read as {} (median residual {:.2}° and {:.1}% of the motion range, against {:.2}° and {:.1}% as given), and each reading gives another X: the motions are too small or too alike to tell whether the input is read right; record poses with wider turns (30° or more, about different axes) and check {check}",
                    read.join(", or as "),
                    fit[0],
                    100.0 * fit[1],
                    given[0],
                    100.0 * given[1],
                )
            }
            Self::ShiftedPairing {
                shift,
                residual_deg,
                given_residual_deg,
            } => {
                let n = shift.unsigned_abs();
                let records = if n == 1 {
                    "one record".to_string()
                } else {
                    format!("{n} records")
                };
                let way = if *shift > 0 { "after" } else { "before" };
                write!(
                    f,
                    "the camera poses look shifted by {records}: each robot pose fits the camera pose {records} {way} its own (median rotation residual {residual_deg:.2}° against {given_residual_deg:.2}° as paired), and so paired the motions determine X: the motions are fine, the pairing is not; pair each camera pose with its own robot pose (check the export or the time stamps)"
                )
            }
            Self::OrderChange {
                first,
                poses,
                before,
                after,
                rotation_deg,
                translation,
                rotation_sigma_deg,
                translation_sigma,
                p_value,
            } => {
                let angle = |q: &[f64; 4]| 2.0 * q[3].clamp(-1.0, 1.0).acos().to_degrees();
                let t = |v: &[f64; 3]| format!("({:.4}, {:.4}, {:.4})", v[0], v[1], v[2]);
                write!(
                    f,
                    "X changed during the recording, from {first} on (the {} poses before it and the {} from it on agree with two X {rotation_deg:.2}° ± {rotation_sigma_deg:.2}° and {translation:.4} ± {translation_sigma:.4} (input unit) apart; p = {p_value:.1e} over random orders): the camera most likely moved on its mount there (or the target was bumped); X before: translation {}, rotation {:.2}°; from {first} on: translation {}, rotation {:.2}°; the X of the whole recording is neither: calibrate the poses after the change alone (or record again with the camera fixed)",
                    poses[0],
                    poses[1],
                    t(&before.translation),
                    angle(&before.quaternion_xyzw),
                    t(&after.translation),
                    angle(&after.quaternion_xyzw),
                )
            }
            Self::SystematicError {
                p_value,
                halves_rotation_deg,
                halves_translation,
                rotation_sigma_deg,
                translation_sigma,
                joint,
                kinematic_z,
            } => systematic_words(
                f,
                *p_value,
                (*halves_rotation_deg, *halves_translation),
                (*rotation_sigma_deg, *translation_sigma),
                (*joint, *kinematic_z),
            ),
        }
    }
}

/// The z-score of the residuals along the robot's DH table at or below which the warning names the
/// robot's kinematics (`check::identification`).
pub const KINEMATIC_Z: f64 = -3.0;

/// The words of [`Warning::SystematicError`].
fn systematic_words(
    f: &mut fmt::Formatter<'_>,
    p_value: f64,
    halves: (Option<f64>, Option<f64>),
    sigma: (f64, f64),
    (joint, kinematic_z): (Option<usize>, Option<f64>),
) -> fmt::Result {
    write!(
        f,
        "the residuals follow the robot's configuration (poses close together share their error; p = {p_value:.1e}): an error that depends on where the robot is, most often the robot's own kinematic model (uncalibrated link lengths or joint zero offsets), a wrong TCP or flange offset, or the camera's intrinsics; more poses of the same kind will not average it out"
    )?;
    if let (Some(r), Some(t)) = halves {
        write!(
            f,
            "; the two halves of the workspace give X {r:.2}° and {t:.4} (input unit) apart"
        )?;
    }
    write!(
        f,
        "; resampled by workspace region, X is uncertain by {:.2}° and {:.4} (one-sigma, reported as the uncertainty)",
        sigma.0, sigma.1
    )?;
    if let Some(k) = joint {
        write!(f, "; the residual follows joint {k}'s angle most")?;
    }
    match kinematic_z {
        Some(z) if z <= KINEMATIC_Z => {
            return write!(
                f,
                "; it lies along what errors of the robot's DH table do (z = {z:.1}): the robot's kinematics, most likely; calibrate the robot (or use its calibrated model), then calibrate X again"
            );
        }
        Some(z) => write!(
            f,
            "; it does not lie along what errors of the robot's DH table do (z = {z:.1}): look first at the camera's intrinsics and the target's detection"
        )?,
        None => {}
    }
    f.write_str(
        ": calibrate the robot's kinematics (or use its calibrated model), check the TCP/flange offset and the camera's intrinsics, and spread the poses over the workspace you will use X in",
    )
}

/// A size with four significant digits (`0.0007029`, `0.03350`, `12.35`).
fn four_digits(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let digits = (3 - v.abs().log10().floor() as i32).max(0) as usize;
    format!("{v:.digits$}")
}

/// " and N more" when a list shows fewer than it has.
fn more(count: usize, shown: usize) -> String {
    match count.saturating_sub(shown) {
        0 => String::new(),
        n => format!(" and {n} more"),
    }
}

/// One warning as its JSON object: its code and data, `message`, and `remedy` when there is one.
struct Described<'a>(&'a Warning);

impl Serialize for Described<'_> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let data = serde_json::to_value(self.0).map_err(serde::ser::Error::custom)?;
        let mut map = serializer.serialize_map(None)?;
        if let serde_json::Value::Object(fields) = data {
            for (k, v) in &fields {
                map.serialize_entry(k, v)?;
            }
        }
        map.serialize_entry("message", &self.0.to_string())?;
        if let Some(remedy) = self.0.remedy() {
            map.serialize_entry("remedy", &remedy)?;
        }
        map.end()
    }
}

/// Serialises a list of warnings with their messages and remedies (`serialize_with` of the
/// reports' `warnings`); they read back as plain [`Warning`]s, the extra fields ignored.
pub fn described<S: Serializer>(warnings: &[Warning], serializer: S) -> Result<S::Ok, S::Error> {
    let mut seq = serializer.serialize_seq(Some(warnings.len()))?;
    for w in warnings {
        seq.serialize_element(&Described(w))?;
    }
    seq.end()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Serialize, Deserialize)]
    struct Holder {
        #[serde(serialize_with = "described")]
        warnings: Vec<Warning>,
    }

    #[test]
    fn warnings_carry_code_message_and_remedy_and_read_back() {
        let warnings = vec![
            Warning::OneAxis {
                axis_spread_deg: 2.5,
            },
            Warning::SwappedSizes {
                x_translation: 1.2,
                y_translation: 0.1,
                setup: Setup::EyeInHand,
            },
        ];
        let json = serde_json::to_value(Holder {
            warnings: warnings.clone(),
        })
        .unwrap();
        let w = &json["warnings"];
        assert_eq!(w[0]["code"], "one_axis");
        assert_eq!(w[0]["axis_spread_deg"], 2.5);
        assert!(w[0]["message"].as_str().unwrap().contains("2.5°"));
        assert!(w[0].get("remedy").is_none());
        assert_eq!(w[1]["remedy"]["option"], "fix");
        assert_eq!(w[1]["remedy"]["value"], "both-inverted");
        let back: Holder = serde_json::from_value(json).unwrap();
        assert_eq!(back.warnings, warnings);
    }

    #[test]
    fn no_message_names_a_command_line_flag() {
        let every = [
            Warning::WeakConditioning { conditioning: 0.01 },
            Warning::SmallRotations { largest_deg: 1.0 },
            Warning::OneAxis {
                axis_spread_deg: 1.0,
            },
            Warning::RotationResiduals { rms_deg: 9.0 },
            Warning::TranslationResiduals { relative: 0.2 },
            Warning::Outliers {
                count: 7,
                shown: vec![],
            },
            Warning::PoorlyPredicted {
                count: 1,
                median_rotation_deg: 0.1,
                median_translation: 0.001,
                shown: vec!["a.jsonl:3".into()],
            },
            Warning::WeakDirection {
                part: Part::Rotation,
                axis: [0.0, 0.0, 1.0],
                sigma: 1.0,
                setup: Setup::EyeToHand,
                one_axis: None,
            },
            Warning::WeakDirection {
                part: Part::Translation,
                axis: [0.0, 1.0, 0.0],
                sigma: 0.03,
                setup: Setup::EyeInHand,
                one_axis: Some([0.0, 0.0, 1.0]),
            },
            Warning::ReadAs {
                reading: Reading::RobotInverted,
                finding: "f".into(),
            },
            Warning::KeptAsGiven {
                better: Reading::CameraMm,
                finding: "f".into(),
            },
            Warning::SwappedSizes {
                x_translation: 1.0,
                y_translation: 0.1,
                setup: Setup::EyeToHand,
            },
            Warning::ReadingsAlike {
                readings: vec![Reading::CameraInverted, Reading::RobotInverted],
                fit: [0.16, 0.006],
                given: [0.18, 0.010],
                frames: true,
                setup: Setup::EyeInHand,
            },
            Warning::ShiftedPairing {
                shift: 1,
                residual_deg: 0.1,
                given_residual_deg: 9.0,
            },
            Warning::OrderChange {
                first: "a.jsonl:22".into(),
                poses: [21, 19],
                before: Box::new((&crate::model::pose::Transform::identity()).into()),
                after: Box::new((&crate::model::pose::Transform::identity()).into()),
                rotation_deg: 1.0,
                translation: 0.004,
                rotation_sigma_deg: 0.1,
                translation_sigma: 0.001,
                p_value: 5e-4,
            },
            Warning::SystematicError {
                p_value: 1e-5,
                halves_rotation_deg: Some(0.3),
                halves_translation: Some(0.004),
                rotation_sigma_deg: 0.2,
                translation_sigma: 0.003,
                joint: Some(2),
                kinematic_z: Some(-7.5),
            },
            Warning::IntrinsicsDisagree {
                focal_scale: 0.98,
                sigma_px: 1.6,
                scaled_sigma_px: 1.4,
                rotation_deg: 0.07,
                translation: 0.01,
                sigmas: 3.6,
            },
            Warning::DistortionDisagrees {
                k1: -0.18,
                k1_best: -0.21,
                sigma_px: 1.1,
                refit_sigma_px: 0.97,
                rotation_deg: 0.04,
                translation: 0.003,
                sigmas: 4.5,
            },
        ];
        for w in &every {
            let text = w.to_string();
            assert!(!text.contains("--"), "{}: {text}", w.code());
            let json = serde_json::to_value(w).unwrap();
            assert_eq!(json["code"], w.code(), "serde's tag is code()");
        }
    }

    #[test]
    fn a_low_dof_weak_direction_advises_what_such_a_robot_can_record() {
        for part in [Part::Rotation, Part::Translation] {
            let weak = |one_axis| Warning::WeakDirection {
                part,
                axis: [0.02, -0.01, 1.0],
                sigma: 1.35,
                setup: Setup::EyeInHand,
                one_axis,
            };
            let general = weak(None).to_string();
            assert!(
                general.contains("about the gripper x or y axis"),
                "{general}"
            );
            let scara = weak(Some([0.0, 0.0, 1.0]));
            let text = scara.to_string();
            assert!(!text.contains("x or y"), "{text}");
            assert!(text.contains("(0.000, 0.000, 1.000)"), "{text}");
            assert!(text.contains("further across the axis"), "{text}");
            let json = serde_json::to_value(&scara).unwrap();
            assert_eq!(json["one_axis"], serde_json::json!([0.0, 0.0, 1.0]));
            assert!(
                serde_json::to_value(weak(None))
                    .unwrap()
                    .get("one_axis")
                    .is_none()
            );
            assert_eq!(serde_json::from_value::<Warning>(json).unwrap(), scara);
        }
    }
}
