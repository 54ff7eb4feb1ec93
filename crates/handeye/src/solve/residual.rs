//! The A X − X B residual of one motion, and what the solvers and the metrics build on it: the
//! residual summaries, the block scales, the Jacobian of the refinement and its Gauss–Newton
//! covariance. Below the solvers ([`solve()`](crate::solve())) and the checks of an X (`check::quality`).
//!
//! The residual of a motion pair (A, B) under X is ΔR = R_a R_x − R_x R_b and
//! ΔT = R_a t_x + t_a − R_x t_b − t_x (the paper's sec. 4.2). Both are linear in
//! z = [vec R_x; t_x; 1] (row-major vec): `vec ΔR = (R_a ⊗ I − I ⊗ R_bᵀ) vec R_x` and
//! `ΔT = [−(I ⊗ t_bᵀ), R_a − I, t_a] z`. So the squared residuals summed over any set of motions
//! are a quadratic form `zᵀ M z` (`solve::quadratic::Quadratic`); over all pairs of n poses its matrices
//! accumulate in O(n) (`solve::accumulate::PairSums`) and a refinement costs O(1) per iteration.

use nalgebra::{Matrix3, Matrix6, SMatrix, Vector3, Vector6};
use serde::{Deserialize, Serialize};

use crate::model::motion::MotionPair;
use crate::model::pose::{Transform, axis_angle, rotation_angle_between, rotation_matrix, skew};
use crate::solve::lm::Linearisation;
use crate::solve::motions::{AllPairs, MotionSource};
use crate::solve::quadratic::{Quadratic, z_jacobian, z_of};

/// Smallest ‖t‖ used as a divisor in relative translation errors (an X with zero translation
/// would otherwise divide by zero).
pub(crate) const MIN_NORM: f64 = 1e-300;

/// A block RMS below this counts as this, so that exact data does not divide by zero (SPEC sec. 3).
/// For the ΔT block it is in units of the data's length scale (see `solve::refine`), not of the
/// input: 1e-12 of a kilometre and 1e-12 of a micrometre are the same floor relative to the data.
pub(crate) const MIN_BLOCK_RMS: f64 = 1e-12;

/// The residual of one motion pair under X: ΔR = R_a R_x − R_x R_b and
/// ΔT = R_a t_x + t_a − R_x t_b − t_x (the paper's sec. 4.2, `A X − X B`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotionResidual {
    /// ΔR, the rotation block of A X − X B.
    pub delta_r: Matrix3<f64>,
    /// ΔT, the translation column of A X − X B (input length units).
    pub delta_t: Vector3<f64>,
    /// Angle between R_a R_x and R_x R_b, degrees.
    pub rotation_deg: f64,
}

impl MotionResidual {
    /// The residual of motion pair `m` under `x`.
    pub fn of(m: &MotionPair, x: &Transform) -> Self {
        let (delta_r, delta_t) = delta(m, &rotation_matrix(x), &x.translation.vector);
        Self {
            delta_r,
            delta_t,
            rotation_deg: rotation_angle_between(
                &(m.a.rotation * x.rotation),
                &(x.rotation * m.b.rotation),
            )
            .to_degrees(),
        }
    }
}

/// One pose's disagreement with the fixed frame Y that all poses share: Y_i = Q_i X C_i (the fixed
/// frame as pose i and X see it, Q_i the hand pose) against Y, as a rotation and a translation.
/// The hand–eye checks take it in the target frame, D_i = Y⁻¹ Y_i
/// (`check::outliers::PoseResiduals`); the robot-world report in the fixed frame,
/// R_Yᵀ R_Yi and t_Yi − t_Y (`solve::pose_residuals`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseResidual {
    /// The rotation as a rotation vector θk, radians (`log_so3` of the rotation).
    pub rotation: Vector3<f64>,
    /// The rotation angle θ, radians (‖`rotation`‖ up to rounding).
    pub angle: f64,
    /// The translation, input units.
    pub translation: Vector3<f64>,
}

impl PoseResidual {
    /// The residual of a rotation (a rotation matrix) and a translation.
    pub fn new(rotation: &Matrix3<f64>, translation: Vector3<f64>) -> Self {
        let (angle, axis) = axis_angle(rotation);
        Self {
            rotation: axis.map_or_else(Vector3::zeros, |k| k * angle),
            angle,
            translation,
        }
    }

