//! `handeye calibrate`: one batch solve over a whole recording, with its uncertainty, or a refusal
//! that says why and what to do.

use anyhow::Result;
use clap::Args as ClapArgs;
use clap::builder::PossibleValuesParser;
use handeye::{Assessment, Fix, Options, Problem, Report, calibrate};
use handeye::{Frame, HandEyeReport, Intrinsics, RobotWorldReport};

use handeye::TsaiOptions;
use handeye::{Error, Method, Pairing, PosePair, Setup};
use handeye::{Named, RobotWorldMethod};

use crate::faces::{self, Face, Published, length_unit};
use crate::input::{InputArgs, read_all};
use crate::output::{Questionable, print_json, print_text};
use crate::publish::Publication;
use crate::values;
use handeye::io::CameraMount;
use handeye::io::Recording;

/// Options of `handeye calibrate`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    #[command(flatten)]
    input: InputArgs,
    /// Solver: a hand–eye method (default andreff), or with --robot-world a robot-world one
    /// (shah, li or refine; default refine).
    #[arg(long, value_parser = any_method())]
    method: Option<String>,
    /// Robot-world–hand-eye calibration (A X = Z B): solve X and the target's pose together
    /// from every pose once (`base_from_target` eye-in-hand, `gripper_from_target` eye-to-hand),
    /// instead of X alone from motions between poses.
    #[arg(long)]
    robot_world: bool,
    /// Motions from every pair i < j (the default, as OpenCV does: the most accurate on real and
    /// realistic pose sets, and O(n)), or from consecutive poses (the paper's pairing).
    #[arg(long, value_parser = values::named::<Pairing>())]
    pairs: Option<Pairing>,
    /// Leave out the poses that disagree with the others (their motions' robot and camera
    /// rotation angles or pitches differ beyond the data's own noise).
    #[arg(long)]
    reject_outliers: bool,
    /// A pose whose motions' robot and camera rotation angles differ by more than this (median,
    /// degrees) is an outlier whatever the noise level.
    #[arg(long, default_value_t = Options::default().outlier_deg, value_parser = values::angle_deg)]
    outlier_deg: f64,
    /// Read the input another way: `auto` applies a reading that fits far better when one is
    /// found; `as-given` keeps the input as it is (a better reading is then a warning, not a
    /// refusal); or another reading (robot-inverted, robot-wxyz, robot-mm, …). Without it (or
    /// with `refuse`), a reading that fits far better refuses the calibration (exit 3) and names
    /// the fix.
    #[arg(long, value_parser = values::named::<Fix>())]
    fix: Option<Fix>,
    /// Bootstrap replicates behind the reported uncertainty.
    #[arg(long, default_value_t = Options::default().replicates, value_parser = values::count(*Options::REPLICATES_RANGE.start() as u64, *Options::REPLICATES_RANGE.end() as u64))]
    bootstrap: usize,
    /// Drop the motions OpenCV's Tsai drops: robot or camera rotation with 2·sin(θ/2) outside
    /// [0.3, 1.7] (with --method tsai).
    #[arg(long)]
    tsai_opencv_filter: bool,
    /// Output: the JSON object; a summary for a person (`text`); easy_handeye2's calibration
    /// YAML (with translation {x,y,z} and rotation {x,y,z,w}); a `static_transform_publisher`
    /// line and launch snippet (`ros2`); a URDF `<joint>` (`urdf`) [default: text on a terminal,
    /// JSON otherwise].
    #[arg(long, value_parser = values::named::<Face>())]
    output: Option<Face>,
    /// Exit 5 when X is found but the verdict is questionable (a caution stands), after printing
    /// the result: for scripts that must not use such an X.
    #[arg(long)]
    strict: bool,
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
    /// The point whose error through X `uncertainty.at_point` gives: X,Y,Z in the camera frame,
    /// the input's unit [default: the median target position seen by the camera].
    #[arg(long, value_name = "X,Y,Z", value_parser = values::point)]
    point: Option<[f64; 3]>,
    /// A prior on a component of X's translation, for a low-DOF robot (a SCARA, a 4- or 5-axis
    /// arm, a gantry with one wrist joint) whose motions all rotate about one axis and so never
    /// determine X's translation along it: NAME=VALUE (exact) or NAME=VALUE+-SIGMA, NAME one of
    /// tx, ty, tz (in X's parent frame: the gripper's eye-in-hand, the robot base's eye-to-hand;
    /// the input's length unit), e.g. `--prior tz=0.12+-0.002`. Repeatable. A prior on a
    /// component the motions determine is checked, not used.
    #[arg(long, value_name = "NAME=VALUE[+-SIGMA]", value_parser = values::prior)]
    prior: Vec<handeye::Prior>,
    /// Also write a page for a person: the held-out gap of every pose, the rotation axes and the
    /// rotation angles of the motions (one self-contained HTML file).
    #[arg(long, value_name = "FILE.html")]
    report: Option<std::path::PathBuf>,
    /// The camera's intrinsics, for `--method reprojection`: OpenCV FileStorage YAML
    /// (`camera_matrix`, `distortion_coefficients`) or a ROS `camera_info` YAML (`k`, `d`).
    #[arg(long, value_name = "FILE")]
    intrinsics: Option<std::path::PathBuf>,
    /// With --method reprojection: refine the camera's intrinsics with X (fx, fy, cx, cy, k1, k2,
    /// p1, p2; k3 kept as given), reported with their sigmas (`reprojection.intrinsics`) and
    /// accounted for in X's uncertainty. Refused (exit 2) when the frames do not determine them:
    /// the detections must reach the image's corners and the target tilt about both image axes,
    /// over more than 20 frames.
    #[arg(long)]
    refine_intrinsics: bool,
    /// The robot's DH table, the one its poses are reported through (JSON: `convention`
    /// standard|modified, `a`, `d`, `alpha`, `theta_offset`, optional `sign` and `tool`; the poses'
    /// unit and radians). With every pose's joint angles, the systematic-error test also asks
    /// whether the residuals follow an error of the table's parameters: an uncalibrated robot is
    /// then seen at 1 mm. Refused (exit 2) when it does not turn the hand as the poses do.
    #[arg(long, value_name = "FILE")]
    robot_model: Option<std::path::PathBuf>,
    /// The uncertainty you need: a one-sigma rotation in degrees and a translation in the input's
    /// unit (`0.2,0.001`), as `advise --goal` takes it. An X whose one-sigma uncertainty is above
    /// it in either is not `good`: the verdict says whether it is met (JSON `goal.met`).
    #[arg(long, value_name = "DEGREES,LENGTH", value_parser = values::goal)]
    goal: Option<handeye::Sizes>,
    /// Calibrate from images: INPUT is a ViSP folder of images and robot poses, in which the
    /// target is found as `handeye detect --target SPEC` finds it (`chessboard:COLSxROWS:SQUARE`
    /// or `apriltag36h11:SIZE`), with --intrinsics FILE; then the pose path on each image's pose
    /// of the target, or the pixel path with --method reprojection. Messages name each pose by its
    /// image; `handeye detect` writes the records found.
    #[arg(long, value_name = "SPEC", value_parser = crate::detect::parse_target)]
    target: Option<handeye::detect::Target>,
}

