//! Truth files (SPEC sec. 7): the true X under its frame name, and optionally the target pose.
//!
//! ```json
//! {"gripper_from_camera": {"translation": [...], "quaternion_xyzw": [...], "matrix": [...]},
//!  "base_from_target": {...}}
//! ```
//! X is `gripper_from_camera` (eye-in-hand) or `base_from_camera` (eye-to-hand); the target pose,
//! when given, is `base_from_target` (eye-in-hand: the target is fixed in the base) or
//! `gripper_from_target` (eye-to-hand: the target rides on the gripper). Each is a transform in
//! any input form of SPEC sec. 7.

use std::path::Path;

use serde_json::{Value, json};

use crate::io::json_text::{line_of_field, repeated_key};
use crate::io::{parse_error, read_text, transform_from_json};
use crate::model::error::Result;
use crate::model::pose::Transform;
use crate::model::pose::TransformJson;

/// The names X may have in a truth file.
const X_FRAMES: [&str; 2] = ["gripper_from_camera", "base_from_camera"];
/// The names the target pose may have in a truth file.
const TARGET_FRAMES: [&str; 2] = ["base_from_target", "gripper_from_target"];

/// The content of a truth file.
#[derive(Debug, Clone, PartialEq)]
pub struct Truth {
    /// The true X.
    pub x: Transform,
    /// Its frame name: `gripper_from_camera` (eye-in-hand) or `base_from_camera` (eye-to-hand).
    pub frame: String,
    /// The target pose, `base_from_target` or `gripper_from_target`, when given.
    pub target: Option<(String, Transform)>,
}

impl Truth {
    /// Reads a truth file; errors name the file, the line of the offending value and the field. A
    /// key given twice in one object is refused.
    pub fn read(path: impl AsRef<Path>) -> Result<Truth> {
        let path = path.as_ref();
        parse_truth(&read_text(path)?, &path.display().to_string())
    }
}

/// Parses the text of a truth file, named `file` in messages.
///
/// # Example
/// ```
/// let text = r#"{"base_from_camera": [[1,0,0,0.5],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}"#;
/// let truth = handeye::io::parse_truth(text, "truth.json")?;
/// assert_eq!(truth.frame, "base_from_camera");
/// assert_eq!(truth.x.translation.vector.x, 0.5);
/// assert!(truth.target.is_none());
/// # Ok::<(), handeye::Error>(())
/// ```
pub fn parse_truth(text: &str, file: &str) -> Result<Truth> {
    let value: Value = serde_json::from_str(text)
        .map_err(|e| parse_error(file, e.line(), "-", format!("malformed JSON: {e}")))?;
    if !value.is_object() {
        return Err(parse_error(
            file,
            1,
            "-",
            "expected a JSON object naming `gripper_from_camera` or `base_from_camera`",
        ));
    }
    if let Some(repeated) = repeated_key(text) {
        return Err(parse_error(
            file,
            repeated.line,
            repeated.path.clone(),
            repeated.message(),
        ));
    }
    let get = |name: &str| -> Result<Option<Transform>> {
        value
            .get(name)
            .map(|v| {
                transform_from_json(v).map_err(|p| {
                    let field = p.path_under(name);
                    parse_error(file, line_of_field(text, &field), field, p.message)
                })
            })
            .transpose()
    };
    let one_of = |names: [&str; 2]| -> Result<Option<(String, Transform)>> {
        match (get(names[0])?, get(names[1])?) {
            (Some(t), None) => Ok(Some((names[0].to_string(), t))),
            (None, Some(t)) => Ok(Some((names[1].to_string(), t))),
            (None, None) => Ok(None),
            (Some(_), Some(_)) => Err(parse_error(
                file,
                line_of_field(text, names[1]),
                names[1],
                format!("both `{}` and `{}` given: give one", names[0], names[1]),
            )),
        }
    };
    let (frame, x) = one_of(X_FRAMES)?.ok_or_else(|| {
        parse_error(
            file,
            0,
            X_FRAMES.join("|"),
            format!("missing: give `{}` or `{}`", X_FRAMES[0], X_FRAMES[1]),
        )
    })?;
    let target = one_of(TARGET_FRAMES)?;
    Ok(Truth { x, frame, target })
}

