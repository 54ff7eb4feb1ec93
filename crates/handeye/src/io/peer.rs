//! The pose files of other calibration tools: OpenCV-YAML pairs (camodocal), moveit_calibration's
//! sample JSON, and ViSP's `pose_fPe_*.yaml` / `pose_cPo_*.yaml`.

use std::collections::BTreeMap;
use std::path::Path;

use nalgebra::{Matrix4, Vector3};
use serde_json::Value;

use crate::io::json_text::{Step, line_of_field, path_name, repeated_key, steps};
use crate::io::yaml_tree::YamlTree;
use crate::io::{
    DeclaredSetup, FieldProblem, PoseSeries, Projections, parse_error, read_text,
    read_transform_json,
};
use crate::model::error::{Error, Result};
use crate::model::findings::{Written, WrittenAs};
use crate::model::motion::{PosePair, Setup};
use crate::model::pose::{
    ReadTransform, Transform, check_translation, exp_so3, read_matrix4, transform_from_parts,
    transform_from_xyz_quat_xyzw,
};

/// Reads OpenCV-YAML pose pairs as camodocal writes them: `T1_i` and `T2_i`, each a 4×4
/// `!!opencv-matrix`, for i = 0, 1, …
///
/// camodocal's pairs are eye-to-hand recordings with the tag on the arm; `T1_i` is read as the
/// robot's `gripper_from_base` and `T2_i` as the camera's `target_from_camera`, the directions with
/// which the file's own data agree on one X (`--setup eye-to-hand`).
pub fn read_opencv_yaml(text: &str, file: &str) -> Result<PoseSeries> {
    let mut t1: Vec<YamlMatrix> = Vec::new();
    let mut t2: Vec<YamlMatrix> = Vec::new();
    let mut projections = Projections::default();
    let lines: Vec<&str> = text.lines().collect();
    let mut k = 0;
    while k < lines.len() {
        let Some((which, key)) = matrix_key(lines[k]) else {
            k += 1;
            continue;
        };
        let index: usize = key[3..]
            .parse()
            .map_err(|_| parse_error(file, k + 1, key, "expected `T1_<n>` or `T2_<n>`"))?;
        let (read, next) = yaml_matrix(&lines, k, key, file)?;
        projections.add(&read);
        let m = YamlMatrix {
            index,
            line: k + 1,
            key: key.to_string(),
            transform: read.transform,
        };
        if which == 1 {
            t1.push(m)
        } else {
            t2.push(m)
        }
        k = next;
    }
    let (pairs, lines) = pair_up(t1, t2, file)?
        .into_iter()
        .map(|(gripper_from_base, target_from_camera, line)| {
            let pair = PosePair {
                base_from_gripper: gripper_from_base.inverse(),
                camera_from_target: target_from_camera.inverse(),
            };
            (pair, line)
        })
        .unzip();
    let series = series_at(pairs, lines, file, projections)?;
    Ok(PoseSeries {
        written: Written {
            robot: WrittenAs::Inverse,
            camera: WrittenAs::Inverse,
            frames: false,
        },
        ..series
    })
}

/// One `T1_i` or `T2_i` matrix of an OpenCV-YAML file, with its place.
struct YamlMatrix {
    index: usize,
    /// Line of its key, from 1.
    line: usize,
    key: String,
    transform: Transform,
}

/// Which matrix (1 or 2) a line's key opens, and the key (`T1_3`).
fn matrix_key(line: &str) -> Option<(u8, &str)> {
    let key = line.trim().split(':').next().unwrap_or("");
    if key.starts_with("T1_") {
        Some((1, key))
    } else if key.starts_with("T2_") {
        Some((2, key))
    } else {
        None
    }
}

