//! A saved X, as `calibrate` wrote it: its JSON object (`--output json`, in the input's unit, with
//! the bootstrap covariance), or easy_handeye2's calibration YAML (`--output yaml`, or
//! easy_handeye2's own file: metres, X alone; ours adds the one-sigma sizes in a comment).

use std::path::Path;

use serde_json::Value;

use crate::calibrate::verify::{SavedUnit, SavedX};
use crate::io::json_text::{line_of, steps};
use crate::io::{parse_error, read_text, transform_from_json};
use crate::model::error::Result;
use crate::model::motion::Setup;
use crate::model::pose::transform_from_xyz_quat_xyzw;

/// Reads a saved X from a file (JSON when its first character is `{`, YAML otherwise); errors name
/// the file, the line and the field.
pub fn read_saved_x(path: &Path) -> Result<SavedX> {
    parse_saved_x(&read_text(path)?, &path.display().to_string())
}

/// Parses the text of a saved X, named `file` in messages (see [`read_saved_x`]).
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
    let line = |field: &str| line_of(text, &steps(field)).unwrap_or(1);
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
    let setup = match value.get("setup") {
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
        unit: SavedUnit::Unknown,
    })
}

/// A 6×6 covariance: finite, symmetric, with a non-negative diagonal.
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
    }
    Ok(c)
}

/// easy_handeye2's calibration YAML: `transform.translation.{x,y,z}` (metres) and
/// `transform.rotation.{x,y,z,w}`, in block or flow style; `parameters.calibration_type`; and
/// handeye's comment `# uncertainty (one sigma): rotation_deg R, translation T m`, whose sizes
/// become an isotropic covariance (a third of each variance per axis).
fn parse_yaml(text: &str, file: &str) -> Result<SavedX> {
    let mut path: Vec<(usize, String)> = Vec::new();
    let mut numbers: Vec<(String, f64, usize)> = Vec::new();
    let mut kind: Option<(String, usize)> = None;
    let mut sigma: Option<(f64, f64)> = None;
    let mut unit = SavedUnit::Metre;
    for (k, raw) in text.lines().enumerate() {
        let number = k + 1;
        let trimmed = raw.trim();
        if let Some(comment) = trimmed.strip_prefix('#') {
            let comment = comment.trim();
            if comment.starts_with("frame:") && comment.contains("translation in the input's unit")
            {
                unit = SavedUnit::Unknown;
            }
            if let Some(rest) = comment.strip_prefix("uncertainty (one sigma):") {
                sigma = one_sigma(rest);
            }
            continue;
        }
        if trimmed.is_empty() || trimmed == "---" {
            continue;
        }
        let indent = raw.len() - raw.trim_start().len();
        let Some((key, value)) = trimmed.split_once(':') else {
            return Err(parse_error(
                file,
                number,
                "-",
                "expected `key: value` (easy_handeye2's calibration YAML)",
            ));
        };
        let key = key.trim().trim_matches(['"', '\'']).to_string();
        let value = value.trim();
        while path.last().is_some_and(|(i, _)| *i >= indent) {
            path.pop();
        }
        let mut full: Vec<&str> = path.iter().map(|(_, k)| k.as_str()).collect();
        full.push(&key);
        let name = full.join(".");
        if value.is_empty() {
            path.push((indent, key));
        } else if let Some(flow) = value.strip_prefix('{').and_then(|v| v.strip_suffix('}')) {
            for entry in flow.split(',') {
                let (k, v) = entry.split_once(':').ok_or_else(|| {
                    parse_error(file, number, name.clone(), "expected `{k: v, ...}`")
                })?;
                numbers.push((
                    format!("{name}.{}", k.trim()),
                    yaml_number(v, file, number, &name)?,
                    number,
                ));
            }
        } else if name == "parameters.calibration_type" {
            kind = Some((value.trim_matches(['"', '\'']).to_string(), number));
        } else if name.starts_with("transform.") {
            numbers.push((
                name.clone(),
                yaml_number(value, file, number, &name)?,
                number,
            ));
        }
    }
    let get = |field: &str| -> Result<f64> {
        numbers
            .iter()
            .find(|(n, _, _)| n == field)
            .map(|(_, v, _)| *v)
            .ok_or_else(|| {
                parse_error(
                    file,
                    0,
                    field,
                    "missing (expected easy_handeye2's calibration YAML: transform.translation {x, y, z} and transform.rotation {x, y, z, w})",
                )
            })
    };
    let t = [
        get("transform.translation.x")?,
        get("transform.translation.y")?,
        get("transform.translation.z")?,
    ];
    let q = [
        get("transform.rotation.x")?,
        get("transform.rotation.y")?,
        get("transform.rotation.z")?,
        get("transform.rotation.w")?,
    ];
    let rotation_line = numbers
        .iter()
        .find(|(n, _, _)| n == "transform.rotation.w")
        .map_or(0, |(_, _, l)| *l);
    let x = transform_from_xyz_quat_xyzw(t, q)
        .map_err(|p| parse_error(file, rotation_line, "transform.rotation", p.to_string()))?;
    let setup = match kind {
        None => None,
        Some((k, line)) => Some(match k.as_str() {
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
        }),
    };
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

fn yaml_number(v: &str, file: &str, line: usize, field: &str) -> Result<f64> {
    let v = v.trim().trim_matches(['"', '\'']);
    v.parse::<f64>()
        .ok()
        .filter(|x| x.is_finite())
        .ok_or_else(|| {
            parse_error(
                file,
                line,
                field,
                format!("`{v}`: expected a finite number"),
            )
        })
}
