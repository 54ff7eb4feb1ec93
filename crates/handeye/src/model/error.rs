//! The library's one error type.

use std::fmt;

use crate::model::findings::Reading;
use crate::model::motion::Setup;
use crate::model::warning::{Remedy, Warning};

pub use crate::model::pose::TransformProblem;

/// Why a set of motions cannot determine X.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum Degeneracy {
    /// Every motion's rotation is (nearly) zero, so no axis constrains the rotation of X.
    SmallRotations {
        /// The largest rotation angle among the motions, degrees.
        largest_deg: f64,
    },
    /// All rotation axes are (nearly) parallel: X's rotation about that axis is undetermined.
    ParallelAxes {
        /// The largest angle between two motion axes, degrees.
        largest_axis_angle_deg: f64,
    },
    /// The rotation system is too ill-conditioned to trust (conditioning given).
    IllConditioned,
    /// The gripper motions (nearly) do not translate, which the simultaneous form needs to fix
    /// the scale of R_x.
    NoTranslation {
        /// The largest gripper translation among the motions, input units.
        largest: f64,
    },
    /// Under the data's own noise one direction of X moves beyond the refusal threshold
    /// (`crate::uncertainty`): the motions do not determine it.
    Undetermined {
        /// The direction (rotation about `axis`, or translation along it).
        part: crate::model::findings::Part,
        /// The direction, in X's reference frame.
        axis: [f64; 3],
        /// Its one-sigma: degrees for rotation, input units for translation.
        sigma: f64,
        /// The setup, which names X's reference frame.
        setup: crate::model::motion::Setup,
    },
    /// The method leaves X undetermined under the data's own noise, but the same motions
    /// determine it with `andreff` (its bootstrap judged with the same bounds): the method, not
    /// the motions, is at fault.
    MethodUndetermined {
        /// The method's name.
        method: &'static str,
        /// `andreff`'s one-sigma of X's rotation, degrees.
        rotation_deg: f64,
        /// `andreff`'s one-sigma of X's translation, input units.
        translation: f64,
    },
    /// Every motion rotates about the same axis (a SCARA, a 4-axis arm, a gantry with one wrist
    /// joint): the motions determine X's rotation and its translation across that axis, never its
    /// translation along it, and something else is missing (`missing`).
    LowDof {
        /// The common axis, in X's parent frame.
        axis: [f64; 3],
        /// The largest angle between a motion's axis and it, degrees.
        spread_deg: f64,
        /// The setup, which names X's parent frame.
        setup: crate::model::motion::Setup,
        /// What is missing.
        missing: LowDofMissing,
        /// How many joint angles each record gives, where the input gives them: a robot of six
        /// or more can turn about another axis, and is told to first (`None`: nothing tells, and
        /// the recording advice leads too).
        joints: Option<usize>,
    },
    /// Re-solving under the data's own noise was refused too often: X is at the edge of what the
    /// motions determine.
    Unstable {
        /// Re-solves refused.
        refused: usize,
        /// Re-solves tried.
        tried: usize,
    },
}

/// " (conditioning c)" after a refusal's reason, but for a low-DOF one (Andreff's rotation
/// system says nothing there).
fn conditioning_words(reason: &Degeneracy, conditioning: f64) -> String {
    match reason {
        Degeneracy::LowDof { .. } => String::new(),
        _ => format!(" (conditioning {conditioning:.3e})"),
    }
}

/// What a low-DOF recording ([`Degeneracy::LowDof`]) lacks.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum LowDofMissing {
    /// A prior on X's translation along the axis (the component named), which no prior covers.
    Prior(crate::model::prior::Component),
    /// The axis is not along a coordinate axis of X's parent frame: no prior on tx, ty or tz can
    /// state X's translation along it.
    NotStatable,
    /// The motions do not fix X's rotation about the axis or its translation across it (too few,
    /// too small, no translation across the axis).
    Motions,
    /// The hand's and the camera's translations along the axis (each motion's pitch, the same
    /// length seen by both) differ by this factor (hand over camera): their length units differ.
    Units {
        /// RMS hand pitch over RMS camera pitch.
        ratio: f64,
    },
}

