//! The readings of the input a user may have meant, tried against the data.
//!
//! The mistakes every hand–eye tool's users make are a pose given inverted under its name, the
//! quaternion written `w, x, y, z` into `x, y, z, w` fields, and millimetres on one side and metres
//! on the other. Each turns consistent data into data that no X fits. [`check_readings`] solves the
//! data as given and, when that fits poorly, under each other [`Reading`], measures how well each
//! fits (the median per-pose residual, [`crate::check::outliers::PoseResiduals`]), and names a reading
//! that fits far better.

use serde::{Deserialize, Serialize};

use crate::check::outliers::{PoseResiduals, gripper_rotations, median, translation_scale};
use crate::model::error::{Error, misread_advice};
use crate::model::findings::{Reading, Written};
use crate::model::motion::{PosePair, Setup};
use crate::model::pose::{exp_so3, transform_from_parts};
use crate::model::warning::Warning;
use crate::solve::REFUSE_ANGLE;
use crate::solve::accumulate::PoseAccumulator;

/// At most this many poses (spread evenly) are used to try each reading.
const SAMPLE: usize = 60;

/// A reading fits far better when one of its residuals is below this fraction of the as-given
/// one and the other is not worse than [`NOT_WORSE`] times it.
const FAR_BETTER: f64 = 0.2;
/// See [`FAR_BETTER`].
const NOT_WORSE: f64 = 1.5;
/// The millimetre readings are tried only when one side's translations are this many times the
/// other's (a factor of 1000 between them, give or take the scene's proportions).
const UNIT_RATIO: f64 = 30.0;
/// Below this axis scatter ([`crate::check::outliers::axis_scatter`]) the motions do not determine X
/// under any reading, so readings are not compared (the fit of a free direction says nothing about
/// the reading). The realistic suite measures ≤ 6.5e-6 for one joint or parallel axes, ≥ 1.8e-2
/// otherwise.
pub const DEGENERATE_SCATTER: f64 = 1e-4;
/// Below this turn of the gripper (degrees, the widest rotation from the first pose) the poses
/// are a robot standing still, whose residuals are the sensors' noise: the ratio of that noise to
/// the motion range says nothing about how the input is read, and no reading is judged. The
/// accumulating estimator reports nothing below it either ([`crate::track`]'s "no rotation
/// above 2° yet"). Issue 32: the ethz-asl simulation starts with about 100 poses of a still robot
/// (0.003°) and a jittering camera, which fit "far better" with the camera in millimetres.
pub const LEAST_TURN_DEG: f64 = 2.0;
/// The as-given reading is questioned only when its median rotation residual is above this
/// (degrees) …
const POOR_ROTATION_DEG: f64 = 0.5;
/// … or its median translation residual above this fraction of the scene's size.
const POOR_TRANSLATION: f64 = 0.02;

/// X and Y sizes must differ by this factor for [`ReadingFit::plausible`] to tell.
const SIZE_RATIO: f64 = 2.0;

/// A camera sees a target only in front of it, within its field of view: the widest angle
/// (degrees) between the optical axis (+z) and the direction of the target's origin that a camera
/// pose may put it at. Half the diagonal field of view of a 90° lens is 45°; the kinhec suite's
/// clean recordings put it at 33.5° at most (75 files, outliers left out), the peers' real ones at
/// 34.4°, camodocal's at 45.5°.
const IN_VIEW_DEG: f64 = 60.0;
/// The camera poses look inverted when, inverted, they put the target this many times nearer the
/// optical axis (median angle) than as given, and all of it in view ([`IN_VIEW_DEG`]).
const NEARER_AXIS: f64 = 2.0;

/// How well one reading fits.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ReadingFit {
    /// The reading.
    pub reading: Reading,
    /// Median per-pose rotation residual, degrees.
    pub rotation_deg: f64,
    /// Median per-pose translation residual over the scene's size (RMS spread of the hand
    /// positions), unit-free.
    pub translation_rel: f64,
    /// ‖t‖ of the X solved under this reading.
    pub x_translation: f64,
    /// ‖t‖ of the fixed frame Y (`base_from_target` eye-in-hand, `gripper_from_target`
    /// eye-to-hand) under this reading.
    pub y_translation: f64,
}

impl ReadingFit {
    /// Whether the fit is poor enough to question the reading ([`POOR_ROTATION_DEG`],
    /// [`POOR_TRANSLATION`]).
    pub(crate) fn poor(&self) -> bool {
        self.rotation_deg > POOR_ROTATION_DEG || self.translation_rel > POOR_TRANSLATION
    }

