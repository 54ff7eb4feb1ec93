//! Rigid transforms and SO(3) helpers: the conventions every other module relies on.
//!
//! A transform is a [`Transform`] (`nalgebra::IsometryMatrix3<f64>`: a rotation matrix and a
//! translation) named `a_from_b`: it maps
//! b-coordinates into frame a (`p_a = a_from_b * p_b`), so products chain visibly:
//! `a_from_c = a_from_b * b_from_c`.

use nalgebra::{
    IsometryMatrix3, Matrix3, Matrix4, Quaternion, Rotation3, Translation3, UnitQuaternion, Vector3,
};

use serde::{Deserialize, Serialize};

/// A rigid transform `a_from_b` (rotation then translation): `p_a = R p_b + t`.
///
/// The rotation is stored as a matrix: the solvers work on matrices, and inverse and products are
/// then exact transposes and plain matrix products, as in OpenCV and in the paper's equations.
pub type Transform = IsometryMatrix3<f64>;

/// Rotations read from files whose deviation from orthonormality is below this are kept exactly as
/// given; larger deviations (up to [`ORTHONORMAL_TOL`]) are projected onto SO(3).
pub const KEEP_AS_GIVEN_TOL: f64 = 1e-12;

/// Largest deviation of `RᵀR` from the identity (max entry) accepted for a rotation read from data.
/// Rotations printed with 6 decimals (logs, copy-paste) deviate by about 1e-6, with 4 by 1e-4:
/// such a matrix is orthonormal to the precision it was printed with, and is projected onto the
/// nearest rotation. A larger deviation is not rounding and is refused.
pub const ORTHONORMAL_TOL: f64 = 1e-3;

/// Largest deviation of a quaternion's norm from 1 that input normalises silently; further is refused.
pub const QUATERNION_NORM_TOL: f64 = 1e-3;

/// Largest size of a translation component accepted from data, in any unit: a million kilometres
/// in metres, a kilometre in micrometres. Beyond it a value is a corrupt field, and inverses and
/// products of poses could overflow.
pub const MAX_TRANSLATION: f64 = 1e9;

/// Rotations smaller than this (radians) have no defined axis (SPEC sec. 1).
pub(crate) const NO_AXIS_ANGLE: f64 = 1e-12;

/// Builds a transform from a rotation matrix that is already a rotation (not checked) and a translation.
pub fn transform_from_parts(rotation: &Matrix3<f64>, translation: &Vector3<f64>) -> Transform {
    IsometryMatrix3::from_parts(
        Translation3::from(*translation),
        Rotation3::from_matrix_unchecked(*rotation),
    )
}

/// The rotation matrix of a transform.
pub fn rotation_matrix(a_from_b: &Transform) -> Matrix3<f64> {
    *a_from_b.rotation.matrix()
}

/// What is wrong with a transform read from data.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum TransformProblem {
    /// A NaN or infinite entry.
    NotFinite,
    /// `RᵀR` differs from the identity by more than
    /// `ORTHONORMAL_TOL` (the largest entry deviation is given).
    NotOrthonormal {
        /// Largest absolute entry of `RᵀR − I`.
        deviation: f64,
    },
    /// The rotation part has a negative determinant (a reflection).
    Reflection,
    /// The last row of a homogeneous matrix is not `0 0 0 1`.
    BadLastRow,
    /// A quaternion whose norm is not within 1e-3 of 1.
    QuaternionNorm {
        /// The norm found.
        norm: f64,
    },
    /// Both a matrix and translation + quaternion were given and they differ by more than 1e-6 and
    /// more than the matrix's deviation from orthonormality (the precision it was printed with).
    Inconsistent {
        /// Largest entry difference between the two.
        difference: f64,
    },
    /// A translation component beyond `MAX_TRANSLATION` in size:
    /// not a length in any unit (a corrupt field), and one whose products could overflow.
    ImplausibleTranslation {
        /// The value found.
        value: f64,
    },
}

