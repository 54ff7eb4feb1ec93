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

/// The data's length unit: the power of two nearest the RMS of the gripper and camera translation
/// lengths over all motions, or 1 when every translation is 0 (or the RMS is not finite).
///
/// A power of two, so that dividing by it is exact: scaling every length of the input by 2^k
/// scales X's translation by 2^k and changes nothing else, bit for bit; any other factor changes
/// the result only by the rounding of the input.
///
/// Over all pairs of a pose sequence the sum of squares comes from the per-pose sums
/// ([`crate::solve::accumulate::PairSums`]) in O(n); it equals the motion-by-motion sum up to rounding,
/// and the power of two then differs only for an RMS within rounding of a half-way point.
pub(crate) fn length_scale(motions: &(impl MotionSource + ?Sized)) -> f64 {
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
    if !(rms.is_finite() && rms > 0.0) {
        return 1.0;
    }
    // log2 of a finite positive f64 lies in [−1075, 1024]; 2^k is exact for such integer k.
    let k = rms.log2().round().clamp(-1000.0, 1000.0) as i32;
    2.0_f64.powi(k)
}

/// Within this factor of the input's unit (2^5 = 32 either way), [`weighting_unit`] is the
/// input's unit itself. At 2^10 the rows' imbalance cost Daniilidis up to 1.5e-9 of X on exact
/// data (a case found by `tests/solver_180.rs` at scale 1.1e3); at 2^5 it is 32× less.
const OPENCV_RANGE: f64 = 32.0;

/// The unit for least-squares systems whose rows weigh rotation equations (order 1) against
/// translation equations (order the data's lengths): Eq. (10) of `andreff-joint` and Eq. (31) of
/// `daniilidis`.
///
/// On noisy data the answer of such a system depends on the unit (the unit is the relative weight
/// of the two kinds of rows), and OpenCV solves it in the input's unit; its fixtures fix that
/// answer. So while the data's scale ([`length_scale`]) is within 2^5 of the input's unit this is
/// 1, the input's unit, and OpenCV's answer is kept; beyond, the data is weighted as if its scale
/// were 2^±5 (the unit is [`length_scale`] / 2^5, or × 2^5 for small data), where the normal
/// equations are still accurate: in kilometres or micrometres OpenCV's weighting leaves one block
/// of rows ~1e-8 of the other, and its normal equations lose the smaller block entirely. The unit
/// is continuous in the data's scale and a power of two, and noise-free data gives X at any scale.
pub(crate) fn weighting_unit(motions: &(impl MotionSource + ?Sized)) -> f64 {
    weighting_from_scale(length_scale(motions))
}

/// [`weighting_unit`] for a data scale computed elsewhere (the robot-world solvers' poses).
pub(crate) fn weighting_from_scale(scale: f64) -> f64 {
    if scale > OPENCV_RANGE {
        scale / OPENCV_RANGE
    } else if scale < 1.0 / OPENCV_RANGE {
        scale * OPENCV_RANGE
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
    /// The motions in units of `unit` (a power of two, see [`length_scale`]).
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
    fn the_scale_is_the_nearest_power_of_two_of_the_rms_translation() {
        let m = |t: f64| MotionPair {
            a: Transform::new(Vector3::new(t, 0.0, 0.0), Vector3::zeros()),
            b: Transform::new(Vector3::new(0.0, t, 0.0), Vector3::zeros()),
        };
        assert_eq!(length_scale(&[m(3.0)]), 4.0);
        assert_eq!(length_scale(&[m(1e-8)]), 2.0_f64.powi(-27));
        assert_eq!(length_scale(&[m(1e8)]), 2.0_f64.powi(27));
        assert_eq!(length_scale(&[m(0.0)]), 1.0);
        assert_eq!(length_scale(&[m(f64::NAN)]), 1.0);
        assert_eq!(length_scale(&Vec::<MotionPair>::new()), 1.0);
        assert_eq!(weighting_unit(&[m(3.0)]), 1.0);
        assert_eq!(weighting_unit(&[m(30.0)]), 1.0);
        assert_eq!(weighting_unit(&[m(1000.0)]), 32.0);
        assert_eq!(weighting_unit(&[m(1e-8)]), 2.0_f64.powi(-22));
        assert_eq!(weighting_unit(&[m(1e8)]), 2.0_f64.powi(22));
    }
}
