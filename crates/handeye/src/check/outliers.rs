//! Per-pose consistency: how well each pose agrees with the others, before and after solving.
//!
//! A rigid X and a fixed target make every pose tell the same story. Two tests follow from it, both
//! per *pose* (not per motion), so that a bad pose is named once with its place and the all-pairs
//! solve keeps O(n) memory:
//!
//! - [`pose_outliers`], before any solve: the rotation angle θ and the pitch k·t (translation along
//!   the rotation axis) of a motion are invariant under A = X B X⁻¹, so for every motion of a good
//!   pose to other good poses θ_A = θ_B and k_A·t_A = k_B·t_B up to noise, whatever X is. A pose
//!   whose motions to most other poses break this is an outlier (a bad detection, a flipped target
//!   pose, a typo).
//! - [`PoseResiduals`], given X: each pose's own estimate of the fixed frame,
//!   Y_i = Q_i X P_i⁻¹ (`base_from_target` eye-in-hand, `gripper_from_target` eye-to-hand); A X = X B
//!   for every pair of poses is the statement that all Y_i are equal (A X = Y B), so
//!   D_i = Y⁻¹ Y_i is the pose's own error, in the target frame.

use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

use crate::check::precision::resolution;
use crate::model::motion::{MotionFeatures, MotionPair, PosePair, Setup};
use crate::model::pose::{Transform, axis_angle, exp_so3, proj_so3, transform_from_parts};
use crate::solve::residual::PoseResidual;

/// Partners each pose is compared with in [`pose_outliers`] (all others when there are fewer).
const PARTNERS: usize = 32;

/// A pose is an outlier when its median gap is above this many times the median over all poses.
pub(crate) const OUTLIER_FACTOR: f64 = 6.0;

/// Motions whose gripper rotation is below this angle (radians, 3°) have too noisy an axis for the
/// pitch test; their pitch gap is not used.
const PITCH_MIN_ANGLE: f64 = 3.0 * std::f64::consts::PI / 180.0;

/// The screw-invariant gaps of one pose: medians over its motions to the partner poses.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PoseGap {
    /// Index of the pose in the input.
    pub pose: usize,
    /// Median |θ_A − θ_B| over its motions, degrees.
    pub angle_gap_deg: f64,
    /// Median |k_A·t_A − k_B·t_B| over its motions, input length units.
    pub pitch_gap: f64,
}

/// The poses that disagree with the others, and the noise level they were judged against.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PoseOutliers {
    /// The outlier poses, in input order.
    pub poses: Vec<PoseGap>,
    /// Median over all poses of the angle gap, degrees: the data's own noise level.
    pub typical_angle_gap_deg: f64,
    /// Median over all poses of the pitch gap, input length units.
    pub typical_pitch_gap: f64,
    /// Angle gap above which a pose is an outlier, degrees.
    pub angle_threshold_deg: f64,
    /// Pitch gap above which a pose is an outlier, input length units.
    pub pitch_threshold: f64,
}

impl PoseOutliers {
    /// The indices of the outlier poses.
    pub fn indices(&self) -> Vec<usize> {
        self.poses.iter().map(|g| g.pose).collect()
    }
}

/// Finds the poses whose motions to the others break the screw invariants (module docs).
///
/// Each pose is compared with up to 32 partners spread over the sequence (O(n) work). A pose is
/// an outlier when its median angle gap is above `max(min_angle_gap_deg, 6 × typical)` or its
/// median pitch gap above `6 × typical` (typical: the median over all poses, floored at the data's
/// numerical precision, [`crate::check::precision::resolution`] of the motions' translation scale,
/// so that noise-free data has no outliers).
pub fn pose_outliers(poses: &[PosePair], setup: Setup, min_angle_gap_deg: f64) -> PoseOutliers {
    let gaps = pose_gaps(poses, setup);
    let typical_angle = median(gaps.iter().map(|g| g.angle_gap_deg).collect());
    let typical_pitch = median(gaps.iter().map(|g| g.pitch_gap).collect());
    let scale = translation_scale(poses, setup);
    let angle_threshold_deg = (OUTLIER_FACTOR * typical_angle).max(min_angle_gap_deg);
    let pitch_threshold = OUTLIER_FACTOR * typical_pitch.max(resolution(scale));
    PoseOutliers {
        poses: gaps
            .into_iter()
            .filter(|g| g.angle_gap_deg > angle_threshold_deg || g.pitch_gap > pitch_threshold)
            .collect(),
        typical_angle_gap_deg: typical_angle,
        typical_pitch_gap: typical_pitch,
        angle_threshold_deg,
        pitch_threshold,
    }
}