/// The words of a [`Degeneracy::LowDof`] refusal.
pub(crate) fn low_dof_words(
    axis: &[f64; 3],
    spread_deg: f64,
    setup: Setup,
    missing: LowDofMissing,
    joints: Option<usize>,
) -> String {
    let frame = crate::model::findings::reference_frame(setup);
    // No "-0.000".
    let [x, y, z] = axis.map(|v| if v.abs() < 5e-4 { 0.0 } else { v });
    let i = (0..3)
        .max_by(|&a, &b| axis[a].abs().total_cmp(&axis[b].abs()))
        .unwrap_or(2);
    let along_coordinate = axis[i].abs() >= crate::model::prior::PRIOR_AXIS_DEG.to_radians().cos();
    let which = if along_coordinate {
        format!("the {frame}'s {}", ["x", "y", "z"][i])
    } else {
        "one axis".into()
    };
    let what = format!(
        "every motion rotates about the same axis ({which}, ({x:.3}, {y:.3}, {z:.3}) in the {frame} frame, within {spread_deg:.2}°): a SCARA or 4-axis robot, or a gantry with one wrist joint"
    );
    match missing {
        LowDofMissing::Prior(c) => {
            let measure = match setup {
                Setup::EyeInHand => "the camera's offset from the gripper frame's origin",
                Setup::EyeToHand => "the camera's offset from the robot base's origin",
            };
            let n = c.name();
            // A robot that can turn about another axis is told so first; the prior is for one
            // that cannot (its joints say so, when the records give them).
            let lead = match joints {
                Some(j) if j <= 5 => String::new(),
                Some(j) => format!(
                    "record turns about another axis: the records give {j} joint angles, a robot that can turn the camera about a second axis, and motions about two axes determine X whole. "
                ),
                None => "record turns about another axis, if the robot can (a 6-axis arm): motions about two axes determine X whole; a prior is for a robot that cannot. ".into(),
            };
            format!(
                "{lead}{what}. Such motions determine X's rotation and its translation across the axis, but never its translation along it: measure {measure} along {} (X's {n}, signed: positive when the camera lies on the + side of the origin, negative on the other; the input's length unit) and give it as a prior, `--prior {n}=VALUE+-SIGMA` (`prior=\"{n}=VALUE+-SIGMA\"` in Python; without `+-SIGMA` the value is taken as exact). The data cannot check the prior, its sign included",
                crate::model::prior::direction_words(setup, c)
            )
        }
        LowDofMissing::NotStatable => format!(
            "{what}. Such motions never determine X's translation along that axis, and it is not along an axis of the {frame} frame (more than {:.0}° from each), so no prior on tx, ty or tz can state it: add motions that rotate about another axis, if the robot can make them",
            crate::model::prior::PRIOR_AXIS_DEG
        ),
        LowDofMissing::Motions => format!(
            "{what}. X's rotation about the axis and its translation across it come from the motions' translations across the axis and their turns about it, and these motions do not fix them: add poses that move the gripper further across the axis and turn it through larger angles about it (or check how the input reads: both sides in one length unit, each pose in the direction its name says)"
        ),
        LowDofMissing::Units { ratio } => {
            let fix = if ratio > 1.0 { "robot-mm" } else { "camera-mm" };
            format!(
                "{what}. The robot's and the camera's translations along the axis, the same length seen by both, differ by a factor of {ratio:.3e} (robot over camera): their poses are in different length units; if one is in millimetres and the other in metres, pass `--fix {fix}` (`fix=\"{fix}\"` in Python)"
            )
        }
    }
}

