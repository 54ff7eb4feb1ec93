//! Robot-world sums: Shah's X and target pose at every pose of a stream in O(1) per pose
//! ([`RobotWorldAccumulator`]), as [`crate::solve::accumulate`] does for A X = X B.

use nalgebra::{Matrix3, SMatrix, Vector3};
use serde::{Deserialize, Serialize};

use crate::model::motion::{PosePair, Setup};
use crate::model::pose::{rotation_matrix, transform_from_parts};
use crate::solve::RotationSystem;
use crate::solve::accumulate::{Matrix39, kron_row};
use crate::solve::quadratic::Matrix9;

/// Running sums from which Shah's robot-world solution follows, in O(1) time and memory per pose:
/// X and the target pose at every pose, equal to the batch [`crate::solve::shah`] on the poses
/// so far (to rounding).
///
/// In OpenCV's form A_i X' = Z' B_i (A_i = C_i = `camera_from_target`, B_i = Q_i⁻¹; see
/// [`crate::solve::shah`]): K = Σ R_A ⊗ R_B gives the rotations; the translations solve the 6×6
/// normal equations of `[−R_A  I] (t_X', t_Z') = t_A − R_Z' t_B`, whose matrix is
/// `[n I, −Uᵀ; −U, n I]` with U = Σ R_A and whose right-hand side is
/// `(−Σ R_Aᵀ t_A + M vec R_Z', Σ t_A − R_Z' Σ t_B)` with M = Σ R_Aᵀ ⊗ t_Bᵀ. Degenerate data are
/// told by the all-pairs rotation system, whose normal matrix `n² I − K Kᵀ` has the eigenvalues of
/// [`PoseAccumulator`](crate::solve::accumulate::PoseAccumulator)'s (K is its S with the Kronecker factors swapped and transposed).
///
/// # Example
/// ```
/// use handeye::solve::robot_world_accumulate::RobotWorldAccumulator;
/// use handeye::sim::{SimConfig, simulate};
/// use handeye::Setup;
/// let s = simulate(&SimConfig { poses: 20, ..SimConfig::default() }, 3, 0);
/// let mut acc = RobotWorldAccumulator::new(Setup::EyeInHand);
/// s.poses.iter().for_each(|p| acc.add(p));
/// let rw = acc.estimate().expect("20 generic poses");
/// let batch = handeye::solve::shah(&s.poses, Setup::EyeInHand)?;
/// assert!((rw.x.to_homogeneous() - batch.x.to_homogeneous()).amax() < 1e-9);
/// # Ok::<(), handeye::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RobotWorldAccumulator {
    setup: Setup,
    n: usize,
    /// K = Σ R_A ⊗ R_B.
    k: Matrix9,
    /// U = Σ R_A.
    u: Matrix3<f64>,
    /// Σ R_Aᵀ t_A.
    at: Vector3<f64>,
    /// Σ t_A.
    ta: Vector3<f64>,
    /// Σ t_B.
    tb: Vector3<f64>,
    /// M = Σ R_Aᵀ ⊗ t_Bᵀ.
    m: Matrix39,
}

impl RobotWorldAccumulator {
    /// An empty accumulator for the given setup.
    pub fn new(setup: Setup) -> Self {
        Self {
            setup,
            n: 0,
            k: Matrix9::zeros(),
            u: Matrix3::zeros(),
            at: Vector3::zeros(),
            ta: Vector3::zeros(),
            tb: Vector3::zeros(),
            m: Matrix39::zeros(),
        }
    }

    /// Adds one pose pair.
    pub fn add(&mut self, pose: &PosePair) {
        let a = pose.camera_from_target;
        let b = self.setup.hand_pose(&pose.base_from_gripper).inverse();
        let (r_a, r_b) = (rotation_matrix(&a), rotation_matrix(&b));
        let (t_a, t_b) = (a.translation.vector, b.translation.vector);
        self.n += 1;
        self.k += crate::solve::robot_world::kron9(&r_a, &r_b);
        self.u += r_a;
        self.at += r_a.transpose() * t_a;
        self.ta += t_a;
        self.tb += t_b;
        self.m += kron_row(&r_a.transpose(), &t_b);
    }

