//! Robot-world–hand-eye calibration, A X = Z B: X and the target's pose together, from absolute
//! poses.
//!
//! # Frames
//! Every pose i gives Q_i = the hand pose ([`Setup::hand_pose`]: `base_from_gripper` eye-in-hand,
//! `gripper_from_base` eye-to-hand) and C_i = `camera_from_target`. With X = `gripper_from_camera`
//! (eye-in-hand) or `base_from_camera` (eye-to-hand) and the fixed target pose
//! Y = `base_from_target` (eye-in-hand) or `gripper_from_target` (eye-to-hand),
//!
//! **Q_i X C_i = Y** for every pose (the chain from the fixed frame to the target through the robot
//! and the camera).
//!
//! # OpenCV's form
//! OpenCV's `calibrateRobotWorldHandEye(R/t_world2cam, R/t_base2gripper, …)` solves
//! A_i X' = Z' B_i with A_i = `world2cam` = `camera_from_world`, B_i = `base2gripper` =
//! `gripper_from_base`, X' = `base2world` = `world_from_base`, Z' = `gripper2cam` =
//! `camera_from_gripper`. Its "world" is the target. In handeye's terms
//! - A_i = C_i (`camera_from_target`) and B_i = Q_i⁻¹;
//! - OpenCV's X' = Y⁻¹ (`target_from_base` / `target_from_gripper`);
//! - OpenCV's Z' = X⁻¹ (`camera_from_gripper` / `camera_from_base`).
//!
//! (C_i Y⁻¹ = X⁻¹ Q_i⁻¹ is Q_i X C_i = Y inverted.) So for eye-in-hand OpenCV's inputs are
//! `camera_from_target` and `gripper_from_base` = `base_from_gripper`⁻¹, and its outputs are
//! inverted to give X and the target pose; for eye-to-hand its B_i is `base_from_gripper` itself.
//! [`shah`] and [`li`] build OpenCV's A_i, B_i this way and solve OpenCV's equations, so the same
//! data give OpenCV's answer.
//!
//! # Methods
//! - [`shah`]: Shah's closed form (Kronecker product, SVD of a 9×9 sum, then translation by least
//!   squares).
//! - [`li`]: Li et al.'s simultaneous 24-unknown linear form.
//! - [`refine_robot_world`]: Levenberg–Marquardt on the per-pose residuals of Q_i X C_i = Y over
//!   X and Y together, started from [`shah`].
//!
//! Degenerate data are refused as by the hand–eye solvers ([`check_motions`] on the motions
//! between consecutive poses): fewer than 3 poses ([`Error::TooFewMotions`] with `need: 2`
//! motions), rotations all ≈ 0 or all about one axis ([`Error::Degenerate`]).

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};
use serde::{Deserialize, Serialize};

use crate::model::error::{Degeneracy, Error, Result};
use crate::model::motion::{Pairing, PosePair, Setup, motion_pairs};
use crate::model::pose::{
    Transform, exp_so3, proj_so3, rotation_matrix, skew, transform_from_parts,
};
use crate::model::warning::Warning;
use crate::solve::lm::{LeastSquares, Linearisation, levenberg_marquardt};
use crate::solve::residual::{BlockRms, PoseResidual};
use crate::solve::scale::weighting_from_scale;
use crate::solve::{RefineOptions, Termination, check_motions, singular};

/// The robot-world solvers, by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RobotWorldMethod {
    /// Shah's closed form (OpenCV's `CALIB_ROBOT_WORLD_HAND_EYE_SHAH`).
    Shah,
    /// Li, Wang and Wu's simultaneous Kronecker form (OpenCV's `CALIB_ROBOT_WORLD_HAND_EYE_LI`).
    Li,
    /// Joint Levenberg–Marquardt over X and the target pose, started from Shah.
    Refine,
    /// X and the target pose on the pixels of the detections
    /// ([`calibrate`](crate::calibrate()) with [`Problem::RobotWorld`](crate::Problem::RobotWorld) on
    /// [`Input::Pixels`](crate::Input::Pixels)): not a
    /// solver of poses, so not in [`RobotWorldMethod::ALL`], and the pose solver `robot_world` refuses it.
    Reprojection,
}

crate::named_enum!(RobotWorldMethod, "robot-world method", "method" {
    Shah => "shah",
    Li => "li",
    Refine => "refine";
    not listed: Reprojection => "reprojection",
});

/// The result of a robot-world solve.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RobotWorld {
    /// X: `gripper_from_camera` (eye-in-hand) or `base_from_camera` (eye-to-hand).
    pub x: Transform,
    /// The target's pose Y: `base_from_target` (eye-in-hand) or `gripper_from_target`
    /// (eye-to-hand).
    pub target: Transform,
    /// The method.
    pub method: RobotWorldMethod,
    /// Poses used.
    pub poses: usize,
    /// Conditioning of Andreff's rotation system over the consecutive motions (1 is ideal), as
    /// for the hand–eye solvers.
    pub conditioning: f64,
    /// Cautions about the data.
    pub warnings: Vec<Warning>,
}