impl std::fmt::Display for TransformProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::NotFinite => write!(f, "contains a NaN or infinite value"),
            Self::NotOrthonormal { deviation } => write!(
                f,
                "rotation is not orthonormal (|RᵀR − I| reaches {deviation:.3e}, more than {:e}: beyond rounding when printed)",
                ORTHONORMAL_TOL
            ),
            Self::Reflection => write!(f, "rotation has det < 0 (a reflection, not a rotation)"),
            Self::BadLastRow => write!(f, "last row of the 4×4 matrix is not [0, 0, 0, 1]"),
            Self::QuaternionNorm { norm } => {
                write!(f, "quaternion norm is {norm:.6}, not within 1e-3 of 1")
            }
            Self::Inconsistent { difference } => write!(
                f,
                "`matrix` and `translation`/`quaternion_xyzw` disagree (by {difference:.3e}, more than 1e-6 and more than the matrix's own rounding)"
            ),
            Self::ImplausibleTranslation { value } => write!(
                f,
                "translation {value:e} is not a plausible length in any unit (more than {:e} in size)",
                MAX_TRANSLATION
            ),
        }
    }
}

/// Checks that `m` is a rotation: orthonormal within [`ORTHONORMAL_TOL`], det > 0, all finite;
/// its deviation from orthonormal (largest entry of `|mᵀm − I|`) when it is.
pub(crate) fn check_rotation(m: &Matrix3<f64>) -> Result<f64, TransformProblem> {
    if m.iter().any(|v| !v.is_finite()) {
        return Err(TransformProblem::NotFinite);
    }
    let deviation = orthonormality_deviation(m);
    // A NaN (entries whose squares overflow) is refused too.
    if deviation.is_nan() || deviation > ORTHONORMAL_TOL {
        return Err(TransformProblem::NotOrthonormal { deviation });
    }
    if m.determinant() <= 0.0 {
        return Err(TransformProblem::Reflection);
    }
    Ok(deviation)
}

/// Checks one translation component read from data: finite and at most [`MAX_TRANSLATION`] in size.
pub(crate) fn check_translation(value: f64) -> Result<(), TransformProblem> {
    if !value.is_finite() {
        Err(TransformProblem::NotFinite)
    } else if value.abs() > MAX_TRANSLATION {
        Err(TransformProblem::ImplausibleTranslation { value })
    } else {
        Ok(())
    }
}

/// A transform read from data, with how far from orthonormal its rotation matrix was as given
/// (0 when it was given as a quaternion or a rotation vector).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ReadTransform {
    /// The transform; its rotation projected onto SO(3) when `deviation` exceeds
    /// [`KEEP_AS_GIVEN_TOL`], else exactly as given.
    pub transform: Transform,
    /// Largest entry of `|RᵀR − I|` of the rotation as given.
    pub deviation: f64,
    /// When the rotation was given as angles in degrees (a vendor's Euler angles, `rpy_deg`):
    /// the largest of them in size.
    pub degrees: Option<f64>,
}

impl ReadTransform {
    /// Whether the rotation was projected onto SO(3) (orthonormal only to the precision it was
    /// printed with).
    pub fn projected(&self) -> bool {
        self.deviation > KEEP_AS_GIVEN_TOL
    }
}

/// Reads a homogeneous 4×4 matrix (row-major, last row `0 0 0 1`) as a transform, refusing
/// anything that is not a rigid transform; a rotation orthonormal only to the precision it was
/// printed with is projected onto the nearest rotation.
pub fn transform_from_matrix4(m: &Matrix4<f64>) -> Result<Transform, TransformProblem> {
    read_matrix4(m).map(|r| r.transform)
}

