//! Hand–eye calibration of a low-DOF robot (a SCARA, a 4-axis pick-and-place arm, a gantry with
//! one wrist joint): every motion rotates about the same axis.
//!
//! With every A's rotation axis equal to one axis k_A (and every B's to k_B), A X = X B says:
//! - rotation: R_X k_B = k_A, which fixes X's rotation up to an angle θ about k_A
//!   (R_X = Rot(k_A, θ) R₀, R₀ any rotation taking k_B to k_A);
//! - translation: (R_A − I) t_X = R_X t_B − t_A. R_A − I is singular along k_A, so t_X's component
//!   along k_A is never determined (the prior gives it); across the axis the equation is linear in
//!   t_X⊥ and in (cos θ, sin θ): with u = R₀ t_B,
//!   P (R_A − I) t_X⊥ − cos θ P u − sin θ P (k_A × u) = −P t_A, P the projection across k_A.
//!   So θ comes from the motions' translations (as in 4-DOF hand–eye methods), even for motions
//!   that do not rotate at all.
//!
//! [`solve_low_dof`] solves that linear system for (t_X⊥, cos θ, sin θ) in least squares, puts
//! (cos θ, sin θ) back on the circle and re-solves t_X⊥ with θ fixed; the component along the axis
//! is then taken from the prior.
//!
//! # References
//! M. Ulrich, C. Steger, "Hand-eye calibration of SCARA robots using dual quaternions",
//! Pattern Recognition and Image Analysis 26 (2016): the observation that X's translation along
//! the axis is not observable and that the rest is; the linear form above is ours.

use nalgebra::{Matrix2, Matrix4, Rotation3, Unit, Vector2, Vector3, Vector4};

use crate::model::error::{Degeneracy, Error, Result};
use crate::model::motion::{MotionFeatures, MotionPair};
use crate::model::pose::{Transform, transform_from_parts};
use crate::model::prior::{Component, PRIOR_AXIS_DEG};
use crate::solve::motions::{AllPairs, MotionSource, count_pairs};

/// Motions that rotate less than this (degrees) are left out of the axis estimate (their axes are
/// noise), though their translations still fix θ.
pub const LOW_DOF_MIN_ANGLE_DEG: f64 = 5.0;

/// The motions' rotation axes are "all parallel" when every rotating motion's axis is within this
/// many degrees of the dominant axis. A robot with exact kinematics gives ≈0°; 0.1 mrad of
/// rotation noise on a 5° motion moves its axis by ≈0.1°.
pub const LOW_DOF_SPREAD_DEG: f64 = 2.0;

/// The conditioning of the scaled translation system below which θ or t_X⊥ is not determined.
pub(crate) const REFUSE_SYSTEM: f64 = 1e-10;

/// The common rotation axis of a set of motions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CommonAxis {
    /// k_A: the axis in X's parent frame (the gripper eye-in-hand, the robot base eye-to-hand).
    pub hand: Vector3<f64>,
    /// k_B: the axis in the camera frame, oriented so that R_X k_B = k_A.
    pub eye: Vector3<f64>,
    /// The largest angle between a rotating motion's axis and k_A, radians.
    pub spread: f64,
    /// Motions that rotate at least `LOW_DOF_MIN_ANGLE_DEG`.
    pub rotating: usize,
}

impl CommonAxis {
    /// Whether every rotating motion rotates about this one axis (within `LOW_DOF_SPREAD_DEG`).
    pub fn is_low_dof(&self) -> bool {
        self.rotating >= 2 && self.spread.to_degrees() <= LOW_DOF_SPREAD_DEG
    }

    /// The axis in X's parent frame pointing along its largest coordinate's positive direction
    /// (up, for a SCARA), as reports give it.
    pub(crate) fn upward(&self) -> [f64; 3] {
        let k = self.hand * self.hand[self.hand.iamax()].signum();
        k.map(|v| if v == 0.0 { 0.0 } else { v }).into()
    }

    /// The coordinate component of X's translation along the free direction, when the free
    /// direction is within `PRIOR_AXIS_DEG` of a coordinate axis of X's parent frame.
    pub fn free_component(&self) -> Option<Component> {
        let i = self.hand.iamax();
        (self.hand[i].abs() >= PRIOR_AXIS_DEG.to_radians().cos())
            .then(|| Component::of_index(i))
            .flatten()
    }
}

