//! A pose file read whole ([`PoseSeries`]), and what reading it noticed: the setup it declares,
//! the rotation matrices projected onto SO(3).

use super::parse_error;
use crate::model::error::Result;
use crate::model::findings::Written;
use crate::model::motion::{PosePair, Setup};
use crate::model::pose::ReadTransform;

/// A whole pose file.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseSeries {
    /// The pose pairs in file order.
    pub pairs: Vec<PosePair>,
    /// Their stamps, where the file gives them.
    pub stamps: Vec<Option<f64>>,
    /// Their line numbers.
    pub lines: Vec<usize>,
    /// The robot's joint angles at each pair, where the records give them (every record as many,
    /// the reader's rule); empty when they do not.
    pub joints: Vec<Vec<f64>>,
    /// The rotation matrices that were orthonormal only to the precision they were printed with
    /// and were projected onto the nearest rotation.
    pub projections: Projections,
    /// The directions in which the file wrote its poses (for `Options::written`).
    pub written: Written,
    /// The setup the file declares, if it declares one (easy_handeye2's samples do).
    pub setup: Option<DeclaredSetup>,
}

/// The setup a pose file declares, and the line where it does.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DeclaredSetup {
    /// The setup.
    pub setup: Setup,
    /// Its line, from 1.
    pub line: usize,
}

/// A setup as a sample file's reader says it.
fn setup_words(setup: Setup) -> &'static str {
    match setup {
        Setup::EyeInHand => "eye-in-hand (a camera on the gripper)",
        Setup::EyeToHand => "eye-to-hand (a fixed camera)",
    }
}

impl PoseSeries {
    /// Refuses to read the file `source` for `setup` when it declares the other one: its robot
    /// poses were written for that one, and an X solved the other way would be meaningless.
    pub fn check_setup(&self, setup: Setup, source: &str) -> Result<()> {
        match self.setup {
            Some(declared) if declared.setup != setup => Err(parse_error(
                source,
                declared.line,
                "parameters.calibration_type",
                format!(
                    "the file declares {}, and this run asks for {}: calibrate it with the setup it declares",
                    setup_words(declared.setup),
                    setup_words(setup)
                ),
            )),
            _ => Ok(()),
        }
    }
}

/// The least deviation from orthonormality a note names ([`Projections::note`]): rounding to 6
/// decimals (about 1e-6) is worth saying, to 10 is not.
pub const NOTED_DEVIATION: f64 = 1e-6;

/// The rotation matrices of one input that were orthonormal only to the precision they were
/// printed with (between `KEEP_AS_GIVEN_TOL` and
/// `ORTHONORMAL_TOL`) and were projected onto the nearest rotation.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Projections {
    /// How many matrices were projected.
    pub count: usize,
    /// The largest deviation `max |RᵀR − I|` among them.
    pub largest_deviation: f64,
}

impl Projections {
    /// Counts `read` when its rotation was projected.
    pub(crate) fn add(&mut self, read: &ReadTransform) {
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
        // Matrices orthonormal to 1e-10 (printed with 10 digits) are projected without a word:
        // a note on them is noise.
        (self.count > 0 && self.largest_deviation > NOTED_DEVIATION).then(|| {
            format!(
                "{} rotation {} orthonormal only to {:.0e} (rounded when printed): projected onto the nearest rotation",
                self.count,
                if self.count == 1 { "matrix" } else { "matrices" },
                self.largest_deviation
            )
        })
    }
}