/// Reads a homogeneous 4×4 matrix (row-major, last row `0 0 0 1` within 1e-6) as a transform: a
/// rotation orthonormal within [`ORTHONORMAL_TOL`] with det > 0, projected onto SO(3) unless exact
/// to rounding, and a translation passing [`check_translation`].
pub(crate) fn read_matrix4(m: &Matrix4<f64>) -> Result<ReadTransform, TransformProblem> {
    if m.iter().any(|v| !v.is_finite()) {
        return Err(TransformProblem::NotFinite);
    }
    let last = m.row(3);
    if (last[0].abs() + last[1].abs() + last[2].abs() + (last[3] - 1.0).abs()) > LAST_ROW_TOL {
        return Err(TransformProblem::BadLastRow);
    }
    let r: Matrix3<f64> = m.fixed_view::<3, 3>(0, 0).into_owned();
    let deviation = check_rotation(&r)?;
    let t: Vector3<f64> = m.fixed_view::<3, 1>(0, 3).into_owned();
    for v in t.iter() {
        check_translation(*v)?;
    }
    let mut read = ReadTransform {
        transform: transform_from_parts(&r, &t),
        deviation,
        degrees: None,
    };
    if read.projected() {
        read.transform = transform_from_parts(&proj_so3(&r), &t);
    }
    Ok(read)
}

/// Largest sum of the deviations of a 4×4 matrix's last row from `0 0 0 1`.
const LAST_ROW_TOL: f64 = 1e-6;

/// Builds a transform from a translation and a quaternion given as `[x, y, z, w]` (file order).
/// A quaternion whose norm is within [`QUATERNION_NORM_TOL`] of 1 is normalised; others are refused,
/// as are translations that are not finite or beyond [`MAX_TRANSLATION`].
pub fn transform_from_xyz_quat_xyzw(
    translation: [f64; 3],
    quaternion_xyzw: [f64; 4],
) -> Result<Transform, TransformProblem> {
    if quaternion_xyzw.iter().any(|v| !v.is_finite()) {
        return Err(TransformProblem::NotFinite);
    }
    for v in translation {
        check_translation(v)?;
    }
    let [x, y, z, w] = quaternion_xyzw;
    // nalgebra's constructor takes w first.
    let q = Quaternion::new(w, x, y, z);
    let norm = q.norm();
    // A NaN norm is refused too.
    if norm.is_nan() || (norm - 1.0).abs() > QUATERNION_NORM_TOL {
        return Err(TransformProblem::QuaternionNorm { norm });
    }
    Ok(IsometryMatrix3::from_parts(
        Translation3::new(translation[0], translation[1], translation[2]),
        UnitQuaternion::from_quaternion(q).to_rotation_matrix(),
    ))
}

/// The quaternion of a transform in file order `[x, y, z, w]`, with `w ≥ 0`.
pub fn quaternion_xyzw(a_from_b: &Transform) -> [f64; 4] {
    let q = UnitQuaternion::from_rotation_matrix(&a_from_b.rotation);
    let s = if q.w < 0.0 { -1.0 } else { 1.0 };
    [s * q.i, s * q.j, s * q.k, s * q.w]
}

/// Largest entry of |RᵀR − I|.
fn orthonormality_deviation(m: &Matrix3<f64>) -> f64 {
    (m.transpose() * m - Matrix3::identity()).abs().max()
}

/// Nearest rotation to `m` in the Frobenius norm: `U diag(1, 1, det(UVᵀ)) Vᵀ` (SPEC sec. 3).
///
/// When det(m) > 0 this is the orthogonal polar factor of m, computed by Higham's scaled Newton
/// iteration `X ← ½(γX + X⁻ᵀ/γ)` (quadratic convergence, a few 3×3 inverses: an order of magnitude
/// cheaper than an SVD, and as accurate); otherwise, or if the iteration does not settle, by SVD.
/// A matrix already orthonormal to 1e-5 (a rotation printed with six or more digits, say) takes
/// one or two Newton–Schulz steps instead, which need no inverse.
pub fn proj_so3(m: &Matrix3<f64>) -> Matrix3<f64> {
    if let Some(r) = near_rotation_polar(m) {
        return r;
    }
    if m.determinant() > 0.0
        && let Some(r) = polar_newton(m)
    {
        return r;
    }
    proj_so3_svd(m)
}

