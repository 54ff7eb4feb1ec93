//! Daniilidis' dual-quaternion solver, as OpenCV's `CALIB_HAND_EYE_DANIILIDIS` computes it.

use nalgebra::{SMatrix, SVector, SymmetricEigen, Vector3, Vector4};

use crate::error::Result;
use crate::motion::MotionPair;
use crate::pose::{rotation_matrix, skew};
use crate::solve::quaternion::{multiply, quaternion_of, rotation_of};
use crate::solve::{Calibration, Method, check_motions, finish, singular};

/// Daniilidis' simultaneous solution with dual quaternions.
///
/// Each motion gives 6 rows of Eq. (31) in the 8 entries of X's dual quaternion (q, q'):
/// `[a − b, [a + b]×, 0, 0; a' − b', [a' + b']×, a − b, [a + b]×]`, with a, a' (b, b') the vector
/// parts of the dual quaternion of A (B). X lies in the span of the two right singular vectors
/// of the smallest singular values (found from the 8×8 normal matrix); Eqs. (34)–(35) fix the
/// combination that is a unit dual quaternion.
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
pub fn daniilidis(motions: &[MotionPair]) -> Result<Calibration> {
    let check = check_motions(motions)?;
    let mut normal = SMatrix::<f64, 8, 8>::zeros();
    for m in motions {
        let t = rows(m);
        normal += t.transpose() * t;
    }
    let eigen = SymmetricEigen::new(normal);
    let mut order: [usize; 8] = std::array::from_fn(|k| k);
    order.sort_by(|&i, &j| eigen.eigenvalues[i].total_cmp(&eigen.eigenvalues[j]));
    // OpenCV's v6 and v7: the second-smallest and the smallest singular vectors.
    let v6: SVector<f64, 8> = eigen.eigenvectors.column(order[1]).into_owned();
    let v7: SVector<f64, 8> = eigen.eigenvectors.column(order[0]).into_owned();
    let (u1, w1) = split(&v6);
    let (u2, w2) = split(&v7);
    // Eq. (34): λ₁/λ₂ = s solves a s² + b s + c = 0 so that the real part is orthogonal to the dual.
    let a = u1.dot(&w1);
    let b = u1.dot(&w2) + u2.dot(&w1);
    let c = u2.dot(&w2);
    let root = (b * b - 4.0 * a * c).sqrt();
    let s1 = (-b + root) / (2.0 * a);
    let s2 = (-b - root) / (2.0 * a);
    // Eq. (35): of the two, the one that gives the larger norm of the real part.
    let norm = |s: f64| s * s * u1.dot(&u1) + 2.0 * s * u1.dot(&u2) + u2.dot(&u2);
    let (s, value) = if norm(s1) > norm(s2) {
        (s1, norm(s1))
    } else {
        (s2, norm(s2))
    };
    let lambda2 = (1.0 / value).sqrt();
    let lambda1 = s * lambda2;
    let dual = v6 * lambda1 + v7 * lambda2;
    if !dual.iter().all(|v| v.is_finite()) {
        return Err(singular(check.conditioning));
    }
    let (q, q_prime) = split(&dual);
    let r_x = rotation_of(&q);
    let conjugate = Vector4::new(q[0], -q[1], -q[2], -q[3]);
    let t = multiply(&q_prime, &conjugate) * 2.0;
    let t_x = Vector3::new(t[1], t[2], t[3]);
    Ok(finish(Method::Daniilidis, motions.len(), check, &r_x, &t_x))
}

/// The real and dual halves of an 8-vector.
fn split(v: &SVector<f64, 8>) -> (Vector4<f64>, Vector4<f64>) {
    (
        v.fixed_rows::<4>(0).into_owned(),
        v.fixed_rows::<4>(4).into_owned(),
    )
}

/// Real part q and dual part q' = ½ (0, t) ⊗ q of a motion's dual quaternion.
fn dual_quaternion(r: &nalgebra::Matrix3<f64>, t: &Vector3<f64>) -> (Vector4<f64>, Vector4<f64>) {
    let q = quaternion_of(r);
    let q_prime = multiply(&Vector4::new(0.0, t.x, t.y, t.z), &q) * 0.5;
    (q, q_prime)
}

/// The 6 rows of Eq. (31) for one motion.
fn rows(m: &MotionPair) -> SMatrix<f64, 6, 8> {
    let (qa, qa_) = dual_quaternion(&rotation_matrix(&m.a), &m.a.translation.vector);
    let (qb, qb_) = dual_quaternion(&rotation_matrix(&m.b), &m.b.translation.vector);
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
