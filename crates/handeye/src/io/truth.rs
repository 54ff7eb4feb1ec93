//! Truth files (SPEC sec. 7): the true X under its frame name, and optionally the target pose.

use std::path::Path;

use serde_json::{Value, json};

use crate::error::Result;
use crate::io::{TransformJson, parse_error, read_text, transform_from_json};
use crate::pose::Transform;

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

/// Reads a truth file.
pub fn read_truth(path: &Path) -> Result<Truth> {
    let file = path.display().to_string();
    let text = read_text(path)?;
    let value: Value = serde_json::from_str(&text)
        .map_err(|e| parse_error(&file, e.line(), "-", format!("malformed JSON: {e}")))?;
    let get = |name: &str| -> Result<Option<Transform>> {
        value
            .get(name)
            .map(|v| {
                transform_from_json(v).map_err(|p| {
                    let field = if p.field.is_empty() {
                        name.to_string()
                    } else {
                        format!("{name}.{}", p.field)
                    };
                    parse_error(&file, 0, field, p.message)
                })
            })
            .transpose()
    };
    let (frame, x) = match (get("gripper_from_camera")?, get("base_from_camera")?) {
        (Some(x), None) => ("gripper_from_camera", x),
        (None, Some(x)) => ("base_from_camera", x),
        _ => {
            return Err(parse_error(
                &file,
                0,
                "gripper_from_camera|base_from_camera",
                "give exactly one of `gripper_from_camera` and `base_from_camera`",
            ));
        }
    };
    let target = match (get("base_from_target")?, get("gripper_from_target")?) {
        (Some(t), _) => Some(("base_from_target".to_string(), t)),
        (None, Some(t)) => Some(("gripper_from_target".to_string(), t)),
        _ => None,
    };
    Ok(Truth {
        x,
        frame: frame.to_string(),
        target,
    })
}

/// The JSON of a truth file.
pub fn truth_json(truth: &Truth) -> Value {
    let mut v = json!({ truth.frame.as_str(): TransformJson::from(&truth.x) });
    if let Some((name, t)) = &truth.target {
        v[name.as_str()] = json!(TransformJson::from(t));
    }
    v
}
