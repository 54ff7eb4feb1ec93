//! A saved X, as `calibrate` wrote it: its JSON object (`--output json`, in the input's unit, with
//! the bootstrap covariance), or easy_handeye2's calibration YAML (`--output yaml`, or
//! easy_handeye2's own file: metres, X alone; ours adds the one-sigma sizes in a comment).

use std::path::Path;

use serde_json::Value;

use crate::io::json_text::{line_of_field, repeated_key};
use crate::io::peer::{declared_setup, yaml_transform};
use crate::io::yaml_tree::YamlTree;
use crate::io::{parse_error, read_text, transform_from_json};
use crate::model::error::Result;
use crate::model::motion::Setup;
use crate::model::prior::LengthUnit;
use crate::model::saved::SavedX;

impl SavedX {
    /// Reads a saved X from a file: `calibrate --output json` or `--output yaml` (JSON when its
    /// first character is `{`, YAML otherwise; easy_handeye2's calibration file too). Errors name
    /// the file, the line and the field.
    pub fn read(path: impl AsRef<Path>) -> Result<SavedX> {
        let path = path.as_ref();
        parse_saved_x(&read_text(path)?, &path.display().to_string())
    }
}

/// Parses the text of a saved X, named `file` in messages (see [`SavedX::read`]).
///
/// # Example
/// ```
/// let yaml = "transform:\n  translation:\n    x: 0.1\n    y: 0\n    z: 0.05\n  rotation:\n    x: 0\n    y: 0\n    z: 0\n    w: 1\n";
/// let saved = handeye::io::parse_saved_x(yaml, "x.calib")?;
/// assert_eq!(saved.x.translation.vector.x, 0.1);
/// assert!(saved.covariance.is_none());
/// # Ok::<(), handeye::Error>(())
/// ```
pub fn parse_saved_x(text: &str, file: &str) -> Result<SavedX> {
    if text.trim_start().starts_with('{') {
        parse_json(text, file)
    } else {
        parse_yaml(text, file)
    }
}

fn parse_json(text: &str, file: &str) -> Result<SavedX> {
    let value: Value = serde_json::from_str(text)
        .map_err(|e| parse_error(file, e.line(), "-", format!("malformed JSON: {e}")))?;
    // A key given twice (`x` twice, say): the JSON parser keeps the last, so which X was meant
    // is not known.
    if let Some(repeated) = repeated_key(text) {
        return Err(parse_error(
            file,
            repeated.line,
            repeated.path.clone(),
            repeated.message(),
        ));
    }
    let line = |field: &str| line_of_field(text, field);
    let x = transform_from_json(&value).map_err(|p| {
        let field = if p.field.is_empty() {
            "matrix".to_string()
        } else {
            p.field.clone()
        };
        parse_error(
            file,
            line(&field),
            field,
            format!(
                "{} (expected what `calibrate --output json` writes)",
                p.message
            ),
        )
    })?;
    let setup = json_setup(&value, text, file)?;
    let covariance = match value.get("uncertainty").and_then(|u| u.get("covariance")) {
        None => None,
        Some(c) => Some(covariance(c).map_err(|(field, message)| {
            let field = format!("uncertainty.covariance{field}");
            parse_error(file, line(&field), field, message)
        })?),
    };
    Ok(SavedX {
        x,
        setup,
        covariance,
        unit: None,
    })
}

/// The setup a saved JSON declares: its `setup` (`eye-in-hand` or `eye-to-hand`) or its `frame`
/// (X's frame name: `gripper_from_camera` or `base_from_camera`, as `calibrate --output json`
/// writes both); the two must agree.
fn json_setup(value: &Value, text: &str, file: &str) -> Result<Option<Setup>> {
    let line = |field: &str| line_of_field(text, field);
    let named = match value.get("setup") {
        None => None,
        Some(Value::String(s)) => Some(
            s.parse::<Setup>()
                .map_err(|e| parse_error(file, line("setup"), "setup", e.to_string()))?,
        ),
        Some(_) => {
            return Err(parse_error(
                file,
                line("setup"),
                "setup",
                "expected a string (eye-in-hand or eye-to-hand)",
            ));
        }
    };
    let framed = match value.get("frame") {
        None => None,
        Some(frame) => Some(
            [Setup::EyeInHand, Setup::EyeToHand]
                .into_iter()
                .find(|s| frame.as_str() == Some(s.x_frame()))
                .ok_or_else(|| {
                    parse_error(
                        file,
                        line("frame"),
                        "frame",
                        format!(
                            "`{}`: expected X's frame, gripper_from_camera (eye-in-hand) or base_from_camera (eye-to-hand)",
                            frame.as_str().map_or_else(|| frame.to_string(), str::to_string)
                        ),
                    )
                })?,
        ),
    };
    match (named, framed) {
        (Some(a), Some(b)) if a != b => Err(parse_error(
            file,
            line("frame"),
            "frame",
            format!(
                "`{}` is X of {}, but `setup` says {}",
                b.x_frame(),
                b.name(),
                a.name()
            ),
        )),
        (a, b) => Ok(a.or(b)),
    }
}

