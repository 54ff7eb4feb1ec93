//! The pose files one reader reads: a streaming reader of JSON Lines and CSV records
//! ([`PoseReader`]), the formats read whole, and what reading them noticed. Crate-internal: the
//! faces read through [`super::PoseStream`] and [`super::Recording`].

use super::format::Reading;
use super::*;

/// The largest angle (in size) each side of an input gave in a convention in degrees (a vendor's
/// Euler angles, `rpy-deg`), where one did: every angle within a turn's 2π of a whole recording
/// is radians given to a convention in degrees, most likely (robot and camera poses turn by tens
/// of degrees; read as degrees, radians turn them by a few). Told as a note, not refused: a few
/// degrees are valid angles.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct DegreeAngles {
    /// The robot poses' largest angle in degrees, if they gave angles in degrees.
    pub robot: Option<f64>,
    /// The camera poses'.
    pub camera: Option<f64>,
}

impl DegreeAngles {
    /// Counts the largest angle `degrees` of a pose of one side (the robot's when `robot`).
    pub(crate) fn add(&mut self, robot: bool, degrees: Option<f64>) {
        let side = if robot {
            &mut self.robot
        } else {
            &mut self.camera
        };
        if let Some(d) = degrees {
            *side = Some(side.map_or(d, |s: f64| s.max(d)));
        }
    }

    /// The sides whose every angle in degrees is within ±2π, with their largest: `robot` or
    /// `camera`, and the angle.
    pub fn within_a_radian_turn(&self) -> Vec<(&'static str, f64)> {
        [("robot", self.robot), ("camera", self.camera)]
            .into_iter()
            .filter_map(|(side, d)| Some((side, d?)))
            .filter(|(_, d)| *d <= std::f64::consts::TAU)
            .collect()
    }
}

/// A streaming reader of pose pairs: one record at a time, so that a pipe can be processed as it
/// arrives. Yields `Err` for a bad record and goes on with the next one.
///
/// Lines are read with a bounded buffer (`MAX_LINE` bytes; a longer line is a bad line, skipped
/// without being kept) and CSV lines are parsed one at a time (a stray quote costs its line only),
/// so that no input can make the reader lose the stream or grow without bound.
pub struct PoseReader<R: BufRead> {
    inner: Inner<R>,
    preamble: Option<Preamble>,
}

enum Inner<R: BufRead> {
    Jsonl(JsonlPairs<R>),
    Csv(Box<CsvPairs<R>>),
}

/// Lines skipped before the first pose record (log lines of a driver, say), beyond blank and
/// `#` comment lines.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Preamble {
    /// Lines skipped in all, blank and comment lines included.
    pub lines: usize,
    /// Number of the first skipped line that is neither blank nor a comment.
    pub first_line: usize,
    /// Its text, shortened to 80 characters.
    pub first: String,
    /// Whether no pose record followed.
    pub no_record: bool,
}

impl Preamble {
    /// The message to show, once.
    ///
    /// # Example
    /// ```
    /// let p = handeye::io::Preamble {
    ///     lines: 2, first_line: 1, first: "[INFO] started".into(), no_record: false,
    /// };
    /// assert_eq!(
    ///     p.note(),
    ///     "skipped 2 line(s) before the first pose record, the first not blank nor a comment at line 1: `[INFO] started`"
    /// );
    /// ```
    pub fn note(&self) -> String {
        format!(
            "skipped {} line(s) {}, the first not blank nor a comment at line {}: `{}`",
            self.lines,
            if self.no_record {
                "and found no pose record"
            } else {
                "before the first pose record"
            },
            self.first_line,
            self.first
        )
    }
}

/// What a line before the first record is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Blank,
    Jsonl,
    CsvHeader,
    Other,
}

fn kind_of(line: &Line<'_>) -> Kind {
    let Line::Text(text) = line else {
        return Kind::Other;
    };
    let trimmed = text.trim_ascii();
    match trimmed.first() {
        None | Some(b'#') => Kind::Blank,
        Some(b'{') => Kind::Jsonl,
        Some(_) => {
            // A header: at least two fields, every one a name (`stamp`, `base_from_gripper_x`).
            let name = |f: &[u8]| {
                let f = f.trim_ascii();
                let f = f
                    .strip_prefix(b"\"")
                    .and_then(|f| f.strip_suffix(b"\""))
                    .unwrap_or(f);
                f.first()
                    .is_some_and(|b| b.is_ascii_alphabetic() || *b == b'_')
                    && f.iter().all(|b| b.is_ascii_alphanumeric() || *b == b'_')
            };
            if trimmed.contains(&b',') && trimmed.split(|b| *b == b',').all(name) {
                Kind::CsvHeader
            } else {
                Kind::Other
            }
        }
    }
}

