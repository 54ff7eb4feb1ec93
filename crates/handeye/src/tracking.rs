//! The accumulating estimator on a live stream: every pose gated, the estimate watched for a change
//! of X or of the target, and reported on its own schedule with the reason when there is none.
//!
//! One [`Tracker`] takes the poses one at a time ([`Tracker::push`]). Each pose passes two tests
//! before it enters the all-pairs sums of [`PoseAccumulator`]:
//!
//! 1. **The screw gate** (X-free, from the second pose on): the median screw-invariant gaps of the
//!    pose against up to eight recent accepted poses ([`crate::consistency::screw_gaps`], the test
//!    of batch `--reject-outliers`) above `max(outlier_deg, 6 × typical)` in angle, or 6 × typical
//!    in pitch, hold it out: a flipped or random target pose, a gross error, a bad stamp. Eight
//!    held out in a row mean the partners are stale (the rig changed): they are dropped.
//! 2. **The residual gate**, once the estimate is mature: the pose's own fixed frame
//!    Y_k = H_k X C_k against the accumulated Y, normalised by the scatter of all accepted poses
//!    under the same X ([`PoseAccumulator::residual_scatter`], O(1)): the larger of rotation and
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

use std::collections::VecDeque;
use std::fmt;

use serde::{Deserialize, Serialize};

use crate::accumulate::{PoseAccumulator, RobotWorldAccumulator, Scatter};
use crate::consistency::{OUTLIER_FACTOR, median, pose_outliers, screw_gaps};
use crate::conventions::{Reading, check_readings};
use crate::motion::{PosePair, Setup};
use crate::pose::{Transform, rotation_angle_between};
use crate::uncertainty::{UNDETERMINED_ROTATION_DEG, UNDETERMINED_TRANSLATION};

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
        }
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
/// A challenger unconfirmed after this many times `confirm_poses` poses is dropped.
const CHALLENGER_LIFE: usize = 10;

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
    /// The robot-world solution (Shah's A X = Z B over the same accepted poses of the segment,
    /// [`RobotWorldAccumulator`]): X and the target solved together rather than the target as
    /// the mean fixed frame under the hand–eye X. `None` while its system is degenerate.
    pub robot_world: Option<RobotWorldPair>,
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
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
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
}

/// Why there is no estimate to report.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
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
    /// [`check_readings`], on the first poses): an inverted pose, `w, x, y, z` quaternions, or
    /// millimetres on one side. Nothing is reported from data read wrongly.
    Misread {
        /// The reading that fits.
        reading: Reading,
        /// The setup the poses are read in.
        setup: Setup,
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
}

impl fmt::Display for Pending {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::FewPoses { poses } => write!(f, "only {poses} usable pose(s) so far"),
            Self::NoRotation { largest_deg } => write!(
                f,
                "no rotation above 2° yet (the largest is {largest_deg:.2}°): turn the gripper"
            ),
            Self::ParallelAxes => write!(
                f,
                "all rotation axes parallel so far: rotate the gripper about another axis"
            ),
            Self::Misread { reading, setup } => write!(
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

/// All-pairs sums of one segment, with the two halves of the split-half uncertainty.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct Segment {
    all: PoseAccumulator,
    halves: [PoseAccumulator; 2],
    /// Shah's robot-world sums over the same poses.
    robot_world: RobotWorldAccumulator,
    since: usize,
    /// The first accepted hand rotation and the largest rotation from it (radians).
    first: Option<Transform>,
    largest: f64,
    /// Earlier estimates (pose count, X), each at 1.5 times the count of the one before, those of
    /// at least a quarter of the poses now.
    checkpoints: Vec<(usize, Transform)>,
}

impl Segment {
    fn new(setup: Setup, since: usize) -> Self {
        Self {
            all: PoseAccumulator::new(setup),
            halves: [PoseAccumulator::new(setup), PoseAccumulator::new(setup)],
            robot_world: RobotWorldAccumulator::new(setup),
            since,
            first: None,
            largest: 0.0,
            checkpoints: Vec::new(),
        }
    }

    fn add(&mut self, pose: &PosePair) {
        let hand = self.all.setup().hand_pose(&pose.base_from_gripper);
        let first = *self.first.get_or_insert(hand);
        self.largest = self
            .largest
            .max(rotation_angle_between(&first.rotation, &hand.rotation));
        self.all.add(pose);
        self.halves[self.all.poses() % 2].add(pose);
        self.robot_world.add(pose);
    }