/// The target pose's frame name for a setup: `base_from_target` or `gripper_from_target`.
pub fn target_frame(setup: Setup) -> &'static str {
    match setup {
        Setup::EyeInHand => "base_from_target",
        Setup::EyeToHand => "gripper_from_target",
    }
}

/// What the checks learned: OpenCV's A_i, B_i and the motion check.
struct Prepared {
    /// (A_i, B_i) = (C_i, Q_i⁻¹) per pose.
    ab: Vec<(Transform, Transform)>,
    conditioning: f64,
    warnings: Vec<Warning>,
}

fn prepare(poses: &[PosePair], setup: Setup) -> Result<Prepared> {
    if poses.len() < 3 {
        return Err(Error::TooFewMotions {
            got: poses.len().saturating_sub(1),
            need: 2,
        });
    }
    let check = check_motions(&motion_pairs(poses, Pairing::Consecutive, setup))?;
    let ab = poses
        .iter()
        .map(|p| {
            (
                p.camera_from_target,
                setup.hand_pose(&p.base_from_gripper).inverse(),
            )
        })
        .collect();
    Ok(Prepared {
        ab,
        conditioning: check.conditioning,
        warnings: check.warnings,
    })
}

/// Builds the result from OpenCV's X' (`target_from_…`) and Z' (`camera_from_…`).
fn finish(
    method: RobotWorldMethod,
    p: Prepared,
    x_cv: (&Matrix3<f64>, &Vector3<f64>),
    z_cv: (&Matrix3<f64>, &Vector3<f64>),
) -> RobotWorld {
    RobotWorld {
        x: transform_from_parts(z_cv.0, z_cv.1).inverse(),
        target: transform_from_parts(x_cv.0, x_cv.1).inverse(),
        method,
        poses: p.ab.len(),
        conditioning: p.conditioning,
        warnings: p.warnings,
    }
}

/// Row-major Kronecker product of two 3×3 matrices: `(M ⊗ N)[(3i+k, 3j+l)] = M[i,j] N[k,l]`, so
/// that `vec(M V Nᵀ) = (M ⊗ N) vec(V)` for row-major vec.
fn kron(m: &Matrix3<f64>, n: &Matrix3<f64>) -> SMatrix<f64, 9, 9> {
    SMatrix::<f64, 9, 9>::from_fn(|r, c| m[(r / 3, c / 3)] * n[(r % 3, c % 3)])
}

/// The 3×3 matrix of a row-major 9-vector.
fn unvec(v: &[f64]) -> Matrix3<f64> {
    Matrix3::from_row_slice(&v[..9])
}

/// OpenCV's `normalizeRotation`: scale to unit determinant (keeping its sign), then the nearest
/// rotation. `None` when the determinant is below single-precision epsilon.
fn normalize_rotation(m: &Matrix3<f64>) -> Option<Matrix3<f64>> {
    let det = m.determinant();
    if !det.is_finite() || det.abs() < f64::from(f32::EPSILON) {
        return None;
    }
    Some(proj_so3(&(m * (det.signum() / det.abs()).cbrt())))
}

