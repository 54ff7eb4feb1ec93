//! A robot's DH table (`--robot-model FILE`): JSON, `{"convention": "standard" | "modified", "a":
//! [...], "d": [...], "alpha": [...], "theta_offset": [...], "sign": [...], "tool": 4×4}` (lengths
//! in the poses' unit, angles in radians, `sign` and `tool` optional).

use std::path::Path;

use crate::io::json_text::line_of_field;
use crate::io::parse_error;
use crate::model::error::Result;
use crate::model::kinematics::Kinematics;

impl Kinematics {
    /// Reads a DH table. Errors name the file, the line and the field.
    pub fn read(path: impl AsRef<Path>) -> Result<Kinematics> {
        let path = path.as_ref();
        let text = crate::io::read_text(path)?;
        parse_kinematics(&text, &path.display().to_string())
    }
}

/// Parses a DH table from the text of a file named `file` in messages.
pub(crate) fn parse_kinematics(text: &str, file: &str) -> Result<Kinematics> {
    let table: Kinematics = serde_json::from_str(text)
        .map_err(|e| parse_error(file, e.line(), "robot model", e.to_string()))?;
    table
        .validate()
        .map_err(|p| parse_error(file, line_of_field(text, &p.field), p.field, p.message))?;
    Ok(table)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_a_table_and_names_what_is_wrong() {
        let ok = r#"{"convention": "standard", "a": [0, 0.4], "d": [0.1, 0], "alpha": [1.5707963, 0], "theta_offset": [0, 0]}"#;
        assert_eq!(parse_kinematics(ok, "ur.json").unwrap().dof(), 2);
        let short = ok.replace("\"d\": [0.1, 0]", "\"d\": [0.1]");
        let e = parse_kinematics(&short, "ur.json").unwrap_err().to_string();
        assert!(e.contains("ur.json:1: field `d`"), "{e}");
        let typo = ok.replace("theta_offset", "theta_ofset");
        let e = parse_kinematics(&typo, "ur.json").unwrap_err().to_string();
        assert!(e.contains("theta_ofset"), "{e}");
        let e = parse_kinematics("{\n\"convention\": \"dh\"}", "ur.json")
            .unwrap_err()
            .to_string();
        assert!(e.contains("ur.json:2"), "{e}");
        // A value found wrong after parsing is named at its own line.
        let multi = "{\n\"convention\": \"standard\",\n\"a\": [0, 0.4],\n\"d\": [0.1, 0],\n\"alpha\": [0, 0],\n\"theta_offset\": [0, 0],\n\"sign\": [1, 2]\n}";
        let e = parse_kinematics(multi, "ur.json").unwrap_err().to_string();
        assert!(e.contains("ur.json:7: field `sign[1]`"), "{e}");
    }
}
