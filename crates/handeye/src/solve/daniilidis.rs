//! Daniilidis' dual-quaternion solver, as OpenCV's `CALIB_HAND_EYE_DANIILIDIS` computes it.

use nalgebra::{Matrix3, SMatrix, SVector, SymmetricEigen, Vector3, Vector4};

use crate::error::Result;
use crate::motion::{MotionPair, MotionSource};
use crate::pose::{rotation_matrix, skew};
use crate::solve::quaternion::{motion_quaternions, multiply, rotation_of};
use crate::solve::scale::{Scaled, weighting_unit};
use crate::solve::{Calibration, Method, check_motions, finish, singular};

/// Daniilidis' simultaneous solution with dual quaternions.
///
/// Each motion gives 6 rows of Eq. (31) in the 8 entries of X's dual quaternion (q, q'):
/// `[a − b, [a + b]×, 0, 0; a' − b', [a' + b']×, a − b, [a + b]×]`, with a, a' (b, b') the vector
/// parts of the dual quaternion of A (B). X lies in the span of the two right singular vectors
/// of the smallest singular values (found from the 8×8 normal matrix); Eqs. (34)–(35) fix the
/// combination that is a unit dual quaternion (solved in a form that stays finite where OpenCV's
/// divides by zero).
///
/// # References
/// K. Daniilidis, "Hand-eye calibration using dual quaternions", IJRR 18(3), 1999.
///
/// # Example
/// ```
/// use handeye::{MotionPair, Transform, daniilidis};
/// use nalgebra::{Rotation3, Translation3, Vector3};
/// let x = Transform::from_parts(Translation3::new(0.1, 0.0, 0.05), Rotation3::from_euler_angles(0.1, 0.2, 0.3));
/// let a1 = Transform::new(Vector3::new(0.1, 0.2, 0.3), Vector3::new(0.5, 0.0, 0.0));
/// let a2 = Transform::new(Vector3::new(-0.2, 0.1, 0.4), Vector3::new(0.0, 0.4, 0.1));
/// let motions: Vec<_> = [a1, a2].iter().map(|a| MotionPair { a: *a, b: x.inverse() * a * x }).collect();
/// let cal = daniilidis(&motions)?;
/// assert!((cal.x.to_homogeneous() - x.to_homogeneous()).norm() < 1e-9);
/// # Ok::<(), handeye::Error>(())
/// ```
pub fn daniilidis(motions: &(impl MotionSource + ?Sized)) -> Result<Calibration> {
    let check = check_motions(motions)?;
    // The rows of Eq. (31) mix the real parts (order 1) with the dual parts (order the data's
    // lengths): in the input's unit the eigenvectors lose digits as lengths grow or shrink (1e-2
    // at lengths ×1e8 on exact data). Within 2^5 of the input's unit it is solved as OpenCV
    // solves it; beyond, in units that keep the two within 2^5 of each other, and t_x scaled
    // back (see `weighting_unit`).
    let unit = weighting_unit(motions);
    let r_x0 = check.andreff_rotation;
    let mut normal = SMatrix::<f64, 8, 8>::zeros();
    Scaled::new(motions, unit).for_each_motion(|m| {
        let t = rows(m, &r_x0);
        normal += t.transpose() * t;
    });
    let eigen = SymmetricEigen::new(normal);
    let mut order: [usize; 8] = std::array::from_fn(|k| k);
    order.sort_by(|&i, &j| eigen.eigenvalues[i].total_cmp(&eigen.eigenvalues[j]));
    // OpenCV's v6 and v7: the second-smallest and the smallest singular vectors.
    let v6: SVector<f64, 8> = eigen.eigenvectors.column(order[1]).into_owned();
    let v7: SVector<f64, 8> = eigen.eigenvectors.column(order[0]).into_owned();
    let (u1, w1) = split(&v6);
    let (u2, w2) = split(&v7);
    // Eq. (34): (λ₁, λ₂) makes the real part orthogonal to the dual part:
    // a λ₁² + b λ₁λ₂ + c λ₂² = 0. Its two root directions are taken by the stable quadratic formula,
    // in λ₁/λ₂ or λ₂/λ₁ whichever has the larger leading coefficient (OpenCV divides by a, which
    // fails when the solution lies along v7).
    let a = u1.dot(&w1);
    let b = u1.dot(&w2) + u2.dot(&w1);
    let c = u2.dot(&w2);
    let root = (b * b - 4.0 * a * c).max(0.0).sqrt();
    let q = -0.5 * (b + root.copysign(b));
    let directions = if a.abs() >= c.abs() {
        [(q / a, 1.0), (c / q, 1.0)]
    } else {
        [(1.0, q / c), (1.0, a / q)]
    };
    // Eq. (35): of the two, the one whose real part is longer (for unit (λ₁, λ₂), so that a
    // direction along v7 with its vanishing real part is not mistaken for the answer), scaled to a
    // unit real part.
    let norm = |(l1, l2): (f64, f64)| (u1 * l1 + u2 * l2).norm_squared() / (l1 * l1 + l2 * l2);
    let best = if norm(directions[0]) >= norm(directions[1]) {
        directions[0]
    } else {
        directions[1]
    };
    let scale = 1.0 / (u1 * best.0 + u2 * best.1).norm();
    let (lambda1, lambda2) = (best.0 * scale, best.1 * scale);
    let dual = v6 * lambda1 + v7 * lambda2;
    if !dual.iter().all(|v| v.is_finite()) {
        return Err(singular(check.conditioning));
    }
    let (q, q_prime) = split(&dual);
    let r_x = rotation_of(&q);
    let conjugate = Vector4::new(q[0], -q[1], -q[2], -q[3]);
    let t = multiply(&q_prime, &conjugate) * 2.0;
    let t_x = Vector3::new(t[1], t[2], t[3]) * unit;
    Ok(finish(
        Method::Daniilidis,
        motions.count(),
        check,
        &r_x,
        &t_x,
    ))
}

