//! What the tracker tells: its estimates, reports, changes, held-out poses and why it has nothing
//! to report, with the JSON lines every face prints.

use std::fmt;

use serde::{Deserialize, Serialize};

use crate::model::error::misread_advice;
use crate::model::findings::{Assessment, Reading};
use crate::model::motion::Setup;
use crate::model::pose::Transform;
use crate::model::prior::Component;

/// The estimate of one segment of the stream (since the start or the last change).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TrackEstimate {
    /// X from every pair of accepted poses of the segment (all-pairs Andreff).
    pub x: Transform,
    /// The fixed frame every pose sees under X: `base_from_target` eye-in-hand,
    /// `gripper_from_target` eye-to-hand.
    pub target: Transform,
    /// Accepted poses it rests on.
    pub poses: usize,
    /// First pose number (from 1) of the segment.
    pub since: usize,
    /// Conditioning of its rotation system.
    pub conditioning: f64,
    /// RMS disagreement of the accepted poses with (X, target): rotation in degrees, translation in
    /// input units. The data's own noise level.
    pub noise_rotation_deg: f64,
    /// See `noise_rotation_deg`.
    pub noise_translation: f64,
    /// Expected size of the error of X, rotation in degrees (split-half: the poses are dealt
    /// alternately to two more accumulators, and half the difference of their estimates has the
    /// distribution of the full estimate's error). `None` until both halves have an estimate.
    pub uncertainty_rotation_deg: Option<f64>,
    /// The same for the translation, input units.
    pub uncertainty_translation: Option<f64>,
    /// The covariance of X's error (rotation vector in radians, then translation, in X's parent
    /// frame as the batch `Uncertainty::covariance`): the first-order covariance with each pose
    /// one measurement at the data's noise level, scaled up until its sizes reach the reported
    /// uncertainty (which may be the split-half or the drift term). `None` with the uncertainty.
    #[serde(default)]
    pub covariance: Option<[[f64; 6]; 6]>,
    /// The error at the working distance (SPEC sec. 9 `at_point`): a point in the camera frame
    /// (the mean target position seen in the segment, or the one asked for) and the one-sigma
    /// distance by which X misplaces it, input unit. `None` with the uncertainty.
    #[serde(default)]
    pub at_point: Option<([f64; 3], f64)>,
    /// The robot-world solution (Shah's A X = Z B over the same accepted poses of the segment,
    /// [`crate::solve::robot_world_accumulate::RobotWorldAccumulator`]): X and the target solved together rather than
    /// the target as the mean fixed frame under the hand–eye X. `None` while its system is
    /// degenerate.
    pub robot_world: Option<RobotWorldPair>,
    /// Set when X is the low-DOF solve (every rotation about one axis, a prior on X's translation
    /// along it, [`crate::solve::low_dof_accumulate`]): the component that came from the prior.
    #[serde(default)]
    pub prior: Option<TrackPrior>,
    /// Set when X was solved on the pixels of the detections (`handeye online --intrinsics`,
    /// `OnlinePixels`): the fit on the pixels. `None` on poses.
    #[serde(default)]
    pub reprojection: Option<PixelFit>,
}

/// The fit on the pixels of an estimate solved on them (as the batch `ReprojectionSummary`, in
/// counts: the frames are named in the batch report).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PixelFit {
    /// RMS reprojection error over the detections kept, pixels.
    pub rms_px: f64,
    /// Robust sigma of one pixel coordinate, pixels.
    pub sigma_px: f64,
    /// Detections used in all.
    pub detections: usize,
    /// Detections left out as mis-detections (beyond 5 robust sigmas).
    pub outlier_detections: usize,
    /// Frames whose start pose was the other pose of the planar ambiguity: chosen by the robot's
    /// motion.
    pub flips_resolved: usize,
    /// The verdict of the calibration on the pixels (its cautions: a weakly determined direction
    /// of X, …): a `questionable` one makes the report's verdict `questionable`.
    pub verdict: Assessment,
}