/// The most negative eigenvalue a saved covariance may have, as a fraction of its largest: the
/// rounding of 16 printed digits, not a direction of negative variance.
const PSD_TOLERANCE: f64 = 1e-9;

/// A 6×6 covariance: finite, symmetric, positive semi-definite (to [`PSD_TOLERANCE`]), its
/// rotation one-sigmas at most π radians and its translation ones at most
/// [`MAX_TRANSLATION`](crate::model::pose::MAX_TRANSLATION): what a covariance can mean.
fn covariance(v: &Value) -> std::result::Result<[[f64; 6]; 6], (String, String)> {
    let rows = v
        .as_array()
        .filter(|r| r.len() == 6)
        .ok_or_else(|| (String::new(), "expected 6 rows of 6 numbers".to_string()))?;
    let mut c = [[0.0; 6]; 6];
    for (i, row) in rows.iter().enumerate() {
        let row = row
            .as_array()
            .filter(|r| r.len() == 6)
            .ok_or_else(|| (format!("[{i}]"), "expected a row of 6 numbers".to_string()))?;
        for (j, x) in row.iter().enumerate() {
            c[i][j] = x.as_f64().filter(|x| x.is_finite()).ok_or_else(|| {
                (
                    format!("[{i}][{j}]"),
                    "expected a finite number".to_string(),
                )
            })?;
        }
    }
    for i in 0..6 {
        if c[i][i] < 0.0 {
            return Err((
                format!("[{i}][{i}]"),
                "a variance cannot be negative".into(),
            ));
        }
        for j in 0..i {
            let scale = (c[i][i] * c[j][j]).sqrt().max(f64::MIN_POSITIVE);
            if (c[i][j] - c[j][i]).abs() > 1e-6 * scale {
                return Err((
                    format!("[{i}][{j}]"),
                    "the covariance is not symmetric".into(),
                ));
            }
        }
        let (bound, what) = if i < 3 {
            (std::f64::consts::PI, "a rotation one-sigma above π radians")
        } else {
            (
                crate::model::pose::MAX_TRANSLATION,
                "a translation one-sigma above 1e9",
            )
        };
        if c[i][i].sqrt() > bound {
            return Err((
                format!("[{i}][{i}]"),
                format!("{what} ({:e}) is no uncertainty of X", c[i][i].sqrt()),
            ));
        }
    }
    let eigen = nalgebra::SymmetricEigen::new(nalgebra::Matrix6::from_fn(|i, j| c[i][j]));
    let largest = eigen.eigenvalues.max().max(0.0);
    let least = eigen.eigenvalues.min();
    if !largest.is_finite() || least.is_nan() || least < -PSD_TOLERANCE * largest {
        return Err((
            String::new(),
            format!(
                "not a covariance: an eigenvalue of {least:e} (the largest {largest:e}), a direction of negative variance"
            ),
        ));
    }
    Ok(c)
}

