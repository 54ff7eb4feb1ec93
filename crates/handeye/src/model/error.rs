//! The library's one error type.

use std::fmt;

/// What is wrong with a transform read from data.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum TransformProblem {
    /// A NaN or infinite entry.
    NotFinite,
    /// `RᵀR` differs from the identity by more than
    /// `ORTHONORMAL_TOL` (the largest entry deviation is given).
    NotOrthonormal {
        /// Largest absolute entry of `RᵀR − I`.
        deviation: f64,
    },
    /// The rotation part has a negative determinant (a reflection).
    Reflection,
    /// The last row of a homogeneous matrix is not `0 0 0 1`.
    BadLastRow,
    /// A quaternion whose norm is not within 1e-3 of 1.
    QuaternionNorm {
        /// The norm found.
        norm: f64,
    },
    /// Both a matrix and translation + quaternion were given and they differ by more than 1e-6 and
    /// more than the matrix's deviation from orthonormality (the precision it was printed with).
    Inconsistent {
        /// Largest entry difference between the two.
        difference: f64,
    },
    /// A translation component beyond `MAX_TRANSLATION` in size:
    /// not a length in any unit (a corrupt field), and one whose products could overflow.
    ImplausibleTranslation {
        /// The value found.
        value: f64,
    },
}

impl fmt::Display for TransformProblem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::NotFinite => write!(f, "contains a NaN or infinite value"),
            Self::NotOrthonormal { deviation } => write!(
                f,
                "rotation is not orthonormal (|RᵀR − I| reaches {deviation:.3e}, more than {:e}: beyond rounding when printed)",
                crate::model::pose::ORTHONORMAL_TOL
            ),
            Self::Reflection => write!(f, "rotation has det < 0 (a reflection, not a rotation)"),
            Self::BadLastRow => write!(f, "last row of the 4×4 matrix is not [0, 0, 0, 1]"),
            Self::QuaternionNorm { norm } => {
                write!(f, "quaternion norm is {norm:.6}, not within 1e-3 of 1")
            }
            Self::Inconsistent { difference } => write!(
                f,
                "`matrix` and `translation`/`quaternion_xyzw` disagree (by {difference:.3e}, more than 1e-6 and more than the matrix's own rounding)"
            ),
            Self::ImplausibleTranslation { value } => write!(
                f,
                "translation {value:e} is not a plausible length in any unit (more than {:e} in size)",
                crate::model::pose::MAX_TRANSLATION
            ),
        }
    }
}

/// Why a set of motions cannot determine X.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum Degeneracy {
    /// Every motion's rotation is (nearly) zero, so no axis constrains the rotation of X.
    SmallRotations {
        /// The largest rotation angle among the motions, degrees.
        largest_deg: f64,
    },
    /// All rotation axes are (nearly) parallel: X's rotation about that axis is undetermined.
    ParallelAxes {
        /// The largest angle between two motion axes, degrees.
        largest_axis_angle_deg: f64,
    },
    /// The rotation system is too ill-conditioned to trust (conditioning given).
    IllConditioned,
    /// The gripper motions (nearly) do not translate, which the simultaneous form needs to fix
    /// the scale of R_x.
    NoTranslation {
        /// The largest gripper translation among the motions, input units.
        largest: f64,
    },
    /// Under the data's own noise one direction of X moves beyond the refusal threshold
    /// (`crate::uncertainty`): the motions do not determine it.
    Undetermined {
        /// The direction (rotation about `axis`, or translation along it).
        part: crate::model::findings::Part,
        /// The direction, in X's reference frame.
        axis: [f64; 3],
        /// Its one-sigma: degrees for rotation, input units for translation.
        sigma: f64,
        /// The setup, which names X's reference frame.
        setup: crate::model::motion::Setup,
    },
    /// Re-solving under the data's own noise was refused too often: X is at the edge of what the
    /// motions determine.
    Unstable {
        /// Re-solves refused.
        refused: usize,
        /// Re-solves tried.
        tried: usize,
    },
}

