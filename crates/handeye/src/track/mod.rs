//! The accumulating estimator on a live stream: every pose gated, the estimate watched for a change
//! of X or of the target, and reported on its own schedule with the reason when there is none.
//!
//! One [`Tracker`] takes the poses one at a time ([`Tracker::push`]). Each pose passes two tests
//! before it enters the all-pairs sums of [`crate::solve::accumulate::PoseAccumulator`]:
//!
//! 1. **The screw gate** (X-free, from the second pose on): the median screw-invariant gaps of the
//!    pose against up to eight recent accepted poses (`consistency::screw_gaps`, the test
//!    of batch `--reject-outliers`) above `max(outlier_deg, 6 × typical)` in angle, or 6 × typical
//!    in pitch, hold it out: a flipped or random target pose, a gross error, a bad stamp. Eight
//!    held out in a row mean the partners are stale (the rig changed): they are dropped.
//! 2. **The residual gate**, once the estimate is mature: the pose's own fixed frame
//!    Y_k = H_k X C_k against the accumulated Y, normalised by the scatter of all accepted poses
//!    under the same X ([`crate::solve::accumulate::PoseAccumulator::residual_scatter`], O(1)): the larger of rotation and
//!    translation in units of their RMS. Above `gate` the pose is held out.
//!
//! **Change of X (or of the target).** A pose above `elevated` opens a *challenger*: a second
//! accumulator fed with every pose from then on. It is dismissed when fewer than half of its poses
//! stay elevated under the incumbent after `confirm_poses` (a burst of bad frames, a region where
//! the robot's model is worse), and confirmed when at least 60% are elevated, its own estimate is
//! determined, and it explains its poses at the incumbent's noise level. Then it replaces the
//! incumbent (the restart keeps the poses since the change) and the change is reported with the
//! pose where it began. A systematic error that only shows in one region of the workspace cannot
//! confirm: the challenger's data are local, so its estimate is not determined before the robot
//! leaves the region and the incumbent fits again.
//!
//! **Reporting.** An estimate is reported only when it is determined (split-half uncertainty below
//! `max_rotation_deg` and `max_translation` × the scene's size): first when it becomes so, then
//! every `every` poses, whenever both uncertainties have shrunk to `shrink` of the last reported
//! ones, and at the end of the stream ([`Tracker::finish`]). Until then [`Tracker::pending`] says
//! why there is none.

mod events;
mod segment;
mod systematic;
pub use systematic::test_step;

use std::collections::VecDeque;

use serde::{Deserialize, Serialize};

use crate::check::outliers::{OUTLIER_FACTOR, median_in, pose_outliers, screw_gaps};
use crate::check::precision::resolution;
use crate::check::readings::check_readings;
use crate::check::uncertainty::{
    UNDETERMINED_ROTATION_DEG, UNDETERMINED_TRANSLATION, point_sigma, summarise, warn_weak,
};
use crate::model::findings::Reading;
use crate::model::findings::Written;
use crate::model::motion::{PosePair, Setup};
use crate::model::pose::{Transform, axis_angle, rotation_angle_between};
use crate::model::station::{self, SAME_STATION};

pub use events::target_frame;
pub use events::{
    Change, HeldOut, Pending, PixelFit, Reason, Report, RobotWorldPair, Step, TrackEstimate,
    TrackPrior,
};
use segment::{Segment, Snapshot};
use systematic::{JointRing, Watch};

/// Settings of the tracker; `Default` gives the values on each field.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TrackOptions {
    /// Report the estimate at least every this many poses. Default 100.
    pub every: usize,
    /// Also report when both uncertainties have shrunk to this fraction of the last reported ones.
    /// Default 0.5.
    pub shrink: f64,
    /// An estimate is reported only when its rotation uncertainty is at most this, degrees.
    /// Default 2.
    pub max_rotation_deg: f64,
    /// … and its translation uncertainty at most this fraction of the scene's size (the RMS spread
    /// of the hand positions; not ‖t_x‖, which a wrong estimate would inflate), or what
    /// `max_rotation_deg` moves at the camera's viewing distance if that is more. Default 0.1.
    pub max_translation: f64,
    /// A mature estimate holds out a pose whose residual exceeds this many RMS. Default 5.
    pub gate: f64,
    /// A residual above this many RMS opens or feeds the case for a change. Default 3.
    pub elevated: f64,
    /// Poses a challenger needs before it is judged. Default 10.
    pub confirm_poses: usize,
    /// Poses the incumbent needs before new poses are tested against it. Default 30.
    pub mature_poses: usize,
    /// Least screw-invariant angle gap that holds a pose out, degrees (`--outlier-deg`).
    /// Default 3.
    pub outlier_deg: f64,
    /// The point (camera frame, input unit) whose error through X each report's
    /// `uncertainty.at_point` gives (`--point`). Default `None`: the mean target position seen.
    #[serde(default)]
    pub point: Option<[f64; 3]>,
}

