//! The JSON form of a transform (SPEC sec. 7): `{"translation", "quaternion_xyzw", "matrix"}`.

use nalgebra::{Matrix4, Vector3};
use serde_json::{Map, Value};

use crate::model::pose::TransformProblem;
use crate::model::pose::{
    ReadTransform, Transform, check_translation, read_matrix4, transform_from_parts,
    transform_from_xyz_quat_xyzw,
};
use crate::model::rotation::{RotationConvention, Rotations};

/// Largest entry difference accepted between `matrix` and `translation`/`quaternion_xyzw` when both
/// are given.
pub const CONSISTENCY_TOL: f64 = 1e-6;

/// A problem found while reading a transform: where inside it (a field path relative to the
/// transform, such as `matrix[1][2]`, empty for the whole) and what.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldProblem {
    /// Path inside the transform (empty: the transform as a whole).
    pub field: String,
    /// What is wrong.
    pub message: String,
}

impl FieldProblem {
    /// The full field path of this problem inside the transform named `name`
    /// (`name`, `name[1][2]` or `name.matrix[1][2]`).
    pub fn path_under(&self, name: &str) -> String {
        if self.field.is_empty() {
            name.to_string()
        } else if self.field.starts_with('[') {
            format!("{name}{}", self.field)
        } else {
            format!("{name}.{}", self.field)
        }
    }

    fn new(field: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            field: field.into(),
            message: message.into(),
        }
    }
}

impl From<TransformProblem> for FieldProblem {
    fn from(p: TransformProblem) -> Self {
        Self::new("", p.to_string())
    }
}

/// Reads a transform from JSON: a bare matrix (4×4, 3×4 with the row `0 0 0 1` implied, or 16
/// numbers row by row), or an object with `matrix` and/or `translation` and one rotation field
/// (`quaternion_xyzw`, `rvec` in radians, or another [`RotationConvention::json_field`]:
/// `quaternion_wxyz`, `kuka_abc_deg`, …) (both forms must then agree within
/// `CONSISTENCY_TOL`, or within the matrix's deviation from orthonormality when it was printed
/// more coarsely).
pub fn transform_from_json(v: &Value) -> Result<Transform, FieldProblem> {
    read_transform_json(v).map(|r| r.transform)
}

/// As [`transform_from_json`], also telling how far from orthonormal a matrix was as given (its
/// rotation is then projected onto SO(3), see [`read_matrix4`]).
pub(crate) fn read_transform_json(v: &Value) -> Result<ReadTransform, FieldProblem> {
    read_transform_json_as(v, (true, Conventions::default()))
}

/// As [`read_transform_json`], for a side (the robot's when `robot`) whose rotation convention
/// `conventions` may name (by the flag): a rotation field of another convention is then refused,
/// naming the one expected (a matrix has no convention and is read as always).
pub(crate) fn read_transform_json_as(
    v: &Value,
    (robot, conventions): (bool, Conventions),
) -> Result<ReadTransform, FieldProblem> {
    match v {
        Value::Array(_) => Ok(read_matrix4(&matrix_from_json(v, "")?)?),
        Value::Object(o) => {
            let from_matrix = o
                .get("matrix")
                .map(|m| Ok::<_, FieldProblem>(read_matrix4(&matrix_from_json(m, "matrix")?)?))
                .transpose()?;
            let from_parts =
                transform_from_parts_json(o, from_matrix.is_some(), (robot, conventions))?;
            one_transform(from_matrix, from_parts)
        }
        _ => Err(FieldProblem::new(
            "",
            "expected a matrix (4×4, 3×4 or 16 numbers) or an object with `matrix`, or `translation` and a rotation (`quaternion_xyzw`, `rvec`, …)",
        )),
    }
}

