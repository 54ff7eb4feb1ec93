//! `handeye online`: the online calibrator on a stream, one JSON line per reported estimate and
//! change (the accumulating estimator, the default) or per calibration (`--estimator paper`).

use std::collections::VecDeque;
use std::path::PathBuf;
use std::rc::Rc;

use anyhow::{Result, bail};
use clap::Args as ClapArgs;
use handeye::io::Truth;
use handeye::{AdaptiveParams, Selection, StreamReading};
use handeye::{ErrorSource, Estimator, Event, OnlineCalibrator, OnlineConfig, Unit};
use handeye::{Step, TrackOptions, TrackReport as Report};

use crate::faces::{self, Face, Published};
use crate::input::{InputArgs, read_ahead};
use crate::output::{LineOut, print_text};
use crate::values;

mod pixels;

/// Options of `handeye online`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    #[command(flatten)]
    input: InputArgs,
    /// Motion selection: the paper's adaptive thresholds, Shi et al.'s fixed ones, or none (the
    /// conventional method).
    #[arg(long, default_value_t = Selection::Adaptive, value_parser = values::named::<Selection>())]
    selection: Selection,
    /// Estimator: `accumulate` (every pair of poses since the last detected change of X, outliers
    /// held out, the readings checked, each estimate with its uncertainty, reported on its own
    /// schedule: --every, --shrink, and at the end) or `paper` (the paper's method: Andreff on the
    /// two selected motions of each calibration, no uncertainty; not published by --output
    /// yaml|ros2|urdf).
    #[arg(long, default_value_t = Estimator::Accumulate, value_parser = values::named::<Estimator>())]
    estimator: Estimator,
    /// With --estimator accumulate: report the estimate at least every N poses.
    #[arg(long, default_value_t = TrackOptions::default().every, value_parser = values::count(1, u64::MAX))]
    every: usize,
    /// With --estimator accumulate: also report when both uncertainties have shrunk to this
    /// fraction of the last reported ones.
    #[arg(long, default_value_t = TrackOptions::default().shrink, value_parser = values::positive)]
    shrink: f64,
    /// Length unit of the input: `auto` infers metres or millimetres from the first pose; it
    /// sets the default --d-max (0.1 m).
    #[arg(long, default_value_t = Unit::Auto, value_parser = values::named_of(&[Unit::Auto, Unit::Metre, Unit::Millimetre]))]
    unit: Unit,
    /// Least rotation-angle gap (degrees) that marks a pose as an outlier (accumulate estimator).
    #[arg(long, default_value_t = TrackOptions::default().outlier_deg, value_parser = values::angle_deg)]
    outlier_deg: f64,
    /// With --estimator accumulate: the point whose error through X each report's
    /// `uncertainty.at_point` gives: X,Y,Z in the camera frame, input unit (default: the mean
    /// target position seen, the working distance).
    #[arg(long, value_name = "X,Y,Z", value_parser = values::point)]
    point: Option<[f64; 3]>,
    /// With --estimator accumulate: a prior on a component of X's translation, for a low-DOF
    /// robot (a SCARA, a 4-axis arm) whose rotations are all about one axis and so never
    /// determine X's translation along it: NAME=VALUE (exact) or NAME=VALUE+-SIGMA, NAME one of
    /// tx, ty, tz (X's parent frame; the input's length unit, or with its unit: tz=0.12m,
    /// tz=120mm+-2mm), e.g. `--prior tz=0.12+-0.002`. Repeatable. Used only while the rotations
    /// are about one axis, for the component along it; its sigma is added to the translation
    /// uncertainty.
    #[arg(long, value_name = "NAME=VALUE[+-SIGMA]", value_parser = values::prior)]
    prior: Vec<handeye::Prior>,
    /// The robot's DH table, as `calibrate --robot-model` (JSON; the records' `joints` needed):
    /// the systematic-error test also asks whether the residuals follow an error of the table's
    /// parameters. Refused (exit 2) at the first test when it does not turn the hand as the poses
    /// do, or when the records carry no joint angles.
    #[arg(long, value_name = "FILE")]
    robot_model: Option<std::path::PathBuf>,
    /// Also refine over the last five selected motions (the paper's optimal method).
    #[arg(long)]
    optimal: bool,
    /// Source of rmsR/rmsT: the AX − XB residuals, or the true X (needs --truth).
    #[arg(long, default_value_t = ErrorSource::Residual, value_parser = values::named::<ErrorSource>())]
    error_source: ErrorSource,
    /// Truth file (the true X), for --error-source truth.
    #[arg(long)]
    truth: Option<PathBuf>,
    /// What to do with a bad line: report it and skip it, or stop (exit 2).
    #[arg(long, default_value_t = OnBadLine::Skip, value_parser = values::named::<OnBadLine>())]
    on_bad_line: OnBadLine,
    /// N of Eq. (1): motions averaged for the initial thresholds (2 to 1000000).
    #[arg(long, default_value_t = AdaptiveParams::default().n_init, value_parser = values::count(2, AdaptiveParams::MAX_N_INIT as u64))]
    n_init: usize,
    /// Candidates tried before the thresholds are relaxed.
    #[arg(long, default_value_t = AdaptiveParams::default().interval, value_parser = values::count(1, u64::MAX))]
    interval: usize,
    /// Relaxation factor of sin α₀ and β₀, in [0.1, 1].
    #[arg(long, default_value_t = AdaptiveParams::default().relax_down, value_parser = values::relax_down)]
    relax_down: f64,
    /// Relaxation factor of d₀, in [1, 10].
    #[arg(long, default_value_t = AdaptiveParams::default().relax_up, value_parser = values::relax_up)]
    relax_up: f64,
    /// Exploration factor after calibrations 1–3, in [0.1, 10].
    #[arg(long, default_value_t = AdaptiveParams::default().explore, value_parser = values::explore)]
    explore: f64,
    /// Required rotation accuracy rmsRMax, unit-free: the RMS of the nine entries of R̂ − R
    /// (‖R̂ − R‖_F / 3, the events' `rms_r`; 0.001 is a rotation error of about 0.12°).
    #[arg(long, default_value_t = AdaptiveParams::default().rms_r_max, value_parser = values::positive)]
    rms_r_max: f64,
    /// Required translation accuracy rmsTMax, unit-free: a translation error relative to ‖t_X‖
    /// (the events' `rms_t`; 0.05 is 5 %).
    #[arg(long, default_value_t = AdaptiveParams::default().rms_t_max, value_parser = values::positive)]
    rms_t_max: f64,
    /// Floor of a predicted α₀ (the angle between the axes of A' and A''), degrees, in (0, 90].
    #[arg(long, default_value_t = ALPHA_MIN_DEG, value_parser = values::axis_angle_deg, conflicts_with = "alpha_min")]
    alpha_min_deg: f64,
    /// Deprecated: the floor as a sine (sin α₀, in (0, 1]); use --alpha-min-deg.
    #[arg(long, value_parser = values::fraction)]
    alpha_min: Option<f64>,
    /// Floor of a predicted β₀ (the least rotation angle of a selected motion), degrees, in
    /// (0, 180] [default: 3, the library's default].
    #[arg(long, value_parser = values::angle_deg)]
    beta_min_deg: Option<f64>,
    /// Ceiling of a predicted d₀, in the input's length unit [default: 0.1 m in the unit of
    /// --unit].
    #[arg(long, value_parser = values::positive)]
    d_max: Option<f64>,
    /// Opt-in remedy for thresholds that lock when their four records are equal.
    #[arg(long)]
    unfreeze: bool,
    /// Output: JSON Lines; a line for a person per calibration or estimate (`text`); or, at the
    /// end of the stream, the last estimate (with its uncertainty: the accumulating estimator's
    /// only) as easy_handeye2's YAML, a `static_transform_publisher` line and launch snippet
    /// (`ros2`) or a URDF `<joint>` (`urdf`); exit 3 when the stream gave none, saying why
    /// [default: text on a terminal, JSON otherwise].
    #[arg(long, value_parser = values::named::<Face>())]
    output: Option<Face>,
    /// The parent frame of X in the yaml, ros2 and urdf outputs [default: the recording's gripper
    /// frame (eye-in-hand) or base frame (eye-to-hand); `gripper` or `base` for files].
    #[arg(long)]
    parent_frame: Option<String>,
    /// The child frame of X (the camera's) [default: the recording's camera frame, or, when the
    /// recording's tf gives it a parent, the root of its subtree, X carried there; `camera` for
    /// files]. A name given is kept (X carried to it when the recording's /tf_static holds it
    /// above the camera frame), with a warning when the recording gives that frame a parent.
    #[arg(long)]
    child_frame: Option<String>,
    /// The calibration's name in the yaml output (easy_handeye2's `parameters.name`, the file
    /// name it loads: ~/.ros2/easy_handeye2/calibrations/NAME.calib).
    #[arg(long, default_value = "handeye")]
    name: String,
    /// Also write a page for a person at the end: the estimate's convergence with its uncertainty
    /// band, changes and held-out poses, and the paper's thresholds (one self-contained HTML
    /// file).
    #[arg(long, value_name = "FILE.html")]
    report: Option<PathBuf>,
    /// The camera's intrinsics (OpenCV FileStorage YAML or ROS camera_info), for a stream of
    /// records with `detections` (SPEC sec. 9): X is calibrated on their pixels as `calibrate
    /// --method reprojection` does it, reported at 16, 32, 64, … records and at the end.
    #[arg(long, value_name = "FILE")]
    intrinsics: Option<PathBuf>,
}