/// easy_handeye2's calibration YAML: `transform.translation.{x,y,z}` (metres) and
/// `transform.rotation.{x,y,z,w}`, in block or flow style; `parameters.calibration_type`; and
/// handeye's comment `# uncertainty (one sigma): rotation_deg R, translation T m`, whose sizes
/// become an isotropic covariance (a third of each variance per axis). Read by the sample files'
/// YAML reader ([`YamlTree`], with their `geometry_msgs/Transform` and setup), so every error
/// names the line and the field.
fn parse_yaml(text: &str, file: &str) -> Result<SavedX> {
    let mut sigma: Option<(f64, f64)> = None;
    let mut unit = Some(LengthUnit::Metre);
    // handeye's comment `# frame: gripper_from_camera (…)`: X's frame name, with its line.
    let mut framed: Option<(Setup, usize)> = None;
    let comments = text
        .lines()
        .enumerate()
        .filter_map(|(i, l)| Some((i + 1, l.trim().strip_prefix('#')?)));
    for (line, comment) in comments {
        let comment = comment.trim();
        if let Some(rest) = comment.strip_prefix("frame:") {
            let name = rest.split_whitespace().next().unwrap_or("");
            framed = framed.or(Setup::ALL
                .into_iter()
                .find(|s| s.x_frame() == name)
                .map(|s| (s, line)));
        }
        if comment.starts_with("frame:") && comment.contains("translation in the input's unit") {
            unit = None;
        }
        if let Some(rest) = comment.strip_prefix("uncertainty (one sigma):") {
            sigma = one_sigma(rest);
        }
    }
    let tree = YamlTree::parse(text, file)?;
    let x = yaml_transform(&tree, "transform", file)?;
    let setup = match declared_setup(&tree, file)? {
        Some(d) => Some(d.setup),
        None => eye_on_hand(&tree, file)?,
    };
    if let (Some((named, line)), Some(declared)) = (framed, setup)
        && named != declared
    {
        return Err(parse_error(
            file,
            line,
            "frame",
            format!(
                "`{}` is X of {}, but the file's calibration type says {}: which X this is cannot be told; correct one of them",
                named.x_frame(),
                named.name(),
                declared.name()
            ),
        ));
    }
    let covariance = sigma.map(|(rotation_deg, translation)| {
        let mut c = [[0.0; 6]; 6];
        for (i, row) in c.iter_mut().enumerate() {
            row[i] = if i < 3 {
                rotation_deg.to_radians().powi(2) / 3.0
            } else {
                translation.powi(2) / 3.0
            };
        }
        c
    });
    Ok(SavedX {
        x,
        setup,
        covariance,
        unit,
    })
}

/// easy_handeye's (ROS 1) `parameters.eye_on_hand: true|false`, when there.
fn eye_on_hand(tree: &YamlTree, file: &str) -> Result<Option<Setup>> {
    let Some((value, line)) = tree.text("parameters.eye_on_hand") else {
        return Ok(None);
    };
    match value.trim() {
        "true" | "True" => Ok(Some(Setup::EyeInHand)),
        "false" | "False" => Ok(Some(Setup::EyeToHand)),
        other => Err(parse_error(
            file,
            line,
            "parameters.eye_on_hand",
            format!("`{other}`: expected true (eye-in-hand) or false (eye-on-base)"),
        )),
    }
}

