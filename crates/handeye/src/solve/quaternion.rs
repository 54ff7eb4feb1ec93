//! Quaternions for the quaternion-based methods (Tsai, Horaud, Daniilidis).
//!
//! OpenCV reads a quaternion from a matrix by four branches and keeps whatever sign the branch
//! gives; for rotations above 120° (trace < 0) the scalar part can come out negative for A and
//! positive for B, and the methods, which need the same sign on both sides, then return a wrong X.
//! Here the same branches are used (for the same rounding) and the sign is then made canonical,
//! w ≥ 0: identical to OpenCV wherever OpenCV is right.
//!
//! The canonical sign is not enough at 180°. A motion pair needs q_b = q_x* ⊗ q_a ⊗ q_x (the
//! scalar parts equal and b = R_xᵀ a), and at θ = 180° the scalar part w = cos(θ/2) is 0: what
//! the matrices give is ±(rounding), its sign is noise, and "w ≥ 0" then picks the sign of q_a and
//! q_b independently, half the time the wrong pair (−q_b satisfies q_a ⊗ q_x = −q_x ⊗ q_b, a
//! different linear constraint, and one such motion pulls the least squares to a wrong X; on
//! exact data it was 180° off). [`motion_quaternions`] takes the sign of q_b from the data
//! instead, near 180° ([`HALF_TURN_WITHIN`]): the one closer to the q_b that a first estimate of
//! R_x predicts.

use nalgebra::{Matrix3, Vector3, Vector4};

/// Quaternion (w, x, y, z), w ≥ 0, of a rotation matrix by the four-branch method of OpenCV's
/// `rot2quat` (Shepperd's).
pub fn quaternion_of(r: &Matrix3<f64>) -> Vector4<f64> {
    let q = branch_quaternion(r);
    if q[0] < 0.0 { -q } else { q }
}

/// How far from 180° a motion's rotations may turn for the sign of their quaternions (and the
/// lift of their logarithms) to be in question: 10°, where the scalar part cos(θ/2) is below
/// sin 5° ≈ 0.087. Noise moves a rotation's angle by far less (kinhec's PnP noise: under 1°), so
/// a motion pair that agrees with X and crosses 180° by noise is inside it. Beyond it, a pair
/// whose quaternions disagree under every near estimate of R_x is not a sign question but a pair
/// that does not agree with X (an outlier): its canonical signs are kept, as OpenCV keeps them.
pub(crate) const HALF_TURN_WITHIN: f64 = 10.0 * std::f64::consts::PI / 180.0;

/// The scalar part cos(θ/2) at θ = 180° − [`HALF_TURN_WITHIN`], sin 5°: quaternions with a larger
/// one are not near a half turn (a constant, not a `sin` per motion).
const HALF_TURN_SCALAR: f64 = 0.087_155_742_747_658_17;

/// Which motions [`motion_quaternions`] gives the sign that agrees with the estimate of R_x.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Signs {
    /// Every motion (Daniilidis, whose all-pairs sums give every pair the sign that agrees, per
    /// pose: the per-motion form must choose as they do).
    Agreeing,
    /// Only motions that turn within [`HALF_TURN_WITHIN`] of 180° on both sides; the others keep
    /// w ≥ 0 (Tsai, Horaud). Giving an outlier motion the sign that agrees with Andreff's R_x makes
    /// it pull towards Andreff's answer, which the outliers have moved too: on kinhec's series
    /// with random poses Horaud answered 10° from the truth where OpenCV's w ≥ 0 answers 5°.
    NearHalfTurn,
}

/// The quaternions (q_a, q_b) of a motion pair's rotations, with the signs that make
/// q_a ⊗ q_x = q_x ⊗ q_b hold for the true X.
///
/// q_a is [`quaternion_of`] R_a (w ≥ 0). q_b is ±[`quaternion_of`] R_b, whichever is nearer (in
/// R⁴) to q_x* ⊗ q_a ⊗ q_x = (w_a, R_xᵀ a) predicted by `r_x`, a first estimate of R_x (Andreff's
/// rotation, which has no sign ambiguity), for the motions `signs` names; w ≥ 0 for the others.
/// The two candidates are 180° apart as rotations of the pair, so any estimate within 90° of R_x
/// chooses right. For a pair that agrees with X, away from 180° both scalar parts are clearly
/// positive and the choice is the canonical w ≥ 0 one (OpenCV's answer is unchanged); it differs
/// when |w| is at noise level, where w ≥ 0 is arbitrary.
pub(crate) fn motion_quaternions(
    r_a: &Matrix3<f64>,
    r_b: &Matrix3<f64>,
    r_x: &Matrix3<f64>,
    signs: Signs,
) -> (Vector4<f64>, Vector4<f64>) {
    let q_a = quaternion_of(r_a);
    let q_b = quaternion_of(r_b);
    if signs == Signs::NearHalfTurn && q_a[0].max(q_b[0]) > HALF_TURN_SCALAR {
        return (q_a, q_b);
    }
    let predicted = r_x.transpose() * Vector3::new(q_a[1], q_a[2], q_a[3]);
    let agreement = q_a[0] * q_b[0] + predicted.dot(&Vector3::new(q_b[1], q_b[2], q_b[3]));
    (q_a, if agreement < 0.0 { -q_b } else { q_b })
}