impl fmt::Display for Degeneracy {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::SmallRotations { largest_deg } => write!(
                f,
                "all rotations are too small (largest {largest_deg:.3}°): move the gripper through larger rotations"
            ),
            Self::ParallelAxes {
                largest_axis_angle_deg,
            } => write!(
                f,
                "all rotation axes are nearly parallel (at most {largest_axis_angle_deg:.3}° apart): rotate about at least two clearly different axes"
            ),
            Self::NoTranslation { largest } => write!(
                f,
                "the gripper barely translates (largest motion {largest:.3e}): the simultaneous form cannot fix the scale of the rotation; use `andreff` or another method"
            ),
            Self::Undetermined {
                part,
                axis,
                sigma,
                setup,
            } => f.write_str(&crate::model::findings::advice(
                *part,
                &crate::model::findings::Direction {
                    axis: *axis,
                    sigma: *sigma,
                    verdict: crate::model::findings::Verdict::Undetermined,
                },
                *setup,
            )),
            Self::MethodUndetermined {
                method,
                rotation_deg,
                translation,
            } => write!(
                f,
                "{method} does not determine X from these motions under their own noise, but the motions do: \
                 `andreff` determines X from them (one-sigma {rotation_deg:.2}° and {translation:.3e} in the input's \
                 length unit); use `--method andreff` (`method=\"andreff\"` in Python), or another method"
            ),
            Self::LowDof {
                axis,
                spread_deg,
                setup,
                missing,
                joints,
            } => f.write_str(&low_dof_words(axis, *spread_deg, *setup, *missing, *joints)),
            Self::Unstable { refused, tried } => write!(
                f,
                "{refused} of {tried} re-solves under the data's own noise were refused: X is at the edge of what these motions determine; add motions with larger rotations about different axes"
            ),
            Self::IllConditioned => write!(
                f,
                "the rotation system is too ill-conditioned: add motions with larger rotations about different axes"
            ),
        }
    }
}