/// The dominant rotation axis of the motions' A (and the matching one of their B), with the
/// spread of the A axes about it; `None` with fewer than two motions rotating at least
/// `LOW_DOF_MIN_ANGLE_DEG`.
pub fn common_axis(motions: &(impl MotionSource + ?Sized)) -> Option<CommonAxis> {
    let min = LOW_DOF_MIN_ANGLE_DEG.to_radians();
    let mut scatter = nalgebra::Matrix3::zeros();
    let mut rotating = 0;
    motions.for_each_motion(|m| {
        let f = MotionFeatures::of(&m.a);
        if let (Some(k), true) = (f.axis, f.angle >= min) {
            scatter += k * k.transpose() * (f.angle * f.angle);
            rotating += 1;
        }
    });
    if rotating < 2 {
        return None;
    }
    let eigen = scatter.symmetric_eigen();
    let hand: Vector3<f64> = eigen
        .eigenvectors
        .column(eigen.eigenvalues.imax())
        .into_owned();
    // k_B with each motion's sign matched to its A axis's side of k_A: R_X k_B,i = k_A,i.
    let mut eye = Vector3::zeros();
    let mut spread = 0.0_f64;
    motions.for_each_motion(|m| {
        let fa = MotionFeatures::of(&m.a);
        let fb = MotionFeatures::of(&m.b);
        if let (Some(ka), Some(kb), true) = (fa.axis, fb.axis, fa.angle >= min) {
            let side = ka.dot(&hand);
            spread = spread.max(side.abs().min(1.0).acos());
            eye += kb * (side.signum() * fa.angle * fa.angle);
        }
    });
    let eye = eye.try_normalize(f64::MIN_POSITIVE)?;
    Some(CommonAxis {
        hand,
        eye,
        spread,
        rotating,
    })
}

/// Whether the motions of every pair of `pairs` certainly do not rotate about one axis: whether
/// [`common_axis`] over them would find a spread above [`LOW_DOF_SPREAD_DEG`] (or no axis), told
/// in O(n) from 2n − 3 of the motions.
///
/// The spread is the largest angle between a rotating motion's axis (as a line) and the dominant
/// axis; two rotating motions whose axes are more than twice [`LOW_DOF_SPREAD_DEG`] apart cannot
/// both be within it of any axis (the angle between lines obeys the triangle inequality). The
/// witnesses are the motions from pose 0 to every pose and between consecutive poses, made and
/// judged exactly as [`common_axis`] makes and judges them (rotating at least
/// [`LOW_DOF_MIN_ANGLE_DEG`], both axes defined), each against the first rotating one. `false`
/// means only that these motions do not tell: [`common_axis`] then goes through all of them
/// (as on a low-DOF robot's recording, where every axis is alike).
pub(crate) fn axes_surely_apart(pairs: &AllPairs) -> bool {
    let n = pairs.poses();
    let min = LOW_DOF_MIN_ANGLE_DEG.to_radians();
    // Twice the spread, and a margin far above the rounding of the angles (1e-15 rad at 4°).
    let apart = 2.0 * LOW_DOF_SPREAD_DEG.to_radians() + 1e-9;
    let witnesses = (1..n).map(|j| (0, j)).chain((2..n).map(|j| (j - 1, j)));
    count_pairs(2 * n.saturating_sub(1));
    let mut first: Option<Vector3<f64>> = None;
    for (i, j) in witnesses {
        let m = pairs.motion(i, j);
        let fa = MotionFeatures::of(&m.a);
        let (Some(k), true) = (fa.axis, fa.angle >= min) else {
            continue;
        };
        if MotionFeatures::of(&m.b).axis.is_none() {
            continue;
        }
        match first {
            None => first = Some(k),
            Some(f) if f.dot(&k).abs().min(1.0).acos() > apart => return true,
            Some(_) => {}
        }
    }
    false
}

/// A low-DOF solution: X and the conditioning of its translation system.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LowDofSolution {
    /// X, its component along the axis from the prior.
    pub x: Transform,
    /// Smallest over largest eigenvalue of the scaled normal equations of (t_X⊥, cos θ, sin θ)
    /// (1 is ideal).
    pub conditioning: f64,
}

