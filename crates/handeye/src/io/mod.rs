//! Readers and writers of the file formats: pose pairs as JSON Lines or CSV (SPEC sec. 7), truth
//! files, and timestamped pose streams (TUM / ethz-asl layout).
//!
//! Every reader reports bad input as [`Error::Parse`] naming the file, the line (from 1) and the
//! field, and never panics. Pose pairs are normalised to [`PosePair`]
//! (`base_from_gripper`, `camera_from_target`) whichever direction the file gives.

mod csv_pairs;
mod json_text;
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
use crate::pose::ReadTransform;

pub use csv_pairs::CsvPairs;
pub use jsonl::{JsonlPairs, parse_pose_line};
pub use peer::{read_moveit_json, read_opencv_yaml, read_visp_dir, read_visp_pose};
pub use stamped::{parse_stamped_poses, read_stamped_poses};
pub use transform::{
    CONSISTENCY_TOL, FieldProblem, TransformJson, read_transform_json, transform_from_json,
};
pub use truth::{Truth, parse_truth, read_truth, truth_json, write_truth};

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
            "opencv-yaml" | "yaml" => Ok(Self::OpencvYaml),
            "moveit" => Ok(Self::Moveit),
            "visp" => Ok(Self::Visp),
            _ => Err(Error::InvalidParameter {
                name: "format",
                message: format!(
                    "unknown format `{s}`; one of auto, jsonl, csv, opencv-yaml, moveit, visp"
                ),
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
    /// The rotation matrices that were orthonormal only to the precision they were printed with
    /// and were projected onto the nearest rotation.
    pub projections: Projections,
}

/// The rotation matrices of one input that were orthonormal only to the precision they were
/// printed with (between [`KEEP_AS_GIVEN_TOL`](crate::pose::KEEP_AS_GIVEN_TOL) and
/// [`ORTHONORMAL_TOL`](crate::pose::ORTHONORMAL_TOL)) and were projected onto the nearest rotation.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Projections {
    /// How many matrices were projected.
    pub count: usize,
    /// The largest deviation `max |RᵀR − I|` among them.
    pub largest_deviation: f64,
}

impl Projections {
    /// Counts `read` when its rotation was projected.
    pub fn add(&mut self, read: &ReadTransform) {
        if read.projected() {
            self.count += 1;
            self.largest_deviation = self.largest_deviation.max(read.deviation);
        }
    }