/// Every error of the library.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Fewer motions than the method needs.
    #[error(
        "{got} motion(s) given, at least {need} needed: record more poses (each motion joins two poses)"
    )]
    TooFewMotions {
        /// Motions given.
        got: usize,
        /// Motions needed.
        need: usize,
    },
    /// The motions cannot determine X.
    #[error("degenerate motions: {reason}{}", conditioning_words(reason, *conditioning))]
    Degenerate {
        /// Which degeneracy.
        reason: Degeneracy,
        /// Conditioning of the rotation system (second-smallest over largest singular value).
        conditioning: f64,
    },
    /// A transform that is not rigid.
    #[error("{what}: {problem}")]
    InvalidTransform {
        /// Which transform (field, pose number …).
        what: String,
        /// What is wrong.
        problem: TransformProblem,
    },
    /// The poses fit far better read another way (inverted, another quaternion order, another
    /// unit): the as-given reading would give a wrong X.
    ///
    /// It carries the finding in words and the readings as data; its message adds the fix in the
    /// words of both faces ([`Error::remedy`] gives it typed, for a face that words it in its own
    /// terms: the OpenCV drop-in names OpenCV's arguments).
    #[error(
        "{}",
        misread_message(.finding, .fit, .readings, .setup, .other_setup, .frames)
    )]
    Misread {
        /// What fits better, how well, and the other readings that fit as well, in words (no
        /// face's spelling of the fix), as `ReadingCheck::finding` words it.
        finding: String,
        /// How well, in numbers: "median residual 0.17° and 0.4% of the motion range, against
        /// 29.45° and 15.0% as given" (`ReadingCheck::fit_words`; empty where the finding has
        /// none apart). A recording of the other setup is refused with these numbers after the
        /// setup it looks like.
        fit: String,
        /// The readings that fit far better, the one the finding leads with first.
        readings: Vec<Reading>,
        /// The setup the poses were read in (a robot pose inverted may be the other setup).
        setup: Setup,
        /// The poses may be a recording of the other setup: the robot poses read inverted (what
        /// the other setup reads) fit far better, with X and Y of the sizes the other setup makes
        /// likely (`ReadingCheck::other_setup`). The first remedy is then `setup`.
        other_setup: bool,
        /// The poses were looked up between named frames (`Written::frames`): an inverted
        /// reading means two frame names swapped, which no option of the call fixes.
        frames: bool,
    },
    /// X is not determined, and the input shows why: outlier poses, or a reading of the input
    /// that fits far better (kept by request). Its message gives each cause with its fix in the
    /// words of both faces ([`Error::remedy`] gives the first fix typed).
    #[error("X cannot be trusted: {}", untrusted_advice(.refusal, .why))]
    Untrusted {
        /// The refusal the input explains; `None` when the outlier poses alone refuse X (the
        /// drop-in for OpenCV's `calibrateHandEye`, which returns X alone).
        refusal: Option<Box<Error>>,
        /// What the input shows: the warnings that explain the refusal, each with its remedy.
        why: Vec<Warning>,
    },
    /// A stream ended without an X to publish, and why (what the estimator was waiting for).
    #[error("no X to publish from {poses} pose(s): {why}")]
    NoEstimate {
        /// Poses read.
        poses: usize,
        /// Why there is no estimate, in words.
        why: String,
    },
    /// Malformed input data, with its place.
    #[error("{}", parse_words(.file, *.line, .field, .message))]
    Parse {
        /// File name (or `-` for standard input).
        file: String,
        /// Line number, from 1 (0 when the problem concerns the whole file).
        line: usize,
        /// Field or column concerned.
        field: String,
        /// What is wrong.
        message: String,
        /// The one option that would read the line, where one would (a record with `detections`
        /// and no camera pose: [`Remedy::Pixels`]); each face words it ([`Error::remedy`]).
        remedy: Option<Remedy>,
    },
    /// A ROS 2 recording that cannot be read or used: the file, the place (topic and message
    /// number) when one message is at fault, and what is wrong.
    #[error("{file}{}: {message}", .at.as_ref().map(|a| format!(" ({a})")).unwrap_or_default())]
    Bag {
        /// The recording or one of its storage files.
        file: String,
        /// Where in it: `topic /tf, message 12`.
        at: Option<String>,
        /// What is wrong.
        message: String,
    },
    /// A file could not be read.
    #[error("{file}: {source}")]
    Io {
        /// File name.
        file: String,
        /// Underlying error.
        source: std::io::Error,
    },
    /// The clock offset searched pairs the poses into no agreement on one X: the clocks differ
    /// by more than the offsets searched, or the streams are not of one motion. A solve on such
    /// pairs is not an answer.
    #[error(
        "the clock offset was not found: the best offset searched within ±{searched:.0} s, {offset:.3} s, {}, the poses paired there disagree on X by {agreement_deg:.1}° RMS (the best 80% of them; under {limit_deg:.0}° when paired right): the camera's and the robot's clocks probably differ by more than {searched:.0} s; give the offset, `--time-offset SECONDS` (camera clock minus robot clock; `time_offset=SECONDS` in Python)",
        if *at_edge { "lies at the edge of the search" } else { "is no answer" }
    )]
    OffsetNotFound {
        /// The best offset searched, seconds (camera clock minus robot clock).
        offset: f64,
        /// It lies at the edge of the offsets searched (`io::sync::at_search_edge`): the best may
        /// lie beyond.
        at_edge: bool,
        /// How well the poses paired at it agree on one X, degrees RMS.
        agreement_deg: f64,
        /// The offsets searched, ± seconds.
        searched: f64,
        /// The most the poses of a found offset disagree, degrees.
        limit_deg: f64,
    },
    /// The clock offset of two streams could not be found (`auto`): which streams, and why.
    #[error("time offset `auto` on {streams}: {source}")]
    TimeOffset {
        /// The streams searched (two files, or a recording's robot and target).
        streams: String,
        /// Why the search failed.
        source: Box<Error>,
    },
    /// The detections do not fit any X: the pixels left after the best fit are far above
    /// detection noise (a wrong unit, wrong intrinsics, robot poses that are not the images').
    #[error(
        "X cannot be trusted: the detections do not fit (reprojection sigma {sigma_px:.1} px after the best fit, RMS {rms_px:.1} px): {hint}"
    )]
    PixelsUnfit {
        /// Robust sigma of one pixel coordinate, pixels.
        sigma_px: f64,
        /// RMS over the detections kept, pixels.
        rms_px: f64,
        /// What to check, in words.
        hint: String,
    },
    /// One camera's observations of a rig fit far better read another way (inverted, another
    /// quaternion order, another length unit): the rig's solve would be wrong.
    #[error(
        "camera `{camera}` seeing `{target}`: {finding}; correct that camera's observations in the recording (a rig is read as given)"
    )]
    RigMisread {
        /// The camera.
        camera: String,
        /// The target it sees.
        target: String,
        /// What fits better, in words.
        finding: String,
    },
    /// Nothing of a rig is determined by its observations.
    #[error(
        "no camera or target of the rig is determined: {}; record poses in which each camera sees a target on the other part (gripper or base) while the robot turns about two different axes",
        .parts.join("; ")
    )]
    RigUndetermined {
        /// Each part with its reason, in words.
        parts: Vec<String>,
    },
    /// A parameter out of its valid range.
    #[error("parameter `{name}`: {message}")]
    InvalidParameter {
        /// The parameter's name.
        name: &'static str,
        /// What is wrong.
        message: String,
    },
}

