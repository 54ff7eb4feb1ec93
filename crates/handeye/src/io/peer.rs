//! The pose files of other calibration tools: OpenCV-YAML pairs (camodocal), moveit_calibration's
//! sample JSON, and ViSP's `pose_fPe_*.yaml` / `pose_cPo_*.yaml`.

use std::path::{Path, PathBuf};

use nalgebra::{Matrix4, Vector3};
use serde_json::Value;

use crate::error::{Error, Result};
use crate::io::{PoseSeries, parse_error, read_text, transform_from_json};
use crate::motion::PosePair;
use crate::pose::{Transform, exp_so3, transform_from_matrix4, transform_from_parts};

/// Reads OpenCV-YAML pose pairs as camodocal writes them: `T1_i` and `T2_i`, each a 4×4
/// `!!opencv-matrix`, for i = 0, 1, …
///
/// camodocal's pairs are eye-to-hand recordings with the tag on the arm; `T1_i` is read as the
/// robot's `gripper_from_base` and `T2_i` as the camera's `target_from_camera`, the directions with
/// which the file's own data agree on one X (`--setup eye-to-hand`).
pub fn read_opencv_yaml(text: &str, file: &str) -> Result<PoseSeries> {
    let mut t1: Vec<(usize, Transform)> = Vec::new();
    let mut t2: Vec<(usize, Transform)> = Vec::new();
    let lines: Vec<&str> = text.lines().collect();
    let mut k = 0;
    while k < lines.len() {
        let line = lines[k].trim();
        let key = line.split(':').next().unwrap_or("");
        let which = if key.starts_with("T1_") {
            Some(1)
        } else if key.starts_with("T2_") {
            Some(2)
        } else {
            None
        };
        let Some(which) = which else {
            k += 1;
            continue;
        };
        let index: usize = key[3..]
            .parse()
            .map_err(|_| parse_error(file, k + 1, key, "expected `T1_<n>` or `T2_<n>`"))?;
        let start = k + 1;
        // Collect the numbers of `data: [ … ]`, which may span lines.
        let mut j = k + 1;
        while j < lines.len() && !lines[j].contains("data:") {
            j += 1;
        }
        let mut body = String::new();
        while j < lines.len() {
            let l = lines[j];
            body.push_str(l.split("data:").last().unwrap_or(l));
            body.push(' ');
            if l.contains(']') {
                break;
            }
            j += 1;
        }
        let numbers: Vec<f64> = body
            .trim()
            .trim_start_matches('[')
            .trim_end_matches(']')
            .split(',')
            .map(|s| s.trim().parse::<f64>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| {
                parse_error(
                    file,
                    start,
                    format!("{key}.data"),
                    "expected 16 numbers in `data: [...]`",
                )
            })?;
        if numbers.len() != 16 {
            return Err(parse_error(
                file,
                start,
                format!("{key}.data"),
                format!("{} numbers, expected 16 (a 4×4 matrix)", numbers.len()),
            ));
        }
        let m = Matrix4::from_row_slice(&numbers);
        let t =
            transform_from_matrix4(&m).map_err(|p| parse_error(file, start, key, p.to_string()))?;
        if which == 1 {
            t1.push((index, t))
        } else {
            t2.push((index, t))
        }
        k = j + 1;
    }
    t1.sort_by_key(|(i, _)| *i);
    t2.sort_by_key(|(i, _)| *i);
    if t1.len() != t2.len() || t1.iter().zip(&t2).any(|(a, b)| a.0 != b.0) {
        return Err(parse_error(
            file,
            0,
            "T1_*/T2_*",
            format!(
                "{} `T1_` and {} `T2_` matrices do not pair up by index",
                t1.len(),
                t2.len()
            ),
        ));
    }
    let pairs = t1
        .iter()
        .zip(&t2)
        .map(
            |((_, gripper_from_base), (_, target_from_camera))| PosePair {
                base_from_gripper: gripper_from_base.inverse(),
                camera_from_target: target_from_camera.inverse(),
            },
        )
        .collect();
    series(pairs, file)
}