/// The matrix whose key is on line `k` (from 0): the 16 numbers of its `data: [ … ]`, which may
/// span lines, and the index of the line after it.
fn yaml_matrix(lines: &[&str], k: usize, key: &str, file: &str) -> Result<(ReadTransform, usize)> {
    let field = format!("{key}.data");
    let mut j = k + 1;
    while j < lines.len() && !lines[j].contains("data:") {
        if matrix_key(lines[j]).is_some() {
            break;
        }
        j += 1;
    }
    if j >= lines.len() || !lines[j].contains("data:") {
        return Err(parse_error(file, k + 1, field, "missing `data: [...]`"));
    }
    // Each number with the line (from 1) it is on.
    let mut numbers: Vec<(&str, usize)> = Vec::new();
    let mut closed = false;
    while j < lines.len() && !closed {
        let l = lines[j];
        let body = l.split("data:").last().unwrap_or(l);
        closed = body.contains(']');
        let body = body.split(']').next().unwrap_or("");
        numbers.extend(
            body.split(|c: char| c == ',' || c == '[' || c.is_whitespace())
                .filter(|s| !s.is_empty())
                .map(|s| (s, j + 1)),
        );
        j += 1;
    }
    let data_line = numbers.first().map_or(k + 2, |n| n.1);
    if !closed || numbers.len() != 16 {
        return Err(parse_error(
            file,
            data_line,
            field,
            format!(
                "{} numbers, expected 16 (a 4×4 matrix) in `data: [...]`",
                numbers.len()
            ),
        ));
    }
    let mut m = Matrix4::zeros();
    for (n, (s, line)) in numbers.iter().enumerate() {
        let at = format!("{field}[{n}]");
        let v = s
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| {
                parse_error(
                    file,
                    *line,
                    at.clone(),
                    format!("expected a finite number, found `{s}`"),
                )
            })?;
        if n % 4 == 3 && n < 12 {
            check_translation(v).map_err(|p| parse_error(file, *line, at, p.to_string()))?;
        }
        m[(n / 4, n % 4)] = v;
    }
    let t = read_matrix4(&m).map_err(|p| parse_error(file, data_line, key, p.to_string()))?;
    Ok((t, j))
}

/// Pairs `T1_i` with `T2_i` by index, refusing an index given twice or without its partner.
fn pair_up(
    mut t1: Vec<YamlMatrix>,
    mut t2: Vec<YamlMatrix>,
    file: &str,
) -> Result<Vec<(Transform, Transform, usize)>> {
    for list in [&mut t1, &mut t2] {
        list.sort_by_key(|m| (m.index, m.line));
        if let Some(w) = list.windows(2).find(|w| w[0].index == w[1].index) {
            return Err(parse_error(
                file,
                w[1].line,
                w[1].key.clone(),
                format!(
                    "matrix index {} given twice (`{}` on line {} and `{}` here)",
                    w[1].index, w[0].key, w[0].line, w[1].key
                ),
            ));
        }
    }
    let partner = |m: &YamlMatrix, others: &[YamlMatrix], other: &str| {
        if others.binary_search_by_key(&m.index, |o| o.index).is_ok() {
            Ok(())
        } else {
            Err(parse_error(
                file,
                m.line,
                m.key.clone(),
                format!("no `{other}{}` to pair it with", m.index),
            ))
        }
    };
    for m in &t1 {
        partner(m, &t2, "T2_")?;
    }
    for m in &t2 {
        partner(m, &t1, "T1_")?;
    }
    Ok(t1
        .into_iter()
        .zip(t2)
        .map(|(a, b)| (a.transform, b.transform, a.line))
        .collect())
}

/// Reads moveit_calibration's sample JSON: a list of `[[4×4 effector in base], [4×4 object in
/// camera]]` pairs (`base_from_gripper`, `camera_from_target`), each matrix as 4 rows or 16 numbers.
/// Errors name the line of the offending value and its place (`[pair][matrix][row][column]`).
pub fn read_moveit_json(text: &str, file: &str) -> Result<PoseSeries> {
    let value: Value = serde_json::from_str(text)
        .map_err(|e| parse_error(file, e.line().max(1), "-", format!("malformed JSON: {e}")))?;
    if let Some(repeated) = repeated_key(text) {
        return Err(parse_error(
            file,
            repeated.line,
            repeated.path.clone(),
            repeated.message(),
        ));
    }
    let list = value.as_array().ok_or_else(|| {
        parse_error(
            file,
            1,
            "-",
            "expected a list of [effector_in_base, object_in_camera] pairs",
        )
    })?;
    let mut pairs = Vec::with_capacity(list.len());
    let mut projections = Projections::default();
    for k in 0..list.len() {
        let robot = moveit_matrix(&value, k, 0, text, file)?;
        let camera = moveit_matrix(&value, k, 1, text, file)?;
        projections.add(&robot);
        projections.add(&camera);
        pairs.push(PosePair {
            base_from_gripper: robot.transform,
            camera_from_target: camera.transform,
        });
    }
    series(pairs, file, projections)
}

