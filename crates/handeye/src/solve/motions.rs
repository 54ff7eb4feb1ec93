//! Motion sources: the motion pairs a solver goes through, stored ([`MotionPair`] slices) or made
//! on the fly from every pair of poses ([`AllPairs`], O(n) memory, with the per-pose sums that let
//! the solvers work in O(n)).

use std::sync::OnceLock;
use std::sync::atomic::{AtomicU64, Ordering};

use nalgebra::{Matrix3, SVector, Vector3};

use crate::model::motion::{MotionFeatures, MotionPair, Pairing, PosePair, Setup};
use crate::model::pose::{Transform, rotation_matrix};
use crate::solve::accumulate::PairSums;
use crate::solve::rotation_system::StackedRows;

/// Pairs of poses gone through one by one so far in this process ([`pair_work`]).
static PAIR_WORK: AtomicU64 = AtomicU64::new(0);

/// Counts `n` pairs of poses gone through one by one.
pub(crate) fn count_pairs(n: usize) {
    PAIR_WORK.fetch_add(n as u64, Ordering::Relaxed);
}

/// The pairs of poses gone through one by one so far in this process, on every thread: every
/// motion [`AllPairs`] made on the fly, and every pair the checks visited pair by pair (the quality
/// check's pass over the pairs, the low-DOF check's witnesses). The solvers and checks that work
/// from per-pose sums add nothing. For tests that show the work of a calibration linear in the
/// poses (ten times the poses, about ten times the pairs, where every pair would be a hundred).
pub fn pair_work() -> u64 {
    PAIR_WORK.load(Ordering::Relaxed)
}

/// A set of motion pairs that the solvers can go through as often as they need, without
/// necessarily storing them: a slice of [`MotionPair`]s, or [`AllPairs`], which makes the
/// n(n − 1)/2 motions of every pose pair on the fly in constant memory.
pub trait MotionSource {
    /// Number of motion pairs.
    fn count(&self) -> usize;

    /// Calls `f` on every motion pair, in order.
    fn for_each_motion(&self, f: impl FnMut(&MotionPair));

    /// The poses behind the motions when they are every pair of a pose sequence ([`AllPairs`]):
    /// the solvers and the quality report then work from per-pose sums in O(n) instead of going
    /// through the n(n − 1)/2 motions. `None` by default.
    fn all_pairs(&self) -> Option<&AllPairs> {
        None
    }
}

impl MotionSource for [MotionPair] {
    fn count(&self) -> usize {
        self.len()
    }

    fn for_each_motion(&self, f: impl FnMut(&MotionPair)) {
        self.iter().for_each(f);
    }
}

impl MotionSource for Vec<MotionPair> {
    fn count(&self) -> usize {
        self.len()
    }

    fn for_each_motion(&self, f: impl FnMut(&MotionPair)) {
        self.iter().for_each(f);
    }
}

impl<const N: usize> MotionSource for [MotionPair; N] {
    fn count(&self) -> usize {
        N
    }

    fn for_each_motion(&self, f: impl FnMut(&MotionPair)) {
        self.iter().for_each(f);
    }
}

/// `Σ_k K_kᵀ K_k v` evaluated row block by row block: with V the 3×3 matrix of v (row-major),
/// `K v = vec(V − R_a V R_bᵀ)` and `Kᵀ w = vec(W − R_aᵀ W R_b)`.
impl<M: MotionSource + ?Sized> StackedRows for M {
    fn stacked_gradient(&self, v: &SVector<f64, 9>) -> SVector<f64, 9> {
        let motions = self;
        let v_m = Matrix3::new(v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8]);
        let g = match motions.all_pairs() {
            // Over all pairs of poses, from per-pose deviations in O(n).
            Some(pairs) => pairs.rotation_gradient(&v_m),
            None => {
                let mut g = Matrix3::zeros();
                motions.for_each_motion(|m| {
                    let r_a = rotation_matrix(&m.a);
                    let r_b = rotation_matrix(&m.b);
                    let w = v_m - r_a * v_m * r_b.transpose();
                    g += w - r_a.transpose() * w * r_b;
                });
                g
            }
        };
        SVector::<f64, 9>::from_row_slice(&[
            g[(0, 0)],
            g[(0, 1)],
            g[(0, 2)],
            g[(1, 0)],
            g[(1, 1)],
            g[(1, 2)],
            g[(2, 0)],
            g[(2, 1)],
            g[(2, 2)],
        ])
    }
}

/// The motions of every pose pair i < j ([`Pairing::All`], built as OpenCV builds them), made on
/// the fly: memory O(n) instead of O(n²), the same motions in the same order as
/// `motion_pairs(poses, Pairing::All, setup)`.
#[derive(Debug, Clone)]
pub struct AllPairs {
    /// Q_k and Q_k⁻¹ of each pose.
    hand: Vec<(Transform, Transform)>,
    /// P_k⁻¹ = `camera_from_target` and P_k of each pose.
    camera: Vec<(Transform, Transform)>,
    /// The all-pairs sums, made on first use.
    sums: OnceLock<PairSums>,
}

