//! Readers and writers of the file formats: pose pairs as JSON Lines or CSV (SPEC sec. 7), truth
//! files, and timestamped pose streams (TUM / ethz-asl layout).
//!
//! Every reader reports bad input as [`Error::Parse`] naming the file, the line (from 1) and the
//! field, and never panics. Pose pairs are normalised to [`PosePair`]
//! (`base_from_gripper`, `camera_from_target`) whichever direction the file gives.

mod csv_pairs;
mod jsonl;
mod peer;
mod stamped;
mod transform;
mod truth;

use std::fs::File;
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::str::FromStr;

use crate::error::{Error, Result};
use crate::motion::PosePair;

pub use csv_pairs::CsvPairs;
pub use jsonl::{JsonlPairs, parse_pose_line};
pub use peer::{read_moveit_json, read_opencv_yaml, read_visp_dir, read_visp_pose};
pub use stamped::{parse_stamped_poses, read_stamped_poses};
pub use transform::{CONSISTENCY_TOL, FieldProblem, TransformJson, transform_from_json};
pub use truth::{Truth, read_truth, truth_json};

/// The names a pose may have in a file, and whether the file's transform is the inverse of ours.
pub(crate) const ROBOT_FRAMES: [(&str, bool); 2] =
    [("base_from_gripper", false), ("gripper_from_base", true)];
/// See [`ROBOT_FRAMES`].
pub(crate) const CAMERA_FRAMES: [(&str, bool); 2] =
    [("camera_from_target", false), ("target_from_camera", true)];

/// Pose-pair file formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Format {
    /// By extension (`.jsonl`/`.json`, `.csv`), else by content (`{` first: JSON Lines).
    #[default]
    Auto,
    /// One JSON object per line.
    Jsonl,
    /// CSV with a header naming `<frame>_x … <frame>_qw` columns.
    Csv,
    /// OpenCV-YAML pairs `T1_i` / `T2_i` (camodocal).
    OpencvYaml,
    /// moveit_calibration's sample JSON (a list of matrix pairs).
    Moveit,
    /// A directory of ViSP `pose_fPe_*.yaml` / `pose_cPo_*.yaml` files.
    Visp,
}

impl FromStr for Format {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self> {
        match s {
            "auto" => Ok(Self::Auto),
            "jsonl" | "json" => Ok(Self::Jsonl),
            "csv" => Ok(Self::Csv),
            _ => Err(Error::InvalidParameter {
                name: "format",
                message: format!("unknown format `{s}`; one of auto, jsonl, csv"),
            }),
        }
    }
}

/// One pose pair read from a file, with its place.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StampedPosePair {
    /// Line number in the file, from 1.
    pub line: usize,
    /// Time stamp, seconds, if the file gives one.
    pub stamp: Option<f64>,
    /// The pose pair.
    pub pose: PosePair,
}

/// A whole pose file.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseSeries {
    /// The pose pairs in file order.
    pub pairs: Vec<PosePair>,
    /// Their stamps, where the file gives them.
    pub stamps: Vec<Option<f64>>,
    /// Their line numbers.
    pub lines: Vec<usize>,
}

/// A streaming reader of pose pairs: one record at a time, so that a pipe can be processed as it
/// arrives. Yields `Err` for a bad record and goes on with the next one.
pub enum PoseReader<R: BufRead> {
    /// JSON Lines.
    Jsonl(JsonlPairs<R>),
    /// CSV.
    Csv(Box<CsvPairs<R>>),
}

impl<R: BufRead> PoseReader<R> {
    /// A reader of `input`, named `source` in messages. With [`Format::Auto`] the format is taken
    /// from the extension of `source`, else from the first non-blank byte of the input.
    pub fn new(mut input: R, source: &str, format: Format) -> Result<Self> {
        let format = match format {
            Format::Auto => detect(&mut input, source)?,
            f => f,
        };
        Ok(match format {
            Format::Csv => Self::Csv(Box::new(CsvPairs::new(input, source)?)),
            Format::Jsonl => Self::Jsonl(JsonlPairs::new(input, source)),
            other => {
                return Err(Error::InvalidParameter {
                    name: "format",
                    message: format!(
                        "{other:?} files are read whole (`calibrate`, or `online FILE`), not streamed"
                    ),
                });
            }
        })
    }
}

