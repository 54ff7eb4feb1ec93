//! Andreff's solver in its simultaneous 12-unknown form, as OpenCV's `CALIB_HAND_EYE_ANDREFF`.

use nalgebra::{Matrix3, SMatrix, SVector};

use crate::error::{Degeneracy, Error, Result};
use crate::motion::{MotionPair, MotionSource};
use crate::pose::{proj_so3, rotation_matrix};
use crate::solve::least_squares::least_squares_12;
use crate::solve::{Calibration, Method, check_motions, finish, singular};

/// Andreff et al.'s linear solution with R_x and t_x as one 12-vector.
///
/// Eq. (10), per motion: `[I₉ − R_a ⊗ R_b, 0; I₃ ⊗ t_bᵀ, I₃ − R_a] (vec R_x, t_x) = (0, t_a)`
/// (row-major vec), stacked and solved in least squares; then (Eq. (15)) R_x is scaled to unit
/// determinant and projected onto SO(3), while t_x is kept as solved.
///
/// # References
/// N. Andreff, R. Horaud, B. Espiau, "On-line hand-eye calibration", 3DIM 1999.
///
/// # Example
/// ```
/// use handeye::{MotionPair, Transform, andreff_joint};
/// use nalgebra::{Rotation3, Translation3, Vector3};
/// let x = Transform::from_parts(Translation3::new(0.1, 0.0, 0.05), Rotation3::from_euler_angles(0.1, 0.2, 0.3));
/// let a1 = Transform::new(Vector3::new(0.1, 0.2, 0.3), Vector3::new(0.5, 0.0, 0.0));
/// let a2 = Transform::new(Vector3::new(-0.2, 0.1, 0.4), Vector3::new(0.0, 0.4, 0.1));
/// let motions: Vec<_> = [a1, a2].iter().map(|a| MotionPair { a: *a, b: x.inverse() * a * x }).collect();
/// let cal = andreff_joint(&motions)?;
/// assert!((cal.x.to_homogeneous() - x.to_homogeneous()).norm() < 1e-9);
/// # Ok::<(), handeye::Error>(())
/// ```
pub fn andreff_joint(motions: &(impl MotionSource + ?Sized)) -> Result<Calibration> {
    let check = check_motions(motions)?;
    let x = least_squares_12(motions, rows).ok_or_else(|| singular(check.conditioning))?;
    let raw = Matrix3::new(x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7], x[8]);
    let det = raw.determinant();
    // The scale of vec(R_x) is fixed only by the gripper translations (the right-hand side); with
    // none, the solution is 0. OpenCV refuses |det| below single-precision epsilon likewise.
    if det.is_nan() || det.abs() < f64::from(f32::EPSILON) {
        let mut largest = 0.0_f64;
        motions.for_each_motion(|m| largest = largest.max(m.a.translation.vector.norm()));
        return Err(Error::Degenerate {
            reason: Degeneracy::NoTranslation { largest },
            conditioning: check.conditioning,
        });
    }
    let r_x = proj_so3(&(raw * det.signum()));
    let t_x = x.fixed_rows::<3>(9).into_owned();
    Ok(finish(
        Method::AndreffJoint,
        motions.count(),
        check,
        &r_x,
        &t_x,
    ))
}

/// The 12 rows of Eq. (10) for one motion.
fn rows(m: &MotionPair) -> (SMatrix<f64, 12, 12>, SVector<f64, 12>) {
    let r_a = rotation_matrix(&m.a);
    let r_b = rotation_matrix(&m.b);
    let t_b = m.b.translation.vector;
    let mut c = SMatrix::<f64, 12, 12>::zeros();
    for i in 0..3 {
        for j in 0..3 {
            for k in 0..3 {
                for l in 0..3 {
                    // (R_a ⊗ R_b)[(3i+k, 3j+l)] = R_a[i,j] R_b[k,l].
                    c[(3 * i + k, 3 * j + l)] = -r_a[(i, j)] * r_b[(k, l)];
                }
            }
        }
    }
    for d in 0..9 {
        c[(d, d)] += 1.0;
    }
    for i in 0..3 {
        // (I₃ ⊗ t_bᵀ) vec(R_x) = R_x t_b.
        for l in 0..3 {
            c[(9 + i, 3 * i + l)] = t_b[l];
        }
        for j in 0..3 {
            c[(9 + i, 9 + j)] = if i == j { 1.0 } else { 0.0 } - r_a[(i, j)];
        }
    }
    let mut d = SVector::<f64, 12>::zeros();
    d.fixed_rows_mut::<3>(9).copy_from(&m.a.translation.vector);
    (c, d)
}
