//! What goes into the online calibrator ([`Record`]) and what comes out of it ([`Outputs`]):
//! one record in, everything that happened out, every pose it cites named as its input names it.

use std::collections::VecDeque;

use serde::{Deserialize, Serialize};

use crate::check::stream::StreamReading;
use crate::model::camera::Frame;
use crate::model::motion::PosePair;
use crate::model::pose::Transform;
use crate::model::warning::Warning;
use crate::online::select::Thresholds;
use crate::online::{Event, Unit};
use crate::track::{Change, HeldOut, Report};

/// One record of a stream: a pose pair or a frame with detections, its name as the input gives
/// it, and the robot's joint angles at it when the input has them.
///
/// A pose pair converts into a record named by its number (`&PosePair: Into<Record>`), so that
/// `calibrator.push(&pose)` reads as before.
#[derive(Debug, Clone, PartialEq)]
pub struct Record<'a> {
    /// What was observed.
    pub observed: Observed<'a>,
    /// How the input names the record: by its number (the default), its line, its stamp or a
    /// name of its own. Held-out poses and changes of X are named so.
    pub name: Name<'a>,
    /// The robot's joint angles at the pose (radians; every record the same joints), for the
    /// accumulating estimator's systematic-error test; `None` when the input has none.
    pub joints: Option<&'a [f64]>,
}

/// What a [`Record`] observed.
#[derive(Debug, Clone, PartialEq)]
pub enum Observed<'a> {
    /// A robot pose and the camera's pose of the target.
    Pose(&'a PosePair),
    /// A robot pose and the target's detections (a calibrator on the pixels); boxed, as it
    /// holds its detections anyway.
    Frame(Box<Frame>),
}

/// How the input names a record, for the outputs that cite it.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Name<'a> {
    /// By its number: `pose 12` (`record 12` for a frame).
    #[default]
    Numbered,
    /// Line `line` of `source` (`robot.jsonl:12`); a refused pose is then a parse error at it.
    Line {
        /// The input, as the face shows it.
        source: &'a str,
        /// Its line (from 1).
        line: usize,
    },
    /// The camera stamp of two streams paired by time (`robot.csv at t = 1.250 s`); `line` is the
    /// line a refused pose is a parse error at.
    Stamp {
        /// The input, as the face shows it.
        source: &'a str,
        /// Its line (from 1).
        line: usize,
        /// The stamp, seconds.
        seconds: f64,
    },
    /// A name of its own, as given.
    Text(&'a str),
}

impl<'a> Record<'a> {
    /// A pose pair, named by its number.
    pub fn pose(pose: &'a PosePair) -> Self {
        Self {
            observed: Observed::Pose(pose),
            name: Name::Numbered,
            joints: None,
        }
    }

    /// A frame with detections, named by its number.
    pub fn frame(frame: Frame) -> Self {
        Self {
            observed: Observed::Frame(Box::new(frame)),
            name: Name::Numbered,
            joints: None,
        }
    }

    /// The same record named `name`.
    pub fn named(self, name: Name<'a>) -> Self {
        Self { name, ..self }
    }

    /// The same record with the robot's joint angles at it.
    pub fn with_joints(self, joints: &'a [f64]) -> Self {
        Self {
            joints: Some(joints),
            ..self
        }
    }
}

impl<'a> From<&'a PosePair> for Record<'a> {
    fn from(pose: &'a PosePair) -> Self {
        Self::pose(pose)
    }
}

/// Everything one push (or [`OnlineCalibrator::finish`](crate::OnlineCalibrator::finish))
/// made happen, in the order a face tells it: the length unit once known, a misread found, the
/// poses held out, a change of X, an estimate, the paper's calibrations, a stuck selection, the
/// cautions of the end's estimate on the pixels. Empty (and allocation-free) on most pushes.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Outputs {
    /// The length unit, told once (poses only): known, or not told by the first pose.
    pub unit: Option<UnitTold>,
    /// With the paper's estimator: what the readings check of the first poses found (once).
    pub misread: Option<StreamReading>,
    /// Poses the accumulating estimator held out at this record (this one, or earlier ones judged
    /// now), each named as its input names it.
    pub held_out: Vec<HeldOutPose>,
    /// A change of X (or of the target) that this record confirmed.
    pub change: Option<ChangeFound>,
    /// The accumulating estimator's (or on the pixels, the batch calibration's) estimate reported
    /// at this record; at the end, the end's report.
    pub report: Option<Report>,
    /// The paper's calibrations this record completed (usually none).
    pub events: Vec<Event>,
    /// With the paper's estimator: why its selection has made no calibration for a while, told
    /// at 200, 400, 800, … poses without one.
    pub stuck: Option<String>,
    /// At the end on the pixels: the cautions of the last estimate (its verdict `questionable`
    /// when any).
    pub warnings: Vec<Warning>,
}