/// `rotation_deg R, translation T[ m]` → (R, T), `None` when not so.
fn one_sigma(text: &str) -> Option<(f64, f64)> {
    let mut r = None;
    let mut t = None;
    for part in text.split(',') {
        let part = part.trim();
        if let Some(v) = part.strip_prefix("rotation_deg ") {
            r = v.trim().parse::<f64>().ok();
        } else if let Some(v) = part.strip_prefix("translation ") {
            t = v.trim().trim_end_matches(" m").trim().parse::<f64>().ok();
        }
    }
    match (r, t) {
        (Some(r), Some(t)) if r.is_finite() && t.is_finite() && r >= 0.0 && t >= 0.0 => {
            Some((r, t))
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::error::Error;

    #[test]
    fn easy_handeye_yaml_in_block_or_flow_style_and_its_errors_placed() {
        let block = "parameters:\n  calibration_type: eye_on_base\ntransform:\n  translation:\n    x: 0.1\n    y: 0\n    z: 0.05\n  rotation:\n    x: 0\n    y: 0\n    z: 0\n    w: 1\n# uncertainty (one sigma): rotation_deg 0.5, translation 0.002 m\n";
        let flow = "transform:\n  translation: {x: 0.1, y: 0, z: 0.05}\n  rotation: {x: 0, y: 0, z: 0, w: 1}\n";
        let a = parse_saved_x(block, "a.yaml").unwrap();
        let b = parse_saved_x(flow, "b.yaml").unwrap();
        assert_eq!(a.x, b.x);
        assert_eq!(a.setup, Some(Setup::EyeToHand));
        assert!((a.covariance.unwrap()[3][3] - 0.002f64.powi(2) / 3.0).abs() < 1e-15);
        assert!(b.covariance.is_none() && b.setup.is_none());
        let place = |text: &str| match parse_saved_x(text, "c.yaml") {
            Err(Error::Parse { line, field, .. }) => (line, field),
            other => panic!("{other:?}"),
        };
        assert_eq!(
            place(&block.replace("    w: 1\n", "")),
            (8, "transform.rotation.w".to_string())
        );
        assert_eq!(
            place(&block.replace("y: 0\n    z: 0.05", "y: zero\n    z: 0.05")),
            (6, "transform.translation.y".to_string())
        );
        assert_eq!(
            place(&block.replace("eye_on_base", "eye_on_wrist")),
            (2, "parameters.calibration_type".to_string())
        );
        let ros1 = flow.replace("transform:", "parameters: {eye_on_hand: false}\ntransform:");
        assert_eq!(
            parse_saved_x(&ros1, "d.yaml").unwrap().setup,
            Some(Setup::EyeToHand)
        );
        assert_eq!(
            place(&ros1.replace("false", "maybe")),
            (1, "parameters.eye_on_hand".to_string())
        );
    }

    #[test]
    fn a_saved_json_declares_its_setup_by_setup_or_by_frame_and_they_must_agree() {
        let x = r#""matrix": [[1,0,0,0.1],[0,1,0,0],[0,0,1,0.05],[0,0,0,1]]"#;
        let json = |fields: &str| format!("{{{fields},\n{x}}}");
        let setup = |text: &str| parse_saved_x(text, "x.json").map(|s| s.setup);
        assert_eq!(
            setup(&json(r#""frame": "base_from_camera""#)).unwrap(),
            Some(Setup::EyeToHand)
        );
        assert_eq!(
            setup(&json(r#""frame": "gripper_from_camera""#)).unwrap(),
            Some(Setup::EyeInHand)
        );
        assert_eq!(
            setup(&json(r#""setup": "eye-to-hand""#)).unwrap(),
            Some(Setup::EyeToHand)
        );
        assert_eq!(setup(&format!("{{{x}}}")).unwrap(), None);
        match setup(&json(
            "\"setup\": \"eye-in-hand\",\n\"frame\": \"base_from_camera\"",
        )) {
            Err(Error::Parse {
                line,
                field,
                message,
                ..
            }) => {
                assert_eq!((line, field.as_str()), (2, "frame"));
                assert!(
                    message.contains("eye-to-hand") && message.contains("eye-in-hand"),
                    "{message}"
                );
            }
            other => panic!("{other:?}"),
        }
        match setup(&json(r#""frame": "camera_from_gripper""#)) {
            Err(Error::Parse { field, .. }) => assert_eq!(field, "frame"),
            other => panic!("{other:?}"),
        }
    }

    /// A saved X that says two things is refused where the second is said (issue 59): a key
    /// given twice in the JSON, a second YAML document, handeye's `# frame:` comment against the
    /// file's calibration type.
    #[test]
    fn a_saved_x_that_contradicts_itself_is_refused_where() {
        let place = |text: &str, file: &str| match parse_saved_x(text, file) {
            Err(Error::Parse {
                line,
                field,
                message,
                ..
            }) => (line, field, message),
            other => panic!("{other:?}"),
        };
        let x = r#""x": {"translation": [0.1, 0, 0.05], "quaternion_xyzw": [0, 0, 0, 1]}"#;
        let twice = format!("{{{x},\n\"setup\": \"eye-in-hand\",\n\"setup\": \"eye-in-hand\"}}");
        let (line, field, message) = place(&twice, "x.json");
        assert_eq!((line, field.as_str()), (3, "setup"), "{message}");
        assert!(message.contains("given twice"), "{message}");
        let yaml = "parameters:\n  calibration_type: eye_on_base\ntransform:\n  translation: {x: 0.1, y: 0, z: 0.05}\n  rotation: {x: 0, y: 0, z: 0, w: 1}\n";
        assert!(parse_saved_x(yaml, "x.calib").is_ok());
        let (line, _, message) = place(&format!("{yaml}---\n{yaml}"), "x.calib");
        assert_eq!(line, 6, "{message}");
        assert!(message.contains("second YAML document"), "{message}");
        let framed =
            |name: &str| format!("# frame: {name} (a -> b); translation in metres\n{yaml}");
        assert!(parse_saved_x(&framed("base_from_camera"), "x.calib").is_ok());
        let (line, field, message) = place(&framed("gripper_from_camera"), "x.calib");
        assert_eq!((line, field.as_str()), (1, "frame"), "{message}");
        assert!(
            message.contains("eye-in-hand") && message.contains("eye-to-hand"),
            "{message}"
        );
    }
}