/// The component of a low-DOF X that came from the prior, not from the data.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TrackPrior {
    /// The component (`tz` for a SCARA).
    pub component: Component,
    /// Its value, the poses' length unit (a prior that named another unit converted).
    pub value: f64,
    /// Its one-sigma, the same unit (0: exact); added to the translation uncertainty.
    pub sigma: f64,
    /// The common rotation axis, X's parent frame (its largest component positive).
    pub axis: [f64; 3],
    /// RMS angle of the rotations' axes from it, degrees.
    pub spread_deg: f64,
}

/// X and the target pose of a robot-world solution.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RobotWorldPair {
    /// X.
    pub x: Transform,
    /// The target pose (`base_from_target` / `gripper_from_target`).
    pub target: Transform,
}

/// Why a pose was held out of the sums.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "test")]
pub enum HeldOut {
    /// Its motions to recent poses break the screw invariants.
    Screw {
        /// Median rotation-angle gap, degrees.
        angle_gap_deg: f64,
        /// Median pitch gap, input units.
        pitch_gap: f64,
    },
    /// Its fixed frame disagrees with the mature estimate.
    Residual {
        /// Residual in RMS of the accepted poses' residuals.
        statistic: f64,
    },
}

impl fmt::Display for HeldOut {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Screw {
                angle_gap_deg,
                pitch_gap,
            } => write!(
                f,
                "its motions to the recent poses break the rigid-motion invariants (angle gap {angle_gap_deg:.2}°, pitch gap {pitch_gap:.2e}): a bad detection, a flipped target pose or a wrong stamp"
            ),
            Self::Residual { statistic } => write!(
                f,
                "it disagrees with the current estimate by {statistic:.1} times the typical residual"
            ),
        }
    }
}

/// A confirmed change of X or of the target.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Change {
    /// First pose number of the new segment (where the disagreement began).
    pub at: usize,
    /// Pose number at which the change was confirmed.
    pub confirmed: usize,
    /// Rotation between the old and the new X, degrees.
    pub x_rotation_deg: f64,
    /// Distance between the old and the new X's translations, input units.
    pub x_translation: f64,
    /// Rotation between the old and the new target pose, degrees.
    pub target_rotation_deg: f64,
    /// Distance between the old and the new target positions, input units.
    pub target_translation: f64,
}

/// Why an estimate was reported.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Reason {
    /// The first determined estimate of a segment.
    Determined,
    /// `every` poses since the last report.
    Every,
    /// Both uncertainties shrank to `shrink` of the last report's.
    Shrunk,
    /// The end of the stream.
    End,
}

/// A reported estimate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Report {
    /// Number of this report (1, 2, …).
    pub number: usize,
    /// Pose number at which it was made.
    pub pose: usize,
    /// Why now.
    pub reason: Reason,
    /// The estimate.
    pub estimate: TrackEstimate,
    /// Set on a final report whose uncertainty is above the reporting bounds (but below the batch
    /// refusal's, 10° and half the scene): why it is weak. `None`: determined.
    pub weak: Option<Pending>,
    /// X and the target pose have the sizes the setup makes unlikely (the camera farther from
    /// the gripper than the target from the base, eye-in-hand): the data fit exactly as well with
    /// both inputs inverted, X and the target swapped.
    pub implausible: bool,
    /// The last systematic-error test of the segment's poses (as the batch report's
    /// `systematic`, `check::systematic`): run at a report once the segment has doubled since
    /// the last one, and at the end. `None` before the segment has 12 poses.
    #[serde(default)]
    pub systematic: Option<crate::check::systematic::Systematic>,
    /// The cautions on the estimate, as the batch report's (`systematic_error` when the test
    /// flags an error that follows the configuration: the uncertainty is then widened as the
    /// batch widens it).
    #[serde(default)]
    pub warnings: Vec<crate::model::warning::Warning>,
}

