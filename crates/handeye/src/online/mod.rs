//! The online calibrator: one record in at a time ([`Record`]: a pose pair, or on the pixels a
//! frame with detections, named as its input names it); everything it made happen out
//! ([`Outputs`]). One engine per calibrator, an internal choice of its configuration:
//!
//! - **The paper's** ([`Estimator::Paper`]): [`OnlineCalibrator::push`] offers each pose pair to
//!   the selection policy ([`select`]); when a pair of motions is selected it solves X with
//!   Andreff's method on those two motions, measures rmsR and rmsT with the configured
//!   [`ErrorSource`], tells the adaptive policy, and returns an [`Event`]. With `optimal` set it
//!   also refines X over the last five selected motions (the paper's "optimal method", sec.
//!   4.1.3). Its readings are checked on the first poses ([`Outputs::misread`]), and a selection
//!   that makes no calibration for a while is told ([`Outputs::stuck`]).
//! - **Accumulate** ([`Estimator::Accumulate`]): every pose goes to the accumulating estimator
//!   (all pairs of poses, gated, watched for change, reported on its own schedule:
//!   [`Outputs::held_out`], [`Outputs::change`], [`Outputs::report`]); the paper's selection does
//!   not run beside it.
//! - **On the pixels** (`intrinsics` in [`OnlineSettings`], [`OnlineCalibrator::on_pixels`],
//!   `handeye online --intrinsics`): frames with detections, and the batch calibration on their
//!   pixels on a doubling schedule, in the same report type.
//!
//! The one length threshold, `d_max`, follows the input's unit, inferred from the first pose
//! unless given ([`Unit`], told once: [`Outputs::unit`]). The configuration rules (what a
//! setting left out defaults to, α₀ in degrees or as a sine, an explicit `d_max` as given) are
//! [`OnlineSettings`]'s, so that every face only gathers and prints. The state is constant in
//! size (the names of the last 300 records kept to name the poses held out), and serialisable
//! (serde) so that a run can be saved and resumed. This layer sits above `calibrate/` for the
//! pixels.

mod event;
mod record;
pub mod select;
mod settings;

use std::collections::VecDeque;
use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::calibrate::options::{Options, Problem};
use crate::calibrate::pixels::OnlinePixels;
use crate::check::quality::{errors_against_truth, residual_rms};
use crate::check::stream::{StreamReading, StreamReadings};
use crate::model::camera::{Frame, Intrinsics};
use crate::model::error::{Error, Result};
use crate::model::motion::{MotionPair, PosePair};
use crate::model::pose::Transform;
use crate::online::select::{Selected, Selector};
use crate::solve::{RefineOptions, andreff, refine_from};
use crate::track::{Pending, Report, Step, TrackEstimate, Tracker};

pub use event::{Event, OptimalEstimate, Rms};
use record::Names;
pub use record::{
    ChangeFound, HeldOutPose, Name, Observed, Outputs, Record, Tell, Thinning, UnitTold,
};
pub use record::{Summary, Tracked};
pub use settings::{AlphaMin, ErrorSource, Estimator, OnlineConfig, OnlineSettings, Unit};

/// Number of selected motions the optimal method refines over (sec. 4.1.3).
pub const OPTIMAL_WINDOW: usize = 5;

/// Poses without a calibration after which the paper's estimator says why
/// ([`Outputs::stuck`]), and again at each doubling of it.
const QUIET_POSES: usize = 200;