    /// The rotation angle θ, degrees.
    pub fn angle_deg(&self) -> f64 {
        self.angle.to_degrees()
    }

    /// The length of the translation, input units.
    pub fn distance(&self) -> f64 {
        self.translation.norm()
    }
}

/// ΔR and ΔT of one motion at (R_x, t_x).
pub(crate) fn delta(
    m: &MotionPair,
    r_x: &Matrix3<f64>,
    t_x: &Vector3<f64>,
) -> (Matrix3<f64>, Vector3<f64>) {
    let r_a = rotation_matrix(&m.a);
    let r_b = rotation_matrix(&m.b);
    let dr = r_a * r_x - r_x * r_b;
    let dt = r_a * t_x + m.a.translation.vector - r_x * m.b.translation.vector - t_x;
    (dr, dt)
}

/// The 12×6 Jacobian of one motion's residuals (the 9 entries of ΔR row-major, then ΔT), each
/// block multiplied by its weight, for the increment `R_x exp([δ]×)`, `t_x + Δt`.
///
/// ∂ΔR/∂δ_m = R_a R_x [e_m]× − R_x [e_m]× R_b, ∂ΔT/∂δ_m = −R_x [e_m]× t_b, ∂ΔT/∂t = R_a − I.
pub(crate) fn jacobian(
    m: &MotionPair,
    r_x: &Matrix3<f64>,
    weights: [f64; 2],
) -> SMatrix<f64, 12, 6> {
    let r_a = rotation_matrix(&m.a);
    let r_b = rotation_matrix(&m.b);
    let t_b = m.b.translation.vector;
    let ar = r_a * r_x;
    let mut j = SMatrix::<f64, 12, 6>::zeros();
    for c in 0..3 {
        let e = skew(&Vector3::ith(c, 1.0));
        let d_r = (ar * e - r_x * e * r_b) * weights[0];
        let d_t = -(r_x * e * t_b) * weights[1];
        for row in 0..3 {
            for col in 0..3 {
                j[(3 * row + col, c)] = d_r[(row, col)];
            }
            j[(9 + row, c)] = d_t[row];
        }
    }
    let dta = (r_a - Matrix3::identity()) * weights[1];
    j.fixed_view_mut::<3, 3>(9, 3).copy_from(&dta);
    j
}

/// The weighted residual vector of one motion: the 9 entries of ΔR (row-major), then ΔT.
fn weighted(dr: &Matrix3<f64>, dt: &Vector3<f64>, weights: [f64; 2]) -> SMatrix<f64, 12, 1> {
    let mut r = SMatrix::<f64, 12, 1>::zeros();
    for row in 0..3 {
        for col in 0..3 {
            r[3 * row + col] = dr[(row, col)] * weights[0];
        }
        r[9 + row] = dt[row] * weights[1];
    }
    r
}

/// The paper's residual form of rmsR and rmsT (SPEC sec. 2), used when no ground truth exists.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ResidualRms {
    /// RMS of all ΔR entries.
    pub rms_r: f64,
    /// RMS of all ΔT entries divided by ‖t̂_x‖ (unit-free like the relative translation error).
    pub rms_t: f64,
}

/// rmsR and rmsT of the residuals of `motions` under `x` (SPEC sec. 2, residual form).
pub fn residual_rms(motions: &(impl MotionSource + ?Sized), x: &Transform) -> ResidualRms {
    let sums = block_sums(motions, &rotation_matrix(x), &x.translation.vector);
    let n = sums.count.max(1) as f64;
    ResidualRms {
        rms_r: (sums.rotation / (9.0 * n)).sqrt(),
        rms_t: (sums.translation / (3.0 * n)).sqrt() / x.translation.vector.norm().max(MIN_NORM),
    }
}

/// Σ‖ΔR‖²_F and Σ‖ΔT‖² of `motions` at (R_x, t_x): from the all-pairs sums when the motions are
/// all pairs of a pose sequence, else motion by motion.
pub(crate) fn block_sums(
    motions: &(impl MotionSource + ?Sized),
    r_x: &Matrix3<f64>,
    t_x: &Vector3<f64>,
) -> BlockRms {
    match motions.all_pairs() {
        Some(pairs) => pairs.sums().quadratic().block_rms(r_x, t_x),
        None => PerMotion(motions).block_rms(r_x, t_x),
    }
}

