//! An online estimate that keeps improving: the normal equations of Andreff's linear system over
//! *every pair* of poses seen so far, updated in O(1) time and memory per pose. On a stream it is
//! run by [`crate::track::Tracker`], which gates the poses and notices when X changes.
//!
//! Over all pairs i < j (motion from pose j to pose i, as [`crate::Pairing::All`]) the sums that
//! make the normal equations factor through per-pose sums. With G_k = R_k ⊗ S_k (R_k the rotation
//! of Q_k, S_k that of P_k), the rotation blocks are K_ij = R_a ⊗ R_b = G_jᵀ G_i, so
//! `Σ_{i<j} (2I − K_ij − K_ijᵀ) = n² I − SᵀS` with `S = Σ_k G_k`. Likewise, for the translation
//! system `(I − R_a) t = t_a − R_x t_b`, `Σ CᵀC = n² I − UᵀU` with `U = Σ R_k`,
//! `Σ Cᵀ t_a = UᵀΣp_k − n Σ R_kᵀ p_k`, and `Σ Cᵀ R_x t_b = E vec(R_x)` where E grows by an O(1)
//! term per pose built from running prefix sums. The result is the batch all-pairs Andreff
//! solution — the most accurate batch solve on the paper's protocol — at every pose, for the cost
//! of a 9×9 eigen-decomposition.
//!
//! The same sums give, for any X, the fixed frame every pose sees, Y_i = H_i X C_i (H_i the hand
//! pose, C_i = `camera_from_target`; Y is `base_from_target` eye-in-hand, `gripper_from_target`
//! eye-to-hand): `Σ R_Yi = unvec(S vec R_x)` and `Σ t_Yi = N vec R_x + U t_x + Σ p_k` with
//! `N = Σ R_k ⊗ c_kᵀ` (c_k the translation of C_k). Two more sums (Σ‖c‖², Σ‖w‖², Σc, Σ c wᵀ with
//! w_k = R_kᵀ p_k) give the scatter of the Y_i about their mean, Σ‖R_Yi − R_Y‖²_F and
//! Σ‖t_Yi − t_Y‖², in closed form: the data's own noise level under X, in O(1)
//! ([`PoseAccumulator::residual_scatter`]). [`crate::track`] judges each new pose by it.

use std::sync::OnceLock;

use nalgebra::{Matrix3, Matrix4, SMatrix, Vector3, Vector4};
use serde::{Deserialize, Serialize};

use crate::model::motion::{Pairing, PosePair, Setup};
use crate::model::pose::{Transform, rotation_matrix, transform_from_parts};
use crate::solve::RotationSystem;
use crate::solve::quadratic::{Matrix9, Matrix13, Quadratic};
/// A 3×9 matrix.
pub(crate) type Matrix39 = SMatrix<f64, 3, 9>;

/// Running sums from which the all-pairs normal equations follow (see the module documentation).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PoseAccumulator {
    setup: Setup,
    n: usize,
    /// S = Σ R_k ⊗ S_k.
    g: Matrix9,
    /// U = Σ R_k.
    u: Matrix3<f64>,
    /// Σ p_k (translations of Q_k).
    p: Vector3<f64>,
    /// Σ R_kᵀ p_k.
    w: Vector3<f64>,
    /// Σ q_k (translations of P_k).
    q: Vector3<f64>,
    /// Σ R_kᵀ ⊗ q_kᵀ.
    t: Matrix39,
    /// E with Σ_{i<j} Cᵀ R_x t_b = E vec(R_x).
    e: Matrix39,
    /// N = Σ R_k ⊗ c_kᵀ, c_k the translation of `camera_from_target`.
    n_c: Matrix39,
    /// Σ c_k.
    c: Vector3<f64>,
    /// Σ c_k w_kᵀ, w_k = R_kᵀ p_k.
    cw: Matrix3<f64>,
    /// Σ‖c_k‖² + Σ‖w_k‖².
    cc_ww: f64,
    /// Σ‖p_k‖² (the spread of the hand positions).
    pp: f64,
    /// Σ‖c_k‖² (the camera's distance to the target).
    cc: f64,
    /// Σ [p_k]× R_k.
    pr: Matrix3<f64>,
    /// Σ w_k w_kᵀ.
    ww: Matrix3<f64>,
}

/// The accumulated estimate of X.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Estimate {
    /// X from all pairs of the poses accumulated so far.
    pub x: Transform,
    /// Poses it rests on.
    pub poses: usize,
    /// Conditioning of the rotation system (second-smallest over largest singular value).
    pub conditioning: f64,
}

/// How the poses' fixed frames Y_i = H_i X C_i scatter under one X (module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Scatter {
    /// The mean fixed frame Y (chordal mean rotation, mean translation).
    pub y: Transform,
    /// RMS rotation of the Y_i about Y, radians (from Σ‖R_Yi − R_Y‖²_F = Σ 4(1 − cos θ_i) ≈ Σ 2θ_i²).
    pub rotation: f64,
    /// RMS distance of the Y_i from Y, input units.
    pub translation: f64,
}