impl Outputs {
    /// Whether nothing happened.
    pub fn is_empty(&self) -> bool {
        *self == Self::default()
    }
}

/// The length unit of the input, told once ([`Outputs::unit`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum UnitTold {
    /// The unit in force: given, or inferred from the poses.
    Known {
        /// Metres, millimetres, or `AsGiven` (an explicit `d_max`).
        unit: Unit,
        /// The pose it was inferred from, when it was (the unit `Auto`).
        inferred_at: Option<usize>,
        /// `d_max` in force, in the input's unit.
        d_max: f64,
    },
    /// The first pose's translations fit neither metres nor millimetres: `d_max` stays as
    /// configured until a pose tells.
    Unknown {
        /// The lengths of the first pose's robot and camera translations.
        sizes: [f64; 2],
        /// `d_max` in force, in the input's unit.
        d_max: f64,
    },
}

/// A pose held out of the accumulating estimator's sums, named as its input names it.
#[derive(Debug, Clone, PartialEq)]
pub struct HeldOutPose {
    /// Its pose number (from 1).
    pub pose: usize,
    /// Its name: `file:line`, `file at t = … s`, or `pose N`.
    pub name: String,
    /// Why it was held out.
    pub why: HeldOut,
    /// Whether a face tells it, by the rule of [`Thinning`].
    pub tell: Tell,
}

/// A change of X (or of the target), with the poses it cites named as their input names them.
#[derive(Debug, Clone, PartialEq)]
pub struct ChangeFound {
    /// The change.
    pub change: Change,
    /// The name of the pose where it began (`change.at`).
    pub from: String,
    /// The name of the pose that confirmed it (`change.confirmed`).
    pub confirmed: String,
}

/// Whether a message of one kind is told ([`Thinning`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Tell {
    /// Tell it.
    Now,
    /// Tell it, and that the further ones are counted and told only at the 2^k-th.
    NowThenThinned,
    /// Count it only.
    Counted,
}

impl Tell {
    /// Whether the message is told.
    pub fn told(self) -> bool {
        self != Self::Counted
    }
}

/// The rule by which messages of one kind on a stream (held-out poses, bad lines) are told: the
/// first [`Thinning::ONE_BY_ONE`] one by one, then only every 2^k-th (the count told at the end),
/// so that an endless bad stream cannot flood what a face shows. Every face tells them by it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct Thinning {
    count: usize,
}

impl Thinning {
    /// Messages told one by one before only the 2^k-th are.
    pub const ONE_BY_ONE: usize = 100;

    /// Counts one more message; says whether it is told.
    pub fn tell(&mut self) -> Tell {
        self.count += 1;
        let n = self.count;
        if n == Self::ONE_BY_ONE {
            Tell::NowThenThinned
        } else if n <= Self::ONE_BY_ONE || n.is_power_of_two() {
            Tell::Now
        } else {
            Tell::Counted
        }
    }

    /// Messages counted so far.
    pub fn count(&self) -> usize {
        self.count
    }
}

/// Records kept by their names, for naming the poses held out later (the accumulating estimator
/// may hold out a pose up to 256 poses after it came, when it judges its first poses together).
pub(crate) const NAMES_KEPT: usize = 300;

/// The names of the recent records that have one (a record named by its number needs none),
/// bounded, and the input's name once.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub(crate) struct Names {
    source: String,
    recent: VecDeque<(usize, Kept)>,
}

/// A record's name as kept.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
enum Kept {
    Line(usize),
    Stamp(f64),
    Text(String),
}

impl Names {
    /// Keeps record `number`'s name.
    pub(crate) fn keep(&mut self, number: usize, name: Name<'_>) {
        let kept = match name {
            Name::Numbered => return,
            Name::Line { source, line } => {
                self.source_is(source);
                Kept::Line(line)
            }
            Name::Stamp {
                source, seconds, ..
            } => {
                self.source_is(source);
                Kept::Stamp(seconds)
            }
            Name::Text(text) => Kept::Text(text.to_string()),
        };
        if self.recent.len() == NAMES_KEPT {
            self.recent.pop_front();
        }
        self.recent.push_back((number, kept));
    }