/// Default floor of a predicted α₀, degrees (the library's sin 15°).
const ALPHA_MIN_DEG: f64 = 15.0;

/// Runs the command.
pub fn run(args: Args) -> Result<()> {
    if args.intrinsics.is_some() {
        // The flags that do not apply on the pixels are refused before anything is read.
        pixels::refuse_flags(&args)?;
    }
    let truth = args.truth.as_ref().map(Truth::read).transpose()?;
    let setup = args.input.setup();
    if let Some(t) = &truth
        && t.frame != setup.x_frame()
    {
        bail!(
            "the truth file gives `{}` but --setup {} needs `{}`",
            t.frame,
            setup.name(),
            setup.x_frame()
        );
    }
    let config = OnlineConfig {
        setup,
        selection: args.selection,
        params: AdaptiveParams {
            n_init: args.n_init,
            interval: args.interval,
            relax_down: args.relax_down,
            relax_up: args.relax_up,
            explore: args.explore,
            rms_r_max: args.rms_r_max,
            rms_t_max: args.rms_t_max,
            alpha_min: match args.alpha_min {
                Some(sine) => {
                    crate::tell!(
                        "warning: --alpha-min (a sine) is deprecated: use --alpha-min-deg {:.4}",
                        sine.asin().to_degrees()
                    );
                    sine
                }
                None => args.alpha_min_deg.to_radians().sin(),
            },
            beta_min: args
                .beta_min_deg
                .map_or(AdaptiveParams::default().beta_min, f64::to_radians),
            d_max: args.d_max.unwrap_or(AdaptiveParams::default().d_max),
            unfreeze: args.unfreeze,
        },
        error_source: args.error_source,
        truth: truth.map(|t| t.x),
        optimal: args.optimal,
        estimator: args.estimator,
        tracking: TrackOptions {
            every: args.every,
            shrink: args.shrink,
            outlier_deg: args.outlier_deg,
            point: args.point,
            ..TrackOptions::default()
        },
        // An explicit --d-max is in the input's unit whatever it is.
        unit: match args.d_max {
            Some(_) => Unit::AsGiven,
            None => args.unit,
        },
        // A recording's poses are looked up between the frames named.
        written: if args.input.is_bag() {
            handeye::Written::FRAMES
        } else {
            handeye::Written::NAMED
        },
    };
    for (name, value) in [("--every", args.every as f64), ("--shrink", args.shrink)] {
        if !(value.is_finite() && value > 0.0) {
            bail!("{name} must be a positive number, found {value}");
        }
    }
    if let Some(intrinsics) = &args.intrinsics {
        return pixels::run(&args, config, intrinsics);
    }
    let accumulate = config.estimator == Estimator::Accumulate;
    let face = Face::chosen(args.output);
    let publish = matches!(face, Face::Yaml | Face::Ros2 | Face::Urdf);
    // Only an X with an uncertainty, from checked readings, is published.
    if publish {
        config.estimator.publishable()?;
    }
    // The frame names and the name are checked before the input is read.
    let frames = faces::frames(
        &args.input,
        args.parent_frame.as_deref(),
        args.child_frame.as_deref(),
        &args.name,
    )?;
    if let Some(path) = &args.report {
        crate::report::check_writable(path)?;
    }
    let mut calibrator = OnlineCalibrator::new(config)?
        .with_priors(&args.prior)?
        .with_robot_model(crate::input::robot_model(args.robot_model.as_deref())?)?;
    // Event lines are buffered, and written out before the input is waited for.
    let out = LineOut::stdout();
    let (records, opened) = read_ahead(&args.input, {
        let out = out.clone();
        Rc::new(move || out.flush_quietly())
    })?;
    let (source, offset) = (opened.source, opened.offset);
    let time_offset = offset.as_ref().map(|o| o.seconds);
    let mut messages = Thinned {
        bad_lines: 0,
        held_out: 0,
        out: out.clone(),
    };
    // Kept only for --report: a few numbers per event.
    let mut trace = args
        .report
        .as_ref()
        .map(|_| crate::report::OnlineTrace::default());
    let mut told_unit = false;
    // Bad lines that are records with detections alone, for the refusal's words.
    let mut on_pixels = 0usize;
    // The input's length unit as the first poses tell, for the ROS outputs (in metres).
    let mut pose_unit: Option<Unit> = None;
    // Input lines of the recent poses, for naming the ones held out (the tracker may hold out a
    // pose up to 256 poses after it came, when it judges its first poses together).
    let mut lines: VecDeque<(usize, usize, Option<f64>)> = VecDeque::with_capacity(LINES_KEPT);
    for record in records {
        let record = match record {
            Ok(r) => r,
            Err(e) => {
                on_pixels += usize::from(detections_only(&e));
                bad_line(e, args.on_bad_line, &mut messages)?;
                continue;
            }
        };
        // A pose the calibrator refuses (not finite, overflowing) is a bad line too, named by its
        // place; a unit it cannot tell stops the run.
        // The joint angles, where the record gives them (the systematic-error test's order).
        let pushed = match record.joint_count {
            0 => calibrator.push(&record.pose),
            n => calibrator.push_with_joints(&record.pose, &record.joints[..n]),
        };
        let events = match pushed {
            Ok(events) => events,
            Err(e @ handeye::Error::InvalidTransform { .. }) => {
                let e = handeye::Error::Parse {
                    file: source.clone(),
                    line: record.line,
                    field: "-".to_string(),
                    message: e.to_string(),
                    remedy: None,
                };
                bad_line(e, args.on_bad_line, &mut messages)?;
                continue;
            }
            Err(e) => return Err(e.into()),
        };
        if !told_unit {
            told_unit = tell_unit(&calibrator, &record);
        }
        if pose_unit.is_none() {
            pose_unit = Unit::infer(&record.pose);
        }
        // The paper's estimator has no checks of its own: the calibrator runs the batch's check
        // of the readings on the first poses (the accumulating estimator runs it itself).
        if let Some(found) = calibrator.misread() {
            out.flush_quietly();
            warn_misread(found);
        }
        if lines.len() == LINES_KEPT {
            lines.pop_front();
        }
        // Paired streams are named by the camera stamp, files by their line.
        let stamp = args.input.robot.as_ref().and(record.stamp);
        lines.push_back((calibrator.poses(), record.line, stamp));
        if let Some(step) = calibrator.step() {
            if let Some(t) = &mut trace {
                t.step(step);
            }
            print_step(
                step,
                setup,
                calibrator.unit(),
                &lines,
                &source,
                time_offset,
                face,
                &mut messages,
            )?;
        }
        if let Some(t) = &mut trace {
            events.iter().for_each(|e| t.calibration(e));
        }
        if !accumulate {
            for event in events {
                match face {
                    Face::Json => out.json(&Event {
                        time_offset_s: time_offset,
                        ..event
                    })?,
                    Face::Text => {
                        out.text(&format!("{}\n", event_text(&event, calibrator.unit())))?
                    }
                    _ => {}
                }
            }
            // Said at 200, 400, 800, … poses without a calibration.
            if let Some(why) = calibrator.stuck() {
                out.flush_quietly();
                crate::tell!("{why}");
            }
        }
    }
    let finished = calibrator.finish();
    if let Some(found) = calibrator.misread() {
        warn_misread(found);
    }
    let finished = match finished {
        Ok(report) => report,
        Err(e) => {
            out.flush()?;
            return Err(e.into());
        }
    };
    if let Some(report) = finished {
        print_report(&report, setup, time_offset, face, &out, calibrator.unit())?;
        if let Some(t) = &mut trace {
            t.step(&Step {
                pose: report.pose,
                report: Some(report),
                ..Step::default()
            });
        }
    }
    // Every line is out before the summary, the report and the other faces.
    out.flush()?;
    // The estimate to use: the last report since the last change, from readings not found
    // misread since.
    let last = calibrator.last_report();
    let summary = summary(&calibrator, last.as_ref(), messages.bad_lines);
    crate::tell!("{summary}");
    if let (Some(path), Some(mut trace)) = (&args.report, trace) {
        trace.poses = calibrator.poses();
        trace.offset = offset.and_then(|o| o.curve.map(|c| (o.seconds, c)));
        crate::report::write_online(path, &trace, &summary)?;
        crate::tell!("wrote {}", path.display());
    }
    if calibrator.poses() == 0 {
        // As `calibrate` refuses an input without a pose pair.
        return Err(handeye::Error::Parse {
            file: source,
            line: 0,
            field: "-".into(),
            message: match (messages.bad_lines, on_pixels) {
                (0, _) => "no pose pair in the input".into(),
                (n, 0) => format!("no pose pair in the input: all {n} record line(s) were bad"),
                (n, p) => format!(
                    "no pose pair in the input: all {n} record line(s) were bad, {p} of them records with `detections` and no camera pose: calibrate them on the pixels with `handeye online --intrinsics FILE` (the camera's intrinsics: OpenCV YAML or ROS camera_info)"
                ),
            },
            remedy: None,
        }
        .into());
    }
    if publish {
        let Some(report) = &last else {
            return Err(handeye::Error::NoEstimate {
                poses: calibrator.poses(),
                why: no_estimate(&calibrator),
            }
            .into());
        };
        // In metres whatever the input.
        let unit = match calibrator.unit() {
            Unit::Millimetre => Some(Unit::Millimetre),
            Unit::Metre => Some(Unit::Metre),
            Unit::Auto | Unit::AsGiven => pose_unit,
        };
        publish_report(
            report,
            &args,
            &frames,
            opened.camera_mount.as_ref(),
            face,
            unit,
        )?;
    }
    Ok(())
}