impl<R: BufRead> PoseReader<R> {
    /// A reader of `input`, named `source` in messages. With [`Format::Auto`] the format is taken
    /// from the extension of `source`, else from the first line that looks like a record: `{` for
    /// JSON Lines, a CSV header (names separated by commas) for CSV. A UTF-8 byte order mark and
    /// the lines before the first record-looking line (blank, `#` comments, a driver's log lines)
    /// are skipped: see [`PoseReader::preamble`]. Line numbers in records and errors count every
    /// line of the input, the skipped ones included.
    ///
    /// # Example
    /// ```
    /// use handeye::io::{Format, PoseReader};
    /// let text = "\u{feff}[INFO] robot driver started\n# recorded by hand\n\
    ///     {\"base_from_gripper\": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]], \
    ///      \"target_from_camera\": {\"translation\": [0,0,1], \"quaternion_xyzw\": [0,0,0,1]}}\n";
    /// let mut reader = PoseReader::new(text.as_bytes(), "-", Format::Auto)?;
    /// assert_eq!(reader.preamble().unwrap().lines, 2);
    /// let records: Vec<_> = reader.by_ref().collect::<Result<_, _>>()?;
    /// assert_eq!(records[0].line, 3);
    /// // target_from_camera is inverted into camera_from_target.
    /// assert_eq!(records[0].pose.camera_from_target.translation.vector.z, -1.0);
    /// # Ok::<(), handeye::Error>(())
    /// ```
    pub fn new(input: R, source: &str, format: Format) -> Result<Self> {
        Self::with_rotations(input, source, format, Rotations::default())
    }

    /// As [`PoseReader::new`], each side's rotations read in the convention `rotations` names
    /// (CSV columns of that convention; in JSON Lines a rotation field of another convention is
    /// refused). Unnamed sides are read as their columns or fields say (`_qx … _qw` in CSV).
    pub fn with_rotations(
        input: R,
        source: &str,
        format: Format,
        rotations: Rotations,
    ) -> Result<Self> {
        Self::with_conventions(input, source, format, Conventions::named(rotations))
    }

    /// As [`PoseReader::with_rotations`], the numbers read as [`Conventions`] says.
    pub(crate) fn with_conventions(
        input: R,
        source: &str,
        format: Format,
        conventions: Conventions,
    ) -> Result<Self> {
        let format = match format {
            Format::Auto => Format::by_extension(source),
            f if f.is_streamed() => f,
            other => {
                return Err(Error::InvalidParameter {
                    name: "format",
                    message: format!(
                        "{other:?} files are read whole (`calibrate`, or `online FILE`), not streamed"
                    ),
                });
            }
        };
        let mut lines = Lines::new(input);
        let mut skipped = 0;
        let mut preamble: Option<Preamble> = None;
        let decided = loop {
            let (number, line) = match lines.next_line() {
                None => break None,
                Some(Err(e)) => {
                    return Err(Error::Io {
                        file: source.to_string(),
                        source: e,
                    });
                }
                Some(Ok(l)) => l,
            };
            let kind = kind_of(&line);
            let found = match (kind, format) {
                (Kind::Jsonl, Format::Auto | Format::Jsonl) => Some(Format::Jsonl),
                (Kind::CsvHeader, Format::Auto | Format::Csv) => Some(Format::Csv),
                _ => None,
            };
            if found.is_some() {
                lines.unread();
                break found;
            }
            if line == Line::TooLong {
                // Before any record, a line without end (`/dev/zero`) would be skipped forever.
                return Err(parse_error(
                    source,
                    number,
                    "-",
                    format!(
                        "a line longer than {MAX_LINE} bytes before any pose record: not a pose file (JSON Lines or CSV)"
                    ),
                ));
            }
            skipped += 1;
            if kind != Kind::Blank && preamble.is_none() {
                let first = match line {
                    Line::Text(t) => String::from_utf8_lossy(t).chars().take(80).collect(),
                    Line::TooLong => String::new(),
                };
                preamble = Some(Preamble {
                    lines: 0,
                    first_line: number,
                    first,
                    no_record: false,
                });
            }
        };
        let preamble = preamble.map(|p| Preamble {
            lines: skipped,
            no_record: decided.is_none(),
            ..p
        });
        if let (None, Format::Csv, Some(p)) = (decided, format, &preamble) {
            // Read as CSV (by its name or by `--format csv`) and no line is a header.
            return Err(parse_error(
                source,
                p.first_line,
                "-",
                format!(
                    "no CSV header: no line names the columns (`stamp,base_from_gripper_x,…`); line {}, the first not blank nor a comment, is `{}`{}",
                    p.first_line,
                    p.first,
                    if p.first.contains('\0') {
                        " (it holds a NUL byte)"
                    } else {
                        ""
                    }
                ),
            ));
        }
        let inner = match decided.unwrap_or(if format == Format::Csv {
            Format::Csv
        } else {
            Format::Jsonl
        }) {
            Format::Csv => Inner::Csv(Box::new(CsvPairs::from_lines(lines, source, conventions)?)),
            _ => Inner::Jsonl(JsonlPairs::from_lines(lines, source, conventions)),
        };
        Ok(Self { inner, preamble })
    }

