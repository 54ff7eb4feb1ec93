//! The check of a named rotation convention (issue 33 item 11): an input read in the convention
//! named for it whose poses fit poorly is read again, the same numbers in each other convention
//! of as many numbers and the same unit, and refused when one of those fits far better. KUKA's
//! and Mitsubishi's `A, B, C`, FANUC's `W, P, R` and Stäubli's `Rx, Ry, Rz` are three angles each,
//! in degrees, in different orders: named wrongly they read as rotations that no X fits well, but
//! as rotations all the same.

use crate::check::readings::{ReadingFit, judged_fit};
use crate::io::recording::{Recording, RecordingOptions, Source, read_source};
use crate::io::sync::TimeOffset;
use crate::io::{Conventions, Format};
use crate::model::error::Error;
use crate::model::rotation::{RotationConvention, Rotations};

/// Which function of its numbers a convention is: conventions of one formula read the same
/// numbers alike (FANUC's `W, P, R`, Mitsubishi's `A, B, C`, Yaskawa's `Rx, Ry, Rz` and `rpy-deg`
/// are all `Rz(v₃)·Ry(v₂)·Rx(v₁)` in degrees).
fn formula(c: RotationConvention) -> RotationConvention {
    use RotationConvention::*;
    match c {
        MitsubishiAbc | YaskawaRxryrz | RpyDeg => FanucWpr,
        other => other,
    }
}

/// The conventions of `c`'s formula, `c` first.
fn same_formula(c: RotationConvention) -> Vec<RotationConvention> {
    std::iter::once(c)
        .chain(
            RotationConvention::ALL
                .into_iter()
                .filter(|&o| o != c && formula(o) == formula(c)),
        )
        .collect()
}

/// The conventions a side named `named` may have been meant as: one of each other formula of as
/// many numbers and the same unit (degrees or not).
fn alternatives(named: RotationConvention) -> impl Iterator<Item = RotationConvention> {
    RotationConvention::ALL.into_iter().filter(move |&c| {
        formula(c) == c
            && formula(c) != formula(named)
            && c.components().len() == named.components().len()
            && c.in_degrees() == named.in_degrees()
    })
}

/// Each side's choices: its named convention first, then the others it may have been meant as.
fn choices(named: Option<RotationConvention>) -> Vec<Option<RotationConvention>> {
    match named {
        None => vec![None],
        Some(c) => std::iter::once(Some(c))
            .chain(alternatives(c).map(Some))
            .collect(),
    }
}

/// Refuses `recording` ([`Error::Misread`]) when its poses, read in the conventions `options`
/// names, fit poorly and another reading of the same numbers fits far better (the rule of the
/// readings check, [`ReadingFit::far_better_than`]) and fits well. Standard input cannot be read
/// again and is not checked; a reading that fails (a number out of the other convention's range)
/// is passed.
pub(super) fn check_named(
    source: &Source,
    options: &RecordingOptions,
    recording: &Recording,
) -> Result<(), Error> {
    let named = options.rotations;
    if !named.is_named() || matches!(source, Source::File { path, .. } if path.as_os_str() == "-") {
        return Ok(());
    }
    let Some(given) = judged_fit(&recording.poses, options.setup) else {
        return Ok(());
    };
    if !given.poor() {
        return Ok(());
    }
    // The offset the input was paired with: searching it again for each reading would cost more
    // than the reading, and a wrong convention does not move a clock. A pose file has none (and
    // refuses one).
    let again = RecordingOptions {
        time_offset: match source {
            Source::File { .. } => None,
            _ => Some(TimeOffset::Fixed(recording.time_offset.unwrap_or(0.0))),
        },
        ..*options
    };
    let mut best: Option<(Rotations, ReadingFit)> = None;
    for robot in choices(named.robot) {
        for camera in choices(named.camera) {
            let read_as = Rotations { robot, camera };
            if read_as == named {
                continue;
            }
            let conventions = Conventions { named, read_as };
            let Ok(other) = read_source(source, &again, conventions, &mut |_| {}) else {
                continue;
            };
            let Some(fit) = judged_fit(&other.poses, options.setup) else {
                continue;
            };
            // Far better, and good: a reading that still fits poorly says the input has another
            // fault too, and naming a convention would send the user the wrong way.
            if fit.far_better_than(&given)
                && !fit.poor()
                && best
                    .as_ref()
                    .is_none_or(|(_, b)| fit.score(&given) < b.score(&given))
            {
                best = Some((read_as, fit));
            }
        }
    }
    let Some((read_as, fit)) = best else {
        return Ok(());
    };
    Err(Error::Misread {
        finding: finding(source, named, read_as, (&given, &fit)),
        fit: String::new(),
        readings: Vec::new(),
        setup: options.setup,
        other_setup: false,
        frames: false,
    })
}