/// Shah's closed-form robot-world–hand-eye solution, as OpenCV's `CALIB_ROBOT_WORLD_HAND_EYE_SHAH`.
///
/// In OpenCV's form A_i X' = Z' B_i (see the module docs), R_Z' = R_A R_X' R_Bᵀ gives
/// vec(R_Z') = (R_A ⊗ R_B) vec(R_X') for every pose: vec(R_X') and vec(R_Z') are the first right
/// and left singular vectors of K = Σ R_A ⊗ R_B (singular value n). Each is normalised to unit
/// determinant and projected onto SO(3); then (t_X', t_Z') is the least-squares solution of the
/// stacked −R_A t_X' + t_Z' = t_A − R_Z' t_B.
///
/// # References
/// M. Shah, "Solving the robot-world/hand-eye calibration problem using the Kronecker product",
/// Journal of Mechanisms and Robotics 5, 031007, 2013 (sec. 3).
///
/// # Example
/// ```
/// use handeye::solve::shah;
/// use handeye::{PosePair, Setup, Transform};
/// use nalgebra::{Rotation3, Translation3, Vector3};
/// let x = Transform::from_parts(Translation3::new(0.1, 0.0, 0.05), Rotation3::from_euler_angles(0.1, 0.2, 0.3));
/// let base_from_target = Transform::new(Vector3::new(0.8, 0.1, 0.0), Vector3::new(0.0, 3.0, 0.2));
/// let poses: Vec<PosePair> = [(0.1, 0.2, 0.3), (-0.4, 0.1, 0.2), (0.3, -0.5, 0.1), (0.2, 0.1, -0.6)]
///     .iter()
///     .map(|&(a, b, c)| {
///         let base_from_gripper = Transform::new(Vector3::new(0.3 * a, 0.2, b), Vector3::new(a, b, c));
///         PosePair { base_from_gripper, camera_from_target: (base_from_gripper * x).inverse() * base_from_target }
///     })
///     .collect();
/// let rw = shah(&poses, Setup::EyeInHand)?;
/// assert!((rw.x.to_homogeneous() - x.to_homogeneous()).norm() < 1e-9);
/// assert!((rw.target.to_homogeneous() - base_from_target.to_homogeneous()).norm() < 1e-9);
/// # Ok::<(), handeye::Error>(())
/// ```
pub fn shah(poses: &[PosePair], setup: Setup) -> Result<RobotWorld> {
    let p = prepare(poses, setup)?;
    let mut k = SMatrix::<f64, 9, 9>::zeros();
    for (a, b) in &p.ab {
        k += kron(&rotation_matrix(a), &rotation_matrix(b));
    }
    let ill = || singular(p.conditioning);
    let (r_x, r_z) = shah_rotations(&k).ok_or_else(ill)?;
    // Translation: [−R_A  I] (t_X', t_Z') = t_A − R_Z' t_B, by normal equations and one step of
    // iterative refinement.
    let rows = |(a, b): &(Transform, Transform)| {
        let mut c = SMatrix::<f64, 3, 6>::zeros();
        c.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(-rotation_matrix(a)));
        c.fixed_view_mut::<3, 3>(0, 3)
            .copy_from(&Matrix3::identity());
        (c, a.translation.vector - r_z * b.translation.vector)
    };
    let t = least_squares_6(&p.ab, rows).ok_or_else(ill)?;
    let t_x: Vector3<f64> = t.fixed_rows::<3>(0).into_owned();
    let t_z: Vector3<f64> = t.fixed_rows::<3>(3).into_owned();
    Ok(finish(
        RobotWorldMethod::Shah,
        p,
        (&r_x, &t_x),
        (&r_z, &t_z),
    ))
}

/// Shah's rotations (R_X', R_Z') from K = Σ R_A ⊗ R_B (row-major): the first singular pair (the
/// eigenvector v of the largest eigenvalue of KᵀK, and K v), each normalised as OpenCV does.
pub(crate) fn shah_rotations(k: &SMatrix<f64, 9, 9>) -> Option<(Matrix3<f64>, Matrix3<f64>)> {
    let eigen = (k.transpose() * k).symmetric_eigen();
    let top = eigen.eigenvalues.imax();
    let v: SVector<f64, 9> = eigen.eigenvectors.column(top).into_owned();
    let u = k * v;
    Some((
        normalize_rotation(&unvec(v.as_slice()))?,
        normalize_rotation(&unvec(u.as_slice()))?,
    ))
}

/// Row-major Kronecker product `M ⊗ N` (see [`kron`]), for the accumulating form.
pub(crate) fn kron9(m: &Matrix3<f64>, n: &Matrix3<f64>) -> SMatrix<f64, 9, 9> {
    kron(m, n)
}