/// What one pose did.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Step {
    /// Pose number (from 1).
    pub pose: usize,
    /// Set when the pose was held out of the sums.
    pub held_out: Option<HeldOut>,
    /// Earlier poses held out now: the first poses, judged together once the gate has learned
    /// (pose number, why).
    pub earlier: Vec<(usize, HeldOut)>,
    /// Set when this pose confirmed a change.
    pub change: Option<Change>,
    /// Set when an estimate is reported at this pose.
    pub report: Option<Report>,
    /// Set when the robot pose is the pose before's (the robot standing still while the camera
    /// streams): one more image of that pose, whose error it shares, so it is not counted again.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub repeat: bool,
}

impl Step {
    /// The poses this step held out, with why: this pose, and earlier ones judged now (the first
    /// poses, judged together once the gate has learned), as (pose number, why).
    pub fn held_out_poses(&self) -> impl Iterator<Item = (usize, &HeldOut)> {
        self.held_out
            .iter()
            .map(|h| (self.pose, h))
            .chain(self.earlier.iter().map(|(p, h)| (*p, h)))
    }
}

/// Why there is no estimate to report.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "why")]
pub enum Pending {
    /// Fewer than three accepted poses since the start or the last change.
    FewPoses {
        /// Accepted poses.
        poses: usize,
    },
    /// The gripper has not turned by more than 2° from the segment's first pose.
    NoRotation {
        /// Largest rotation so far, degrees.
        largest_deg: f64,
    },
    /// Every rotation so far is about one axis: X's rotation about it is not determined.
    ParallelAxes,
    /// The poses fit far better read another way (the batch's check of the readings,
    /// `check::readings::check_readings`, on the first poses): an inverted pose, `w, x, y, z` quaternions, or
    /// millimetres on one side. Nothing is reported from data read wrongly.
    Misread {
        /// The reading that fits.
        reading: Reading,
        /// The setup the poses are read in.
        setup: Setup,
        /// The poses may be the other setup's recording (the same numbers; see
        /// `ReadingCheck::other_setup`): the user is asked where the camera is.
        #[serde(default, skip_serializing_if = "std::ops::Not::not")]
        other_setup: bool,
        /// The poses were looked up between named frames (a recording): an inverted reading
        /// means two frame names swapped.
        #[serde(default, skip_serializing_if = "std::ops::Not::not")]
        frames: bool,
    },
    /// Another reading of the input fits about as well as the as-given one
    /// (`ReadingCheck::alike`): the motions so far are too small or too alike to tell whether
    /// the input is read right. Nothing is reported before they can.
    ReadingsAlike {
        /// The reading that fits about as well.
        reading: Reading,
        /// The setup the poses are read in.
        setup: Setup,
        /// The poses were looked up between named frames.
        #[serde(default, skip_serializing_if = "std::ops::Not::not")]
        frames: bool,
    },
    /// The readings of the input (inverted poses, quaternion order, units) could not be checked
    /// yet: the poses so far are a gripper standing still or turning about one axis. Nothing is
    /// reported before they are.
    ReadingsUnchecked,
    /// Every rotation is about one axis (a low-DOF robot: a SCARA, a 4-axis arm): X's translation
    /// along it is never determined and no prior gives it.
    LowDof {
        /// The axis, X's parent frame.
        axis: [f64; 3],
        /// RMS angle of the rotations' axes from it, degrees.
        spread_deg: f64,
        /// The setup the poses are read in.
        setup: Setup,
        /// The component a prior should give; `None` when the axis is along no coordinate axis.
        prior: Option<Component>,
    },
    /// An estimate exists but its uncertainty is above the bound.
    Undetermined {
        /// Rotation uncertainty, degrees (`None`: too few poses for the split-half estimate).
        rotation_deg: Option<f64>,
        /// Translation uncertainty, input units.
        translation: Option<f64>,
        /// The bound on the rotation, degrees.
        bound_rotation_deg: f64,
        /// The bound on the translation, input units.
        bound_translation: f64,
    },
    /// On the pixels: no estimate is due yet (one is solved at 16, 32, 64, … frames and at the
    /// end).
    FewFrames {
        /// Frames pushed.
        frames: usize,
    },
    /// On the pixels: the last solve made no estimate.
    RefusedOnPixels {
        /// Why, in the calibration's words.
        reason: String,
    },
    /// After a change of X or of the target: why the poses since have no estimate (an estimate
    /// from before the change is not the current X).
    SinceChange {
        /// Why, of the poses since the change ([`Pending::of_motions`]).
        pending: Box<Pending>,
    },
}