/// `T (R ⊗ S)` for a 3×9 T, without forming the 9×9 `R ⊗ S`: row a of the product, read as a
/// 3×3 in the layout of [`kron_row`], is `Rᵀ M_a S` with `M_a[b, c] = T[a, 3b + c]` (162
/// multiplications instead of 243, and none to build the Kronecker product).
fn times_kron(t: &Matrix39, r: &Matrix3<f64>, s: &Matrix3<f64>) -> Matrix39 {
    let mut out = Matrix39::zeros();
    for a in 0..3 {
        let m = Matrix3::from_fn(|b, c| t[(a, 3 * b + c)]);
        let block = r.transpose() * m * s;
        for d in 0..3 {
            for e in 0..3 {
                out[(a, 3 * d + e)] = block[(d, e)];
            }
        }
    }
    out
}

/// `A ⊗ r` for a 3×3 A and a row 3-vector r (3×9).
pub(crate) fn kron_row(a: &Matrix3<f64>, r: &Vector3<f64>) -> Matrix39 {
    Matrix39::from_fn(|i, c| a[(i, c / 3)] * r[c % 3])
}

impl PoseAccumulator {
    /// An empty accumulator for the given setup.
    pub fn new(setup: Setup) -> Self {
        Self {
            setup,
            n: 0,
            g: Matrix9::zeros(),
            u: Matrix3::zeros(),
            p: Vector3::zeros(),
            w: Vector3::zeros(),
            q: Vector3::zeros(),
            t: Matrix39::zeros(),
            e: Matrix39::zeros(),
            n_c: Matrix39::zeros(),
            c: Vector3::zeros(),
            cw: Matrix3::zeros(),
            cc_ww: 0.0,
            pp: 0.0,
            cc: 0.0,
            pr: Matrix3::zeros(),
            ww: Matrix3::zeros(),
        }
    }

    /// The sums of every pose in `poses`.
    pub fn of(poses: &[PosePair], setup: Setup) -> Self {
        let mut sums = Self::new(setup);
        poses.iter().for_each(|p| sums.add(p));
        sums
    }

    /// Adds one pose pair: the motions from it to every earlier pose enter the normal equations.
    pub fn add(&mut self, pose: &PosePair) {
        self.add_returning(pose);
    }

    /// [`Self::add`], returning the pose's R_k, S_k and S_kᵀ q_k for [`MergeableAccumulator`].
    fn add_returning(&mut self, pose: &PosePair) -> (Matrix3<f64>, Matrix3<f64>, Vector3<f64>) {
        let hand = self.setup.hand_pose(&pose.base_from_gripper);
        let camera = pose.camera_from_target.inverse();
        let r = rotation_matrix(&hand);
        let s = rotation_matrix(&camera);
        let (p, q) = (hand.translation.vector, camera.translation.vector);
        let g = Matrix9::from_fn(|row, col| r[(row / 3, col / 3)] * s[(row % 3, col % 3)]);
        // New pairs (i, j) for every earlier i: E += I⊗(Σq_i)ᵀS_j − n I⊗q_jᵀS_j − T G_j + (UᵀR_j)⊗q_jᵀS_j.
        let q_s = s.transpose() * q;
        let sum_q_s = s.transpose() * self.q;
        let identity = Matrix3::identity();
        self.e += kron_row(&identity, &sum_q_s)
            - kron_row(&identity, &q_s) * self.n as f64
            - times_kron(&self.t, &r, &s)
            + kron_row(&(self.u.transpose() * r), &q_s);
        self.g += g;
        self.u += r;
        self.p += p;
        self.w += r.transpose() * p;
        self.q += q;
        self.t += kron_row(&r.transpose(), &q);
        // The fixed-frame sums: c = translation of camera_from_target, w = Rᵀp.
        let c = pose.camera_from_target.translation.vector;
        let w = r.transpose() * p;
        self.n_c += kron_row(&r, &c);
        self.c += c;
        self.cw += c * w.transpose();
        self.cc_ww += c.norm_squared() + w.norm_squared();
        self.pp += p.norm_squared();
        self.cc += c.norm_squared();
        self.pr += crate::model::pose::skew(&p) * r;
        self.ww += w * w.transpose();
        self.n += 1;
        (r, s, q_s)
    }

    /// The setup the poses are read in.
    pub fn setup(&self) -> Setup {
        self.setup
    }

    /// RMS distance of the hand positions from their mean, input units: the size of the scene.
    pub fn scene_scale(&self) -> f64 {
        let n = self.n.max(1) as f64;
        (self.pp / n - (self.p / n).norm_squared()).max(0.0).sqrt()
    }

    /// The RMS size of the translations the scatter's sums hold (the camera's distance from the
    /// target and the hand positions, ‖c_k‖² + ‖w_k‖²), input units: what the precision of
    /// [`Self::residual_scatter`]'s translation is relative to.
    pub fn translation_magnitude(&self) -> f64 {
        (self.cc_ww / self.n.max(1) as f64).sqrt()
    }

    /// RMS distance of the camera from the target, input units.
    pub fn viewing_distance(&self) -> f64 {
        (self.cc / self.n.max(1) as f64).sqrt()
    }

    /// The mean target position seen by the camera (the translation of `camera_from_target`,
    /// camera frame) over the poses accumulated, or `None` before the first.
    pub fn mean_target(&self) -> Option<Vector3<f64>> {
        (self.n > 0).then(|| self.c / self.n as f64)
    }

