//! Pose pairs one record at a time (`online`'s input): the one entry behind which every pose
//! format is read as a stream.

use std::io::BufRead;
use std::path::Path;

use super::{DegreeAngles, Format, Note, PoseInput, PoseReader, Projections, StampedPosePair};
use crate::model::error::Result;
use crate::model::motion::Setup;
use crate::model::rotation::Rotations;

/// Pose pairs one at a time, each with its place, or the error of a bad record (the stream goes on
/// with the next one): from a pose file of any format, a directory of ViSP files, or a reader of
/// the caller's own (standard input, a pipe, a file wrapped to act before it waits for input).
///
/// JSON Lines and CSV are read as they arrive; the formats of a whole file (OpenCV YAML, moveit,
/// ViSP, easy_handeye2) are read whole when opened and then given one record at a time. What the
/// reading noticed (lines skipped before the first record, rotation matrices projected onto a
/// rotation, angles in degrees that look like radians) is in [`PoseStream::notes`], each once.
///
/// # Example
/// ```
/// use handeye::io::{Format, PoseStream};
/// use handeye::{Rotations, Setup};
/// let text = "[INFO] driver started\n\
///     {\"base_from_gripper\": {\"translation\": [0,0,0], \"quaternion_xyzw\": [0,0,0,1]},\
///      \"target_from_camera\": {\"translation\": [0,0,1], \"quaternion_xyzw\": [0,0,0,1]}}\n";
/// let mut stream = PoseStream::from_reader(
///     text.as_bytes(), "-", Format::Auto, Rotations::default(), Setup::EyeInHand,
/// )?;
/// assert_eq!(stream.notes().len(), 1); // the skipped line
/// let records: Vec<_> = stream.by_ref().collect::<Result<_, _>>()?;
/// assert_eq!(records[0].line, 2);
/// // target_from_camera is inverted into camera_from_target.
/// assert_eq!(records[0].pose.camera_from_target.translation.vector.z, -1.0);
/// # Ok::<(), handeye::Error>(())
/// ```
pub struct PoseStream {
    records: Records,
    source: String,
    notes: Vec<Note>,
    ended: bool,
}

enum Records {
    Whole(std::vec::IntoIter<StampedPosePair>),
    Stream(Box<dyn RecordReader>),
}

/// A [`PoseReader`] of any input, as the stream keeps it.
trait RecordReader: Iterator<Item = Result<StampedPosePair>> {
    fn projections(&self) -> Projections;
    fn degree_angles(&self) -> DegreeAngles;
}

impl<R: BufRead> RecordReader for PoseReader<R> {
    fn projections(&self) -> Projections {
        PoseReader::projections(self)
    }

    fn degree_angles(&self) -> DegreeAngles {
        PoseReader::degree_angles(self)
    }
}

impl PoseStream {
    /// Opens the pose file `path` once (a FIFO cannot be read twice): with [`Format::Auto`] a
    /// directory is ViSP, else the format is told from the head of the content. The rotations of
    /// JSON Lines and CSV are read in the conventions `rotations` names; a format of its own
    /// refuses a named convention. A file that declares a setup other than `setup` is refused.
    pub fn open(path: &Path, format: Format, rotations: Rotations, setup: Setup) -> Result<Self> {
        let source = path.display().to_string();
        Self::from_input(super::open_poses(path, format, rotations)?, source, setup)
    }

    /// As [`PoseStream::open`], on an input already open and named `source` in messages.
    pub fn from_reader(
        input: impl BufRead + 'static,
        source: &str,
        format: Format,
        rotations: Rotations,
        setup: Setup,
    ) -> Result<Self> {
        let input = super::open_pose_stream(input, source, format, rotations)?;
        Self::from_input(input, source.to_string(), setup)
    }

    fn from_input<R: BufRead + 'static>(
        input: PoseInput<R>,
        source: String,
        setup: Setup,
    ) -> Result<Self> {
        let mut notes = Vec::new();
        let records = match input {
            PoseInput::Whole(series) => {
                series.check_setup(setup, &source)?;
                if series.projections.note().is_some() {
                    notes.push(Note::Projections {
                        source: source.clone(),
                        projections: series.projections,
                    });
                }
                let written = series.written;
                let records: Vec<_> = (series.pairs.into_iter().enumerate())
                    .map(|(k, pose)| StampedPosePair::new(k + 1, None, pose, written))
                    .collect();
                Records::Whole(records.into_iter())
            }
            PoseInput::Stream(reader) => {
                if let Some(preamble) = reader.preamble() {
                    notes.push(Note::Preamble {
                        source: source.clone(),
                        preamble: preamble.clone(),
                    });
                }
                Records::Stream(Box::new(reader))
            }
        };
        Ok(Self {
            records,
            source,
            notes,
            ended: false,
        })
    }

    /// The notes not yet taken: when opened, the lines skipped before the first record (or the
    /// rotation matrices a whole file's reading projected); once the stream has ended, the
    /// rotation matrices projected and the sides whose angles in degrees look like radians.
    pub fn notes(&mut self) -> Vec<Note> {
        std::mem::take(&mut self.notes)
    }

    /// The notes of a streamed input at its end.
    fn end(&mut self) {
        self.ended = true;
        if let Records::Stream(reader) = &self.records {
            let projections = reader.projections();
            if projections.note().is_some() {
                self.notes.push(Note::Projections {
                    source: self.source.clone(),
                    projections,
                });
            }
            let degrees = reader.degree_angles();
            self.notes
                .extend(Note::small_degrees(&self.source, &degrees));
        }
    }
}

impl Iterator for PoseStream {
    type Item = Result<StampedPosePair>;

    fn next(&mut self) -> Option<Self::Item> {
        let next = match &mut self.records {
            Records::Whole(records) => records.next().map(Ok),
            Records::Stream(reader) => reader.next(),
        };
        if next.is_none() && !self.ended {
            self.end();
        }
        next
    }
}
