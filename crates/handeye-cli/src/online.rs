//! `handeye online`: the online calibrator on a stream, one JSON line per reported estimate and
//! change (the accumulating estimator, the default) or per calibration (`--estimator paper`).

use std::path::PathBuf;
use std::rc::Rc;

use anyhow::{Result, bail};
use clap::Args as ClapArgs;
use handeye::io::Truth;
use handeye::{AdaptiveParams, AlphaMin, Selection, StreamReading};
use handeye::{ErrorSource, Estimator, Event, OnlineCalibrator, OnlineSettings, Unit};
use handeye::{Name, Outputs, Record, Tell, Thinning, UnitTold};
use handeye::{TrackOptions, TrackReport as Report};

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
/// Default floor of a predicted α₀, degrees (the library's sin 15°).
const ALPHA_MIN_DEG: f64 = 15.0;

/// Runs the command: each record pushed to the library's online calibrator, what it returns
/// printed.
pub fn run(args: Args) -> Result<()> {
    if args.intrinsics.is_some() {
        // The flags that do not apply on the pixels are refused before anything is read.
        pixels::refuse_flags(&args)?;
    }
    let settings = settings(&args)?;
    if let Some(intrinsics) = &args.intrinsics {
        return pixels::run(&args, settings, intrinsics);
    }
    let face = Face::chosen(args.output);
    let publish = matches!(face, Face::Yaml | Face::Ros2 | Face::Urdf);
    // Only an X with an uncertainty, from checked readings, is published.
    if publish {
        settings.estimator.publishable()?;
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
    let robot_model = crate::input::robot_model(args.robot_model.as_deref())?;
    let mut calibrator = OnlineSettings {
        robot_model,
        ..settings
    }
    .calibrator()?;
    // Event lines are buffered, and written out before the input is waited for.
    let out = LineOut::stdout();
    let (records, opened) = read_ahead(&args.input, {
        let out = out.clone();
        Rc::new(move || out.flush_quietly())
    })?;
    let source = opened.source.clone();
    let mut print = Printer::new(
        &args,
        out.clone(),
        opened.offset.as_ref().map(|o| o.seconds),
    );
    for record in records {
        let record = match record {
            Ok(r) => r,
            Err(e) => {
                print.bad_line(e)?;
                continue;
            }
        };
        // A pose the calibrator refuses (not finite) is a bad line too, named by its place.
        match calibrator.push(pose_record(&args, &source, &record)) {
            Ok(o) => print.outputs(&o, record.line, calibrator.unit())?,
            Err(e @ handeye::Error::Parse { .. }) => print.bad_line(e)?,
            Err(e) => return Err(e.into()),
        }
    }
    let finished = calibrator.finish().or_else(|e| {
        out.flush()?;
        Err(anyhow::Error::from(e))
    })?;
    print.outputs(&finished, 0, calibrator.unit())?;
    // Every line is out before the summary, the report and the other faces.
    out.flush()?;
    let mount = opened.camera_mount.as_ref();
    let offset = opened.offset.and_then(|o| o.curve.map(|c| (o.seconds, c)));
    let published = publish.then_some((&frames, mount, face));
    end(&args, &calibrator, print, offset, source, published)
}

/// The end of a run on poses: the summary, the report page, the refusal of an input without a
/// pose pair, and X published as `--output yaml|ros2|urdf` says.
fn end(
    args: &Args,
    calibrator: &OnlineCalibrator,
    print: Printer,
    offset: Option<(f64, Vec<[f64; 2]>)>,
    source: String,
    published: Option<(&faces::Frames, Option<&handeye::io::CameraMount>, Face)>,
) -> Result<()> {
    // The estimate to use: the last report since the last change, from readings not found
    // misread since.
    let last = calibrator.last_report();
    let summary = summary(calibrator, last.as_ref(), print.bad_lines.count());
    crate::tell!("{summary}");
    if let (Face::Text, Some(report)) = (Face::chosen(args.output), &last) {
        print_text(&copyable(
            report,
            args.input.setup(),
            calibrator.summary().unit,
        ))?;
    }
    if let (Some(path), Some(mut trace)) = (&args.report, print.trace) {
        trace.poses = calibrator.poses();
        trace.offset = offset;
        crate::report::write_online(path, &trace, &summary)?;
        crate::tell!("wrote {}", path.display());
    }
    if calibrator.poses() == 0 {
        return Err(no_pose(source, print.bad_lines.count(), print.on_pixels).into());
    }
    // A misread input gives no estimate: the same refusal, and exit code, as `calibrate`'s; its
    // reason is the summary's, said once.
    if last.is_none() && matches!(calibrator.pending(), Some(handeye::Pending::Misread { .. })) {
        return Err(crate::output::Verdict {
            code: crate::output::DEGENERATE,
            message: "refused: the input looks misread (the summary above says how)".into(),
        }
        .into());
    }
    if let Some((frames, mount, face)) = published {
        let Some(report) = &last else {
            let (poses, why) = (calibrator.poses(), no_estimate(calibrator));
            return Err(handeye::Error::NoEstimate { poses, why }.into());
        };
        // In metres whatever the input.
        let unit = calibrator.summary().length_unit;
        publish_report(report, args, frames, mount, face, unit)?;
    }
    Ok(())
}

/// A record of the input as the calibrator takes it: paired streams named by the camera stamp,
/// files by their line; with its joint angles when it has them.
fn pose_record<'a>(
    args: &Args,
    source: &'a str,
    record: &'a handeye::io::StampedPosePair,
) -> Record<'a> {
    let line = record.line;
    let name = match args.input.robot.as_ref().and(record.stamp) {
        Some(seconds) => Name::Stamp {
            source,
            line,
            seconds,
        },
        None => Name::Line { source, line },
    };
    let pose = Record::pose(&record.pose).named(name);
    match record.joint_count {
        0 => pose,
        n => pose.with_joints(&record.joints[..n]),
    }
}