/// Orthogonal polar factor by the scaled Newton iteration; `None` if it does not converge.
fn polar_newton(m: &Matrix3<f64>) -> Option<Matrix3<f64>> {
    let mut x = *m;
    for _ in 0..POLAR_ITERATIONS {
        let inv_t = x.try_inverse()?.transpose();
        // Frobenius-norm scaling γ = (‖X⁻¹‖_F / ‖X‖_F)^½ speeds up the first steps.
        let gamma = (inv_t.norm() / x.norm()).sqrt();
        let next = (x * gamma + inv_t / gamma) * 0.5;
        let change = (next - x).abs().max();
        x = next;
        if change <= 4.0 * f64::EPSILON {
            // One more unscaled step polishes the last bits.
            let inv_t = x.try_inverse()?.transpose();
            return Some((x + inv_t) * 0.5);
        }
    }
    None
}

/// Largest deviation of `MᵀM` from I (max entry) for which [`proj_so3`] takes Newton–Schulz
/// steps: from there two steps reach rounding.
const NEAR_ROTATION: f64 = 1e-5;

/// The orthogonal polar factor of a matrix within [`NEAR_ROTATION`] of orthonormal with det > 0,
/// by the Newton–Schulz iteration `X ← ½ X (3I − XᵀX)` (N. J. Higham, *Functions of Matrices*,
/// 2008, sec. 8.3). For `X = Q(I + E)`, E symmetric, one step leaves `Q(I − 3E²/2 − E³/2)`: the
/// error is squared, so a deviation up to 1e-9 needs one step and up to [`NEAR_ROTATION`] two.
/// `None` for any other matrix.
fn near_rotation_polar(m: &Matrix3<f64>) -> Option<Matrix3<f64>> {
    let identity = Matrix3::identity();
    let gram = m.transpose() * m;
    let deviation = (gram - identity).abs().max();
    if !(deviation <= NEAR_ROTATION && m.determinant() > 0.0) {
        return None;
    }
    let mut x = m * (identity * 3.0 - gram) * 0.5;
    if deviation > 1e-9 {
        x = x * (identity * 3.0 - x.transpose() * x) * 0.5;
    }
    Some(x)
}

/// Iteration cap of [`polar_newton`] (it needs about 5 from a near-rotation, 10 from far).
const POLAR_ITERATIONS: usize = 30;

/// Nearest rotation by SVD: `U diag(1, 1, det(UVᵀ)) Vᵀ`.
fn proj_so3_svd(m: &Matrix3<f64>) -> Matrix3<f64> {
    // A finite 3×3 SVD converges in a few sweeps; the cap only guards against NaN input, for
    // which the result is NaN too.
    let Some((u, v_t)) = m
        .try_svd(true, true, f64::EPSILON, 1000)
        .and_then(|svd| svd.u.zip(svd.v_t))
    else {
        return Matrix3::from_element(f64::NAN);
    };
    let d = (u * v_t).determinant().signum();
    u * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, d)) * v_t
}

/// The skew-symmetric matrix `[v]×` with `[v]× w = v × w`.
pub(crate) fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// Exponential map of so(3): the rotation `exp([w]×)` of angle `‖w‖` about `w`.
pub fn exp_so3(w: &Vector3<f64>) -> Matrix3<f64> {
    *Rotation3::new(*w).matrix()
}

