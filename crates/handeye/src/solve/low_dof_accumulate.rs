//! The low-DOF solve ([`crate::solve::low_dof`]) on a stream: running sums, O(1) time and memory
//! per pose, from which X of a robot that rotates about one axis follows at any time, with a
//! prior on X's translation along that axis.
//!
//! **Pose form.** Every pose k sees the fixed frame Y = Q_k X C_k (Q_k the hand pose as
//! [`crate::solve::accumulate::PoseAccumulator`] takes it: the gripper's pose eye-in-hand, its
//! inverse eye-to-hand; C_k = `camera_from_target`). Its translation residual is
//! r_k = R_Qk R_X c_k + R_Qk t_X + p_k − t_Y = L_k w + p_k with w = (vec R_X, t_X, t_Y) (15
//! unknowns, vec row-major) and L_k = [R_Qk ⊗ c_kᵀ, R_Qk, −I] (3×15).
//!
//! **One axis.** When every hand rotation is about one axis, R_Qk k_x = k_y for every k (k_x the
//! axis in X's parent frame, k_y in Y's). Projected across k_y, P = I − k_y k_yᵀ, the residual loses
//! t_X's component along k_x (the free one) and t_Y's along k_y. Σ_k ‖P r_k‖² =
//! Σ_ab P_ab Σ_k r_k\[a\] r_k\[b\] needs only the row products Σ_k L_k\[a\]ᵀ L_k\[b\] (six 15×15 sums),
//! Σ_k L_k\[a\]ᵀ p_k\[b\] (nine 15-vectors) and Σ_k p_k p_kᵀ, none of which depends on the axis: they
//! are accumulated before it is known. Minimising over t_Y is the all-pairs motion form
//! (Σ_{i<j} ‖r_i − r_j‖² = n Σ_i ‖r_i − r̄‖²), so the solution is [`solve_low_dof`]'s over every
//! pair of the same poses (equal on exact data; the unit test checks it to 1e-9).
//!
//! **Unknowns.** R_X = Rot(k_x, θ) R₀ = c (I − k kᵀ) R₀ + s \[k\]× R₀ + k kᵀ R₀ (R₀ takes the
//! camera-frame axis k_c to k_x), t_X = a e₁' + b e₂' + k_x v / k_x,i (e₁, e₂ across k_x, each
//! moved along k_x to keep the prior's component i at its value v), t_Y = y₁ f₁ + y₂ f₂ (across
//! k_y): w is affine in z = (a, b, c, s, y₁, y₂). The 6×6 normal equations are solved, (c, s) put
//! on the circle and (a, b, y₁, y₂) solved again with θ fixed, as [`solve_low_dof`] does.
//!
//! **Axes in O(1).** R_Qkᵀ R_Q1 is a rotation about k_x for every k, so the symmetric part of
//! (Σ_k R_Qk)ᵀ R_Q1 is (Σ cos φ_k)(I − k_x k_xᵀ) + n k_x k_xᵀ: its top eigenvector is k_x, and
//! k_y = R_Q1 k_x. Likewise R_C1 R_Ckᵀ turns about k_c: the top eigenvector of the symmetric part
//! of R_C1 (Σ_k R_Ck)ᵀ. Its sign is unknown: both are solved and the one with the smaller
//! projected cost is kept.
//!
//! **Is it low-DOF?** For D_k = R_Qkᵀ R_Q1, turning by φ_k about an axis α_k off k_x,
//! k_xᵀ D_k k_x = 1 − (1 − cos φ_k) sin² α_k and tr D_k = 1 + 2 cos φ_k. So
//! (n − k_xᵀ sym(M) k_x) / Σ(1 − cos φ_k) is the mean sin² α_k weighted by 1 − cos φ_k ≈ φ_k²/2:
//! the spread of the rotation axes about k_x, an RMS weighted as [`common_axis`]'s scatter weighs
//! motions (by angle²), and acos(1 − Σ(1 − cos φ_k)/n) the turn about it (relative to the first
//! pose). [`OneAxis::is_low_dof`] compares them with [`LOW_DOF_SPREAD_DEG`] and
//! [`LOW_DOF_MIN_ANGLE_DEG`]: an RMS within 2° where the batch asks every motion's axis to be, a
//! typical turn of 5° where the batch asks two motions to turn that much.

use nalgebra::{Matrix3, Matrix4, SMatrix, SVector, Unit, Vector2, Vector3, Vector4};
use serde::{Deserialize, Serialize};

