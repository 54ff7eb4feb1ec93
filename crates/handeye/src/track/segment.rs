//! One segment of the stream: its all-pairs sums, the halves of the split-half uncertainty and
//! the checkpoints of the drift term.

use serde::{Deserialize, Serialize};

use super::{Pending, RobotWorldPair, TrackEstimate, TrackOptions};
use crate::model::motion::{PosePair, Setup};
use crate::model::pose::{Transform, rotation_angle_between};
use crate::solve::accumulate::{PoseAccumulator, RobotWorldAccumulator, Scatter};

/// An estimate with what the tracker needs to judge by it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub(super) struct Snapshot {
    pub(super) estimate: TrackEstimate,
    pub(super) scatter: Scatter,
    /// The uncertainty without the drift term (split-half and first-order), rotation in degrees
    /// and translation: whether the poses so far fix X at all, as a challenger needs.
    pub(super) local: Option<(f64, f64)>,
}

/// All-pairs sums of one segment, with the two halves of the split-half uncertainty.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(super) struct Segment {
    pub(super) all: PoseAccumulator,
    pub(super) halves: [PoseAccumulator; 2],
    /// Shah's robot-world sums over the same poses.
    pub(super) robot_world: RobotWorldAccumulator,
    pub(super) since: usize,
    /// The first accepted hand rotation and the largest rotation from it (radians).
    pub(super) first: Option<Transform>,
    pub(super) largest: f64,
    /// Earlier estimates (pose count, X), each at 1.5 times the count of the one before, those of
    /// at least a quarter of the poses now.
    pub(super) checkpoints: Vec<(usize, Transform)>,
}

impl Segment {
    pub(super) fn new(setup: Setup, since: usize) -> Self {
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

    pub(super) fn add(&mut self, pose: &PosePair) {
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
    pub(super) fn refresh(&mut self) -> Option<Snapshot> {
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
    pub(super) fn drift(&self, x: &Transform) -> Option<(f64, f64)> {
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

    pub(super) fn estimate(&self) -> Option<Snapshot> {
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
            local,
        })
    }

    /// The translation bound for `e`, input units.
    pub(super) fn translation_bound(&self, options: &TrackOptions) -> f64 {
        (options.max_translation * self.all.scene_scale())
            .max(options.max_rotation_deg.to_radians() * self.all.viewing_distance())
    }

    /// Why `e` (this segment's estimate, if any) is not reportable; `None` when it is.
    pub(super) fn pending(
        &self,
        e: Option<&TrackEstimate>,
        options: &TrackOptions,
    ) -> Option<Pending> {
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