/// Axis–angle of a rotation matrix (Rodrigues), robust near 0 and near π.
///
/// Returns the angle θ ∈ [0, π] and the unit axis, or `None` for the axis when θ < 1e-12
/// (SPEC sec. 1). Near θ = π the axis comes from the symmetric part of R, its sign matched to the
/// skew part.
pub fn axis_angle(r: &Matrix3<f64>) -> (f64, Option<Vector3<f64>>) {
    // sin θ · k from the skew part, cos θ from the trace: atan2 is accurate over the whole range.
    let s = 0.5
        * Vector3::new(
            r[(2, 1)] - r[(1, 2)],
            r[(0, 2)] - r[(2, 0)],
            r[(1, 0)] - r[(0, 1)],
        );
    let c = ((r.trace() - 1.0) * 0.5).clamp(-1.0, 1.0);
    let sin = s.norm();
    let theta = sin.atan2(c);
    if theta < NO_AXIS_ANGLE {
        return (theta, None);
    }
    if c > -0.5 {
        // Away from π the skew part determines the axis well.
        return (theta, Some(s / sin));
    }
    // Near π: R + Rᵀ = 2 cos θ I + 2 (1 − cos θ) k kᵀ; take the largest column of k kᵀ.
    let kk = (r + r.transpose() - Matrix3::identity() * (2.0 * c)) / (2.0 * (1.0 - c));
    let i = (0..3)
        .max_by(|&a, &b| kk[(a, a)].total_cmp(&kk[(b, b)]))
        .unwrap_or(0);
    let mut k: Vector3<f64> = kk.column(i).into_owned();
    k /= k.norm();
    if k.dot(&s) < 0.0 {
        k = -k;
    }
    (theta, Some(k))
}

/// The angle in radians of the rotation between two rotations, `∠(R₁ᵀ R₂)` ∈ [0, π], accurate
/// for tiny angles too (nalgebra's `angle_to` takes an acos that gives NaN or loses all digits
/// near 0).
pub fn rotation_angle_between(r1: &nalgebra::Rotation3<f64>, r2: &nalgebra::Rotation3<f64>) -> f64 {
    axis_angle(&(r1.matrix().transpose() * r2.matrix())).0
}

/// Logarithm of a rotation: the rotation vector θ·k (zero for the identity).
pub fn log_so3(r: &Matrix3<f64>) -> Vector3<f64> {
    match axis_angle(r) {
        (theta, Some(k)) => k * theta,
        (_, None) => Vector3::zeros(),
    }
}

/// Angle in radians between two unit axes, `acos(k₁·k₂)` ∈ [0, π] (SPEC sec. 1); 0 when either
/// axis is undefined, so that a rotation with no axis fails every axis test.
pub(crate) fn axis_angle_between(k1: Option<&Vector3<f64>>, k2: Option<&Vector3<f64>>) -> f64 {
    match (k1, k2) {
        (Some(a), Some(b)) => a.dot(b).clamp(-1.0, 1.0).acos(),
        _ => 0.0,
    }
}

/// A transform as written in output: translation, quaternion (x y z w, w ≥ 0) and the 4×4
/// row-major matrix.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TransformJson {
    /// Translation `[x, y, z]`.
    pub translation: [f64; 3],
    /// Rotation as a unit quaternion `[x, y, z, w]`.
    pub quaternion_xyzw: [f64; 4],
    /// The homogeneous 4×4 matrix, row-major.
    pub matrix: [[f64; 4]; 4],
}