    fn source_is(&mut self, source: &str) {
        if self.source != source {
            self.source = source.to_string();
        }
    }

    /// Pose `number`'s name (`what` names a record known by its number only: `pose`, `record`).
    pub(crate) fn of(&self, number: usize, what: &str) -> String {
        let source = &self.source;
        match self.recent.iter().rev().find(|(n, _)| *n == number) {
            Some((_, Kept::Stamp(t))) => format!("{source} at t = {t:.3} s"),
            Some((_, Kept::Line(line))) => format!("{source}:{line}"),
            Some((_, Kept::Text(text))) => text.clone(),
            None if source.is_empty() => format!("{what} {number}"),
            None => format!("{source}, {what} {number}"),
        }
    }

    /// A record's name as the input gives it, at once (a frame's, for the figures and outlier
    /// lists of the estimates on the pixels).
    pub(crate) fn now(name: Name<'_>, number: usize, what: &str) -> String {
        match name {
            Name::Numbered => format!("{what} {number}"),
            Name::Line { source, line } => format!("{source}:{line}"),
            Name::Stamp {
                source, seconds, ..
            } => format!("{source} at t = {seconds:.3} s"),
            Name::Text(text) => text.to_string(),
        }
    }
}

/// What an online run did ([`OnlineCalibrator::summary`](crate::OnlineCalibrator::summary)).
#[derive(Debug, Clone, PartialEq)]
pub struct Summary {
    /// Records pushed.
    pub poses: usize,
    /// The paper's calibrations made.
    pub calibrations: usize,
    /// The paper's selections that Andreff refused as degenerate (no event for them).
    pub refused: usize,
    /// The paper's latest X.
    pub last_x: Option<Transform>,
    /// The paper's adaptive thresholds in force now.
    pub thresholds: Option<Thresholds>,
    /// With the paper's estimator: why no calibration came (at all, or in the last 200 poses).
    pub stuck: Option<String>,
    /// The accumulating estimator's counts, when it runs.
    pub tracked: Option<Tracked>,
    /// The length unit in force (`Auto` while no pose told it).
    pub unit: Unit,
    /// `d_max` in force, in the input's unit.
    pub d_max: f64,
    /// The input's length unit when known: the one in force, or the one the poses tell (an
    /// explicit `d_max` sets no unit); for publishing X in metres.
    pub length_unit: Option<Unit>,
}

/// The accumulating estimator's counts ([`Summary::tracked`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Tracked {
    /// Poses at the robot pose of the pose before, each counted with it.
    pub repeats: usize,
    /// Poses held out.
    pub held_out: usize,
    /// Changes of X confirmed.
    pub changes: usize,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The first 100 messages are told, the 100th says the rest are thinned, then only the
    /// 2^k-th.
    #[test]
    fn thinning_tells_the_first_hundred_then_the_powers_of_two() {
        let mut thinning = Thinning::default();
        let tells: Vec<Tell> = (0..600).map(|_| thinning.tell()).collect();
        assert!(tells[..99].iter().all(|t| *t == Tell::Now));
        assert_eq!(tells[99], Tell::NowThenThinned);
        let told: Vec<usize> = (101..=600).filter(|n| tells[n - 1].told()).collect();
        assert_eq!(told, [128, 256, 512]);
        assert_eq!(thinning.count(), 600);
    }

    /// A record is named by its line, its stamp, its own name or its number; only the last 300
    /// named are kept, and one named by its number costs nothing.
    #[test]
    fn names_are_the_input_s_and_bounded() {
        let mut names = Names::default();
        assert_eq!(names.of(3, "pose"), "pose 3");
        for n in 1..=400 {
            names.keep(
                n,
                Name::Line {
                    source: "poses.jsonl",
                    line: n + 1,
                },
            );
        }
        assert_eq!(names.recent.len(), NAMES_KEPT);
        assert_eq!(names.of(400, "pose"), "poses.jsonl:401");
        assert_eq!(names.of(50, "pose"), "poses.jsonl, pose 50");
        names.keep(
            401,
            Name::Stamp {
                source: "robot.csv",
                line: 7,
                seconds: 1.25,
            },
        );
        assert_eq!(names.of(401, "pose"), "robot.csv at t = 1.250 s");
        names.keep(402, Name::Text("frame 2"));
        assert_eq!(names.of(402, "pose"), "frame 2");
        names.keep(403, Name::Numbered);
        assert_eq!(names.recent.len(), NAMES_KEPT);
        assert_eq!(Names::now(Name::Numbered, 5, "record"), "record 5");
    }
}
