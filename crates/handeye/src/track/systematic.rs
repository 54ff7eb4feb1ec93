//! The systematic-error test (issue 29, [`crate::check::systematic`]) on a segment of the stream:
//! the batch's test, with the batch's widening of the uncertainty, on the segment's accepted
//! poses.
//!
//! **Cost.** The segment's poses are kept as a bounded, deterministic sample: every pose until
//! [`SAMPLE`] are kept; each time it fills, the repeats of a robot pose (`model::station`) are
//! dropped first, and a sample still more than half full is thinned by half and its stride
//! doubled (constant memory, as the tracker's sample of the readings; a robot program that tours
//! the same poses keeps every pose of its tour). The test runs when a report
//! is made and the segment has doubled since the last test (at 12, 24, 48, … poses; so about
//! log₂ n times over a stream of n poses, each on at most [`SAMPLE`] poses), and at the end of the
//! stream. Between two tests, each report carries the last test's finding and widening: an error
//! that follows the configuration does not shrink as poses of the same kind come. A sample that is
//! still a dense stream is thinned into stretches of the robot's motion, as the batch's is
//! (`check::systematic::test_stations`, in the test itself).
//!
//! **Repeated tests: a flag is confirmed.** About log₂ n tests of one stream, each at P_FLAG,
//! would flag a stream of random errors far more often than P_FLAG (measured on 100,000 simulated
//! poses: 2 of 14 tests, and 288 of 1002 reports questionable). A test before the end whose
//! p-value is below the threshold therefore flags only when the previous test of the segment was
//! below it too (on half the sample: the same error seen twice); alone, it is kept as
//! `unconfirmed` and the verdict stays. The end-of-stream test, the stream's last word, flags
//! alone, so a stream of 32 poses keeps its power: its end test decides as the batch does.
//!
//! **Joint angles.** A pose pushed with its joint angles keeps them in a ring of the last
//! [`JOINT_RING`] poses (by pose number), from which the sample takes them when the pose is
//! accepted (also later: the first poses judged together, a challenger's poses given back). The
//! test orders the poses by their joint angles when every pose of the sample has them, in one
//! length; otherwise by the hand pose, as the batch without joints.

use nalgebra::Matrix6;
use serde::{Deserialize, Serialize};

use crate::check::identification::check_model;
use crate::check::outliers::{translation_scale, working_distance};
use crate::check::systematic::{Systematic, systematic_test, systematic_warning, widen_by};
use crate::check::uncertainty::{
    REPLICATES, Uncertainty, bootstrap, bootstrap_by_region, point_sigma, stations_of, summarise,
};
use crate::model::error::{Degeneracy, Error, Result};
use crate::model::kinematics::Kinematics;
use crate::model::motion::{PosePair, Setup};
use crate::model::pose::Transform;
use crate::model::warning::Warning;
use crate::solve::accumulate::PoseAccumulator;

use super::TrackEstimate;

/// Poses the sample holds at most (see the module documentation).
pub(super) const SAMPLE: usize = 512;
/// Pushed poses whose joint angles are kept for the sample (longer than the tracker holds a
/// pose before accepting it: 256 first poses, a challenger's life of 100).
pub(super) const JOINT_RING: usize = 1024;

/// The joint angles of the last [`JOINT_RING`] poses pushed, by pose number.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub(super) struct JointRing {
    /// Angles per pose: the length of the first list given.
    dim: usize,
    /// The pose number in each slot (0: none).
    numbers: Vec<usize>,
    values: Vec<f64>,
}

impl JointRing {
    /// Keeps the angles of pose `number` (a list of another length than the first is not kept:
    /// the test then orders by the hand pose). Allocates once, at the first list.
    pub(super) fn put(&mut self, number: usize, joints: &[f64]) {
        if self.numbers.is_empty() {
            if joints.is_empty() {
                return;
            }
            self.dim = joints.len();
            self.numbers = vec![0; JOINT_RING];
            self.values = vec![0.0; JOINT_RING * self.dim];
        }
        let slot = number % JOINT_RING;
        if joints.len() != self.dim {
            self.numbers[slot] = 0;
            return;
        }
        self.numbers[slot] = number;
        self.values[slot * self.dim..(slot + 1) * self.dim].copy_from_slice(joints);
    }