    /// The segment's estimate now, kept as a checkpoint when its pose count has grown by half
    /// since the last one.
    fn refresh(&mut self) -> Option<Snapshot> {
        let current = self.estimate();
        let n = self.all.poses();
        let due = self
            .checkpoints
            .last()
            .is_none_or(|(c, _)| 2 * n >= 3 * c && n >= c + 2);
        if let Some(Snapshot { estimate: e, .. }) = current
            && due
            && n >= 6
        {
            self.checkpoints.push((n, e.x));
            // Those below n/4 are of no more use (constant memory: about four are kept).
            self.checkpoints.retain(|(c, _)| 4 * c >= n);
        }
        current
    }

    /// The drift of the estimate as an uncertainty: with c a checkpoint between n/4 and n/2 poses,
    /// X_c − X_n has the spread of σ_n·√(n/c − 1) when the poses' errors are independent, and
    /// more when the estimate still moves as the robot reaches new parts of the workspace (real
    /// data). The largest over those checkpoints (two or three), so that one lucky agreement
    /// does not pass for certainty.
    fn drift(&self, x: &Transform) -> Option<(f64, f64)> {
        let n = self.all.poses();
        self.checkpoints
            .iter()
            .filter(|(c, _)| 2 * c <= n && 4 * c >= n)
            .map(|(c, x_c)| {
                let scale = ((n as f64 / *c as f64) - 1.0).max(1e-9).sqrt();
                (
                    rotation_angle_between(&x_c.rotation, &x.rotation).to_degrees() / scale,
                    (x_c.translation.vector - x.translation.vector).norm() / scale,
                )
            })
            .reduce(|a, b| (a.0.max(b.0), a.1.max(b.1)))
    }

    fn estimate(&self) -> Option<Snapshot> {
        let e = self.all.estimate()?;
        let scatter = self.all.residual_scatter(&e.x)?;
        // The largest of three measures: the split-half difference, the first-order covariance
        // with each pose as one measurement at the scatter's noise level, and the drift since
        // half the poses.
        let halves = (self.halves[0].estimate(), self.halves[1].estimate());
        let split = match halves {
            (Some(a), Some(b)) => Some((
                0.5 * rotation_angle_between(&a.x.rotation, &b.x.rotation).to_degrees(),
                0.5 * (a.x.translation.vector - b.x.translation.vector).norm(),
            )),
            _ => None,
        };
        let linear = self
            .all
            .covariance(
                &e.x,
                scatter.rotation / 3f64.sqrt(),
                scatter.translation / 3f64.sqrt(),
            )
            .map(|c| {
                let rotation = (c[(0, 0)] + c[(1, 1)] + c[(2, 2)]).sqrt().to_degrees();
                (rotation, (c[(3, 3)] + c[(4, 4)] + c[(5, 5)]).sqrt())
            });
        let drift = self.drift(&e.x);
        let local = split.zip(linear).map(|(a, b)| (a.0.max(b.0), a.1.max(b.1)));
        let (ur, ut) = match (local, drift) {
            (Some(a), Some(b)) => (Some(a.0.max(b.0)), Some(a.1.max(b.1))),
            _ => (None, None),
        };
        Some(Snapshot {
            estimate: TrackEstimate {
                x: e.x,
                target: scatter.y,
                poses: e.poses,
                since: self.since,
                conditioning: e.conditioning,
                noise_rotation_deg: scatter.rotation.to_degrees(),
                noise_translation: scatter.translation,
                uncertainty_rotation_deg: ur,
                uncertainty_translation: ut,
                robot_world: self.robot_world.estimate().map(|r| RobotWorldPair {
                    x: r.x,
                    target: r.target,
                }),
            },
            scatter,
            local_rotation_deg: local.map(|l| l.0),
            local,
        })
    }

    /// The translation bound for `e`, input units.
    fn translation_bound(&self, options: &TrackOptions) -> f64 {
        (options.max_translation * self.all.scene_scale())
            .max(options.max_rotation_deg.to_radians() * self.all.viewing_distance())
    }