/// The online calibrator (see the module documentation).
///
/// # Example
/// ```
/// use handeye::online::{OnlineCalibrator, OnlineConfig};
/// use handeye::{PosePair, Transform};
/// let mut calibrator = OnlineCalibrator::new(OnlineConfig::default())?;
/// let still = PosePair { base_from_gripper: Transform::identity(), camera_from_target: Transform::identity() };
/// // A robot that never moves gives no calibration.
/// for _ in 0..20 {
///     assert!(calibrator.push(&still)?.events.is_empty());
/// }
/// assert_eq!(calibrator.poses(), 20);
/// # Ok::<(), handeye::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OnlineCalibrator {
    config: OnlineConfig,
    selector: Selector,
    poses: usize,
    calibrations: usize,
    /// Selections that Andreff refused as degenerate.
    refused: usize,
    /// The last selected motions with their pose numbers (optimal method only).
    window: VecDeque<([usize; 2], MotionPair)>,
    optimal_results: usize,
    last_x: Option<Transform>,
    /// Pose number of the last calibration, and the previous hand pose with the largest rotation
    /// between consecutive poses since then (radians): what `quiet` says.
    last_calibration: usize,
    previous: Option<Transform>,
    largest_step: f64,
    /// The unit in force: `config.unit`, or the one inferred from the first pose.
    unit: Unit,
    /// The accumulating estimator and what it did with the last pose.
    tracker: Option<Tracker>,
    step: Step,
    /// The paper's estimator: the readings check of the first poses (the accumulating estimator
    /// checks its readings itself), and what it found, until taken. Absent from a calibrator
    /// saved before they were kept here: no check then.
    #[serde(default)]
    readings: Option<StreamReadings>,
    #[serde(default)]
    misread: Option<StreamReading>,
    /// On the pixels ([`OnlineCalibrator::on_pixels`]): the batch calibration on the pixels of
    /// the frames pushed, on a doubling schedule, in place of the paper's selection and the
    /// tracker. Its frames are not saved: serialising a calibrator on the pixels is refused
    /// with an error ([`OnlineCalibrator::on_the_pixels`]), rather than saving a state that would
    /// resume as another calibrator.
    #[serde(
        skip_deserializing,
        skip_serializing_if = "Option::is_none",
        serialize_with = "refuse_to_save"
    )]
    pixels: Option<OnlinePixels>,
    /// The robot pose of the first frame on the pixels: with a report's target pose, the length
    /// unit.
    #[serde(skip)]
    first_robot: Option<Transform>,
    /// The names of the recent records, for naming the poses held out and the changes.
    #[serde(default)]
    names: Names,
    /// Held-out poses counted, for telling them by [`Thinning`]'s rule.
    #[serde(default)]
    held_out_told: Thinning,
    /// Whether the length unit was told ([`Outputs::unit`]).
    #[serde(default)]
    unit_told: bool,
    /// The unit the first pose that fits one tells, whatever the unit in force.
    #[serde(default)]
    pose_unit: Option<Unit>,
}

impl OnlineCalibrator {
    /// A calibrator for `config`; errors on invalid parameters or `Truth` without a truth.
    pub fn new(config: OnlineConfig) -> Result<Self> {
        config.validate()?;
        Ok(Self {
            selector: Selector::new(config.selection, config.setup, config.params)?,
            config,
            poses: 0,
            calibrations: 0,
            refused: 0,
            window: VecDeque::with_capacity(OPTIMAL_WINDOW + 1),
            optimal_results: 0,
            last_x: None,
            last_calibration: 0,
            previous: None,
            largest_step: 0.0,
            unit: config.unit,
            tracker: (config.estimator == Estimator::Accumulate)
                .then(|| Tracker::new(config.setup, config.tracking).with_written(config.written)),
            step: Step::default(),
            readings: (config.estimator != Estimator::Accumulate)
                .then(|| StreamReadings::new(config.setup)),
            misread: None,
            pixels: None,
            first_robot: None,
            names: Names::default(),
            held_out_told: Thinning::default(),
            unit_told: false,
            pose_unit: None,
        })
    }

