//! Andreff's linear solver in its two-step form, the one the paper uses.

use crate::model::error::Result;
use crate::solve::motions::MotionSource;
use crate::solve::{
    Calibration, Method, check_motions, finish, singular, translation_least_squares,
};

/// Andreff et al.'s two-step linear solution of A X = X B.
///
/// Step 1: vec(R_x) spans the null space of the stacked 9m×9 matrix `[I₉ − R_a ⊗ R_b]` (row-major
/// vec), found as the eigenvector of the smallest eigenvalue of its normal matrix
/// (`solve::rotation_system`); its sign is fixed so that det > 0 and it is projected onto
/// SO(3). Step 2: t_x is the least-squares solution of the stacked (I₃ − R_a) t_x = t_a − R_x t_b.
/// This is SPEC sec. 3 `andreff`, and the solver of the paper's online methods.
///
/// # References
/// N. Andreff, R. Horaud, B. Espiau, "On-line hand-eye calibration", 3DIM 1999, and "Robot
/// hand-eye calibration using structure-from-motion", IJRR 2001 (the Kronecker form, sec. 3).
///
/// # Example
/// ```
/// use handeye::{Method, MotionPair, Transform, solve};
/// use nalgebra::{Rotation3, Translation3, Vector3};
/// let x = Transform::from_parts(Translation3::new(0.1, 0.0, 0.05), Rotation3::from_euler_angles(0.1, 0.2, 0.3));
/// let a1 = Transform::new(Vector3::new(0.1, 0.2, 0.3), Vector3::new(0.5, 0.0, 0.0));
/// let a2 = Transform::new(Vector3::new(-0.2, 0.1, 0.4), Vector3::new(0.0, 0.4, 0.1));
/// let motions: Vec<_> = [a1, a2].iter().map(|a| MotionPair { a: *a, b: x.inverse() * a * x }).collect();
/// let cal = solve(Method::Andreff, &motions)?;
/// assert!((cal.x.to_homogeneous() - x.to_homogeneous()).norm() < 1e-9);
/// # Ok::<(), handeye::Error>(())
/// ```
pub fn andreff(motions: &(impl MotionSource + ?Sized)) -> Result<Calibration> {
    let check = check_motions(motions)?;
    let r_x = check.andreff_rotation;
    let t_x =
        translation_least_squares(motions, &r_x).ok_or_else(|| singular(check.conditioning))?;
    Ok(finish(Method::Andreff, motions.count(), check, &r_x, &t_x))
}
