//! One AprilTag 36h11's four corners in an image, by `kornia-apriltag` (its default settings:
//! the image halved for the quads, edges refined on the whole one).
//!
//! The corners are the tag's own, turned with its code: the library's homography (which carries
//! the decoded rotation) taken at the corners' coordinates [`TAG_CORNERS`], so that corner k is
//! the same corner of the tag in every view.

use image::GrayImage;
use kornia_apriltag::family::TagFamilyKind;
use kornia_apriltag::{AprilTagDecoder, DecodeTagsConfig};
use kornia_image::{Image, ImageSize};

use super::target::TAG_CORNERS;

/// The tag's four corners in the image (in [`TAG_CORNERS`]' order), or why not: no tag, or more
/// than one (which one is the target cannot be told).
pub fn find(image: GrayImage) -> Result<Vec<[f64; 2]>, String> {
    let size = ImageSize {
        width: image.width() as usize,
        height: image.height() as usize,
    };
    let pixels = Image::<u8, 1>::new(size, image.into_raw()).map_err(|e| e.to_string())?;
    let config = DecodeTagsConfig::new(vec![TagFamilyKind::Tag36H11]).map_err(|e| e.to_string())?;
    let mut decoder = AprilTagDecoder::new(config, size).map_err(|e| e.to_string())?;
    let found = decoder.decode(&pixels).map_err(|e| e.to_string())?;
    match found.as_slice() {
        [] => Err("no AprilTag 36h11 found".into()),
        [tag] => Ok(TAG_CORNERS
            .iter()
            .map(|&(x, y)| {
                let p = tag.quad.homography_project(x as f32, y as f32);
                [f64::from(p.x), f64::from(p.y)]
            })
            .collect()),
        tags => Err(format!(
            "{} AprilTags 36h11 found (ids {:?}): the target is one tag",
            tags.len(),
            tags.iter().map(|t| t.id).collect::<Vec<_>>()
        )),
    }
}