    /// The angles of pose `number`, when they were given and are still kept.
    pub(super) fn get(&self, number: usize) -> Option<&[f64]> {
        let slot = number % JOINT_RING;
        (self.numbers.get(slot) == Some(&number) && number > 0)
            .then(|| &self.values[slot * self.dim..(slot + 1) * self.dim])
    }
}

/// What the last test found, with the region bootstrap that widens each estimate after it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(super) struct Finding {
    pub(super) systematic: Systematic,
    /// The region bootstrap of a flagged test; `None` unflagged.
    regions: Option<Uncertainty>,
    /// The scene's size the test judged by.
    scene: f64,
}

/// A segment's sample of accepted poses and its last test.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(super) struct Watch {
    poses: Vec<PosePair>,
    /// The joint angles of the sampled poses, flat (`dim` a pose), while every one has them.
    joints: Vec<f64>,
    /// Angles per pose; `None` before the first pose, `Some(0)` once a pose came without them.
    dim: Option<usize>,
    stride: usize,
    /// Accepted poses offered to the sample.
    seen: usize,
    /// Accepted poses at which the next test is due.
    next: usize,
    /// Accepted poses at the last test.
    tested: usize,
    /// Whether the last test's p-value was below the threshold (confirmed or not).
    #[serde(default)]
    below: bool,
    pub(super) found: Option<Finding>,
}

impl Default for Watch {
    fn default() -> Self {
        Self {
            poses: Vec::new(),
            joints: Vec::new(),
            dim: None,
            stride: 1,
            seen: 0,
            next: crate::check::systematic::MIN_POSES,
            tested: 0,
            below: false,
            found: None,
        }
    }
}

impl Watch {
    /// Offers an accepted pose with its joint angles, if known.
    pub(super) fn add(&mut self, pose: &PosePair, joints: Option<&[f64]>) {
        self.seen += 1;
        if !(self.seen - 1).is_multiple_of(self.stride) {
            return;
        }
        if self.poses.capacity() == 0 {
            self.poses.reserve_exact(SAMPLE);
        }
        let dim = *self.dim.get_or_insert(joints.map_or(0, <[f64]>::len));
        match joints {
            Some(q) if dim > 0 && q.len() == dim => self.joints.extend_from_slice(q),
            _ => {
                self.dim = Some(0);
                self.joints = Vec::new();
            }
        }
        self.poses.push(*pose);
        if self.poses.len() < SAMPLE {
            return;
        }
        // Full. Repeats of a robot pose go first (the test counts a station once: a robot
        // program touring 40 poses would otherwise leave, by every other pose, 20 of them); then,
        // still more than half full, every other pose is kept, and every other pose offered from
        // now on.
        let stations = stations_of(&self.poses);
        if !stations.distinct() {
            let first = stations.first_poses();
            self.keep(&first);
        }
        if self.poses.len() > SAMPLE / 2 {
            let every_other: Vec<usize> = (0..self.poses.len()).step_by(2).collect();
            self.keep(&every_other);
            self.stride *= 2;
        }
    }

    /// Keeps the sampled poses `kept` (increasing indices) and their joint angles, in place.
    fn keep(&mut self, kept: &[usize]) {
        let joints = self
            .dim
            .filter(|d| *d > 0 && self.joints.len() == d * self.poses.len());
        for (to, &from) in kept.iter().enumerate() {
            self.poses[to] = self.poses[from];
            if let Some(d) = joints {
                self.joints.copy_within(from * d..(from + 1) * d, to * d);
            }
        }
        self.poses.truncate(kept.len());
        if let Some(d) = joints {
            self.joints.truncate(kept.len() * d);
        }
    }

    /// Whether a test is due: at the end when poses came since the last one or its flag is
    /// unconfirmed (the end's test has the last word), else when the segment has doubled since it.
    pub(super) fn due(&self, at_end: bool) -> bool {
        let unconfirmed = self
            .found
            .as_ref()
            .is_some_and(|f| f.systematic.unconfirmed);
        self.seen >= self.next
            || (at_end
                && (self.seen > self.tested || unconfirmed)
                && self.seen >= crate::check::systematic::MIN_POSES)
    }

