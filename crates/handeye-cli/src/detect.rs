//! `handeye detect FOLDER --target SPEC`: the target's points found in each image of a ViSP
//! recording, written as the JSON Lines records with `detections` that the pixel path reads (and,
//! with `--intrinsics`, each image's `camera_from_target`, which the pose path reads). One line
//! per image on stderr; an image where the target is not found whole costs its line, not the run.

use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Result;
use clap::Args as ClapArgs;
use handeye::detect::{ImageRecord, Target, frames, read_visp_images};
use handeye::{Error, Frame, Intrinsics, Setup};
use serde_json::{Value, json};

/// Options of `handeye detect`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// A ViSP recording: a folder of `<prefix>image-<i>.png` (or .jpg) and the robot's pose at
    /// each, `<prefix>pose_rPe_<i>.yaml`.
    #[arg(value_name = "FOLDER")]
    input: PathBuf,
    #[command(flatten)]
    target: TargetArgs,
    /// Camera on the gripper or fixed: with --intrinsics, the robot's motion tells each image's
    /// pose of the target from its mirror image, by the setup's equation [default: eye-in-hand]
    #[arg(long, value_parser = crate::values::named::<Setup>())]
    setup: Option<Setup>,
}

/// The target and the camera, shared with `calibrate --target`.
#[derive(ClapArgs, Debug, Clone)]
pub struct TargetArgs {
    /// The target in the images: `chessboard:COLSxROWS:SQUARE` (inner corners, a square's side in
    /// the poses' unit; COLS + ROWS odd), or `apriltag36h11:SIZE` (one tag, its black square's
    /// side), e.g. `chessboard:9x6:0.0236`.
    #[arg(long, value_name = "SPEC", value_parser = parse_target)]
    pub target: Target,
    /// The camera's intrinsics (OpenCV YAML, ROS camera_info or ViSP's camera XML): each image's
    /// `camera_from_target` is added, the pose of the target the robot's motion agrees with.
    #[arg(long, value_name = "FILE")]
    pub intrinsics: Option<PathBuf>,
}

/// `--target`'s parser: the library's words for a bad spec.
pub fn parse_target(spec: &str) -> std::result::Result<Target, String> {
    spec.parse().map_err(|e: Error| e.to_string())
}

/// Runs the command: the records on stdout.
pub fn run(args: Args) -> Result<()> {
    let camera = args
        .target
        .intrinsics
        .as_ref()
        .map(Intrinsics::read)
        .transpose()?;
    let setup = args.setup.unwrap_or_default();
    let found = detected(&args.input, &args.target.target, camera.as_ref(), setup)?;
    let mut out = std::io::stdout().lock();
    for (record, frame) in &found {
        writeln!(out, "{}", record_line(record, frame))?;
    }
    out.flush()?;
    Ok(())
}

/// The images of `folder` where the target is found whole, each with its frame (and, with the
/// `camera`, its pose of the target), each image told on stderr (`<image>: 54 points`, or why
/// not); refused when no image shows it.
pub fn detected(
    folder: &Path,
    target: &Target,
    camera: Option<&Intrinsics>,
    setup: Setup,
) -> Result<Vec<(ImageRecord, Frame)>> {
    let records = read_visp_images(folder)?;
    let total = records.len();
    let mut found = Vec::with_capacity(total);
    for (record, frame) in records.iter().zip(frames(&records, target, camera, setup)) {
        match frame {
            Ok(frame) => {
                crate::tell!(
                    "{}: {} points of {target}",
                    record.image.display(),
                    frame.detections.pixels.len()
                );
                found.push((record.clone(), frame));
            }
            Err(e) => crate::tell!("{e}: left out"),
        }
    }
    crate::tell!(
        "{} of {total} image(s) with the target ({target})",
        found.len()
    );
    if found.is_empty() {
        return Err(Error::InvalidParameter {
            name: "target",
            message: format!(
                "no image of {} shows the whole target {target}",
                folder.display()
            ),
        }
        .into());
    }
    Ok(found)
}

/// One record: the image, the robot's pose, the camera's pose (with intrinsics) and the
/// detections.
fn record_line(record: &ImageRecord, frame: &Frame) -> Value {
    let mut line = json!({
        "image": record.image.display().to_string(),
        "base_from_gripper": matrix(&frame.base_from_gripper),
    });
    if let Some(pose) = &frame.camera_from_target {
        line["camera_from_target"] = matrix(pose);
    }
    let d = &frame.detections;
    line["detections"] = json!({ "target": d.target, "pixels": d.pixels });
    line
}

/// The 4×4 matrix, row-major, as the pose readers read it.
fn matrix(t: &handeye::Transform) -> Value {
    json!(handeye::TransformJson::from(t).matrix)
}