/// Publishes a report's X as `--output yaml|ros2|urdf` says (in metres whatever the input's
/// `unit`).
fn publish_report(
    report: &Report,
    args: &Args,
    frames: &faces::Frames,
    mount: Option<&handeye::io::CameraMount>,
    face: Face,
    unit: Option<Unit>,
) -> Result<()> {
    let setup = args.input.setup();
    let unit = faces::ros_unit(unit);
    let e = &report.estimate;
    let (scale, unit_name) = match unit {
        Some(Unit::Millimetre) => (1e-3, " m"),
        Some(_) => (1.0, " m"),
        None => (1.0, " (input unit)"),
    };
    let x = e.x;
    let source = format!(
        "online, estimate {} from {} poses, uncertainty (one sigma) {:.4}° / {:.6}{unit_name}",
        report.number,
        e.poses,
        e.uncertainty_rotation_deg.unwrap_or(f64::NAN),
        e.uncertainty_translation.unwrap_or(f64::NAN) * scale,
    );
    let child_given = args.child_frame.is_some();
    let publication = crate::publish::publication(&x, frames, mount, child_given);
    let published = publication.of(Published {
        x: &x,
        frame: setup.x_frame(),
        setup,
        source: &source,
        unit,
        note: None,
        warning: None,
    });
    publication.tell(published, false);
    let to = &publication.frames;
    print_text(&match face {
        Face::Yaml => faces::yaml(published, to, None),
        Face::Ros2 => faces::ros2(published, to),
        _ => faces::urdf(published, to),
    })
}