    /// Runs the test on the sample under `x` (the segment's estimate), as the batch does
    /// (`calibrate::pipeline`): X of each half and of each region replicate solved by all pairs of
    /// their poses, as the tracker solves the whole.
    ///
    /// With the robot's DH table (`model`), the test has the table's statistic as the batch's
    /// `--robot-model`, where the table is the robot's (`check::identification::check_model` on
    /// the sample): otherwise the test runs without it and the reason is returned.
    pub(super) fn test(
        &mut self,
        setup: Setup,
        x: &Transform,
        at_end: bool,
        model: Option<&Kinematics>,
    ) -> Option<String> {
        self.tested = self.seen;
        self.next = 2 * self.seen.max(1);
        let poses = &self.poses;
        let n = poses.len();
        let joints: Vec<Vec<f64>> = match self.dim {
            Some(d) if d > 0 && self.joints.len() == d * n => {
                self.joints.chunks(d).map(<[f64]>::to_vec).collect()
            }
            _ => Vec::new(),
        };
        let kept: Vec<usize> = (0..n).collect();
        let scene = translation_scale(poses, setup).max(working_distance(poses));
        let solve = |p: &[PosePair]| all_pairs(p, setup);
        let refused = model.and_then(|m| check_model(m, poses, &joints).err());
        let found = systematic_test(
            (poses, setup, x),
            (
                &joints,
                &kept,
                if joints.is_empty() { usize::MAX } else { n },
            ),
            model.filter(|_| refused.is_none()),
            false,
            &solve,
            scene,
        )
        .ok();
        // Confirmation (module documentation): a flag before the end stands when the previous
        // test flagged too; the end's stands alone.
        let confirmed = at_end || self.below;
        self.below = found.as_ref().is_some_and(|s| s.flagged);
        self.found = found.map(|mut systematic| {
            if systematic.flagged && !confirmed {
                systematic.flagged = false;
                systematic.unconfirmed = true;
            }
            let regions = systematic.flagged.then(|| {
                bootstrap_by_region(
                    poses,
                    setup,
                    x,
                    &solve,
                    (REPLICATES, scene),
                    &systematic.order,
                )
            });
            Finding {
                systematic,
                regions,
                scene,
            }
        });
        refused
    }

    /// The estimate widened as the batch widens a flagged test's uncertainty
    /// ([`crate::check::systematic::widened_for_systematic`]: the region bootstrap where it is the
    /// wider, at least the halves' disagreement), with the warning; unchanged and `None`
    /// otherwise.
    pub(super) fn widen(&self, estimate: &mut TrackEstimate) -> Option<Warning> {
        let found = self.found.as_ref()?;
        let regions = found
            .regions
            .as_ref()
            .filter(|_| found.systematic.flagged)?;
        let c = estimate.covariance?;
        let ordinary = summarise(Matrix6::from_fn(|i, j| c[i][j]), 0, 0, found.scene);
        let wide = widen_by(
            ordinary,
            regions,
            &found.systematic,
            &estimate.x,
            found.scene,
        );
        estimate.uncertainty_rotation_deg = Some(wide.rotation_deg);
        estimate.uncertainty_translation = Some(wide.translation);
        estimate.covariance = Some(wide.covariance);
        if let Some((point, _)) = estimate.at_point {
            estimate.at_point = Some((point, wide.place(&estimate.x, point).sigma));
        }
        Some(systematic_warning(&found.systematic, &wide))
    }

    /// A report's uncertainty made at least the batch's on the segment's poses (the bootstrap of
    /// `calibrate`: runs of consecutive stations share one sign, as long as the residuals'
    /// correlation), while the sample holds every robot pose of the segment (up to [`SAMPLE`]).
    /// On a dense stream the poses of a short segment are a slow path through one part of the
    /// workspace: their errors are correlated in time, the halves agree with each other and are
    /// both off, and the first-order covariance (independent poses) is many times too small
    /// (ethz-asl's simulation, each robot pose once: 1.6° off at 134 poses with a sigma of 0.19°,
    /// where `calibrate` on the same poses gives 1.62°). Later, with the sample thinned, the
    /// drift term watches the estimate.
    pub(super) fn at_least_batch(&self, setup: Setup, scene: f64, estimate: &mut TrackEstimate) {
        if self.stride > 1 || self.poses.len() < crate::check::systematic::MIN_POSES {
            return;
        }
        let (Some(c), Some(ur), Some(ut)) = (
            estimate.covariance,
            estimate.uncertainty_rotation_deg,
            estimate.uncertainty_translation,
        ) else {
            return;
        };
        let poses = &self.poses;
        let solve = |p: &[PosePair]| all_pairs(p, setup);
        let batch = bootstrap(poses, setup, &estimate.x, &solve, REPLICATES, scene);
        let at_least = |a: f64, b: f64| {
            if b > 0.0 && a > b && a.is_finite() {
                a / b
            } else {
                1.0
            }
        };
        let (sr, st) = (
            at_least(batch.rotation_deg, ur),
            at_least(batch.translation, ut),
        );
        if sr == 1.0 && st == 1.0 {
            return;
        }
        // The covariance's rotation and translation blocks scaled until each size is at least
        // the batch's (D C D, D = diag(sr, sr, sr, st, st, st): the correlations kept).
        let d = |i: usize| if i < 3 { sr } else { st };
        let wide = Matrix6::from_fn(|i, j| c[i][j] * d(i) * d(j));
        estimate.covariance = Some(std::array::from_fn(|i| {
            std::array::from_fn(|j| wide[(i, j)])
        }));
        estimate.uncertainty_rotation_deg = Some(ur * sr);
        estimate.uncertainty_translation = Some(ut * st);
        if let Some((point, _)) = estimate.at_point {
            estimate.at_point = Some((point, point_sigma(&wide, &estimate.x, point)));
        }
    }