impl Truth {
    /// The JSON of its truth file: X under its frame name, and the target pose when known, each
    /// as a full transform (translation, quaternion and matrix).
    pub fn json(&self) -> Value {
        let mut v = json!({ self.frame.as_str(): TransformJson::from(&self.x) });
        if let Some((name, t)) = &self.target {
            v[name.as_str()] = json!(TransformJson::from(t));
        }
        v
    }
}

/// Writes a truth file (pretty JSON, see [`Truth::json`]).
pub fn write_truth(path: &Path, truth: &Truth) -> Result<()> {
    let io_error = |e: std::io::Error| crate::model::error::Error::Io {
        file: path.display().to_string(),
        source: e,
    };
    let text = serde_json::to_string_pretty(&truth.json())
        .map_err(|e| io_error(std::io::Error::other(e)))?;
    std::fs::write(path, text + "\n").map_err(io_error)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::error::Error;
    use nalgebra::Vector3;

    fn field_and_line(e: Error) -> (usize, String) {
        match e {
            Error::Parse {
                file, line, field, ..
            } => {
                assert_eq!(file, "t.json");
                (line, field)
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn reads_the_paper_fixture() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../testdata/paper/series_2007_000_200.truth.json");
        let truth = Truth::read(&path).unwrap();
        assert_eq!(truth.frame, "gripper_from_camera");
        assert_eq!(truth.target.as_ref().unwrap().0, "base_from_target");
        assert!((truth.x.translation.vector.x - 20.04194804110198).abs() < 1e-12);
    }

    #[test]
    fn writes_what_it_reads() {
        let truth = Truth {
            x: Transform::new(Vector3::new(1.0, 2.0, 3.0), Vector3::new(0.3, 0.2, -0.1)),
            frame: "base_from_camera".into(),
            target: Some((
                "gripper_from_target".into(),
                Transform::new(Vector3::new(0.0, 0.0, 0.2), Vector3::new(0.0, 1.0, 0.0)),
            )),
        };
        let dir = std::env::temp_dir().join(format!("handeye-truth-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("truth.json");
        write_truth(&path, &truth).unwrap();
        let back = Truth::read(&path).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(back.frame, truth.frame);
        assert!(
            (back.x.to_homogeneous() - truth.x.to_homogeneous())
                .abs()
                .max()
                < 1e-12
        );
        let (name, t) = back.target.unwrap();
        assert_eq!(name, "gripper_from_target");
        let t0 = truth.target.unwrap().1;
        assert!((t.to_homogeneous() - t0.to_homogeneous()).abs().max() < 1e-12);
    }

    #[test]
    fn bad_files_name_line_and_field() {
        let i = "[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]";
        let cases = [
            ("{\n\"gripper_from_camera\": [1,\n".to_string(), 3, "-"),
            ("[1, 2]".to_string(), 1, "-"),
            (
                "{\"base_from_target\": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}".to_string(),
                0,
                "gripper_from_camera|base_from_camera",
            ),
            (
                format!("{{\"gripper_from_camera\": {i},\n\"base_from_camera\": {i}}}"),
                2,
                "base_from_camera",
            ),
            (
                "{\n\n\"gripper_from_camera\": [[1,0,0,0],[0,1,0,0],[0,0,2,0],[0,0,0,1]]}"
                    .to_string(),
                3,
                "gripper_from_camera",
            ),
            (
                "{\"gripper_from_camera\":\n {\"translation\": [0, 0, \"x\"], \"quaternion_xyzw\": [0,0,0,1]}}"
                    .to_string(),
                2,
                "gripper_from_camera.translation[2]",
            ),
            (
                format!("{{\"gripper_from_camera\": {i},\n\"gripper_from_target\": [[1,0]]}}"),
                2,
                "gripper_from_target",
            ),
            (
                format!("{{\"gripper_from_camera\": {i},\n\"base_from_target\": {{\"matrix\": {i},\n \"matrix\": {i}}}}}"),
                3,
                "base_from_target.matrix",
            ),
            (
                format!("{{\"gripper_from_camera\": {i},\n\n\"gripper_from_camera\": {i}}}"),
                3,
                "gripper_from_camera",
            ),
        ];
        for (text, line, field) in cases {
            let e = parse_truth(&text, "t.json").unwrap_err();
            assert_eq!(field_and_line(e), (line, field.to_string()), "{text}");
        }
    }
}