    /// The covariance of X's error to first order, as (rotation about the gripper axes in
    /// radians², translation in units²; 6×6), when every pose's fixed frame Y_k = H_k X C_k carries
    /// independent noise of RMS `noise_rotation` (radians) and `noise_translation` about the
    /// common Y: the robot-world reading of the poses, where each pose is one measurement (the
    /// all-pairs sums count each pose's noise in n − 1 motions). With δ = (δr, δt) in the gripper
    /// frame, Y_k moves by A_k δ, `A_k = [[R_k, 0], [R_k [t_x]× + [p_k]× R_k, R_k]]`; Y absorbs the
    /// mean, so the information is Σ A_kᵀ W A_k − (Σ A_k)ᵀ W (Σ A_k) / n with
    /// W = diag(I/σ_r², I/σ_t²), every sum from the accumulated ones. `None` when it is singular.
    pub fn covariance(
        &self,
        x: &Transform,
        noise_rotation: f64,
        noise_translation: f64,
    ) -> Option<SMatrix<f64, 6, 6>> {
        self.information(x, noise_rotation, noise_translation)?
            .try_inverse()
            .filter(|c| (0..6).all(|k| c[(k, k)].is_finite() && c[(k, k)] > 0.0))
    }

    /// The information matrix whose inverse is [`Self::covariance`] (symmetric; singular when the
    /// poses leave a direction of X free). `None` with fewer than three poses or no noise.
    fn information(
        &self,
        x: &Transform,
        noise_rotation: f64,
        noise_translation: f64,
    ) -> Option<SMatrix<f64, 6, 6>> {
        if self.n < 3 || !(noise_rotation > 0.0 && noise_translation > 0.0) {
            return None;
        }
        let n = self.n as f64;
        let (wr, wt) = (
            1.0 / noise_rotation.powi(2),
            1.0 / noise_translation.powi(2),
        );
        let t = x.translation.vector;
        let tx = crate::model::pose::skew(&t);
        let identity = Matrix3::identity();
        // Lower-left block summed: Σ (R_k [t]× + [p_k]× R_k) = U [t]× + Σ [p_k]× R_k.
        let sum_l = self.u * tx + self.pr;
        // Σ L_kᵀ L_k with L_k = R_k [t]× + [p_k]× R_k: [t]×ᵀ[t]× n + [t]×ᵀ Σ Rᵀ[p]×R + its
        // transpose + Σ Rᵀ[p]×ᵀ[p]×R, where Rᵀ[p]×R = [w]× and Rᵀ[p]×ᵀ[p]×R = ‖p‖² I − w wᵀ.
        let w_sum = crate::model::pose::skew(&self.w);
        let ltl = tx.transpose() * tx * n
            + tx.transpose() * w_sum
            + w_sum.transpose() * tx
            + identity * self.pp
            - self.ww;
        // Σ L_kᵀ R_k = [t]×ᵀ n + Σ Rᵀ[p]×ᵀ R... = n [t]×ᵀ + [w]×ᵀ summed.
        let ltr = tx.transpose() * n + w_sum.transpose();
        let mut info = SMatrix::<f64, 6, 6>::zeros();
        // Rotation block: Σ R_kᵀ R_k wr + Σ L_kᵀ L_k wt.
        info.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(identity * (n * wr) + ltl * wt));
        info.fixed_view_mut::<3, 3>(0, 3).copy_from(&(ltr * wt));
        info.fixed_view_mut::<3, 3>(3, 0)
            .copy_from(&(ltr.transpose() * wt));
        info.fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&(identity * (n * wt)));
        // Minus the mean's share: (Σ A)ᵀ W (Σ A) / n, Σ A = [[U, 0], [ΣL, U]].
        let mut sum_a = SMatrix::<f64, 6, 6>::zeros();
        sum_a.fixed_view_mut::<3, 3>(0, 0).copy_from(&self.u);
        sum_a.fixed_view_mut::<3, 3>(3, 0).copy_from(&sum_l);
        sum_a.fixed_view_mut::<3, 3>(3, 3).copy_from(&self.u);
        let weight =
            SMatrix::<f64, 6, 6>::from_diagonal(&nalgebra::Vector6::new(wr, wr, wr, wt, wt, wt));
        let info = info - sum_a.transpose() * weight * sum_a / n;
        Some((info + info.transpose()) * 0.5)
    }

    /// [`Self::covariance`] with priors on components of X's translation (each a measurement of
    /// that component with its sigma: information 1/σ² on it; an exact prior's sigma is taken as
    /// 1e-9 of the scene's size): the covariance of a low-DOF recording, whose motions leave a
    /// component free, is then finite. `None` when it is singular.
    pub fn covariance_given(
        &self,
        x: &Transform,
        noise_rotation: f64,
        noise_translation: f64,
        priors: &[crate::model::prior::Prior],
    ) -> Option<SMatrix<f64, 6, 6>> {
        if priors.is_empty() {
            return self.covariance(x, noise_rotation, noise_translation);
        }
        // The information without priors may be singular (the free direction): it is inverted
        // with the priors' information added.
        let floor = 1e-9 * self.scene_scale().max(1e-12);
        let mut prior_info = SMatrix::<f64, 6, 6>::zeros();
        for p in priors {
            let k = 3 + p.component.index();
            prior_info[(k, k)] += 1.0 / p.sigma.max(floor).powi(2);
        }
        let info = self.information(x, noise_rotation, noise_translation)? + prior_info;
        info.try_inverse()
            .filter(|c| (0..6).all(|k| c[(k, k)].is_finite() && c[(k, k)] > 0.0))
    }

    /// The fixed frame Y and how the poses scatter about it under `x` (module documentation), in
    /// O(1). `None` before the first pose.
    pub fn residual_scatter(&self, x: &Transform) -> Option<Scatter> {
        if self.n == 0 {
            return None;
        }
        let n = self.n as f64;
        let r_x = rotation_matrix(x);
        let t_x = x.translation.vector;
        let vec_r = SMatrix::<f64, 9, 1>::from_fn(|k, _| r_x[(k / 3, k % 3)]);
        let sum_r = self.g * vec_r;
        let sum_r = Matrix3::from_fn(|i, j| sum_r[3 * i + j]);
        let r_y = crate::model::pose::proj_so3(&sum_r);
        let sum_t = self.n_c * vec_r + self.u * t_x + self.p;
        let t_y = sum_t / n;
        // Σ‖R_Yi − R_Y‖²_F = 6n − 2 tr(R_Yᵀ Σ R_Yi), and per pose ‖R − R_Y‖²_F = 4(1 − cos θ) ≈ 2θ².
        let rotation_f2 = (6.0 * n - 2.0 * (r_y.transpose() * sum_r).trace()).max(0.0);
        let rotation = (rotation_f2 / (2.0 * n)).sqrt();
        // ‖t_Yi‖² = ‖R_x c + t_x + w‖², summed term by term.
        let sum_tt = self.cc_ww
            + n * t_x.norm_squared()
            + 2.0 * t_x.dot(&(r_x * self.c))
            + 2.0 * (r_x * self.cw).trace()
            + 2.0 * t_x.dot(&self.w);
        let translation = ((sum_tt - n * t_y.norm_squared()) / n).max(0.0).sqrt();
        Some(Scatter {
            y: transform_from_parts(&r_y, &t_y),
            rotation,
            translation,
        })
    }

    /// Poses accumulated.
    pub fn poses(&self) -> usize {
        self.n
    }

    /// U = Σ R_k, the sum of the hand rotations.
    pub(crate) fn rotation_sum(&self) -> Matrix3<f64> {
        self.u
    }

    /// Forgets every pose (after a detected change).
    pub fn reset(&mut self) {
        *self = Self::new(self.setup);
    }

    /// The current X, the all-pairs Andreff solution: R_x from `n² I − SᵀS`, then
    /// `t = (n² I − UᵀU)⁻¹ (d − E vec R_x)`. `None` with fewer than three poses or a degenerate
    /// system.
    pub fn estimate(&self) -> Option<Estimate> {
        if self.n < 3 {
            return None;
        }
        let solution = self.rotation_system().solve();
        if solution.conditioning.is_nan()
            || solution.conditioning <= crate::solve::REFUSE_CONDITIONING
        {
            return None;
        }
        let t = self.translation(&solution.r_x)?;
        Some(Estimate {
            x: transform_from_parts(&solution.r_x, &t),
            poses: self.n,
            conditioning: solution.conditioning,
        })
    }

    /// Andreff's rotation system over all pairs: the normal matrix `n² I − SᵀS`.
    pub(crate) fn rotation_system(&self) -> RotationSystem {
        let n2 = (self.n * self.n) as f64;
        RotationSystem::from_normal(
            Matrix9::identity() * n2 - self.g.transpose() * self.g,
            self.n * self.n.saturating_sub(1) / 2,
        )
    }

    /// The normal matrix `n² I − UᵀU` of Andreff's translation system over all pairs.
    pub(crate) fn translation_normal(&self) -> Matrix3<f64> {
        Matrix3::identity() * (self.n * self.n) as f64 - self.u.transpose() * self.u
    }

    /// Andreff's translation over all pairs given R_x: `t = (n² I − UᵀU)⁻¹ (d − E vec R_x)`.
    /// `None` when the system is singular.
    pub(crate) fn translation(&self, r_x: &Matrix3<f64>) -> Option<Vector3<f64>> {
        let vec_r = SMatrix::<f64, 9, 1>::from_fn(|k, _| r_x[(k / 3, k % 3)]);
        let normal = self.translation_normal();
        let d = self.u.transpose() * self.p - self.w * self.n as f64;
        let t = normal.lu().solve(&(d - self.e * vec_r))?;
        t.iter().all(|v| v.is_finite()).then_some(t)
    }
}