/// The settings of the command line, as the library's online calibrator takes them (the library
/// applies their rules: defaults, α₀ in degrees or as a sine, an explicit `--d-max` as given).
fn settings(args: &Args) -> Result<OnlineSettings> {
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
    let alpha_min = match args.alpha_min {
        Some(sine) => {
            crate::tell!(
                "warning: --alpha-min (a sine) is deprecated: use --alpha-min-deg {:.4}",
                sine.asin().to_degrees()
            );
            AlphaMin::Sine(sine)
        }
        None => AlphaMin::Degrees(args.alpha_min_deg),
    };
    Ok(OnlineSettings {
        setup,
        selection: args.selection,
        estimator: args.estimator,
        error_source: args.error_source,
        truth: truth.map(|t| t.x),
        optimal: args.optimal,
        n_init: Some(args.n_init),
        interval: Some(args.interval),
        relax_down: Some(args.relax_down),
        relax_up: Some(args.relax_up),
        explore: Some(args.explore),
        rms_r_max: Some(args.rms_r_max),
        rms_t_max: Some(args.rms_t_max),
        alpha_min: Some(alpha_min),
        beta_min_deg: args.beta_min_deg,
        d_max: args.d_max,
        unfreeze: args.unfreeze,
        unit: args.unit,
        every: Some(args.every),
        shrink: Some(args.shrink),
        outlier_deg: Some(args.outlier_deg),
        point: args.point,
        // A recording's poses are looked up between the frames named.
        written: if args.input.is_bag() {
            handeye::Written::FRAMES
        } else {
            handeye::Written::NAMED
        },
        priors: args.prior.clone(),
        ..OnlineSettings::default()
    })
}