/// Where the camera is in a setup: "fixed (eye-to-hand)".
fn where_camera(setup: Setup) -> String {
    let camera = match setup {
        Setup::EyeInHand => "on the gripper",
        Setup::EyeToHand => "fixed",
    };
    format!("{camera} ({})", setup.name())
}

impl Pending {
    /// Whether the reason is the motions of the current segment (too few, too small, about one
    /// axis, not determining X), rather than how the input is read.
    pub fn of_motions(&self) -> bool {
        matches!(
            self,
            Self::FewPoses { .. }
                | Self::NoRotation { .. }
                | Self::ParallelAxes
                | Self::LowDof { .. }
                | Self::Undetermined { .. }
                | Self::SinceChange { .. }
        )
    }
}

impl fmt::Display for Pending {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::FewPoses { poses } => write!(f, "only {poses} usable pose(s) so far"),
            Self::FewFrames { frames } => write!(
                f,
                "{frames} record(s) with detections so far: an estimate is solved at 16, 32, 64, … records and at the end"
            ),
            Self::RefusedOnPixels { reason } => f.write_str(reason),
            Self::SinceChange { pending } => {
                write!(f, "since the last change of X or of the target, {pending}")
            }
            Self::NoRotation { largest_deg } => write!(
                f,
                "no rotation above 2° yet (the largest is {largest_deg:.2}°): turn the gripper"
            ),
            Self::ParallelAxes => write!(
                f,
                "all rotation axes parallel so far: rotate the gripper about another axis"
            ),
            Self::LowDof {
                axis,
                spread_deg,
                setup,
                prior,
            } => f.write_str(&crate::model::error::low_dof_words(
                axis,
                *spread_deg,
                *setup,
                match prior {
                    Some(c) => crate::model::error::LowDofMissing::Prior(*c),
                    None => crate::model::error::LowDofMissing::NotStatable,
                },
                None,
            )),
            Self::ReadingsUnchecked => write!(
                f,
                "the readings of the input (pose directions, quaternion order, units) are not checked yet: the poses sampled so far turn the gripper less than 2° or about one axis only; turn it about other axes"
            ),
            Self::Misread {
                reading,
                setup,
                other_setup,
                frames: true,
            } => f.write_str(&misread_advice(
                &format!(
                    "the poses fit far better read as {}",
                    reading.meaning_in_frames(*setup)
                ),
                "",
                &[*reading],
                setup,
                other_setup,
                &true,
            )),
            Self::ReadingsAlike {
                reading,
                setup,
                frames,
            } => write!(
                f,
                "the poses fit about as well read as {}, which gives another X: the motions so far are too small or too alike to tell whether the input is read right; turn the gripper more (30° or more), about other axes{}",
                if *frames {
                    reading.meaning_in_frames(*setup)
                } else {
                    reading.meaning(*setup)
                },
                if *frames {
                    ", and check the frame names"
                } else {
                    ""
                }
            ),
            Self::Misread {
                reading,
                setup,
                other_setup: true,
                ..
            } => write!(
                f,
                "the poses look like a recording of the {} setup: if the camera is {}, pass `--setup {}`; if it is {}, its camera poses are inverted: correct the input (with `handeye calibrate`, `--fix {}` reads it that way)",
                setup.other().name(),
                where_camera(setup.other()),
                setup.other().name(),
                where_camera(*setup),
                reading.name()
            ),
            Self::Misread {
                reading: Reading::BothInverted,
                setup,
                ..
            } => write!(
                f,
                "both inputs look inverted: X and the target have the sizes of each other for the {} setup, and the camera poses put the target off the camera's axis where, inverted, they put it in view (both readings fit the poses as well): correct the input (with `handeye calibrate`, `--fix both-inverted` reads it that way)",
                setup.name()
            ),
            Self::Misread { reading, setup, .. } => write!(
                f,
                "the poses fit far better read as {}: correct the input (with `handeye calibrate`, `--fix {}` reads it that way)",
                reading.meaning(*setup),
                reading.name()
            ),
            Self::Undetermined {
                rotation_deg,
                translation,
                bound_rotation_deg,
                bound_translation,
            } => match (rotation_deg, translation) {
                (Some(r), Some(t)) => write!(
                    f,
                    "X not determined yet: uncertainty {r:.2}° and {t:.4} (reported below {bound_rotation_deg:.2}° and {bound_translation:.4}); add rotations about other axes"
                ),
                _ => write!(
                    f,
                    "X not determined yet: too few poses to measure its uncertainty"
                ),
            },
        }
    }
}

