//! `handeye online --intrinsics FILE`: the online calibrator on a stream of records with
//! `detections` (SPEC sec. 9), calibrated on their pixels by the library's online calibrator
//! ([`handeye::OnlineSettings::intrinsics`]): each record read by the library's one reader of
//! such records, a bad one costing its line.

use anyhow::{Result, bail};
use std::path::Path;

use handeye::{Error, Name, OnlineSettings, Record};

use super::{Args, Printer, print_report, publish_report};
use crate::faces::{self, Face};
use crate::output::LineOut;

/// Runs `online --intrinsics`: the library's online calibrator on the pixels, printed.
pub(super) fn run(args: &Args, settings: OnlineSettings, intrinsics: &Path) -> Result<()> {
    let Some(path) = &args.input.input else {
        bail!("online --intrinsics reads a JSON Lines file with `detections` (or - for stdin)");
    };
    let setup = settings.setup;
    let face = Face::chosen(args.output);
    let publish_x = matches!(face, Face::Yaml | Face::Ros2 | Face::Urdf);
    // The frame names and the name are checked before the input is read.
    let frames = faces::frames(
        &args.input,
        args.parent_frame.as_deref(),
        args.child_frame.as_deref(),
        &args.name,
    )?;
    let camera = handeye::Intrinsics::read(intrinsics)?;
    let mut calibrator = OnlineSettings {
        intrinsics: Some(camera),
        // Refused on the pixels by the library, after it is read.
        robot_model: crate::input::robot_model(args.robot_model.as_deref())?,
        ..settings
    }
    .calibrator()?;
    let out = LineOut::stdout();
    let mut messages = Printer::new(args, out.clone(), None);
    let source = path.display().to_string();
    let mut read = |input: &mut dyn std::io::BufRead| -> Result<()> {
        for record in handeye::io::FrameRecording::records(input, &source) {
            let (line, frame) = match record {
                Ok(r) => r,
                Err(e) => {
                    messages.bad_line(e)?;
                    continue;
                }
            };
            let name = Name::Line {
                source: &source,
                line,
            };
            if let Some(report) = calibrator.push(Record::frame(frame).named(name))?.report {
                print_report(&report, setup, None, face, &out, calibrator.unit())?;
                out.flush_quietly();
            }
        }
        Ok(())
    };
    if path.as_os_str() == "-" {
        read(&mut std::io::stdin().lock())?;
    } else {
        let file = std::fs::File::open(path).map_err(|e| Error::Io {
            file: source.clone(),
            source: e,
        })?;
        read(&mut std::io::BufReader::new(file))?;
    }
    if calibrator.poses() == 0 {
        out.flush()?;
        return Err(Error::Parse {
            file: source,
            line: 0,
            field: "-".into(),
            message: match messages.bad_lines.count() {
                0 => "no record with `detections` in the input".into(),
                n => format!(
                    "no record with `detections` in the input: all {n} record line(s) were bad"
                ),
            },
            remedy: None,
        }
        .into());
    }
    let bad = match messages.bad_lines.count() {
        0 => String::new(),
        n => format!(", {n} bad line(s) skipped"),
    };
    let (report, warnings) = match calibrator.finish() {
        Ok(handeye::Outputs {
            report: Some(report),
            warnings,
            ..
        }) => (report, warnings),
        Ok(_) => bail!("no estimate on the pixels"),
        Err(e) => {
            out.flush()?;
            crate::tell!(
                "no estimate from {} record(s){bad}: the calibration on the pixels refused them",
                calibrator.poses()
            );
            return Err(e.into());
        }
    };
    let unit = calibrator.unit();
    print_report(&report, setup, None, face, &out, unit)?;
    out.flush()?;
    for w in &warnings {
        crate::tell!("warning: {}", faces::warning(w));
    }
    // Beyond 256 records the calibrator keeps a spread of views (and leaves outlier poses out).
    let records = if report.estimate.poses < report.pose {
        format!("{} of {} record(s)", report.estimate.poses, report.pose)
    } else {
        format!("{} record(s)", report.estimate.poses)
    };
    crate::tell!(
        "last estimate ({}) from {records}{bad}, on the pixels: {}",
        report.number,
        super::estimate_words(&report, unit)
    );
    if publish_x {
        let known = calibrator.summary().length_unit;
        publish_report(&report, args, &frames, None, face, known)?;
    }
    Ok(())
}

/// The inputs and pages of this command that do not apply on the pixels, refused before the input
/// is read (exit 2) rather than ignored. The calibrator's own settings (the paper's estimator, the
/// optimal method, the truth, a prior) are refused by the library
/// (`OnlineSettings::calibrator`), in the words every face prints.
pub(super) fn refuse_flags(args: &Args) -> Result<()> {
    let given = [
        ("--report", args.report.is_some()),
        ("--robot/--camera streams", args.input.robot.is_some()),
        ("a ROS 2 recording", args.input.is_bag()),
        // The records' JSON fields name their own conventions.
        ("--rotation", !args.input.rotation.is_empty()),
    ];
    if let Some((flag, _)) = given.iter().find(|(_, given)| *given) {
        return Err(Error::InvalidParameter {
            name: "intrinsics",
            message: format!(
                "{flag} is not offered on the pixels (online --intrinsics) (yet): give a JSON Lines file with `detections`"
            ),
        }
        .into());
    }
    Ok(())
}