/// Matrix `j` of pair `k` of a moveit file (`value` its parsed `text`).
fn moveit_matrix(
    value: &Value,
    k: usize,
    j: usize,
    text: &str,
    file: &str,
) -> Result<ReadTransform> {
    let error = |field: String, message: String| {
        let line = line_of_field(text, &field);
        parse_error(file, line, field, message)
    };
    let pair = &value[k];
    let Some(v) = pair
        .as_array()
        .filter(|p| p.len() == 2)
        .and_then(|p| p.get(j))
    else {
        return Err(error(
            format!("[{k}]"),
            format!(
                "expected a pair [effector_in_base, object_in_camera], found {}",
                brief(pair)
            ),
        ));
    };
    let flat = v.as_array().filter(|flat| flat.len() == 16);
    let rows = match flat {
        Some(flat) => Value::Array(flat.chunks(4).map(|r| Value::Array(r.to_vec())).collect()),
        None => v.clone(),
    };
    read_transform_json(&rows).map_err(|p| {
        // A flat matrix's [r][c] is its element 4r + c in the file.
        let inner = match steps(&p.field).as_slice() {
            [Step::Index(r), Step::Index(c), rest @ ..] if flat.is_some() => {
                let mut at = vec![Step::Index(4 * r + c)];
                at.extend_from_slice(rest);
                path_name(&at)
            }
            _ => p.field.clone(),
        };
        let inner = FieldProblem {
            field: inner,
            message: String::new(),
        };
        error(inner.path_under(&format!("[{k}][{j}]")), p.message)
    })
}

/// Reads moveit_calibration's "Save samples" YAML: a list of `{effector_wrt_world: [16 numbers],
/// object_wrt_sensor: [16 numbers]}`, each a 4×4 matrix row by row: the effector in the robot's
/// base (`base_from_gripper`) and the target in the camera (`camera_from_target`). Errors name the
/// line and the place (`[pair].effector_wrt_world[k]`).
pub fn read_moveit_yaml(text: &str, file: &str) -> Result<PoseSeries> {
    let tree = YamlTree::parse(text, file)?;
    const WHAT: &str =
        "moveit_calibration's samples: a list of effector_wrt_world and object_wrt_sensor";
    let n = tree.sequence("", WHAT)?;
    let mut pairs = Vec::with_capacity(n);
    let mut lines = Vec::with_capacity(n);
    let mut projections = Projections::default();
    for k in 0..n {
        let robot = yaml_matrix16(&tree, &format!("[{k}].effector_wrt_world"), file)?;
        let camera = yaml_matrix16(&tree, &format!("[{k}].object_wrt_sensor"), file)?;
        projections.add(&robot);
        projections.add(&camera);
        pairs.push(PosePair {
            base_from_gripper: robot.transform,
            camera_from_target: camera.transform,
        });
        lines.push(
            tree.line_of_sequence(&format!("[{k}].effector_wrt_world"))
                .unwrap_or(0),
        );
    }
    series_at(pairs, lines, file, projections)
}

/// A 4×4 matrix written as a YAML list of 16 numbers, row by row.
fn yaml_matrix16(tree: &YamlTree, path: &str, file: &str) -> Result<ReadTransform> {
    let count = tree.sequence(path, "a list of 16 numbers, a 4×4 matrix row by row")?;
    let line = tree.line_of_sequence(path).unwrap_or(0);
    if count != 16 {
        return Err(parse_error(
            file,
            line,
            path,
            format!("{count} numbers: expected 16, a 4×4 matrix row by row"),
        ));
    }
    let mut m = Matrix4::zeros();
    for k in 0..16 {
        m[(k / 4, k % 4)] = tree.number(&format!("{path}[{k}]"), "a number")?;
    }
    read_matrix4(&m).map_err(|p| parse_error(file, line, path, p.to_string()))
}

/// Reads easy_handeye2's saved samples (`~/.ros2/easy_handeye2/calibrations/NAME.samples`, the
/// YAML of its `SampleList` message): `parameters.calibration_type` and a list of `samples`, each a
/// `robot` and a `tracking` transform (`translation {x, y, z}`, `rotation {x, y, z, w}`).
///
/// easy_handeye2 looks the robot transform up from the base to the effector for `eye_in_hand`
/// (`base_from_gripper`) and from the effector to the base otherwise, for `eye_on_base` and for an
/// empty `calibration_type` (`gripper_from_base`, read as written: inverted); `tracking` is the
/// marker in the tracking system (`camera_from_target`). The setup the file declares is returned
/// with the series, to be checked against the one asked; an empty type declares none.
pub fn read_easy_handeye_samples(text: &str, file: &str) -> Result<PoseSeries> {
    let tree = YamlTree::parse(text, file)?;
    let setup = declared_setup(&tree, file)?;
    // easy_handeye2's sampler looks the robot up base-to-effector only for `eye_in_hand`: any
    // other type, its empty one included, is written effector-to-base as for `eye_on_base`.
    let written_empty = tree
        .text("parameters.calibration_type")
        .is_some_and(|(kind, _)| kind.trim().is_empty());
    let robot_inverted = written_empty || setup.is_some_and(|s| s.setup == Setup::EyeToHand);
    let n = tree.sequence(
        "samples",
        "easy_handeye2's samples: a list of robot and tracking transforms",
    )?;
    let mut pairs = Vec::with_capacity(n);
    let mut lines = Vec::with_capacity(n);
    for k in 0..n {
        let robot = yaml_transform(&tree, &format!("samples[{k}].robot"), file)?;
        let tracking = yaml_transform(&tree, &format!("samples[{k}].tracking"), file)?;
        pairs.push(PosePair {
            base_from_gripper: if robot_inverted {
                robot.inverse()
            } else {
                robot
            },
            camera_from_target: tracking,
        });
        lines.push(
            tree.text(&format!("samples[{k}].robot.translation.x"))
                .map_or(0, |(_, line)| line.saturating_sub(2)),
        );
    }
    let series = series_at(pairs, lines, file, Projections::default())?;
    Ok(PoseSeries {
        written: Written {
            robot: if robot_inverted {
                WrittenAs::Inverse
            } else {
                WrittenAs::Named
            },
            camera: WrittenAs::Named,
            frames: false,
        },
        setup,
        ..series
    })
}