/// A report of the accumulating estimator on stdout, in the face chosen.
fn print_report(
    r: &Report,
    setup: handeye::Setup,
    time_offset: Option<f64>,
    face: Face,
    out: &LineOut,
    unit: Unit,
) -> Result<()> {
    match face {
        Face::Json => out.json(&r.json(setup, time_offset)),
        Face::Text => out.text(&format!(
            "estimate {} from {} poses: {}\n",
            r.number,
            r.estimate.poses,
            estimate_words(r, unit)
        )),
        _ => Ok(()),
    }
}

/// A report in words, every length with its unit: X, its uncertainty, the error at the working
/// distance and the verdict.
fn estimate_words(r: &Report, unit: Unit) -> String {
    let e = &r.estimate;
    let at_point = e.at_point.map_or(String::new(), |(point, sigma)| {
        let words = faces::at_point(point, sigma, known(unit));
        format!("; {}{}", words[..1].to_lowercase(), &words[1..])
    });
    // Which component came from the prior (a low-DOF robot), as the batch's text says it.
    let prior = e.prior.map_or(String::new(), |p| {
        format!(
            "; {} from the prior ({} +- {})",
            p.component.name(),
            length(p.value, unit),
            length(p.sigma, unit)
        )
    });
    // An estimate on the pixels says how well it fits them, as calibrate's text does.
    let pixels = e.reprojection.map_or(String::new(), |p| {
        format!(
            "; reprojection RMS {:.3} px over {} detections ({} left out)",
            p.rms_px, p.detections, p.outlier_detections
        )
    });
    format!(
        "{}, uncertainty {:.3}° / {}{at_point}{prior}{pixels}; verdict {}",
        describe(&e.x, unit),
        e.uncertainty_rotation_deg.unwrap_or(f64::NAN),
        length(e.uncertainty_translation.unwrap_or(f64::NAN), unit),
        r.verdict().name()
    )
}