    /// Whether this fit is far better than `given` (see [`FAR_BETTER`]).
    pub(crate) fn far_better_than(&self, given: &ReadingFit) -> bool {
        let poor = given.poor();
        let much = self.rotation_deg < FAR_BETTER * given.rotation_deg
            || self.translation_rel < FAR_BETTER * given.translation_rel;
        let not_worse = self.rotation_deg <= NOT_WORSE * given.rotation_deg
            && self.translation_rel <= NOT_WORSE * given.translation_rel;
        poor && much && not_worse
    }

    /// Whether this fit is about as good as `given` in both residuals (within [`NOT_WORSE`]): the
    /// poses cannot tell the two readings apart.
    pub(crate) fn as_well_as(&self, given: &ReadingFit) -> bool {
        self.rotation_deg <= NOT_WORSE * given.rotation_deg
            && self.translation_rel <= NOT_WORSE * given.translation_rel
    }

    /// Whether X and Y have the sizes the setup makes likely: a camera on the gripper is nearer to
    /// the gripper than the target is to the base (eye-in-hand), a fixed camera farther from the
    /// base than the target is from the gripper (eye-to-hand). A reading and its mirror image
    /// (robot inverted / camera inverted, as given / both inverted) fit equally well with X and Y
    /// swapped (Q X P⁻¹ = Y is also Q⁻¹ Y P = X), so only this tells them apart.
    ///
    /// `Some(true)` when the sizes differ by at least twice (`SIZE_RATIO`) in the likely direction,
    /// `Some(false)` when in the other, `None` when they are too alike to tell.
    pub fn plausible(&self, setup: Setup) -> Option<bool> {
        let (near, far) = match setup {
            Setup::EyeInHand => (self.x_translation, self.y_translation),
            Setup::EyeToHand => (self.y_translation, self.x_translation),
        };
        if far >= SIZE_RATIO * near {
            Some(true)
        } else if near >= SIZE_RATIO * far {
            Some(false)
        } else {
            None
        }
    }

    /// Improvement score against `given` (smaller is better).
    pub(crate) fn score(&self, given: &ReadingFit) -> f64 {
        self.rotation_deg / given.rotation_deg.max(1e-300)
            + self.translation_rel / given.translation_rel.max(1e-300)
    }
}

/// What [`check_readings`] found.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReadingCheck {
    /// The fit of the poses as given (`None` when they cannot be solved at all, or when every
    /// rotation is about one axis and no reading could be judged).
    pub as_given: Option<ReadingFit>,
    /// A reading that fits far better than the as-given one, if any: the best, the plausible one
    /// first among equals ([`ReadingFit::plausible`]).
    pub better: Option<ReadingFit>,
    /// Other readings that fit about as well as `better` (its mirror image, typically).
    pub also: Vec<ReadingFit>,
    /// When the as-given reading fits (not `ReadingFit::poor`) and no reading fits far better:
    /// the other readings that fit about as well (`ReadingFit::as_well_as`), but for its mirror
    /// image (both poses inverted, which always fits as well: [`Self::size_warning`]) and the
    /// millimetre readings (judged by sizes). The motions are too small, or too alike, to tell
    /// whether the input is read right, and the X of each reading is a different one.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub alike: Vec<ReadingFit>,
    /// The poses were looked up between named frames ([`Written::frames`]): an inverted
    /// reading means frame names swapped.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub frames: bool,
    /// Where the camera poses put the target, as given and inverted, when the as-given sizes are
    /// implausible ([`Self::size_warning`]): what tells a recording with both inputs inverted
    /// ([`Self::both_inverted`]) from one whose rig just has unusual sizes.
    #[serde(skip)]
    pub view: Option<TargetInView>,
}

/// Where the camera poses put the target's origin: how far off the camera's optical axis (+z).
/// A camera sees the target in front of it, near its axis; a camera pose inverted (the camera in
/// the target's frame) puts it wherever the camera stood around the target.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TargetInView {
    /// The median angle between the optical axis and the target, degrees, the poses as given.
    pub as_given_deg: f64,
    /// The same, the camera poses inverted.
    pub inverted_deg: f64,
    /// The widest such angle, the camera poses inverted (above 90° when a target is behind).
    pub inverted_widest_deg: f64,
}

