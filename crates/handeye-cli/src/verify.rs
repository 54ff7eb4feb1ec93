//! `handeye verify`: does a saved X still fit a new recording? The decision is the library's
//! ([`handeye::verify`]); this prints it and exits 0 (consistent), 4 (inconsistent) or 3 (the
//! recording cannot tell).

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::Result;
use clap::Args as ClapArgs;
use handeye::{Assessment, Consistency, Fix, Method, Options, Pairing};

use crate::faces::{self, Face};
use crate::input::{InputArgs, read_all};
use crate::output::{DEGENERATE, INCONSISTENT, Questionable, Verdict, print_json, print_text};
use crate::values;

/// Options of `handeye verify`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// The saved X: what `calibrate --output json` or `--output yaml` wrote (or easy_handeye2's
    /// calibration file). The setup it declares (`setup` or `frame` in the JSON,
    /// `calibration_type` in the YAML) is the recording's unless --setup is given, which must agree.
    #[arg(long = "x", value_name = "SAVED")]
    saved: PathBuf,
    #[command(flatten)]
    input: InputArgs,
    /// The hand–eye method the recording is calibrated with [default: andreff; reprojection with
    /// --intrinsics].
    #[arg(long, value_parser = values::named_of(&Method::WITH_PIXELS))]
    method: Option<Method>,
    /// Motions from every pair of poses (default) or from consecutive ones.
    #[arg(long, default_value_t = Pairing::All, value_parser = values::named::<Pairing>())]
    pairs: Pairing,
    /// Leave out the recording's poses that disagree with the others.
    #[arg(long)]
    reject_outliers: bool,
    /// Read the recording another way (as `calibrate --fix`).
    #[arg(long, value_parser = values::named::<Fix>())]
    fix: Option<Fix>,
    /// Bootstrap replicates behind the recording's uncertainty.
    #[arg(long, default_value_t = Options::default().replicates, value_parser = values::count(*Options::REPLICATES_RANGE.start() as u64, *Options::REPLICATES_RANGE.end() as u64))]
    bootstrap: usize,
    /// Output: the JSON object, or a summary for a person (`text`) [default: text on a terminal,
    /// JSON otherwise]. Only these two: a saved X is checked here, not published.
    #[arg(long, value_parser = values::named_of(&[Face::Json, Face::Text]))]
    output: Option<Face>,
    /// A prior on a component of X's translation, for a low-DOF robot (as `calibrate --prior`):
    /// NAME=VALUE or NAME=VALUE+-SIGMA, NAME one of tx, ty, tz. Without one, the component such a
    /// recording leaves free is taken from the saved X and the rest is checked. Repeatable.
    #[arg(long, value_name = "NAME=VALUE[+-SIGMA]", value_parser = values::prior)]
    prior: Vec<handeye::Prior>,
    /// The change that matters to you: a rotation in degrees and a translation in the recording's
    /// unit. A consistent X whose recording could not have seen a change of that size (`detectable`
    /// beyond it) is undetermined (exit 3).
    #[arg(long, value_name = "DEGREES,LENGTH", value_parser = values::tolerance)]
    tolerance: Option<handeye::Sizes>,
    /// Exit 5 when the saved X is consistent but the recording's own calibration is questionable.
    #[arg(long)]
    strict: bool,
    /// Write an HTML page: the verdict, the two X's, and where each places the target, pose by
    /// pose.
    #[arg(long, value_name = "FILE.html")]
    report: Option<PathBuf>,
    /// The camera's intrinsics (OpenCV YAML or ROS camera_info): check the saved X on the pixels
    /// of the recording's `detections` (a JSON Lines file), as `calibrate --method reprojection`.
    #[arg(long, value_name = "FILE")]
    intrinsics: Option<PathBuf>,
}

/// Runs the command.
pub fn run(mut args: Args) -> Result<()> {
    let face = Face::chosen(args.output);
    if let Some(path) = &args.report {
        crate::report::check_writable(path)?;
    }
    let saved = handeye::SavedX::read(&args.saved)?;
    // The setup the saved file declares, unless --setup says otherwise (then an error naming both).
    args.input.setup = Some(saved.setup_for(args.input.given_setup())?);
    let fix = args.fix.unwrap_or_default();
    let method = match (args.method, &args.intrinsics) {
        (None | Some(Method::Reprojection), Some(_)) => Method::Reprojection,
        (Some(Method::Reprojection), None) => {
            return Err(invalid(
                "method",
                "reprojection needs the camera's intrinsics: --intrinsics FILE (OpenCV YAML or ROS camera_info)",
            ));
        }
        (Some(m), Some(_)) => {
            return Err(invalid(
                "intrinsics",
                &format!(
                    "--intrinsics is read on the pixels (--method reprojection), not by --method {m}"
                ),
            ));
        }
        (m, None) => m.unwrap_or(Method::Andreff),
    };
    if method == Method::Reprojection {
        return run_pixels(&args, &saved, face);
    }
    let mut recording = read_all(&args.input, fix.reading())?;
    let options = Options {
        problem: handeye::Problem::HandEye(method),
        pairing: args.pairs,
        reject_outliers: args.reject_outliers,
        fix,
        replicates: args.bootstrap,
        pose_names: recording.names.clone(),
        written: recording.written,
        joints: std::mem::take(&mut recording.joints),
        priors: args.prior,
        ..Options::default()
    };
    let setup = args.input.setup();
    let v = tolerated(
        recording.offset_checked(handeye::verify(&saved, &recording.poses, setup, &options))?,
        args.tolerance,
    )?;
    show(&v, face)?;
    // After the result: a report that cannot be written loses nothing computed.
    if let Some(path) = &args.report {
        let reading = v
            .recording
            .as_ref()
            .map_or(handeye::Reading::AsGiven, |r| r.reading.applied);
        let unit = faces::length_unit(&reading.apply(&recording.poses, recording.written));
        let page = crate::report::RunPage {
            poses: &recording.poses,
            names: &recording.names,
            written: recording.written,
            setup,
            unit,
            summary: text(&v),
        };
        crate::report::write_verify(path, &page, &v)?;
        crate::tell!("wrote {}", path.display());
    }
    exit(v, args.strict)
}