    /// A calibrator on the pixels of `camera`: each frame (a robot pose and the target's
    /// detections, pushed as a [`Record`]) is kept, and X solved by the batch
    /// calibration on the pixels ([`calibrate`](crate::calibrate()) with [`Input::Pixels`](crate::Input::Pixels), with its
    /// checks) at 16, 32, 64, … frames and at the end, in the accumulating estimator's report
    /// with the fit in `estimate.reprojection` (`handeye online --intrinsics`). `config` gives
    /// the setup, `tracking.point` and the unit; the paper's estimator, the optimal method and
    /// errors against the truth are not offered on the pixels (an error names which).
    ///
    /// Errors: [`Error::InvalidParameter`] for those, for unusable intrinsics, and for settings
    /// out of range.
    pub fn on_pixels(camera: Intrinsics, config: OnlineConfig) -> Result<Self> {
        let given = [
            (
                "the paper's estimator",
                config.estimator == Estimator::Paper,
                "the estimate on the pixels is the accumulating estimator's (the default)",
            ),
            (
                "the optimal method",
                config.optimal,
                "it refines the paper's calibrations, which do not run on the pixels",
            ),
            (
                "errors against the truth",
                config.error_source == ErrorSource::Truth || config.truth.is_some(),
                "each report's uncertainty is its own measure",
            ),
        ];
        if let Some((what, _, why)) = given.iter().find(|(_, given, _)| *given) {
            return Err(Error::InvalidParameter {
                name: "intrinsics",
                message: format!("{what} is not offered on the pixels (yet): {why}"),
            });
        }
        let options = Options {
            problem: Problem::HandEye(crate::solve::Method::Reprojection),
            pairing: crate::model::motion::Pairing::All,
            point: config.tracking.point,
            ..Options::default()
        };
        let pixels = OnlinePixels::new(camera, config.setup, options)?;
        // No length threshold applies on the pixels: the unit is the poses' (metres or
        // millimetres when given, else told by the first report).
        let unit = match config.unit {
            Unit::AsGiven => Unit::Auto,
            unit => unit,
        };
        Ok(Self {
            tracker: None,
            readings: None,
            pixels: Some(pixels),
            unit,
            ..Self::new(OnlineConfig {
                estimator: Estimator::Accumulate,
                ..config
            })?
        })
    }

    /// Whether this calibrator is on the pixels ([`OnlineCalibrator::on_pixels`]), whose state
    /// (the frames) is not saved with serde.
    pub fn on_the_pixels(&self) -> bool {
        self.pixels.is_some()
    }

    /// Pushes one frame on the pixels, named `name` (`file:line`, for the report's figures and
    /// outlier lists); returns the estimate when one is solved at this frame (16, 32, 64, …
    /// frames), also as the step's report.
    ///
    /// Errors: [`Error::InvalidParameter`] on a calibrator of pose pairs.
    fn push_frame(&mut self, frame: Frame, name: String) -> Result<Option<Report>> {
        let Some(pixels) = self.pixels.as_mut() else {
            return Err(Error::InvalidParameter {
                name: "intrinsics",
                message: "frames with detections are calibrated on the pixels: give the camera's intrinsics (`OnlineCalibrator::on_pixels`)".into(),
            });
        };
        self.first_robot.get_or_insert(frame.base_from_gripper);
        let report = pixels.push(frame, name);
        self.poses += 1;
        if let Some(r) = &report {
            self.unit_from(r);
        }
        self.step = Step {
            pose: self.poses,
            report: report.clone(),
            ..Step::default()
        };
        Ok(report)
    }

    /// On the pixels, while the unit is not given: the one the first robot pose and a report's
    /// target pose tell.
    fn unit_from(&mut self, report: &Report) {
        if self.unit != Unit::Auto {
            return;
        }
        let pose = PosePair {
            base_from_gripper: self.first_robot.unwrap_or_else(Transform::identity),
            camera_from_target: report.estimate.target,
        };
        self.unit = Unit::infer(&pose).unwrap_or(Unit::Auto);
    }

    /// The cautions of the last estimate on the pixels (its verdict `questionable` when any);
    /// on pose pairs the reports carry their own (`Report::warnings`).
    fn warnings(&self) -> &[crate::model::warning::Warning] {
        self.pixels.as_ref().map_or(&[], |p| p.warnings())
    }