impl TargetInView {
    /// The angles of `poses` (`None` for no pose).
    pub fn of(poses: &[PosePair]) -> Option<Self> {
        let off_axis = |t: &nalgebra::Vector3<f64>| {
            let n = t.norm();
            if n > 0.0 {
                (t.z / n).clamp(-1.0, 1.0).acos().to_degrees()
            } else {
                180.0
            }
        };
        let given: Vec<f64> = poses
            .iter()
            .map(|p| off_axis(&p.camera_from_target.translation.vector))
            .collect();
        let inverted: Vec<f64> = poses
            .iter()
            .map(|p| off_axis(&p.camera_from_target.inverse().translation.vector))
            .collect();
        let widest = inverted.iter().copied().reduce(f64::max)?;
        Some(Self {
            as_given_deg: median(given),
            inverted_deg: median(inverted),
            inverted_widest_deg: widest,
        })
    }

    /// Whether the camera poses look inverted: inverted, they put every target in view
    /// (within `IN_VIEW_DEG`) and `NEARER_AXIS` times nearer the axis than as given.
    pub fn says_inverted(&self) -> bool {
        self.inverted_widest_deg <= IN_VIEW_DEG
            && NEARER_AXIS * self.inverted_deg <= self.as_given_deg
    }
}

impl ReadingCheck {
    /// The finding in words, when a reading fits far better: what fits, how well, and the other
    /// readings that fit as well (no face's spelling of the fix: see [`ReadingCheck::advice`]).
    pub fn finding(&self, setup: Setup) -> Option<String> {
        let better = self.better?;
        let meaning = |r: Reading| {
            if self.frames {
                r.meaning_in_frames(setup)
            } else {
                r.meaning(setup)
            }
        };
        let mut text = format!(
            "the poses fit far better read as {} ({})",
            meaning(better.reading),
            self.fit_words()?
        );
        for other in &self.also {
            text.push_str(&format!(
                "; it fits as well read as {}{}, which gives an X of {} size for the {} setup",
                meaning(other.reading),
                if self.frames && other.reading.inverts() {
                    String::new()
                } else {
                    format!(" (fix {})", other.reading.name())
                },
                match other.plausible(setup) {
                    Some(true) => "a plausible",
                    Some(false) => "an unlikely",
                    None => "a possible",
                },
                setup.name(),
            ));
        }
        Some(text)
    }

    /// How much better the better reading fits, in numbers: "median residual 0.17° and 0.4% of
    /// the motion range, against 29.45° and 15.0% as given".
    pub fn fit_words(&self) -> Option<String> {
        let (given, better) = (self.as_given?, self.better?);
        Some(format!(
            "median residual {:.2}° and {:.1}% of the motion range, against {:.2}° and {:.1}% as given",
            better.rotation_deg,
            100.0 * better.translation_rel,
            given.rotation_deg,
            100.0 * given.translation_rel,
        ))
    }

    /// The refusal of the input as given when a reading fits far better
    /// ([`crate::model::error::Error::Misread`]): the finding and the readings, typed.
    pub fn misread(&self, setup: Setup) -> Option<Error> {
        if self.better.is_none() {
            return self.both_inverted_misread(setup);
        }
        Some(Error::Misread {
            finding: self.finding(setup)?,
            fit: self.fit_words()?,
            readings: self.fitting_better(),
            setup,
            other_setup: self.other_setup(setup),
            frames: self.frames,
        })
    }

    /// Whether the poses may be a recording of the other setup: a reading that fits far better
    /// is the robot poses inverted (what the other setup reads), with X and Y of the sizes the
    /// other setup makes likely and this one does not.
    ///
    /// Its mirror, the camera poses inverted, then fits as well with plausible sizes for this
    /// setup, and no pose tells the two apart (a recording of the other setup, and one of this
    /// setup with its camera poses inverted, are the same numbers), but the user can: whether the
    /// camera is fixed or rides on the gripper.
    pub fn other_setup(&self, setup: Setup) -> bool {
        self.better
            .iter()
            .chain(&self.also)
            .any(|f| f.reading == Reading::RobotInverted && f.plausible(setup) == Some(false))
    }

    /// The finding with the fix in the words of both faces: the advice of [`Self::misread`].
    pub fn advice(&self, setup: Setup) -> Option<String> {
        Some(misread_advice(
            &self.finding(setup)?,
            &self.fit_words()?,
            &self.fitting_better(),
            &setup,
            &self.other_setup(setup),
            &self.frames,
        ))
    }