/// A [`PoseAccumulator`] with the three sums more that merging two of them needs: the sums of
/// poses 0..m followed by poses m..n from the two parts' sums, equal to adding the n poses in
/// order (to rounding). The leave-one-out check ([`crate::holdout`]) merges a prefix and a suffix
/// of the poses for each pose left out. Kept apart from [`PoseAccumulator`], whose serialised
/// form is part of saved online states.
///
/// Every sum of [`PoseAccumulator`] but E is a plain sum over the poses and merges by addition.
/// E (Σ_{i<j} Cᵀ R_x t_b = E vec R_x) grows per pose j by
/// `I⊗(Σq)ᵀS_j − n I⊗q_jᵀS_j − T G_j + (UᵀR_j)⊗q_jᵀS_j`, linear in the earlier poses' sums
/// (n, Σq, T, U). For A (earlier poses) then B (later poses), E = E_A + E_B plus the pairs
/// (a ∈ A, b ∈ B): that increment summed over b ∈ B with A's sums,
/// `I⊗(Σ_A q)ᵀ(Σ_B S) − n_A I⊗(Σ_B S_bᵀ q_b)ᵀ − T_A S_B + U_Aᵀ Σ_B R_b ⊗ (S_bᵀ q_b)ᵀ`
/// (S_B = Σ_B G_b, [`PoseAccumulator`]'s S; `(UᵀR)⊗r = Uᵀ(R⊗r)` for a row r).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct MergeableAccumulator {
    poses: PoseAccumulator,
    /// Σ S_k (rotations of P_k = C_k⁻¹).
    s: Matrix3<f64>,
    /// Σ S_kᵀ q_k.
    s_q: Vector3<f64>,
    /// Σ R_k ⊗ (S_kᵀ q_k)ᵀ.
    r_sq: Matrix39,
}