impl Default for TrackOptions {
    fn default() -> Self {
        Self {
            every: 100,
            shrink: 0.5,
            max_rotation_deg: 2.0,
            max_translation: 0.1,
            gate: 5.0,
            elevated: 3.0,
            confirm_poses: 10,
            mature_poses: 30,
            outlier_deg: 3.0,
            point: None,
        }
    }
}

impl TrackOptions {
    /// Checks the ranges of the settings a face exposes and the others: `every` at least 1,
    /// `shrink` and the gates finite and above 0, `outlier_deg` in (0, 180], a finite `point`.
    pub fn validate(&self) -> crate::model::error::Result<()> {
        let bad = |name: &'static str, message: String| {
            Err(crate::model::error::Error::InvalidParameter { name, message })
        };
        if self.every < 1 {
            return bad("every", "must be at least 1 (poses between reports)".into());
        }
        for (name, v) in [
            ("shrink", self.shrink),
            ("max_rotation_deg", self.max_rotation_deg),
            ("max_translation", self.max_translation),
            ("gate", self.gate),
            ("elevated", self.elevated),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return bad(name, format!("must be a finite number above 0, got {v}"));
            }
        }
        if !(self.outlier_deg > 0.0 && self.outlier_deg <= 180.0) {
            return bad(
                "outlier_deg",
                format!("must be in (0, 180] degrees, got {}", self.outlier_deg),
            );
        }
        if self.point.is_some_and(|p| p.iter().any(|v| !v.is_finite())) {
            return bad("point", "must be three finite numbers".into());
        }
        Ok(())
    }
}

/// Recent accepted poses the screw gate compares a new pose with.
const PARTNER_RING: usize = 32;
/// Of those, every this-many-th is a partner (up to eight motions per pose).
const PARTNER_STRIDE: usize = 4;
/// Screw gaps kept to learn their typical size.
const GAP_RING: usize = 64;
/// Held out in a row by the screw gate before its partners are taken to be stale.
const STALE_RUN: usize = 8;
/// Incumbent poses below which the estimate is refreshed at every pose (then every 10th).
const REFRESH_ALWAYS: usize = 200;
/// The first accepted poses are kept and judged again together by the batch test when this many
/// have come, the gate having learned its typical gaps by then (it lets the very first poses
/// through untested): at 16, 64 and 256 poses, each time over all of them.
const WARMUP: [usize; 3] = [16, 64, 256];
/// Poses kept for checking the readings again as the stream goes on (the first ones may not tell
/// a misread: a robot standing still, turning about one axis, or turning too little to tell an
/// inverted pose): a sample of every pose pushed, thinned by half, its stride doubled, each time
/// it fills, and checked then and at the end.
const READINGS_SAMPLE: usize = 128;

/// Every stride-th pose pushed, for [`Tracker::sample_readings`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct ReadingsSample {
    poses: Vec<PosePair>,
    stride: usize,
    seen: usize,
}

impl Default for ReadingsSample {
    fn default() -> Self {
        Self {
            poses: Vec::with_capacity(READINGS_SAMPLE),
            stride: 1,
            seen: 0,
        }
    }
}
/// A challenger unconfirmed after this many times `confirm_poses` poses is dropped.
const CHALLENGER_LIFE: usize = 10;

/// Saved states from before `readings_judged` had their readings judged by the rule then.
fn judged_before() -> bool {
    true
}

/// The case for a change: a second segment since the first elevated pose.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct Challenger {
    segment: Segment,
    current: Option<Snapshot>,
    poses: usize,
    elevated: usize,
    /// Elevated poses kept out of the incumbent meanwhile, with their numbers and statistics.
    pending: Vec<(usize, PosePair, f64)>,
    /// The sample of its poses for the systematic-error test, kept on when it is confirmed.
    #[serde(default)]
    watch: Watch,
}