/// Sums of squares of the rotation-matrix entries and of the translation entries of residuals;
/// [`Self::scales`] gives their RMS, each floored at [`MIN_BLOCK_RMS`]: the block scales that keep
/// either block from dominating (SPEC sec. 3), for hand–eye motions and robot-world poses alike.
#[derive(Debug, Default, Clone, Copy, PartialEq)]
pub(crate) struct BlockRms {
    /// Σ‖ΔR‖²_F.
    pub(crate) rotation: f64,
    /// Σ‖ΔT‖².
    pub(crate) translation: f64,
    /// Residuals summed.
    pub(crate) count: usize,
}

impl BlockRms {
    /// Adds one residual: ΔR (3×3) and ΔT.
    pub(crate) fn add(&mut self, dr: &Matrix3<f64>, dt: &Vector3<f64>) {
        self.rotation += dr.norm_squared();
        self.translation += dt.norm_squared();
        self.count += 1;
    }

    /// [rotation, translation] RMS per entry.
    pub(crate) fn scales(&self) -> [f64; 2] {
        let n = self.count.max(1) as f64;
        [
            (self.rotation / (9.0 * n)).sqrt().max(MIN_BLOCK_RMS),
            (self.translation / (3.0 * n)).sqrt().max(MIN_BLOCK_RMS),
        ]
    }
}

/// The residuals of a set of motions as the refinement sees them. `weights` multiply the ΔR and
/// the ΔT block.
pub(crate) trait Residuals {
    /// Number of motions.
    fn count(&self) -> usize;
    /// Σ‖ΔR‖² and Σ‖ΔT‖² at (R_x, t_x).
    fn block_rms(&self, r_x: &Matrix3<f64>, t_x: &Vector3<f64>) -> BlockRms;
    /// JᵀJ, Jᵀr and ½Σr² at (R_x, t_x).
    fn linearise(
        &self,
        r_x: &Matrix3<f64>,
        t_x: &Vector3<f64>,
        weights: [f64; 2],
    ) -> Linearisation<6>;

    /// Weighted cost ½Σr² at (R_x, t_x).
    fn cost(&self, r_x: &Matrix3<f64>, t_x: &Vector3<f64>, weights: [f64; 2]) -> f64;

    /// The change of the weighted cost from (R_x, t_x), where it is `cost`, to (R, t).
    fn cost_change(
        &self,
        from: (&Matrix3<f64>, &Vector3<f64>),
        to: (&Matrix3<f64>, &Vector3<f64>),
        cost: f64,
        weights: [f64; 2],
    ) -> f64 {
        let _ = from;
        self.cost(to.0, to.1, weights) - cost
    }
}

/// The residuals evaluated motion by motion.
pub(crate) struct PerMotion<'a, M: MotionSource + ?Sized>(pub(crate) &'a M);

impl<M: MotionSource + ?Sized> Residuals for PerMotion<'_, M> {
    fn count(&self) -> usize {
        self.0.count()
    }

    fn cost(&self, r_x: &Matrix3<f64>, t_x: &Vector3<f64>, weights: [f64; 2]) -> f64 {
        let mut sum = 0.0;
        self.0.for_each_motion(|m| {
            let (dr, dt) = delta(m, r_x, t_x);
            sum += (weights[0] * weights[0]) * dr.norm_squared()
                + (weights[1] * weights[1]) * dt.norm_squared();
        });
        0.5 * sum
    }

    fn block_rms(&self, r_x: &Matrix3<f64>, t_x: &Vector3<f64>) -> BlockRms {
        let mut rms = BlockRms::default();
        self.0.for_each_motion(|m| {
            let (dr, dt) = delta(m, r_x, t_x);
            rms.add(&dr, &dt);
        });
        rms
    }

    fn linearise(
        &self,
        r_x: &Matrix3<f64>,
        t_x: &Vector3<f64>,
        weights: [f64; 2],
    ) -> Linearisation<6> {
        let mut jtj = Matrix6::zeros();
        let mut jtr = Vector6::zeros();
        let mut cost = 0.0;
        self.0.for_each_motion(|m| {
            let (dr, dt) = delta(m, r_x, t_x);
            let j = jacobian(m, r_x, weights);
            let r = weighted(&dr, &dt, weights);
            jtj += j.transpose() * j;
            jtr += j.transpose() * r;
            cost += 0.5 * r.norm_squared();
        });
        Linearisation { jtj, jtr, cost }
    }
}