/// Li, Wang and Wu's simultaneous solution, as OpenCV's `CALIB_ROBOT_WORLD_HAND_EYE_LI`.
///
/// Unknowns vec(R_X'), vec(R_Z') (row-major), t_X', t_Z' (24 in all); per pose (Eq. (19))
/// `(R_A ⊗ I) vec R_X' − (I ⊗ R_Bᵀ) vec R_Z' = 0` (that is R_A R_X' = R_Z' R_B) and
/// `R_Z' t_B − R_A t_X' + t_Z' = t_A`, stacked and solved in least squares; both rotations are then
/// normalised to unit determinant and projected onto SO(3), the translations kept as solved. The
/// rows weigh rotations against lengths in units of the data's own RMS translation length (as the
/// hand–eye `andreff-joint` does), so that the answer does not depend on the input's unit.
///
/// Refused with [`Degeneracy::NoTranslation`] when the solved rotations have (near) zero
/// determinant: the scale of the rotation block is fixed by the translations only.
///
/// # References
/// A. Li, L. Wang, D. Wu, "Simultaneous robot-world and hand-eye calibration using
/// dual-quaternions and Kronecker product", International Journal of Physical Sciences 5,
/// 1530–1536, 2010 (sec. 3, Eq. (19)).
///
/// # Example
/// ```
/// use handeye::solve::li;
/// use handeye::{PosePair, Setup, Transform};
/// use nalgebra::{Rotation3, Translation3, Vector3};
/// let x = Transform::from_parts(Translation3::new(0.1, 0.0, 0.05), Rotation3::from_euler_angles(0.1, 0.2, 0.3));
/// let base_from_target = Transform::new(Vector3::new(0.8, 0.1, 0.0), Vector3::new(0.0, 3.0, 0.2));
/// let poses: Vec<PosePair> = [(0.1, 0.2, 0.3), (-0.4, 0.1, 0.2), (0.3, -0.5, 0.1), (0.2, 0.1, -0.6)]
///     .iter()
///     .map(|&(a, b, c)| {
///         let base_from_gripper = Transform::new(Vector3::new(0.3 * a, 0.2, b), Vector3::new(a, b, c));
///         PosePair { base_from_gripper, camera_from_target: (base_from_gripper * x).inverse() * base_from_target }
///     })
///     .collect();
/// let rw = li(&poses, Setup::EyeInHand)?;
/// assert!((rw.x.to_homogeneous() - x.to_homogeneous()).norm() < 1e-9);
/// # Ok::<(), handeye::Error>(())
/// ```
pub fn li(poses: &[PosePair], setup: Setup) -> Result<RobotWorld> {
    let p = prepare(poses, setup)?;
    let unit = weighting_from_scale(pose_rms(&p.ab));
    let i3 = Matrix3::identity();
    let rows = |(a, b): &(Transform, Transform)| {
        let r_a = rotation_matrix(a);
        let r_b = rotation_matrix(b);
        let t_b = b.translation.vector / unit;
        let mut c = SMatrix::<f64, 12, 24>::zeros();
        c.fixed_view_mut::<9, 9>(0, 0).copy_from(&kron(&r_a, &i3));
        c.fixed_view_mut::<9, 9>(0, 9)
            .copy_from(&(-kron(&i3, &r_b.transpose())));
        for i in 0..3 {
            // (I ⊗ t_Bᵀ) vec R_Z' = R_Z' t_B.
            for l in 0..3 {
                c[(9 + i, 9 + 3 * i + l)] = t_b[l];
            }
        }
        c.fixed_view_mut::<3, 3>(9, 18).copy_from(&(-r_a));
        c.fixed_view_mut::<3, 3>(9, 21).copy_from(&i3);
        let mut d = SVector::<f64, 12>::zeros();
        d.fixed_rows_mut::<3>(9)
            .copy_from(&(a.translation.vector / unit));
        (c, d)
    };
    let sol = least_squares_24(&p.ab, rows).ok_or_else(|| singular(p.conditioning))?;
    let no_translation = || {
        let largest =
            p.ab.iter()
                .map(|(_, b)| b.translation.vector.norm())
                .fold(0.0, f64::max);
        Error::Degenerate {
            reason: Degeneracy::NoTranslation { largest },
            conditioning: p.conditioning,
        }
    };
    let r_x = normalize_rotation(&unvec(&sol.as_slice()[0..9])).ok_or_else(no_translation)?;
    let r_z = normalize_rotation(&unvec(&sol.as_slice()[9..18])).ok_or_else(no_translation)?;
    let t_x: Vector3<f64> = sol.fixed_rows::<3>(18) * unit;
    let t_z: Vector3<f64> = sol.fixed_rows::<3>(21) * unit;
    Ok(finish(RobotWorldMethod::Li, p, (&r_x, &t_x), (&r_z, &t_z)))
}

/// Defines a stacked least-squares solver over a slice of items (normal equations, LU, one step of
/// iterative refinement), as [`crate::solve::least_squares`] does over motions.
macro_rules! stacked_items {
    ($name:ident, $r:literal, $n:literal) => {
        fn $name<T>(
            items: &[T],
            rows: impl Fn(&T) -> (SMatrix<f64, $r, $n>, SVector<f64, $r>),
        ) -> Option<SVector<f64, $n>> {
            let mut normal = SMatrix::<f64, $n, $n>::zeros();
            let mut rhs = SVector::<f64, $n>::zeros();
            for item in items {
                let (c, d) = rows(item);
                normal += c.transpose() * c;
                rhs += c.transpose() * d;
            }
            let lu = normal.lu();
            let mut x = lu.solve(&rhs)?;
            let mut correction = SVector::<f64, $n>::zeros();
            for item in items {
                let (c, d) = rows(item);
                correction += c.transpose() * (d - c * x);
            }
            x += lu.solve(&correction)?;
            x.iter().all(|v| v.is_finite()).then_some(x)
        }
    };
}

stacked_items!(least_squares_6, 3, 6);
stacked_items!(least_squares_24, 12, 24);

/// The data's length unit: the RMS translation of the A_i and B_i (1 when all are 0), so that the
/// solution does not depend on the input's unit.
pub(crate) fn pose_length_scale(ab: &[(Transform, Transform)]) -> f64 {
    weighting_from_scale(pose_rms(ab))
}

/// The RMS translation length of the A_i and B_i.
fn pose_rms(ab: &[(Transform, Transform)]) -> f64 {
    let sum: f64 = ab
        .iter()
        .map(|(a, b)| a.translation.vector.norm_squared() + b.translation.vector.norm_squared())
        .sum();
    (sum / (2 * ab.len().max(1)) as f64).sqrt()
}