/// The real and dual halves of an 8-vector.
fn split(v: &SVector<f64, 8>) -> (Vector4<f64>, Vector4<f64>) {
    (
        v.fixed_rows::<4>(0).into_owned(),
        v.fixed_rows::<4>(4).into_owned(),
    )
}

/// The dual part q' = ½ (0, t) ⊗ q of a motion's dual quaternion with real part q.
fn dual_part(q: &Vector4<f64>, t: &Vector3<f64>) -> Vector4<f64> {
    multiply(&Vector4::new(0.0, t.x, t.y, t.z), q) * 0.5
}

/// The 6 rows of Eq. (31) for one motion; `r_x0` is a first estimate of R_x.
///
/// Eq. (31) drops the scalar equations a₀ = b₀, a₀' = b₀' of the screw congruence theorem, which
/// hold only for one sign of B's dual quaternion (q_b, q_b') relative to A's. Away from 180° the
/// canonical w ≥ 0 of both real parts is that sign; at 180° (a₀ = b₀ = 0) it is rounding noise
/// and the wrong sign gives six false rows. The sign of q_b (and with it q_b') is taken from
/// `r_x0` (see `motion_quaternions`).
fn rows(m: &MotionPair, r_x0: &Matrix3<f64>) -> SMatrix<f64, 6, 8> {
    let (qa, qb) = motion_quaternions(&rotation_matrix(&m.a), &rotation_matrix(&m.b), r_x0);
    let qa_ = dual_part(&qa, &m.a.translation.vector);
    let qb_ = dual_part(&qb, &m.b.translation.vector);
    let vec = |q: &Vector4<f64>| Vector3::new(q[1], q[2], q[3]);
    let (a, b, a_, b_) = (vec(&qa), vec(&qb), vec(&qa_), vec(&qb_));
    let mut t = SMatrix::<f64, 6, 8>::zeros();
    t.fixed_view_mut::<3, 1>(0, 0).copy_from(&(a - b));
    t.fixed_view_mut::<3, 3>(0, 1).copy_from(&skew(&(a + b)));
    t.fixed_view_mut::<3, 1>(3, 0).copy_from(&(a_ - b_));
    t.fixed_view_mut::<3, 3>(3, 1).copy_from(&skew(&(a_ + b_)));
    t.fixed_view_mut::<3, 1>(3, 4).copy_from(&(a - b));
    t.fixed_view_mut::<3, 3>(3, 5).copy_from(&skew(&(a + b)));
    t
}