impl Error {
    /// The one option of the call that would fix the refusal, if one would (as
    /// [`Warning::remedy`] for a caution): the better reading of a misread input, the first
    /// remedy of what makes X untrusted, or the option that reads a line (calibrating a record
    /// with `detections` alone on its pixels).
    pub fn remedy(&self) -> Option<Remedy> {
        match self {
            Self::Misread {
                setup,
                other_setup: true,
                ..
            } => Some(Remedy::Setup(setup.other())),
            Self::Misread {
                readings,
                frames: true,
                ..
            } if readings.first().is_some_and(|r| r.inverts()) => None,
            Self::Misread { readings, .. } => readings.first().map(|&r| Remedy::Fix(r)),
            Self::Untrusted { why, .. } => why.iter().find_map(|w| w.remedy()),
            Self::Parse { remedy, .. } => *remedy,
            _ => None,
        }
    }
}

/// The advice of [`Error::Misread`]: the finding, then the fix in the words of both faces; for a
/// robot pose inverted, also the other setup (which reads the robot poses the other way). When the
/// poses may be the other setup's (`other_setup`), the user is asked where the camera is, the
/// other setup first: a recording of the other setup and one of this setup with the camera poses
/// inverted are the same numbers, and the wrong one of the two fixes gives the target's pose as X
/// under a good verdict.
pub(crate) fn misread_advice(
    finding: &str,
    fit: &str,
    readings: &[Reading],
    setup: &Setup,
    other_setup: &bool,
    frames: &bool,
) -> String {
    let Some(&better) = readings.first() else {
        return finding.to_string();
    };
    if *frames && better.inverts() {
        return frames_advice(finding, readings, *setup, *other_setup);
    }
    if *other_setup {
        return other_setup_advice(fit, readings, *setup);
    }
    let mut text = format!(
        "{finding}: correct the input, or {}",
        Remedy::Fix(better).in_words()
    );
    if better == Reading::RobotInverted {
        let other = setup.other().name();
        text.push_str(&format!(
            "; if the setup is {other}, pass `--setup {other}` (`setup=\"{other}\"` in Python)"
        ));
    }
    text
}

/// The message of [`Error::Misread`]: "the input looks misread" and its advice; a recording that
/// looks like the other setup's (the commonest mistake, a forgotten `--setup`) leads with that
/// setup instead, in its first words.
fn misread_message(
    finding: &str,
    fit: &str,
    readings: &[Reading],
    setup: &Setup,
    other_setup: &bool,
    frames: &bool,
) -> String {
    let advice = misread_advice(finding, fit, readings, setup, other_setup, frames);
    if *other_setup && !*frames {
        advice
    } else {
        format!("the input looks misread: {advice}")
    }
}