/// Solves with the given method (Refine runs [`refine_robot_world`]).
pub fn robot_world(
    method: RobotWorldMethod,
    poses: &[PosePair],
    setup: Setup,
) -> Result<RobotWorld> {
    match method {
        RobotWorldMethod::Shah => shah(poses, setup),
        RobotWorldMethod::Li => li(poses, setup),
        RobotWorldMethod::Refine => refine_robot_world(poses, setup).map(|r| r.solution),
        RobotWorldMethod::Reprojection => Err(Error::InvalidParameter {
            name: "method",
            message: "`reprojection` solves on the pixels: give detections and intrinsics (`--intrinsics FILE`), not poses".into(),
        }),
    }
}

// ---------------------------------------------------------------------------------------------
// The per-pose residual and the joint refinement.

/// The residual of one pose at (X, Y), defined once for the refinement and for reports:
/// ΔR = R_Q R_X R_C − R_Y and ΔT = R_Q (R_X t_C + t_X) + t_Q − t_Y (the target's origin as pose i
/// sees it, minus Y's, in the fixed frame: input units).
pub(crate) fn pose_residual(
    q: &Transform,
    camera_from_target: &Transform,
    x: (&Matrix3<f64>, &Vector3<f64>),
    y: (&Matrix3<f64>, &Vector3<f64>),
) -> (Matrix3<f64>, Vector3<f64>) {
    let r_q = rotation_matrix(q);
    let r_c = rotation_matrix(camera_from_target);
    let dr = r_q * x.0 * r_c - y.0;
    let dt = r_q * (x.0 * camera_from_target.translation.vector + x.1) + q.translation.vector - y.1;
    (dr, dt)
}

/// The per-pose residuals of Q_i X C_i = Y at (X, Y), in the fixed frame: the rotation
/// R_Yᵀ R_Q R_X R_C and the translation ΔT of `pose_residual`.
pub fn pose_residuals(
    poses: &[PosePair],
    setup: Setup,
    x: &Transform,
    target: &Transform,
) -> Vec<PoseResidual> {
    let (r_x, t_x) = (rotation_matrix(x), x.translation.vector);
    let (r_y, t_y) = (rotation_matrix(target), target.translation.vector);
    poses
        .iter()
        .map(|p| {
            let q = setup.hand_pose(&p.base_from_gripper);
            let (_, dt) = pose_residual(&q, &p.camera_from_target, (&r_x, &t_x), (&r_y, &t_y));
            let predicted = rotation_matrix(&q) * r_x * rotation_matrix(&p.camera_from_target);
            PoseResidual::new(&(r_y.transpose() * predicted), dt)
        })
        .collect()
}

/// Joint covariance of (δ_X, t_X, δ_Y, t_Y): rotation increments R exp(\[δ\]×) in radians, then
/// translations in input units; 12×12.
pub type JointCovariance = SMatrix<f64, 12, 12>;

/// The outcome of [`refine_robot_world`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RobotWorldRefinement {
    /// The refined X and target pose.
    pub solution: RobotWorld,
    /// Weighted cost ½Σr² at the start.
    pub initial_cost: f64,
    /// Weighted cost at the end; never above `initial_cost`.
    pub final_cost: f64,
    /// Iterations run.
    pub iterations: usize,
    /// Why it stopped.
    pub termination: Termination,
    /// First-order covariance at the end ([`joint_covariance`]); `None` when singular.
    pub covariance: Option<JointCovariance>,
}

/// Refines X and the target pose jointly over all poses, started from [`shah`].
///
/// Unknowns R_X exp(\[δ_X\]×), t_X, R_Y exp(\[δ_Y\]×), t_Y; residuals the 9 entries of ΔR_i and the 3
/// of ΔT_i of the pose residual per pose, each block divided by its RMS at the start (as the
/// hand–eye `refine`, SPEC sec. 3). Levenberg–Marquardt with Nielsen's damping, in units of the
/// data's own length scale; never returns a higher cost than its start.
///
/// # Example
/// ```
/// use handeye::solve::refine_robot_world;
/// use handeye::{PosePair, Setup, Transform};
/// use nalgebra::{Rotation3, Translation3, Vector3};
/// let x = Transform::from_parts(Translation3::new(0.1, 0.0, 0.05), Rotation3::from_euler_angles(0.1, 0.2, 0.3));
/// let base_from_target = Transform::new(Vector3::new(0.8, 0.1, 0.0), Vector3::new(0.0, 3.0, 0.2));
/// let poses: Vec<PosePair> = [(0.1, 0.2, 0.3), (-0.4, 0.1, 0.2), (0.3, -0.5, 0.1), (0.2, 0.1, -0.6)]
///     .iter()
///     .map(|&(a, b, c)| {
///         let base_from_gripper = Transform::new(Vector3::new(0.3 * a, 0.2, b), Vector3::new(a, b, c));
///         PosePair { base_from_gripper, camera_from_target: (base_from_gripper * x).inverse() * base_from_target }
///     })
///     .collect();
/// let r = refine_robot_world(&poses, Setup::EyeInHand)?;
/// assert!(r.final_cost <= r.initial_cost);
/// assert!((r.solution.target.to_homogeneous() - base_from_target.to_homogeneous()).norm() < 1e-9);
/// # Ok::<(), handeye::Error>(())
/// ```
pub fn refine_robot_world(poses: &[PosePair], setup: Setup) -> Result<RobotWorldRefinement> {
    let start = shah(poses, setup)?;
    Ok(run(poses, setup, start, &RefineOptions::default()))
}