/// The accumulating estimator on a stream (see the module documentation).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Tracker {
    options: TrackOptions,
    setup: Setup,
    poses: usize,
    incumbent: Segment,
    current: Option<Snapshot>,
    challenger: Option<Challenger>,
    partners: VecDeque<PosePair>,
    gaps: VecDeque<[f64; 2]>,
    /// The first accepted poses with their numbers, until they are judged together.
    warmup: Option<Vec<(usize, PosePair)>>,
    /// What the last check of the readings on them found: a reading that fits far better (and
    /// whether the poses may be the other setup's), and whether X and Y have sizes the setup makes
    /// unlikely (both poses inverted fit as well).
    misread: Option<(Reading, bool)>,
    implausible: bool,
    /// Whether a check of the readings could judge them (the gripper turned, about more than one
    /// axis): nothing is reported before (a saved state from before this field was judged).
    #[serde(default = "judged_before")]
    readings_judged: bool,
    /// A reading that fits about as well as the as-given one, while the readings are not judged
    /// ([`crate::check::readings::ReadingCheck::alike`]).
    #[serde(default)]
    alike: Option<Reading>,
    /// A thinned sample of every pose pushed, judged again each time it fills and at the end.
    #[serde(default)]
    sample: ReadingsSample,
    /// The directions in which the input writes its poses.
    #[serde(default)]
    written: Written,
    /// The last report of the current segment (none after a change, or once the readings are
    /// found misread).
    #[serde(default)]
    last: Option<Report>,
    /// The poses held out in a row by the screw gate, with their numbers.
    screw_run: Vec<(usize, PosePair)>,
    /// Pose number and uncertainties of the last report of this segment.
    last_report: Option<(usize, f64, f64)>,
    reports: usize,
    held_out: usize,
    changes: usize,
    /// The priors on X's translation for a low-DOF robot ([`Tracker::with_priors`]).
    #[serde(default)]
    priors: Option<TrackPriors>,
    /// The incumbent's sample of accepted poses and its last systematic-error test (issue 29).
    #[serde(default)]
    watch: Watch,
    /// The joint angles of the recent poses, where they were given ([`Tracker::push_with_joints`]).
    #[serde(default)]
    joints: JointRing,
    /// The robot's DH table ([`Tracker::with_robot_model`]), and why it was refused once the
    /// poses showed it is not the robot's.
    #[serde(default)]
    robot_model: Option<crate::model::kinematics::Kinematics>,
    #[serde(default)]
    robot_model_refused: Option<String>,
    /// The robot pose of the last pose pushed: a pose at it is one more image of that pose.
    #[serde(default)]
    previous: Option<Transform>,
    /// Poses pushed at the robot pose of the pose before them ([`Step::repeat`]).
    #[serde(default)]
    repeats: usize,
}

/// A tracker's priors: as given, and in the poses' length unit once the first poses tell it (or
/// why they were refused).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct TrackPriors {
    given: Vec<crate::model::prior::Prior>,
    resolved: Option<Vec<crate::model::prior::Prior>>,
    refused: Option<String>,
}

/// Poses pushed after which the priors' unit is told from them (the median size of that many
/// poses, as the batch tells it from all of them); fewer at the end of a shorter stream.
const PRIOR_UNIT_POSES: usize = WARMUP[0];

impl Tracker {
    /// A tracker for poses read in `setup`.
    pub fn new(setup: Setup, options: TrackOptions) -> Self {
        Self {
            options,
            setup,
            poses: 0,
            incumbent: Segment::new(setup, 1, None),
            current: None,
            challenger: None,
            partners: VecDeque::with_capacity(PARTNER_RING),
            gaps: VecDeque::with_capacity(GAP_RING),
            warmup: Some(Vec::new()),
            misread: None,
            implausible: false,
            readings_judged: false,
            alike: None,
            sample: ReadingsSample::default(),
            written: Written::NAMED,
            last: None,
            screw_run: Vec::with_capacity(STALE_RUN),
            last_report: None,
            reports: 0,
            held_out: 0,
            changes: 0,
            priors: None,
            watch: Watch::default(),
            joints: JointRing::default(),
            robot_model: None,
            robot_model_refused: None,
            previous: None,
            repeats: 0,
        }
    }

    /// The same with priors on X's translation (`--prior tz=…`), for a low-DOF robot (a SCARA,
    /// a 4-axis arm): when every rotation of a segment is about one axis and a prior covers the
    /// component along it, X is the low-DOF solve over every pair of the segment's poses
    /// ([`crate::solve::low_dof_accumulate`], O(1) per pose), the prior's sigma added to its
    /// translation uncertainty; otherwise the priors change nothing. A prior that names its unit
    /// (`tz=0.12m`) is converted, and one without a unit refused when it is of another unit than
    /// the poses, as the batch does, on the first 16 poses ([`Tracker::refusal`]). Before the first
    /// pose; refuses two priors on one component and bad numbers.
    pub fn with_priors(
        mut self,
        priors: &[crate::model::prior::Prior],
    ) -> crate::model::error::Result<Self> {
        crate::model::prior::check_priors(priors)?;
        if priors.is_empty() {
            return Ok(self);
        }
        self.priors = Some(TrackPriors {
            given: priors.to_vec(),
            resolved: None,
            refused: None,
        });
        self.incumbent = Segment::new(self.setup, 1, self.segment_priors());
        Ok(self)
    }

    /// Why the priors were refused (a prior in another length unit than the poses): the tracker
    /// then gives no low-DOF estimate, and a face stops with this error.
    pub fn refusal(&self) -> Option<crate::model::error::Error> {
        if let Some(message) = self.priors.as_ref().and_then(|p| p.refused.clone()) {
            return Some(crate::model::error::Error::InvalidParameter {
                name: "prior",
                message,
            });
        }
        let message = self.robot_model_refused.clone()?;
        Some(crate::model::error::Error::InvalidParameter {
            name: "robot-model",
            message,
        })
    }