    /// The scene's size as `calibrate` measures it (the larger of the hand positions' median
    /// spread and the camera's median distance from the target) on the sample, or `None` while
    /// it is empty.
    pub(super) fn scene(&self, setup: Setup) -> Option<f64> {
        (!self.poses.is_empty())
            .then(|| translation_scale(&self.poses, setup).max(working_distance(&self.poses)))
    }
}

/// One online test step on `poses` (at most `SAMPLE` are kept, as the tracker keeps them) under
/// `x`: the systematic-error test with the halves' solves and, flagged, the region bootstrap, as
/// at the end of a stream (the crate's benches time it).
pub fn test_step(poses: &[PosePair], setup: Setup, x: &Transform) -> Option<Systematic> {
    let mut watch = Watch::default();
    poses.iter().for_each(|p| watch.add(p, None));
    watch.test(setup, x, true, None);
    watch.found.map(|f| f.systematic)
}

/// X from every pair of `poses` (the tracker's own solve), for the halves and the replicates.
fn all_pairs(poses: &[PosePair], setup: Setup) -> Result<Transform> {
    let mut sums = PoseAccumulator::new(setup);
    poses.iter().for_each(|p| sums.add(p));
    sums.estimate().map(|e| e.x).ok_or(Error::Degenerate {
        reason: Degeneracy::IllConditioned,
        conditioning: 0.0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_ring_gives_back_what_it_kept_and_nothing_else() {
        let mut ring = JointRing::default();
        ring.put(1, &[0.1, 0.2]);
        ring.put(2, &[0.3]);
        assert_eq!(ring.get(1), Some(&[0.1, 0.2][..]));
        assert_eq!(ring.get(2), None, "a list of another length is not kept");
        assert_eq!(ring.get(1 + JOINT_RING), None);
        ring.put(1 + JOINT_RING, &[0.5, 0.6]);
        assert_eq!(ring.get(1), None, "overwritten");
        assert_eq!(ring.get(1 + JOINT_RING), Some(&[0.5, 0.6][..]));
    }

    #[test]
    fn the_sample_is_bounded_and_keeps_the_joints_in_step() {
        let pose = PosePair {
            base_from_gripper: Transform::identity(),
            camera_from_target: Transform::identity(),
        };
        let mut w = Watch::default();
        for i in 0..5000 {
            w.add(&pose, Some(&[i as f64, -(i as f64)]));
        }
        assert!(w.poses.len() < SAMPLE && w.poses.len() >= SAMPLE / 2);
        assert_eq!(w.joints.len(), 2 * w.poses.len());
        // Every kept pose's angles are of one pose, every stride-th offered.
        let stride = w.stride as f64;
        assert!(w.joints.chunks(2).all(|q| q[0] == -q[1]));
        assert!(
            w.joints.chunks(2).all(|q| (q[0] / stride).fract() == 0.0),
            "{stride}"
        );
        // A sampled pose without angles: the test orders by the hand pose (one the sample skips
        // changes nothing).
        for _ in 0..w.stride {
            w.add(&pose, None);
        }
        assert_eq!(w.dim, Some(0));
        assert!(w.joints.is_empty());
    }
}
