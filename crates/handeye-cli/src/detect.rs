//! `handeye detect FOLDER --target SPEC`: the target's points found in each image of a ViSP
//! recording, written as the JSON Lines records with `detections` that the pixel path reads (and,
//! with `--intrinsics`, each image's `camera_from_target`, which the pose path reads). One line
//! per image on stderr; an image where the target is not found whole costs its line, not the run.

use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Result;
use clap::Args as ClapArgs;
use handeye::detect::{ImageRecord, Target, camera_from_target, detect_all, read_visp_images};
use handeye::{Detections, Error, Intrinsics};
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
    /// `camera_from_target` is added, the pose of the target that fits its pixels best.
    #[arg(long, value_name = "FILE")]
    pub intrinsics: Option<PathBuf>,
}

/// `--target`'s parser: the library's words for a bad spec.
pub fn parse_target(spec: &str) -> std::result::Result<Target, String> {
    spec.parse().map_err(|e: Error| e.to_string())
}

/// Runs the command: the records on stdout.
pub fn run(args: Args) -> Result<()> {
    let lines = detected(&args.input, &args.target)?;
    let mut out = std::io::stdout().lock();
    for line in lines {
        writeln!(out, "{line}")?;
    }
    out.flush()?;
    Ok(())
}

/// The JSON Lines records of the images of `folder` where the target is found whole, each line
/// told on stderr (`<image>: 54 points`, or why not); refused when no image shows it.
pub fn detected(folder: &Path, args: &TargetArgs) -> Result<Vec<String>> {
    let camera = args.intrinsics.as_ref().map(Intrinsics::read).transpose()?;
    let records = read_visp_images(folder)?;
    let found = detect_all(&records, &args.target);
    let mut lines = Vec::with_capacity(records.len());
    for (record, found) in records.iter().zip(found) {
        let name = record.image.display();
        match found {
            Ok(d) => {
                let line = record_line(record, &d, camera.as_ref());
                match line {
                    Some(line) => {
                        crate::tell!("{name}: {} points of {}", d.pixels.len(), args.target);
                        lines.push(line.to_string());
                    }
                    None => crate::tell!(
                        "{name}: left out: the {} points give no pose of the target",
                        d.pixels.len()
                    ),
                }
            }
            Err(e) => crate::tell!("{e}: left out"),
        }
    }
    crate::tell!(
        "{} of {} image(s) with the target ({})",
        lines.len(),
        records.len(),
        args.target
    );
    if lines.is_empty() {
        return Err(Error::InvalidParameter {
            name: "target",
            message: format!(
                "no image of {} shows the whole target {}",
                folder.display(),
                args.target
            ),
        }
        .into());
    }
    Ok(lines)
}

/// One record: the image, the robot's pose, the camera's pose (with intrinsics) and the
/// detections; `None` when the intrinsics are given and no pose fits the pixels.
fn record_line(record: &ImageRecord, d: &Detections, camera: Option<&Intrinsics>) -> Option<Value> {
    let mut line = json!({
        "image": record.image.display().to_string(),
        "base_from_gripper": matrix(&record.base_from_gripper),
    });
    if let Some(camera) = camera {
        line["camera_from_target"] = matrix(&camera_from_target(d, camera)?);
    }
    line["detections"] = json!({ "target": d.target, "pixels": d.pixels });
    Some(line)
}

fn matrix(t: &handeye::Transform) -> Value {
    let m = t.to_homogeneous();
    Value::from(
        (0..4)
            .map(|r| (0..4).map(|c| m[(r, c)]).collect::<Vec<f64>>())
            .collect::<Vec<_>>(),
    )
}