    /// The estimate to use now: the last report since the last change of X, from readings not
    /// found misread since (on the pixels: the last estimate solved); `None` with the paper's
    /// estimator.
    pub fn last_report(&self) -> Option<Report> {
        match &self.pixels {
            Some(p) => p.last_report(),
            None => self.tracker.as_ref()?.last_report(),
        }
    }

    /// The length unit in force: the configured one, or the one inferred from the poses (`Auto`
    /// while none fitted a unit; `params.d_max` is then in force).
    pub fn unit(&self) -> Unit {
        self.unit
    }

    /// `d_max` in force, in the input's unit.
    fn d_max(&self) -> f64 {
        self.unit.d_max().unwrap_or(self.config.params.d_max)
    }

    /// The configuration.
    pub fn config(&self) -> &OnlineConfig {
        &self.config
    }

    /// Poses pushed so far.
    pub fn poses(&self) -> usize {
        self.poses
    }

    /// Calibrations made so far.
    pub fn calibrations(&self) -> usize {
        self.calibrations
    }

    /// What the run did, for a face's summary at the end (or at any point): counts, the
    /// paper's last X and thresholds, why its selection made no calibration lately, the
    /// accumulating estimator's counts, the length unit.
    pub fn summary(&self) -> Summary {
        Summary {
            poses: self.poses,
            calibrations: self.calibrations,
            refused: self.refused,
            last_x: self.last_x,
            thresholds: self.selector.thresholds(),
            stuck: self.stuck_at_end(),
            tracked: self.tracker.as_ref().map(|t| Tracked {
                repeats: t.repeats(),
                held_out: t.held_out(),
                changes: t.changes(),
            }),
            unit: self.unit,
            d_max: self.d_max(),
            length_unit: match self.unit {
                Unit::Metre | Unit::Millimetre => Some(self.unit),
                Unit::Auto | Unit::AsGiven => self.pose_unit,
            },
        }
    }

    /// Poses pushed since the last calibration (all of them before the first).
    fn poses_since_calibration(&self) -> usize {
        self.poses - self.last_calibration
    }

    /// With the paper's estimator, why its selection has made no calibration for a while, told
    /// at 200, 400, 800, … poses without one (a stuck stream is told so at growing intervals, not
    /// every 200 poses): the words when the last push reached such a count, else `None`. Every
    /// face tells them then.
    fn stuck(&self) -> Option<String> {
        if self.tracker.is_some() || self.pixels.is_some() {
            return None;
        }
        let since = self.poses_since_calibration();
        let due = since.is_multiple_of(QUIET_POSES) && (since / QUIET_POSES).is_power_of_two();
        due.then(|| self.quiet(QUIET_POSES)).flatten()
    }

    /// At the end of a stream, with the paper's estimator: why no calibration came (at all, or
    /// in the last 200 poses), in words; `None` otherwise.
    fn stuck_at_end(&self) -> Option<String> {
        if self.tracker.is_some() || self.pixels.is_some() {
            return None;
        }
        self.quiet(if self.calibrations == 0 {
            1
        } else {
            QUIET_POSES
        })
    }

    /// Why the paper's selection has made no calibration for a while, in words: `None` when a
    /// calibration came within the last `poses` poses (or fewer were pushed).
    fn quiet(&self, poses: usize) -> Option<String> {
        let since = self.poses_since_calibration();
        if since < poses.max(1) {
            return None;
        }
        let largest = self.largest_step.to_degrees();
        let what = if self.calibrations == 0 {
            format!("no calibration in {} poses", self.poses)
        } else {
            format!("no calibration in the last {since} poses")
        };
        Some(match self.selector.thresholds() {
            Some(t) => format!(
                "{what}: the selection needs motions turning β₀ = {:.2}° or more, with axes at least {:.1}° apart and translations within d₀ = {:.4}; the largest turn between consecutive poses was {largest:.2}°",
                t.beta.to_degrees(),
                t.sin_alpha.clamp(-1.0, 1.0).asin().to_degrees(),
                t.d
            ),
            None => format!(
                "{what}: the largest turn between consecutive poses was {largest:.2}° (the selection needs rotations about different axes)"
            ),
        })
    }