impl Residuals for Quadratic {
    fn count(&self) -> usize {
        self.motions
    }

    fn cost(&self, r_x: &Matrix3<f64>, t_x: &Vector3<f64>, weights: [f64; 2]) -> f64 {
        let z = z_of(r_x, t_x);
        0.5 * z.dot(&(self.weighted(weights) * z))
    }

    /// `½ (z' − z)ᵀ M (z' + z)`: the change itself rather than the difference of two costs, which
    /// near the minimum is lost in the rounding of the large terms the costs are made of.
    fn cost_change(
        &self,
        from: (&Matrix3<f64>, &Vector3<f64>),
        to: (&Matrix3<f64>, &Vector3<f64>),
        _cost: f64,
        weights: [f64; 2],
    ) -> f64 {
        let (z, z_new) = (z_of(from.0, from.1), z_of(to.0, to.1));
        0.5 * (z_new - z).dot(&(self.weighted(weights) * (z_new + z)))
    }

    fn block_rms(&self, r_x: &Matrix3<f64>, t_x: &Vector3<f64>) -> BlockRms {
        let z = z_of(r_x, t_x);
        let v = z.fixed_rows::<9>(0);
        // Rounding can leave a sum of squares slightly negative; it is at least 0.
        BlockRms {
            rotation: v.dot(&(self.rotation * v)).max(0.0),
            translation: z.dot(&(self.translation * z)).max(0.0),
            count: self.motions,
        }
    }

    fn linearise(
        &self,
        r_x: &Matrix3<f64>,
        t_x: &Vector3<f64>,
        weights: [f64; 2],
    ) -> Linearisation<6> {
        let z = z_of(r_x, t_x);
        let j = z_jacobian(r_x);
        let m = self.weighted(weights);
        let mj = m * j;
        let jtj = j.transpose() * mj;
        Linearisation {
            jtj: (jtj + jtj.transpose()) * 0.5,
            jtr: mj.transpose() * z,
            cost: 0.5 * z.dot(&(m * z)),
        }
    }
}

/// Covariance of (δ, t) at (R_x, t_x): `s² (JᵀJ)⁻¹` of the problem weighted by the block RMS
/// values at that point, with `s² = Σr² / (N − 6)` for N residuals (Gauss–Newton with each
/// block's noise estimated from its own residuals). `None` when JᵀJ is singular or there are too
/// few residuals.
pub(crate) fn covariance(
    residuals: &dyn Residuals,
    r_x: &Matrix3<f64>,
    t_x: &Vector3<f64>,
) -> Option<Matrix6<f64>> {
    let count = 12 * residuals.count();
    if count <= 6 {
        return None;
    }
    let scales = residuals.block_rms(r_x, t_x).scales();
    let lin = residuals.linearise(r_x, t_x, [1.0 / scales[0], 1.0 / scales[1]]);
    let s2 = 2.0 * lin.cost / (count - 6) as f64;
    lin.jtj.try_inverse().map(|inv| inv * s2)
}

/// One pose of an all-pairs sequence seen through X (or through any 3×3 V in place of R_x): the
/// rotation R_k of Q_k and S_k of C_k = (S_k, c_k) = `camera_from_target`, the deviations
/// D_k = W_k − W̄ and e_k = y_k − ȳ of the fixed frame Q_k X C_k (rotation W_k = R_k R_x S_k,
/// translation y_k) from their means, and o_k = S_kᵀ c_k; in a base frame at the mean hand
/// position and a target frame at the mean of the o_k (which change no motion).
///
/// The residual of the motion from pose j to pose i is the disagreement of the two poses:
/// `R_j ΔR S_i = W_i − W_j = D_i − D_j` and `R_j ΔT = g_i − e_j + D_j o_i`, g = e − D o. Every
/// factor is a deviation from a mean, so sums over the pairs built from them lose no digits to
/// the cancellation of large terms.
pub(crate) struct PoseUnderX {
    pub(crate) r: Matrix3<f64>,
    pub(crate) s: Matrix3<f64>,
    pub(crate) d: Matrix3<f64>,
    pub(crate) e: Vector3<f64>,
    pub(crate) o: Vector3<f64>,
}