/// The unit when it is known (metres or millimetres).
fn known(unit: Unit) -> Option<Unit> {
    matches!(unit, Unit::Metre | Unit::Millimetre).then_some(unit)
}

/// A length with its unit.
fn length(v: f64, unit: Unit) -> String {
    match unit {
        Unit::Metre => format!("{v:.4} m"),
        Unit::Millimetre => format!("{v:.2} mm"),
        _ => format!("{v:.4} (input units)"),
    }
}

/// A calibration event for a person.
fn event_text(e: &Event, unit: Unit) -> String {
    let [a, i, j] = e.poses;
    format!(
        "calibration {} (poses {a}, {i}, {j}): {}, rms_r {:.2e}, rms_t {:.2e}",
        e.calibration,
        describe(&e.x, unit),
        e.rms.rms_r,
        e.rms.rms_t
    )
}

/// Warns that the poses fit far better read another way (an inverted pose, `w, x, y, z`
/// quaternions, millimetres on one side), have sizes the setup makes unlikely, or turn about one
/// axis.
fn warn_misread(found: StreamReading) {
    match found {
        StreamReading::ReadWrongly(_) => {
            crate::tell!("warning: {found} (`handeye calibrate` checks this too)")
        }
        _ => crate::tell!("warning: {found}"),
    }
}