use crate::model::error::{Degeneracy, Error, Result};
use crate::model::motion::{PosePair, Setup};
use crate::model::pose::{rotation_matrix, skew, transform_from_parts};
use crate::model::prior::Component;
use crate::solve::low_dof::{
    CommonAxis, LowDofSolution, REFUSE_SYSTEM, across, align, scaled_conditioning,
};
#[cfg(doc)]
use crate::solve::low_dof::{
    LOW_DOF_MIN_ANGLE_DEG, LOW_DOF_SPREAD_DEG, common_axis, solve_low_dof,
};

type Matrix15 = SMatrix<f64, 15, 15>;
type Vector15 = SVector<f64, 15>;
type Matrix15x6 = SMatrix<f64, 15, 6>;
type Matrix6 = SMatrix<f64, 6, 6>;
type Vector6 = SVector<f64, 6>;

/// The row pairs (a, b), a ≤ b, of the six row-product sums.
const PAIRS: [(usize, usize); 6] = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)];

/// The common rotation axis of the poses so far, from their running sums.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OneAxis {
    /// k_x: the axis in X's parent frame (unit; its sign arbitrary).
    pub hand: Vector3<f64>,
    /// k_y = R_Q1 k_x: the axis in the fixed frame's.
    pub fixed: Vector3<f64>,
    /// ±k_c: the axis in the camera frame (its sign relative to k_x unknown).
    pub eye: Vector3<f64>,
    /// RMS angle of the hand rotations' axes from k_x, weighted by 1 − cos of their angles
    /// (radians).
    pub spread: f64,
    /// The typical turn about it from the first pose: acos of the mean cos φ_k (radians).
    pub turn: f64,
    /// Poses.
    pub poses: usize,
}

impl OneAxis {
    /// The axis of hand rotations summed as `sum` (Σ R_Qk, n of them) with `first` the first
    /// one's (R_Q1); `None` with fewer than three poses or no turn. `eye` is left zero.
    pub(crate) fn of_hand(sum: &Matrix3<f64>, first: &Matrix3<f64>, n: usize) -> Option<Self> {
        if n < 3 {
            return None;
        }
        let m = sum.transpose() * first;
        let k = top_eigenvector(&m)?;
        let count = n as f64;
        // Σ (1 − cos φ_k) and Σ (1 − cos φ_k) sin² α_k.
        let turned = 0.5 * (3.0 * count - m.trace());
        let off = count - k.dot(&(m * k));
        if turned.is_nan() || turned <= 0.0 {
            return None;
        }
        Some(Self {
            hand: k,
            fixed: first * k,
            eye: Vector3::zeros(),
            spread: (off.max(0.0) / turned).sqrt().min(1.0).asin(),
            turn: (1.0 - turned / count).clamp(-1.0, 1.0).acos(),
            poses: n,
        })
    }

    /// Whether the hand rotations turn about this one axis: spread within
    /// [`LOW_DOF_SPREAD_DEG`] and a typical turn of at least [`LOW_DOF_MIN_ANGLE_DEG`].
    pub fn is_low_dof(&self) -> bool {
        use crate::solve::low_dof::{LOW_DOF_MIN_ANGLE_DEG, LOW_DOF_SPREAD_DEG};
        self.spread.to_degrees() <= LOW_DOF_SPREAD_DEG
            && self.turn.to_degrees() >= LOW_DOF_MIN_ANGLE_DEG
    }

    /// As the batch's [`CommonAxis`] (for the free component and the words of a refusal).
    pub fn common(&self) -> CommonAxis {
        CommonAxis {
            hand: self.hand,
            eye: self.eye,
            spread: self.spread,
            rotating: self.poses,
        }
    }
}

/// The top eigenvector of the symmetric part of `m`.
fn top_eigenvector(m: &Matrix3<f64>) -> Option<Vector3<f64>> {
    let sym = (m + m.transpose()) * 0.5;
    let eigen = sym.symmetric_eigen();
    let k: Vector3<f64> = eigen
        .eigenvectors
        .column(eigen.eigenvalues.imax())
        .into_owned();
    k.try_normalize(f64::MIN_POSITIVE)
}

/// Running sums of the pose form (module documentation).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LowDofAccumulator {
    setup: Setup,
    n: usize,
    /// R_Q1 and R_C1 (the first pose's; zero before it).
    first_hand: Matrix3<f64>,
    first_camera: Matrix3<f64>,
    /// Σ R_Qk and Σ R_Ck.
    sum_hand: Matrix3<f64>,
    sum_camera: Matrix3<f64>,
    /// Σ L_k[a]ᵀ L_k[b] for (a, b) in [`PAIRS`].
    rows: [Matrix15; 6],
    /// Σ L_k[a]ᵀ p_k[b] at 3a + b.
    cross: [Vector15; 9],
    /// Σ p_k p_kᵀ.
    pp: Matrix3<f64>,
}

