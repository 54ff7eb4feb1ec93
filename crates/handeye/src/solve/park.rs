//! Park and Martin's solver, as OpenCV's `CALIB_HAND_EYE_PARK` computes it.

use std::f64::consts::PI;

use nalgebra::{Matrix3, Vector3};

use crate::model::error::Result;
use crate::model::pose::{log_so3, proj_so3, rotation_matrix};
use crate::solve::motions::MotionSource;
use crate::solve::quaternion::HALF_TURN_WITHIN;
use crate::solve::{
    Calibration, Method, check_motions, finish, singular, translation_least_squares,
};

/// Park and Martin's solution on the Euclidean group.
///
/// The paper's closed-form least-squares solution: with α = log R_a and β = log R_b (rotation
/// vectors), `M = Σ β αᵀ` and `R_x = (MᵀM)^(−1/2) Mᵀ`, the orthogonal polar factor of Mᵀ (with
/// two motions M has rank 2, OpenCV's (MᵀM)^(−1/2) does not exist, and the nearest rotation to
/// Mᵀ is taken); then t_x by least squares of the stacked `(I − R_a) t_x = t_a − R_x t_b`, as
/// OpenCV solves it.
///
/// # References
/// F. C. Park, B. J. Martin, "Robot sensor calibration: solving AX = XB on the Euclidean group",
/// IEEE Trans. Robotics and Automation 10(5), 1994.
///
/// # Example
/// ```
/// use handeye::{Method, MotionPair, Transform, solve};
/// use nalgebra::{Rotation3, Translation3, Vector3};
/// let x = Transform::from_parts(Translation3::new(0.1, 0.0, 0.05), Rotation3::from_euler_angles(0.1, 0.2, 0.3));
/// let a1 = Transform::new(Vector3::new(0.1, 0.2, 0.3), Vector3::new(0.5, 0.0, 0.0));
/// let a2 = Transform::new(Vector3::new(-0.2, 0.1, 0.4), Vector3::new(0.0, 0.4, 0.1));
/// let motions: Vec<_> = [a1, a2].iter().map(|a| MotionPair { a: *a, b: x.inverse() * a * x }).collect();
/// let cal = solve(Method::Park, &motions)?;
/// assert!((cal.x.to_homogeneous() - x.to_homogeneous()).norm() < 1e-9);
/// # Ok::<(), handeye::Error>(())
/// ```
pub fn park(motions: &(impl MotionSource + ?Sized)) -> Result<Calibration> {
    let check = check_motions(motions)?;
    let mut m = Matrix3::zeros();
    // M = Σ β αᵀ (the paper's least-squares sum) rests on β = R_xᵀ α for every motion. At
    // θ = 180° the logarithm is ±π k and the sign that a rotation matrix gives is rounding noise,
    // so β may come out as −R_xᵀ α and pull M towards a wrong R_x: near 180° β takes the lift that
    // agrees with Andreff's R_x.
    let r_x0 = check.andreff_rotation;
    motions.for_each_motion(|motion| {
        let alpha = log_so3(&rotation_matrix(&motion.a));
        let mut beta = log_so3(&rotation_matrix(&motion.b));
        if near_half_turn(&alpha, &beta) && opposed(&alpha, &beta, &r_x0) {
            beta = other_lift(&beta);
        }
        m += beta * alpha.transpose();
    });
    // (MᵀM)^(−1/2) Mᵀ is the orthogonal polar factor of Mᵀ; `proj_so3` computes it, and also
    // covers two motions (M of rank 2, where MᵀM is singular) and keeps det = +1.
    let r_x = proj_so3(&m.transpose());
    if !r_x.iter().all(|v| v.is_finite()) {
        return Err(singular(check.conditioning));
    }
    let t_x =
        translation_least_squares(motions, &r_x).ok_or_else(|| singular(check.conditioning))?;
    Ok(finish(Method::Park, motions.count(), check, &r_x, &t_x))
}

/// Whether the logarithms α of R_a and β of R_b are of opposite lifts: the unit quaternions
/// (cos(θ/2), sin(θ/2) k) of α and of β are more than 90° apart in R⁴ once β's is carried into the
/// gripper frame by the estimate `r_x` (the test of `quaternion::motion_quaternions`). For a pair
/// that agrees with X the two scalar parts are cos(θ/2) of the same angle, so only angles near
/// 180° (scalar parts near 0) can be opposed under any estimate within 90° of R_x. A pair that
/// does not (an outlier) can be opposed at any angle; its lift is not in question, so [`park`]
/// asks only within [`HALF_TURN_WITHIN`] of 180° ([`near_half_turn`]), as the quaternion methods
/// do.
fn opposed(alpha: &Vector3<f64>, beta: &Vector3<f64>, r_x: &Matrix3<f64>) -> bool {
    let (ta, tb) = (alpha.norm(), beta.norm());
    if ta == 0.0 || tb == 0.0 {
        return false;
    }
    let axes = beta.dot(&(r_x.transpose() * alpha)) / (ta * tb);
    (0.5 * ta).cos() * (0.5 * tb).cos() + (0.5 * ta).sin() * (0.5 * tb).sin() * axes < 0.0
}

/// Whether both logarithms turn within [`HALF_TURN_WITHIN`] of 180°.
fn near_half_turn(alpha: &Vector3<f64>, beta: &Vector3<f64>) -> bool {
    alpha.norm().min(beta.norm()) > PI - HALF_TURN_WITHIN
}

/// The other logarithm of the same rotation: θ k turned the other way round, −(2π − θ) k (the
/// log of −q where β is the log of q). At 180° it is −β; near it, unlike −β, it is still the
/// rotation that was measured.
fn other_lift(beta: &Vector3<f64>) -> Vector3<f64> {
    let theta = beta.norm();
    beta * ((theta - 2.0 * PI) / theta)
}