impl PoseUnderX {
    /// g = e − D o.
    pub(crate) fn g(&self) -> Vector3<f64> {
        self.e - self.d * self.o
    }
}

/// The poses of `pairs` seen through (R_x, t_x) ([`PoseUnderX`]).
pub(crate) fn poses_under(
    pairs: &AllPairs,
    r_x: &Matrix3<f64>,
    t_x: &Vector3<f64>,
) -> Vec<PoseUnderX> {
    let n = pairs.poses();
    let count = n.max(1) as f64;
    let p_mean = (0..n)
        .map(|k| pairs.pose(k).0.translation.vector)
        .sum::<Vector3<f64>>()
        / count;
    let o_mean = (0..n)
        .map(|k| pairs.pose(k).1.rotation.inverse() * pairs.pose(k).1.translation.vector)
        .sum::<Vector3<f64>>()
        / count;
    let mut poses: Vec<(PoseUnderX, Matrix3<f64>, Vector3<f64>)> = (0..n)
        .map(|k| {
            let (q, c) = pairs.pose(k);
            let (r, s) = (rotation_matrix(q), rotation_matrix(c));
            let p = q.translation.vector - p_mean;
            let o = s.transpose() * c.translation.vector - o_mean;
            let w = r * r_x * s;
            // y = R (R_x c + t_x) + p with the moved target frame's c = S o.
            let y = r * (r_x * (s * o) + t_x) + p;
            let pose = PoseUnderX {
                r,
                s,
                d: Matrix3::zeros(),
                e: Vector3::zeros(),
                o,
            };
            (pose, w, y)
        })
        .collect();
    let w_mean = poses.iter().map(|p| p.1).sum::<Matrix3<f64>>() / count;
    let y_mean = poses.iter().map(|p| p.2).sum::<Vector3<f64>>() / count;
    for (pose, w, y) in &mut poses {
        pose.d = *w - w_mean;
        pose.e = *y - y_mean;
    }
    poses.into_iter().map(|p| p.0).collect()
}

/// `Σ_{i<j} K_ijᵀ K_ij v` of Andreff's rotation system over all pairs, V the 3×3 of v
/// (row-major), in O(n) and without cancellation: `Σ‖K_ij v‖² = Σ_{i<j} ‖W_i − W_j‖²`
/// with W_k = R_k V S_k ([`PoseUnderX`]), whose half-gradient is `n Σ_k R_kᵀ D_k S_kᵀ`.
pub(crate) fn pairs_rotation_gradient(pairs: &AllPairs, v: &Matrix3<f64>) -> Matrix3<f64> {
    let poses = poses_under(pairs, v, &Vector3::zeros());
    poses
        .iter()
        .map(|p| p.r.transpose() * p.d * p.s.transpose())
        .sum::<Matrix3<f64>>()
        * poses.len() as f64
}

