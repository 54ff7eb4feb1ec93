//! Timestamped pose streams in the TUM / ethz-asl layout: one pose per line,
//! `t x y z qx qy qz qw`, separated by commas or white space, `#` starting a comment. With a
//! rotation convention named, the rotation's numbers are that convention's (`t x y z a b c` for
//! KUKA A, B, C: [`RotationConvention::components`]).

use std::path::Path;

use nalgebra::Vector3;

use crate::io::sync::StampedPose;
use crate::io::{check_stamp, parse_error, read_text};
use crate::model::error::Result;
use crate::model::pose::{check_translation, transform_from_parts};
use crate::model::rotation::{RotationConvention, Rotations};

/// The field names of a stream line before the rotation's, for messages.
const FIELDS: [&str; 4] = ["t", "x", "y", "z"];

/// Reads a stream file: `t x y z qx qy qz qw` per line (the ethz-asl / TUM layout), or `t x y z`
/// and the components of the convention `rotation` names.
pub fn read_stamped_poses(
    path: &Path,
    rotation: Option<RotationConvention>,
) -> Result<StampedStream> {
    let file = path.display().to_string();
    let text = read_text(path)?;
    parse_stamped_poses(&text, &file, rotation)
}

/// Reads a camera stream file, which holds `target_from_camera` (the ethz-asl and TUM layout), as
/// `camera_from_target` samples: what the pose pairs hold.
pub fn read_camera_stream(
    path: &Path,
    rotation: Option<RotationConvention>,
) -> Result<StampedStream> {
    let mut stream = read_stamped_poses(path, rotation)?;
    for s in &mut stream.poses {
        s.pose = s.pose.inverse();
    }
    Ok(stream)
}

/// The fields of a stream line read in `convention`: `t x y z` and its components.
fn layout(convention: RotationConvention) -> String {
    format!("t x y z {}", convention.components().join(" "))
}

/// Why a line has the wrong count of values, and what would read it.
fn wrong_count(found: usize, named: Option<RotationConvention>) -> String {
    let convention = named.unwrap_or(RotationConvention::QuaternionXyzw);
    let expected = 4 + convention.components().len();
    let mut message = format!(
        "{found} values, expected {expected}: {}",
        layout(convention)
    );
    let three = found == 7;
    let four = found == 8;
    match named {
        None if three => message.push_str(&format!(
            " (a quaternion x y z w); 7 values are `t x y z` and three angles or a rotation vector, whose convention a line cannot tell: name it, {} (`robot=NAME` or `camera=NAME` for one stream; NAME one of {})",
            Rotations::flag_words("NAME"),
            RotationConvention::ALL
                .iter()
                .filter(|c| c.components().len() == 3)
                .map(|c| c.name())
                .collect::<Vec<_>>()
                .join(", ")
        )),
        Some(named) if four && named.components().len() == 3 => message.push_str(&format!(
            " ({}, named by `--rotation`); 8 values are `t x y z` and a quaternion: name its order for this stream (`robot=quaternion-xyzw` or `camera=quaternion-xyzw`, or quaternion-wxyz), or drop the name",
            named.describe()
        )),
        Some(named) if three && named.components().len() == 4 => message.push_str(&format!(
            " ({}, named by `--rotation`); 7 values are `t x y z` and three angles or a rotation vector: name their convention for this stream",
            named.describe()
        )),
        Some(named) => message.push_str(&format!(" ({})", named.describe())),
        None => {}
    }
    message
}