/// Refuses the flags of the calibration on the pixels without `--method reprojection` (exit 2).
fn pixels_only(args: &Args) -> Result<()> {
    for (flag, given, words) in [
        (
            "intrinsics",
            // With --target, the intrinsics find each image's pose of the target.
            args.intrinsics.is_some() && args.target.is_none(),
            "--intrinsics is read by",
        ),
        (
            "refine-intrinsics",
            args.refine_intrinsics,
            "--refine-intrinsics refines the intrinsics on the pixels: it needs",
        ),
    ] {
        if given {
            return Err(Error::InvalidParameter {
                name: flag,
                message: format!(
                    "{words} --method reprojection (calibration on the pixels of the detections)"
                ),
            }
            .into());
        }
    }
    Ok(())
}

/// The names of `--method`: the hand–eye methods and the robot-world ones, each once.
fn any_method() -> PossibleValuesParser {
    let robot_world = RobotWorldMethod::ALL.iter().map(|m| m.name());
    let mut names: Vec<&'static str> = Method::WITH_PIXELS.iter().map(|m| m.name()).collect();
    names.extend(robot_world.filter(|m| m.parse::<Method>().is_err()));
    PossibleValuesParser::new(names)
}

/// Runs the command: one path for every problem and input kind. The input is read (pose pairs,
/// or the target's detections with the camera's intrinsics for `--method reprojection`), one
/// [`Options`] built, one [`calibrate`] called, and its report printed in the face asked.
pub fn run(args: Args) -> Result<()> {
    let options = Options {
        // On the pixels the library refuses it, after it is read.
        robot_model: crate::input::robot_model(args.robot_model.as_deref())?,
        ..options(&args)?
    };
    let setup = args.input.setup();
    let recorded = read(&args, &options)?;
    let face = Face::chosen(args.output);
    let tsai = options.tsai;
    let report = match &recorded {
        Recorded::Poses(recording) => {
            let options = Options {
                pose_names: recording.names.clone(),
                written: recording.written,
                joints: recording.joints.clone(),
                ..options
            };
            recording
                .offset_checked(calibrate(&recording.poses, setup, &options))
                .map_err(|e| refused(&args, e, face, &recording.poses, setup))?
        }
        Recorded::Pixels {
            camera,
            frames,
            names,
        } => {
            let options = Options {
                pose_names: names.clone(),
                refine_intrinsics: args.refine_intrinsics,
                ..options
            };
            let input = handeye::Input::Pixels { frames, camera };
            calibrate(input, setup, &options).map_err(|e| refused_on_pixels(e, face))?
        }
    };
    match report {
        Report::HandEye(report) => match &recorded {
            Recorded::Poses(recording) => print_hand_eye(&args, &report, recording, (face, tsai)),
            Recorded::Pixels {
                camera,
                frames,
                names,
            } => print_on_pixels(&args, &report, (camera, frames, names), face),
        },
        Report::RobotWorld(report) => print_robot_world(&args, &report, &recorded, face),
    }
}