/// The one transform of an object giving a matrix, the parts, or both (which must agree within
/// [`CONSISTENCY_TOL`], or within the matrix's deviation from orthonormality).
fn one_transform(
    from_matrix: Option<ReadTransform>,
    from_parts: Option<(Transform, Option<f64>)>,
) -> Result<ReadTransform, FieldProblem> {
    match (from_matrix, from_parts) {
        (Some(a), Some((b, _))) => {
            let difference = (a.transform.to_homogeneous() - b.to_homogeneous())
                .abs()
                .max();
            if difference > CONSISTENCY_TOL.max(a.deviation) {
                return Err(TransformProblem::Inconsistent { difference }.into());
            }
            Ok(a)
        }
        (Some(a), None) => Ok(a),
        (None, Some((b, degrees))) => Ok(ReadTransform {
            transform: b,
            deviation: 0.0,
            degrees,
        }),
        (None, None) => Err(FieldProblem::new(
            "",
            "a transform needs `matrix`, or `translation` and a rotation field (`quaternion_xyzw`, `rvec`, `quaternion_wxyz`, `kuka_abc_deg`, …)",
        )),
    }
}

/// The numbers of a transform as a line gives them (a bare 4×4 array is a `matrix`), read
/// without `serde_json::Value` by the JSON Lines reader's fast path.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct TransformNumbers {
    /// The 4×4 matrix, row-major.
    pub matrix: Option<Matrix4<f64>>,
    /// `translation`.
    pub translation: Option<[f64; 3]>,
    /// `quaternion_xyzw`.
    pub quaternion_xyzw: Option<[f64; 4]>,
}

impl TransformNumbers {
    /// The transform, as [`read_transform_json`] reads the same numbers; `None` where it refuses
    /// them (it then says why).
    pub fn read(&self) -> Option<ReadTransform> {
        let from_matrix = self.matrix.map(|m| read_matrix4(&m)).transpose().ok()?;
        let from_parts = match (self.translation, self.quaternion_xyzw) {
            (Some(t), Some(q)) => {
                if t.iter().any(|&v| check_translation(v).is_err()) {
                    return None;
                }
                Some((transform_from_xyz_quat_xyzw(t, q).ok()?, None))
            }
            (Some(_), None) | (None, Some(_)) if self.matrix.is_none() => return None,
            _ => None,
        };
        one_transform(from_matrix, from_parts).ok()
    }
}

/// The rotation fields a transform may give, one per convention.
fn rotation_fields() -> impl Iterator<Item = (RotationConvention, &'static str)> {
    RotationConvention::ALL.iter().map(|&c| (c, c.json_field()))
}

/// The transform of `translation` and one rotation field (`quaternion_xyzw`, `rvec`, or another
/// [`RotationConvention::json_field`]), if given, with the largest of its angles when they are in
/// degrees; a translation without a rotation (or the reverse) is an error unless a `matrix` is
/// given (`has_matrix`). With a convention `named` for this side, a rotation field of another
/// convention is refused.
fn transform_from_parts_json(
    o: &Map<String, Value>,
    has_matrix: bool,
    (robot, conventions): (bool, Conventions),
) -> Result<Option<(Transform, Option<f64>)>, FieldProblem> {
    let named = if robot {
        conventions.named.robot
    } else {
        conventions.named.camera
    };
    let given: Vec<(RotationConvention, &str)> = rotation_fields()
        .filter(|(_, f)| o.contains_key(*f))
        .collect();
    let rotation = match given.as_slice() {
        [] => None,
        [(convention, field)] => Some((*convention, *field)),
        [(_, first), (_, second), ..] => {
            return Err(FieldProblem::new(
                *second,
                format!("give one rotation: `{first}` or `{second}`, not both"),
            ));
        }
    };
    if let (Some((given, field)), Some(named)) = (rotation, named)
        && given != named
    {
        return Err(FieldProblem::new(
            field,
            format!(
                "the rotations of these poses are named {} (`--rotation`; `rotation=` in Python), given as `{}`, and this one is `{field}`: {}; write it as `{}`, or drop the name (a field named for its convention needs none)",
                named.name(),
                named.json_field(),
                given.describe(),
                named.json_field(),
            ),
        ));
    }
    match (o.get("translation"), rotation) {
        (Some(t), Some((convention, field))) => {
            let t = numbers::<3>(t, "translation")?;
            for (k, v) in t.iter().enumerate() {
                check_translation(*v)
                    .map_err(|p| FieldProblem::new(format!("translation[{k}]"), p.to_string()))?;
            }
            let values = numbers_n(&o[field], field, convention.components().len())?;
            let convention = conventions.read_as(robot, convention);
            let r = convention.rotation(&values).map_err(|p| {
                let at = match p.component {
                    Some(k) => format!("{field}[{k}]"),
                    None => field.to_string(),
                };
                FieldProblem::new(at, p.message)
            })?;
            let degrees = convention
                .in_degrees()
                .then(|| values.iter().fold(0.0f64, |m, v| m.max(v.abs())));
            Ok(Some((transform_from_parts(&r, &Vector3::from(t)), degrees)))
        }
        (Some(_), None) if !has_matrix => Err(FieldProblem::new(
            named.map_or("quaternion_xyzw", RotationConvention::json_field),
            match named {
                Some(named) => format!("missing (needed with `translation`: {})", named.describe()),
                None => {
                    "missing (needed with `translation`; or give `rvec`, or another rotation field)"
                        .to_string()
                }
            },
        )),
        (None, Some((_, field))) if !has_matrix => Err(FieldProblem::new(
            "translation",
            format!("missing (needed with `{field}`)"),
        )),
        _ => Ok(None),
    }
}