/// The setup easy_handeye2's `parameters.calibration_type` declares (in its sample files and its
/// calibration files), with its line; `None` where the file does not say, and where it says `''`
/// (the empty string is what easy_handeye2 writes when its `calibration_type` parameter was never
/// set: the setup then comes from the run, `--setup`).
pub(crate) fn declared_setup(tree: &YamlTree, file: &str) -> Result<Option<DeclaredSetup>> {
    let Some((kind, line)) = tree.text("parameters.calibration_type") else {
        return Ok(None);
    };
    let setup = match kind.trim() {
        "" => return Ok(None),
        "eye_in_hand" => Setup::EyeInHand,
        "eye_on_base" | "eye_to_hand" => Setup::EyeToHand,
        other => {
            return Err(parse_error(
                file,
                line,
                "parameters.calibration_type",
                format!("`{other}`: expected eye_in_hand or eye_on_base"),
            ));
        }
    };
    Ok(Some(DeclaredSetup { setup, line }))
}

/// A `geometry_msgs/Transform` in YAML: `translation {x, y, z}` and `rotation {x, y, z, w}`.
pub(crate) fn yaml_transform(tree: &YamlTree, path: &str, file: &str) -> Result<Transform> {
    let t = ["x", "y", "z"].map(|c| format!("{path}.translation.{c}"));
    let q = ["x", "y", "z", "w"].map(|c| format!("{path}.rotation.{c}"));
    let mut translation = [0.0; 3];
    for (v, at) in translation.iter_mut().zip(&t) {
        *v = tree.number(at, "a geometry_msgs/Transform: translation {x, y, z}")?;
        check_translation(*v).map_err(|p| {
            parse_error(file, tree.text(at).map_or(0, |(_, l)| l), at, p.to_string())
        })?;
    }
    let mut quaternion = [0.0; 4];
    for (v, at) in quaternion.iter_mut().zip(&q) {
        *v = tree.number(at, "a geometry_msgs/Transform: rotation {x, y, z, w}")?;
    }
    transform_from_xyz_quat_xyzw(translation, quaternion).map_err(|p| {
        let line = tree.text(&q[3]).map_or(0, |(_, l)| l);
        parse_error(file, line, format!("{path}.rotation"), p.to_string())
    })
}

/// A short form of a JSON value for messages.
fn brief(v: &Value) -> String {
    let text = v.to_string();
    match text.char_indices().nth(40) {
        Some((at, _)) => format!("{}…", &text[..at]),
        None => text,
    }
}