/// Solves X from motions that all rotate about `axis` (see the module docs), with X's translation
/// component `along.0` (which must be the [`CommonAxis::free_component`]) equal to `along.1`.
///
/// Errors: [`Degeneracy::IllConditioned`] when the motions do not fix θ and t_X⊥ (no translation
/// across the axis, or no rotation).
///
/// # Example
/// ```
/// use handeye::solve::low_dof::{common_axis, solve_low_dof};
/// use handeye::{Component, MotionPair, Transform};
/// use nalgebra::{Rotation3, Translation3, Vector3};
/// let x = Transform::from_parts(
///     Translation3::new(0.03, -0.02, 0.12),
///     Rotation3::from_euler_angles(0.2, -0.1, 0.7),
/// );
/// // SCARA motions: a turn about z and a move in x, y, z.
/// let a = |yaw: f64, t: [f64; 3]| Transform::new(Vector3::new(t[0], t[1], t[2]), Vector3::z() * yaw);
/// let motions: Vec<MotionPair> = [a(0.5, [0.1, 0.0, 0.02]), a(-0.8, [0.0, 0.2, 0.0]), a(0.3, [0.1, 0.1, -0.05])]
///     .iter()
///     .map(|a| MotionPair { a: *a, b: x.inverse() * a * x })
///     .collect();
/// let axis = common_axis(&motions).unwrap();
/// assert!(axis.is_low_dof());
/// let solved = solve_low_dof(&motions, &axis, (Component::Tz, 0.12))?;
/// assert!((solved.x.to_homogeneous() - x.to_homogeneous()).norm() < 1e-9);
/// # Ok::<(), handeye::Error>(())
/// ```
pub fn solve_low_dof(
    motions: &(impl MotionSource + ?Sized),
    axis: &CommonAxis,
    along: (Component, f64),
) -> Result<LowDofSolution> {
    let k = axis.hand;
    let r0 = align(&axis.eye, &k);
    let (e1, e2) = across(&k);
    // One motion's two rows (e1, e2) of: P (R_A − I) t⊥ − c P u − s P (k × u) = −P t_A.
    let rows = |m: &MotionPair| {
        let ra = *m.a.rotation.matrix();
        let u = r0 * m.b.translation.vector;
        let ku = k.cross(&u);
        let ta = m.a.translation.vector;
        [e1, e2].map(|e| {
            let ra_minus_i = ra.transpose() * e - e; // (R_A − I)ᵀ e
            (
                Vector4::new(
                    ra_minus_i.dot(&e1),
                    ra_minus_i.dot(&e2),
                    -e.dot(&u),
                    -e.dot(&ku),
                ),
                -e.dot(&ta),
            )
        })
    };
    let mut normal = Matrix4::zeros();
    let mut rhs = Vector4::zeros();
    motions.for_each_motion(|m| {
        for (row, b) in rows(m) {
            normal += row * row.transpose();
            rhs += row * b;
        }
    });
    let conditioning = scaled_conditioning(&normal);
    let ill = || Error::Degenerate {
        reason: Degeneracy::IllConditioned,
        conditioning,
    };
    if conditioning.is_nan() || conditioning < REFUSE_SYSTEM {
        return Err(ill());
    }
    let first = normal.cholesky().ok_or_else(ill)?.solve(&rhs);
    let cs = Vector2::new(first[2], first[3])
        .try_normalize(f64::MIN_POSITIVE)
        .ok_or_else(ill)?;
    // t⊥ again with θ on the circle: the 2×2 block, its right side less the θ columns.
    let mut normal_t = Matrix2::zeros();
    let mut rhs_t = Vector2::zeros();
    motions.for_each_motion(|m| {
        for (row, b) in rows(m) {
            let r = Vector2::new(row[0], row[1]);
            normal_t += r * r.transpose();
            rhs_t += r * (b - row[2] * cs[0] - row[3] * cs[1]);
        }
    });
    let p = normal_t.cholesky().ok_or_else(ill)?.solve(&rhs_t);
    let rotation = Rotation3::from_axis_angle(&Unit::new_unchecked(k), cs[1].atan2(cs[0])) * r0;
    let across_axis = e1 * p[0] + e2 * p[1];
    let t = with_component(&across_axis, &k, along);
    Ok(LowDofSolution {
        x: transform_from_parts(rotation.matrix(), &t),
        conditioning,
    })
}