    /// The lines skipped before the first record, when any of them was neither blank nor a `#`
    /// comment (a log line, say): to be told once.
    pub fn preamble(&self) -> Option<&Preamble> {
        self.preamble.as_ref()
    }

    /// The format read: [`Format::Jsonl`] or [`Format::Csv`].
    pub fn format(&self) -> Format {
        match self.inner {
            Inner::Jsonl(_) => Format::Jsonl,
            Inner::Csv(_) => Format::Csv,
        }
    }

    /// The rotation matrices projected onto SO(3) so far (see [`Projections`]).
    pub fn projections(&self) -> Projections {
        match &self.inner {
            Inner::Jsonl(r) => r.projections(),
            // CSV gives no matrices.
            Inner::Csv(_) => Projections::default(),
        }
    }

    /// The largest angles in degrees read so far (see [`DegreeAngles`]).
    pub fn degree_angles(&self) -> DegreeAngles {
        match &self.inner {
            Inner::Jsonl(r) => r.degree_angles(),
            Inner::Csv(r) => r.degree_angles(),
        }
    }
}

impl<R: BufRead> Iterator for PoseReader<R> {
    type Item = Result<StampedPosePair>;

    fn next(&mut self) -> Option<Self::Item> {
        match &mut self.inner {
            Inner::Jsonl(r) => r.next(),
            Inner::Csv(r) => r.next(),
        }
    }
}

/// A pose-pair input opened once: read whole, or streamed.
pub enum PoseInput<R: BufRead> {
    /// A format read whole (OpenCV YAML, moveit, ViSP).
    Whole(PoseSeries),
    /// JSON Lines or CSV, one record at a time.
    Stream(PoseReader<Sniffed<R>>),
}

/// Opens the pose-pair file `path` once (a FIFO or `<(…)` cannot be read twice): with
/// [`Format::Auto`] a directory is ViSP, else the format is told from the head of the content
/// (its head tells the format), which is then read again from memory, not from the file. The
/// rotations of JSON Lines and CSV are read in the conventions `rotations` names; a format of its
/// own (OpenCV YAML, moveit, ViSP, easy_handeye2) refuses a named convention.
pub fn open_poses(
    path: &Path,
    format: Format,
    rotations: Rotations,
) -> Result<PoseInput<BufReader<File>>> {
    open_poses_as(path, format, Conventions::named(rotations))
}

/// As [`open_poses`], the numbers read as [`Conventions`] says.
pub(crate) fn open_poses_as(
    path: &Path,
    format: Format,
    conventions: Conventions,
) -> Result<PoseInput<BufReader<File>>> {
    let source = path.display().to_string();
    if let Some((read, what)) = format.directory(path) {
        no_rotations(conventions.named, &source, what)?;
        return read(path).map(PoseInput::Whole);
    }
    if matches!(format.reading(), Reading::Whole(_)) {
        let meta = std::fs::metadata(path).map_err(|e| Error::Io {
            file: source.clone(),
            source: e,
        })?;
        whole_file_kind(&meta, &source)?;
    }
    open_pose_stream_as(open(path)?, &source, format, conventions)
}