/// Reads a ViSP recording: a directory of robot poses `<prefix>pose_rPe_<i>.yaml` (the end
/// effector in the robot's reference frame, as ViSP's hand-eye apps name them today, e.g.
/// `franka_pose_rPe_1.yaml`) or `<prefix>pose_fPe_<i>.yaml` (in the fixed frame, the older
/// tutorials' name), both `base_from_gripper`, and camera poses `<prefix>pose_cPo_<i>.yaml`
/// (the object in the camera, `camera_from_target`), each a 6-vector `tx ty tz θux θuy θuz`
/// (metres, radians), paired by index. The prefix is anything (empty by default in ViSP); the
/// robot's and the camera's may differ (ViSP's acquisition app writes `franka_pose_rPe_<i>`, its
/// pose computation `pose_cPo_<i>`).
///
/// Two namings of one kind in a directory (two recordings, or `fPe` beside `rPe`), an index given
/// twice (`pose_fPe_03.yaml` beside `pose_fPe_3.yaml`), a file of either kind without its partner,
/// or an index that is not a number is refused, naming the files.
pub fn read_visp_dir(dir: &Path) -> Result<PoseSeries> {
    let (name, files) = visp_files(dir)?;
    let (robot_stem, robot) = visp_indices(&files, &VISP_ROBOT, &[".yaml"], &name)?;
    let (camera_stem, camera) = visp_indices(&files, &[VISP_CAMERA], &[".yaml"], &name)?;
    if robot.is_empty() {
        return Err(parse_error(
            &name,
            0,
            "pose_rPe_*.yaml",
            "no ViSP robot pose files in this directory (expected `<prefix>pose_rPe_<i>.yaml` or \
             `<prefix>pose_fPe_<i>.yaml`, each with its `<prefix>pose_cPo_<i>.yaml`)",
        ));
    }
    let camera_stem = camera_stem.unwrap_or_else(|| VISP_CAMERA.to_owned());
    let robot_stem = robot_stem.unwrap_or_else(|| VISP_ROBOT[0].to_owned());
    for (index, file) in &camera {
        if !robot.contains_key(index) {
            return Err(parse_error(
                &name,
                0,
                file.as_str(),
                format!("no `{robot_stem}{index}.yaml` to pair it with"),
            ));
        }
    }
    let mut pairs = Vec::with_capacity(robot.len());
    for (index, file) in &robot {
        let Some(camera_file) = camera.get(index) else {
            return Err(parse_error(
                &name,
                0,
                file.as_str(),
                format!("no `{camera_stem}{index}.yaml` to pair it with"),
            ));
        };
        pairs.push(PosePair {
            base_from_gripper: read_visp_pose(&regular(dir, file)?)?,
            camera_from_target: read_visp_pose(&regular(dir, camera_file)?)?,
        });
    }
    series(pairs, &name, Projections::default())
}

/// `dir/file` when it is a regular file (a link to one included): a pipe in a directory of pose
/// files would wait for a writer forever, and a device (a link to `/dev/zero`) never ends.
fn regular(dir: &Path, file: &str) -> Result<std::path::PathBuf> {
    let path = dir.join(file);
    let meta = std::fs::metadata(&path).map_err(|e| Error::Io {
        file: path.display().to_string(),
        source: e,
    })?;
    if meta.is_file() {
        Ok(path)
    } else {
        Err(parse_error(
            &dir.display().to_string(),
            0,
            file,
            "not a regular file (a pipe, a device or a directory): a ViSP pose file is read from a directory of files",
        ))
    }
}

/// Largest norm of a ViSP θu rotation vector accepted, radians (a full turn; ViSP writes θ ≤ π).
const MAX_VISP_ANGLE: f64 = 2.0 * std::f64::consts::PI;

/// File-name markers of ViSP robot poses (`base_from_gripper`): the apps' current name, then the
/// older tutorials'.
const VISP_ROBOT: [&str; 2] = ["pose_rPe_", "pose_fPe_"];
/// File-name marker of ViSP camera poses (`camera_from_target`).
const VISP_CAMERA: &str = "pose_cPo_";

/// The file names of a ViSP folder, sorted, with the folder's name for errors.
fn visp_files(dir: &Path) -> Result<(String, Vec<String>)> {
    let name = dir.display().to_string();
    let io_error = |e| Error::Io {
        file: name.clone(),
        source: e,
    };
    let mut files: Vec<String> = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(io_error)? {
        files.push(
            entry
                .map_err(io_error)?
                .file_name()
                .to_string_lossy()
                .into_owned(),
        );
    }
    files.sort();
    Ok((name, files))
}

/// The files `<prefix><marker><index><extension>` among `files` (sorted; the extension in any
/// case), by index, with the naming (`<prefix><marker>`) they share; an index that is not a
/// number, one given twice, or two namings are refused.
fn visp_indices(
    files: &[String],
    markers: &[&str],
    extensions: &[&str],
    dir: &str,
) -> Result<(Option<String>, BTreeMap<usize, String>)> {
    let mut out: BTreeMap<usize, String> = BTreeMap::new();
    let mut naming: Option<String> = None;
    for file in files {
        let Some((stem, extension)) = extensions
            .iter()
            .find_map(|ext| without_extension(file, ext).map(|stem| (stem, *ext)))
        else {
            continue;
        };
        let Some((at, marker)) = markers
            .iter()
            .filter_map(|m| stem.rfind(m).map(|at| (at, *m)))
            .max_by_key(|(at, _)| *at)
        else {
            continue;
        };
        let (stem, digits) = stem.split_at(at + marker.len());
        match &naming {
            None => naming = Some(stem.to_owned()),
            Some(first) if first != stem => {
                return Err(parse_error(
                    dir,
                    0,
                    file.as_str(),
                    format!(
                        "two ViSP namings in one directory, `{first}<i>{extension}` and `{stem}<i>{extension}`: keep one recording per directory"
                    ),
                ));
            }
            Some(_) => {}
        }
        let index = digits
            .bytes()
            .all(|b| b.is_ascii_digit())
            .then(|| digits.parse::<usize>().ok())
            .flatten()
            .ok_or_else(|| {
                parse_error(
                    dir,
                    0,
                    file.as_str(),
                    format!(
                        "expected `{stem}<number>{extension}`: `{digits}` is not a pose number"
                    ),
                )
            })?;
        if let Some(first) = out.insert(index, file.clone()) {
            return Err(parse_error(
                dir,
                0,
                file.as_str(),
                format!(
                    "pose {index} given twice: `{first}` and `{file}` (one would silently replace the other)"
                ),
            ));
        }
    }
    Ok((naming, out))
}