    /// Pushes the next record (a pose pair, or on the pixels a frame with detections); returns
    /// everything it made happen ([`Outputs`]): the paper's calibrations (usually none, at most
    /// one except at the end of the fixed method's initial window), or the accumulating
    /// estimator's held-out poses, change and report, or on the pixels an estimate at 16, 32, 64,
    /// … frames; the length unit once known; a misread or a stuck selection found. The poses
    /// cited are named as the record's input names them ([`Name`]).
    ///
    /// With `Unit::Auto`, the first pose whose size fits a unit fixes it ([`Unit::infer`]);
    /// until then `params.d_max` is in force ([`OnlineCalibrator::unit`] tells which). The
    /// record's joint angles (radians, every pose the same joints) order the accumulating
    /// estimator's systematic-error test, which names the joint whose angle the residual follows;
    /// the paper's estimator does not use them.
    ///
    /// Errors, the state left untouched: a pose with a non-finite entry
    /// ([`Error::InvalidTransform`]; a parse error at its line when the record is named by one);
    /// a joint angle that is not finite; a pose on a calibrator on the pixels, a frame on one of
    /// pose pairs ([`Error::InvalidParameter`]). And the accumulating estimator's refusal of its
    /// priors or of the robot's table, told when its data show it.
    pub fn push<'a>(&mut self, record: impl Into<Record<'a>>) -> Result<Outputs> {
        let Record {
            observed,
            name,
            joints,
        } = record.into();
        let mut out = Outputs::default();
        let pose = match observed {
            Observed::Frame(frame) => {
                let number = self.poses + 1;
                out.report = self.push_frame(*frame, Names::now(name, number, "record"))?;
                return Ok(out);
            }
            Observed::Pose(pose) => pose,
        };
        let events = match self.push_pose(pose, joints) {
            Err(e @ Error::InvalidTransform { .. }) => {
                return Err(match name {
                    Name::Line { source, line } | Name::Stamp { source, line, .. } => {
                        Error::Parse {
                            file: source.to_string(),
                            line,
                            field: "-".to_string(),
                            message: e.to_string(),
                            remedy: None,
                        }
                    }
                    Name::Numbered | Name::Text(_) => e,
                });
            }
            result => result?,
        };
        self.names.keep(self.poses, name);
        if !self.unit_told {
            out.unit = self.unit_told(pose);
        }
        out.misread = self.misread();
        if self.tracker.is_some() {
            let step = &self.step;
            for (pose, why) in step.held_out_poses() {
                out.held_out.push(HeldOutPose {
                    pose,
                    name: self.names.of(pose, "pose"),
                    why: *why,
                    tell: self.held_out_told.tell(),
                });
            }
            out.change = step.change.map(|change| ChangeFound {
                change,
                from: self.names.of(change.at, "pose"),
                confirmed: self.names.of(change.confirmed, "pose"),
            });
            out.report = step.report.clone();
        }
        out.events = events;
        out.stuck = self.stuck();
        Ok(out)
    }

    /// The length unit, the first time it is known (or, at the first pose, not told by it).
    fn unit_told(&mut self, pose: &PosePair) -> Option<UnitTold> {
        let d_max = self.d_max();
        match self.unit {
            Unit::Auto => (self.poses == 1).then(|| UnitTold::Unknown {
                sizes: [
                    pose.base_from_gripper.translation.vector.norm(),
                    pose.camera_from_target.translation.vector.norm(),
                ],
                d_max,
            }),
            unit => {
                self.unit_told = true;
                Some(UnitTold::Known {
                    unit,
                    inferred_at: (self.config.unit == Unit::Auto).then_some(self.poses),
                    d_max,
                })
            }
        }
    }

    /// Pushes a pose pair, with the joint angles at it if given: the paper's calibrations it
    /// completes, or the accumulating estimator's step (`OnlineCalibrator::step`).
    fn push_pose(&mut self, pose: &PosePair, joints: Option<&[f64]>) -> Result<Vec<Event>> {
        if let Some(joints) = joints
            && let Some(k) = joints.iter().position(|q| !q.is_finite())
        {
            return Err(Error::InvalidParameter {
                name: "joints",
                message: format!(
                    "joint {} is {}: every joint angle must be a finite number of radians",
                    k + 1,
                    joints[k]
                ),
            });
        }
        if self.pixels.is_some() {
            return Err(Error::InvalidParameter {
                name: "intrinsics",
                message: "this calibrator is on the pixels (the camera's intrinsics given): push frames with detections".into(),
            });
        }
        check_finite(pose)?;
        if self.poses == 0 || self.unit == Unit::Auto {
            self.fix_unit(pose);
        }
        self.poses += 1;
        if self.pose_unit.is_none() {
            self.pose_unit = Unit::infer(pose);
        }
        let hand = self.config.setup.hand_pose(&pose.base_from_gripper);
        if let Some(previous) = self.previous {
            let step =
                crate::model::pose::rotation_angle_between(&previous.rotation, &hand.rotation);
            self.largest_step = self.largest_step.max(step);
        }
        self.previous = Some(hand);
        // The accumulating estimator is its own entry: the paper's selection does not run
        // beside it.
        if let Some(tracker) = &mut self.tracker {
            self.step = match joints {
                Some(q) => tracker.push_with_joints(pose, q),
                None => tracker.push(pose),
            };
            return match tracker.refusal() {
                Some(e) => Err(e),
                None => Ok(Vec::new()),
            };
        }
        if let Some(found) = self.readings.as_mut().and_then(|r| r.push(pose)) {
            self.misread = Some(found);
        }
        let selections = self.selector.offer(self.poses, pose);
        Ok(selections
            .into_iter()
            .filter_map(|s| self.calibrate(&s))
            .collect())
    }

    /// Step 14 of the Main Algorithm: Andreff on (A', A''), the errors, the threshold update.
    fn calibrate(&mut self, selected: &Selected) -> Option<Event> {
        let started = Instant::now();
        let pair = [selected.first, selected.second];
        let Ok(calibration) = andreff(&pair) else {
            self.refused += 1;
            return None;
        };
        let x = calibration.x;
        let rms = self.errors(&pair, &x);
        self.selector.record(rms.rms_r, rms.rms_t);
        let seconds = started.elapsed().as_secs_f64();
        self.calibrations += 1;
        self.last_x = Some(x);
        self.last_calibration = self.poses;
        self.largest_step = 0.0;
        let optimal = self
            .config
            .optimal
            .then(|| self.optimal(selected))
            .flatten();
        Some(Event {
            calibration: self.calibrations,
            poses: selected.poses,
            thresholds: selected.thresholds,
            x,
            rms,
            conditioning: calibration.conditioning,
            seconds,
            optimal,
            time_offset_s: None,
        })
    }

    /// Fixes the unit from the pose when it is `Auto`, and sets the selector's `d_max` from it.
    fn fix_unit(&mut self, pose: &PosePair) {
        if self.unit == Unit::Auto {
            self.unit = Unit::infer(pose).unwrap_or(Unit::Auto);
        }
        if let Some(d_max) = self.unit.d_max() {
            self.selector.set_d_max(d_max);
        }
    }

    /// What the accumulating estimator did with the last pose: held it out, confirmed a change,
    /// reported an estimate (on the pixels: the estimate solved at the last frame, if one was).
    /// `None` with the paper's estimator.
    pub(crate) fn step(&self) -> Option<&Step> {
        (self.tracker.is_some() || self.pixels.is_some()).then_some(&self.step)
    }

    /// The accumulating estimator's report at the end of the stream (the current estimate, if it
    /// is determined and was not just reported); on the pixels, the calibration on the pixels of
    /// every frame pushed (or of the frames kept, beyond 256), reported with `reason` `end`. With
    /// the paper's estimator, the readings check runs now on a stream shorter than its sample
    /// ([`Outputs::misread`]) and there is no report.
    ///
    /// Errors: the priors refused (a prior in another length unit than the poses, told only now
    /// on a short stream); on the pixels, the calibration's refusal (too few frames, degenerate
    /// motions, robot poses that fit the pixels far better inverted, a fit far above detection
    /// noise).
    ///
    /// The outputs carry the report, what the readings check found, and on the pixels the
    /// cautions of the end's estimate.
    pub fn finish(&mut self) -> Result<Outputs> {
        if let Some(found) = self.readings.as_mut().and_then(StreamReadings::finish) {
            self.misread = Some(found);
        }
        let report = self.final_report()?;
        Ok(Outputs {
            misread: self.misread(),
            report,
            warnings: self.warnings().to_vec(),
            ..Outputs::default()
        })
    }

    /// The report of [`OnlineCalibrator::finish`].
    fn final_report(&mut self) -> Result<Option<Report>> {
        if let Some(pixels) = self.pixels.as_mut() {
            let report = pixels.finish()?;
            self.unit_from(&report);
            return Ok(Some(report));
        }
        let Some(tracker) = self.tracker.as_mut() else {
            return Ok(None);
        };
        let report = tracker.finish();
        match tracker.refusal() {
            Some(e) => Err(e),
            None => Ok(report),
        }
    }

    /// What the readings check of the first poses found, once (then `None`): with the paper's
    /// estimator, which has no checks of its own, the check `calibrate` makes on a recording runs
    /// on the first 64 poses (or at [`OnlineCalibrator::finish`] on a stream of 16 to 63);
    /// its calibrations are then from poses read wrongly, or about one axis. The
    /// accumulating estimator checks its readings itself and refuses.
    fn misread(&mut self) -> Option<StreamReading> {
        self.misread.take()
    }

    /// The same calibrator with priors on X's translation for a low-DOF robot (the accumulating
    /// estimator solves the rest from the data); refused with the paper's estimator, which has no
    /// low-DOF solve.
    /// Before the first pose.
    pub fn with_priors(mut self, priors: &[crate::model::prior::Prior]) -> Result<Self> {
        if priors.is_empty() {
            return Ok(self);
        }
        if self.pixels.is_some() {
            return Err(Error::InvalidParameter {
                name: "prior",
                message: "a prior is not offered on the pixels (yet)".into(),
            });
        }
        let Some(tracker) = self.tracker.take() else {
            return Err(Error::InvalidParameter {
                name: "prior",
                message: "a prior needs the accumulating estimator (`--estimator accumulate`, the default): the paper's estimator solves X from two motions at a time and has no low-DOF solve".into(),
            });
        };
        self.tracker = Some(tracker.with_priors(priors)?);
        Ok(self)
    }

    /// The same calibrator with the robot's DH table (`--robot-model`): the accumulating
    /// estimator's systematic-error test gains the table's statistic, as `calibrate`'s
    /// (`track::Tracker::with_robot_model`; push the poses with their joint angles). Refused with the
    /// paper's estimator, which has no systematic-error test, and on the pixels. Before the first
    /// pose.
    pub fn with_robot_model(
        mut self,
        model: Option<crate::model::kinematics::Kinematics>,
    ) -> Result<Self> {
        let Some(model) = model else {
            return Ok(self);
        };
        let refuse = |message: &str| Error::InvalidParameter {
            name: "robot-model",
            message: message.into(),
        };
        if self.pixels.is_some() {
            return Err(refuse("a robot model is not offered on the pixels (yet)"));
        }
        let Some(tracker) = self.tracker.take() else {
            return Err(refuse(
                "the robot's table needs the accumulating estimator (`--estimator accumulate`, the default): the paper's estimator has no systematic-error test",
            ));
        };
        self.tracker = Some(tracker.with_robot_model(Some(model)));
        Ok(self)
    }

    /// The accumulating estimator's current estimate, determined or not; `None` before it has
    /// one or with the paper's estimator.
    pub fn accumulated(&self) -> Option<TrackEstimate> {
        self.tracker.as_ref()?.estimate()
    }

    /// Why the accumulating estimator has nothing to report now; `None` when it has. On the
    /// pixels: why the last solve made no estimate, or that none was due yet.
    pub fn pending(&self) -> Option<Pending> {
        if let Some(pixels) = &self.pixels {
            return match (pixels.last_report(), pixels.refused()) {
                (_, Some(why)) => Some(Pending::RefusedOnPixels {
                    reason: why.to_string(),
                }),
                (None, None) => Some(Pending::FewFrames {
                    frames: pixels.frames(),
                }),
                (Some(_), None) => None,
            };
        }
        let tracker = self.tracker.as_ref()?;
        let why = tracker.pending()?;
        Some(if tracker.changes() > 0 && why.of_motions() {
            Pending::SinceChange {
                pending: Box::new(why),
            }
        } else {
            why
        })
    }

    /// rmsR and rmsT of `x` from the configured source.
    fn errors(&self, pair: &[MotionPair; 2], x: &Transform) -> Rms {
        match (self.config.error_source, self.config.truth) {
            (ErrorSource::Truth, Some(truth)) => {
                let e = errors_against_truth(x, &truth);
                Rms {
                    rms_r: e.rms_r(),
                    rms_t: e.rms_t(),
                }
            }
            _ => residual_rms(pair, x),
        }
    }

    /// Sec. 4.5: once five motions have been selected (the first A' and every accepted A''),
    /// refine over the last five, started from Andreff on them.
    fn optimal(&mut self, selected: &Selected) -> Option<OptimalEstimate> {
        let [a, i, j] = selected.poses;
        if self.window.is_empty() {
            self.window.push_back(([a, i], selected.first));
        }
        self.window.push_back(([i, j], selected.second));
        while self.window.len() > OPTIMAL_WINDOW {
            self.window.pop_front();
        }
        if self.window.len() < OPTIMAL_WINDOW {
            return None;
        }
        let started = Instant::now();
        let mut motions = [selected.first; OPTIMAL_WINDOW];
        let mut numbers = [[0; 2]; OPTIMAL_WINDOW];
        for (k, (n, m)) in self.window.iter().enumerate() {
            motions[k] = *m;
            numbers[k] = *n;
        }
        let start = andreff(&motions).ok()?;
        let refined = refine_from(&motions, &start.x, &RefineOptions::default()).ok()?;
        self.optimal_results += 1;
        Some(OptimalEstimate {
            number: self.optimal_results,
            x: refined.calibration.x,
            motions: numbers,
            seconds: started.elapsed().as_secs_f64(),
        })
    }
}

