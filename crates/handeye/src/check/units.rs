//! The poses' length unit told by their size, and the priors (`--prior tz=…`) in it: a prior that
//! names its unit is converted, one that names none is refused when its size says it is in
//! another unit than the poses.

use crate::check::outliers::{median, working_distance};
use crate::model::error::{Error, Result};
use crate::model::motion::PosePair;
use crate::model::prior::{LengthUnit, Prior};

/// A prior larger than this many times the poses' size (the larger of the median robot and camera
/// translation) is in another length unit: a millimetre prior on a recording in metres is 1000
/// times too large, and its value then leaks through the axes' spread into X's other components
/// (on `testdata/low_dof`, a refusal that blamed the motions).
pub const PRIOR_SIZE_RATIO: f64 = 20.0;

/// A prior other than 0 and without a unit, smaller than the poses' size over this, is refused
/// as in another length unit too: a metre prior on a recording in millimetres is 1000 times too
/// small (`tz=0.1075` read as 0.1 mm gave "verdict good", X's height 107 mm off), and nothing in
/// the data tells, since the motions leave that component free. 300, not 1000: a fixed camera's
/// height in metres is about 1/1000 of the scene in millimetres (0.63 against 620 on
/// `testdata/low_dof`'s eye-to-hand recording). A value that small in the poses' unit is given
/// with its unit (`tz=1.5mm`), which is then taken as said.
pub const PRIOR_SMALL_RATIO: f64 = 300.0;

/// The priors in the poses' length unit: one that names its unit (`tz=0.12m`) converted to the
/// unit the poses' sizes tell (metres when their size is 0.05–10, millimetres when 50–10,000);
/// one that names none refused when its size says it is in another unit ([`PRIOR_SIZE_RATIO`],
/// [`PRIOR_SMALL_RATIO`]).
pub(crate) fn in_poses_unit(priors: &[Prior], poses: &[PosePair]) -> Result<Vec<Prior>> {
    let robot = median(
        poses
            .iter()
            .map(|p| p.base_from_gripper.translation.vector.norm())
            .collect(),
    );
    let camera = working_distance(poses);
    if robot.max(camera) > MIXED_UNITS_RATIO * robot.min(camera) {
        // The robot and the camera in two units: the poses' unit is not one, and the calibration
        // names the mix-up and its `--fix` (a prior judged against the larger would be refused as
        // in the wrong unit first, sending the user to the wrong fix).
        return Ok(priors.to_vec());
    }
    let size = robot.max(camera);
    let unit = length_unit(poses);
    priors.iter().map(|p| in_unit(p, size, unit)).collect()
}

/// The robot's and the camera's translations (medians) further apart than this are in two length
/// units (metres against millimetres is about 1000); a fixed camera two metres away from a robot
/// whose flange is half a metre from its base is 4.
const MIXED_UNITS_RATIO: f64 = 50.0;

/// The poses' length unit told by their size (the median over the poses of the larger of the
/// robot's and the camera's translation): metres when it is 0.05–10, millimetres when 50–10,000.
pub(crate) fn length_unit(poses: &[PosePair]) -> Option<LengthUnit> {
    let size = median(
        poses
            .iter()
            .map(|p| {
                p.base_from_gripper
                    .translation
                    .vector
                    .norm()
                    .max(p.camera_from_target.translation.vector.norm())
            })
            .collect(),
    );
    if (0.05..=10.0).contains(&size) {
        Some(LengthUnit::Metre)
    } else if (50.0..=10_000.0).contains(&size) {
        Some(LengthUnit::Millimetre)
    } else {
        None
    }
}

/// One prior in the unit of poses of size `size` and unit `poses_unit` (see [`in_poses_unit`]).
fn in_unit(prior: &Prior, size: f64, poses_unit: Option<LengthUnit>) -> Result<Prior> {
    let refuse = |message: String| {
        Err(Error::InvalidParameter {
            name: "prior",
            message,
        })
    };
    if let Some(unit) = prior.unit {
        let Some(poses_unit) = poses_unit else {
            return refuse(format!(
                "{prior} names its unit, but the poses' unit cannot be told from their size (median translation {size:.4}): give the prior without a unit, in the poses' unit"
            ));
        };
        let factor = unit.metres() / poses_unit.metres();
        let converted = Prior {
            value: prior.value * factor,
            sigma: prior.sigma * factor,
            unit: None,
            ..*prior
        };
        // Converted, it is judged as one given in the poses' unit: by the same bounds.
        if converted.value.abs() > PRIOR_SIZE_RATIO * size {
            return refuse(format!(
                "{prior} is {:.0} times the size of the poses' translations (median {size:.4} {}): not a length of this recording",
                converted.value.abs() / size.max(f64::MIN_POSITIVE),
                poses_unit.suffix()
            ));
        }
        return loose(&converted, prior, size).map_or(Ok(converted), refuse);
    }
    let value = prior.value.abs();
    let with_unit = |unit: &str| {
        format!(
            "{}={}{unit}{}",
            prior.component.name(),
            prior.value,
            if prior.sigma > 0.0 {
                format!("+-{}{unit}", prior.sigma)
            } else {
                String::new()
            }
        )
    };
    if value > PRIOR_SIZE_RATIO * size {
        return refuse(format!(
            "{prior} is {:.0} times the size of the poses' translations (median {size:.4}): it is in another length unit than the poses; give it in theirs, or with its unit ({})",
            value / size.max(f64::MIN_POSITIVE),
            with_unit("mm")
        ));
    }
    if value > 0.0 && value * PRIOR_SMALL_RATIO < size {
        return refuse(format!(
            "{prior} is 1/{:.0} of the size of the poses' translations (median {size:.4}): it is in another length unit than the poses (metres on poses in millimetres?), or the camera is that close to the flange along it; give it with its unit, {} if it is in metres or {} if in millimetres",
            size / value,
            with_unit("m"),
            with_unit("mm")
        ));
    }
    loose(prior, prior, size).map_or(Ok(*prior), refuse)
}

/// Why a prior (`converted` to the poses' unit, `given` as written) is too loose to mean anything:
/// a one-sigma larger than the poses' size (median translation `size`) determines no component of
/// X (the motions of a 0.5 m robot say more), and its uncertainty would be reported as if it did.
fn loose(converted: &Prior, given: &Prior, size: f64) -> Option<String> {
    (converted.sigma > size).then(|| {
        format!(
            "{given}: a sigma of {} is larger than the poses' translations themselves (median {size:.4}): such a prior determines nothing; measure the component to better than the size of the robot's motions, or give it exact",
            converted.sigma
        )
    })
}