/// Parses a stream, its rotations in the convention `rotation` names (a quaternion `x y z w` when
/// none is). Samples out of time order (real recordings have them) are put in order, the later
/// line first among equal stamps, and counted in the result. Errors name the line and the field
/// (`t`, `x` … `qw`, or the convention's components).
pub(crate) fn parse_stamped_poses(
    text: &str,
    source: &str,
    rotation: Option<RotationConvention>,
) -> Result<StampedStream> {
    let convention = rotation.unwrap_or(RotationConvention::QuaternionXyzw);
    let components = convention.components();
    let fields = 4 + components.len();
    let field = |k: usize| {
        if k < 4 { FIELDS[k] } else { components[k - 4] }
    };
    let mut out: Vec<StampedPose> = Vec::new();
    let mut reordered = 0usize;
    let mut largest_degrees: Option<f64> = None;
    for (k, raw) in text.lines().enumerate() {
        let line = k + 1;
        let content = raw.split('#').next().unwrap_or("").trim();
        if content.is_empty() {
            continue;
        }
        let parts: Vec<&str> = content
            .split(|c: char| c == ',' || c.is_whitespace())
            .filter(|s| !s.is_empty())
            .collect();
        if parts.len() != fields {
            return Err(parse_error(
                source,
                line,
                "-",
                wrong_count(parts.len(), rotation),
            ));
        }
        let mut v = [0.0; 8];
        for (i, p) in parts.iter().enumerate() {
            v[i] = p
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| {
                    parse_error(
                        source,
                        line,
                        field(i),
                        format!("expected a finite number, found `{p}`"),
                    )
                })?;
        }
        check_stamp(v[0]).map_err(|m| parse_error(source, line, "t", m))?;
        for k in 1..4 {
            check_translation(v[k])
                .map_err(|e| parse_error(source, line, FIELDS[k], e.to_string()))?;
        }
        if out.last().is_some_and(|last| v[0] < last.stamp) {
            reordered += 1;
        }
        let r = convention.rotation(&v[4..fields]).map_err(|e| {
            let at = match e.component {
                Some(k) => components[k].to_string(),
                None => format!("{}..{}", components[0], components[components.len() - 1]),
            };
            parse_error(source, line, at, e.message)
        })?;
        if convention.in_degrees() {
            let largest = v[4..fields].iter().fold(0.0f64, |m, x| m.max(x.abs()));
            largest_degrees = Some(largest_degrees.map_or(largest, |d| d.max(largest)));
        }
        let pose = transform_from_parts(&r, &Vector3::new(v[1], v[2], v[3]));
        out.push(StampedPose { stamp: v[0], pose });
    }
    if out.len() < 2 {
        return Err(parse_error(
            source,
            0,
            "-",
            format!("{} pose(s) in the stream: at least 2 are needed", out.len()),
        ));
    }
    out.sort_by(|a, b| a.stamp.total_cmp(&b.stamp));
    Ok(StampedStream {
        poses: out,
        reordered,
        largest_degrees,
    })
}

/// A parsed stream.
#[derive(Debug, Clone, PartialEq)]
pub struct StampedStream {
    /// The samples in time order.
    pub poses: Vec<StampedPose>,
    /// How many samples came before an earlier stamp in the file and were moved.
    pub reordered: usize,
    /// With a rotation convention in degrees: the largest angle, in size.
    pub largest_degrees: Option<f64>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::error::Error;

    #[test]
    fn reads_comma_and_space_separated_streams() {
        let a = parse_stamped_poses(
            "# t x y z qx qy qz qw\n1.0, 0, 0, 0, 0, 0, 0, 1\n2.0, 1, 0, 0, 0, 0, 0, 1\n",
            "a",
            None,
        )
        .unwrap();
        let b = parse_stamped_poses("1.0 0 0 0 0 0 0 1\n2.0 1 0 0 0 0 0 1\n", "b", None).unwrap();
        assert_eq!(a, b);
    }

    #[test]
    fn out_of_order_samples_are_sorted_and_counted() {
        let s = parse_stamped_poses(
            "2 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n3 0 0 0 0 0 0 1\n",
            "s",
            None,
        )
        .unwrap();
        assert_eq!(s.reordered, 1);
        assert_eq!(
            s.poses.iter().map(|p| p.stamp).collect::<Vec<_>>(),
            vec![1.0, 2.0, 3.0]
        );
    }

    #[test]
    fn bad_lines_name_line_and_field() {
        let check =
            |text: &str, line: usize, field: &str| match parse_stamped_poses(text, "s.csv", None) {
                Err(Error::Parse {
                    line: l,
                    field: f,
                    file,
                    ..
                }) => {
                    assert_eq!(
                        (l, f.as_str(), file.as_str()),
                        (line, field, "s.csv"),
                        "{text}"
                    );
                }
                other => panic!("{text}: {other:?}"),
            };
        check("1 0 0 0 0 0 0 1\n2 0 0 0 0 0 1\n", 2, "-");
        check("1 0 0 0 0 0 0 1\n2 0 0 zz 0 0 0 1\n", 2, "z");
        check("1 0 0 0 0 0 0 1\n2 0 0 0 0 0 0 3\n", 2, "qx..qw");
        check("1 0 0 0 0 0 0 1\nx 0 0 0 0 0 0 1\n", 2, "t");
        check("1 0 0 0 0 0 0 1\n", 0, "-");
    }
}