    /// The note to show for an input, or `None` when nothing was projected.
    ///
    /// # Example
    /// ```
    /// let p = handeye::io::Projections { count: 40, largest_deviation: 3.2e-6 };
    /// assert_eq!(
    ///     p.note().unwrap(),
    ///     "40 rotation matrices orthonormal only to 3e-6 (rounded when printed): projected onto the nearest rotation"
    /// );
    /// ```
    pub fn note(&self) -> Option<String> {
        (self.count > 0).then(|| {
            format!(
                "{} rotation {} orthonormal only to {:.0e} (rounded when printed): projected onto the nearest rotation",
                self.count,
                if self.count == 1 { "matrix" } else { "matrices" },
                self.largest_deviation
            )
        })
    }
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
    /// from the extension of `source`, else from the content: the first character that is not
    /// blank and not in a `#` comment line is `{` for JSON Lines, anything else for CSV. Line
    /// numbers in records and errors count every line of the input, the skipped ones included.
    ///
    /// # Example
    /// ```
    /// use handeye::io::{Format, PoseReader};
    /// let text = "# recorded by hand\n\
    ///     {\"base_from_gripper\": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]], \
    ///      \"target_from_camera\": {\"translation\": [0,0,1], \"quaternion_xyzw\": [0,0,0,1]}}\n";
    /// let records: Vec<_> = PoseReader::new(text.as_bytes(), "-", Format::Auto)?
    ///     .collect::<Result<_, _>>()?;
    /// assert_eq!(records[0].line, 2);
    /// // target_from_camera is inverted into camera_from_target.
    /// assert_eq!(records[0].pose.camera_from_target.translation.vector.z, -1.0);
    /// # Ok::<(), handeye::Error>(())
    /// ```
    pub fn new(mut input: R, source: &str, format: Format) -> Result<Self> {
        let (format, skipped_lines) = match format {
            Format::Auto => detect(&mut input, source)?,
            f => (f, 0),
        };
        Ok(match format {
            Format::Csv => Self::Csv(Box::new(CsvPairs::after_lines(
                input,
                source,
                skipped_lines,
            )?)),
            Format::Jsonl => Self::Jsonl(JsonlPairs::after_lines(input, source, skipped_lines)),
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

impl<R: BufRead> PoseReader<R> {
    /// The rotation matrices projected onto SO(3) so far (see [`Projections`]).
    pub fn projections(&self) -> Projections {
        match self {
            Self::Jsonl(r) => r.projections(),
            // CSV gives quaternions only.
            Self::Csv(_) => Projections::default(),
        }
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

/// Picks the format from the extension of `source`, else from the content: the first character
/// that is neither blank nor in a `#` comment line, `{` meaning JSON Lines and anything else CSV
/// (an input with nothing else counts as JSON Lines). The blank and comment lines before it are
/// consumed (both readers skip them anyway); their number is returned with the format so that the
/// reader's line numbers still count from the top of the input.
fn detect<R: BufRead>(input: &mut R, source: &str) -> Result<(Format, usize)> {
    let lower = source.to_ascii_lowercase();
    if lower.ends_with(".jsonl") || lower.ends_with(".json") || lower.ends_with(".ndjson") {
        return Ok((Format::Jsonl, 0));
    }
    if lower.ends_with(".csv") {
        return Ok((Format::Csv, 0));
    }
    let mut lines = 0;
    // Inside a `#` comment line whose end has not been seen yet.
    let mut in_comment = false;
    loop {
        let buffer = input.fill_buf().map_err(|e| Error::Io {
            file: source.to_string(),
            source: e,
        })?;
        if buffer.is_empty() {
            return Ok((Format::Jsonl, lines));
        }
        // Consume whole lines only, so that no byte of the first record is lost.
        let mut consumed = 0;
        let mut decided = None;
        for (k, &b) in buffer.iter().enumerate() {
            if b == b'\n' {
                lines += 1;
                in_comment = false;
                consumed = k + 1;
            } else if in_comment || b.is_ascii_whitespace() {
                continue;
            } else if b == b'#' {
                in_comment = true;
            } else {
                decided = Some(if b == b'{' {
                    Format::Jsonl
                } else {
                    Format::Csv
                });
                break;
            }
        }
        if let Some(format) = decided {
            input.consume(consumed);
            return Ok((format, lines));
        }
        // Nothing decided in this buffer: all of it is blank or comment. Its last, unfinished
        // line holds no newline, so consuming it keeps the count right.
        let n = buffer.len();
        input.consume(n);
    }
}

/// Reads a whole text file, naming it in the error; text that is not UTF-8 is a parse error on
/// the line of its first invalid byte.
pub fn read_text(path: &Path) -> Result<String> {
    let file = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| Error::Io {
        file: file.clone(),
        source: e,
    })?;
    String::from_utf8(bytes).map_err(|e| {
        let valid = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        let line = 1 + valid.iter().filter(|&&b| b == b'\n').count();
        let column = 1 + valid.iter().rev().take_while(|&&b| b != b'\n').count();
        parse_error(
            &file,
            line,
            "-",
            format!("not valid UTF-8 text (byte {column} of the line)"),
        )
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
        projections: Projections::default(),
    };
    let mut reader = PoseReader::new(open(path)?, &source, format)?;
    for record in reader.by_ref() {
        let r = record?;
        series.pairs.push(r.pose);
        series.stamps.push(r.stamp);
        series.lines.push(r.line);
    }
    series.projections = reader.projections();
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

/// Largest size of a time stamp accepted, seconds: about 31,700 years (Unix time is near 1.7e9 s;
/// stamps in milli- or nanoseconds are beyond it). Differences of stamps within it cannot overflow.
pub const MAX_STAMP: f64 = 1e12;

/// Checks a time stamp read from data: finite and at most [`MAX_STAMP`] in size; the message
/// says why not.
pub(crate) fn check_stamp(value: f64) -> std::result::Result<f64, String> {
    if !value.is_finite() {
        Err(format!(
            "expected a finite number of seconds, found {value}"
        ))
    } else if value.abs() > MAX_STAMP {
        Err(format!(
            "stamp {value:e} is not a plausible time in seconds (more than {MAX_STAMP:e} in size: milli- or nanoseconds?)"
        ))
    } else {
        Ok(value)
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

#[cfg(test)]
mod tests {
    use super::*;

    const I: &str = "[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]";
    const CSV_HEADER: &str = "base_from_gripper_x,base_from_gripper_y,base_from_gripper_z,base_from_gripper_qx,base_from_gripper_qy,base_from_gripper_qz,base_from_gripper_qw,camera_from_target_x,camera_from_target_y,camera_from_target_z,camera_from_target_qx,camera_from_target_qy,camera_from_target_qz,camera_from_target_qw";
    const CSV_ROW: &str = "1,2,3,0,0,0,1,0,0,1,0,0,0,1";

    fn jsonl_line() -> String {
        format!("{{\"base_from_gripper\": {I}, \"camera_from_target\": {I}}}")
    }

    /// (line, field) of a parse error.
    fn place(e: &Error) -> (usize, String) {
        match e {
            Error::Parse { line, field, .. } => (*line, field.clone()),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn formats_parse_from_their_names() {
        for (name, format) in [
            ("auto", Format::Auto),
            ("jsonl", Format::Jsonl),
            ("csv", Format::Csv),
            ("opencv-yaml", Format::OpencvYaml),
            ("moveit", Format::Moveit),
            ("visp", Format::Visp),
        ] {
            assert_eq!(name.parse::<Format>().unwrap(), format);
        }
        assert!(matches!(
            "xml".parse::<Format>(),
            Err(Error::InvalidParameter { name: "format", .. })
        ));
    }

    #[test]
    fn auto_detects_by_extension_then_content_and_keeps_line_numbers() {
        // Tiny buffers, so that the comment lines span several reads.
        let small = |text: &str| {
            std::io::BufReader::with_capacity(3, std::io::Cursor::new(text.to_string()))
        };
        let jsonl = format!(
            "\n# a comment longer than the buffer\n\n  {}\n{}\n",
            jsonl_line(),
            jsonl_line()
        );
        let csv = format!("# recorded 2024\n\n{CSV_HEADER}\n{CSV_ROW}\n# pause\n{CSV_ROW}\n");
        for (text, source, lines) in [
            (jsonl.as_str(), "-", [4, 5]),
            (csv.as_str(), "-", [4, 6]),
            (csv.as_str(), "poses.csv", [4, 6]),
            (jsonl.as_str(), "poses.JSONL", [4, 5]),
        ] {
            let records: Vec<StampedPosePair> = PoseReader::new(small(text), source, Format::Auto)
                .unwrap()
                .collect::<Result<_>>()
                .unwrap();
            let got: Vec<usize> = records.iter().map(|r| r.line).collect();
            assert_eq!(got, lines, "{source}: {text}");
        }
        let csv_reader = PoseReader::new(small(&csv), "-", Format::Auto).unwrap();
        assert!(matches!(csv_reader, PoseReader::Csv(_)));
        // Nothing but comments: JSON Lines with no records.
        assert_eq!(
            PoseReader::new(small("# only\n\n"), "-", Format::Auto)
                .unwrap()
                .count(),
            0
        );
        // A CSV header error names the header's own line, after the comments.
        let e = PoseReader::new(small("# c\n\nstamp,foo\n"), "-", Format::Auto)
            .err()
            .unwrap();
        assert_eq!(place(&e), (3, "foo".to_string()));
    }

    #[test]
    fn invalid_utf8_names_the_line_and_reading_goes_on() {
        let mut bytes = format!("{}\n", jsonl_line()).into_bytes();
        bytes.extend_from_slice(b"\xff\xfe\n");
        bytes.extend_from_slice(format!("{}\n", jsonl_line()).as_bytes());
        let r: Vec<_> = PoseReader::new(&bytes[..], "u.jsonl", Format::Auto)
            .unwrap()
            .collect();
        assert_eq!(r.len(), 3);
        assert_eq!(place(r[1].as_ref().unwrap_err()), (2, "-".to_string()));
        assert_eq!(r[2].as_ref().unwrap().line, 3);

        let mut bytes = format!("{CSV_HEADER}\n{CSV_ROW}\n").into_bytes();
        bytes.extend_from_slice(b"1,2,\xff,0,0,0,1,0,0,1,0,0,0,1\n");
        bytes.extend_from_slice(format!("{CSV_ROW}\n").as_bytes());
        let r: Vec<_> = PoseReader::new(&bytes[..], "u.csv", Format::Auto)
            .unwrap()
            .collect();
        assert_eq!(r.len(), 3);
        assert_eq!(
            place(r[1].as_ref().unwrap_err()),
            (3, "base_from_gripper_z".to_string())
        );
        assert_eq!(r[2].as_ref().unwrap().line, 4);
    }

    #[test]
    fn a_failing_input_ends_the_iteration() {
        let dir = std::env::temp_dir();
        for format in [Format::Jsonl, Format::Csv] {
            let reader = open(&dir).map(|r| PoseReader::new(r, "dir", format));
            // Opening a directory fails on some systems, reading it on others: either way an
            // error, and never an endless one.
            if let Ok(Ok(reader)) = reader {
                let records: Vec<_> = reader.take(10).collect();
                assert!(records.len() <= 1, "{format:?}: {records:?}");
                assert!(records.iter().all(Result::is_err));
            }
        }
    }

    proptest::proptest! {
        /// No input makes a reader panic or loop: every record is a pair or an error.
        #[test]
        fn arbitrary_input_never_panics(
            bytes in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..400),
            cut in 0usize..400,
            noise in "[-{}\\[\\],:#\"0-9.eE a-z_\n]{0,40}",
        ) {
            // Raw bytes, and a good record with noise spliced in at `cut`.
            let mut spliced = format!("{}\n{CSV_HEADER}\n{CSV_ROW}\n", jsonl_line()).into_bytes();
            let at = cut.min(spliced.len());
            spliced.splice(at..at, noise.bytes());
            for input in [&bytes, &spliced] {
                for format in [Format::Auto, Format::Jsonl, Format::Csv] {
                    if let Ok(reader) = PoseReader::new(&input[..], "-", format) {
                        let n = reader.take(1000).count();
                        proptest::prop_assert!(n < 1000);
                    }
                }
            }
        }
    }

    #[test]
    fn a_whole_file_needs_two_poses() {
        let dir = std::env::temp_dir().join(format!("handeye-io-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let one = dir.join("one.jsonl");
        std::fs::write(&one, format!("# one pose\n{}\n", jsonl_line())).unwrap();
        let two = dir.join("two");
        std::fs::write(
            &two,
            format!("stamp,{CSV_HEADER}\n0.5,{CSV_ROW}\n1.5,{CSV_ROW}\n"),
        )
        .unwrap();
        let e = read_pose_file(&one, Format::Auto).unwrap_err();
        let series = read_pose_file(&two, Format::Auto).unwrap();
        let missing = read_pose_file(&dir.join("missing.jsonl"), Format::Auto).unwrap_err();
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(place(&e), (0, "-".to_string()));
        assert!(e.to_string().contains("one.jsonl") && e.to_string().contains("at least 2"));
        assert_eq!(series.pairs.len(), 2);
        assert_eq!(series.stamps, [Some(0.5), Some(1.5)]);
        assert_eq!(series.lines, [2, 3]);
        assert_eq!(series.pairs[0].base_from_gripper.translation.vector.z, 3.0);
        assert!(matches!(missing, Error::Io { .. }));
    }
}