/// `file` without `extension`, compared in any case (`.PNG` is `.png`).
fn without_extension<'a>(file: &'a str, extension: &str) -> Option<&'a str> {
    let at = file.len().checked_sub(extension.len())?;
    (file.is_char_boundary(at) && file[at..].eq_ignore_ascii_case(extension)).then(|| &file[..at])
}

/// One image of a recording and the robot's pose when it was taken.
#[derive(Debug, Clone, PartialEq)]
pub struct ImageRecord {
    /// The image file.
    pub image: std::path::PathBuf,
    /// Q, the robot's pose (`base_from_gripper`).
    pub base_from_gripper: Transform,
}

/// File-name marker of the images of a ViSP recording of images (its hand-eye acquisition app's
/// `<prefix>image-<i>.png`).
const VISP_IMAGE: &str = "image-";
/// The image files read.
const VISP_IMAGE_EXTENSIONS: [&str; 3] = [".png", ".jpg", ".jpeg"];

/// Reads a ViSP recording of images: in one folder, `<prefix>image-<i>.png` (or `.jpg`, `.jpeg`)
/// and the robot's pose at each, `<prefix>pose_rPe_<i>.yaml` (or the older `pose_fPe_`), paired
/// by index as the ViSP pose folders are (`Format::Visp`), by the same rules (one naming of each
/// kind, an index once, each file with its partner, regular files only).
pub fn read_visp_images(dir: &Path) -> Result<Vec<ImageRecord>> {
    let (name, files) = visp_files(dir)?;
    let (_, images) = visp_indices(&files, &[VISP_IMAGE], &VISP_IMAGE_EXTENSIONS, &name)?;
    let (robot_stem, robot) = visp_indices(&files, &VISP_ROBOT, &[".yaml"], &name)?;
    if images.is_empty() {
        return Err(parse_error(
            &name,
            0,
            "image-*.png",
            "no ViSP images in this folder (expected `<prefix>image-<i>.png`, each with its `<prefix>pose_rPe_<i>.yaml`)",
        ));
    }
    let robot_stem = robot_stem.unwrap_or_else(|| VISP_ROBOT[0].to_owned());
    if let Some((index, file)) = robot.iter().find(|(i, _)| !images.contains_key(i)) {
        return Err(parse_error(
            &name,
            0,
            file.as_str(),
            format!("no `<prefix>image-{index}.png` to pair it with"),
        ));
    }
    images
        .iter()
        .map(|(index, image)| {
            let pose = robot.get(index).ok_or_else(|| {
                parse_error(
                    &name,
                    0,
                    image.as_str(),
                    format!("no `{robot_stem}{index}.yaml` to pair it with"),
                )
            })?;
            Ok(ImageRecord {
                image: regular(dir, image)?,
                base_from_gripper: read_visp_pose(&regular(dir, pose)?)?,
            })
        })
        .collect()
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
    let data_line = 1 + text[..at].matches('\n').count();
    // Each value with the line (from 1) it is on.
    let mut values: Vec<(f64, usize)> = Vec::new();
    for (k, line) in text[at + 5..].split('\n').enumerate() {
        let parts = line
            .split(|c: char| c == '[' || c == ']' || c == ',' || c.is_whitespace())
            .filter(|s| !s.is_empty() && *s != "-");
        for s in parts {
            let field = format!("data[{}]", values.len());
            let v = s
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    parse_error(
                        &file,
                        data_line + k,
                        field,
                        format!("expected a finite number, found `{s}`"),
                    )
                })?;
            if values.len() == 6 {
                return Err(parse_error(
                    &file,
                    data_line + k,
                    "data",
                    "more than 6 values, expected tx ty tz θux θuy θuz",
                ));
            }
            values.push((v, data_line + k));
        }
    }
    let [tx, ty, tz, ux, uy, uz] = match values.as_slice() {
        [a, b, c, d, e, f] => [a.0, b.0, c.0, d.0, e.0, f.0],
        _ => {
            return Err(parse_error(
                &file,
                data_line,
                "data",
                format!("{} values, expected 6: tx ty tz θux θuy θuz", values.len()),
            ));
        }
    };
    for (k, v) in [tx, ty, tz].into_iter().enumerate() {
        check_translation(v)
            .map_err(|p| parse_error(&file, values[k].1, format!("data[{k}]"), p.to_string()))?;
    }
    let theta_u = Vector3::new(ux, uy, uz);
    // ViSP writes θ in [0, π]; more than a full turn is not a rotation vector it wrote (and a
    // huge one would give NaN sines).
    if theta_u.norm().is_nan() || theta_u.norm() > MAX_VISP_ANGLE {
        return Err(parse_error(
            &file,
            values[3].1,
            "data[3..5]",
            format!(
                "θu of norm {:e} rad is more than a full turn: not a ViSP rotation vector",
                theta_u.norm()
            ),
        ));
    }
    let rotation = exp_so3(&theta_u);
    Ok(transform_from_parts(&rotation, &Vector3::new(tx, ty, tz)))
}