/// Every pose's gaps against its partners. When every other pose is a partner (at most
/// `PARTNERS + 1` poses), the motion between two poses serves both: its gaps are made once, for
/// half the work (the reversed motion has the same angles and |pitch|, to rounding).
fn pose_gaps(poses: &[PosePair], setup: Setup) -> Vec<PoseGap> {
    let n = poses.len();
    if n > PARTNERS + 1 {
        return (0..n).map(|i| pose_gap(poses, setup, i)).collect();
    }
    let mut pairs = vec![(0.0, None); n * n];
    for i in 0..n {
        for j in i + 1..n {
            let gaps = motion_gaps(setup, &poses[j], &poses[i]);
            pairs[i * n + j] = gaps;
            pairs[j * n + i] = gaps;
        }
    }
    (0..n)
        .map(|i| {
            let (angle_gap_deg, pitch_gap) =
                gap_medians((0..n).filter(|&j| j != i).map(|j| pairs[i * n + j]));
            PoseGap {
                pose: i,
                angle_gap_deg,
                pitch_gap,
            }
        })
        .collect()
}

/// The gaps of pose `i` against its partners.
fn pose_gap(poses: &[PosePair], setup: Setup, i: usize) -> PoseGap {
    let (angle_gap_deg, pitch_gap) = screw_gaps(
        setup,
        &poses[i],
        partners(poses.len(), i).map(|j| &poses[j]),
    );
    PoseGap {
        pose: i,
        angle_gap_deg,
        pitch_gap,
    }
}

/// The screw-invariant gaps of `pose` against `partners` (module documentation): the medians over
/// its motions to them of |θ_A − θ_B| (degrees) and |k_A·t_A − k_B·t_B| (input units; motions
/// below 3° left out), over the first `PARTNERS` (32) partners. The per-pose test of the batch
/// ([`pose_outliers`]) and of the online tracker ([`crate::tracking`]) alike; it allocates
/// nothing (the tracker runs it on every pose).
pub(crate) fn screw_gaps<'a>(
    setup: Setup,
    pose: &PosePair,
    partners: impl Iterator<Item = &'a PosePair>,
) -> (f64, f64) {
    gap_medians(partners.map(|partner| motion_gaps(setup, partner, pose)))
}

/// The medians of the first [`PARTNERS`] motions' angle gaps and of their pitch gaps (where a
/// motion has one), with no allocation.
fn gap_medians(gaps: impl Iterator<Item = (f64, Option<f64>)>) -> (f64, f64) {
    let (mut angle, mut pitch) = ([0.0; PARTNERS], [0.0; PARTNERS]);
    let (mut na, mut np) = (0, 0);
    for (angle_gap, pitch_gap) in gaps.take(PARTNERS) {
        angle[na] = angle_gap;
        na += 1;
        if let Some(gap) = pitch_gap {
            pitch[np] = gap;
            np += 1;
        }
    }
    (median_in(&mut angle[..na]), median_in(&mut pitch[..np]))
}

/// The gaps of the motion from `partner` to `pose`: |θ_A − θ_B| (degrees) and, when the motion
/// turns by more than 3° about a defined axis, |k_A·t_A − k_B·t_B|.
fn motion_gaps(setup: Setup, partner: &PosePair, pose: &PosePair) -> (f64, Option<f64>) {
    let m = MotionPair::between(setup, partner, pose);
    let (a, b) = (MotionFeatures::of(&m.a), MotionFeatures::of(&m.b));
    let angle = (a.angle - b.angle).abs().to_degrees();
    let pitch = match (a.axis, b.axis) {
        (Some(ka), Some(kb)) if a.angle > PITCH_MIN_ANGLE => {
            // Near π the axis sign is arbitrary, so compare |pitch|.
            let pa = ka.dot(&m.a.translation.vector).abs();
            let pb = kb.dot(&m.b.translation.vector).abs();
            Some((pa - pb).abs())
        }
        _ => None,
    };
    (angle, pitch)
}

/// Up to [`PARTNERS`] other poses spread evenly over the sequence, starting at an offset that
/// depends on `i` so that neighbours do not all share the same partners.
fn partners(n: usize, i: usize) -> impl Iterator<Item = usize> {
    let others = n.saturating_sub(1);
    let take = others.min(PARTNERS);
    let step = others.checked_div(take).unwrap_or(1);
    (0..take).map(move |k| (i + 1 + (k * step + i % step.max(1)) % others.max(1)) % n)
}

