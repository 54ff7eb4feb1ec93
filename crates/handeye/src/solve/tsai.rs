//! Tsai and Lenz's solver, as OpenCV's `CALIB_HAND_EYE_TSAI` computes it.

use nalgebra::{Matrix3, Vector3, Vector4};
use serde::{Deserialize, Serialize};

use crate::model::error::{Error, Result};
use crate::model::motion::MotionPair;
use crate::model::pose::{rotation_matrix, skew};
use crate::solve::least_squares::least_squares_3;
use crate::solve::motions::MotionSource;
use crate::solve::quaternion::{Signs, motion_quaternions, rotation_of};
use crate::solve::{
    Calibration, Method, MotionCheck, check_motions, finish, singular, translation_least_squares,
};

/// Options of `tsai_with`; `Default` gives the values on each field.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct TsaiOptions {
    /// Drop the motions whose gripper rotation (A) or camera rotation (B) has 2·sin(θ/2) outside
    /// [0.3, 1.7] (θ below about 17° or above about 116°), as OpenCV 4.14's Tsai does before
    /// solving (its fix for OpenCV issue #24871). With fewer than two motions left the solve fails
    /// with [`Error::TooFewMotions`], where OpenCV logs an error and returns the identity.
    /// Default `false`.
    pub opencv_filter: bool,
}

impl TsaiOptions {
    /// Tsai and Lenz's solve of A X = X B with these options: OpenCV's motion
    /// filter with [`TsaiOptions::opencv_filter`]. [`solve`](crate::solve())`(Method::Tsai, …)`
    /// is this with the default options, and [`calibrate`](crate::calibrate()) solves Tsai with
    /// `Options::tsai`.
    pub fn solve(&self, motions: &(impl MotionSource + ?Sized)) -> Result<Calibration> {
        tsai_with(motions, self)
    }

    /// What OpenCV's motion filter did, in words, when it dropped motions (`None` when it kept all
    /// `of`): the drop-in applies it silently for OpenCV's Tsai constant, as OpenCV does, and its
    /// callers should know why X comes from fewer motions than they gave.
    pub fn opencv_filter_note(kept: usize, of: usize) -> Option<String> {
        let turn = |p: f64| (2.0 * (p / 2.0).asin()).to_degrees();
        (kept < of).then(|| {
            format!(
                "OpenCV's Tsai motion filter kept {kept} of {of} motions: as cv2.calibrateHandEye does, it drops a motion whose gripper or camera turn has 2·sin(θ/2) outside [{}, {}] (turns under {:.1}° or over {:.1}°), and X comes from the motions kept",
                FILTER_RANGE.0,
                FILTER_RANGE.1,
                turn(FILTER_RANGE.0),
                turn(FILTER_RANGE.1)
            )
        })
    }
}

/// Range of 2·sin(θ/2) kept by the OpenCV motion filter.
const FILTER_RANGE: (f64, f64) = (0.3, 1.7);

/// Tsai and Lenz's two-step solution with the modified Rodrigues vector P = 2 sin(θ/2) k.
///
/// Eq. (12): `[P_g + P_c]× P'_cg = P_c − P_g` in least squares over all motions; Eq. (14):
/// `P_cg = 2 P'_cg / √(1 + |P'_cg|²)` gives R_x; Eq. (15): `(R_g − I) t_x = R_x t_c − t_g` in
/// least squares. The quaternion of each rotation is read by OpenCV's branches so that the same
/// motions give OpenCV's answer, with the sign of P_c made to agree with P_g (which OpenCV leaves
/// to chance at 180°, see `solve_tsai`).
///
/// # References
/// R. Y. Tsai, R. K. Lenz, "A new technique for fully autonomous and efficient 3D robotics
/// hand/eye calibration", IEEE Trans. Robotics and Automation 5(3), 1989.
///
/// # Example
/// ```
/// use handeye::{Method, MotionPair, Transform, solve};
/// use nalgebra::{Rotation3, Translation3, Vector3};
/// let x = Transform::from_parts(Translation3::new(0.1, 0.0, 0.05), Rotation3::from_euler_angles(0.1, 0.2, 0.3));
/// let a1 = Transform::new(Vector3::new(0.1, 0.2, 0.3), Vector3::new(0.5, 0.0, 0.0));
/// let a2 = Transform::new(Vector3::new(-0.2, 0.1, 0.4), Vector3::new(0.0, 0.4, 0.1));
/// let motions: Vec<_> = [a1, a2].iter().map(|a| MotionPair { a: *a, b: x.inverse() * a * x }).collect();
/// let cal = solve(Method::Tsai, &motions)?;
/// assert!((cal.x.to_homogeneous() - x.to_homogeneous()).norm() < 1e-9);
/// # Ok::<(), handeye::Error>(())
/// ```
pub fn tsai(motions: &(impl MotionSource + ?Sized)) -> Result<Calibration> {
    tsai_with(motions, &TsaiOptions::default())
}