impl MergeableAccumulator {
    /// An empty accumulator for the given setup.
    pub(crate) fn new(setup: Setup) -> Self {
        Self {
            poses: PoseAccumulator::new(setup),
            s: Matrix3::zeros(),
            s_q: Vector3::zeros(),
            r_sq: Matrix39::zeros(),
        }
    }

    /// Adds one pose pair after the others ([`PoseAccumulator::add`]).
    pub(crate) fn add(&mut self, pose: &PosePair) {
        let (r, s, q_s) = self.poses.add_returning(pose);
        self.s += s;
        self.s_q += q_s;
        self.r_sq += kron_row(&r, &q_s);
    }

    /// Adds `later`'s poses after these, as if each had been added in turn (type documentation).
    pub(crate) fn merge(&mut self, later: &Self) {
        debug_assert_eq!(self.poses.setup, later.poses.setup);
        let a = &mut self.poses;
        // Every field named, so that a sum added to PoseAccumulator must be merged here too.
        let PoseAccumulator {
            setup: _,
            n,
            g,
            u,
            p,
            w,
            q,
            t,
            e,
            n_c,
            c,
            cw,
            cc_ww,
            pp,
            cc,
            pr,
            ww,
        } = &later.poses;
        let identity = Matrix3::identity();
        // The pairs (a, b), a earlier: from A's sums before they take in B's.
        let cross = kron_row(&identity, &(later.s.transpose() * a.q))
            - kron_row(&identity, &later.s_q) * a.n as f64
            - a.t * g
            + a.u.transpose() * later.r_sq;
        a.e += e + cross;
        a.n += n;
        a.g += g;
        a.u += u;
        a.p += p;
        a.w += w;
        a.q += q;
        a.t += t;
        a.n_c += n_c;
        a.c += c;
        a.cw += cw;
        a.cc_ww += cc_ww;
        a.pp += pp;
        a.cc += cc;
        a.pr += pr;
        a.ww += ww;
        self.s += later.s;
        self.s_q += later.s_q;
        self.r_sq += later.r_sq;
    }

    /// The accumulated sums.
    pub(crate) fn accumulator(&self) -> &PoseAccumulator {
        &self.poses
    }
}

/// The sums over every pair i < j of a pose sequence that the batch solvers and the quality
/// report use, in O(n) time and memory: Andreff's normal equations (a [`PoseAccumulator`]), the
/// quadratic form of the residuals ([`Quadratic`]) and the lengths of the motions.
///
/// The poses are first moved to a base frame at the mean hand position and a target frame at
/// the mean camera position: the motions (A_ij = Q_j⁻¹ Q_i, B_ij = C_j C_i⁻¹) do not change, and
/// the sums, which are differences of large terms, lose fewer digits.
///
/// The ΔT form: with Q_k = (R_k, p_k), C_k = `camera_from_target` = (S_k, c_k) and
/// o_k = S_kᵀ c_k, one finds `R_j ΔT_ij = F_i z − H_j z + R_j R_x S_j o_i`, where
/// `F_k z = R_k t_x + p_k` and `H_k z = R_k R_x c_k + R_k t_x + p_k` (the translation of
/// Q_k X C_k). So `L_ij = F_i + Σ_m a_i[m] B_j^m` with a_i = (1, o_i), B^0 = −H and
/// B^{m+1} z = R_j R_x (S_j e_m), and Σ_{i<j} L_ijᵀ L_ij needs only the prefix sums
/// Σ_{i<j} F_iᵀF_i, Σ_{i<j} a_i[m] F_iᵀ and Σ_{i<j} a_i a_iᵀ.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct PairSums {
    /// Andreff's all-pairs normal equations.
    pub(crate) poses: PoseAccumulator,
    /// Σ‖ΔR‖² and Σ‖ΔT‖² over all pairs as a quadratic form in [vec R_x; t_x; 1], made on first
    /// use ([`Self::quadratic`]): only refine, andreff-joint and the residual scales need it.
    quadratic: OnceLock<Quadratic>,
    /// The centred poses the form is made from.
    centred: Vec<PoseParts>,
    /// Σ_{i<j} ‖t_a‖² + ‖t_b‖².
    pub(crate) length_squares: f64,
    /// Σ_{i<j} ‖t_b‖², the camera motions' share.
    pub(crate) camera_length_squares: f64,
}