impl<R: BufRead> Iterator for PoseReader<R> {
    type Item = Result<StampedPosePair>;

    fn next(&mut self) -> Option<Self::Item> {
        match self {
            Self::Jsonl(r) => r.next(),
            Self::Csv(r) => r.next(),
        }
    }
}

/// Picks the format from the extension of `source`, else from the content.
fn detect<R: BufRead>(input: &mut R, source: &str) -> Result<Format> {
    let lower = source.to_ascii_lowercase();
    if lower.ends_with(".jsonl") || lower.ends_with(".json") || lower.ends_with(".ndjson") {
        return Ok(Format::Jsonl);
    }
    if lower.ends_with(".csv") {
        return Ok(Format::Csv);
    }
    loop {
        let buffer = input.fill_buf().map_err(|e| Error::Io {
            file: source.to_string(),
            source: e,
        })?;
        if buffer.is_empty() {
            return Ok(Format::Jsonl);
        }
        match buffer.iter().position(|b| !b.is_ascii_whitespace()) {
            Some(k) => {
                return Ok(if buffer[k] == b'{' || buffer[k] == b'#' {
                    Format::Jsonl
                } else {
                    Format::Csv
                });
            }
            None => {
                let n = buffer.len();
                input.consume(n);
            }
        }
    }
}

/// Reads a whole text file, naming it in the error.
pub fn read_text(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).map_err(|e| Error::Io {
        file: path.display().to_string(),
        source: e,
    })
}

/// Opens a file for reading, naming it in the error.
pub fn open(path: &Path) -> Result<BufReader<File>> {
    File::open(path).map(BufReader::new).map_err(|e| Error::Io {
        file: path.display().to_string(),
        source: e,
    })
}

/// Reads a whole pose-pair file; errors on the first bad record, or with fewer than 2 poses.
pub fn read_pose_file(path: &Path, format: Format) -> Result<PoseSeries> {
    let source = path.display().to_string();
    let format = match format {
        Format::Auto => detect_file_format(path)?,
        f => f,
    };
    let text = || read_text(path);
    match format {
        Format::OpencvYaml => return peer::read_opencv_yaml(&text()?, &source),
        Format::Moveit => return peer::read_moveit_json(&text()?, &source),
        Format::Visp => return peer::read_visp_dir(path),
        _ => {}
    }
    let mut series = PoseSeries {
        pairs: Vec::new(),
        stamps: Vec::new(),
        lines: Vec::new(),
    };
    for record in PoseReader::new(open(path)?, &source, format)? {
        let r = record?;
        series.pairs.push(r.pose);
        series.stamps.push(r.stamp);
        series.lines.push(r.line);
    }
    if series.pairs.len() < 2 {
        return Err(Error::Parse {
            file: source,
            line: 0,
            field: "-".to_string(),
            message: format!(
                "{} pose pair(s): at least 2 are needed to make a motion",
                series.pairs.len()
            ),
        });
    }
    Ok(series)
}

/// The format of a file for [`Format::Auto`]: a directory is ViSP, `%YAML` or
/// `!!opencv-matrix` content is OpenCV YAML, a JSON list is moveit; otherwise decided per record
/// ([`Format::Auto`] again, for the streaming reader).
pub fn detect_file_format(path: &Path) -> Result<Format> {
    if path.is_dir() {
        return Ok(Format::Visp);
    }
    let mut head = [0u8; 4096];
    let n = {
        use std::io::Read;
        let mut f = File::open(path).map_err(|e| Error::Io {
            file: path.display().to_string(),
            source: e,
        })?;
        f.read(&mut head).map_err(|e| Error::Io {
            file: path.display().to_string(),
            source: e,
        })?
    };
    let text = String::from_utf8_lossy(&head[..n]);
    let trimmed = text.trim_start();
    if trimmed.starts_with("%YAML") || text.contains("!!opencv-matrix") {
        Ok(Format::OpencvYaml)
    } else if trimmed.starts_with('[') {
        Ok(Format::Moveit)
    } else {
        Ok(Format::Auto)
    }
}

/// Builds an [`Error::Parse`].
pub(crate) fn parse_error(
    file: &str,
    line: usize,
    field: impl Into<String>,
    message: impl Into<String>,
) -> Error {
    Error::Parse {
        file: file.to_string(),
        line,
        field: field.into(),
        message: message.into(),
    }
}