impl Report {
    /// The report as its JSON line (SPEC sec. 7), the one output of every face: `estimate`,
    /// `pose`, `reason`, `frame`, X (`translation`, `quaternion_xyzw`, `matrix`), `poses`,
    /// `since`, `uncertainty`, `noise`, `conditioning`, `target` (the fixed frame), `robot_world`
    /// (X and the target solved together by Shah over the same poses, when determined) and, on a
    /// weak final report, `weak` with the reason in words; last, `time_offset_s` when a clock
    /// offset was applied to a second stream (as `crate::online::Event` carries it).
    pub fn json(&self, setup: Setup, time_offset_s: Option<f64>) -> serde_json::Value {
        let e = &self.estimate;
        let mut out = serde_json::Map::new();
        out.insert("estimate".into(), self.number.into());
        out.insert("pose".into(), self.pose.into());
        out.insert("reason".into(), serde_json::json!(self.reason));
        let estimator = match e.reprojection {
            Some(_) => "reprojection",
            None => "accumulate",
        };
        out.insert("estimator".into(), estimator.into());
        out.insert("frame".into(), setup.x_frame().into());
        insert_transform(&mut out, &e.x);
        out.insert("poses".into(), e.poses.into());
        out.insert("since".into(), e.since.into());
        let mut uncertainty = serde_json::json!({"rotation_deg": e.uncertainty_rotation_deg, "translation": e.uncertainty_translation});
        if let Some((point, sigma)) = e.at_point {
            uncertainty["at_point"] =
                serde_json::json!({"point": point, "frame": "camera", "sigma": sigma});
        }
        out.insert("uncertainty".into(), uncertainty);
        out.insert("verdict".into(), self.verdict().name().into());
        out.insert(
            "noise".into(),
            serde_json::json!({"rotation_deg": e.noise_rotation_deg, "translation": e.noise_translation}),
        );
        out.insert("conditioning".into(), e.conditioning.into());
        let mut target = serde_json::Map::new();
        target.insert("frame".into(), target_frame(setup).into());
        insert_transform(&mut target, &e.target);
        out.insert("target".into(), target.into());
        if let Some(rw) = &e.robot_world {
            let mut x = serde_json::Map::new();
            x.insert("method".into(), "shah".into());
            x.insert("frame".into(), setup.x_frame().into());
            insert_transform(&mut x, &rw.x);
            let mut target = serde_json::Map::new();
            target.insert("frame".into(), target_frame(setup).into());
            insert_transform(&mut target, &rw.target);
            x.insert("target".into(), target.into());
            out.insert("robot_world".into(), x.into());
        }
        if let Some(p) = &e.prior {
            // As the batch report: which component came from the prior, and the axis.
            out.insert(
                "prior".into(),
                serde_json::json!({p.component.name(): {"value": p.value, "sigma": p.sigma}}),
            );
            out.insert(
                "low_dof".into(),
                serde_json::json!({"axis": p.axis, "spread_deg": p.spread_deg, "free": p.component}),
            );
        }
        if let Some(p) = &e.reprojection {
            out.insert(
                "reprojection".into(),
                serde_json::json!({
                    "rms_px": p.rms_px,
                    "sigma_px": p.sigma_px,
                    "detections": p.detections,
                    "outlier_detections": p.outlier_detections,
                    "flips_resolved": p.flips_resolved,
                }),
            );
        }
        if let Some(w) = &self.weak {
            out.insert("weak".into(), w.to_string().into());
        }
        // A flagged systematic error: its finding and the warning, as the batch report lists
        // them (an unflagged test adds nothing to the line).
        if let Some(s) = self.systematic.as_ref().filter(|s| s.flagged) {
            out.insert("systematic".into(), serde_json::json!(s));
        }
        if !self.warnings.is_empty() {
            let described =
                crate::model::warning::described(&self.warnings, serde_json::value::Serializer);
            if let Ok(w) = described {
                out.insert("warnings".into(), w);
            }
        }
        if self.implausible {
            out.insert(
                "warning".into(),
                "X and the target pose have the sizes the setup makes unlikely: if both inputs give the inverse of the transform they name, the same data fit exactly with X and the target's pose swapped; check the directions".into(),
            );
        }
        if let Some(t) = time_offset_s {
            out.insert("time_offset_s".into(), t.into());
        }
        out.into()
    }
}