impl fmt::Display for Degeneracy {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::SmallRotations { largest_deg } => write!(
                f,
                "all rotations are too small (largest {largest_deg:.3}°): move the gripper through larger rotations"
            ),
            Self::ParallelAxes {
                largest_axis_angle_deg,
            } => write!(
                f,
                "all rotation axes are nearly parallel (at most {largest_axis_angle_deg:.3}° apart): rotate about at least two clearly different axes"
            ),
            Self::NoTranslation { largest } => write!(
                f,
                "the gripper barely translates (largest motion {largest:.3e}): the simultaneous form cannot fix the scale of the rotation; use `andreff` or another method"
            ),
            Self::Undetermined {
                part,
                axis,
                sigma,
                setup,
            } => f.write_str(&crate::model::findings::advice(
                *part,
                &crate::model::findings::Direction {
                    axis: *axis,
                    sigma: *sigma,
                    verdict: crate::model::findings::Verdict::Undetermined,
                },
                *setup,
            )),
            Self::Unstable { refused, tried } => write!(
                f,
                "{refused} of {tried} re-solves under the data's own noise were refused: X is at the edge of what these motions determine; add motions with larger rotations about different axes"
            ),
            Self::IllConditioned => write!(
                f,
                "the rotation system is too ill-conditioned: add motions with larger rotations about different axes"
            ),
        }
    }
}

/// Every error of the library.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Fewer motions than the method needs.
    #[error(
        "{got} motion(s) given, at least {need} needed: record more poses (each motion joins two poses)"
    )]
    TooFewMotions {
        /// Motions given.
        got: usize,
        /// Motions needed.
        need: usize,
    },
    /// The motions cannot determine X.
    #[error("degenerate motions: {reason} (conditioning {conditioning:.3e})")]
    Degenerate {
        /// Which degeneracy.
        reason: Degeneracy,
        /// Conditioning of the rotation system (second-smallest over largest singular value).
        conditioning: f64,
    },
    /// A transform that is not rigid.
    #[error("{what}: {problem}")]
    InvalidTransform {
        /// Which transform (field, pose number …).
        what: String,
        /// What is wrong.
        problem: TransformProblem,
    },
    /// The poses fit far better read another way (inverted, another quaternion order, another
    /// unit): the as-given reading would give a wrong X.
    #[error("the input looks misread: {advice}")]
    Misread {
        /// What fits better, and the fix.
        advice: String,
        /// The readings that fit far better, the one the advice leads with first: for a face
        /// that words the fix in its own terms (the OpenCV drop-in names OpenCV's arguments).
        readings: Vec<crate::model::findings::Reading>,
    },
    /// X is not determined, and the input shows why: outlier poses, or a reading of the input
    /// that fits far better (kept by request).
    #[error("X cannot be trusted: {advice}")]
    Untrusted {
        /// What is undetermined, what the input shows, and the fix.
        advice: String,
    },
    /// Malformed input data, with its place.
    #[error("{file}:{line}: field `{field}`: {message}")]
    Parse {
        /// File name (or `-` for standard input).
        file: String,
        /// Line number, from 1 (0 when the problem concerns the whole file).
        line: usize,
        /// Field or column concerned.
        field: String,
        /// What is wrong.
        message: String,
    },
    /// A ROS 2 recording that cannot be read or used: the file, the place (topic and message
    /// number) when one message is at fault, and what is wrong.
    #[error("{file}{}: {message}", .at.as_ref().map(|a| format!(" ({a})")).unwrap_or_default())]
    Bag {
        /// The recording or one of its storage files.
        file: String,
        /// Where in it: `topic /tf, message 12`.
        at: Option<String>,
        /// What is wrong.
        message: String,
    },
    /// A file could not be read.
    #[error("{file}: {source}")]
    Io {
        /// File name.
        file: String,
        /// Underlying error.
        source: std::io::Error,
    },
    /// The clock offset of two streams could not be found (`auto`): which streams, and why.
    #[error("time offset `auto` on {streams}: {source}")]
    TimeOffset {
        /// The streams searched (two files, or a recording's robot and target).
        streams: String,
        /// Why the search failed.
        source: Box<Error>,
    },
    /// A parameter out of its valid range.
    #[error("parameter `{name}`: {message}")]
    InvalidParameter {
        /// The parameter's name.
        name: &'static str,
        /// What is wrong.
        message: String,
    },
}

/// Result alias of the library.
pub type Result<T, E = Error> = std::result::Result<T, E>;