/// [`misread_advice`] when the poses may be the other setup's: that setup first (its remedy in the
/// first line), then the fit's numbers (`fit`), then the one mirror reading that means this setup
/// with its camera poses inverted.
fn other_setup_advice(numbers: &str, readings: &[Reading], setup: Setup) -> String {
    let other = setup.other();
    let mirror = readings
        .iter()
        .copied()
        .find(|&r| r != Reading::RobotInverted)
        .unwrap_or(Reading::CameraInverted);
    format!(
        "the poses look like a recording of the {} setup: if {}, {}. They fit far better read that way ({numbers}); if {} instead, its camera poses are inverted: correct the input, or {}",
        other.name(),
        camera_in_words(other),
        Remedy::Setup(other).in_words(),
        camera_in_words(setup),
        Remedy::Fix(mirror).in_words()
    )
}

/// [`misread_advice`] for poses looked up between named frames, whose directions are right as
/// named: an inverted reading means two frame names given the wrong way round (swap them), or,
/// for the robot poses, the other setup. Inverting the poses is never advised.
fn frames_advice(finding: &str, readings: &[Reading], setup: Setup, other_setup: bool) -> String {
    let swap = |reading: Reading| match reading {
        Reading::RobotInverted => Some(SWAP_ROBOT_FRAMES),
        Reading::CameraInverted => Some(SWAP_CAMERA_FRAMES),
        Reading::BothInverted => Some(SWAP_BOTH_FRAMES),
        _ => None,
    };
    let swaps: Vec<&str> = readings.iter().filter_map(|&r| swap(r)).collect();
    let other = setup.other();
    let robot = readings.contains(&Reading::RobotInverted);
    let mut text = format!(
        "{finding}: the poses were looked up between the frames named, so their directions are right as named and inverting them is not the fix"
    );
    if robot && other_setup {
        text.push_str(&format!(
            "; if {}, {}; if {}, {}",
            camera_in_words(other),
            Remedy::Setup(other).in_words(),
            camera_in_words(setup),
            swaps.join(", or ")
        ));
    } else {
        text.push_str(&format!("; {}", swaps.join(", or ")));
        if robot {
            text.push_str(&format!(
                "; if {}, {}",
                camera_in_words(other),
                Remedy::Setup(other).in_words()
            ));
        }
    }
    text
}

/// The swap of the robot's two frame names, in the words of both faces.
const SWAP_ROBOT_FRAMES: &str = "swap the base and gripper frame names (`--base-frame` and `--gripper-frame`; `base_frame` and `gripper_frame` in Python)";
/// The swap of the camera's two frame names.
const SWAP_CAMERA_FRAMES: &str = "swap the camera and target frame names (`--camera-frame` and `--target-frame`; `camera_frame` and `target_frame` in Python)";
/// Both swaps.
const SWAP_BOTH_FRAMES: &str =
    "swap both pairs of frame names (base and gripper, camera and target)";

/// Where the camera is in a setup, in words: "the camera is fixed (eye-to-hand)".
fn camera_in_words(setup: Setup) -> String {
    let camera = match setup {
        Setup::EyeInHand => "the camera rides on the gripper",
        Setup::EyeToHand => "the camera is fixed",
    };
    format!("{camera} ({})", setup.name())
}

/// The advice of [`Error::Untrusted`]: the refusal, then each warning that explains it with its
/// remedy in the words of both faces; without a refusal, the outliers and how to leave them out
/// (for the drop-in, whose callers calibrate in Python or on the command line to do so).
fn untrusted_advice(refusal: &Option<Box<Error>>, why: &[Warning]) -> String {
    let Some(refusal) = refusal else {
        return why
            .iter()
            .map(|w| format!("{w}; X would follow them: leave them out, or calibrate with `reject_outliers=True` (`handeye.calibrate` in Python, `--reject-outliers` on the command line)"))
            .collect::<Vec<_>>()
            .join("; ");
    };
    untrusted_in_order(Some(refusal.to_string()), why, |w, leads| {
        match (leads, w.remedy()) {
            (true, Some(remedy)) => format!("{w}; {}", remedy.in_words()),
            _ => w.to_string(),
        }
    })
}