/// The verification judged against `--tolerance`, when given.
fn tolerated(
    v: handeye::Verification,
    tolerance: Option<handeye::Sizes>,
) -> Result<handeye::Verification> {
    Ok(match tolerance {
        Some(t) => v.within(t)?,
        None => v,
    })
}

fn invalid(name: &'static str, message: &str) -> anyhow::Error {
    handeye::Error::InvalidParameter {
        name,
        message: message.into(),
    }
    .into()
}

/// `verify --intrinsics`: the saved X on the pixels of a JSON Lines file with `detections`.
fn run_pixels(args: &Args, saved: &handeye::SavedX, face: Face) -> Result<()> {
    let (camera, frames_read, names) =
        crate::calibrate::pixel_input(&args.input, args.intrinsics.as_ref(), None)?;
    let setup = args.input.setup();
    let options = Options {
        problem: handeye::Problem::HandEye(Method::Reprojection),
        pairing: args.pairs,
        fix: args.fix.unwrap_or_default(),
        pose_names: names.clone(),
        reject_outliers: args.reject_outliers,
        priors: args.prior.clone(),
        ..Options::default()
    };
    let input = handeye::Input::Pixels {
        frames: &frames_read,
        camera: &camera,
    };
    let v = tolerated(
        handeye::verify(saved, input, setup, &options)?,
        args.tolerance,
    )?;
    show(&v, face)?;
    if let Some(report) = &args.report {
        let poses = handeye::calibrate::problem::pixels::pose_pairs(&frames_read, &v.start_poses);
        let page = crate::report::RunPage {
            poses: &poses,
            names: &names,
            written: handeye::Written::NAMED,
            setup,
            unit: faces::length_unit(&poses),
            summary: text(&v),
        };
        crate::report::write_verify(report, &page, &v)?;
        crate::tell!("wrote {}", report.display());
    }
    exit(v, args.strict)
}

/// Prints the verification in its face (notes and warnings on stderr beside the JSON).
fn show(v: &handeye::Verification, face: Face) -> Result<()> {
    match face {
        Face::Text => print_text(&text(v))?,
        _ => {
            for note in &v.notes {
                crate::tell!("note: {note}");
            }
            if let Some(r) = &v.recording {
                for w in &r.warnings {
                    crate::tell!("warning: {}", faces::warning(w));
                }
            }
            print_json(&v)?
        }
    }
    Ok(())
}

/// The exit of a verification: 0 consistent, 4 inconsistent, 3 cannot tell; 5 with `--strict` on
/// a questionable recording.
fn exit(v: handeye::Verification, strict: bool) -> Result<()> {
    match v.verdict {
        Consistency::Consistent if strict && v.quality == Assessment::Questionable => {
            Err(Questionable.into())
        }
        Consistency::Consistent => Ok(()),
        Consistency::Inconsistent => Err(Verdict {
            code: INCONSISTENT,
            message: v.message,
        }
        .into()),
        Consistency::Undetermined => Err(Verdict {
            code: DEGENERATE,
            message: v.message,
        }
        .into()),
    }
}

/// The summary for a person.
fn text(v: &handeye::Verification) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "Verdict: {}", v.verdict.name());
    let _ = writeln!(s, "  {}", v.message);
    if v.distance_sigmas.is_finite() {
        let u = match v.length_unit.as_str() {
            "unknown" => "(input units)",
            u => u,
        };
        let _ = writeln!(
            s,
            "Difference: rotation {:.4}°, translation {} {u} (one sigma {:.4}°, {} {u}); {:.2} sigmas, at most {:.2} for the same rig",
            v.difference.rotation_deg,
            faces::short(v.difference.translation),
            v.sigma.rotation_deg,
            faces::short(v.sigma.translation),
            v.distance_sigmas,
            v.limit_sigmas
        );
        let _ = writeln!(
            s,
            "Smallest change this recording sees: rotation {:.4}°, translation {} {u}",
            v.detectable.rotation_deg,
            faces::short(v.detectable.translation)
        );
    }
    if let Some(p) = &v.pixels {
        let worst = p
            .per_frame
            .iter()
            .max_by(|a, b| (a.saved_px - a.own_px).total_cmp(&(b.saved_px - b.own_px)));
        let _ = writeln!(
            s,
            "On the pixels (the target's pose fitted to each X): saved X {:.3} px RMS, the recording's own X {:.3} px RMS{}",
            p.saved_rms_px,
            p.own_rms_px,
            worst.map_or(String::new(), |w| format!(
                "; most worse at {} ({:.3} px against {:.3} px)",
                w.name, w.saved_px, w.own_px
            ))
        );
    }
    for note in &v.notes {
        let _ = writeln!(s, "Note: {note}");
    }
    if let Some(r) = &v.recording {
        let _ = writeln!(
            s,
            "The recording's own calibration: {} ({} poses, {} motions)",
            r.verdict.name(),
            r.poses,
            r.motions
        );
        for w in &r.warnings {
            let _ = writeln!(s, "  - {}", faces::warning(w));
        }
    }
    s
}
