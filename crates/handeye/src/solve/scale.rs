//! The data's own length scale, for the solvers whose arithmetic mixes lengths with pure numbers.
//!
//! Rotations are unit-free; translations are in whatever unit the input uses (SPEC sec. 1). A
//! linear system that stacks rotation rows (entries of order 1) with translation rows (entries of
//! order the data's lengths) has a condition number that grows with the length unit: in
//! kilometres or micrometres the normal equations lose every digit of the smaller block. Any
//! fixed tolerance on a length (a floor, a step size, "barely translates") is likewise right in
//! one unit only. The solvers that need it therefore solve in units of [`length_scale`] and scale
//! the translation of X back.

use crate::model::motion::MotionPair;
use crate::model::pose::transform_from_parts;
use crate::solve::motions::MotionSource;

/// The data's length unit: the RMS of the gripper and camera translation lengths over all motions
/// ([`rms_length`]), or 1 when every translation is 0 (or the RMS is not finite).
///
/// The data's own, not a power of two near it: the solvers that work in it (their weighting of
/// rows, their tolerances) then give the same X, its translation scaled, whatever the input's
/// unit (metres and millimetres are 1000 apart, not a power of two), up to the rounding of the
/// division.
pub(crate) fn length_scale(motions: &(impl MotionSource + ?Sized)) -> f64 {
    rms_length(motions).unwrap_or(1.0)
}

/// The RMS of the gripper and camera translation lengths over all motions; `None` when every
/// translation is 0 or the RMS is not finite.
///
/// Over all pairs of a pose sequence the sum of squares comes from the per-pose sums
/// ([`crate::solve::accumulate::PairSums`]) in O(n); it equals the motion-by-motion sum up to
/// rounding.
pub(crate) fn rms_length(motions: &(impl MotionSource + ?Sized)) -> Option<f64> {
    let sum = match motions.all_pairs() {
        Some(pairs) => pairs.sums().length_squares,
        None => {
            let mut sum = 0.0;
            motions.for_each_motion(|m| {
                sum +=
                    m.a.translation.vector.norm_squared() + m.b.translation.vector.norm_squared();
            });
            sum
        }
    };
    let rms = (sum / (2 * motions.count().max(1)) as f64).sqrt();
    (rms.is_finite() && rms > 0.0).then_some(rms)
}

/// The unit for least-squares systems whose rows weigh rotation equations (order 1) against
/// translation equations (order the data's lengths): Eq. (10) of `andreff-joint` and Eq. (31) of
/// `daniilidis`, and Li's robot-world system.
///
/// On noisy data the answer of such a system depends on the unit, which is the relative weight of
/// the two kinds of rows. Solved in the input's unit (as OpenCV solves it), the answer depends on
/// whether the input is in metres or millimetres: in millimetres the translation rows outweigh
/// the rotation rows a million times, and on a real recording Daniilidis' X came out 26° and
/// 2.2 m from its answer in metres. So the system is solved in units of the data's own length:
/// the RMS translation of the camera motions B ([`camera_rms_length`]; of all the motions when
/// the camera never translates, 1 when nothing does). Both kinds of rows are then of order 1
/// whatever the input's unit, the normal equations keep their digits in kilometres or
/// micrometres, and the same data in metres and in millimetres give the same X, its translation
/// ×1000, up to rounding. The camera's motions and not the gripper's: a change of the robot's base
/// frame (eye-to-hand) or gripper frame (eye-in-hand) changes the gripper's translations but not
/// the camera's, and X then follows the change exactly (`tests/contract.rs`). OpenCV's answer is
/// kept where that length is 1 in the input's unit (exactly, and on noise-free data at any scale).
pub(crate) fn weighting_unit(motions: &(impl MotionSource + ?Sized)) -> f64 {
    camera_rms_length(motions).unwrap_or_else(|| length_scale(motions))
}

/// The RMS translation length of the camera motions B; `None` when every one is 0 or the RMS is
/// not finite. Over all pairs of a pose sequence, from the per-pose sums in O(n).
pub(crate) fn camera_rms_length(motions: &(impl MotionSource + ?Sized)) -> Option<f64> {
    let sum = match motions.all_pairs() {
        Some(pairs) => pairs.sums().camera_length_squares,
        None => {
            let mut sum = 0.0;
            motions.for_each_motion(|m| sum += m.b.translation.vector.norm_squared());
            sum
        }
    };
    let rms = (sum / motions.count().max(1) as f64).sqrt();
    (rms.is_finite() && rms > 0.0).then_some(rms)
}

/// [`weighting_unit`] for a data scale computed elsewhere (the robot-world solvers' poses: their
/// RMS translation length): the scale itself, or 1 for none.
pub(crate) fn weighting_from_scale(scale: f64) -> f64 {
    if scale.is_finite() && scale > 0.0 {
        scale
    } else {
        1.0
    }
}

/// Motions with every translation divided by a length unit.
pub(crate) struct Scaled<'a, M: MotionSource + ?Sized> {
    motions: &'a M,
    inverse_unit: f64,
}

impl<'a, M: MotionSource + ?Sized> Scaled<'a, M> {
    /// The motions in units of `unit` (the data's own, see [`length_scale`]).
    pub(crate) fn new(motions: &'a M, unit: f64) -> Self {
        Self {
            motions,
            inverse_unit: 1.0 / unit,
        }
    }
}

impl<M: MotionSource + ?Sized> MotionSource for Scaled<'_, M> {
    fn count(&self) -> usize {
        self.motions.count()
    }

    fn for_each_motion(&self, mut f: impl FnMut(&MotionPair)) {
        let s = self.inverse_unit;
        self.motions.for_each_motion(|m| {
            let scaled = |t: &crate::model::pose::Transform| {
                transform_from_parts(t.rotation.matrix(), &(t.translation.vector * s))
            };
            f(&MotionPair {
                a: scaled(&m.a),
                b: scaled(&m.b),
            });
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::pose::Transform;
    use nalgebra::Vector3;

    #[test]
    fn the_scale_is_the_rms_translation() {
        let m = |t: f64| MotionPair {
            a: Transform::new(Vector3::new(t, 0.0, 0.0), Vector3::zeros()),
            b: Transform::new(Vector3::new(0.0, t, 0.0), Vector3::zeros()),
        };
        assert_eq!(length_scale(&[m(3.0)]), 3.0);
        assert_eq!(length_scale(&[m(1e-8)]), 1e-8);
        assert_eq!(length_scale(&[m(1e8)]), 1e8);
        assert_eq!(length_scale(&[m(0.0)]), 1.0);
        assert_eq!(length_scale(&[m(f64::NAN)]), 1.0);
        assert_eq!(length_scale(&Vec::<MotionPair>::new()), 1.0);
        assert_eq!(weighting_unit(&[m(3.0)]), 3.0);
        assert_eq!(weighting_unit(&[m(1000.0)]), 1000.0);
        assert_eq!(weighting_unit(&[m(1e-8)]), 1e-8);
        let still_camera = MotionPair {
            a: Transform::new(Vector3::new(2.0, 0.0, 0.0), Vector3::zeros()),
            b: Transform::identity(),
        };
        assert_eq!(weighting_unit(&[still_camera]), 2.0_f64.sqrt());
        assert_eq!(weighting_unit(&[m(0.0)]), 1.0);
        assert_eq!(weighting_unit(&[m(f64::NAN)]), 1.0);
    }
}
