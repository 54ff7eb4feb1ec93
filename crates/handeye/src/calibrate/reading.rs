//! The pipeline's first steps on pose pairs: the reading of the input (the readings a user may
//! have meant, tried), and the outliers (the poses that break the screw invariants of their
//! motions), with the refusals they explain.

use crate::calibrate::options::{Fix, Options};
use crate::calibrate::report::hand_eye::Outliers;
use crate::check::outliers::{PoseOutliers, pose_outliers};
use crate::check::readings::{ReadingCheck, check_readings};
use crate::model::error::{Error, Result};
use crate::model::findings::{OutlierPose, Reading, Written};
use crate::model::motion::{PosePair, Setup};
use crate::model::warning::{SHOWN, Warning};

/// The poses as they are to be read, with the reading chosen, its check and the outliers of the
/// poses so read. The readings are judged on the poses that agree with the others, so that
/// outliers do not make a mirror-image reading look better.
/// `fix` is what to do about a better reading, and the directions the input wrote its poses in.
pub(crate) fn read_poses(
    poses: &[PosePair],
    setup: Setup,
    (fix, written): (Fix, Written),
    outlier_deg: f64,
    warnings: &mut Vec<Warning>,
) -> Result<(Reading, Option<ReadingCheck>, Vec<PosePair>, PoseOutliers)> {
    let as_given = pose_outliers(poses, setup, outlier_deg);
    let (applied, check) =
        choose_reading(&without(poses, &as_given), setup, (fix, written), warnings)?;
    let read = applied.apply(poses, written);
    let found = match applied {
        Reading::AsGiven => as_given,
        _ => pose_outliers(&read, setup, outlier_deg),
    };
    Ok((applied, check, read, found))
}

/// The reading to solve under, and the check behind it.
pub(crate) fn choose_reading(
    poses: &[PosePair],
    setup: Setup,
    (fix, written): (Fix, Written),
    warnings: &mut Vec<Warning>,
) -> Result<(Reading, Option<ReadingCheck>)> {
    if let Fix::Read(r) = fix
        && r != Reading::AsGiven
    {
        if !r.applies_to(written) {
            return Err(Error::InvalidParameter {
                name: "fix",
                message: format!(
                    "`{}` undoes a quaternion order on the poses as the input wrote them, and this input writes them in both directions (some `_from_` names one way, some the other): write every record in one direction",
                    r.name()
                ),
            });
        }
        return Ok((r, None));
    }
    let check = check_readings(poses, setup, written);
    let (Some(finding), Some(better)) = (check.finding(setup), check.better) else {
        return both_inverted(check, setup, fix, warnings);
    };
    match fix {
        Fix::Auto if check.unambiguous() => {
            warnings.push(Warning::ReadAs {
                reading: better.reading,
                finding,
            });
            Ok((better.reading, Some(check)))
        }
        Fix::Read(_) => {
            warnings.push(Warning::KeptAsGiven {
                better: better.reading,
                finding,
            });
            Ok((Reading::AsGiven, Some(check)))
        }
        _ => Err(Error::Misread {
            finding,
            fit: check.fit_words().unwrap_or_default(),
            readings: check.fitting_better(),
            setup,
            other_setup: check.other_setup(setup),
            frames: check.frames,
        }),
    }
}

/// The reading to solve under when no reading fits better: as given, unless both inputs look
/// inverted ([`ReadingCheck::both_inverted`]), which is refused (`--fix as-given` keeps the
/// input, with the warning on the sizes) or, under `--fix auto`, read so.
fn both_inverted(
    check: ReadingCheck,
    setup: Setup,
    fix: Fix,
    warnings: &mut Vec<Warning>,
) -> Result<(Reading, Option<ReadingCheck>)> {
    if let Some(refusal) = check.both_inverted_misread(setup) {
        match (fix, refusal) {
            (Fix::Read(_), _) => {}
            (Fix::Auto, Error::Misread { finding, .. }) if !check.frames => {
                warnings.push(Warning::ReadAs {
                    reading: Reading::BothInverted,
                    finding,
                });
                return Ok((Reading::BothInverted, Some(check)));
            }
            (_, refusal) => return Err(refusal),
        }
    }
    warnings.extend(check.size_warning(setup));
    warnings.extend(check.alike_warning(setup));
    Ok((Reading::AsGiven, Some(check)))
}

/// The poses without the outliers.
pub(crate) fn without(poses: &[PosePair], found: &PoseOutliers) -> Vec<PosePair> {
    let bad = found.indices();
    poses
        .iter()
        .enumerate()
        .filter(|(i, _)| bad.binary_search(i).is_err())
        .map(|(_, p)| *p)
        .collect()
}

/// A refusal with what in the input explains it (outliers kept, a better reading kept as given),
/// when anything does.
pub(crate) fn explained(
    refusal: Error,
    warnings: &[Warning],
    kept_outliers: Option<&Warning>,
) -> Error {
    let why: Vec<Warning> = warnings.iter().chain(kept_outliers).cloned().collect();
    if why.is_empty() {
        return refusal;
    }
    Error::Untrusted {
        refusal: Some(Box::new(refusal)),
        why,
    }
}

pub(crate) fn outlier_report(found: &PoseOutliers, options: &Options) -> Outliers {
    Outliers {
        poses: found
            .poses
            .iter()
            .map(|g| OutlierPose {
                pose: g.pose,
                name: options
                    .pose_names
                    .get(g.pose)
                    .cloned()
                    .unwrap_or_else(|| format!("pose {}", g.pose)),
                angle_gap_deg: g.angle_gap_deg,
                pitch_gap: g.pitch_gap,
                rms_px: None,
            })
            .collect(),
        rejected: options.reject_outliers,
        angle_threshold_deg: found.angle_threshold_deg,
        pitch_threshold: found.pitch_threshold,
    }
}

pub(crate) fn outlier_warning(o: &Outliers) -> Warning {
    Warning::Outliers {
        count: o.poses.len(),
        shown: o.poses.iter().take(SHOWN).cloned().collect(),
    }
}