    /// The readings that fit far better than the as-given one: the better one, then the others
    /// that fit as well.
    pub fn fitting_better(&self) -> Vec<Reading> {
        self.better
            .iter()
            .chain(&self.also)
            .map(|f| f.reading)
            .collect()
    }

    /// Whether the better reading is the only one that fits (so `--fix auto` may apply it).
    pub fn unambiguous(&self) -> bool {
        self.better.is_some()
            && self.also.is_empty()
            && !(self.frames && self.better.is_some_and(|b| b.reading.inverts()))
    }

    /// Whether both inputs look inverted, decisively: X and the target have the sizes the setup
    /// makes unlikely ([`Self::size_warning`]), and the camera poses, inverted, put the target in
    /// view and near the optical axis where as given they do not ([`TargetInView::says_inverted`]).
    /// Both readings fit exactly as well (X and the target's pose swapped); only these tell.
    pub fn both_inverted(&self, setup: Setup) -> bool {
        self.size_warning(setup).is_some() && self.view.is_some_and(|v| v.says_inverted())
    }

    /// The refusal of a recording whose both inputs look inverted ([`Self::both_inverted`]).
    pub fn both_inverted_misread(&self, setup: Setup) -> Option<Error> {
        if !self.both_inverted(setup) {
            return None;
        }
        let (given, view) = (self.as_given?, self.view?);
        let (x_is, y_is) = setup.distances_in_words();
        let fit = format!(
            "the camera poses put the target {:.1}° off the camera's optical axis (median), against {:.1}° inverted",
            view.as_given_deg, view.inverted_deg
        );
        Some(Error::Misread {
            finding: format!(
                "both inputs look inverted (each gives the inverse of the transform it names): as given, X puts {x_is} at {:.3} and {y_is} at {:.3}, the reverse of what the {} setup has, and {fit}; both readings fit the poses exactly as well (X and the target's pose swapped)",
                given.x_translation,
                given.y_translation,
                setup.name(),
            ),
            fit,
            readings: vec![Reading::BothInverted],
            setup,
            other_setup: false,
            frames: self.frames,
        })
    }

    /// A warning when another reading fits about as well as the as-given one ([`Self::alike`]).
    pub fn alike_warning(&self, setup: Setup) -> Option<Warning> {
        let (given, best) = (self.as_given?, self.alike.first()?);
        Some(Warning::ReadingsAlike {
            readings: self.alike.iter().map(|f| f.reading).collect(),
            fit: [best.rotation_deg, best.translation_rel],
            given: [given.rotation_deg, given.translation_rel],
            frames: self.frames,
            setup,
        })
    }

    /// A warning when the as-given reading fits but gives X and Y implausible sizes for the setup:
    /// both poses inverted fit exactly as well, with X and Y swapped.
    pub fn size_warning(&self, setup: Setup) -> Option<Warning> {
        let given = self.as_given?;
        if self.better.is_some() || given.plausible(setup) != Some(false) {
            return None;
        }
        Some(Warning::SwappedSizes {
            x_translation: given.x_translation,
            y_translation: given.y_translation,
            setup,
        })
    }
}