/// Input lines kept for naming held-out poses.
const LINES_KEPT: usize = 300;

/// Counts and thins the messages of bad lines and held-out poses, shown after the lines of `out`
/// before them.
struct Thinned {
    bad_lines: usize,
    held_out: usize,
    out: LineOut,
}

/// Whether a bad line is a record with `detections` and no camera pose (the pose reader's
/// remedy for it): one for `online --intrinsics`.
fn detections_only(e: &handeye::Error) -> bool {
    e.remedy() == Some(handeye::Remedy::Pixels)
}

impl Thinned {
    /// Every message is counted; the first ones are shown, later ones sparsely, so that an
    /// endless bad stream cannot flood the terminal. The lines of `out` before it come first.
    fn show(count: &mut usize, what: &str, message: String, out: &LineOut) {
        *count += 1;
        if OnlineCalibrator::told(*count) {
            out.flush_quietly();
            crate::tell!("{message}");
        }
        if *count == OnlineCalibrator::TOLD_ONE_BY_ONE {
            crate::tell!(
                "further {what} are counted and shown only at the 2^k-th (the count is given at the end)"
            );
        }
    }
}

/// What `--on-bad-line` does with a line that does not parse.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum OnBadLine {
    /// Report it and read on.
    Skip,
    /// Stop with its error (exit 2).
    Stop,
}