/// `Σ_{i<j} (R_a − I)ᵀ ΔT_ij` over all pairs at (R_x, t_x): the gradient in t_x of ½Σ‖ΔT‖², in
/// O(n) and without cancellation. With h_ij = R_j ΔT_ij = g_i − e_j + D_j o_i ([`PoseUnderX`])
/// and ∂h_ij/∂t_x = R_i − R_j, it is `Σ_{i<j} (R_i − R_j)ᵀ h_ij`, from prefix sums over i < j.
pub(crate) fn pairs_translation_gradient(
    pairs: &AllPairs,
    r_x: &Matrix3<f64>,
    t_x: &Vector3<f64>,
) -> Vector3<f64> {
    let poses = poses_under(pairs, r_x, t_x);
    let mut gradient = Vector3::zeros();
    // Prefix sums over i < j: Σ R_iᵀ g_i, Σ R_i, Σ g_i, Σ o_i, and T_a[b, c] = Σ R_i[b, a] o_i[c].
    let (mut rg, mut sum_r) = (Vector3::zeros(), Matrix3::zeros());
    let (mut sum_g, mut sum_o) = (Vector3::zeros(), Vector3::zeros());
    let mut t = [Matrix3::zeros(); 3];
    for (j, p) in poses.iter().enumerate() {
        // Σ_{i<j} R_iᵀ h_ij = Σ R_iᵀ g_i − (Σ R_i)ᵀ e_j + (⟨D_j, T_a⟩)_a.
        let rd = Vector3::new(p.d.dot(&t[0]), p.d.dot(&t[1]), p.d.dot(&t[2]));
        let left = rg - sum_r.transpose() * p.e + rd;
        // Σ_{i<j} R_jᵀ h_ij = R_jᵀ (Σ g_i − j e_j + D_j Σ o_i).
        let right = p.r.transpose() * (sum_g - p.e * j as f64 + p.d * sum_o);
        gradient += left - right;
        let g = p.g();
        rg += p.r.transpose() * g;
        sum_r += p.r;
        sum_g += g;
        sum_o += p.o;
        for (a, t_a) in t.iter_mut().enumerate() {
            *t_a += p.r.column(a) * p.o.transpose();
        }
    }
    gradient
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::motion::{Pairing, Setup, motion_pairs};
    use crate::model::pose::exp_so3;
    use crate::sim::{SimConfig, simulate};
    use crate::solve::motions::AllPairs;
    use crate::solve::quadratic::{Matrix9, Matrix13};

    fn problem() -> (Vec<MotionPair>, Matrix3<f64>, Vector3<f64>) {
        let s = simulate(
            &SimConfig {
                poses: 8,
                ..SimConfig::default()
            },
            5,
            0,
        );
        let motions = motion_pairs(&s.poses, Pairing::All, Setup::EyeInHand);
        // A point away from the solution, so that the residuals are not small.
        let x = s.gripper_from_camera;
        let r_x = rotation_matrix(&x) * exp_so3(&Vector3::new(0.02, -0.03, 0.01));
        let t_x = x.translation.vector + Vector3::new(3.0, -2.0, 1.0);
        (motions, r_x, t_x)
    }

    /// The residuals of every motion at the increment (δ, Δt), stacked and weighted.
    fn stacked(
        motions: &[MotionPair],
        r_x: &Matrix3<f64>,
        t_x: &Vector3<f64>,
        step: &Vector6<f64>,
        weights: [f64; 2],
    ) -> Vec<f64> {
        let r = r_x * exp_so3(&step.fixed_rows::<3>(0).into_owned());
        let t = t_x + step.fixed_rows::<3>(3);
        motions
            .iter()
            .flat_map(|m| {
                let (dr, dt) = delta(m, &r, &t);
                weighted(&dr, &dt, weights)
                    .iter()
                    .copied()
                    .collect::<Vec<_>>()
            })
            .collect()
    }

    #[test]
    fn the_jacobian_matches_central_differences() {
        let (motions, r_x, t_x) = problem();
        let weights = [2.0, 0.5];
        let h = 1e-6;
        for (k, m) in motions.iter().enumerate() {
            let j = jacobian(m, &r_x, weights);
            for c in 0..6 {
                let e = Vector6::ith(c, h);
                let plus = stacked(&motions[k..=k], &r_x, &t_x, &e, weights);
                let minus = stacked(&motions[k..=k], &r_x, &t_x, &(-e), weights);
                for row in 0..12 {
                    let numeric = (plus[row] - minus[row]) / (2.0 * h);
                    let scale = 1.0 + j[(row, c)].abs();
                    assert!(
                        (numeric - j[(row, c)]).abs() < 1e-6 * scale,
                        "motion {k} row {row} column {c}: {numeric} vs {}",
                        j[(row, c)]
                    );
                }
            }
        }
    }

    #[test]
    fn the_quadratic_form_gives_the_per_motion_normal_equations() {
        let (motions, r_x, t_x) = problem();
        let weights = [3.0, 0.25];
        let mut quadratic = Quadratic {
            rotation: Matrix9::zeros(),
            translation: Matrix13::zeros(),
            motions: motions.len(),
        };
        let mut system = crate::solve::RotationSystem::default();
        for m in &motions {
            let r_a = rotation_matrix(&m.a);
            system.add(&r_a, &rotation_matrix(&m.b));
            // L_k = [−(I ⊗ t_bᵀ), R_a − I, t_a].
            let mut l = SMatrix::<f64, 3, 13>::zeros();
            let t_b = m.b.translation.vector;
            for row in 0..3 {
                for col in 0..3 {
                    l[(row, 3 * row + col)] = -t_b[col];
                }
            }
            l.fixed_view_mut::<3, 3>(0, 9)
                .copy_from(&(r_a - Matrix3::identity()));
            l.fixed_view_mut::<3, 1>(0, 12)
                .copy_from(&m.a.translation.vector);
            quadratic.translation += l.transpose() * l;
        }
        quadratic.rotation = *system.normal_matrix();
        let per_motion = PerMotion(&motions[..]).linearise(&r_x, &t_x, weights);
        let from_form = quadratic.linearise(&r_x, &t_x, weights);
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-10 * (1.0 + a.abs().max(b.abs()));
        assert!(close(per_motion.cost, from_form.cost));
        for k in 0..36 {
            assert!(close(per_motion.jtj[k], from_form.jtj[k]), "JᵀJ entry {k}");
        }
        for k in 0..6 {
            assert!(close(per_motion.jtr[k], from_form.jtr[k]), "Jᵀr entry {k}");
        }
        // In another length unit the form is the one of the scaled motions.
        let unit = 8.0;
        let scaled = crate::solve::Scaled::new(&motions[..], unit);
        let a = PerMotion(&scaled).block_rms(&r_x, &(t_x / unit));
        let b = quadratic.in_unit(unit).block_rms(&r_x, &(t_x / unit));
        assert!(close(a.rotation, b.rotation) && close(a.translation, b.translation));
        // And the all-pairs sums of the poses build the same form.
        let s = simulate(
            &SimConfig {
                poses: 8,
                ..SimConfig::default()
            },
            5,
            0,
        );
        for setup in [Setup::EyeInHand, Setup::EyeToHand] {
            let pairs = AllPairs::new(&s.poses, setup);
            let stored = motion_pairs(&s.poses, Pairing::All, setup);
            let a = PerMotion(&stored[..]).linearise(&r_x, &t_x, weights);
            let b = pairs.sums().quadratic().linearise(&r_x, &t_x, weights);
            assert!(close(a.cost, b.cost), "{setup:?}: {} vs {}", a.cost, b.cost);
            for k in 0..36 {
                assert!(close(a.jtj[k], b.jtj[k]), "{setup:?} JᵀJ entry {k}");
            }
        }
    }

    #[test]
    fn the_per_pose_gradients_are_the_motion_by_motion_ones() {
        let s = simulate(
            &SimConfig {
                poses: 9,
                ..SimConfig::default()
            },
            4,
            0,
        );
        let (_, r_x, t_x) = problem();
        let v = r_x * 0.9 + Matrix3::new(0.01, 0.0, -0.02, 0.0, 0.03, 0.0, 0.01, 0.0, 0.0);
        for setup in [Setup::EyeInHand, Setup::EyeToHand] {
            let pairs = AllPairs::new(&s.poses, setup);
            let stored = motion_pairs(&s.poses, Pairing::All, setup);
            let mut rotation = Matrix3::zeros();
            let mut translation = Vector3::zeros();
            for m in &stored {
                let (r_a, r_b) = (rotation_matrix(&m.a), rotation_matrix(&m.b));
                let w = v - r_a * v * r_b.transpose();
                rotation += w - r_a.transpose() * w * r_b;
                let (_, dt) = delta(m, &r_x, &t_x);
                translation += (r_a - Matrix3::identity()).transpose() * dt;
            }
            let a = pairs_rotation_gradient(&pairs, &v);
            assert!((a - rotation).norm() < 1e-12 * rotation.norm(), "{setup:?}");
            let b = pairs_translation_gradient(&pairs, &r_x, &t_x);
            assert!(
                (b - translation).norm() < 1e-12 * translation.norm(),
                "{setup:?}"
            );
        }
    }
}
