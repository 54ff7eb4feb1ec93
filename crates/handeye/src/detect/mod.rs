//! From images to detections (issue 54): the target a recording's images show ([`Target`],
//! `--target`), a ViSP recording of images and robot poses ([`read_visp_images`]), the target's
//! points found in one image (`detect`, feature `images`) and the camera's pose of them
//! ([`camera_from_target`]). The detections are what the pixel path reads (`Frame`,
//! `Detections`); docs/SPEC.md sec. 7 (`detect`) says the command that writes them.

#[cfg(feature = "images")]
mod apriltag;
#[cfg(feature = "images")]
mod chessboard;
mod target;
mod visp;

pub use target::{MAX_SIDE, TAG_CORNERS, Target};
pub use visp::{ImageRecord, read_visp_images};

use crate::model::camera::{Detections, Intrinsics};
use crate::model::pose::Transform;

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
pub fn detect(path: &std::path::Path, target: &Target) -> crate::model::error::Result<Detections> {
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

/// The camera's pose of the target from its detections (the planar target's two poses that fit
/// the pixels, refined on them; the one with the smaller pixel error), or `None` when the
/// detections do not determine one.
pub fn camera_from_target(detections: &Detections, camera: &Intrinsics) -> Option<Transform> {
    let points: Vec<nalgebra::Vector3<f64>> = detections
        .target
        .iter()
        .map(|p| nalgebra::Vector3::from(*p))
        .collect();
    let pixels: Vec<nalgebra::Vector2<f64>> = detections
        .pixels
        .iter()
        .map(|p| nalgebra::Vector2::from(*p))
        .collect();
    crate::solve::reprojection::planar_poses(&points, &pixels, camera)
        .ok()?
        .into_iter()
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(pose, _)| pose)
}

/// [`detect`] on every image of `records`, in parallel (rayon), in their order.
#[cfg(feature = "images")]
pub fn detect_all(
    records: &[ImageRecord],
    target: &Target,
) -> Vec<crate::model::error::Result<Detections>> {
    use rayon::prelude::*;
    records
        .par_iter()
        .map(|r| detect(&r.image, target))
        .collect()
}