impl AllPairs {
    /// The all-pairs motions of `poses`.
    pub fn new(poses: &[PosePair], setup: Setup) -> Self {
        Self {
            hand: poses
                .iter()
                .map(|p| {
                    let q = setup.hand_pose(&p.base_from_gripper);
                    (q, q.inverse())
                })
                .collect(),
            camera: poses
                .iter()
                .map(|p| (p.camera_from_target, p.camera_from_target.inverse()))
                .collect(),
            sums: OnceLock::new(),
        }
    }

    /// Number of poses.
    pub fn poses(&self) -> usize {
        self.hand.len()
    }

    /// The motion of the pair (i, j), i < j, exactly as [`MotionSource::for_each_motion`] makes
    /// it: from pose j to pose i, A = Q_j⁻¹ Q_i, B = P_j⁻¹ P_i.
    #[inline(always)]
    pub(crate) fn motion(&self, i: usize, j: usize) -> MotionPair {
        MotionPair {
            a: self.hand[j].1 * self.hand[i].0,
            b: self.camera[j].0 * self.camera[i].1,
        }
    }

    /// Q_k (the setup's hand pose, [`Setup::hand_pose`]) and C_k = `camera_from_target` of pose k.
    pub(crate) fn pose(&self, k: usize) -> (&Transform, &Transform) {
        (&self.hand[k].0, &self.camera[k].0)
    }

    /// The sums over all pairs (computed once, O(n)).
    pub(crate) fn sums(&self) -> &PairSums {
        self.sums.get_or_init(|| {
            let hand: Vec<Transform> = self.hand.iter().map(|h| h.0).collect();
            let camera: Vec<Transform> = self.camera.iter().map(|c| c.0).collect();
            PairSums::new(&hand, &camera)
        })
    }
}

impl AllPairs {
    /// `Σ_{i<j} K_ijᵀ K_ij v` of Andreff's rotation system over every pair, in O(n)
    /// (`solve::residual::pairs_rotation_gradient`): the Newton step of the rotation solve.
    pub(crate) fn rotation_gradient(&self, v: &Matrix3<f64>) -> Matrix3<f64> {
        crate::solve::residual::pairs_rotation_gradient(self, v)
    }
}

impl MotionSource for AllPairs {
    fn count(&self) -> usize {
        Pairing::All.motion_count(self.hand.len())
    }

    fn for_each_motion(&self, mut f: impl FnMut(&MotionPair)) {
        count_pairs(self.count());
        for i in 0..self.hand.len() {
            for j in i + 1..self.hand.len() {
                f(&self.motion(i, j));
            }
        }
    }

    fn all_pairs(&self) -> Option<&AllPairs> {
        Some(self)
    }
}

/// Largest angle between a motion axis (as a line) and the dominant axis of Σ θ² k kᵀ, radians.
pub(crate) fn axis_spread(motions: &(impl MotionSource + ?Sized)) -> f64 {
    let mut scatter = Matrix3::zeros();
    motions.for_each_motion(|m| {
        let f = MotionFeatures::of(&m.a);
        if let Some(k) = f.axis {
            scatter += k * k.transpose() * (f.angle * f.angle);
        }
    });
    let eigen = scatter.symmetric_eigen();
    let dominant: Vector3<f64> = eigen
        .eigenvectors
        .column(eigen.eigenvalues.imax())
        .into_owned();
    let mut spread = 0.0_f64;
    motions.for_each_motion(|m| {
        if let Some(k) = MotionFeatures::of(&m.a).axis {
            spread = spread.max(k.dot(&dominant).abs().min(1.0).acos());
        }
    });
    spread
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::motion::motion_pairs;
    use crate::sim::{SimConfig, simulate};

    #[test]
    fn all_pairs_on_the_fly_equal_the_stored_ones() {
        let s = simulate(
            &SimConfig {
                poses: 12,
                ..SimConfig::default()
            },
            3,
            0,
        );
        for setup in [Setup::EyeInHand, Setup::EyeToHand] {
            let stored = motion_pairs(&s.poses, Pairing::All, setup);
            let source = AllPairs::new(&s.poses, setup);
            let mut made = Vec::new();
            source.for_each_motion(|m| made.push(*m));
            assert_eq!(source.count(), stored.len());
            assert_eq!(made, stored);
            // Tsai's rotation step goes through the motions either way; its translation step and
            // the motion check come from the per-pose sums for `AllPairs`, equal up to rounding.
            let a = crate::solve::solve(crate::solve::Method::Tsai, &stored).unwrap();
            let b = crate::solve::solve(crate::solve::Method::Tsai, &source).unwrap();
            assert_eq!(a.x.rotation, b.x.rotation);
            let t = a.x.translation.vector;
            assert!((t - b.x.translation.vector).norm() < 1e-12 * t.norm());
            assert!((a.conditioning - b.conditioning).abs() < 1e-12);
            assert_eq!((a.motions, &a.warnings), (b.motions, &b.warnings));
        }
    }
}