    /// Why `e` (this segment's estimate, if any) is not reportable; `None` when it is.
    fn pending(&self, e: Option<&TrackEstimate>, options: &TrackOptions) -> Option<Pending> {
        let Some(e) = e else {
            return Some(if self.all.poses() < 3 {
                Pending::FewPoses {
                    poses: self.all.poses(),
                }
            } else if self.largest < 2f64.to_radians() {
                Pending::NoRotation {
                    largest_deg: self.largest.to_degrees(),
                }
            } else {
                Pending::ParallelAxes
            });
        };
        let bound_translation = self.translation_bound(options);
        let ok = matches!(
            (e.uncertainty_rotation_deg, e.uncertainty_translation),
            (Some(r), Some(t)) if r <= options.max_rotation_deg && t <= bound_translation
        );
        (!ok).then_some(Pending::Undetermined {
            rotation_deg: e.uncertainty_rotation_deg,
            translation: e.uncertainty_translation,
            bound_rotation_deg: options.max_rotation_deg,
            bound_translation,
        })
    }
}

/// An estimate with what the tracker needs to judge by it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
struct Snapshot {
    estimate: TrackEstimate,
    scatter: Scatter,
    /// The rotation uncertainty without the drift term (split-half and first-order): whether the
    /// poses so far fix the rotation at all, as a challenger needs.
    local_rotation_deg: Option<f64>,
    /// Both, rotation (degrees) and translation.
    local: Option<(f64, f64)>,
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
    /// What the last check of the readings on them found: a reading that fits far better, and
    /// whether X and Y have sizes the setup makes unlikely (both poses inverted fit as well).
    misread: Option<Reading>,
    implausible: bool,
    /// The poses held out in a row by the screw gate, with their numbers.
    screw_run: Vec<(usize, PosePair)>,
    /// Pose number and uncertainties of the last report of this segment.
    last_report: Option<(usize, f64, f64)>,
    reports: usize,
    held_out: usize,
    changes: usize,
}

impl Tracker {
    /// A tracker for poses read in `setup`.
    pub fn new(setup: Setup, options: TrackOptions) -> Self {
        Self {
            options,
            setup,
            poses: 0,
            incumbent: Segment::new(setup, 1),
            current: None,
            challenger: None,
            partners: VecDeque::with_capacity(PARTNER_RING),
            gaps: VecDeque::with_capacity(GAP_RING),
            warmup: Some(Vec::new()),
            misread: None,
            implausible: false,
            screw_run: Vec::with_capacity(STALE_RUN),
            last_report: None,
            reports: 0,
            held_out: 0,
            changes: 0,
        }
    }

    /// Poses pushed so far.
    pub fn poses(&self) -> usize {
        self.poses
    }

    /// Poses held out so far.
    pub fn held_out(&self) -> usize {
        self.held_out
    }

    /// Changes confirmed so far.
    pub fn changes(&self) -> usize {
        self.changes
    }

    /// The current segment's estimate, reportable or not.
    pub fn estimate(&self) -> Option<TrackEstimate> {
        self.current.map(|c| c.estimate)
    }

    /// The current estimate if it is determined (what a report would carry).
    pub fn determined(&self) -> Option<TrackEstimate> {
        self.estimate().filter(|_| self.pending().is_none())
    }

    /// Why there is no estimate to report now; `None` when there is one.
    pub fn pending(&self) -> Option<Pending> {
        if let Some(reading) = self.misread {
            return Some(Pending::Misread {
                reading,
                setup: self.setup,
            });
        }
        self.incumbent
            .pending(self.estimate().as_ref(), &self.options)
    }

    /// Takes the next pose (module documentation).
    pub fn push(&mut self, pose: &PosePair) -> Step {
        self.poses += 1;
        let mut step = Step {
            pose: self.poses,
            ..Step::default()
        };
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
            && (self.incumbent.all.poses() < REFRESH_ALWAYS || self.poses % 10 == 0)
        {
            self.current = self.incumbent.refresh();
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

    /// The final report at the end of the stream, unless the last pose was just reported: the
    /// current estimate when it is determined, or flagged `weak` when its uncertainty is above the
    /// reporting bounds but below the batch refusal's (10°, half the scene). `None` when there is
    /// no estimate or it is not determined at all ([`Tracker::pending`] says why).
    pub fn finish(&mut self) -> Option<Report> {
        self.current = self.incumbent.refresh();
        if self.last_report.is_some_and(|(p, _, _)| p == self.poses) {
            return None;
        }
        let e = self.estimate()?;
        let weak = self.pending();
        // Only an estimate that is merely not determined enough may be reported as weak.
        if weak.is_some_and(|w| !matches!(w, Pending::Undetermined { .. })) {
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
        // The batch's check of the readings, on the same poses.
        let readings = check_readings(&poses, self.setup);
        if readings.as_given.is_some() {
            self.misread = readings.better.map(|b| b.reading);
            self.implausible = readings.size_warning(self.setup).is_some();
        }
        let found = pose_outliers(&poses, self.setup, self.options.outlier_deg);
        let mut held = Vec::new();
        if !found.poses.is_empty() {
            let mut segment = Segment::new(self.setup, self.incumbent.since);
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
                        true
                    }
                }
            });
            self.incumbent = segment;
            self.held_out += held.len();
            self.current = self.incumbent.refresh();
        }
        if !last {
            self.warmup = Some(warmup);
        }
        held
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
        Some([d.rotation.angle(), d.translation.vector.norm()])
    }