    /// The robot's DH table (`online --robot-model`): the systematic-error test then has the
    /// table's statistic as `calibrate --robot-model` (`check::identification`), with the joint
    /// angles of [`Tracker::push_with_joints`]. Its first test (at 12 accepted poses, or the end)
    /// checks that the table is the robot's on the poses so far; a table that is not, or poses
    /// without joint angles, make [`Tracker::refusal`] the error that says why.
    pub fn with_robot_model(mut self, model: Option<crate::model::kinematics::Kinematics>) -> Self {
        self.robot_model = model;
        self
    }

    /// What a new segment keeps of the priors (see [`Segment::new`]).
    fn segment_priors(&self) -> Option<Option<Vec<crate::model::prior::Prior>>> {
        self.priors.as_ref().map(|p| p.resolved.clone())
    }

    /// Tells the priors' unit from the poses sampled so far, once there are
    /// [`PRIOR_UNIT_POSES`] of them (at the end, three), as the batch's `in_poses_unit`.
    fn resolve_priors(&mut self, at_end: bool) {
        let Some(p) = &mut self.priors else {
            return;
        };
        let n = self.sample.poses.len();
        if p.resolved.is_some()
            || p.refused.is_some()
            || n < if at_end { 3 } else { PRIOR_UNIT_POSES }
        {
            return;
        }
        match crate::check::units::in_poses_unit(&p.given, &self.sample.poses) {
            Ok(resolved) => {
                p.resolved = Some(resolved.clone());
                if let Some(low) = &mut self.incumbent.low {
                    low.priors = Some(resolved.clone());
                }
                if let Some(low) = self
                    .challenger
                    .as_mut()
                    .and_then(|c| c.segment.low.as_mut())
                {
                    low.priors = Some(resolved);
                }
            }
            Err(e) => {
                p.refused = Some(match e {
                    crate::model::error::Error::InvalidParameter { message, .. } => message,
                    other => other.to_string(),
                });
            }
        }
    }

    /// Whether the readings' check may be left unjudged: the incumbent is a low-DOF robot solved
    /// with its prior, whose readings the check cannot judge (it solves the general problem, which
    /// one-axis rotations leave undetermined), as the batch calibrates such a recording.
    fn readings_moot(&self) -> bool {
        self.incumbent.solves_low_dof()
    }

    /// The same, for an input that writes its poses in the directions `written`
    /// (`io::Recording::written`): a misread of a recording is worded as frame names swapped.
    pub fn with_written(mut self, written: Written) -> Self {
        self.written = written;
        self
    }

    /// The estimate to use now: the last report since the last change of X, unless the readings
    /// have since been found misread. `None` when there is none (see [`Tracker::pending`]): an
    /// estimate from before a change is not the current X.
    pub fn last_report(&self) -> Option<Report> {
        self.last.clone().filter(|_| self.misread.is_none())
    }

    /// Poses held out so far.
    pub fn held_out(&self) -> usize {
        self.held_out
    }

    /// Poses pushed at the robot pose of the pose before them, each counted with it
    /// ([`Step::repeat`]).
    pub fn repeats(&self) -> usize {
        self.repeats
    }

    /// Changes confirmed so far.
    pub fn changes(&self) -> usize {
        self.changes
    }

    /// The current segment's estimate, reportable or not.
    pub fn estimate(&self) -> Option<TrackEstimate> {
        self.current.map(|c| c.estimate)
    }

    /// Why there is no estimate to report now; `None` when there is one.
    pub fn pending(&self) -> Option<Pending> {
        if let Some((reading, other_setup)) = self.misread {
            return Some(Pending::Misread {
                reading,
                setup: self.setup,
                other_setup,
                frames: self.written.frames,
            });
        }
        let unjudged = match self.alike {
            Some(reading) => Pending::ReadingsAlike {
                reading,
                setup: self.setup,
                frames: self.written.frames,
            },
            None => Pending::ReadingsUnchecked,
        };
        self.incumbent
            .pending(self.estimate().as_ref(), &self.options)
            .or((!self.readings_judged && !self.readings_moot()).then_some(unjudged))
    }

    /// Takes the next pose with the robot's joint angles at it (radians, in the robot's joint
    /// order, every pose the same joints): the systematic-error test then orders the poses by
    /// their joint angles and names the joint whose angle the residual follows, as the batch
    /// does with joints given. Otherwise as [`Tracker::push`].
    pub fn push_with_joints(&mut self, pose: &PosePair, joints: &[f64]) -> Step {
        self.joints.put(self.poses + 1, joints);
        self.push(pose)
    }