/// How far the gripper's rotation axes spread beyond one direction, X-free: the second-largest over
/// the largest eigenvalue of Σ (1 − cos θ) k kᵀ over the gripper's motions between every pair of
/// poses (motions between distant poses are large, so noise hardly moves their axes; the weight
/// 1 − cos θ = 2 sin²(θ/2) weighs down the small ones whose axes noise does move). Near 0 when
/// every rotation is about one axis: then X's rotation about that axis, and its translation along
/// it, are not determined by any reading of the input.
///
/// O(n), with no trigonometry: for the motion M = R_iᵀ R_j, (M + Mᵀ)/2 = cos θ I + (1 − cos θ) k kᵀ
/// and tr M = 1 + 2 cos θ, both linear in M, and with U = Σ R_k the pairs sum to
/// Σ_{i<j} (M + Mᵀ)/2 = (UᵀU − n I)/2. (The weight θ² of an earlier, O(n²) form moves the ratio
/// by at most π²/4; on the repository's realistic suite and real data the two agree within a
/// factor 0.93–1.40: degenerate series ≤ 6.5e-6, the others ≥ 1.8e-2.)
pub fn axis_scatter(poses: &[PosePair], setup: Setup) -> f64 {
    gripper_rotations(poses, setup).scatter
}

/// What the gripper's rotations between the poses show: their [`axis_scatter`] and how large
/// they are.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct GripperRotations {
    /// [`axis_scatter`].
    pub scatter: f64,
    /// The largest rotation angle from the first pose to another, radians: at least half the
    /// largest between any two (the angles obey the triangle inequality).
    pub widest_from_first: f64,
}

/// [`axis_scatter`] and the widest rotation from the first pose, in one O(n) pass.
pub(crate) fn gripper_rotations(poses: &[PosePair], setup: Setup) -> GripperRotations {
    let Some(first) = poses.first() else {
        return GripperRotations {
            scatter: 0.0,
            widest_from_first: 0.0,
        };
    };
    let r_0 = *setup.hand_pose(&first.base_from_gripper).rotation.matrix();
    let mut u = Matrix3::zeros();
    let mut widest = Matrix3::identity();
    for p in poses {
        let r = *setup.hand_pose(&p.base_from_gripper).rotation.matrix();
        u += r;
        let m = r_0.transpose() * r;
        if m.trace() < widest.trace() {
            widest = m;
        }
    }
    let n = poses.len() as f64;
    let pairs = n * (n - 1.0) / 2.0;
    // Σ (M + Mᵀ)/2 − Σ cos θ I, with Σ cos θ = (tr Σ M − pairs)/2.
    let sym = (u.transpose() * u - Matrix3::identity() * n) * 0.5;
    let scatter = sym - Matrix3::identity() * ((sym.trace() - pairs) * 0.5);
    let mut e: Vec<f64> = scatter.symmetric_eigenvalues().iter().copied().collect();
    e.sort_by(|a, b| b.total_cmp(a));
    GripperRotations {
        scatter: if e[0] <= 0.0 {
            0.0
        } else {
            e[1].max(0.0) / e[0]
        },
        widest_from_first: axis_angle(&widest).0,
    }
}

/// Median of the values (upper middle), 0 for none.
pub(crate) fn median(mut v: Vec<f64>) -> f64 {
    median_in(&mut v)
}

/// [`median`] in place, reordering the slice.
pub(crate) fn median_in(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    let mid = v.len() / 2;
    *v.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// Median distance from the camera to the target, input units.
pub(crate) fn working_distance(poses: &[PosePair]) -> f64 {
    median(
        poses
            .iter()
            .map(|p| p.camera_from_target.translation.vector.norm())
            .collect(),
    )
}

/// The length scale of the scene, in the robot's unit: the median distance of the hand positions
/// from their coordinate-wise median (robust, so that one mistyped pose does not set it).
pub(crate) fn translation_scale(poses: &[PosePair], setup: Setup) -> f64 {
    let hand: Vec<Vector3<f64>> = poses
        .iter()
        .map(|p| setup.hand_pose(&p.base_from_gripper).translation.vector)
        .collect();
    let centre = Vector3::from_fn(|k, _| median(hand.iter().map(|v| v[k]).collect()));
    median(hand.iter().map(|v| (v - centre).norm()).collect())
}

/// Each pose's disagreement D_i = Y⁻¹ Y_i with the common fixed frame Y under a given X.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseResiduals {
    /// The common frame Y (`base_from_target` eye-in-hand, `gripper_from_target` eye-to-hand):
    /// a robust mean of the Y_i.
    pub y: Transform,
    /// D_i per pose, in the target frame.
    pub residuals: Vec<PoseResidual>,
}