/// [`tsai`] with options.
///
/// With [`TsaiOptions::opencv_filter`] the motions outside OpenCV's range are dropped first and
/// [`check_motions`] runs on the motions kept, so the result's `motions`, `conditioning` and
/// warnings are theirs. When fewer than two are kept, degenerate input is reported as without
/// the filter, other input as [`Error::TooFewMotions`] with the number kept.
///
/// # Example
/// ```
/// use handeye::solve::{TsaiOptions, tsai_with};
/// use handeye::{MotionPair, Transform};
/// use nalgebra::{Rotation3, Translation3, Vector3};
/// let x = Transform::from_parts(Translation3::new(0.1, 0.0, 0.05), Rotation3::from_euler_angles(0.1, 0.2, 0.3));
/// // 0.5 rad and 0.6 rad pass OpenCV's filter; 0.1 rad (2·sin(θ/2) = 0.1) does not.
/// let a: Vec<Transform> = [Vector3::new(0.5, 0.0, 0.0), Vector3::new(0.0, 0.6, 0.0), Vector3::new(0.0, 0.0, 0.1)]
///     .iter()
///     .map(|r| Transform::new(Vector3::new(0.2, -0.1, 0.3), *r))
///     .collect();
/// let motions: Vec<_> = a.iter().map(|a| MotionPair { a: *a, b: x.inverse() * a * x }).collect();
/// let cal = tsai_with(&motions, &TsaiOptions { opencv_filter: true })?;
/// assert_eq!(cal.motions, 2);
/// assert!((cal.x.to_homogeneous() - x.to_homogeneous()).norm() < 1e-9);
/// # Ok::<(), handeye::Error>(())
/// ```
pub fn tsai_with(
    motions: &(impl MotionSource + ?Sized),
    options: &TsaiOptions,
) -> Result<Calibration> {
    if !options.opencv_filter {
        let check = check_motions(motions)?;
        return solve_tsai(motions, check);
    }
    // OpenCV 4.14 keeps a motion only when both its gripper and its camera rotation are in range.
    let mut kept: Vec<MotionPair> = Vec::with_capacity(motions.count());
    motions.for_each_motion(|m| {
        if in_filter_range(&rotation_matrix(&m.a)) && in_filter_range(&rotation_matrix(&m.b)) {
            kept.push(*m);
        }
    });
    if kept.len() < 2 {
        // Degenerate input is reported as such (as without the filter); otherwise the filter
        // left too little.
        check_motions(motions)?;
        return Err(Error::TooFewMotions {
            got: kept.len(),
            need: 2,
        });
    }
    let check = check_motions(kept.as_slice())?;
    solve_tsai(kept.as_slice(), check)
}