impl Report {
    /// The verdict every report carries (SPEC sec. 9): `questionable` for a weak final report,
    /// sizes the setup makes unlikely or a warning (a systematic error), else `good` (an estimate
    /// is reported only once determined).
    pub fn verdict(&self) -> Assessment {
        let pixels = self
            .estimate
            .reprojection
            .as_ref()
            .is_some_and(|p| p.verdict == Assessment::Questionable);
        if self.weak.is_some() || self.implausible || pixels || !self.warnings.is_empty() {
            Assessment::Questionable
        } else {
            Assessment::Good
        }
    }
}

impl Change {
    /// The change as its JSON line: `change` (the first pose of the new segment), `confirmed`,
    /// and how far X and the target moved.
    pub fn json(&self) -> serde_json::Value {
        serde_json::json!({
            "change": self.at,
            "confirmed": self.confirmed,
            "x_rotation_deg": self.x_rotation_deg,
            "x_translation": self.x_translation,
            "target_rotation_deg": self.target_rotation_deg,
            "target_translation": self.target_translation,
        })
    }
}

/// The fixed frame the poses agree on: the target in the base eye-in-hand, on the gripper
/// eye-to-hand.
pub fn target_frame(setup: Setup) -> &'static str {
    match setup {
        Setup::EyeInHand => "base_from_target",
        Setup::EyeToHand => "gripper_from_target",
    }
}

/// Inserts `translation`, `quaternion_xyzw` and `matrix` of `t` into a JSON object.
pub(crate) fn insert_transform(
    object: &mut serde_json::Map<String, serde_json::Value>,
    t: &Transform,
) {
    let j = crate::model::pose::TransformJson::from(t);
    object.insert("translation".into(), serde_json::json!(j.translation));
    object.insert(
        "quaternion_xyzw".into(),
        serde_json::json!(j.quaternion_xyzw),
    );
    object.insert("matrix".into(), serde_json::json!(j.matrix));
}