    /// Takes the next pose (module documentation).
    pub fn push(&mut self, pose: &PosePair) -> Step {
        self.poses += 1;
        self.sample_readings(pose);
        self.resolve_priors(false);
        let mut step = Step {
            pose: self.poses,
            ..Step::default()
        };
        // A robot standing still while the camera streams: one more image of the pose before,
        // whose error it shares; the pose is counted once (`model::station`).
        let previous = self.previous.replace(pose.base_from_gripper);
        if previous.is_some_and(|q| same_station(&q, &pose.base_from_gripper)) {
            self.repeats += 1;
            step.repeat = true;
            return step;
        }
        match self.screw_gate(pose) {
            Some(h) => {
                self.held_out += 1;
                step.held_out = Some(h);
                if self.screw_run.len() == STALE_RUN {
                    // The partners are stale (the rig changed): start again from the held run.
                    self.partners.clear();
                    self.gaps.clear();
                    step.held_out = None;
                    for (number, held) in std::mem::take(&mut self.screw_run) {
                        self.screw_gate(&held);
                        self.held_out -= 1;
                        self.accept(&held, number, &mut step);
                    }
                }
            }
            None => {
                self.screw_run.clear();
                self.accept(pose, self.poses, &mut step);
            }
        }
        if step.change.is_none()
            && (self.incumbent.all.poses() < REFRESH_ALWAYS || self.poses.is_multiple_of(10))
        {
            self.current = self.incumbent.refresh(&self.options);
        }
        step.report = self.report_due().map(|reason| self.report(reason));
        step
    }

    /// A pose past the screw gate: tested against the mature incumbent, or simply added.
    fn accept(&mut self, pose: &PosePair, number: usize, step: &mut Step) {
        let Some(s) = self.residual(self.raw_residual(pose)) else {
            step.earlier = self.add(pose, number);
            return;
        };
        self.feed_challenger(pose, s, number);
        if s <= self.options.elevated || (s <= self.options.gate && self.challenger.is_none()) {
            step.earlier = self.add(pose, number);
        } else {
            // Kept out of the incumbent while the case for a change is open (it would pull the
            // incumbent towards a new X); given back if the case is dismissed.
            if let Some(c) = &mut self.challenger {
                c.pending.push((number, *pose, s));
            }
            if s > self.options.gate {
                self.held_out += 1;
                step.held_out = Some(HeldOut::Residual { statistic: s });
            }
        }
        step.change = step.change.or(self.judge_challenger());
    }

    /// The final report at the end of the stream, unless the last pose was just reported with a
    /// systematic-error test on every pose (the end's test always runs): the current estimate when it is determined, or flagged `weak` when its uncertainty is above the
    /// reporting bounds but below the batch refusal's (10°, half the scene). `None` when there is
    /// no estimate or it is not determined at all ([`Tracker::pending`] says why).
    pub fn finish(&mut self) -> Option<Report> {
        // The last word on the readings: the sample of the whole stream (a stream too short for
        // the checks so far, or one whose first poses could not tell a misread).
        if self.sample.poses.len() >= WARMUP[0] {
            let poses = self.sample.poses.clone();
            self.judge_sample(&poses);
        }
        self.resolve_priors(true);
        // Nothing from readings never checked ([`Tracker::pending`] says so), but for a low-DOF
        // robot solved with its prior.
        self.current = self.incumbent.refresh(&self.options);
        if !self.readings_judged && !self.readings_moot() {
            return None;
        }
        // The last pose was just reported: again only for the end's systematic-error test, when
        // that report's test was not on every pose (it runs on a doubling schedule).
        if self.last_report.is_some_and(|(p, _, _)| p == self.poses) && !self.watch.due(true) {
            return None;
        }
        let e = self.estimate()?;
        let weak = self.pending();
        // Only an estimate that is merely not determined enough may be reported as weak.
        if weak
            .as_ref()
            .is_some_and(|w| !matches!(w, Pending::Undetermined { .. }))
        {
            return None;
        }
        if weak.is_some() {
            let scene = self.incumbent.all.scene_scale();
            let usable = matches!(
                (e.uncertainty_rotation_deg, e.uncertainty_translation),
                (Some(r), Some(t)) if r <= UNDETERMINED_ROTATION_DEG && t <= UNDETERMINED_TRANSLATION * scene
            );
            if !usable {
                return None;
            }
        }
        let mut report = self.report(Reason::End);
        report.weak = weak;
        Some(report)
    }