/// What `calibrate` calibrates from: a recording of pose pairs, or the target's detections with
/// the camera's intrinsics (`--method reprojection`). One per run: not worth a box.
#[allow(clippy::large_enum_variant)]
enum Recorded {
    /// A recording of pose pairs (names, written directions, joints, clock, the camera's mount).
    Poses(Recording),
    /// The records with detections, each named `file:line`, and the camera.
    Pixels {
        camera: Intrinsics,
        frames: Vec<Frame>,
        names: Vec<String>,
    },
}

/// The frames of the images of a ViSP folder (`--target`), found in the images with the camera of
/// `--intrinsics`: each named by its image, as the pose pairs (each image's pose of the target
/// as the robot's motion tells it) or, for `--method reprojection`, the frames themselves.
fn from_images(
    args: &Args,
    target: &handeye::detect::Target,
    options: &Options,
) -> Result<Recorded> {
    let refuse = |message: &str| -> anyhow::Error {
        Error::InvalidParameter {
            name: "target",
            message: message.into(),
        }
        .into()
    };
    let Some(intrinsics) = &args.intrinsics else {
        return Err(refuse(
            "--target finds the target in the images, whose poses need the camera's intrinsics: give --intrinsics FILE",
        ));
    };
    let Some(folder) = &args.input.input else {
        return Err(refuse(
            "--target reads a folder of images: give it as INPUT",
        ));
    };
    output_frames(args)?;
    if let Some(path) = &args.report {
        crate::report::check_writable(path)?;
    }
    let camera = Intrinsics::read(intrinsics)?;
    let found = crate::detect::detected(folder, target, Some(&camera), args.input.setup())?;
    let names = found
        .iter()
        .map(|(record, _)| record.image.display().to_string())
        .collect();
    let frames: Vec<Frame> = found.into_iter().map(|(_, frame)| frame).collect();
    if on_pixels(options) {
        return Ok(Recorded::Pixels {
            camera,
            frames,
            names,
        });
    }
    let poses: Vec<handeye::PosePair> = frames
        .iter()
        .filter_map(|f| {
            Some(handeye::PosePair {
                base_from_gripper: f.base_from_gripper,
                camera_from_target: f.camera_from_target?,
            })
        })
        .collect();
    pixels_only(args)?;
    enough_for(args, options, poses.len())?;
    Ok(Recorded::Poses(Recording {
        poses,
        names,
        ..Recording::default()
    }))
}