/// Refines X and the target pose from a given start (its conditioning and warnings are kept).
pub fn refine_robot_world_from(
    poses: &[PosePair],
    setup: Setup,
    start: RobotWorld,
    options: &RefineOptions,
) -> RobotWorldRefinement {
    run(poses, setup, start, options)
}

/// The problem in the data's length unit: (Q_i, C_i) with translations divided by the unit.
struct Joint {
    qc: Vec<(Transform, Transform)>,
    weights: [f64; 2],
}

/// The parameters: R_X, t_X, R_Y, t_Y.
#[derive(Clone, Copy)]
struct State {
    r_x: Matrix3<f64>,
    t_x: Vector3<f64>,
    r_y: Matrix3<f64>,
    t_y: Vector3<f64>,
}

impl State {
    fn residual(&self, q: &Transform, c: &Transform) -> (Matrix3<f64>, Vector3<f64>) {
        pose_residual(q, c, (&self.r_x, &self.t_x), (&self.r_y, &self.t_y))
    }

    fn step(&self, d: &SVector<f64, 12>) -> State {
        State {
            r_x: proj_so3(&(self.r_x * exp_so3(&d.fixed_rows::<3>(0).into_owned()))),
            t_x: self.t_x + d.fixed_rows::<3>(3),
            r_y: proj_so3(&(self.r_y * exp_so3(&d.fixed_rows::<3>(6).into_owned()))),
            t_y: self.t_y + d.fixed_rows::<3>(9),
        }
    }

    fn size(&self) -> f64 {
        self.t_x.norm() + self.t_y.norm() + 1.0
    }
}

fn scaled_problem(poses: &[PosePair], setup: Setup) -> (Vec<(Transform, Transform)>, f64) {
    let mut qc: Vec<(Transform, Transform)> = poses
        .iter()
        .map(|p| (setup.hand_pose(&p.base_from_gripper), p.camera_from_target))
        .collect();
    let unit = pose_length_scale(&qc);
    for (q, c) in &mut qc {
        q.translation.vector /= unit;
        c.translation.vector /= unit;
    }
    (qc, unit)
}

fn block_scales(qc: &[(Transform, Transform)], s: &State) -> [f64; 2] {
    let mut rms = BlockRms::default();
    for (q, c) in qc {
        let (dr, dt) = s.residual(q, c);
        rms.add(&dr, &dt);
    }
    rms.scales()
}

/// The 12×12 weighted Jacobian of one pose's residuals at `s` and the weighted residuals.
///
/// ∂ΔR/∂δ_X,m = R_Q R_X [e_m]× R_C, ∂ΔR/∂δ_Y,m = −R_Y [e_m]×; ∂ΔT/∂δ_X,m = R_Q R_X [e_m]× t_C,
/// ∂ΔT/∂t_X = R_Q, ∂ΔT/∂t_Y = −I.
fn jacobian(
    q: &Transform,
    c: &Transform,
    s: &State,
    weights: [f64; 2],
) -> (SMatrix<f64, 12, 12>, SVector<f64, 12>) {
    let r_q = rotation_matrix(q);
    let r_c = rotation_matrix(c);
    let t_c = c.translation.vector;
    let qx = r_q * s.r_x;
    let (dr, dt) = s.residual(q, c);
    let mut j = SMatrix::<f64, 12, 12>::zeros();
    let mut r = SVector::<f64, 12>::zeros();
    for m in 0..3 {
        let e = skew(&Vector3::ith(m, 1.0));
        let dx_r = qx * e * r_c * weights[0];
        let dy_r = -(s.r_y * e) * weights[0];
        let dx_t = qx * e * t_c * weights[1];
        for row in 0..3 {
            for col in 0..3 {
                j[(3 * row + col, m)] = dx_r[(row, col)];
                j[(3 * row + col, 6 + m)] = dy_r[(row, col)];
            }
            j[(9 + row, m)] = dx_t[row];
        }
    }
    j.fixed_view_mut::<3, 3>(9, 3)
        .copy_from(&(r_q * weights[1]));
    j.fixed_view_mut::<3, 3>(9, 9)
        .copy_from(&(-Matrix3::identity() * weights[1]));
    for row in 0..3 {
        for col in 0..3 {
            r[3 * row + col] = dr[(row, col)] * weights[0];
        }
        r[9 + row] = dt[row] * weights[1];
    }
    (j, r)
}