handeye::named_enum!(OnBadLine, "on-bad-line", "on_bad_line" {
    Skip => "skip",
    Stop => "stop",
});

/// Skips a bad line with its message, or stops with it (`--on-bad-line stop`).
fn bad_line(e: handeye::Error, on_bad_line: OnBadLine, messages: &mut Thinned) -> Result<()> {
    if on_bad_line == OnBadLine::Skip && matches!(e, handeye::Error::Parse { .. }) {
        Thinned::show(
            &mut messages.bad_lines,
            "bad lines",
            match e.remedy() {
                Some(r) => format!("skipped: {e}; {}", crate::faces::remedy(r, "online")),
                None => format!("skipped: {e}"),
            },
            &messages.out,
        );
        Ok(())
    } else {
        messages.out.flush_quietly();
        Err(e.into())
    }
}

/// Tells on stderr which length unit the run uses once it is known (true), and that it is not
/// yet when the first pose's size fits neither unit.
fn tell_unit(calibrator: &OnlineCalibrator, record: &handeye::io::StampedPosePair) -> bool {
    let unit = match calibrator.unit() {
        Unit::Metre => "metres",
        Unit::Millimetre => "millimetres",
        Unit::AsGiven => {
            crate::tell!("length unit: as given (d_max = {})", calibrator.d_max());
            return true;
        }
        Unit::Auto => {
            if calibrator.poses() == 1 {
                let p = &record.pose;
                crate::tell!(
                    "warning: cannot tell the length unit from the first pose (line {}: translations of {:.4} and {:.4} fit neither metres nor millimetres); d_max stays {} until a pose tells: pass --unit m or --unit mm, or --d-max in your unit",
                    record.line,
                    p.base_from_gripper.translation.vector.norm(),
                    p.camera_from_target.translation.vector.norm(),
                    calibrator.d_max()
                );
            }
            return false;
        }
    };
    let how = if calibrator.config().unit == Unit::Auto {
        format!(
            "inferred from pose {}; --unit m|mm to set it",
            calibrator.poses()
        )
    } else {
        "--unit".to_string()
    };
    crate::tell!(
        "length unit: {unit} ({how}); d_max = {}",
        calibrator.d_max()
    );
    true
}