/// Refuses rotation conventions named for an input whose format fixes its own (`what`).
pub(crate) fn no_rotations(rotations: Rotations, source: &str, what: &str) -> Result<()> {
    if !rotations.is_named() {
        return Ok(());
    }
    Err(Error::InvalidParameter {
        name: "rotation",
        message: format!(
            "{source} is {what}, whose rotations are written one way only: drop `--rotation` (`rotation=` in Python), which is for stamped streams, CSV columns and JSON fields"
        ),
    })
}

/// [`open_poses`] on an input already open, named `source` in messages: for a reader of the
/// caller's own (one that does something before it waits for input, say). ViSP directories are
/// read by [`open_poses`].
pub fn open_pose_stream<R: BufRead>(
    input: R,
    source: &str,
    format: Format,
    rotations: Rotations,
) -> Result<PoseInput<R>> {
    open_pose_stream_as(input, source, format, Conventions::named(rotations))
}

/// As [`open_pose_stream`], the numbers read as [`Conventions`] says.
fn open_pose_stream_as<R: BufRead>(
    input: R,
    source: &str,
    format: Format,
    conventions: Conventions,
) -> Result<PoseInput<R>> {
    let rotations = conventions.named;
    let (sniffed, input) = sniff_format(input, source)?;
    let format = match format {
        Format::Auto => sniffed,
        f => f,
    };
    Ok(match format.reading() {
        Reading::Whole(read) => {
            if let Some(what) = format.row().and_then(|r| r.own_rotations) {
                no_rotations(rotations, source, what)?;
            }
            PoseInput::Whole(read(&read_whole(input, source)?, source)?)
        }
        _ => PoseInput::Stream(PoseReader::with_conventions(
            input,
            source,
            format,
            conventions,
        )?),
    })
}

/// Every record of a streaming reader as a series (its projections left to the caller); the
/// first bad record is the error.
pub(crate) fn read_records<R: BufRead>(reader: &mut PoseReader<R>) -> Result<PoseSeries> {
    let mut series = PoseSeries {
        pairs: Vec::new(),
        stamps: Vec::new(),
        lines: Vec::new(),
        joints: Vec::new(),
        projections: Projections::default(),
        written: Written::NAMED,
        setup: None,
    };
    for (k, record) in reader.by_ref().enumerate() {
        let record = record?;
        series.written = if k == 0 {
            record.written
        } else {
            series.written.and(record.written)
        };
        series.pairs.push(record.pose);
        series.stamps.push(record.stamp);
        series.lines.push(record.line);
        if record.joint_count > 0 {
            series
                .joints
                .push(record.joints[..record.joint_count].to_vec());
        }
    }
    Ok(series)
}

/// The `joints` of every record of a JSON Lines pose file's text (radians, the robot's joint
/// order), in record order: `None` when no record gives them. Read as the pose reader reads the
/// records, in the same pass as their poses and by the same rules (a record without them when the
/// first gives them, another count, more than 64 or a value that is not a finite number is
/// refused with the file, the line and the field, `joints[k]`).
pub fn read_joints(text: &str, source: &str) -> Result<Option<Vec<Vec<f64>>>> {
    let mut reader = PoseReader::with_conventions(
        text.as_bytes(),
        source,
        Format::Jsonl,
        Conventions::default(),
    )?;
    let series = read_records(&mut reader)?;
    Ok((!series.joints.is_empty()).then_some(series.joints))
}

/// Refuses a file of fewer than 2 pose pairs (no motion), naming it.
pub(crate) fn at_least_two_pairs(pairs: usize, source: String) -> Result<()> {
    if pairs >= 2 {
        return Ok(());
    }
    Err(parse_error(
        &source,
        0,
        "-",
        format!("{pairs} pose pair(s): at least 2 are needed to make a motion"),
    ))
}

/// Reads a whole pose-pair file; errors on the first bad record, or with fewer than 2 poses.
pub fn read_pose_file(path: &Path, format: Format) -> Result<PoseSeries> {
    let source = path.display().to_string();
    let mut reader = match open_poses(path, format, Rotations::default())? {
        PoseInput::Whole(series) => return Ok(series),
        PoseInput::Stream(reader) => reader,
    };
    let mut series = read_records(&mut reader)?;
    series.projections = reader.projections();
    at_least_two_pairs(series.pairs.len(), source)?;
    Ok(series)
}