/// Whether the options ask for the fit on the pixels (`--method reprojection`).
fn on_pixels(options: &Options) -> bool {
    matches!(
        options.problem,
        Problem::HandEye(Method::Reprojection)
            | Problem::RobotWorld(RobotWorldMethod::Reprojection)
    )
}

/// Reads the input the options ask for, after the checks that need no input (the flags of the
/// pixels, the frame names, `--report`'s path): pose pairs (enough of them for the problem), or
/// the records with detections and the intrinsics.
fn read(args: &Args, options: &Options) -> Result<Recorded> {
    if let Some(target) = &args.target {
        return from_images(args, target, options);
    }
    if on_pixels(options) {
        let (camera, frames, names) =
            pixel_input(&args.input, args.intrinsics.as_ref(), args.report.as_ref())?;
        output_frames(args)?;
        return Ok(Recorded::Pixels {
            camera,
            frames,
            names,
        });
    }
    pixels_only(args)?;
    // The frame names and the name are checked before the input is read, and so is the report's
    // path.
    output_frames(args)?;
    if let Some(path) = &args.report {
        crate::report::check_writable(path)?;
    }
    let recording = read_all(&args.input, options.fix.reading())?;
    enough_for(args, options, recording.poses.len())?;
    Ok(Recorded::Poses(recording))
}

/// Refuses fewer pose pairs than the problem needs.
fn enough_for(args: &Args, options: &Options, poses: usize) -> Result<()> {
    let (need, what) = match options.problem {
        Problem::HandEye(_) => (2, "to make a motion"),
        Problem::RobotWorld(_) => (3, "to determine X and the target's pose"),
    };
    enough(&args.input, poses, need, what)
}

/// Prints a hand–eye result on pose pairs in the face asked for, writes `--report`, and sets the
/// exit code (`--strict`).
fn print_hand_eye(
    args: &Args,
    report: &HandEyeReport,
    recording: &Recording,
    (face, tsai): (Face, TsaiOptions),
) -> Result<()> {
    let (poses, written) = (&recording.poses, recording.written);
    let (time_offset, time_offset_sigma) = (recording.time_offset, recording.time_offset_sigma);
    let setup = report.setup;
    let frames = output_frames(args)?;
    // The unit of the poses as solved: a `--fix robot-mm` (or `auto`) reading has made them metres.
    let unit = length_unit(&report.reading.applied.apply(poses, written));
    tell_rejected(
        report.outliers.rejected,
        report.outliers.poses.len(),
        report.poses,
    );
    if args.pairs.is_none() && (args.input.robot.is_some() || args.input.is_bag()) {
        crate::tell!(
            "pairs: every pair of the {} stream samples (consecutive frames barely move; `--pairs consecutive` for the paper's pairing)",
            report.poses
        );
    }
    if let Some(note) = report.tsai_filter_note(tsai) {
        crate::tell!(
            "note: {note}; `--method tsai` without `--tsai-opencv-filter` keeps every motion"
        );
    }
    // The text face lists the warnings itself.
    tell_warnings(&report.warnings, face);
    let source = format!("calibrate, method {}", report.method);
    // The ROS outputs are in metres whatever the input (the text and JSON keep its unit).
    let ros = matches!(face, Face::Yaml | Face::Ros2 | Face::Urdf) || args.input.is_bag();
    let ros_unit = if ros { faces::ros_unit(unit) } else { unit };
    let mount = recording.camera_mount.as_ref();
    let publication = publication(args, &report.transform, &frames, mount);
    let published = publication.of(Published::of(report, &source, ros_unit));
    let to = &publication.frames;
    if args.input.is_bag() {
        publication.tell(published, face != Face::Ros2);
    }
    let summary = faces::text(report, &frames, unit);
    match face {
        Face::Text => print_text(&summary)?,
        Face::Yaml => print_text(&faces::yaml(published, to, Some(report)))?,
        Face::Ros2 => print_text(&faces::ros2(published, to))?,
        Face::Urdf => print_text(&faces::urdf(published, to))?,
        Face::Json => print_json(&WithTimeOffset {
            report,
            time_offset_s: time_offset,
            time_offset_sigma_s: time_offset_sigma,
            publish: publication.json(),
        })?,
    }
    let page = crate::report::RunPage {
        poses,
        names: &recording.names,
        written,
        setup,
        unit,
        summary,
    };
    after_result(args, report.verdict, |path| {
        crate::report::write_calibrate(path, &page, report)
    })
}