/// Reads moveit_calibration's sample JSON: a list of `[[4×4 effector in base], [4×4 object in
/// camera]]` pairs (`base_from_gripper`, `camera_from_target`), each matrix as 4 rows or 16 numbers.
pub fn read_moveit_json(text: &str, file: &str) -> Result<PoseSeries> {
    let value: Value = serde_json::from_str(text)
        .map_err(|e| parse_error(file, e.line(), "-", format!("malformed JSON: {e}")))?;
    let list = value.as_array().ok_or_else(|| {
        parse_error(
            file,
            1,
            "-",
            "expected a list of [effector_in_base, object_in_camera] pairs",
        )
    })?;
    let mut pairs = Vec::with_capacity(list.len());
    for (k, item) in list.iter().enumerate() {
        let field = |j: usize, name: &str| -> Result<Transform> {
            let v = item.get(j).ok_or_else(|| {
                parse_error(
                    file,
                    0,
                    format!("[{k}][{j}]"),
                    format!("missing the {name} matrix"),
                )
            })?;
            let v = match v.as_array() {
                Some(flat) if flat.len() == 16 => {
                    Value::Array(flat.chunks(4).map(|r| Value::Array(r.to_vec())).collect())
                }
                _ => v.clone(),
            };
            transform_from_json(&v)
                .map_err(|p| parse_error(file, 0, format!("[{k}][{j}]{}", p.field), p.message))
        };
        pairs.push(PosePair {
            base_from_gripper: field(0, "effector-in-base")?,
            camera_from_target: field(1, "object-in-camera")?,
        });
    }
    series(pairs, file)
}

/// Reads a ViSP recording: the files `pose_fPe_<i>.yaml` (effector in the fixed frame,
/// `base_from_gripper`) and `pose_cPo_<i>.yaml` (object in the camera, `camera_from_target`) of a
/// directory, each a 6-vector `tx ty tz θux θuy θuz` (metres, radians), paired by index.
pub fn read_visp_dir(dir: &Path) -> Result<PoseSeries> {
    let name = dir.display().to_string();
    let entries = std::fs::read_dir(dir).map_err(|e| Error::Io {
        file: name.clone(),
        source: e,
    })?;
    let mut robot: Vec<(usize, PathBuf)> = Vec::new();
    for e in entries.flatten() {
        let file = e.file_name().to_string_lossy().into_owned();
        if let Some(index) = file
            .strip_prefix("pose_fPe_")
            .and_then(|s| s.strip_suffix(".yaml"))
            .and_then(|s| s.parse().ok())
        {
            robot.push((index, e.path()));
        }
    }
    robot.sort();
    if robot.is_empty() {
        return Err(parse_error(
            &name,
            0,
            "pose_fPe_*.yaml",
            "no ViSP robot pose files in this directory",
        ));
    }
    let mut pairs = Vec::with_capacity(robot.len());
    for (index, path) in robot {
        let camera = dir.join(format!("pose_cPo_{index}.yaml"));
        pairs.push(PosePair {
            base_from_gripper: read_visp_pose(&path)?,
            camera_from_target: read_visp_pose(&camera)?,
        });
    }
    series(pairs, &name)
}

/// One ViSP pose file: `data:` followed by six numbers, as `- [v]` lines or one `[…]` list.
pub fn read_visp_pose(path: &Path) -> Result<Transform> {
    let file = path.display().to_string();
    let text = read_text(path)?;
    let Some(at) = text.find("data:") else {
        return Err(parse_error(
            &file,
            0,
            "data",
            "missing `data:` (expected a ViSP vpPoseVector YAML)",
        ));
    };
    let line = text[..at].lines().count().max(1);
    let values: Vec<f64> = text[at + 5..]
        .split(|c: char| c == '[' || c == ']' || c == ',' || c.is_whitespace())
        .filter(|s| !s.is_empty() && *s != "-")
        .map(|s| {
            s.parse::<f64>().map_err(|_| {
                parse_error(
                    &file,
                    line,
                    "data",
                    format!("expected a number, found `{s}`"),
                )
            })
        })
        .collect::<Result<_>>()?;
    if values.len() != 6 || values.iter().any(|v| !v.is_finite()) {
        return Err(parse_error(
            &file,
            line,
            "data",
            format!(
                "{} values, expected 6 finite: tx ty tz θux θuy θuz",
                values.len()
            ),
        ));
    }
    let rotation = exp_so3(&Vector3::new(values[3], values[4], values[5]));
    Ok(transform_from_parts(
        &rotation,
        &Vector3::new(values[0], values[1], values[2]),
    ))
}