/// Tries every [`Reading`] of `poses` and names one that fits far better than the as-given one.
///
/// Each reading is solved by Andreff over all pairs of at most 60 poses spread over the input, from
/// the accumulated normal equations ([`PoseAccumulator`], O(n)), and judged by its median per-pose
/// residuals; the millimetre readings are judged only by which side's translations are the larger
/// (they fit equally well up to the unit of X).
///
/// `written` is the directions in which the input wrote its poses (where a quaternion-order
/// reading undoes the mix-up, [`Reading::apply`]); a reading that cannot apply to them is not tried.
///
/// Every reading is tried, even when the as-given one fits well (not `ReadingFit::poor`) and no
/// other can be far better by the rule itself: one that fits about as well says the motions cannot
/// tell the readings apart ([`ReadingCheck::alike`]), and an X that fits the poses is then not
/// known to be the right one.
pub fn check_readings(poses: &[PosePair], setup: Setup, written: Written) -> ReadingCheck {
    let sample = spread(poses);
    let none = |as_given| ReadingCheck {
        as_given,
        better: None,
        also: Vec::new(),
        alike: Vec::new(),
        frames: written.frames,
        view: None,
    };
    let Some(given) = judged_fit(&sample, setup) else {
        return none(None);
    };
    let mm = mm_side(&sample, setup);
    let fits: Vec<ReadingFit> = Reading::ALL
        .iter()
        .filter(|&&r| r != Reading::AsGiven && r.applies_to(written))
        .filter_map(|&r| fit(&r.apply(&sample, written), setup, r))
        // A unit mix-up of 1000× leaves translation residuals of the size of the motions; a few
        // percent come from noise, or from motions that leave the translation free (a gripper
        // turning about one point fits any camera unit).
        .filter(|f| {
            !matches!(f.reading, Reading::RobotMm | Reading::CameraMm) || Some(f.reading) == mm
        })
        .collect();
    let mut candidates: Vec<ReadingFit> = fits
        .iter()
        .filter(|f| f.far_better_than(&given))
        .copied()
        .collect();
    if candidates.is_empty() {
        // Only a fit that passes for good is in question (a poor one is judged by its residuals);
        // a unit is judged by the sizes (a gripper turning about one point fits any camera unit).
        let alike = fits
            .into_iter()
            .filter(|f| !given.poor() && f.as_well_as(&given))
            .filter(|f| {
                !matches!(
                    f.reading,
                    Reading::BothInverted | Reading::RobotMm | Reading::CameraMm
                )
            })
            .collect();
        let mut alike: Vec<ReadingFit> = alike;
        alike.sort_by(|a, b| a.score(&given).total_cmp(&b.score(&given)));
        return ReadingCheck {
            alike,
            view: (given.plausible(setup) == Some(false))
                .then(|| TargetInView::of(&sample))
                .flatten(),
            ..none(Some(given))
        };
    }
    candidates.sort_by(|a, b| a.score(&given).total_cmp(&b.score(&given)));
    // Readings within 2× of the best score fit as well: the plausible one leads.
    let best = candidates.first().map_or(0.0, |f| f.score(&given));
    candidates.retain(|f| f.score(&given) <= 2.0 * best + 1e-12);
    candidates.sort_by_key(|f| match f.plausible(setup) {
        Some(true) => 0,
        None => 1,
        Some(false) => 2,
    });
    let mut candidates = candidates.into_iter();
    ReadingCheck {
        as_given: Some(given),
        better: candidates.next(),
        also: candidates.collect(),
        alike: Vec::new(),
        frames: written.frames,
        view: None,
    }
}

/// The fit of `poses` as given (at most [`SAMPLE`] of them, spread), when a reading can be judged
/// on them: `None` below [`DEGENERATE_SCATTER`] (the rotations leave X free) or below
/// [`LEAST_TURN_DEG`] (the gripper stood still: the residuals are noise, whatever the reading),
/// or when they cannot be solved.
pub(crate) fn judged_fit(poses: &[PosePair], setup: Setup) -> Option<ReadingFit> {
    let sample = spread(poses);
    let rotations = gripper_rotations(&sample, setup);
    if rotations.scatter < DEGENERATE_SCATTER
        || rotations.widest_from_first < LEAST_TURN_DEG.to_radians().max(REFUSE_ANGLE)
    {
        return None;
    }
    fit(&sample, setup, Reading::AsGiven)
}

/// The millimetre reading that makes sense, if any: the side whose translations are the larger,
/// when they are [`UNIT_RATIO`] times the other's.
fn mm_side(poses: &[PosePair], setup: Setup) -> Option<Reading> {
    let robot = translation_scale(poses, setup);
    let camera = median(
        poses
            .iter()
            .map(|p| p.camera_from_target.translation.vector.norm())
            .collect(),
    );
    if robot > UNIT_RATIO * camera {
        Some(Reading::RobotMm)
    } else if camera > UNIT_RATIO * robot {
        Some(Reading::CameraMm)
    } else {
        None
    }
}

/// At most [`SAMPLE`] poses spread evenly over the input.
fn spread(poses: &[PosePair]) -> Vec<PosePair> {
    if poses.len() <= SAMPLE {
        return poses.to_vec();
    }
    (0..SAMPLE)
        .map(|k| poses[k * (poses.len() - 1) / (SAMPLE - 1)])
        .collect()
}