/// Says how many outlier poses `--reject-outliers` left out, when it left any.
fn tell_rejected(rejected: bool, outliers: usize, used: usize) {
    if rejected && outliers > 0 {
        crate::tell!("rejected {outliers} outlier pose(s) of {}", outliers + used);
    }
}

/// The warnings on stderr, but in the text face, which lists them itself.
fn tell_warnings(warnings: &[handeye::Warning], face: Face) {
    if face != Face::Text {
        for w in warnings {
            crate::tell!("warning: {}", faces::warning(w));
        }
    }
}

/// After the result is printed: the report page (last, so that a path that cannot be written
/// loses nothing computed), then `--strict`'s exit 5 on a questionable verdict.
fn after_result(
    args: &Args,
    verdict: Assessment,
    write: impl FnOnce(&std::path::Path) -> Result<()>,
) -> Result<()> {
    if let Some(path) = &args.report {
        write(path)?;
        crate::tell!("wrote {}", path.display());
    }
    if args.strict && verdict == Assessment::Questionable {
        return Err(Questionable.into());
    }
    Ok(())
}

/// Whether the input file's first record carries `detections` (a JSON Lines file).
fn carries_detections(input: &InputArgs) -> bool {
    use std::io::BufRead;
    let Some(path) = &input.input else {
        return false;
    };
    let Ok(file) = std::fs::File::open(path) else {
        return false;
    };
    std::io::BufReader::new(file)
        .lines()
        .take(50)
        .map_while(std::result::Result::ok)
        .find(|l| l.trim_start().starts_with('{'))
        .is_some_and(|l| l.contains("\"detections\""))
}

/// The pixel calibrations' input (`calibrate` and `verify` on the pixels): the intrinsics and the
/// records with detections (a JSON Lines file), each record named `file:line`; the input flags
/// that do not apply there refused (exit 2; the library refuses the options it does not take);
/// `--report` checked writable first.
pub(crate) fn pixel_input(
    input: &InputArgs,
    intrinsics: Option<&std::path::PathBuf>,
    report: Option<&std::path::PathBuf>,
) -> Result<(handeye::Intrinsics, Vec<handeye::Frame>, Vec<String>)> {
    let refuse = |message: String| -> anyhow::Error {
        Error::InvalidParameter {
            name: "method",
            message,
        }
        .into()
    };
    let given = [
        ("--robot/--camera streams", input.robot.is_some()),
        // The records' JSON fields name their own conventions (`kuka_abc_deg`, `rvec`, …).
        ("--rotation", !input.rotation.is_empty()),
    ];
    if let Some((flag, _)) = given.iter().find(|(_, given)| *given) {
        return Err(refuse(format!(
            "{flag} is not offered with --method reprojection (yet): give a JSON Lines file with `detections`, or a ROS 2 recording of a tag's detections"
        )));
    }
    if let Some(path) = report {
        crate::report::check_writable(path)?;
    }
    if let Some(read) = crate::input::read_bag_pixels(input)? {
        let camera = match (intrinsics, read.intrinsics) {
            (Some(file), _) => handeye::Intrinsics::read(file)?,
            (None, Some(camera)) => camera,
            (None, None) => {
                return Err(refuse(
                    "reprojection needs the camera's intrinsics: the recording has no sensor_msgs/CameraInfo topic (…camera_info); give --intrinsics FILE (OpenCV YAML or ROS camera_info) or --camera-info-topic TOPIC".into(),
                ));
            }
        };
        return Ok((camera, read.frames, read.names));
    }
    let Some(intrinsics) = intrinsics else {
        return Err(refuse(
            "reprojection needs the camera's intrinsics: --intrinsics FILE (OpenCV YAML or ROS camera_info)".into(),
        ));
    };
    let Some(path) = &input.input else {
        return Err(refuse(
            "reprojection needs a JSON Lines file with `detections`".into(),
        ));
    };
    let camera = handeye::Intrinsics::read(intrinsics)?;
    let source = handeye::io::Source::File {
        path: path.clone(),
        format: handeye::io::Format::Jsonl,
    };
    let read =
        handeye::io::FrameRecording::read(&source, &handeye::io::RecordingOptions::default())?;
    Ok((camera, read.frames, read.names))
}

