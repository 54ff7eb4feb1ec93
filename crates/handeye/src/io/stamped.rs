//! Timestamped pose streams in the TUM / ethz-asl layout: one pose per line,
//! `t x y z qx qy qz qw`, separated by commas or white space, `#` starting a comment.

use std::path::Path;

use crate::io::sync::StampedPose;
use crate::io::{check_stamp, parse_error, read_text};
use crate::model::error::Result;
use crate::model::pose::{check_translation, transform_from_xyz_quat_xyzw};

/// The field names of a stream line, for messages.
const FIELDS: [&str; 8] = ["t", "x", "y", "z", "qx", "qy", "qz", "qw"];

/// Reads a stream file: `t x y z qx qy qz qw` per line (the ethz-asl / TUM layout).
pub fn read_stamped_poses(path: &Path) -> Result<StampedStream> {
    let file = path.display().to_string();
    let text = read_text(path)?;
    parse_stamped_poses(&text, &file)
}

/// Reads a camera stream file, which holds `target_from_camera` (the ethz-asl and TUM layout), as
/// `camera_from_target` samples: what the pose pairs hold.
pub fn read_camera_stream(path: &Path) -> Result<StampedStream> {
    let mut stream = read_stamped_poses(path)?;
    for s in &mut stream.poses {
        s.pose = s.pose.inverse();
    }
    Ok(stream)
}

/// Parses a stream. Samples out of time order (real recordings have them) are put in order, the
/// later line first among equal stamps, and counted in the result. Errors name the line and the
/// field (`t`, `x` … `qw`).
pub(crate) fn parse_stamped_poses(text: &str, source: &str) -> Result<StampedStream> {
    let mut out: Vec<StampedPose> = Vec::new();
    let mut reordered = 0usize;
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
        if parts.len() != 8 {
            return Err(parse_error(
                source,
                line,
                "-",
                format!("{} values, expected 8: t x y z qx qy qz qw", parts.len()),
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
                        FIELDS[i],
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
        let pose = transform_from_xyz_quat_xyzw([v[1], v[2], v[3]], [v[4], v[5], v[6], v[7]])
            .map_err(|e| parse_error(source, line, "qx..qw", e.to_string()))?;
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
    })
}

/// A parsed stream.
#[derive(Debug, Clone, PartialEq)]
pub struct StampedStream {
    /// The samples in time order.
    pub poses: Vec<StampedPose>,
    /// How many samples came before an earlier stamp in the file and were moved.
    pub reordered: usize,
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
        )
        .unwrap();
        let b = parse_stamped_poses("1.0 0 0 0 0 0 0 1\n2.0 1 0 0 0 0 0 1\n", "b").unwrap();
        assert_eq!(a, b);
    }

    #[test]
    fn out_of_order_samples_are_sorted_and_counted() {
        let s = parse_stamped_poses("2 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n3 0 0 0 0 0 0 1\n", "s")
            .unwrap();
        assert_eq!(s.reordered, 1);
        assert_eq!(
            s.poses.iter().map(|p| p.stamp).collect::<Vec<_>>(),
            vec![1.0, 2.0, 3.0]
        );
    }

    #[test]
    fn bad_lines_name_line_and_field() {
        let check = |text: &str, line: usize, field: &str| match parse_stamped_poses(text, "s.csv")
        {
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