/// Wraps pairs as a series, refusing fewer than 2.
fn series(pairs: Vec<PosePair>, file: &str, projections: Projections) -> Result<PoseSeries> {
    let lines = vec![0; pairs.len()];
    series_at(pairs, lines, file, projections)
}

/// [`series`] with each pair's line (of its first matrix), from 1.
fn series_at(
    pairs: Vec<PosePair>,
    lines: Vec<usize>,
    file: &str,
    projections: Projections,
) -> Result<PoseSeries> {
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
        lines,
        joints: Vec::new(),
        projections,
        written: Written::NAMED,
        setup: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_the_camodocal_file() {
        let Some(path) = crate::model::shared_data::shared("camodocal/TransformPairsInput.yml")
        else {
            return;
        };
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
                assert_eq!(line, 11);
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
            matches!(read_moveit_json(&format!("[[{i}]]"), "m.json"), Err(Error::Parse { field, line: 1, .. }) if field == "[0]")
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
                assert_eq!(field, "data[4]");
            }
            other => panic!("{other:?}"),
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn reads_visps_current_names_with_any_prefix() {
        let dir = std::env::temp_dir().join(format!("handeye-visp3-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let pose = |k: usize| {
            let v = 0.1 * k as f64;
            format!(
                "rows: 6\ncols: 1\ndata: \n  - [{v}]\n  - [0]\n  - [0.5]\n  - [{v}]\n  - [0]\n  - [-0.2]\n"
            )
        };
        let write = |file: String, text: &str| std::fs::write(dir.join(file), text).unwrap();
        // As ViSP's apps write them: the acquisition's `franka_pose_rPe_<i>`, the pose
        // computation's `pose_cPo_<i>`, and an image beside them.
        for k in 1..=4 {
            write(format!("franka_pose_rPe_{k}.yaml"), &pose(k));
            write(
                format!("pose_cPo_{k}.yaml"),
                "rows: 6\ncols: 1\ndata: [0, 0, 1, 0, 3.1, 0]\n",
            );
            write(format!("franka_image-{k}.png"), "");
        }
        write("franka_camera.xml".into(), "");
        let s = read_visp_dir(&dir).unwrap();
        assert_eq!(s.pairs.len(), 4);
        assert!((s.pairs[2].base_from_gripper.translation.vector.x - 0.3).abs() < 1e-15);
        assert!((s.pairs[2].camera_from_target.translation.vector.z - 1.0).abs() < 1e-15);
        // A second naming of the robot poses, or a camera pose without its robot pose.
        let name = dir.display().to_string();
        for (extra, says) in [
            ("pose_fPe_1.yaml", "two ViSP namings"),
            ("ur_pose_rPe_1.yaml", "two ViSP namings"),
            ("calib_pose_cPo_9.yaml", "two ViSP namings"),
            ("pose_cPo_5.yaml", "no `franka_pose_rPe_5.yaml`"),
        ] {
            write(extra.into(), &pose(1));
            let e = read_visp_dir(&dir);
            std::fs::remove_file(dir.join(extra)).unwrap();
            let message = format!("{e:?}");
            assert!(message.contains(says), "{extra}: {message}");
            assert_eq!(place(e).0, name, "{extra}");
        }
        // Robot poses alone.
        for k in 1..=4 {
            std::fs::remove_file(dir.join(format!("pose_cPo_{k}.yaml"))).unwrap();
        }
        let message = format!("{:?}", read_visp_dir(&dir));
        assert!(message.contains("no `pose_cPo_1.yaml`"), "{message}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// (file, line, field) of a parse error.
    fn place(r: Result<PoseSeries>) -> (String, usize, String) {
        match r {
            Err(Error::Parse {
                file, line, field, ..
            }) => (file, line, field),
            other => panic!("{other:?}"),
        }
    }

    const YAML_BLOCK: &str = "   rows: 4\n   cols: 4\n   dt: d\n   data: [ 1., 0., 0., 0., 0., 1., 0., 0.,\n       0., 0., 1., 0., 0., 0., 0., 1. ]\n";

    fn yaml(keys: &[&str]) -> String {
        let blocks: String = keys
            .iter()
            .map(|k| format!("{k}: !!opencv-matrix\n{YAML_BLOCK}"))
            .collect();
        format!("%YAML:1.0\n{blocks}")
    }

    #[test]
    fn yaml_errors_name_the_matrix_and_its_line() {
        // Each block takes 6 lines after the header line.
        let place_of = |keys: &[&str]| place(read_opencv_yaml(&yaml(keys), "p.yml"));
        assert!(read_opencv_yaml(&yaml(&["T1_0", "T2_0", "T1_1", "T2_1"]), "p.yml").is_ok());
        assert_eq!(
            place_of(&["T1_0", "T2_0", "T1_1", "T2_1", "T1_2"]),
            ("p.yml".into(), 26, "T1_2".into())
        );
        assert_eq!(
            place_of(&["T1_3", "T2_3", "T1_03", "T2_1"]),
            ("p.yml".into(), 14, "T1_03".into())
        );
        let bad_number =
            yaml(&["T1_0", "T2_0"]).replacen("       0., 0., 1.,", "       0., 0., x,", 1);
        assert_eq!(
            place(read_opencv_yaml(&bad_number, "p.yml")),
            ("p.yml".into(), 7, "T1_0.data[10]".into())
        );
        let no_data = yaml(&["T1_0", "T2_0"]).replacen("   data: [", "   dat: [", 1);
        assert_eq!(
            place(read_opencv_yaml(&no_data, "p.yml")),
            ("p.yml".into(), 2, "T1_0.data".into())
        );
    }

    #[test]
    fn moveit_errors_name_the_line_of_the_value() {
        let i = "[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]";
        let flat = "[1,0,0,0,\n 0,1,0,0,\n 0,0,1,0,\n 0,0,0,1]";
        let two = format!("[\n [{i},\n  {flat}],\n [{i},\n  {i}]\n]\n");
        assert!(read_moveit_json(&two, "m.json").is_ok());
        let cases = [
            (two.replacen("0,0,1,0,", "0,0,\"z\",0,", 1), 5, "[0][1][10]"),
            (
                two.replacen("[[1,0,0,0]", "[[2,0,0,0]", 2)
                    .replacen("[[2,", "[[1,", 1),
                7,
                "[1][0]",
            ),
            (two.replacen("],\n [", "],\n [3], [", 1), 7, "[1]"),
            (
                two.replacen(
                    "  [1,0,0,0,",
                    "  {\"matrix\": 1,\n \"matrix\": 2}, [1,0,0,0,",
                    1,
                ),
                4,
                "[0][1].matrix",
            ),
            ("[\n\n [1, 2".to_string(), 3, "-"),
        ];
        for (text, line, field) in cases {
            assert_eq!(
                place(read_moveit_json(&text, "m.json")),
                ("m.json".into(), line, field.into()),
                "{text}"
            );
        }
    }

    #[test]
    fn visp_refuses_a_pose_given_twice_or_alone() {
        let dir = std::env::temp_dir().join(format!("handeye-visp2-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let pose = "rows: 6\ncols: 1\ndata: [0, 0, 1, 0, 0.3, 0]\n";
        for k in 1..=3 {
            for kind in ["fPe", "cPo"] {
                std::fs::write(dir.join(format!("pose_{kind}_{k}.yaml")), pose).unwrap();
            }
        }
        let name = dir.display().to_string();
        assert_eq!(read_visp_dir(&dir).unwrap().pairs.len(), 3);
        for (extra, field, says) in [
            ("pose_fPe_03.yaml", "pose_fPe_3.yaml", "pose_fPe_03.yaml"),
            ("pose_cPo_002.yaml", "pose_cPo_2.yaml", "pose_cPo_002.yaml"),
            ("pose_cPo_4.yaml", "pose_cPo_4.yaml", "pose_fPe_4.yaml"),
            ("pose_fPe_5.yaml", "pose_fPe_5.yaml", "pose_cPo_5.yaml"),
            ("pose_fPe_x.yaml", "pose_fPe_x.yaml", "not a pose number"),
        ] {
            std::fs::write(dir.join(extra), pose).unwrap();
            let e = read_visp_dir(&dir);
            std::fs::remove_file(dir.join(extra)).unwrap();
            let message = format!("{e:?}");
            assert_eq!(place(e), (name.clone(), 0, field.into()), "{extra}");
            assert!(message.contains(says), "{message}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