/// As `calibrate` refuses an input without a pose pair: how many lines were bad, and how many of
/// them records with detections alone.
fn no_pose(source: String, bad_lines: usize, on_pixels: usize) -> handeye::Error {
    handeye::Error::Parse {
        file: source,
        line: 0,
        field: "-".into(),
        message: match (bad_lines, on_pixels) {
            (0, _) => "no pose pair in the input".into(),
            (n, 0) => format!("no pose pair in the input: all {n} record line(s) were bad"),
            (n, p) => format!(
                "no pose pair in the input: all {n} record line(s) were bad, {p} of them records with `detections` and no camera pose: calibrate them on the pixels with `handeye online --intrinsics FILE` (the camera's intrinsics: OpenCV YAML or ROS camera_info)"
            ),
        },
        remedy: None,
    }
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

/// The estimate to use as the text face of `calibrate` prints X, to copy: its translation (and in
/// millimetres when in metres), roll, pitch, yaw and quaternion.
fn copyable(r: &Report, setup: handeye::Setup, unit: Unit) -> String {
    let mut s = format!(
        "X = {} (estimate {} from {} poses, the one to use):\n",
        setup.x_frame(),
        r.number,
        r.estimate.poses
    );
    faces::transform_lines(&mut s, &r.estimate.x, known(unit));
    s
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

/// Prints what the calibrator returns, in the face chosen: JSON lines or text on stdout,
/// messages on stderr (bad lines and held-out poses thinned by the library's rule).
struct Printer {
    out: LineOut,
    face: Face,
    setup: handeye::Setup,
    /// The clock offset applied to a second stream, for the lines.
    time_offset: Option<f64>,
    on_bad_line: OnBadLine,
    bad_lines: Thinning,
    /// Bad lines that are records with detections alone, for the refusal's words.
    on_pixels: usize,
    /// Kept only for --report: a few numbers per event.
    trace: Option<crate::report::OnlineTrace>,
}

impl Printer {
    fn new(args: &Args, out: LineOut, time_offset: Option<f64>) -> Self {
        Self {
            out,
            face: Face::chosen(args.output),
            setup: args.input.setup(),
            time_offset,
            on_bad_line: args.on_bad_line,
            bad_lines: Thinning::default(),
            on_pixels: 0,
            trace: args.report.as_ref().map(|_| Default::default()),
        }
    }

    /// Prints what a record (at input line `line`), or the end, made happen.
    fn outputs(&mut self, o: &Outputs, line: usize, unit: Unit) -> Result<()> {
        let out = self.out.clone();
        if let Some(told) = o.unit {
            tell_unit(told, line);
        }
        // The paper's estimator has no checks of its own: the calibrator runs the batch's check
        // of the readings on the first poses (the accumulating estimator runs it itself).
        if let Some(found) = o.misread.clone() {
            if line > 0 {
                out.flush_quietly();
            }
            warn_misread(found);
        }
        if let Some(t) = &mut self.trace {
            t.outputs(o);
        }
        for h in &o.held_out {
            let message = format!("held out: {}: {}", h.name, h.why);
            show(h.tell, "held-out poses", message, &out);
        }
        if let Some(c) = &o.change {
            out.flush_quietly();
            crate::tell!(
                "change of X or of the target from {} on (confirmed at {}): X moved by {:.3}° and {:.4}; accumulation restarted there",
                c.from,
                c.confirmed,
                c.change.x_rotation_deg,
                c.change.x_translation
            );
            if self.face == Face::Json {
                out.json(&c.change.json())?;
            }
        }
        if let Some(r) = &o.report {
            print_report(r, self.setup, self.time_offset, self.face, &out, unit)?;
        }
        for event in &o.events {
            match self.face {
                Face::Json => out.json(&Event {
                    time_offset_s: self.time_offset,
                    ..*event
                })?,
                Face::Text => out.text(&format!("{}\n", event_text(event, unit)))?,
                _ => {}
            }
        }
        // Said at 200, 400, 800, … poses without a calibration.
        if let Some(why) = &o.stuck {
            out.flush_quietly();
            crate::tell!("{why}");
        }
        Ok(())
    }

    /// Skips a bad line with its message, or stops with it (`--on-bad-line stop`).
    fn bad_line(&mut self, e: handeye::Error) -> Result<()> {
        if self.on_bad_line == OnBadLine::Skip && matches!(e, handeye::Error::Parse { .. }) {
            // A record with `detections` and no camera pose (the pose reader's remedy for it):
            // one for `online --intrinsics`.
            self.on_pixels += usize::from(e.remedy() == Some(handeye::Remedy::Pixels));
            let message = match e.remedy() {
                Some(r) => format!("skipped: {e}; {}", crate::faces::remedy(r, "online")),
                None => format!("skipped: {e}"),
            };
            show(self.bad_lines.tell(), "bad lines", message, &self.out);
            Ok(())
        } else {
            self.out.flush_quietly();
            Err(e.into())
        }
    }
}

/// Shows a message of one kind as the library's thinning says, after the lines of `out` before
/// it.
fn show(tell: Tell, what: &str, message: String, out: &LineOut) {
    if tell.told() {
        out.flush_quietly();
        crate::tell!("{message}");
    }
    if tell == Tell::NowThenThinned {
        crate::tell!(
            "further {what} are counted and shown only at the 2^k-th (the count is given at the end)"
        );
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

/// Tells on stderr which length unit the run uses once it is known, and that it is not yet
/// when the first pose's size (at input line `line`) fits neither unit.
fn tell_unit(told: UnitTold, line: usize) {
    match told {
        UnitTold::Known {
            unit: Unit::AsGiven,
            d_max,
            ..
        } => crate::tell!("length unit: as given (d_max = {d_max})"),
        UnitTold::Known {
            unit,
            inferred_at,
            d_max,
        } => {
            let unit = match unit {
                Unit::Millimetre => "millimetres",
                _ => "metres",
            };
            let how = match inferred_at {
                Some(pose) => format!("inferred from pose {pose}; --unit m|mm to set it"),
                None => "--unit".to_string(),
            };
            crate::tell!("length unit: {unit} ({how}); d_max = {d_max}");
        }
        UnitTold::Unknown { sizes, d_max } => crate::tell!(
            "warning: cannot tell the length unit from the first pose (line {line}: translations of {:.4} and {:.4} fit neither metres nor millimetres); d_max stays {d_max} until a pose tells: pass --unit m or --unit mm, or --d-max in your unit",
            sizes[0],
            sizes[1],
        ),
    }
}

/// The stderr summary: what the events showed, or why there was none.
fn summary(calibrator: &OnlineCalibrator, last: Option<&Report>, bad_lines: usize) -> String {
    let s = calibrator.summary();
    let bad = if bad_lines > 0 {
        format!(", {bad_lines} bad line(s) skipped")
    } else {
        String::new()
    };
    let bad = if s.unit == Unit::Auto && s.poses > 0 {
        format!(
            "{bad}; the length unit was never told by the data (d_max {} was used: pass --unit)",
            s.d_max
        )
    } else {
        bad
    };
    let Some(tracked) = s.tracked else {
        let last = s
            .last_x
            .map_or("none".to_string(), |x| describe(&x, s.unit));
        let quiet = s.stuck.map_or(String::new(), |why| format!("\n{why}"));
        return format!(
            "{} calibration(s) from {} pose(s){bad}; last X: {last}{quiet}",
            s.calibrations, s.poses
        );
    };
    let repeats = match tracked.repeats {
        0 => String::new(),
        n => format!(" ({n} at the robot pose of the pose before, each counted with it)"),
    };
    let counts = format!(
        "{} pose(s){repeats}{bad}, {} held out, {} change(s)",
        s.poses, tracked.held_out, tracked.changes
    );
    let Some(r) = last else {
        return format!("no estimate from {counts}: {}", no_estimate(calibrator));
    };
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
        estimate_words(r, s.unit)
    )
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