/// The parts of an [`Error::Untrusted`] in the order every face says them: what the input shows
/// that one option fixes (poses that disagree, by their lines; a reading that fits far better; a
/// pairing off by a record: [`Warning::leads`]) first, being the likelier cause (a ×1000 typo on
/// one line leaves X undetermined too, and "add larger rotations" would send the user the wrong
/// way); then the `refusal`, "as the input is: …" after them; then the other warnings. Each
/// warning in the face's `words` (told whether it leads), joined with "; ".
pub fn untrusted_in_order(
    refusal: Option<String>,
    why: &[Warning],
    words: impl Fn(&Warning, bool) -> String,
) -> String {
    let (first, others): (Vec<&Warning>, Vec<&Warning>) = why.iter().partition(|w| w.leads());
    let mut parts: Vec<String> = first.iter().map(|w| words(w, true)).collect();
    if let Some(refusal) = refusal {
        parts.push(if parts.is_empty() {
            refusal
        } else {
            format!("as the input is: {refusal}")
        });
    }
    parts.extend(others.iter().map(|w| words(w, false)));
    parts.join("; ")
}

/// The words of [`Error::Parse`]: `file:line: field `f`: message`, or, for the whole file (line
/// 0, no field), `file: message` (an empty file is refused by the reader: "the file is empty").
fn parse_words(file: &str, line: usize, field: &str, message: &str) -> String {
    if line > 0 || field != "-" {
        format!("{file}:{line}: field `{field}`: {message}")
    } else {
        format!("{file}: {message}")
    }
}

/// Result alias of the library.
pub type Result<T, E = Error> = std::result::Result<T, E>;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::findings::OutlierPose;

    fn outliers() -> Warning {
        Warning::Outliers {
            count: 1,
            shown: vec![OutlierPose {
                pose: 3,
                name: "pose 3".into(),
                angle_gap_deg: 2.0,
                pitch_gap: 0.01,
                rms_px: None,
            }],
        }
    }

    /// The words of each refusal, as the faces print them, and the typed remedy they name.
    #[test]
    fn refusals_word_their_typed_remedy() {
        let misread = Error::Misread {
            finding: "the poses fit far better read as x".into(),
            fit: String::new(),
            readings: vec![Reading::RobotInverted, Reading::CameraInverted],
            setup: Setup::EyeInHand,
            other_setup: false,
            frames: false,
        };
        assert_eq!(
            misread.to_string(),
            "the input looks misread: the poses fit far better read as x: correct the input, or \
             pass `--fix robot-inverted` (`fix=\"robot-inverted\"` in Python) to read the input \
             that way; if the setup is eye-to-hand, pass `--setup eye-to-hand` \
             (`setup=\"eye-to-hand\"` in Python)"
        );
        assert_eq!(misread.remedy(), Some(Remedy::Fix(Reading::RobotInverted)));
        let drop_in = Error::Untrusted {
            refusal: None,
            why: vec![outliers()],
        };
        assert_eq!(
            drop_in.to_string(),
            format!(
                "X cannot be trusted: {}; X would follow them: leave them out, or calibrate with \
                 `reject_outliers=True` (`handeye.calibrate` in Python, `--reject-outliers` on the \
                 command line)",
                outliers()
            )
        );
        assert_eq!(drop_in.remedy(), Some(Remedy::RejectOutliers));
        let explained = Error::Untrusted {
            refusal: Some(Box::new(Error::TooFewMotions { got: 1, need: 2 })),
            why: vec![
                Warning::OneAxis {
                    axis_spread_deg: 1.0,
                },
                outliers(),
            ],
        };
        assert_eq!(
            explained.to_string(),
            format!(
                "X cannot be trusted: {}; pass `--reject-outliers` (`reject_outliers=True` in \
                 Python) to leave them out; as the input is: 1 motion(s) given, at least 2 \
                 needed: record more poses (each motion joins two poses); {}",
                outliers(),
                Warning::OneAxis {
                    axis_spread_deg: 1.0
                }
            )
        );
        assert_eq!(explained.remedy(), Some(Remedy::RejectOutliers));
        assert_eq!(Error::TooFewMotions { got: 1, need: 2 }.remedy(), None);
    }
}