impl PoseResiduals {
    /// The residuals of `poses` under `x`. Y is the chordal mean of the Y_i, recomputed twice with
    /// the poses more than 5× the median residual away left out, so a few bad poses do not move it.
    pub fn at(poses: &[PosePair], setup: Setup, x: &Transform) -> Self {
        let ys: Vec<Transform> = poses
            .iter()
            .map(|p| setup.hand_pose(&p.base_from_gripper) * x * p.camera_from_target)
            .collect();
        let mut y = mean_of(ys.iter()).unwrap_or_else(Transform::identity);
        for _ in 0..2 {
            let d: Vec<_> = ys.iter().map(|yi| residual(&y, yi)).collect();
            let limit_r = 5.0 * median(d.iter().map(|r| r.rotation.norm()).collect());
            let limit_t = 5.0 * median(d.iter().map(PoseResidual::distance).collect());
            let kept = ys
                .iter()
                .zip(&d)
                .filter(|(_, r)| r.rotation.norm() <= limit_r && r.distance() <= limit_t)
                .map(|(yi, _)| yi);
            if let Some(mean) = mean_of(kept) {
                y = mean;
            }
        }
        Self {
            residuals: ys.iter().map(|yi| residual(&y, yi)).collect(),
            y,
        }
    }

    /// Median rotation residual, degrees.
    pub fn median_rotation_deg(&self) -> f64 {
        median(self.residuals.iter().map(|r| r.rotation.norm()).collect()).to_degrees()
    }

    /// Median translation residual, input units.
    pub fn median_translation(&self) -> f64 {
        median(self.residuals.iter().map(PoseResidual::distance).collect())
    }

    /// The pose `camera_from_target` that agrees exactly with X and Y, with the residual
    /// `(rotation, translation)` applied on the target side: X⁻¹ Q⁻¹ Y · D.
    pub(crate) fn camera_from_target_with(
        &self,
        pose: &PosePair,
        setup: Setup,
        x: &Transform,
        rotation: &Vector3<f64>,
        translation: &Vector3<f64>,
    ) -> Transform {
        let consistent = x.inverse() * setup.hand_pose(&pose.base_from_gripper).inverse() * self.y;
        consistent * transform_from_parts(&exp_so3(rotation), translation)
    }
}

/// D = Y⁻¹ Y_i.
fn residual(y: &Transform, yi: &Transform) -> PoseResidual {
    let d = y.inverse() * yi;
    PoseResidual::new(d.rotation.matrix(), d.translation.vector)
}

