//! Horaud and Dornaika's solver, as OpenCV's `CALIB_HAND_EYE_HORAUD` computes it.

use nalgebra::{Matrix4, SymmetricEigen, Vector4};

use crate::model::error::Result;
use crate::model::pose::rotation_matrix;
use crate::solve::motions::MotionSource;
use crate::solve::quaternion::{Signs, motion_quaternions, rotation_of};
use crate::solve::{
    Calibration, Method, check_motions, finish, singular, translation_least_squares,
};

/// Horaud and Dornaika's linear quaternion solution.
///
/// With q_a, q_b the quaternions of R_a, R_b, the rotation constraint is
/// `(Q(q_a) − W(q_b)) q_x = 0` (Appendix A: Q left, W right multiplication); q_x is the eigenvector
/// of the smallest eigenvalue of `Σ (Q − W)ᵀ(Q − W)` (4×4). t_x by least squares of the stacked
/// `(I − R_a) t_x = t_a − R_x t_b`.
///
/// # References
/// R. Horaud, F. Dornaika, "Hand-eye calibration", IJRR 14(3), 1995.
///
/// # Example
/// ```
/// use handeye::{Method, MotionPair, Transform, solve};
/// use nalgebra::{Rotation3, Translation3, Vector3};
/// let x = Transform::from_parts(Translation3::new(0.1, 0.0, 0.05), Rotation3::from_euler_angles(0.1, 0.2, 0.3));
/// let a1 = Transform::new(Vector3::new(0.1, 0.2, 0.3), Vector3::new(0.5, 0.0, 0.0));
/// let a2 = Transform::new(Vector3::new(-0.2, 0.1, 0.4), Vector3::new(0.0, 0.4, 0.1));
/// let motions: Vec<_> = [a1, a2].iter().map(|a| MotionPair { a: *a, b: x.inverse() * a * x }).collect();
/// let cal = solve(Method::Horaud, &motions)?;
/// assert!((cal.x.to_homogeneous() - x.to_homogeneous()).norm() < 1e-9);
/// # Ok::<(), handeye::Error>(())
/// ```
pub fn horaud(motions: &(impl MotionSource + ?Sized)) -> Result<Calibration> {
    let check = check_motions(motions)?;
    let mut a = Matrix4::zeros();
    // q_a ⊗ q_x = q_x ⊗ q_b holds for one sign of q_b only; at 180° (scalar parts 0) the matrix
    // does not tell which, and the wrong one adds a row block that the true q_x does not satisfy.
    // The sign is taken from Andreff's R_x (see `motion_quaternions`).
    let r_x0 = check.andreff_rotation;
    motions.for_each_motion(|m| {
        let (q_a, q_b) = motion_quaternions(
            &rotation_matrix(&m.a),
            &rotation_matrix(&m.b),
            &r_x0,
            Signs::NearHalfTurn,
        );
        let d = left(&q_a) - right(&q_b);
        a += d.transpose() * d;
    });
    let eigen = SymmetricEigen::new(a);
    let q: Vector4<f64> = eigen
        .eigenvectors
        .column(eigen.eigenvalues.imin())
        .into_owned();
    if !q.iter().all(|v| v.is_finite()) {
        return Err(singular(check.conditioning));
    }
    let r_x = rotation_of(&q.normalize());
    let t_x =
        translation_least_squares(motions, &r_x).ok_or_else(|| singular(check.conditioning))?;
    Ok(finish(Method::Horaud, motions.count(), check, &r_x, &t_x))
}

/// Q(r): the matrix of left multiplication, r ⊗ q = Q(r) q.
fn left(r: &Vector4<f64>) -> Matrix4<f64> {
    let (w, x, y, z) = (r[0], r[1], r[2], r[3]);
    Matrix4::new(w, -x, -y, -z, x, w, -z, y, y, z, w, -x, z, -y, x, w)
}

/// W(r): the matrix of right multiplication, q ⊗ r = W(r) q.
fn right(r: &Vector4<f64>) -> Matrix4<f64> {
    let (w, x, y, z) = (r[0], r[1], r[2], r[3]);
    Matrix4::new(w, -x, -y, -z, x, w, z, -y, y, -z, w, x, z, y, -x, w)
}