impl Joint {
    fn cost(&self, s: &State) -> f64 {
        let w = self.weights;
        0.5 * self
            .qc
            .iter()
            .map(|(q, c)| {
                let (dr, dt) = s.residual(q, c);
                w[0] * w[0] * dr.norm_squared() + w[1] * w[1] * dt.norm_squared()
            })
            .sum::<f64>()
    }
}

impl LeastSquares<12> for Joint {
    type State = State;

    fn linearise(&self, s: &State) -> Linearisation<12> {
        let mut jtj = SMatrix::<f64, 12, 12>::zeros();
        let mut jtr = SVector::<f64, 12>::zeros();
        let mut cost = 0.0;
        for (q, c) in &self.qc {
            let (j, r) = jacobian(q, c, s, self.weights);
            jtj += j.transpose() * j;
            jtr += j.transpose() * r;
            cost += 0.5 * r.norm_squared();
        }
        Linearisation { jtj, jtr, cost }
    }

    fn step(&self, s: &State, delta: &SVector<f64, 12>) -> State {
        s.step(delta)
    }

    fn cost_drop(&self, _: &State, to: &State, cost: f64) -> f64 {
        cost - self.cost(to)
    }

    fn size(&self, s: &State) -> f64 {
        s.size()
    }
}

/// [`refine_robot_world_from`]: Levenberg–Marquardt ([`levenberg_marquardt`]) in the data's length
/// unit.
fn run(
    poses: &[PosePair],
    setup: Setup,
    start: RobotWorld,
    options: &RefineOptions,
) -> RobotWorldRefinement {
    let (qc, unit) = scaled_problem(poses, setup);
    let s = State {
        r_x: rotation_matrix(&start.x),
        t_x: start.x.translation.vector / unit,
        r_y: rotation_matrix(&start.target),
        t_y: start.target.translation.vector / unit,
    };
    let scales = block_scales(&qc, &s);
    let problem = Joint {
        qc,
        weights: [1.0 / scales[0], 1.0 / scales[1]],
    };
    let end = levenberg_marquardt(&problem, s, options);
    let s = end.state;
    let covariance = covariance_scaled(&problem.qc, &s, unit);
    RobotWorldRefinement {
        solution: RobotWorld {
            x: transform_from_parts(&s.r_x, &(s.t_x * unit)),
            target: transform_from_parts(&s.r_y, &(s.t_y * unit)),
            method: RobotWorldMethod::Refine,
            poses: poses.len(),
            conditioning: start.conditioning,
            warnings: start.warnings,
        },
        initial_cost: end.initial_cost,
        final_cost: end.final_cost,
        iterations: end.iterations,
        termination: end.termination,
        covariance,
    }
}

/// First-order covariance of (δ_X, t_X, δ_Y, t_Y) at a given (X, Y): `s² (JᵀJ)⁻¹` of the per-pose
/// residuals, each block weighted by its own RMS at (X, Y) and `s² = Σr² / (12n − 12)`
/// (Gauss–Newton with each block's noise estimated from its residuals). `None` when JᵀJ is
/// singular or there are fewer than 2 poses.
pub fn joint_covariance(
    poses: &[PosePair],
    setup: Setup,
    x: &Transform,
    target: &Transform,
) -> Option<JointCovariance> {
    let (qc, unit) = scaled_problem(poses, setup);
    let s = State {
        r_x: rotation_matrix(x),
        t_x: x.translation.vector / unit,
        r_y: rotation_matrix(target),
        t_y: target.translation.vector / unit,
    };
    covariance_scaled(&qc, &s, unit)
}

/// [`joint_covariance`] with X's translation component `fixed` (0, 1, 2) held: the covariance of
/// the other eleven unknowns given it, its own row and column 0. A low-DOF robot's poses leave one
/// combination free (X's translation along the motions' axis and the target's along the same axis
/// seen from the target's frame); a prior on X's component takes it away, and this is what the
/// poses say of the rest, the target's coupled component included. `None` as [`joint_covariance`].
pub fn joint_covariance_given(
    poses: &[PosePair],
    setup: Setup,
    (x, target): (&Transform, &Transform),
    fixed: usize,
) -> Option<JointCovariance> {
    let (qc, unit) = scaled_problem(poses, setup);
    let s = State {
        r_x: rotation_matrix(x),
        t_x: x.translation.vector / unit,
        r_y: rotation_matrix(target),
        t_y: target.translation.vector / unit,
    };
    covariance_of(&qc, &s, unit, Some(3 + fixed))
}