/// The serde form of a calibrator on the pixels: refused (its frames are not saved).
fn refuse_to_save<S: serde::Serializer>(
    _: &Option<OnlinePixels>,
    _: S,
) -> std::result::Result<S::Ok, S::Error> {
    Err(serde::ser::Error::custom(
        "the state of a calibrator on the pixels is not saved (its frames are not): push the records again",
    ))
}

/// Refuses a pose pair with a NaN or infinite entry.
fn check_finite(pose: &PosePair) -> Result<()> {
    let finite = |t: &Transform| {
        t.translation
            .vector
            .iter()
            .chain(t.rotation.matrix().iter())
            .all(|v| v.is_finite())
    };
    for (what, t) in [
        ("base_from_gripper", &pose.base_from_gripper),
        ("camera_from_target", &pose.camera_from_target),
    ] {
        if !finite(t) {
            return Err(Error::InvalidTransform {
                what: what.to_string(),
                problem: crate::model::error::TransformProblem::NotFinite,
            });
        }
    }
    Ok(())
}

/// Convenience for whole series: pushes every pose and collects all events.
pub fn run_series(config: OnlineConfig, poses: &[PosePair]) -> Result<Vec<Event>> {
    let mut calibrator = OnlineCalibrator::new(config)?;
    let mut events = Vec::new();
    for p in poses {
        events.extend(calibrator.push_pose(p, None)?);
    }
    Ok(events)
}