/// Prints what the accumulating estimator did with a pose: held-out poses on stderr (by their
/// input line), a change and a report as JSON lines.
#[allow(clippy::too_many_arguments)]
fn print_step(
    step: &Step,
    setup: handeye::Setup,
    unit: Unit,
    lines: &VecDeque<(usize, usize, Option<f64>)>,
    source: &str,
    time_offset: Option<f64>,
    face: Face,
    messages: &mut Thinned,
) -> Result<()> {
    let out = messages.out.clone();
    let place = |pose: usize| match lines.iter().find(|(p, _, _)| *p == pose) {
        Some((_, _, Some(stamp))) => format!("{source} at t = {stamp:.3} s"),
        Some((_, line, None)) => format!("{source}:{line}"),
        None => format!("{source}, pose {pose}"),
    };
    for (pose, h) in step.held_out_poses() {
        let message = format!("held out: {}: {h}", place(pose));
        Thinned::show(&mut messages.held_out, "held-out poses", message, &out);
    }
    if let Some(c) = &step.change {
        out.flush_quietly();
        crate::tell!(
            "change of X or of the target from {} on (confirmed at {}): X moved by {:.3}° and {:.4}; accumulation restarted there",
            place(c.at),
            place(c.confirmed),
            c.x_rotation_deg,
            c.x_translation
        );
        if face == Face::Json {
            out.json(&c.json())?;
        }
    }
    if let Some(r) = &step.report {
        print_report(r, setup, time_offset, face, &out, unit)?;
    }
    Ok(())
}

/// The stderr summary: what the events showed, or why there was none.
fn summary(calibrator: &OnlineCalibrator, last: Option<&Report>, bad_lines: usize) -> String {
    let bad = if bad_lines > 0 {
        format!(", {bad_lines} bad line(s) skipped")
    } else {
        String::new()
    };
    let bad = if calibrator.unit() == Unit::Auto && calibrator.poses() > 0 {
        format!(
            "{bad}; the length unit was never told by the data (d_max {} was used: pass --unit)",
            calibrator.d_max()
        )
    } else {
        bad
    };
    let Some(tracker) = calibrator.tracker() else {
        let last = calibrator
            .last_x()
            .map_or("none".to_string(), |x| describe(&x, calibrator.unit()));
        let quiet = calibrator
            .stuck_at_end()
            .map_or(String::new(), |why| format!("\n{why}"));
        return format!(
            "{} calibration(s) from {} pose(s){bad}; last X: {last}{quiet}",
            calibrator.calibrations(),
            calibrator.poses()
        );
    };
    let repeats = match tracker.repeats() {
        0 => String::new(),
        n => format!(" ({n} at the robot pose of the pose before, each counted with it)"),
    };
    let counts = format!(
        "{} pose(s){repeats}{bad}, {} held out, {} change(s)",
        calibrator.poses(),
        tracker.held_out(),
        tracker.changes()
    );
    match (last, tracker.pending()) {
        (Some(r), _) => {
            let e = &r.estimate;
            let weak = r
                .weak
                .as_ref()
                .map_or(String::new(), |w| format!(" (weak: {w})"));
            let implausible = if r.implausible {
                " (warning: X and the target pose have sizes the setup makes unlikely: if both inputs give the inverse of the transform they name, the data fit as well with the two swapped)"
            } else {
                ""
            };
            // The library's own cautions (a systematic error), in its words.
            let warnings: String = r
                .warnings
                .iter()
                .map(|w| format!("\nwarning: {w}"))
                .collect();
            format!(
                "last estimate ({}) from {} of {counts}: {}{weak}{implausible}{warnings}",
                r.number,
                e.poses,
                estimate_words(r, calibrator.unit())
            )
        }
        (None, _) => format!("no estimate from {counts}: {}", no_estimate(calibrator)),
    }
}

/// Why the accumulating estimator reported no estimate.
fn no_estimate(calibrator: &OnlineCalibrator) -> String {
    match calibrator.pending() {
        // After a change, why the poses since have none (`Pending::SinceChange`).
        Some(why) => why.to_string(),
        None if calibrator.poses() == 0 => "the input gave no pose".to_string(),
        None => "no estimate was determined".to_string(),
    }
}

/// A transform in a few words.
fn describe(x: &handeye::Transform, unit: Unit) -> String {
    let t = x.translation.vector;
    let unit = match unit {
        Unit::Metre => " m",
        Unit::Millimetre => " mm",
        _ => " (input units)",
    };
    format!(
        "t = [{:.6}, {:.6}, {:.6}]{unit}, rotation {:.4}°",
        t.x,
        t.y,
        t.z,
        x.rotation.angle().to_degrees()
    )
}