/// The finding in words, with the fix of both faces.
fn finding(
    source: &Source,
    named: Rotations,
    read_as: Rotations,
    (given, better): (&ReadingFit, &ReadingFit),
) -> String {
    // The sides read otherwise: the convention named, and the one meant (of the better formula,
    // the one with the named one's letters first: the file's columns or field were named so).
    let mut changed: Vec<(&str, RotationConvention, Vec<RotationConvention>)> = Vec::new();
    for (side, n, r) in [
        ("robot", named.robot, read_as.robot),
        ("camera", named.camera, read_as.camera),
    ] {
        let (Some(n), Some(r)) = (n, r) else { continue };
        if n == r {
            continue;
        }
        let mut meant = same_formula(r);
        meant.sort_by_key(|c| c.components() != n.components());
        changed.push((side, n, meant));
    }
    // Both sides named alike and meant alike: said once.
    if let [(_, n1, m1), (_, n2, m2)] = changed.as_slice()
        && n1 == n2
        && m1 == m2
    {
        changed = vec![("robot and camera", *n1, m1.clone())];
    }
    let read = changed
        .iter()
        .map(|(side, n, meant)| {
            let same = if meant.len() > 1 {
                format!(
                    "; the same formula as {}",
                    meant[1..]
                        .iter()
                        .map(|c| c.name())
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            } else {
                String::new()
            };
            format!(
                "the {side} poses' numbers read as {} ({}{same}) rather than {} ({})",
                meant[0].name(),
                meant[0].describe(),
                n.name(),
                n.describe()
            )
        })
        .collect::<Vec<_>>()
        .join(", and ");
    // The names to give: every side named, the changed ones as meant.
    let meant_for = |side: &str, n: Option<RotationConvention>| {
        changed
            .iter()
            .find(|(s, _, _)| s.contains(side))
            .map(|(_, _, meant)| meant[0])
            .or(n)
    };
    let specs: Vec<String> = match (
        meant_for("robot", named.robot),
        meant_for("camera", named.camera),
    ) {
        (Some(r), Some(c)) if r == c => vec![r.name().to_string()],
        (r, c) => [("robot", r), ("camera", c)]
            .into_iter()
            .filter_map(|(side, c)| Some(format!("{side}={}", c?.name())))
            .collect(),
    };
    let flags = format!(
        "`{}`",
        specs
            .iter()
            .map(|s| format!("--rotation {s}"))
            .collect::<Vec<_>>()
            .join(" ")
    );
    let python = match specs.as_slice() {
        [one] => format!("`rotation=\"{one}\"`"),
        _ => format!(
            "`rotation=[{}]`",
            specs
                .iter()
                .map(|s| format!("\"{s}\""))
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    // Where the convention shows in the file: CSV columns and JSON fields are named for it.
    let written = match source {
        Source::File { path, format } => {
            let csv = *format == Format::Csv
                || (*format == Format::Auto
                    && path
                        .extension()
                        .is_some_and(|e| e.eq_ignore_ascii_case("csv")));
            changed
                .iter()
                // CSV columns the file already has need no word.
                .filter(|(_, n, meant)| !csv || n.components() != meant[0].components())
                .map(|(side, _, meant)| {
                    let r = meant[0];
                    if csv {
                        format!(
                            "; the {side} columns then end in `_{}`",
                            r.components().join("`, `_")
                        )
                    } else {
                        format!(
                            "; the {side} poses' rotation field is then `{}`",
                            r.json_field()
                        )
                    }
                })
                .collect::<String>()
        }
        _ => String::new(),
    };
    format!(
        "the poses fit far better with {read} (median residual {:.2}° and {:.1}% of the motion range, against {:.2}° and {:.1}% as named): name the convention the file uses, {flags} ({python} in Python){written}",
        better.rotation_deg,
        100.0 * better.translation_rel,
        given.rotation_deg,
        100.0 * given.translation_rel,
    )
}