/// The target's pose that best agrees with every pose at a given X: the rotation nearest the sum
/// of R_Q R_X R_C, the translation the mean of R_Q (R_X t_C + t_X) + t_Q.
pub fn target_given(poses: &[PosePair], setup: Setup, x: &Transform) -> Transform {
    let r_x = rotation_matrix(x);
    let mut rotations = Matrix3::zeros();
    let mut origin = Vector3::zeros();
    for p in poses {
        let q = setup.hand_pose(&p.base_from_gripper);
        let r_q = rotation_matrix(&q);
        rotations += r_q * r_x * rotation_matrix(&p.camera_from_target);
        origin += r_q * (r_x * p.camera_from_target.translation.vector + x.translation.vector)
            + q.translation.vector;
    }
    let n = poses.len().max(1) as f64;
    transform_from_parts(&proj_so3(&(rotations / n)), &(origin / n))
}

fn covariance_scaled(
    qc: &[(Transform, Transform)],
    s: &State,
    unit: f64,
) -> Option<JointCovariance> {
    covariance_of(qc, s, unit, None)
}

/// The first-order covariance, with the unknown `fixed` (an index of the 12) held when given.
fn covariance_of(
    qc: &[(Transform, Transform)],
    s: &State,
    unit: f64,
    fixed: Option<usize>,
) -> Option<JointCovariance> {
    if qc.len() < 2 {
        return None;
    }
    let scales = block_scales(qc, s);
    let problem = Joint {
        qc: qc.to_vec(),
        weights: [1.0 / scales[0], 1.0 / scales[1]],
    };
    let Linearisation { jtj, cost, .. } = problem.linearise(s);
    let free = 12 - usize::from(fixed.is_some());
    let s2 = 2.0 * cost / (12 * qc.len() - free) as f64;
    let inv = match fixed {
        None => jtj.try_inverse()?,
        Some(k) => {
            // The held unknown's row and column out, the rest inverted, put back around zeros.
            let kept: Vec<usize> = (0..12).filter(|&i| i != k).collect();
            let reduced = nalgebra::DMatrix::from_fn(11, 11, |i, j| jtj[(kept[i], kept[j])]);
            let reduced = reduced.try_inverse()?;
            let mut inv = SMatrix::<f64, 12, 12>::zeros();
            for (a, &i) in kept.iter().enumerate() {
                for (b, &j) in kept.iter().enumerate() {
                    inv[(i, j)] = reduced[(a, b)];
                }
            }
            inv
        }
    };
    let mut d = SVector::<f64, 12>::repeat(1.0);
    for i in [3, 4, 5, 9, 10, 11] {
        d[i] = unit;
    }
    let dm = SMatrix::<f64, 12, 12>::from_diagonal(&d);
    Some(dm * inv * dm * s2)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The analytic Jacobian against central finite differences of the weighted residuals.
    #[test]
    fn jacobian_matches_central_differences() {
        let q = Transform::new(Vector3::new(0.3, -0.2, 0.5), Vector3::new(0.4, 0.1, -0.7));
        let c = Transform::new(Vector3::new(-0.1, 0.4, 1.2), Vector3::new(0.2, -0.9, 0.3));
        let s = State {
            r_x: exp_so3(&Vector3::new(0.5, -0.3, 0.2)),
            t_x: Vector3::new(0.05, 0.1, -0.02),
            r_y: exp_so3(&Vector3::new(-1.0, 0.4, 2.0)),
            t_y: Vector3::new(0.9, -0.3, 0.1),
        };
        let weights = [1.7, 0.6];
        let (j, _) = jacobian(&q, &c, &s, weights);
        let h = 1e-6;
        for k in 0..12 {
            let mut d = SVector::<f64, 12>::zeros();
            d[k] = h;
            let plus = jacobian(&q, &c, &s.step(&d), weights).1;
            let minus = jacobian(&q, &c, &s.step(&(-d)), weights).1;
            let numeric = (plus - minus) / (2.0 * h);
            let diff = (numeric - j.column(k)).amax();
            assert!(diff < 1e-8, "column {k}: {diff:e}");
        }
    }

    #[test]
    fn kron_is_row_major_vec() {
        let m = exp_so3(&Vector3::new(0.1, 0.2, 0.3));
        let n = exp_so3(&Vector3::new(-0.4, 0.5, 0.1));
        let v = exp_so3(&Vector3::new(0.7, -0.2, 0.3));
        let lhs = m * v * n.transpose();
        let rhs = kron(&m, &n)
            * SVector::<f64, 9>::from_row_slice(&[
                v[(0, 0)],
                v[(0, 1)],
                v[(0, 2)],
                v[(1, 0)],
                v[(1, 1)],
                v[(1, 2)],
                v[(2, 0)],
                v[(2, 1)],
                v[(2, 2)],
            ]);
        assert!((unvec(rhs.as_slice()) - lhs).amax() < 1e-14);
    }
}