/// The refusals of a solve on the pixels, said in the text face too.
fn refused_on_pixels(e: Error, face: Face) -> anyhow::Error {
    if face == Face::Text
        && matches!(
            e,
            Error::Degenerate { .. }
                | Error::TooFewMotions { .. }
                | Error::Misread { .. }
                | Error::PixelsUnfit { .. }
        )
    {
        if let Err(printed) = print_text(&faces::refused(&e)) {
            return printed;
        }
        return crate::output::said(&e.into());
    }
    e.into()
}

/// The camera poses a solve on the pixels started from (a pixel report's `reprojection`).
fn start_poses(reprojection: Option<&handeye::ReprojectionSummary>) -> &[handeye::Transform] {
    reprojection.map_or(&[], |r| &r.start_poses)
}

/// Prints a hand–eye result on the pixels in the face asked for, writes `--report` (with the
/// image's detections), and sets the exit code (`--strict`).
fn print_on_pixels(
    args: &Args,
    report: &HandEyeReport,
    (camera, frames_read, names): (&Intrinsics, &[Frame], &[String]),
    face: Face,
) -> Result<()> {
    let setup = report.setup;
    let frames = output_frames(args)?;
    let poses = handeye::calibrate::problem::pixels::pose_pairs(
        frames_read,
        start_poses(report.reprojection.as_ref()),
    );
    let unit = length_unit(&poses);
    tell_warnings(&report.warnings, face);
    let source = format!("calibrate, method {}", report.method);
    let ros = matches!(face, Face::Yaml | Face::Ros2 | Face::Urdf);
    let ros_unit = if ros { faces::ros_unit(unit) } else { unit };
    let published = Published::of(report, &source, ros_unit);
    let summary = faces::text(report, &frames, unit);
    match face {
        Face::Text => print_text(&summary)?,
        Face::Yaml => print_text(&faces::yaml(published, &frames, Some(report)))?,
        Face::Ros2 => print_text(&faces::ros2(published, &frames))?,
        Face::Urdf => print_text(&faces::urdf(published, &frames))?,
        Face::Json => print_json(report)?,
    }
    let page = crate::report::RunPage {
        poses: &poses,
        names,
        written: handeye::Written::NAMED,
        setup,
        unit,
        summary,
    };
    after_result(args, report.verdict, |path| {
        let image = (camera.width > 0 && camera.height > 0)
            .then(|| (f64::from(camera.width), f64::from(camera.height)));
        crate::report::write_pixels(path, &page, report, image)
    })
}

/// What a robot-world result is printed with, besides the report.
struct RobotWorldInput<'a> {
    poses: &'a [PosePair],
    names: &'a [String],
    written: handeye::Written,
    unit: Option<handeye::Unit>,
    mount: Option<&'a CameraMount>,
    /// `--time-offset` and its one-sigma, seconds.
    time_offset: (Option<f64>, Option<f64>),
}