    /// The typical residual: the RMS scatter of the accepted poses under the current estimate
    /// (the screw gate keeps gross outliers out of it).
    fn typical_scale(&self) -> Option<[f64; 2]> {
        let Snapshot {
            estimate: e,
            scatter,
            ..
        } = self.current?;
        let scale = e.target.translation.vector.norm().max(1.0);
        Some([
            scatter.rotation.max(1e-12),
            scatter.translation.max(1e-12 * scale),
        ])
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
        let elevated = s > self.options.elevated;
        if elevated && self.challenger.is_none() {
            self.challenger = Some(Challenger {
                segment: Segment::new(self.setup, number),
                current: None,
                poses: 0,
                elevated: 0,
                pending: Vec::new(),
            });
        }
        if let Some(c) = &mut self.challenger {
            c.segment.add(pose);
            c.current = c.segment.refresh();
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
        self.current = Some(snapshot);
        self.warmup = None;
        self.last_report = None;
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
            let typical_angle = median(self.gaps.iter().map(|g| g[0]).collect());
            let typical_pitch = median(self.gaps.iter().map(|g| g[1]).collect());
            let angle_limit = (OUTLIER_FACTOR * typical_angle).max(self.options.outlier_deg);
            let scale = pose.base_from_gripper.translation.vector.norm();
            let pitch_limit = OUTLIER_FACTOR * typical_pitch.max(1e-9 * scale);
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
        let estimate = self.current.expect("a report needs an estimate").estimate;
        self.reports += 1;
        self.last_report = Some((
            self.poses,
            estimate.uncertainty_rotation_deg.unwrap_or(f64::INFINITY),
            estimate.uncertainty_translation.unwrap_or(f64::INFINITY),
        ));
        Report {
            number: self.reports,
            pose: self.poses,
            reason,
            estimate,
            weak: None,
            implausible: self.implausible,
        }
    }
}

impl Report {
    /// The report as its JSON line (SPEC sec. 7), the one output of every face: `estimate`,
    /// `pose`, `reason`, `frame`, X (`translation`, `quaternion_xyzw`, `matrix`), `poses`,
    /// `since`, `uncertainty`, `noise`, `conditioning`, `target` (the fixed frame), `robot_world`
    /// (X and the target solved together by Shah over the same poses, when determined) and, on a
    /// weak final report, `weak` with the reason in words.
    pub fn json(&self, setup: Setup) -> serde_json::Value {
        let e = &self.estimate;
        let mut out = serde_json::Map::new();
        out.insert("estimate".into(), self.number.into());
        out.insert("pose".into(), self.pose.into());
        out.insert("reason".into(), serde_json::json!(self.reason));
        out.insert("estimator".into(), "accumulate".into());
        out.insert("frame".into(), setup.x_frame().into());
        insert_transform(&mut out, &e.x);
        out.insert("poses".into(), e.poses.into());
        out.insert("since".into(), e.since.into());
        out.insert(
            "uncertainty".into(),
            serde_json::json!({"rotation_deg": e.uncertainty_rotation_deg, "translation": e.uncertainty_translation}),
        );
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
        if let Some(w) = &self.weak {
            out.insert("weak".into(), w.to_string().into());
        }
        if self.implausible {
            out.insert(
                "warning".into(),
                "X and the target pose have the sizes the setup makes unlikely: if both inputs give the inverse of the transform they name, the same data fit exactly with X and the target's pose swapped; check the directions".into(),
            );
        }
        out.into()
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
fn insert_transform(object: &mut serde_json::Map<String, serde_json::Value>, t: &Transform) {
    let j = crate::io::TransformJson::from(t);
    object.insert("translation".into(), serde_json::json!(j.translation));
    object.insert(
        "quaternion_xyzw".into(),
        serde_json::json!(j.quaternion_xyzw),
    );
    object.insert("matrix".into(), serde_json::json!(j.matrix));
}