/// The four-branch quaternion with the sign its branch gives.
fn branch_quaternion(r: &Matrix3<f64>) -> Vector4<f64> {
    let (m00, m01, m02) = (r[(0, 0)], r[(0, 1)], r[(0, 2)]);
    let (m10, m11, m12) = (r[(1, 0)], r[(1, 1)], r[(1, 2)]);
    let (m20, m21, m22) = (r[(2, 0)], r[(2, 1)], r[(2, 2)]);
    let trace = m00 + m11 + m22;
    if trace > 0.0 {
        let s = (trace + 1.0).sqrt() * 2.0;
        Vector4::new(0.25 * s, (m21 - m12) / s, (m02 - m20) / s, (m10 - m01) / s)
    } else if m00 > m11 && m00 > m22 {
        let s = (1.0 + m00 - m11 - m22).sqrt() * 2.0;
        Vector4::new((m21 - m12) / s, 0.25 * s, (m01 + m10) / s, (m02 + m20) / s)
    } else if m11 > m22 {
        let s = (1.0 + m11 - m00 - m22).sqrt() * 2.0;
        Vector4::new((m02 - m20) / s, (m01 + m10) / s, 0.25 * s, (m12 + m21) / s)
    } else {
        let s = (1.0 + m22 - m00 - m11).sqrt() * 2.0;
        Vector4::new((m10 - m01) / s, (m02 + m20) / s, (m12 + m21) / s, 0.25 * s)
    }
}

/// Rotation matrix of a unit quaternion (w, x, y, z).
pub fn rotation_of(q: &Vector4<f64>) -> Matrix3<f64> {
    let (w, x, y, z) = (q[0], q[1], q[2], q[3]);
    Matrix3::new(
        1.0 - 2.0 * y * y - 2.0 * z * z,
        2.0 * x * y - 2.0 * z * w,
        2.0 * x * z + 2.0 * y * w,
        2.0 * x * y + 2.0 * z * w,
        1.0 - 2.0 * x * x - 2.0 * z * z,
        2.0 * y * z - 2.0 * x * w,
        2.0 * x * z - 2.0 * y * w,
        2.0 * y * z + 2.0 * x * w,
        1.0 - 2.0 * x * x - 2.0 * y * y,
    )
}

/// Hamilton product s ⊗ t of quaternions (w, x, y, z).
pub fn multiply(s: &Vector4<f64>, t: &Vector4<f64>) -> Vector4<f64> {
    Vector4::new(
        s[0] * t[0] - s[1] * t[1] - s[2] * t[2] - s[3] * t[3],
        s[0] * t[1] + s[1] * t[0] + s[2] * t[3] - s[3] * t[2],
        s[0] * t[2] - s[1] * t[3] + s[2] * t[0] + s[3] * t[1],
        s[0] * t[3] + s[1] * t[2] - s[2] * t[1] + s[3] * t[0],
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::pose::exp_so3;

    #[test]
    fn the_half_turn_scalar_is_the_angles() {
        assert!((HALF_TURN_SCALAR - (0.5 * HALF_TURN_WITHIN).sin()).abs() < 1e-17);
    }

    #[test]
    fn round_trips_in_every_branch() {
        for w in [
            Vector3::new(0.1, 0.2, 0.3),
            Vector3::new(3.0, 0.1, 0.0),
            Vector3::new(0.0, 3.0, 0.1),
            Vector3::new(0.1, 0.0, 3.0),
        ] {
            let r = exp_so3(&w);
            let q = quaternion_of(&r);
            assert!((q.norm() - 1.0).abs() < 1e-12);
            assert!((rotation_of(&q) - r).abs().max() < 1e-12);
            assert!(q[0] >= 0.0);
        }
    }
}