/// `t` moved along `k` until its component `along.0` is `along.1`: t + λ k with
/// λ = (v − t_i) / k_i.
pub fn with_component(t: &Vector3<f64>, k: &Vector3<f64>, along: (Component, f64)) -> Vector3<f64> {
    let i = along.0.index();
    let mut moved = t + k * ((along.1 - t[i]) / k[i]);
    // Exactly the prior's value (the product above may round it by an ulp).
    moved[i] = along.1;
    moved
}

/// The smallest rotation taking `from` to `to` (both unit); a half turn about a perpendicular
/// axis when they are opposite.
pub(crate) fn align(from: &Vector3<f64>, to: &Vector3<f64>) -> Rotation3<f64> {
    Rotation3::rotation_between(from, to).unwrap_or_else(|| {
        let (perpendicular, _) = across(from);
        Rotation3::from_axis_angle(&Unit::new_normalize(perpendicular), std::f64::consts::PI)
    })
}

/// Two unit vectors that complete `k` to a right-handed orthonormal basis.
pub(crate) fn across(k: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let helper = if k.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let e1 = k.cross(&helper).normalize();
    (e1, k.cross(&e1))
}

/// Smallest over largest eigenvalue of D N D, D = diag(N_ii^−½) (the conditioning whatever the
/// length unit).
pub(crate) fn scaled_conditioning(normal: &Matrix4<f64>) -> f64 {
    let d = normal
        .diagonal()
        .map(|v| if v > 0.0 { 1.0 / v.sqrt() } else { 0.0 });
    let scaled = Matrix4::from_fn(|i, j| normal[(i, j)] * d[i] * d[j]);
    let eigen = scaled.symmetric_eigen().eigenvalues;
    let max = eigen.max();
    if max <= 0.0 {
        return 0.0;
    }
    eigen.min().max(0.0) / max
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::motion::{PosePair, Setup};
    use rand::{RngExt, SeedableRng};
    use rand_xoshiro::Xoshiro256PlusPlus;

    /// Noise-free poses of a robot turning about the z axis tilted by up to `wobble` radians
    /// (another tilt at each pose), X and the fixed frame given.
    fn wobbling(n: usize, wobble: f64, seed: u64) -> Vec<PosePair> {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let x = Transform::new(Vector3::new(0.03, -0.02, 0.1), Vector3::new(0.2, -0.1, 0.7));
        let y = Transform::new(Vector3::new(0.4, -0.2, 0.1), Vector3::new(0.3, 2.0, -0.4));
        (0..n)
            .map(|_| {
                let mut r = || rng.random_range(-1.0..1.0);
                let axis = Vector3::new(wobble * r(), wobble * r(), 1.0).normalize();
                let q = Transform::new(
                    Vector3::new(0.3 * r(), 0.3 * r(), 0.05 * r()),
                    axis * 3.0 * r(),
                );
                PosePair {
                    base_from_gripper: q,
                    camera_from_target: x.inverse() * q.inverse() * y,
                }
            })
            .collect()
    }

    #[test]
    fn axes_told_apart_by_the_witnesses_are_never_one_axis() {
        let (mut apart, mut undecided) = (0, 0);
        for seed in 0..6 {
            for wobble in [0.0, 0.005, 0.01, 0.02, 0.03, 0.05, 0.2] {
                let poses = wobbling(40, wobble, seed);
                let pairs = AllPairs::new(&poses, Setup::EyeInHand);
                let low_dof = common_axis(&pairs).is_some_and(|a| a.is_low_dof());
                if axes_surely_apart(&pairs) {
                    assert!(!low_dof, "seed {seed}, wobble {wobble}");
                    apart += 1;
                } else {
                    undecided += 1;
                }
                if wobble == 0.0 {
                    assert!(low_dof && !axes_surely_apart(&pairs));
                }
                if wobble == 0.2 {
                    assert!(axes_surely_apart(&pairs), "seed {seed}");
                }
            }
        }
        // Near the limit (a tilt of 1–2°) some are told apart and some left to every pair.
        assert!(apart >= 12 && undecided >= 6, "{apart} {undecided}");
    }
}