/// Prints a robot-world result in the face asked for, writes `--report`, and sets the exit code
/// (`--strict`).
fn print_robot_world(
    args: &Args,
    report: &RobotWorldReport,
    recorded: &Recorded,
    face: Face,
) -> Result<()> {
    let pixel_poses;
    let input = match recorded {
        Recorded::Poses(recording) => {
            let (poses, written) = (&recording.poses, recording.written);
            let unit = length_unit(&report.reading.applied.apply(poses, written));
            tell_rejected(
                report.outliers.rejected,
                report.outliers.poses.len(),
                report.poses,
            );
            RobotWorldInput {
                poses,
                names: &recording.names,
                written,
                unit,
                mount: recording.camera_mount.as_ref(),
                time_offset: (recording.time_offset, recording.time_offset_sigma),
            }
        }
        Recorded::Pixels { frames, names, .. } => {
            pixel_poses = handeye::calibrate::problem::pixels::pose_pairs(
                frames,
                start_poses(report.reprojection.as_ref()),
            );
            RobotWorldInput {
                poses: &pixel_poses,
                names,
                written: handeye::Written::NAMED,
                unit: length_unit(&pixel_poses),
                mount: None,
                time_offset: (None, None),
            }
        }
    };
    let setup = report.setup;
    let frames = output_frames(args)?;
    let unit = input.unit;
    tell_warnings(&report.warnings, face);
    let source = format!("calibrate, robot-world method {}", report.method);
    let ros = matches!(face, Face::Ros2 | Face::Urdf);
    let ros_unit = if ros { faces::ros_unit(unit) } else { unit };
    let publication = publication(args, &report.transform, &frames, input.mount);
    // X, then the target's pose: `base_from_target` (eye-in-hand) or `gripper_from_target`.
    let x = publication.of(Published {
        x: &report.transform,
        frame: &report.frame,
        setup,
        source: &source,
        unit: ros_unit,
        note: None,
        warning: None,
    });
    let target = Published {
        x: &report.target_transform,
        frame: &report.target.frame,
        note: None,
        warning: None,
        ..x
    };
    if args.input.is_bag() {
        publication.tell(x, false);
    }
    let (parent, child) = faces::target_frames(setup, &frames);
    let target_frames = faces::Frames {
        parent,
        child,
        ..frames.clone()
    };
    let summary = faces::robot_world_text(report, &frames, unit);
    match face {
        Face::Text => print_text(&summary)?,
        // The YAML lists X, the target, their one-sigma and the residuals.
        Face::Yaml => print_text(&faces::robot_world_yaml(
            report,
            &publication.frames,
            &target_frames,
        ))?,
        Face::Ros2 => print_text(&format!(
            "{}\n{}",
            faces::ros2(x, &publication.frames),
            faces::ros2(target, &target_frames)
        ))?,
        Face::Urdf => print_text(&format!(
            "{}{}",
            faces::urdf(x, &publication.frames),
            faces::urdf(target, &target_frames)
        ))?,
        Face::Json => print_json(&WithTimeOffset {
            report,
            time_offset_s: input.time_offset.0,
            time_offset_sigma_s: input.time_offset.1,
            publish: publication.json(),
        })?,
    }
    let page = crate::report::RunPage {
        poses: input.poses,
        names: input.names,
        written: input.written,
        setup,
        unit,
        summary,
    };
    after_result(args, report.verdict, |path| {
        crate::report::write_robot_world(path, &page, report)
    })
}

/// A refusal: said in the text face, drawn in `--report` (the motions' axes show what they
/// lack), and returned as the error that sets the exit code.
fn refused(args: &Args, e: Error, face: Face, poses: &[PosePair], setup: Setup) -> anyhow::Error {
    let refusal = matches!(
        e,
        Error::Degenerate { .. }
            | Error::TooFewMotions { .. }
            | Error::Misread { .. }
            | Error::Untrusted { .. }
            | Error::OffsetNotFound { .. }
    );
    let misread = matches!(e, Error::Misread { .. });
    let said = refusal && face == Face::Text;
    let e = anyhow::Error::from(e);
    let e = if misread && carries_detections(&args.input) {
        e.context(
            "these records carry `detections`: the PnP poses of a planar target flip (the planar ambiguity), which the pose-based check can take for inverted poses; calibrate on the pixels, where the reading is checked on the detections: --method reprojection --intrinsics FILE",
        )
    } else {
        e
    };
    if refusal {
        let words = faces::refused_message(&crate::output::error_message(&e));
        if said && let Err(printed) = print_text(&words) {
            return printed;
        }
        if let Some(path) = &args.report {
            match crate::report::write_refused(path, poses, setup, &words) {
                Ok(()) => crate::tell!("wrote {}", path.display()),
                Err(written) => crate::tell!("{written:#}"),
            }
        }
    }
    if said {
        return crate::output::said(&e);
    }
    e
}