/// A 4×3 matrix.
type Matrix43 = SMatrix<f64, 4, 3>;

/// A 3×4 matrix.
type Matrix34 = SMatrix<f64, 3, 4>;

/// One pose as (R_k, p_k) of Q_k and (S_k, c_k) of C_k = `camera_from_target`.
type PoseParts = (Matrix3<f64>, Vector3<f64>, Matrix3<f64>, Vector3<f64>);

impl PairSums {
    /// The sums of the hand poses Q_k and camera poses C_k = `camera_from_target`.
    pub(crate) fn new(hand: &[Transform], camera: &[Transform]) -> Self {
        let n = hand.len().max(1) as f64;
        let p_mean = hand
            .iter()
            .map(|q| q.translation.vector)
            .sum::<Vector3<f64>>()
            / n;
        let o_mean = camera
            .iter()
            .map(|c| c.rotation.inverse() * c.translation.vector)
            .sum::<Vector3<f64>>()
            / n;
        let mut poses = PoseAccumulator::new(Setup::EyeInHand);
        let (mut spread, mut camera_spread) = (0.0, 0.0);
        let centred: Vec<PoseParts> = hand
            .iter()
            .zip(camera)
            .map(|(q, c)| {
                let (r, s) = (rotation_matrix(q), rotation_matrix(c));
                let p = q.translation.vector - p_mean;
                // The target frame moved by −ō: c ← c − S ō, so that o = Sᵀc ← o − ō.
                let cv = c.translation.vector - s * o_mean;
                let o = (s.transpose() * cv).norm_squared();
                spread += p.norm_squared() + o;
                camera_spread += o;
                poses.add(&PosePair {
                    base_from_gripper: transform_from_parts(&r, &p),
                    camera_from_target: transform_from_parts(&s, &cv),
                });
                (r, p, s, cv)
            })
            .collect();
        Self {
            poses,
            quadratic: OnceLock::new(),
            centred,
            length_squares: n * spread,
            camera_length_squares: n * camera_spread,
        }
    }

    /// The quadratic form of the residuals over all pairs (O(n) on first use).
    pub(crate) fn quadratic(&self) -> &Quadratic {
        self.quadratic.get_or_init(|| Quadratic {
            rotation: *self.poses.rotation_system().normal_matrix(),
            translation: translation_form(&self.centred),
            motions: Pairing::All.motion_count(self.centred.len()),
        })
    }
}