/// Chordal mean: the rotation nearest to the summed rotation matrices, the mean translation.
fn mean_of<'a>(ys: impl Iterator<Item = &'a Transform>) -> Option<Transform> {
    let (mut r, mut t, mut n) = (Matrix3::zeros(), Vector3::zeros(), 0usize);
    for y in ys {
        r += y.rotation.matrix();
        t += y.translation.vector;
        n += 1;
    }
    (n > 0).then(|| transform_from_parts(&proj_so3(&r), &(t / n as f64)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::{SimConfig, simulate};
    use crate::solve::accumulate::PoseAccumulator;

    fn noisy(seed: u64) -> (Vec<PosePair>, Transform) {
        let s = simulate(&SimConfig::default(), seed, 0);
        (s.poses, s.gripper_from_camera)
    }

    #[test]
    fn partners_are_other_poses_spread_over_the_sequence() {
        for n in [2, 3, 10, 33, 34, 100, 1000] {
            for i in [0, 1, n / 2, n - 1] {
                let p: Vec<_> = partners(n, i).collect();
                assert_eq!(p.len(), (n - 1).min(PARTNERS), "n {n} i {i}");
                assert!(p.iter().all(|&j| j != i && j < n), "n {n} i {i}: {p:?}");
                let mut unique = p.clone();
                unique.sort_unstable();
                unique.dedup();
                assert_eq!(unique.len(), p.len(), "n {n} i {i}: {p:?}");
            }
        }
    }

    #[test]
    fn a_replaced_pose_is_the_only_outlier() {
        for seed in 0..5 {
            let (mut poses, _) = noisy(seed);
            assert!(
                pose_outliers(&poses, Setup::EyeInHand, 3.0)
                    .poses
                    .is_empty(),
                "seed {seed}"
            );
            let bad = 17;
            poses[bad].camera_from_target =
                Transform::new(Vector3::new(0.1, 0.2, 0.3), Vector3::new(0.3, -0.2, 0.1))
                    * poses[bad].camera_from_target;
            let found = pose_outliers(&poses, Setup::EyeInHand, 3.0);
            assert_eq!(found.indices(), vec![bad], "seed {seed}: {found:?}");
        }
    }

    #[test]
    fn a_translation_typo_is_found_by_its_pitch() {
        let (mut poses, _) = noisy(1);
        poses[5].base_from_gripper.translation.vector.x *= 1000.0;
        assert_eq!(
            pose_outliers(&poses, Setup::EyeInHand, 3.0).indices(),
            vec![5]
        );
    }

    #[test]
    fn residuals_vanish_under_the_true_x_without_noise() {
        let s = simulate(&SimConfig::default().noise_free(), 2, 0);
        // The same poses as eye-to-hand data: Q = gripper_from_base enters as the inverse.
        let eye_to_hand: Vec<PosePair> = s
            .poses
            .iter()
            .map(|p| PosePair {
                base_from_gripper: p.base_from_gripper.inverse(),
                camera_from_target: p.camera_from_target,
            })
            .collect();
        for (setup, poses) in [
            (Setup::EyeInHand, &s.poses),
            (Setup::EyeToHand, &eye_to_hand),
        ] {
            let r = PoseResiduals::at(poses, setup, &s.gripper_from_camera);
            assert!(
                r.median_rotation_deg() < 1e-10,
                "{}",
                r.median_rotation_deg()
            );
            assert!(r.median_translation() < 1e-10, "{}", r.median_translation());
            let rebuilt = r.camera_from_target_with(
                &poses[3],
                setup,
                &s.gripper_from_camera,
                &r.residuals[3].rotation,
                &r.residuals[3].translation,
            );
            let diff = rebuilt.to_homogeneous() - s.poses[3].camera_from_target.to_homogeneous();
            assert!(diff.norm() < 1e-10, "{diff}");
        }
    }

    /// The accumulator's closed-form scatter (`solve::accumulate`) against the poses' own
    /// residuals, and its mean frame against [`PoseResiduals`]'.
    #[test]
    fn the_scatter_in_closed_form_equals_the_poses_own_residuals() {
        let s = simulate(&SimConfig::default(), 4, 0);
        let eye_to_hand: Vec<PosePair> = s
            .poses
            .iter()
            .map(|p| PosePair {
                base_from_gripper: p.base_from_gripper.inverse(),
                camera_from_target: p.camera_from_target,
            })
            .collect();
        for (setup, poses) in [
            (Setup::EyeInHand, &s.poses),
            (Setup::EyeToHand, &eye_to_hand),
        ] {
            let mut acc = PoseAccumulator::new(setup);
            poses.iter().for_each(|p| acc.add(p));
            // Any X, not only the fitted one: the sums are exact for every X.
            let x = s.gripper_from_camera
                * Transform::new(
                    Vector3::new(3.0, -2.0, 1.0),
                    Vector3::new(0.01, 0.02, -0.01),
                );
            let got = acc.residual_scatter(&x).unwrap();
            let ys: Vec<Transform> = poses
                .iter()
                .map(|p| setup.hand_pose(&p.base_from_gripper) * x * p.camera_from_target)
                .collect();
            let n = ys.len() as f64;
            let mean_t = ys
                .iter()
                .map(|y| y.translation.vector)
                .sum::<Vector3<f64>>()
                / n;
            let sum_r: Matrix3<f64> = ys.iter().map(|y| *y.rotation.matrix()).sum();
            let r_y = crate::model::pose::proj_so3(&sum_r);
            let rms_t = (ys
                .iter()
                .map(|y| (y.translation.vector - mean_t).norm_squared())
                .sum::<f64>()
                / n)
                .sqrt();
            let rms_r = (ys
                .iter()
                .map(|y| (y.rotation.matrix() - r_y).norm_squared() / 2.0)
                .sum::<f64>()
                / n)
                .sqrt();
            assert!(
                (got.translation - rms_t).abs() <= 1e-9 * rms_t,
                "{setup:?}: {} {rms_t}",
                got.translation
            );
            assert!(
                (got.rotation - rms_r).abs() <= 1e-9 * rms_r,
                "{setup:?}: {} {rms_r}",
                got.rotation
            );
            assert!((got.y.translation.vector - mean_t).norm() <= 1e-9 * mean_t.norm());
            // Under the true X the mean frame is the one PoseResiduals finds, up to the noise.
            let fitted = acc.residual_scatter(&s.gripper_from_camera).unwrap();
            let robust = PoseResiduals::at(poses, setup, &s.gripper_from_camera);
            let d = fitted.y.inverse() * robust.y;
            assert!(
                d.rotation.angle() < 1e-3 && d.translation.vector.norm() < 1.0,
                "{d:?}"
            );
        }
    }
}