/// The shapes a matrix may be written in, for messages.
const MATRIX_SHAPES: &str =
    "expected 4 rows of 4 numbers, 3 rows of 4 (the row 0 0 0 1 implied), or 16 numbers row by row";

/// A matrix as 4 rows of 4 numbers, 3 rows of 4 (the last row `0 0 0 1` implied), or a flat list
/// of 16 numbers row by row; translation entries must pass [`check_translation`].
fn matrix_from_json(v: &Value, field: &str) -> Result<Matrix4<f64>, FieldProblem> {
    let items = v
        .as_array()
        .ok_or_else(|| FieldProblem::new(field, MATRIX_SHAPES))?;
    let mut m = Matrix4::identity();
    let mut set = |r: usize, c: usize, x: &Value, at: String| {
        m[(r, c)] = number(x, &at)?;
        if c == 3 && r < 3 {
            check_translation(m[(r, c)]).map_err(|p| FieldProblem::new(at, p.to_string()))?;
        }
        Ok::<_, FieldProblem>(())
    };
    if items.len() == 16 && !items.iter().any(Value::is_array) {
        for (k, x) in items.iter().enumerate() {
            set(k / 4, k % 4, x, format!("{field}[{k}]"))?;
        }
        return Ok(m);
    }
    if items.len() != 4 && items.len() != 3 {
        return Err(FieldProblem::new(field, MATRIX_SHAPES));
    }
    for (r, row) in items.iter().enumerate() {
        let row = row.as_array().filter(|c| c.len() == 4).ok_or_else(|| {
            FieldProblem::new(format!("{field}[{r}]"), "expected a row of 4 numbers")
        })?;
        for (c, x) in row.iter().enumerate() {
            set(r, c, x, format!("{field}[{r}][{c}]"))?;
        }
    }
    Ok(m)
}

/// An array of exactly N numbers.
fn numbers<const N: usize>(v: &Value, field: &str) -> Result<[f64; N], FieldProblem> {
    let a = v
        .as_array()
        .filter(|a| a.len() == N)
        .ok_or_else(|| FieldProblem::new(field, format!("expected {N} numbers")))?;
    let mut out = [0.0; N];
    for (k, x) in a.iter().enumerate() {
        out[k] = number(x, &format!("{field}[{k}]"))?;
    }
    Ok(out)
}

/// An array of exactly `n` numbers.
fn numbers_n(v: &Value, field: &str, n: usize) -> Result<Vec<f64>, FieldProblem> {
    let a = v
        .as_array()
        .filter(|a| a.len() == n)
        .ok_or_else(|| FieldProblem::new(field, format!("expected {n} numbers")))?;
    a.iter()
        .enumerate()
        .map(|(k, x)| number(x, &format!("{field}[{k}]")))
        .collect()
}

/// A finite number.
fn number(v: &Value, field: &str) -> Result<f64, FieldProblem> {
    let x = v
        .as_f64()
        .ok_or_else(|| FieldProblem::new(field, format!("expected a number, found {v}")))?;
    if x.is_finite() {
        Ok(x)
    } else {
        Err(FieldProblem::new(field, "not a finite number"))
    }
}