impl LowDofAccumulator {
    /// An empty accumulator for the given setup.
    pub fn new(setup: Setup) -> Self {
        Self {
            setup,
            n: 0,
            first_hand: Matrix3::zeros(),
            first_camera: Matrix3::zeros(),
            sum_hand: Matrix3::zeros(),
            sum_camera: Matrix3::zeros(),
            rows: [Matrix15::zeros(); 6],
            cross: [Vector15::zeros(); 9],
            pp: Matrix3::zeros(),
        }
    }

    /// The sums of every pose in `poses`.
    #[cfg(test)]
    pub fn of(poses: &[PosePair], setup: Setup) -> Self {
        let mut sums = Self::new(setup);
        poses.iter().for_each(|p| sums.add(p));
        sums
    }

    /// Adds one pose pair.
    pub fn add(&mut self, pose: &PosePair) {
        let hand = self.setup.hand_pose(&pose.base_from_gripper);
        let r = rotation_matrix(&hand);
        let p = hand.translation.vector;
        let c = pose.camera_from_target.translation.vector;
        let r_c = rotation_matrix(&pose.camera_from_target);
        if self.n == 0 {
            self.first_hand = r;
            self.first_camera = r_c;
        }
        let l: [Vector15; 3] = std::array::from_fn(|a| {
            Vector15::from_fn(|col, _| match col {
                0..9 => r[(a, col / 3)] * c[col % 3],
                9..12 => r[(a, col - 9)],
                _ => -f64::from(u8::from(col - 12 == a)),
            })
        });
        for (sum, (a, b)) in self.rows.iter_mut().zip(PAIRS) {
            *sum += l[a] * l[b].transpose();
        }
        for (a, row) in l.iter().enumerate() {
            for b in 0..3 {
                self.cross[3 * a + b] += row * p[b];
            }
        }
        self.pp += p * p.transpose();
        self.sum_hand += r;
        self.sum_camera += r_c;
        self.n += 1;
    }

    /// The common axis of the poses so far (whether they are low-DOF: [`OneAxis::is_low_dof`]).
    pub fn axis(&self) -> Option<OneAxis> {
        let mut axis = OneAxis::of_hand(&self.sum_hand, &self.first_hand, self.n)?;
        axis.eye = top_eigenvector(&(self.first_camera * self.sum_camera.transpose()))?;
        Some(axis)
    }

    /// X with its translation component `along.0` equal to `along.1` (which must be the free
    /// component, the axis within `PRIOR_AXIS_DEG` of it), the axis from the sums.
    ///
    /// Errors: [`Degeneracy::IllConditioned`] when the poses do not fix θ and t_X across the axis
    /// (too few, no turn, no translation across it), as [`solve_low_dof`].
    pub fn solve(&self, along: (Component, f64)) -> Result<LowDofSolution> {
        let ill = |conditioning| Error::Degenerate {
            reason: Degeneracy::IllConditioned,
            conditioning,
        };
        let axis = self.axis().ok_or(ill(0.0))?;
        let plus = self.solve_on(&axis.hand, &axis.fixed, &axis.eye, along);
        let minus = self.solve_on(&axis.hand, &axis.fixed, &-axis.eye, along);
        match (plus, minus) {
            (Ok(p), Ok(m)) => Ok(if m.1 < p.1 { m.0 } else { p.0 }),
            (Ok(p), Err(_)) => Ok(p.0),
            (Err(_), Ok(m)) => Ok(m.0),
            (Err(e), Err(_)) => Err(e),
        }
    }