/// The library's options from the command line: the problem (`--robot-world`) with its method
/// (`--method`), and the flags every problem shares.
fn options(args: &Args) -> Result<Options> {
    let problem = if args.robot_world {
        Problem::RobotWorld(robot_world_method(args)?)
    } else {
        Problem::HandEye(hand_eye_method(args)?)
    };
    Ok(Options {
        problem,
        // Every pair by default: on pose files it is the more accurate (docs/DECISIONS.md, "all
        // pairs by default"); on streams consecutive samples are a camera period apart, tiny
        // motions whose noise dominates.
        pairing: args.pairs.unwrap_or(Pairing::All),
        tsai: TsaiOptions {
            opencv_filter: args.tsai_opencv_filter,
        },
        reject_outliers: args.reject_outliers,
        outlier_deg: args.outlier_deg,
        fix: args.fix.unwrap_or_default(),
        replicates: args.bootstrap,
        point: args.point,
        priors: args.prior.clone(),
        goal: args.goal,
        ..Options::default()
    })
}

/// The hand–eye method of `--method` (default andreff); a robot-world one asks for
/// `--robot-world`.
fn hand_eye_method(args: &Args) -> Result<Method> {
    Ok(match args.method.as_deref() {
        None => Method::Andreff,
        Some(name) => name.parse::<Method>().map_err(|e| {
            if name.parse::<RobotWorldMethod>().is_ok() {
                Error::InvalidParameter {
                    name: "method",
                    message: format!("`{name}` is a robot-world method: add --robot-world"),
                }
            } else {
                e
            }
        })?,
    })
}

/// The robot-world method of `--method` (default refine), after refusing the hand–eye flags
/// `--robot-world` does not take.
fn robot_world_method(args: &Args) -> Result<RobotWorldMethod> {
    for (flag, given) in [
        ("--pairs", args.pairs.is_some()),
        ("--tsai-opencv-filter", args.tsai_opencv_filter),
    ] {
        if given {
            return Err(Error::InvalidParameter {
                name: "robot-world",
                message: format!("{flag} is not offered with --robot-world (yet)"),
            }
            .into());
        }
    }
    Ok(match args.method.as_deref() {
        None => RobotWorldMethod::Refine,
        Some(name) => name
            .parse::<RobotWorldMethod>()
            .map_err(|_| Error::InvalidParameter {
                name: "method",
                message: format!(
                    "`{name}` is a hand–eye method; with --robot-world use one of {}",
                    RobotWorldMethod::list_names()
                ),
            })?,
    })
}

/// Refuses fewer than `need` pose pairs, naming the input (exit 2).
fn enough(input: &InputArgs, got: usize, need: usize, what: &str) -> Result<()> {
    if got >= need {
        return Ok(());
    }
    Err(Error::Parse {
        file: input
            .input
            .as_ref()
            .map_or("-".into(), |p| p.display().to_string()),
        line: 0,
        field: "-".into(),
        message: format!("{got} pose pair(s): at least {need} are needed {what}"),
        remedy: None,
    }
    .into())
}

/// A report with the clock offset the input was read under (`--time-offset`), as its last field.
#[derive(serde::Serialize)]
struct WithTimeOffset<'a, T> {
    #[serde(flatten)]
    report: &'a T,
    #[serde(skip_serializing_if = "Option::is_none")]
    time_offset_s: Option<f64>,
    /// Its one-sigma, seconds, when it was estimated.
    #[serde(skip_serializing_if = "Option::is_none")]
    time_offset_sigma_s: Option<f64>,
    /// What to publish in tf instead of X, and why, when a recording's tf gives the camera frame
    /// a parent ([`Publication::json`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    publish: Option<serde_json::Value>,
}

/// What the ROS faces publish for `x` between `frames`, given where a recording's tf places the
/// camera frame (see [`crate::publish`]).
fn publication(
    args: &Args,
    x: &handeye::Transform,
    frames: &faces::Frames,
    mount: Option<&CameraMount>,
) -> Publication {
    crate::publish::publication(x, frames, mount, args.child_frame.is_some())
}

/// The frame names X is published under (`--parent-frame`, `--child-frame`) and the name, checked
/// before the input is read.
fn output_frames(args: &Args) -> Result<faces::Frames> {
    Ok(faces::frames(
        &args.input,
        args.parent_frame.as_deref(),
        args.child_frame.as_deref(),
        &args.name,
    )?)
}