impl From<&Transform> for TransformJson {
    fn from(t: &Transform) -> Self {
        let m = t.to_homogeneous();
        let v = t.translation.vector;
        Self {
            translation: [v.x, v.y, v.z],
            quaternion_xyzw: quaternion_xyzw(t),
            matrix: std::array::from_fn(|r| std::array::from_fn(|c| m[(r, c)])),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axis_angle_round_trips_over_the_whole_range() {
        for &theta in &[
            1e-9,
            1e-3,
            0.5,
            2.0,
            3.0,
            std::f64::consts::PI - 1e-5,
            std::f64::consts::PI,
        ] {
            let k = Vector3::new(0.3, -0.5, 0.8).normalize();
            let r = exp_so3(&(k * theta));
            let (t, axis) = axis_angle(&r);
            assert!((t - theta).abs() < 1e-9, "theta {theta} gave {t}");
            let axis = axis.expect("axis");
            if theta < std::f64::consts::PI {
                assert!((axis - k).norm() < 1e-6, "theta {theta}: axis {axis:?}");
            } else {
                assert!((axis.dot(&k).abs() - 1.0).abs() < 1e-9);
            }
        }
        assert!(axis_angle(&Matrix3::identity()).1.is_none());
    }

    #[test]
    fn proj_so3_returns_a_rotation() {
        let m = Matrix3::new(1.0, 0.01, 0.0, -0.02, 0.99, 0.0, 0.0, 0.003, 1.01);
        let r = proj_so3(&m);
        assert!(check_rotation(&r).is_ok());
        assert!((r - m).norm() < 0.05);
    }

    #[test]
    fn newton_and_svd_projections_agree() {
        for k in 0..50 {
            let f = k as f64;
            let m = exp_so3(&Vector3::new(0.3 * f, -0.2 * f, 0.1)) * (0.2 + 0.1 * f)
                + Matrix3::from_fn(|i, j| 0.05 * ((i * 3 + j) as f64 + f).sin());
            let a = proj_so3(&m);
            let b = proj_so3_svd(&m);
            assert!(
                (a - b).abs().max() < 1e-13,
                "case {k}: {}",
                (a - b).abs().max()
            );
        }
    }

    #[test]
    fn near_rotations_take_newton_schulz_steps_to_the_svd_projection() {
        // Rotations perturbed as printing with 4 to 15 digits perturbs them, on both sides of the
        // one-step bound (1e-9) and up to NEAR_ROTATION.
        let (mut one_step, mut two_steps) = (0, 0);
        for k in 0..400 {
            let f = k as f64;
            let r =
                exp_so3(&Vector3::new(0.7 * f, -0.3 * f, 0.05 * f + 0.1).map(|v| v.sin() * 3.0));
            let size = 10f64.powf(-5.2 - 10.0 * (k % 100) as f64 / 100.0);
            let m = r + Matrix3::from_fn(|i, j| size * ((i * 3 + j) as f64 * 1.7 + f).sin());
            let deviation = orthonormality_deviation(&m);
            let Some(fast) = near_rotation_polar(&m) else {
                assert!(deviation > NEAR_ROTATION, "case {k}: deviation {deviation}");
                continue;
            };
            if deviation > 1e-9 {
                two_steps += 1;
            } else {
                one_step += 1;
            }
            let svd = proj_so3_svd(&m);
            assert!(
                (fast - svd).abs().max() < 1e-15,
                "case {k} (deviation {deviation:e}): {:e}",
                (fast - svd).abs().max()
            );
            assert!(orthonormality_deviation(&fast) < 4.0 * f64::EPSILON);
        }
        assert!(one_step > 100 && two_steps > 100, "{one_step} {two_steps}");
        // A reflection is not a near rotation, however orthonormal.
        let flip = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -1.0));
        assert_eq!(near_rotation_polar(&flip), None);
        assert!((proj_so3(&flip).determinant() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn refuses_non_rotations() {
        let mut m = Matrix4::identity();
        m[(0, 0)] = -1.0;
        assert_eq!(
            transform_from_matrix4(&m),
            Err(TransformProblem::Reflection)
        );
        m[(0, 0)] = 1.1;
        assert!(matches!(
            transform_from_matrix4(&m),
            Err(TransformProblem::NotOrthonormal { .. })
        ));
        m[(0, 0)] = f64::NAN;
        assert_eq!(transform_from_matrix4(&m), Err(TransformProblem::NotFinite));
        assert!(matches!(
            transform_from_xyz_quat_xyzw([0.0; 3], [0.0, 0.0, 0.0, 0.9]),
            Err(TransformProblem::QuaternionNorm { .. })
        ));
    }

    /// `r` with every entry rounded to `decimals` decimals, as a 4×4 with translation `t`.
    fn printed(r: &Matrix3<f64>, t: f64, decimals: i32) -> Matrix4<f64> {
        let scale = 10f64.powi(decimals);
        let mut m = Matrix4::identity();
        for i in 0..3 {
            for j in 0..3 {
                m[(i, j)] = (r[(i, j)] * scale).round() / scale;
            }
            m[(i, 3)] = t;
        }
        m
    }

    #[test]
    fn rotations_rounded_when_printed_are_projected_and_others_refused() {
        let r = exp_so3(&Vector3::new(0.4, -1.1, 2.3));
        // Printed in full: kept bit for bit.
        let exact =
            read_matrix4(&transform_from_parts(&r, &Vector3::zeros()).to_homogeneous()).unwrap();
        assert!(!exact.projected());
        assert_eq!(exact.transform.rotation.matrix(), &r);
        for decimals in [4, 6, 9] {
            let read = read_matrix4(&printed(&r, 1.0, decimals)).unwrap();
            let q = read.transform.rotation.matrix();
            let half_unit = 0.5 * 10f64.powi(-decimals);
            assert!(read.projected(), "{decimals}");
            assert!(
                read.deviation < 6.0 * half_unit,
                "{decimals}: {}",
                read.deviation
            );
            assert!(orthonormality_deviation(q) < 1e-15, "{decimals}");
            // The nearest rotation is no further from the truth than the printed one.
            assert!((q - r).abs().max() <= 2.0 * half_unit, "{decimals}");
        }
        // Two decimals are beyond rounding: refused with the deviation measured.
        match read_matrix4(&printed(&r, 1.0, 2)) {
            Err(TransformProblem::NotOrthonormal { deviation }) => assert!(deviation > 1e-3),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn absurd_values_are_refused_and_nothing_accepted_overflows() {
        let r = exp_so3(&Vector3::new(0.4, -1.1, 2.3));
        assert!(read_matrix4(&printed(&r, MAX_TRANSLATION, 6)).is_ok());
        assert_eq!(
            read_matrix4(&printed(&r, 1e308, 6)),
            Err(TransformProblem::ImplausibleTranslation { value: 1e308 })
        );
        assert_eq!(
            transform_from_xyz_quat_xyzw([0.0, -1.5e9, 0.0], [0.0, 0.0, 0.0, 1.0]),
            Err(TransformProblem::ImplausibleTranslation { value: -1.5e9 })
        );
        // Entries whose products overflow (RᵀR holds inf − inf = NaN) are refused, not passed.
        let mut m = Matrix4::identity();
        m[(0, 0)] = 1e200;
        m[(0, 1)] = 1e200;
        m[(1, 0)] = -1e200;
        m[(1, 1)] = 1e200;
        assert!(matches!(
            read_matrix4(&m),
            Err(TransformProblem::NotOrthonormal { .. })
        ));
        assert!(matches!(
            transform_from_xyz_quat_xyzw([0.0; 3], [1e200, 1e200, 0.0, 1.0]),
            Err(TransformProblem::QuaternionNorm { .. })
        ));
        // What passes stays finite through inverses and products.
        let a = read_matrix4(&printed(&r, MAX_TRANSLATION, 6))
            .unwrap()
            .transform;
        let b =
            transform_from_xyz_quat_xyzw([-MAX_TRANSLATION; 3], [0.1, 0.2, 0.3, 0.86f64.sqrt()])
                .unwrap();
        let chain = a.inverse() * b * a * b.inverse() * a;
        assert!(chain.to_homogeneous().iter().all(|v| v.is_finite()));
    }

    #[test]
    fn quaternions_off_by_rounding_are_normalised_and_others_refused() {
        let unit = [0.1, 0.2, 0.3, (1.0f64 - 0.14).sqrt()];
        let scaled = |f: f64| unit.map(|v| v * f);
        let a = transform_from_xyz_quat_xyzw([0.0; 3], unit).unwrap();
        let b = transform_from_xyz_quat_xyzw([0.0; 3], scaled(1.0009)).unwrap();
        assert!((a.to_homogeneous() - b.to_homogeneous()).abs().max() < 1e-15);
        match transform_from_xyz_quat_xyzw([0.0; 3], scaled(1.002)) {
            Err(TransformProblem::QuaternionNorm { norm }) => assert!((norm - 1.002).abs() < 1e-12),
            other => panic!("{other:?}"),
        }
    }
}
