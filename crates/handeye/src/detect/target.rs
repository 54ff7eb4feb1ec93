//! The target seen in the images (`--target SPEC`): a chessboard's inner corners or one
//! AprilTag 36h11's four corners, with their coordinates on the target (docs/SPEC.md, sec. 7,
//! `detect`).

use std::fmt;
use std::str::FromStr;

use crate::model::error::{Error, Result};

/// The largest number of inner corners along a side of a chessboard (a bound on what a spec may
/// ask to be allocated, far beyond any printed board).
pub const MAX_SIDE: usize = 200;

/// A calibration target, as `--target` spells it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Target {
    /// A chessboard of `cols` × `rows` inner corners, `square` apart (the input's unit). Corner
    /// (row i, column j) is at (j·square, i·square, 0); which corner is (0, 0) is told by the
    /// squares' colours (see `detect::chessboard`), so `cols + rows` must be odd.
    Chessboard {
        /// Inner corners along a row.
        cols: usize,
        /// Inner corners along a column.
        rows: usize,
        /// The side of a square.
        square: f64,
    },
    /// One AprilTag of family 36h11, `size` its black square's side: its corners at (±size/2,
    /// ±size/2, 0), z out of the tag's back (ViSP's tag frame).
    AprilTag36h11 {
        /// The side of the tag's black square.
        size: f64,
    },
}

fn bad(spec: &str, why: impl fmt::Display) -> Error {
    Error::InvalidParameter {
        name: "target",
        message: format!(
            "`{spec}`: {why}; expected `chessboard:COLSxROWS:SQUARE` (inner corners, e.g. `chessboard:9x6:0.0236`) or `apriltag36h11:SIZE` (e.g. `apriltag36h11:0.048`)"
        ),
    }
}

fn length(spec: &str, text: &str, what: &str) -> Result<f64> {
    let v: f64 = text
        .trim()
        .parse()
        .map_err(|_| bad(spec, format!("the {what} `{text}` is not a number")))?;
    if !(v.is_finite() && v > 0.0) {
        return Err(bad(
            spec,
            format!("the {what} must be positive, got {text}"),
        ));
    }
    Ok(v)
}

fn count(spec: &str, text: &str) -> Result<usize> {
    let n: usize = text
        .trim()
        .parse()
        .map_err(|_| bad(spec, format!("`{text}` is not a count of inner corners")))?;
    if !(2..=MAX_SIDE).contains(&n) {
        return Err(bad(
            spec,
            format!("{n} inner corners along a side: from 2 to {MAX_SIDE}"),
        ));
    }
    Ok(n)
}

impl FromStr for Target {
    type Err = Error;

    fn from_str(spec: &str) -> Result<Self> {
        let parts: Vec<&str> = spec.split(':').collect();
        match parts.as_slice() {
            ["chessboard", size, square] => {
                let (cols, rows) = size
                    .split_once(['x', 'X'])
                    .ok_or_else(|| bad(spec, format!("`{size}` is not COLSxROWS")))?;
                let (cols, rows) = (count(spec, cols)?, count(spec, rows)?);
                if (cols + rows) % 2 == 0 {
                    return Err(bad(
                        spec,
                        format!(
                            "a board of {cols}x{rows} inner corners looks the same turned by half a turn, so the images cannot tell its corner (0, 0) and X would be wrong by that turn: use a board with one odd and one even count (9x6, 7x4, …)"
                        ),
                    ));
                }
                Ok(Self::Chessboard {
                    cols,
                    rows,
                    square: length(spec, square, "square's side")?,
                })
            }
            ["apriltag36h11", size] => Ok(Self::AprilTag36h11 {
                size: length(spec, size, "tag's size")?,
            }),
            [kind, ..] if !["chessboard", "apriltag36h11"].contains(kind) => {
                Err(bad(spec, format!("unknown target `{kind}`")))
            }
            _ => Err(bad(spec, "wrong number of `:`-separated fields")),
        }
    }
}

impl fmt::Display for Target {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Chessboard { cols, rows, square } => {
                write!(f, "chessboard:{cols}x{rows}:{square}")
            }
            Self::AprilTag36h11 { size } => write!(f, "apriltag36h11:{size}"),
        }
    }
}

impl Target {
    /// How many points a whole detection has.
    pub fn points(&self) -> usize {
        match self {
            Self::Chessboard { cols, rows, .. } => cols * rows,
            Self::AprilTag36h11 { .. } => 4,
        }
    }

    /// The target's points in its own frame, in the order detections list them: a chessboard's
    /// row by row, a tag's as `detect::apriltag` orders its corners.
    pub fn target_points(&self) -> Vec<[f64; 3]> {
        match *self {
            Self::Chessboard { cols, rows, square } => (0..rows)
                .flat_map(|i| (0..cols).map(move |j| [j as f64 * square, i as f64 * square, 0.0]))
                .collect(),
            Self::AprilTag36h11 { size } => {
                let h = size / 2.0;
                TAG_CORNERS
                    .iter()
                    .map(|&(x, y)| [x * h, -y * h, 0.0])
                    .collect()
            }
        }
    }
}

/// The tag's corners in the AprilTag library's own coordinates (its homography's, ±1), in the
/// order detections list them; the tag frame's point is (x·size/2, −y·size/2, 0) (ViSP's frame:
/// the library's corners turned by half a turn about x).
pub const TAG_CORNERS: [(f64, f64); 4] = [(1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (1.0, -1.0)];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spellings_parse_and_print_back() {
        for spec in ["chessboard:9x6:0.0236", "apriltag36h11:0.048"] {
            let t: Target = spec.parse().unwrap();
            assert_eq!(t.to_string(), spec);
        }
        let t: Target = "chessboard:9x6:0.0236".parse().unwrap();
        assert_eq!(t.points(), 54);
        let p = t.target_points();
        assert_eq!(p[1], [0.0236, 0.0, 0.0]);
        assert_eq!(p[9], [0.0, 0.0236, 0.0]);
    }

    #[test]
    fn bad_specs_are_refused_saying_why() {
        for (spec, says) in [
            ("chessboard:8x6:0.02", "half a turn"),
            ("chessboard:9x6", "number of"),
            ("chessboard:9by6:0.02", "COLSxROWS"),
            ("chessboard:9x6:-1", "positive"),
            ("chessboard:9x1:0.02", "from 2"),
            ("chessboard:99999x6:0.02", "from 2"),
            ("charuco:5x7:0.03", "unknown target `charuco`"),
            ("apriltag36h11:big", "not a number"),
            ("apriltag36h11:inf", "positive"),
        ] {
            let e = spec.parse::<Target>().unwrap_err().to_string();
            assert!(e.contains(says), "{spec}: {e}");
            assert!(e.contains(spec), "{spec}: {e}");
        }
    }
}