    /// Poses accumulated.
    pub fn poses(&self) -> usize {
        self.n
    }

    /// Forgets every pose (after a detected change).
    pub fn reset(&mut self) {
        *self = Self::new(self.setup);
    }

    /// The current X and target pose (Shah's solution over every pose so far), with the
    /// conditioning of the all-pairs rotation system. `None` with fewer than three poses or a
    /// degenerate system.
    pub fn estimate(&self) -> Option<crate::solve::RobotWorld> {
        if self.n < 3 {
            return None;
        }
        let n = self.n as f64;
        let conditioning = RotationSystem::from_normal(
            Matrix9::identity() * (n * n) - self.k * self.k.transpose(),
            self.n * (self.n - 1) / 2,
        )
        .conditioning();
        if conditioning.is_nan() || conditioning <= crate::solve::REFUSE_CONDITIONING {
            return None;
        }
        let (r_x, r_z) = crate::solve::robot_world::shah_rotations(&self.k)?;
        let vec_z = SMatrix::<f64, 9, 1>::from_fn(|k, _| r_z[(k / 3, k % 3)]);
        let mut normal = SMatrix::<f64, 6, 6>::identity() * n;
        normal
            .fixed_view_mut::<3, 3>(0, 3)
            .copy_from(&(-self.u.transpose()));
        normal.fixed_view_mut::<3, 3>(3, 0).copy_from(&(-self.u));
        let mut rhs = SMatrix::<f64, 6, 1>::zeros();
        rhs.fixed_rows_mut::<3>(0)
            .copy_from(&(self.m * vec_z - self.at));
        rhs.fixed_rows_mut::<3>(3)
            .copy_from(&(self.ta - r_z * self.tb));
        let t = normal.lu().solve(&rhs)?;
        if !t.iter().all(|v| v.is_finite()) {
            return None;
        }
        let t_x: Vector3<f64> = t.fixed_rows::<3>(0).into_owned();
        let t_z: Vector3<f64> = t.fixed_rows::<3>(3).into_owned();
        Some(crate::solve::RobotWorld {
            x: transform_from_parts(&r_z, &t_z).inverse(),
            target: transform_from_parts(&r_x, &t_x).inverse(),
            method: crate::solve::RobotWorldMethod::Shah,
            poses: self.n,
            conditioning,
            warnings: Vec::new(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::pose::Transform;
    use crate::sim::{SimConfig, simulate};

    #[test]
    fn robot_world_accumulator_equals_batch_shah() {
        for setup in [Setup::EyeInHand, Setup::EyeToHand] {
            let s = simulate(
                &SimConfig {
                    poses: 40,
                    ..SimConfig::default()
                },
                4,
                0,
            );
            let mut acc = RobotWorldAccumulator::new(setup);
            for (k, p) in s.poses.iter().enumerate() {
                acc.add(p);
                if k < 2 {
                    assert!(acc.estimate().is_none());
                }
                if k + 1 >= 5 && (k + 1) % 7 == 0 {
                    let batch = crate::solve::shah(&s.poses[..=k], setup).unwrap();
                    let online = acc.estimate().unwrap();
                    let dx = (batch.x.to_homogeneous() - online.x.to_homogeneous()).amax();
                    let dy =
                        (batch.target.to_homogeneous() - online.target.to_homogeneous()).amax();
                    // Lengths in millimetres (SPEC sec. 5): 1e-9 of a 300 mm scene.
                    assert!(dx < 1e-7 && dy < 1e-7, "{setup:?} {k}: {dx:e} {dy:e}");
                }
            }
        }
    }

    #[test]
    fn robot_world_accumulator_refuses_one_axis() {
        let mut acc = RobotWorldAccumulator::new(Setup::EyeInHand);
        for i in 0..10 {
            let q = Transform::new(
                Vector3::new(0.1 * i as f64, 0.2, 0.0),
                Vector3::new(0.0, 0.0, 0.3 * i as f64),
            );
            acc.add(&PosePair {
                base_from_gripper: q,
                camera_from_target: q.inverse(),
            });
        }
        assert!(acc.estimate().is_none());
    }
}