    /// Adds a pose to the incumbent. The first ones are kept and judged together by the batch
    /// test ([`pose_outliers`]) at each count of [`WARMUP`], and the segment rebuilt from those it
    /// keeps; returns the ones it holds out.
    fn add(&mut self, pose: &PosePair, number: usize) -> Vec<(usize, HeldOut)> {
        self.incumbent.add(pose);
        self.watch.add(pose, self.joints.get(number));
        let Some(warmup) = &mut self.warmup else {
            return Vec::new();
        };
        warmup.push((number, *pose));
        if !WARMUP.contains(&warmup.len()) {
            return Vec::new();
        }
        let mut warmup = self.warmup.take().unwrap_or_default();
        let last = warmup.len() == WARMUP[WARMUP.len() - 1];
        let poses: Vec<PosePair> = warmup.iter().map(|(_, p)| *p).collect();
        let found = pose_outliers(&poses, self.setup, self.options.outlier_deg);
        // The batch's check of the readings, on the poses that agree with the others (outliers
        // could make a mirror-image reading look better).
        let kept: Vec<PosePair> = (0..poses.len())
            .filter(|i| found.poses.iter().all(|g| g.pose != *i))
            .map(|i| poses[i])
            .collect();
        self.judge_readings(&kept);
        let mut held = Vec::new();
        if !found.poses.is_empty() {
            let mut segment = Segment::new(self.setup, self.incumbent.since, self.segment_priors());
            let mut watch = Watch::default();
            let ring = &self.joints;
            let mut gaps = found.poses.iter().peekable();
            let mut k = 0;
            warmup.retain(|(n, p)| {
                let outlier = gaps.next_if(|g| g.pose == k);
                k += 1;
                match outlier {
                    Some(g) => {
                        held.push((
                            *n,
                            HeldOut::Screw {
                                angle_gap_deg: g.angle_gap_deg,
                                pitch_gap: g.pitch_gap,
                            },
                        ));
                        false
                    }
                    None => {
                        segment.add(p);
                        watch.add(p, ring.get(*n));
                        true
                    }
                }
            });
            self.incumbent = segment;
            self.watch = watch;
            self.held_out += held.len();
            self.current = self.incumbent.refresh(&self.options);
        }
        if !last {
            self.warmup = Some(warmup);
        }
        held
    }

    /// The batch's check of the readings on `poses`. A reading that fits far better stands (nothing
    /// is reported from data read wrongly, and an earlier report is withdrawn); the as-given one
    /// stands when no other fits about as well. A check that cannot judge, or finds another reading
    /// fitting as well, leaves an earlier judgement as it was.
    fn judge_readings(&mut self, poses: &[PosePair]) {
        let readings = check_readings(poses, self.setup, self.written);
        if readings.as_given.is_none() {
            return;
        }
        if let Some(better) = readings.better {
            self.misread = Some((better.reading, readings.other_setup(self.setup)));
            self.readings_judged = true;
            self.last = None;
            return;
        }
        // Both inputs inverted fit as well as given: the sizes and the camera poses tell.
        if readings.both_inverted(self.setup) {
            self.misread = Some((Reading::BothInverted, false));
            self.readings_judged = true;
            self.last = None;
            return;
        }
        if let Some(alike) = readings.alike.first() {
            if !self.readings_judged {
                self.alike = Some(alike.reading);
            }
            return;
        }
        self.misread = None;
        self.alike = None;
        self.implausible = readings.size_warning(self.setup).is_some();
        self.readings_judged = true;
    }

    /// [`Self::judge_readings`] on a sample of poses without those that disagree with the others.
    fn judge_sample(&mut self, poses: &[PosePair]) {
        let found = pose_outliers(poses, self.setup, self.options.outlier_deg).indices();
        let kept: Vec<PosePair> = (0..poses.len())
            .filter(|i| !found.contains(i))
            .map(|i| poses[i])
            .collect();
        self.judge_readings(&kept);
    }

    /// Keeps every stride-th pose pushed for the check of the readings; checks, thins by half
    /// and doubles the stride when the sample is full (constant memory, a check every doubling of
    /// the stream).
    fn sample_readings(&mut self, pose: &PosePair) {
        let sample = &mut self.sample;
        sample.seen += 1;
        if !(sample.seen - 1).is_multiple_of(sample.stride) {
            return;
        }
        sample.poses.push(*pose);
        if sample.poses.len() < READINGS_SAMPLE {
            return;
        }
        let poses = std::mem::take(&mut sample.poses);
        self.judge_sample(&poses);
        self.sample.poses = poses.into_iter().step_by(2).collect();
        self.sample.stride *= 2;
    }

    /// The pose's own disagreement with the current (X, Y): rotation (radians) and translation.
    fn raw_residual(&self, pose: &PosePair) -> Option<[f64; 2]> {
        let Snapshot {
            estimate: e,
            scatter,
            ..
        } = self.current?;
        let y_k = self.setup.hand_pose(&pose.base_from_gripper) * e.x * pose.camera_from_target;
        let d = scatter.y.inverse() * y_k;
        // The angle from atan2 (accurate to ε near the identity, where an arccosine is not).
        Some([
            axis_angle(d.rotation.matrix()).0,
            d.translation.vector.norm(),
        ])
    }