/// M_T = Σ_{i<j} L_ijᵀ L_ij from the prefix sums over the poses (see [`PairSums`]); each pose
/// given as (R_k, p_k, S_k, c_k).
///
/// With z = (vec R_x, t_x, 1), B^m = [K_m, T_m] splits into its 9 rotation columns and 4 others:
/// K_0 = −R ⊗ cᵀ, T_0 = −[R, p], and K_m = R ⊗ (S e_m)ᵀ, T_m = 0 for m = 1..3; F = [0, R, p] has
/// only the 4 others. So the three terms of L_ijᵀ L_ij summed over i < j are, block by block:
/// - Σ F_iᵀF_i: the 4×4 block of Σ_{i<j} [R_i, p_i]ᵀ[R_i, p_i];
/// - Σ_m (Σ_i a_i[m] F_iᵀ) B_j^m and its transpose: rows 9..13 only, P_m = Σ_{i<j} a_i[m] [R_i, p_i]ᵀ;
/// - Σ_{m,l} (Σ_i a_i a_iᵀ)[m, l] B_j^mᵀ B_j^l: K's 9×9, the 9×4 coupling through T_0, and T_0's 4×4.
///
/// Only the non-zero blocks are formed (a third of the products of the full 13-column form).
fn translation_form(poses: &[PoseParts]) -> Matrix13 {
    let mut total = Matrix13::zeros();
    let mut ff = Matrix4::<f64>::zeros();
    let mut p_sums = [Matrix43::zeros(); 4];
    let mut aa = Matrix4::<f64>::zeros();
    for (r, p, s, c) in poses {
        let k = [
            -kron_row(r, c),
            kron_row(r, &s.column(0).into_owned()),
            kron_row(r, &s.column(1).into_owned()),
            kron_row(r, &s.column(2).into_owned()),
        ];
        // F's non-zero columns [R, p]; T_0 = −[R, p].
        let mut f = Matrix34::zeros();
        f.fixed_view_mut::<3, 3>(0, 0).copy_from(r);
        f.set_column(3, p);
        let t0 = -f;
        // The quadratic term: Σ_{m,l} aa[m,l] K_mᵀ K_l, and its coupling and 4×4 through T_0.
        let mut kk = Matrix9::zeros();
        let mut c0 = Matrix39::zeros();
        for m in 0..4 {
            let mut cm = k[0] * aa[(m, 0)];
            for (l, k_l) in k.iter().enumerate().skip(1) {
                cm += k_l * aa[(m, l)];
            }
            kk += k[m].transpose() * cm;
            if m == 0 {
                c0 = cm;
            }
        }
        // The cross term, rows 9..13: Σ_m P_m K_m and P_0 T_0.
        let mut pk = p_sums[0] * k[0];
        for m in 1..4 {
            pk += p_sums[m] * k[m];
        }
        let pt = p_sums[0] * t0;
        let coupling = c0.transpose() * t0 + pk.transpose();
        let mut rotation = total.fixed_view_mut::<9, 9>(0, 0);
        rotation += kk;
        let mut upper = total.fixed_view_mut::<9, 4>(0, 9);
        upper += coupling;
        let mut lower = total.fixed_view_mut::<4, 9>(9, 0);
        lower += coupling.transpose();
        let mut corner = total.fixed_view_mut::<4, 4>(9, 9);
        corner += ff + t0.transpose() * t0 * aa[(0, 0)] + pt + pt.transpose();
        // This pose joins the prefix sums: a = (1, Sᵀc).
        let o = s.transpose() * c;
        let a = Vector4::new(1.0, o.x, o.y, o.z);
        ff += f.transpose() * f;
        let ft = f.transpose();
        for (m, sum) in p_sums.iter_mut().enumerate() {
            *sum += ft * a[m];
        }
        aa += a * a.transpose();
    }
    (total + total.transpose()) * 0.5
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::motion::{Pairing, motion_pairs};
    use crate::sim::{SimConfig, simulate};
    use crate::solve::andreff;

    #[test]
    fn equals_batch_andreff_over_all_pairs() {
        for setup in [Setup::EyeInHand, Setup::EyeToHand] {
            let s = simulate(
                &SimConfig {
                    poses: 40,
                    ..SimConfig::default()
                },
                9,
                0,
            );
            let mut acc = PoseAccumulator::new(setup);
            for (k, p) in s.poses.iter().enumerate() {
                acc.add(p);
                if k + 1 >= 5 && (k + 1) % 7 == 0 {
                    let batch = andreff(&motion_pairs(&s.poses[..=k], Pairing::All, setup))
                        .unwrap()
                        .x;
                    let ours = acc.estimate().unwrap().x;
                    let d = (ours.to_homogeneous() - batch.to_homogeneous()).abs().max();
                    let scale = batch.translation.vector.norm().max(1.0);
                    // Measured: ≤ 3e-14 of the scale eye-in-hand, ≤ 2e-12 eye-to-hand (these poses,
                    // simulated eye-in-hand, make a poorly determined eye-to-hand system).
                    let tolerance = match setup {
                        Setup::EyeInHand => 1e-12,
                        Setup::EyeToHand => 1e-10,
                    };
                    assert!(
                        d <= tolerance * scale,
                        "{} after {} poses: {d:e}",
                        setup.name(),
                        k + 1
                    );
                }
            }
        }
    }

    #[test]
    fn the_covariance_is_the_inverse_of_the_finite_difference_information() {
        use crate::model::pose::{exp_so3, log_so3};
        let s = simulate(&SimConfig::default(), 6, 0);
        let poses = &s.poses[..60];
        let setup = Setup::EyeInHand;
        let mut acc = PoseAccumulator::new(setup);
        poses.iter().for_each(|p| acc.add(p));
        let x = s.gripper_from_camera;
        let (sr, st) = (0.002, 0.7);
        let got = acc.covariance(&x, sr, st).unwrap();
        // Y_k's left perturbation in the base frame under X moved by δ (gripper frame).
        let y = acc.residual_scatter(&x).unwrap().y;
        let residual = |d: &nalgebra::Vector6<f64>, p: &PosePair| {
            let r = exp_so3(&Vector3::new(d[0], d[1], d[2])) * rotation_matrix(&x);
            let t = x.translation.vector + Vector3::new(d[3], d[4], d[5]);
            let y_k = p.base_from_gripper * transform_from_parts(&r, &t) * p.camera_from_target;
            let e = y_k * y.inverse();
            let mut v = nalgebra::Vector6::zeros();
            v.fixed_rows_mut::<3>(0)
                .copy_from(&log_so3(e.rotation.matrix()));
            v.fixed_rows_mut::<3>(3).copy_from(&e.translation.vector);
            v
        };
        let h = 1e-6;
        let jacobian = |p: &PosePair| {
            SMatrix::<f64, 6, 6>::from_fn(|row, col| {
                let mut d = nalgebra::Vector6::zeros();
                d[col] = h;
                (residual(&d, p)[row] - residual(&(-d), p)[row]) / (2.0 * h)
            })
        };
        let w = SMatrix::<f64, 6, 6>::from_diagonal(&nalgebra::Vector6::new(
            1.0 / (sr * sr),
            1.0 / (sr * sr),
            1.0 / (sr * sr),
            1.0 / (st * st),
            1.0 / (st * st),
            1.0 / (st * st),
        ));
        let (mut info, mut sum) = (SMatrix::<f64, 6, 6>::zeros(), SMatrix::<f64, 6, 6>::zeros());
        for p in poses {
            let a = jacobian(p);
            info += a.transpose() * w * a;
            sum += a;
        }
        let info = info - sum.transpose() * w * sum / poses.len() as f64;
        let expected = info.try_inverse().unwrap();
        let d = (got - expected).abs().max() / expected.abs().max();
        // The closed form drops the residuals themselves from the Jacobian (first order).
        assert!(d < 1e-2, "relative difference {d:e}\n{got}\n{expected}");
    }

    /// Every sum of a [`MergeableAccumulator`], by name.
    fn named_sums(m: &MergeableAccumulator) -> Vec<(&'static str, Vec<f64>)> {
        let a = &m.poses;
        let v = |x: &[f64]| x.to_vec();
        vec![
            ("n", vec![a.n as f64]),
            ("g", v(a.g.as_slice())),
            ("u", v(a.u.as_slice())),
            ("p", v(a.p.as_slice())),
            ("w", v(a.w.as_slice())),
            ("q", v(a.q.as_slice())),
            ("t", v(a.t.as_slice())),
            ("e", v(a.e.as_slice())),
            ("n_c", v(a.n_c.as_slice())),
            ("c", v(a.c.as_slice())),
            ("cw", v(a.cw.as_slice())),
            ("cc_ww", vec![a.cc_ww]),
            ("pp", vec![a.pp]),
            ("cc", vec![a.cc]),
            ("pr", v(a.pr.as_slice())),
            ("ww", v(a.ww.as_slice())),
            ("s", v(m.s.as_slice())),
            ("s_q", v(m.s_q.as_slice())),
            ("r_sq", v(m.r_sq.as_slice())),
        ]
    }

    /// The largest difference between two accumulators' sums, each relative to its sum's
    /// largest entry, and the sum it is in.
    fn largest_relative_difference(
        a: &MergeableAccumulator,
        b: &MergeableAccumulator,
    ) -> (f64, &'static str) {
        named_sums(a)
            .into_iter()
            .zip(named_sums(b))
            .map(|((name, x), (_, y))| {
                let scale = x.iter().chain(&y).fold(0.0f64, |m, v| m.max(v.abs()));
                let d = x
                    .iter()
                    .zip(&y)
                    .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
                (if scale > 0.0 { d / scale } else { d }, name)
            })
            .fold((0.0, ""), |m, d| if d.0 > m.0 { d } else { m })
    }

    fn random_pose() -> impl proptest::strategy::Strategy<Value = PosePair> {
        use proptest::prelude::*;
        let vector = |size: f64| {
            (-size..size, -size..size, -size..size).prop_map(|(x, y, z)| Vector3::new(x, y, z))
        };
        (vector(600.0), vector(2.0), vector(900.0), vector(2.0)).prop_map(|(p, r, c, s)| PosePair {
            base_from_gripper: Transform::new(p, r),
            camera_from_target: Transform::new(c, s),
        })
    }

    proptest::proptest! {
        #[test]
        fn a_prefix_merged_with_a_suffix_equals_every_pose_added_in_order(
            poses in proptest::collection::vec(random_pose(), 0..40),
            split in 0.0..=1.0f64,
        ) {
            let m = ((poses.len() as f64 * split) as usize).min(poses.len());
            for setup in [Setup::EyeInHand, Setup::EyeToHand] {
                let mut in_order = MergeableAccumulator::new(setup);
                poses.iter().for_each(|p| in_order.add(p));
                let (mut prefix, mut suffix) =
                    (MergeableAccumulator::new(setup), MergeableAccumulator::new(setup));
                poses[..m].iter().for_each(|p| prefix.add(p));
                poses[m..].iter().for_each(|p| suffix.add(p));
                prefix.merge(&suffix);
                let (d, name) = largest_relative_difference(&prefix, &in_order);
                // Measured: at most 2e-15 (256 cases); dropping any one of the four cross terms of
                // `merge` makes E differ by 100%.
                proptest::prop_assert!(
                    d <= 1e-12,
                    "{setup:?}, {} poses split at {m}: {name} differs by {d:e}",
                    poses.len()
                );
                proptest::prop_assert_eq!(prefix.accumulator().poses(), poses.len());
            }
        }
    }

    #[test]
    fn merging_one_pose_at_a_time_from_the_back_equals_adding_in_order() {
        // The leave-one-out check's backward pass: each pose merged before the later ones.
        let s = simulate(&SimConfig::default(), 5, 0);
        for setup in [Setup::EyeInHand, Setup::EyeToHand] {
            let mut in_order = MergeableAccumulator::new(setup);
            s.poses.iter().for_each(|p| in_order.add(p));
            let mut suffix = MergeableAccumulator::new(setup);
            for p in s.poses.iter().rev() {
                let mut one = MergeableAccumulator::new(setup);
                one.add(p);
                one.merge(&suffix);
                suffix = one;
            }
            let (d, name) = largest_relative_difference(&suffix, &in_order);
            assert!(d <= 1e-12, "{setup:?}: {name} differs by {d:e}");
            let (x, y) = (
                suffix.accumulator().estimate().unwrap().x,
                in_order.accumulator().estimate().unwrap().x,
            );
            assert!((x.to_homogeneous() - y.to_homogeneous()).amax() < 1e-9);
        }
    }
}