    /// The solve on given axes: the solution and its projected cost Σ‖P r_k‖².
    fn solve_on(
        &self,
        k: &Vector3<f64>,
        k_y: &Vector3<f64>,
        k_c: &Vector3<f64>,
        along: (Component, f64),
    ) -> Result<(LowDofSolution, f64)> {
        let i = along.0.index();
        let ill = |conditioning| Error::Degenerate {
            reason: Degeneracy::IllConditioned,
            conditioning,
        };
        if self.n < 3 || k[i].abs() < f64::EPSILON {
            return Err(ill(0.0));
        }
        // The quadratic form of Σ‖P r_k‖² in w: wᵀ Q w + 2 gᵀ w + constant.
        let projection = Matrix3::identity() - k_y * k_y.transpose();
        let mut q = Matrix15::zeros();
        for (sum, (a, b)) in self.rows.iter().zip(PAIRS) {
            if a == b {
                q += sum * projection[(a, a)];
            } else {
                q += (sum + sum.transpose()) * projection[(a, b)];
            }
        }
        let mut g = Vector15::zeros();
        let mut constant = 0.0;
        for a in 0..3 {
            for b in 0..3 {
                g += self.cross[3 * a + b] * projection[(a, b)];
                constant += self.pp[(a, b)] * projection[(a, b)];
            }
        }
        // w = W z + w0, z = (a, b, c, s, y1, y2).
        let r0 = *align(k_c, k).matrix();
        let (e1, e2) = across(k);
        let (f1, f2) = across(k_y);
        let kk = k * k.transpose();
        let vec = |m: Matrix3<f64>| SVector::<f64, 9>::from_fn(|j, _| m[(j / 3, j % 3)]);
        let mut w = Matrix15x6::zeros();
        let mut w0 = Vector15::zeros();
        w.fixed_view_mut::<3, 1>(9, 0)
            .copy_from(&(e1 - k * (e1[i] / k[i])));
        w.fixed_view_mut::<3, 1>(9, 1)
            .copy_from(&(e2 - k * (e2[i] / k[i])));
        w.fixed_view_mut::<9, 1>(0, 2)
            .copy_from(&vec((Matrix3::identity() - kk) * r0));
        w.fixed_view_mut::<9, 1>(0, 3).copy_from(&vec(skew(k) * r0));
        w.fixed_view_mut::<3, 1>(12, 4).copy_from(&f1);
        w.fixed_view_mut::<3, 1>(12, 5).copy_from(&f2);
        w0.fixed_view_mut::<9, 1>(0, 0).copy_from(&vec(kk * r0));
        w0.fixed_view_mut::<3, 1>(9, 0)
            .copy_from(&(k * (along.1 / k[i])));
        let normal: Matrix6 = w.transpose() * q * w;
        let normal = (normal + normal.transpose()) * 0.5;
        let rhs: Vector6 = -(w.transpose() * (q * w0 + g));
        let cost_constant = w0.dot(&(q * w0)) + 2.0 * g.dot(&w0) + constant;
        // The conditioning of (a, b, c, s) with t_Y eliminated: the batch's 4×4 system.
        let n11 = normal.fixed_view::<4, 4>(0, 0).into_owned();
        let n12 = normal.fixed_view::<4, 2>(0, 4).into_owned();
        let n22 = normal.fixed_view::<2, 2>(4, 4).into_owned();
        let schur: Matrix4<f64> = match n22.try_inverse() {
            Some(inv) => n11 - n12 * inv * n12.transpose(),
            None => return Err(ill(0.0)),
        };
        let conditioning = scaled_conditioning(&schur);
        if conditioning.is_nan() || conditioning < REFUSE_SYSTEM {
            return Err(ill(conditioning));
        }
        let first = normal.cholesky().ok_or(ill(conditioning))?.solve(&rhs);
        let cs = Vector2::new(first[2], first[3])
            .try_normalize(f64::MIN_POSITIVE)
            .ok_or(ill(conditioning))?;
        // (a, b, y1, y2) again with θ on the circle.
        let keep = [0, 1, 4, 5];
        let sub = Matrix4::from_fn(|r, s| normal[(keep[r], keep[s])]);
        let sub_rhs = Vector4::from_fn(|r, _| {
            rhs[keep[r]] - normal[(keep[r], 2)] * cs[0] - normal[(keep[r], 3)] * cs[1]
        });
        let rest = sub.cholesky().ok_or(ill(conditioning))?.solve(&sub_rhs);
        let z = Vector6::new(rest[0], rest[1], cs[0], cs[1], rest[2], rest[3]);
        let cost = z.dot(&(normal * z)) - 2.0 * rhs.dot(&z) + cost_constant;
        let rotation =
            nalgebra::Rotation3::from_axis_angle(&Unit::new_unchecked(*k), cs[1].atan2(cs[0]))
                * nalgebra::Rotation3::from_matrix_unchecked(r0);
        let mut t = e1 * z[0] + e2 * z[1];
        t = crate::solve::low_dof::with_component(&t, k, along);
        Ok((
            LowDofSolution {
                x: transform_from_parts(rotation.matrix(), &t),
                conditioning,
            },
            cost,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::pose::Transform;
    use crate::solve::low_dof::{common_axis, solve_low_dof};
    use crate::solve::motions::AllPairs;
    use proptest::prelude::*;

    /// Noise-free poses of a robot turning about `axis` (base frame) at `yaws`, hand positions
    /// `moves`, X and the fixed frame Y given.
    fn poses(
        setup: Setup,
        x: &Transform,
        y: &Transform,
        axis: &Vector3<f64>,
        motions: &[(f64, [f64; 3])],
    ) -> Vec<PosePair> {
        motions
            .iter()
            .map(|(yaw, t)| {
                // Q_k turns about `axis` in its parent frame: Q_k = Rot(axis, yaw), at t.
                let q = Transform::new(Vector3::new(t[0], t[1], t[2]), axis * *yaw);
                let base_from_gripper = match setup {
                    Setup::EyeInHand => q,
                    Setup::EyeToHand => q.inverse(),
                };
                PosePair {
                    base_from_gripper,
                    camera_from_target: x.inverse() * q.inverse() * y,
                }
            })
            .collect()
    }

    fn compare(setup: Setup, x: &Transform, axis: &Vector3<f64>, motions: &[(f64, [f64; 3])]) {
        let y = Transform::new(Vector3::new(0.4, -0.2, 0.1), Vector3::new(0.3, 2.0, -0.4));
        let poses = poses(setup, x, &y, axis, motions);
        let sums = LowDofAccumulator::of(&poses, setup);
        let found = sums.axis().unwrap();
        assert!(found.is_low_dof(), "{found:?}");
        let component = found.common().free_component().unwrap();
        let value = x.translation.vector[component.index()];
        let online = sums.solve((component, value)).unwrap();
        let motions = AllPairs::new(&poses, setup);
        let batch_axis = common_axis(&motions).unwrap();
        let batch = solve_low_dof(&motions, &batch_axis, (component, value)).unwrap();
        let d = (online.x.to_homogeneous() - batch.x.to_homogeneous()).norm();
        assert!(d < 1e-9, "{setup:?}: {d:e}");
        let truth = (online.x.to_homogeneous() - x.to_homogeneous()).norm();
        assert!(truth < 1e-9, "{setup:?}: {truth:e}");
        assert!(online.conditioning > 0.0);
    }

    const SCARA: [(f64, [f64; 3]); 6] = [
        (0.1, [0.3, 0.1, 0.05]),
        (0.9, [0.1, 0.4, 0.0]),
        (-0.6, [-0.2, 0.3, 0.1]),
        (1.7, [0.0, -0.3, 0.02]),
        (-1.2, [0.35, -0.1, -0.04]),
        (2.4, [-0.1, -0.2, 0.08]),
    ];

    #[test]
    fn equals_the_batch_low_dof_solve_over_all_pairs_on_exact_scara_poses() {
        let x = Transform::new(
            Vector3::new(0.03, -0.02, 0.12),
            Vector3::new(0.2, -0.1, 0.7),
        );
        for setup in [Setup::EyeInHand, Setup::EyeToHand] {
            compare(setup, &x, &Vector3::z(), &SCARA);
        }
    }

    #[test]
    fn refuses_poses_that_do_not_turn() {
        let x = Transform::new(
            Vector3::new(0.03, -0.02, 0.12),
            Vector3::new(0.2, -0.1, 0.7),
        );
        let y = Transform::identity();
        let still: Vec<(f64, [f64; 3])> = SCARA.iter().map(|(_, t)| (0.3, *t)).collect();
        let sums = LowDofAccumulator::of(
            &poses(Setup::EyeInHand, &x, &y, &Vector3::z(), &still),
            Setup::EyeInHand,
        );
        assert!(sums.axis().is_none_or(|a| !a.is_low_dof()));
        assert!(sums.solve((Component::Tz, 0.12)).is_err());
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]
        #[test]
        fn equals_the_batch_on_random_x_and_axes(
            rx in prop::array::uniform3(-2.0f64..2.0),
            tx in prop::array::uniform3(-0.3f64..0.3),
            tilt in prop::array::uniform2(-0.05f64..0.05),
            which in 0usize..3,
            eye_to_hand in any::<bool>(),
        ) {
            let x = Transform::new(Vector3::from(tx), Vector3::from(rx));
            let mut axis = Vector3::zeros();
            axis[which] = 1.0;
            axis[(which + 1) % 3] = tilt[0];
            axis[(which + 2) % 3] = tilt[1];
            let axis = axis.normalize();
            let setup = if eye_to_hand { Setup::EyeToHand } else { Setup::EyeInHand };
            compare(setup, &x, &axis, &SCARA);
        }
    }
}