    /// The typical residual: the RMS scatter of the accepted poses under the current estimate
    /// (the screw gate keeps gross outliers out of it), floored at the data's numerical precision
    /// ([`crate::check::precision`]): the scatter comes from running sums of translations of the
    /// size of the camera's distance, the hand positions and X's translation, and resolves no
    /// finer than √(64 ε) of them. On exact data the residuals are rounding, below the floor: no pose
    /// is elevated, none held out.
    fn typical_scale(&self) -> Option<[f64; 2]> {
        let Snapshot {
            estimate: e,
            scatter,
            ..
        } = self.current?;
        Some(self.incumbent.noise_unit(&scatter, &e.x))
    }

    /// The residual statistic of a pose, the larger of its rotation and translation ratios to the
    /// typical ones, when the incumbent is mature (enough poses, determined).
    fn residual(&self, raw: Option<[f64; 2]>) -> Option<f64> {
        let snapshot = self.current?;
        let bound = self.incumbent.translation_bound(&self.options);
        let local = snapshot
            .local
            .is_some_and(|(r, t)| r <= self.options.max_rotation_deg && t <= bound);
        if self.incumbent.all.poses() < self.options.mature_poses || !local {
            return None;
        }
        let [r, t] = raw?;
        let [sr, st] = self.typical_scale()?;
        Some((r / sr).max(t / st))
    }

    fn feed_challenger(&mut self, pose: &PosePair, s: f64, number: usize) {
        let options = self.options;
        let elevated = s > self.options.elevated;
        if elevated && self.challenger.is_none() {
            self.challenger = Some(Challenger {
                segment: Segment::new(self.setup, number, self.segment_priors()),
                current: None,
                poses: 0,
                elevated: 0,
                pending: Vec::new(),
                watch: Watch::default(),
            });
        }
        if let Some(c) = &mut self.challenger {
            c.segment.add(pose);
            c.watch.add(pose, self.joints.get(number));
            c.current = c.segment.refresh(&options);
            c.poses += 1;
            c.elevated += usize::from(elevated);
        }
    }

    /// Dismisses, keeps or confirms the challenger (module documentation).
    fn judge_challenger(&mut self) -> Option<Change> {
        let c = self.challenger.as_ref()?;
        if c.poses < self.options.confirm_poses {
            return None;
        }
        let old = self.current?.estimate;
        let [typical_r, typical_t] = self.typical_scale()?;
        // Dismissed: a few elevated poses among normal ones were the noise's tail or outliers
        // (those above the gate stay out); a long misfit that determines no new X says the
        // incumbent was not yet right for this part of the workspace (all of them go in).
        let sporadic = 2 * c.elevated < c.poses;
        if sporadic || c.poses > CHALLENGER_LIFE * self.options.confirm_poses {
            let dismissed = self.challenger.take()?;
            for (number, pose, s) in dismissed.pending {
                if !sporadic || s <= self.options.gate {
                    self.held_out -= usize::from(s > self.options.gate);
                    self.add(&pose, number);
                }
            }
            return None;
        }
        if 10 * c.elevated < 6 * c.poses {
            return None;
        }
        let snapshot = c.current?;
        let (new, scatter) = (snapshot.estimate, snapshot.scatter);
        // It must explain its own poses at the incumbent's noise level, and its rotation must be
        // determined: a local fit to one region of the workspace is not.
        let fits = scatter.rotation <= 2.0 * typical_r && scatter.translation <= 2.0 * typical_t;
        let bound = c.segment.translation_bound(&self.options);
        let determined = snapshot
            .local
            .is_some_and(|(r, t)| r <= self.options.max_rotation_deg && t <= bound);
        if !(fits && determined) {
            return None;
        }
        let c = self.challenger.take()?;
        let change = Change {
            at: c.segment.since,
            confirmed: self.poses,
            x_rotation_deg: rotation_angle_between(&old.x.rotation, &new.x.rotation).to_degrees(),
            x_translation: (old.x.translation.vector - new.x.translation.vector).norm(),
            target_rotation_deg: rotation_angle_between(&old.target.rotation, &new.target.rotation)
                .to_degrees(),
            target_translation: (old.target.translation.vector - new.target.translation.vector)
                .norm(),
        };
        self.incumbent = c.segment;
        self.watch = c.watch;
        self.current = Some(snapshot);
        self.warmup = None;
        self.last_report = None;
        self.last = None;
        self.changes += 1;
        Some(change)
    }