/// Eqs. (12)–(15) on motions that passed [`check_motions`].
fn solve_tsai(motions: &(impl MotionSource + ?Sized), check: MotionCheck) -> Result<Calibration> {
    // Eq. (12), stacked over the motions. It holds only when P_c is P_g seen from the camera,
    // P_c = R_xᵀ P_g: the same angle and the same orientation of the axis. At θ = 180° the sign of
    // the axis that a rotation matrix gives is arbitrary (2 sin(θ/2) k and −2 sin(θ/2) k are the
    // same rotation), and a P_c of the other sign turns Eq. (12) into a false equation; so the
    // sign of P_c is taken from Andreff's R_x (see `motion_quaternions`).
    let r_x0 = check.andreff_rotation;
    let p_prime = least_squares_3(motions, |m| {
        let (q_g, q_c) = motion_quaternions(
            &rotation_matrix(&m.a),
            &rotation_matrix(&m.b),
            &r_x0,
            Signs::NearHalfTurn,
        );
        let p_g = vector_part(&q_g) * 2.0;
        let p_c = vector_part(&q_c) * 2.0;
        (skew(&(p_g + p_c)), p_c - p_g)
    })
    .ok_or_else(|| singular(check.conditioning))?;
    // Eq. (14), P_cg = 2 P'_cg / √(1 + |P'_cg|²), written as the unit quaternion
    // (1, P'_cg) / √(1 + |P'_cg|²) (P'_cg = tan(θ/2) k): the same rotation, without recovering
    // cos(θ/2) as √(1 − |P_cg|²/4), which cancels and loses digits as θ_x nears 180°.
    let q_x =
        Vector4::new(1.0, p_prime.x, p_prime.y, p_prime.z) / (1.0 + p_prime.norm_squared()).sqrt();
    let r_x: Matrix3<f64> = rotation_of(&q_x);
    // Eq. (15).
    let t_x =
        translation_least_squares(motions, &r_x).ok_or_else(|| singular(check.conditioning))?;
    Ok(finish(Method::Tsai, motions.count(), check, &r_x, &t_x))
}

/// The vector part of a quaternion (w, x, y, z).
fn vector_part(q: &Vector4<f64>) -> Vector3<f64> {
    Vector3::new(q[1], q[2], q[3])
}

/// Whether a rotation passes OpenCV's motion filter: |P| in [0.3, 1.7].
fn in_filter_range(r: &Matrix3<f64>) -> bool {
    (FILTER_RANGE.0..=FILTER_RANGE.1).contains(&modified_rodrigues_norm(r))
}

/// |P| = 2·sin(θ/2), the length of the modified Rodrigues vector. OpenCV takes it from the
/// quaternion; from the trace, tr R = 1 + 2 cos θ = 3 − 4 sin²(θ/2), it is √(3 − tr R), with no
/// quaternion to make (the same value to rounding).
fn modified_rodrigues_norm(r: &Matrix3<f64>) -> f64 {
    (3.0 - r.trace()).max(0.0).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solve::quaternion::quaternion_of;
    use proptest::prelude::*;

    proptest! {
        /// The filter's |P| from the trace is OpenCV's, twice the norm of the quaternion's vector
        /// part, over every angle and axis (to rounding).
        #[test]
        fn filter_norm_from_the_trace_is_the_quaternions(
            angle in 0.0f64..std::f64::consts::PI,
            axis in prop::array::uniform3(-1.0f64..1.0),
        ) {
            let axis = Vector3::from(axis);
            prop_assume!(axis.norm() > 1e-3);
            let r = *nalgebra::Rotation3::new(axis.normalize() * angle).matrix();
            let q = quaternion_of(&r);
            let from_quaternion = 2.0 * vector_part(&q).norm();
            let from_trace = modified_rodrigues_norm(&r);
            // √ of a difference near 0 loses half the digits: 1e-8 at worst, at tiny angles.
            prop_assert!((from_quaternion - from_trace).abs() < 1e-7, "{from_quaternion} vs {from_trace}");
            let bounds = FILTER_RANGE;
            let near_bound = (from_quaternion - bounds.0).abs().min((from_quaternion - bounds.1).abs()) < 1e-12;
            prop_assert!(near_bound || in_filter_range(&r) == (bounds.0..=bounds.1).contains(&from_quaternion));
        }
    }
}