/// The fit of one reading, `None` when it cannot be solved.
///
/// Every measure is the same for a reading and its mirror image (X and Y swapped, see
/// [`ReadingFit::plausible`]), so that only a real difference of fit can favour one: the rotation
/// residual is an angle; the translation residual is the smaller of the medians measured in the
/// target frame and in the camera frame (the mirror swaps the two), over the summed spreads of the
/// hand positions of Q and of Q⁻¹ (the mirror swaps those too).
fn fit(poses: &[PosePair], setup: Setup, reading: Reading) -> Option<ReadingFit> {
    let x = PoseAccumulator::of(poses, setup).estimate()?.x;
    let r = PoseResiduals::at(poses, setup, &x);
    let in_camera_frame = median(
        poses
            .iter()
            .zip(&r.residuals)
            .map(|(p, r)| {
                let d = transform_from_parts(&exp_so3(&r.rotation), &r.translation);
                let c = p.camera_from_target;
                (c * d.inverse() * c.inverse()).translation.vector.norm()
            })
            .collect(),
    );
    let other = match setup {
        Setup::EyeInHand => Setup::EyeToHand,
        Setup::EyeToHand => Setup::EyeInHand,
    };
    let scale =
        (translation_scale(poses, setup) + translation_scale(poses, other)).max(f64::MIN_POSITIVE);
    Some(ReadingFit {
        reading,
        rotation_deg: r.median_rotation_deg(),
        translation_rel: r.median_translation().min(in_camera_frame) / scale,
        x_translation: x.translation.vector.norm(),
        y_translation: r.y.translation.vector.norm(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Quaternion, UnitQuaternion};

    use crate::model::findings::{scaled, wxyz};
    use crate::model::pose::Transform;
    use crate::sim::{SimConfig, simulate};

    fn poses(seed: u64) -> Vec<PosePair> {
        simulate(&SimConfig::large_motions(), seed, 0).poses
    }

    #[test]
    fn wxyz_undoes_the_mistake() {
        let t = Transform::new(
            nalgebra::Vector3::zeros(),
            nalgebra::Vector3::new(0.3, -0.2, 0.5),
        );
        let q = UnitQuaternion::from_rotation_matrix(&t.rotation);
        // What a reader of x, y, z, w fields makes of w, x, y, z written into them.
        let misread = UnitQuaternion::from_quaternion(Quaternion::new(q.k, q.w, q.i, q.j));
        let read = Transform::from_parts(t.translation, misread.to_rotation_matrix());
        let diff = wxyz(&read).to_homogeneous() - t.to_homogeneous();
        assert!(diff.norm() < 1e-12, "{diff}");
    }

    #[test]
    fn correct_data_raises_nothing() {
        for seed in 0..5 {
            let c = check_readings(&poses(seed), Setup::EyeInHand, Written::NAMED);
            // (The simulation's target sits closer to the base than the camera to the gripper,
            // so the size warning is tested on the realistic suite, tests/trust.rs.)
            assert!(c.better.is_none(), "seed {seed}: {c:?}");
        }
    }

    #[test]
    fn each_mistake_is_named() {
        for seed in 0..3 {
            let good = poses(seed);
            for mistake in [
                Reading::RobotInverted,
                Reading::CameraInverted,
                Reading::BothInverted,
            ] {
                // Inverting is its own undoing. Robot and camera inverted mirror each other (the
                // same fit with X and Y swapped): the true one must lead, the mirror follow.
                let c = check_readings(
                    &mistake.apply(&good, Written::NAMED),
                    Setup::EyeInHand,
                    Written::NAMED,
                );
                if mistake == Reading::BothInverted {
                    // Fits exactly as given, with X and Y swapped: only sizes can tell.
                    assert!(c.better.is_none(), "seed {seed}: {c:?}");
                    continue;
                }
                // The simulation's X and Y have alike sizes, so either may lead.
                let named: Vec<Reading> =
                    c.better.iter().chain(&c.also).map(|f| f.reading).collect();
                assert!(named.contains(&mistake), "seed {seed}: {c:?}");
                assert!(!c.unambiguous(), "seed {seed}: {c:?}");
            }
            let mm: Vec<PosePair> = good
                .iter()
                .map(|p| PosePair {
                    base_from_gripper: scaled(&p.base_from_gripper, 1e3),
                    camera_from_target: p.camera_from_target,
                })
                .collect();
            let c = check_readings(&mm, Setup::EyeInHand, Written::NAMED);
            assert_eq!(c.better.map(|f| f.reading), Some(Reading::RobotMm), "{c:?}");
        }
    }
}