/// How a reader finds and reads each side's rotations: `named` finds them (the CSV columns, the
/// JSON field allowed) and reads them, unless `read_as` names for that side another convention
/// of as many numbers: the numbers found are then read as that one. The check of a named
/// convention ([`Recording`]'s) tries the others on the same numbers so.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) struct Conventions {
    /// The conventions named for the input.
    pub named: Rotations,
    /// The conventions to read the numbers as instead, per side.
    pub read_as: Rotations,
}

impl Conventions {
    /// The input's named conventions, read as named.
    pub fn named(named: Rotations) -> Self {
        Self {
            named,
            read_as: Rotations::default(),
        }
    }

    /// The convention to read a side's numbers as, found in the convention `found` (the robot's
    /// side when `robot`).
    pub fn read_as(
        self,
        robot: bool,
        found: crate::model::rotation::RotationConvention,
    ) -> crate::model::rotation::RotationConvention {
        let side = if robot {
            self.read_as.robot
        } else {
            self.read_as.camera
        };
        side.filter(|c| c.components().len() == found.components().len())
            .unwrap_or(found)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::pose::TransformJson;
    use crate::model::pose::quaternion_xyzw;
    use serde_json::json;

    #[test]
    fn reads_every_form_and_round_trips() {
        let t = Transform::new(
            nalgebra::Vector3::new(1.0, 2.0, 3.0),
            nalgebra::Vector3::new(0.1, -0.2, 0.3),
        );
        let j = serde_json::to_value(TransformJson::from(&t)).unwrap();
        let full = transform_from_json(&j).unwrap();
        assert!((full.to_homogeneous() - t.to_homogeneous()).abs().max() < 1e-12);
        let only_matrix = transform_from_json(&json!({"matrix": j["matrix"]})).unwrap();
        let only_parts = transform_from_json(
            &json!({"translation": j["translation"], "quaternion_xyzw": j["quaternion_xyzw"]}),
        )
        .unwrap();
        let bare = transform_from_json(&j["matrix"]).unwrap();
        for x in [only_matrix, only_parts, bare] {
            assert!((x.to_homogeneous() - t.to_homogeneous()).abs().max() < 1e-12);
        }
    }

    #[test]
    fn names_the_bad_field() {
        let mut m = json!([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]);
        m[1][2] = json!("x");
        assert_eq!(transform_from_json(&m).unwrap_err().field, "[1][2]");
        // 3×4 is a matrix (SPEC sec. 9); 2 rows are not.
        let e = transform_from_json(&json!({"matrix": [[1, 0, 0, 0], [0, 1, 0, 0]]})).unwrap_err();
        assert_eq!(e.field, "matrix");
        let e = transform_from_json(&json!({"translation": [0, 0, 0]})).unwrap_err();
        assert_eq!(e.field, "quaternion_xyzw");
        let e = transform_from_json(
            &json!({"translation": [0, 0, 0], "quaternion_xyzw": [0, 0, 0, 2]}),
        )
        .unwrap_err();
        assert_eq!(e.field, "quaternion_xyzw");
        let e = transform_from_json(&json!({
            "matrix": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]],
            "translation": [0, 0, 1], "quaternion_xyzw": [0, 0, 0, 1]
        }))
        .unwrap_err();
        assert!(e.message.contains("disagree"));
        let e = transform_from_json(&json!([
            [2, 0, 0, 0],
            [0, 1, 0, 0],
            [0, 0, 1, 0],
            [0, 0, 0, 1]
        ]))
        .unwrap_err();
        assert!(e.message.contains("orthonormal"));
    }

    #[test]
    fn matrix_and_quaternion_rounded_alike_agree_and_different_ones_do_not() {
        let t = Transform::new(
            nalgebra::Vector3::new(0.1, 0.2, 0.3),
            nalgebra::Vector3::new(0.7, -0.2, 1.9),
        );
        let j = TransformJson::from(&t);
        let round = |v: f64| (v * 1e6).round() / 1e6;
        let both = |q: [f64; 4]| {
            json!({
                "matrix": j.matrix.map(|r| r.map(round)),
                "translation": j.translation.map(round),
                "quaternion_xyzw": q.map(round),
            })
        };
        let read = read_transform_json(&both(j.quaternion_xyzw)).unwrap();
        assert!(read.projected());
        assert!(
            (read.transform.to_homogeneous() - t.to_homogeneous())
                .abs()
                .max()
                < 2e-6
        );
        // A quaternion of a rotation 1e-3 rad away is another rotation, not rounding.
        let other = Transform::new(
            nalgebra::Vector3::new(0.1, 0.2, 0.3),
            nalgebra::Vector3::new(0.7, -0.2, 1.901),
        );
        let e = read_transform_json(&both(quaternion_xyzw(&other))).unwrap_err();
        assert!(e.message.contains("disagree"), "{e:?}");
    }

    #[test]
    fn reads_the_shapes_engineers_have() {
        let t = Transform::new(
            nalgebra::Vector3::new(0.4, -0.2, 0.9),
            nalgebra::Vector3::new(0.3, -1.1, 2.5),
        );
        let m = t.to_homogeneous();
        let flat: Vec<f64> = (0..16).map(|k| m[(k / 4, k % 4)]).collect();
        let rows3: Vec<Vec<f64>> = (0..3)
            .map(|r| (0..4).map(|c| m[(r, c)]).collect())
            .collect();
        let w = t.rotation.scaled_axis();
        let t3 = [0.4, -0.2, 0.9];
        for (what, v) in [
            ("flat", json!(flat)),
            ("flat matrix", json!({ "matrix": flat })),
            ("3×4", json!(rows3)),
            ("3×4 matrix", json!({ "matrix": rows3 })),
            ("rvec", json!({"translation": t3, "rvec": [w.x, w.y, w.z]})),
            (
                "matrix and rvec",
                json!({"matrix": rows3, "translation": t3, "rvec": [w.x, w.y, w.z]}),
            ),
        ] {
            let read = transform_from_json(&v).unwrap_or_else(|e| panic!("{what}: {e:?}"));
            let error = (read.to_homogeneous() - m).abs().max();
            assert!(error < 1e-12, "{what}: {error}");
        }
    }

    #[test]
    fn odd_shapes_and_units_are_named() {
        let field = |v: Value| transform_from_json(&v).unwrap_err();
        let e = field(json!([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0]));
        assert!(e.message.contains("16 numbers row by row"), "{e:?}");
        let mut flat = json!([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]);
        flat[7] = json!("x");
        assert_eq!(field(flat).field, "[7]");
        let e = field(json!({"translation": [0, 0, 0], "rvec": [90, 0, 0]}));
        assert_eq!(e.field, "rvec");
        assert!(e.message.contains("degrees given?"), "{e:?}");
        let e = field(
            json!({"translation": [0, 0, 0], "rvec": [0, 0, 0], "quaternion_xyzw": [0, 0, 0, 1]}),
        );
        assert!(e.message.contains("not both"), "{e:?}");
        let e = field(json!({"rvec": [0, 0, 0.1]}));
        assert_eq!(e.field, "translation");
        assert!(e.message.contains("`rvec`"), "{e:?}");
        let e = field(json!({"translation": [0, 0, 0], "rvec": [0, 0]}));
        assert_eq!(e.field, "rvec");
        // A rotation vector and a matrix that disagree are refused.
        let e = field(json!({
            "matrix": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]],
            "translation": [0, 0, 0], "rvec": [0, 0, 0.01]
        }));
        assert!(e.message.contains("disagree"), "{e:?}");
    }

    #[test]
    fn absurd_translations_name_their_entry() {
        let mut m = json!([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]);
        m[1][3] = json!(1e308);
        let e = transform_from_json(&m).unwrap_err();
        assert_eq!(e.field, "[1][3]");
        assert!(
            e.message.contains("1e308 is not a plausible length"),
            "{e:?}"
        );
        let e = transform_from_json(
            &json!({"translation": [0, -2e9, 0], "quaternion_xyzw": [0, 0, 0, 1]}),
        )
        .unwrap_err();
        assert_eq!(e.field, "translation[1]");
    }
}