/// Wraps pairs as a series, refusing fewer than 2.
fn series(pairs: Vec<PosePair>, file: &str) -> Result<PoseSeries> {
    if pairs.len() < 2 {
        return Err(parse_error(
            file,
            0,
            "-",
            format!(
                "{} pose pair(s): at least 2 are needed to make a motion",
                pairs.len()
            ),
        ));
    }
    let n = pairs.len();
    Ok(PoseSeries {
        pairs,
        stamps: vec![None; n],
        lines: vec![0; n],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_the_camodocal_file() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../testdata/real/camodocal/TransformPairsInput.yml");
        let s = read_opencv_yaml(&std::fs::read_to_string(path).unwrap(), "camodocal").unwrap();
        assert_eq!(s.pairs.len(), 42);
    }

    #[test]
    fn broken_yaml_names_the_matrix() {
        let good = "T1_0: !!opencv-matrix\n   rows: 4\n   cols: 4\n   dt: d\n   data: [ 1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1. ]\n";
        let short = good
            .replace(" 0., 0., 0., 1. ]", " 0., 0., 1. ]")
            .replace("T1_0", "T2_0");
        match read_opencv_yaml(&format!("%YAML:1.0\n{good}{short}"), "p.yml") {
            Err(Error::Parse { line, field, .. }) => {
                assert_eq!(line, 7);
                assert_eq!(field, "T2_0.data");
            }
            other => panic!("{other:?}"),
        }
        let bad = good.replace("data: [ 1.,", "data: [ 2.,");
        assert!(
            matches!(read_opencv_yaml(&bad, "p.yml"), Err(Error::Parse { field, .. }) if field == "T1_0")
        );
    }

    #[test]
    fn reads_moveit_json_and_refuses_broken() {
        let i = "[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]";
        let flat = "[1,0,0,1, 0,1,0,0, 0,0,1,0, 0,0,0,1]";
        let s = read_moveit_json(&format!("[[{i}, {flat}], [{flat}, {i}]]"), "m.json").unwrap();
        assert_eq!(s.pairs[0].camera_from_target.translation.vector.x, 1.0);
        assert!(
            matches!(read_moveit_json(&format!("[[{i}]]"), "m.json"), Err(Error::Parse { field, .. }) if field == "[0][1]")
        );
        assert!(matches!(
            read_moveit_json("{", "m.json"),
            Err(Error::Parse { .. })
        ));
    }

    #[test]
    fn reads_visp_directories() {
        let dir = std::env::temp_dir().join(format!("handeye-visp-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for k in 1..=3 {
            let v = 0.1 * k as f64;
            std::fs::write(dir.join(format!("pose_fPe_{k}.yaml")), format!("rows: 6\ncols: 1\ndata:\n  - [{v}]\n  - [0]\n  - [0.5]\n  - [{v}]\n  - [0]\n  - [-0.2]\n")).unwrap();
            std::fs::write(
                dir.join(format!("pose_cPo_{k}.yaml")),
                "rows: 6\ncols: 1\ndata: [0, 0, 1, 0, 3.1, 0]\n",
            )
            .unwrap();
        }
        let s = read_visp_dir(&dir).unwrap();
        assert_eq!(s.pairs.len(), 3);
        assert!((s.pairs[1].base_from_gripper.translation.vector.x - 0.2).abs() < 1e-15);
        std::fs::write(
            dir.join("pose_cPo_2.yaml"),
            "rows: 6\ncols: 1\ndata: [0, 0, 1, 0, x, 0]\n",
        )
        .unwrap();
        match read_visp_dir(&dir) {
            Err(Error::Parse { file, field, .. }) => {
                assert!(file.ends_with("pose_cPo_2.yaml"));
                assert_eq!(field, "data");
            }
            other => panic!("{other:?}"),
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
