//! From images to detections (issue 54): the target a recording's images show ([`Target`],
//! `--target`), a ViSP recording of images and robot poses ([`read_visp_images`], read by `io`),
//! the target's points found in one image (`detect`, feature `images`) and each image's frame
//! with the camera's pose of them (`frames`). The frames are what the pixel path reads (`Frame`,
//! `Detections`); docs/SPEC.md sec. 7 (`detect`) says the command that writes them.

#[cfg(feature = "images")]
mod apriltag;
#[cfg(feature = "images")]
mod chessboard;
mod target;

pub use crate::io::{ImageRecord, read_visp_images};
pub use target::{MAX_SIDE, TAG_CORNERS, Target};

#[cfg(feature = "images")]
use crate::model::camera::{Detections, Frame, Intrinsics};
#[cfg(feature = "images")]
use crate::model::error::Result;
#[cfg(feature = "images")]
use crate::model::motion::Setup;

/// The largest image side decoded, pixels, and the most bytes a decoded image may take: an
/// image's header cannot ask for more.
pub const MAX_IMAGE_SIDE: u32 = 20_000;
/// See [`MAX_IMAGE_SIDE`].
pub const MAX_IMAGE_BYTES: u64 = 512 << 20;

/// The target's points found in the image file `path`: every point of `target` (a chessboard's
/// inner corners row by row, a tag's four corners), sub-pixel. An image that cannot be read, or
/// in which the target is not found whole, is an error naming the file (`file: what`) and
/// saying what was found.
#[cfg(feature = "images")]
pub fn detect(path: &std::path::Path, target: &Target) -> Result<Detections> {
    let file = path.display().to_string();
    let fail = |message: String| crate::io::parse_error(&file, 0, "-", message);
    let gray = decode(path).map_err(fail)?;
    let pixels = match *target {
        Target::Chessboard { cols, rows, .. } => chessboard::find(&gray, cols, rows),
        Target::AprilTag36h11 { .. } => apriltag::find(gray),
    }
    .map_err(fail)?;
    Ok(Detections {
        target: target.target_points(),
        pixels,
    })
}

/// The image's grey levels (a colour image's luma), within [`MAX_IMAGE_SIDE`] and
/// [`MAX_IMAGE_BYTES`].
#[cfg(feature = "images")]
fn decode(path: &std::path::Path) -> Result<image::GrayImage, String> {
    let mut reader = image::ImageReader::open(path)
        .map_err(|e| format!("cannot open: {e}"))?
        .with_guessed_format()
        .map_err(|e| format!("cannot read: {e}"))?;
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_IMAGE_SIDE);
    limits.max_image_height = Some(MAX_IMAGE_SIDE);
    limits.max_alloc = Some(MAX_IMAGE_BYTES);
    reader.limits(limits);
    let image = reader
        .decode()
        .map_err(|e| format!("not a readable image (PNG or JPEG): {e}"))?;
    Ok(image.to_luma8())
}

/// [`detect`] on every image of `records`, in parallel (rayon), in their order.
#[cfg(feature = "images")]
pub fn detect_all(records: &[ImageRecord], target: &Target) -> Vec<Result<Detections>> {
    use rayon::prelude::*;
    records
        .par_iter()
        .map(|r| detect(&r.image, target))
        .collect()
}

/// Each image's frame: the target's points found ([`detect_all`]) with the robot's pose and,
/// given the camera's intrinsics, the camera's pose of the target as the pixel path starts from
/// it ([`start_camera_poses`]): of the planar target's two poses that fit its pixels, the one the
/// robot's motion agrees with (a single tag's four corners often fit both alike). An image whose
/// target is not found whole, or whose points give no pose, is its error (`file: why`).
///
/// [`start_camera_poses`]: crate::solve::reprojection::start_camera_poses
#[cfg(feature = "images")]
pub fn frames(
    records: &[ImageRecord],
    target: &Target,
    camera: Option<&Intrinsics>,
    setup: Setup,
) -> Vec<Result<Frame>> {
    use crate::solve::reprojection::{candidates, start_camera_poses};
    let mut frames: Vec<Result<Frame>> = detect_all(records, target)
        .into_iter()
        .zip(records)
        .map(|(found, record)| {
            let frame = Frame {
                base_from_gripper: record.base_from_gripper,
                camera_from_target: None,
                detections: found?,
            };
            match camera.map(|c| candidates(&frame, c)) {
                Some(Err(why)) => Err(crate::io::parse_error(
                    &record.image.display().to_string(),
                    0,
                    "-",
                    format!(
                        "the {} points give no pose of the target ({why})",
                        frame.detections.pixels.len()
                    ),
                )),
                _ => Ok(frame),
            }
        })
        .collect();
    if let Some(camera) = camera {
        let found: Vec<Frame> = frames.iter().flatten().cloned().collect();
        let poses = start_camera_poses(&found, camera, setup);
        for (frame, pose) in frames.iter_mut().flatten().zip(poses) {
            frame.camera_from_target = Some(pose);
        }
    }
    frames
}