    /// The screw gate (module documentation): `Some` when the pose is held out.
    fn screw_gate(&mut self, pose: &PosePair) -> Option<HeldOut> {
        let partners = self
            .partners
            .iter()
            .rev()
            .step_by(PARTNER_STRIDE)
            .take(PARTNER_RING / PARTNER_STRIDE);
        let (angle, pitch) = screw_gaps(self.setup, pose, partners);
        if self.partners.len() >= PARTNER_STRIDE && self.gaps.len() >= 8 {
            let typical = |k: usize| {
                let mut v = [0.0; GAP_RING];
                let n = self.gaps.len();
                v.iter_mut().zip(&self.gaps).for_each(|(d, g)| *d = g[k]);
                median_in(&mut v[..n])
            };
            let (typical_angle, typical_pitch) = (typical(0), typical(1));
            let angle_limit = (OUTLIER_FACTOR * typical_angle).max(self.options.outlier_deg);
            let scale = pose.base_from_gripper.translation.vector.norm();
            let pitch_limit = OUTLIER_FACTOR * typical_pitch.max(resolution(scale));
            if angle > angle_limit || pitch > pitch_limit {
                self.screw_run.push((self.poses, *pose));
                return Some(HeldOut::Screw {
                    angle_gap_deg: angle,
                    pitch_gap: pitch,
                });
            }
        }
        if !self.partners.is_empty() {
            if self.gaps.len() == GAP_RING {
                self.gaps.pop_front();
            }
            self.gaps.push_back([angle, pitch]);
        }
        if self.partners.len() == PARTNER_RING {
            self.partners.pop_front();
        }
        self.partners.push_back(*pose);
        None
    }

    /// Whether the current estimate is due for a report, and why.
    fn report_due(&self) -> Option<Reason> {
        let e = self.current?.estimate;
        // Nothing before the first poses have been judged together (outliers, readings).
        let judged = self.warmup.as_ref().is_none_or(|w| w.len() >= WARMUP[0]);
        if self.pending().is_some() || !judged {
            return None;
        }
        let (ur, ut) = (e.uncertainty_rotation_deg?, e.uncertainty_translation?);
        match self.last_report {
            None => Some(Reason::Determined),
            Some((pose, _, _)) if self.poses >= pose + self.options.every.max(1) => {
                Some(Reason::Every)
            }
            Some((_, r, t)) if ur <= self.options.shrink * r && ut <= self.options.shrink * t => {
                Some(Reason::Shrunk)
            }
            Some(_) => None,
        }
    }

    fn report(&mut self, reason: Reason) -> Report {
        let mut estimate = self.current.expect("a report needs an estimate").estimate;
        if let (Some(point), Some(c)) = (self.options.point, estimate.covariance) {
            let c = nalgebra::Matrix6::from_fn(|i, j| c[i][j]);
            estimate.at_point = Some((point, point_sigma(&c, &estimate.x, point)));
        }
        self.reports += 1;
        // The schedule is the estimate's own (its uncertainty before any widening).
        self.last_report = Some((
            self.poses,
            estimate.uncertainty_rotation_deg.unwrap_or(f64::INFINITY),
            estimate.uncertainty_translation.unwrap_or(f64::INFINITY),
        ));
        // The systematic-error test, when due (module `systematic`), and its widening.
        if self.watch.due(reason == Reason::End) {
            let model = self
                .robot_model
                .as_ref()
                .filter(|_| self.robot_model_refused.is_none());
            let refused = self
                .watch
                .test(self.setup, &estimate.x, reason == Reason::End, model);
            self.robot_model_refused = self.robot_model_refused.take().or(refused);
        }
        // A low-DOF robot solved with its prior: the general solve of the bootstrap cannot
        // determine X (one rotation axis), as the readings' check cannot judge it.
        let scene = (!self.readings_moot())
            .then(|| self.watch.scene(self.setup))
            .flatten();
        if let Some(scene) = scene {
            self.watch.at_least_batch(self.setup, scene, &mut estimate);
        }
        let mut warnings: Vec<_> = self.watch.widen(&mut estimate).into_iter().collect();
        // A weakly determined direction of X, as `calibrate` judges it (one verdict in every
        // face): the report's covariance (widened as its sizes are) against the batch's bounds.
        if let (Some(c), Some(scene)) = (estimate.covariance, scene) {
            let c = nalgebra::Matrix6::from_fn(|i, j| c[i][j]);
            warn_weak(&summarise(c, 0, 0, scene), self.setup, None, &mut warnings);
        }
        let report = Report {
            number: self.reports,
            pose: self.poses,
            reason,
            estimate,
            weak: None,
            implausible: self.implausible,
            systematic: self.watch.found.as_ref().map(|f| f.systematic.clone()),
            warnings,
        };
        self.last = Some(report.clone());
        report
    }
}

/// Whether two robot poses are one station ([`station::same_station`]), the translation's
/// tolerance [`SAME_STATION`] of the gripper's distance from the base (the robot's own unit,
/// whatever the camera's; a stream has no spread of hand positions yet to measure it by).
fn same_station(a: &Transform, b: &Transform) -> bool {
    let reach = a.translation.vector.norm().max(b.translation.vector.norm());
    station::same_station(
        (a.rotation.matrix(), &a.translation.vector),
        (b.rotation.matrix(), &b.translation.vector),
        SAME_STATION * reach,
    )
}
