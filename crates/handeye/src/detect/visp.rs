//! ViSP's recordings of images (its hand-eye tutorial's acquisition app): in one folder,
//! `<prefix>image-<i>.png` (or `.jpg`, `.jpeg`) and the robot's pose at that image,
//! `<prefix>pose_rPe_<i>.yaml` (or the older `pose_fPe_`), `base_from_gripper` as ViSP's pose
//! vector, paired by index.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use crate::io::parse_error;
use crate::model::error::{Error, Result};
use crate::model::pose::Transform;

/// One image of a recording and the robot's pose when it was taken.
#[derive(Debug, Clone, PartialEq)]
pub struct ImageRecord {
    /// The image file.
    pub image: PathBuf,
    /// Q, the robot's pose (`base_from_gripper`).
    pub base_from_gripper: Transform,
}

/// The most images a recording may have (a bound on what a folder may ask to be read).
pub const MAX_IMAGES: usize = 100_000;

const IMAGE_MARKER: &str = "image-";
const IMAGE_EXTENSIONS: [&str; 3] = [".png", ".jpg", ".jpeg"];
const ROBOT_MARKERS: [&str; 2] = ["pose_rPe_", "pose_fPe_"];

/// Reads a ViSP folder of images and robot poses, by index. An image without its pose, a pose
/// without its image, an index given twice or that is not a number is refused, naming the file.
pub fn read_visp_images(dir: &Path) -> Result<Vec<ImageRecord>> {
    let name = dir.display().to_string();
    let io_error = |e| Error::Io {
        file: name.clone(),
        source: e,
    };
    let mut images: BTreeMap<usize, String> = BTreeMap::new();
    let mut poses: BTreeMap<usize, String> = BTreeMap::new();
    for entry in std::fs::read_dir(dir).map_err(io_error)? {
        let file = entry
            .map_err(io_error)?
            .file_name()
            .to_string_lossy()
            .into_owned();
        let found = if let Some(stem) = IMAGE_EXTENSIONS
            .iter()
            .find_map(|ext| strip_suffix_ignoring_case(&file, ext))
        {
            index_after(stem, &[IMAGE_MARKER]).map(|i| (i, &mut images))
        } else if let Some(stem) = file.strip_suffix(".yaml") {
            index_after(stem, &ROBOT_MARKERS).map(|i| (i, &mut poses))
        } else {
            None
        };
        let Some((index, into)) = found else { continue };
        let index = index.ok_or_else(|| {
            parse_error(
                &name,
                0,
                file.as_str(),
                "the number after the name is not a pose's index",
            )
        })?;
        if let Some(first) = into.insert(index, file.clone()) {
            return Err(parse_error(
                &name,
                0,
                file.as_str(),
                format!("index {index} given twice: `{first}` and `{file}`"),
            ));
        }
        if images.len() + poses.len() > 2 * MAX_IMAGES {
            return Err(parse_error(
                &name,
                0,
                file.as_str(),
                format!("more than {MAX_IMAGES} images"),
            ));
        }
    }
    if images.is_empty() {
        return Err(parse_error(
            &name,
            0,
            "image-*.png",
            "no ViSP images in this folder (expected `<prefix>image-<i>.png`, each with its `<prefix>pose_rPe_<i>.yaml`)",
        ));
    }
    let unpaired = |file: &str, want: &str| {
        parse_error(
            &name,
            0,
            file,
            format!("no {want} with the same index to pair it with"),
        )
    };
    if let Some((_, file)) = poses.iter().find(|(i, _)| !images.contains_key(i)) {
        return Err(unpaired(file, "image"));
    }
    images
        .iter()
        .map(|(index, image)| {
            let pose = poses
                .get(index)
                .ok_or_else(|| unpaired(image, "`pose_rPe_<i>.yaml`"))?;
            Ok(ImageRecord {
                image: dir.join(image),
                base_from_gripper: crate::io::read_visp_pose(&dir.join(pose))?,
            })
        })
        .collect()
}

fn strip_suffix_ignoring_case<'a>(file: &'a str, ext: &str) -> Option<&'a str> {
    let at = file.len().checked_sub(ext.len())?;
    (file.is_char_boundary(at) && file[at..].eq_ignore_ascii_case(ext)).then(|| &file[..at])
}

/// The index after the last of `markers` in `stem`: `None` when no marker is there, `Some(None)`
/// when what follows is not a number.
fn index_after(stem: &str, markers: &[&str]) -> Option<Option<usize>> {
    let (at, marker) = markers
        .iter()
        .filter_map(|m| stem.rfind(m).map(|at| (at, *m)))
        .max_by_key(|(at, _)| *at)?;
    let digits = &stem[at + marker.len()..];
    Some(
        (!digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit()))
            .then(|| digits.parse().ok())
            .flatten(),
    )
}
