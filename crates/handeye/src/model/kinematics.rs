//! A serial robot's nominal kinematic model: the Denavit–Hartenberg table its controller reports
//! poses through.
//!
//! A robot reports `base_from_gripper` as its nominal model's forward kinematics at the measured
//! joint angles. An uncalibrated robot's true geometry differs from that table by small errors of
//! its parameters, and the pose error they leave changes with the configuration in a way the table
//! fixes: the derivative of the pose with respect to each parameter. The systematic-error test
//! (`check::systematic`) asks whether the residuals lie along those derivatives, which it can ask
//! only where the table is given.

use nalgebra::{Matrix3, Matrix4, Vector3};
use serde::{Deserialize, Serialize};

use crate::model::pose::TransformProblem;
use crate::model::pose::{Transform, transform_from_matrix4, transform_from_parts};

/// The Denavit–Hartenberg convention of a table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DhConvention {
    /// Link i: Rz(θ_i) Tz(d_i) Tx(a_i) Rx(α_i).
    Standard,
    /// Craig's: Rx(α_{i−1}) Tx(a_{i−1}) Rz(θ_i) Tz(d_i).
    Modified,
}

/// A serial robot's DH table: every joint revolute, θ_i = sign_i · q_i + θ_offset_i; lengths in
/// the poses' unit, angles in radians.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Kinematics {
    /// The table's convention.
    pub convention: DhConvention,
    /// Link lengths.
    pub a: Vec<f64>,
    /// Link offsets.
    pub d: Vec<f64>,
    /// Link twists, radians.
    pub alpha: Vec<f64>,
    /// Joint zero offsets, radians.
    pub theta_offset: Vec<f64>,
    /// Each joint's direction (+1 or −1); all +1 when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sign: Option<Vec<f64>>,
    /// `last_link_from_flange`, the 4×4 row-major matrix after the last link; identity when
    /// absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tool: Option<[[f64; 4]; 4]>,
}

/// The most joints a table has, and the most joint angles a record gives (JSON Lines `joints`):
/// the same bound in batch and online.
pub const MAX_JOINTS: usize = 64;

impl Kinematics {
    /// The joints of the table.
    pub fn dof(&self) -> usize {
        self.a.len()
    }

    /// The parameters [`Kinematics::forward_moved`] can move: four per joint.
    pub fn parameter_count(&self) -> usize {
        4 * self.dof()
    }

    /// Whether the table is whole: every column as long as `a`, at least one joint (at most 64),
    /// every number finite, every sign ±1 and the tool rigid. The problem names the field.
    pub fn validate(&self) -> Result<(), TableProblem> {
        let problem = |field: String, message: String| Err(TableProblem { field, message });
        let n = self.dof();
        if n == 0 {
            return problem(
                "a".into(),
                "`a` is empty: a table needs at least one joint".into(),
            );
        }
        if n > MAX_JOINTS {
            return problem("a".into(), format!("{n} joints: at most {MAX_JOINTS}"));
        }
        let columns = [
            ("d", &self.d),
            ("alpha", &self.alpha),
            ("theta_offset", &self.theta_offset),
        ];
        for (name, column) in columns {
            if column.len() != n {
                return problem(
                    name.into(),
                    format!("`{name}` has {} values, `a` has {n}", column.len()),
                );
            }
        }
        for (name, column) in [("a", &self.a)].into_iter().chain(columns) {
            if let Some(i) = column.iter().position(|v| !v.is_finite()) {
                return problem(
                    format!("{name}[{i}]"),
                    format!("`{name}`[{i}] is not a finite number"),
                );
            }
        }
        if let Some(Err(e)) = self.tool.as_ref().map(tool_transform) {
            return problem("tool".into(), format!("`tool`: {e}"));
        }
        if let Some(sign) = &self.sign {
            if sign.len() != n {
                return problem(
                    "sign".into(),
                    format!("`sign` has {} values, `a` has {n}", sign.len()),
                );
            }
            if let Some(i) = sign.iter().position(|s| s.abs() != 1.0) {
                return problem(
                    format!("sign[{i}]"),
                    format!("`sign`[{i}] is {}: each sign is 1 or -1", sign[i]),
                );
            }
        }
        Ok(())
    }

    /// `base_from_flange` at the joint angles `q` (radians; `q.len()` must be [`Kinematics::dof`];
    /// the table validated).
    pub fn forward(&self, q: &[f64]) -> Transform {
        self.forward_moved(q, None)
    }

    /// [`Kinematics::forward`] with parameter `k` moved by `step` (`k / dof` the column: `a`,
    /// `d`, `alpha`, `theta_offset`; `k % dof` the joint), where given: the identification
    /// Jacobian's finite differences, without a copy of the table.
    pub fn forward_moved(&self, q: &[f64], moved: Option<(usize, f64)>) -> Transform {
        let n = self.dof();
        let by = |column: usize, joint: usize| match moved {
            Some((k, step)) if k / n == column && k % n == joint => step,
            _ => 0.0,
        };
        let mut pose = Transform::identity();
        for (i, &qi) in q.iter().enumerate().take(n) {
            let sign = self.sign.as_ref().map_or(1.0, |s| s[i]);
            let theta = sign * qi + self.theta_offset[i] + by(3, i);
            pose *= link(
                self.convention,
                theta,
                self.d[i] + by(1, i),
                self.a[i] + by(0, i),
                self.alpha[i] + by(2, i),
            );
        }
        match self
            .tool
            .as_ref()
            .and_then(|tool| tool_transform(tool).ok())
        {
            Some(tool) => pose * tool,
            None => pose,
        }
    }
}

/// What is wrong with a DH table: the field (`d`, `sign[1]`) and why.
#[derive(Debug, Clone, PartialEq)]
pub struct TableProblem {
    /// The field, with its index where one value is wrong.
    pub field: String,
    /// Why, in words.
    pub message: String,
}

impl std::fmt::Display for TableProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

/// The tool's transform, checked.
fn tool_transform(m: &[[f64; 4]; 4]) -> Result<Transform, TransformProblem> {
    transform_from_matrix4(&Matrix4::from_fn(|r, c| m[r][c]))
}

/// One link's transform.
fn link(convention: DhConvention, theta: f64, d: f64, a: f64, alpha: f64) -> Transform {
    let (st, ct) = theta.sin_cos();
    let (sa, ca) = alpha.sin_cos();
    match convention {
        DhConvention::Standard => transform_from_parts(
            &Matrix3::new(ct, -st * ca, st * sa, st, ct * ca, -ct * sa, 0.0, sa, ca),
            &Vector3::new(a * ct, a * st, d),
        ),
        DhConvention::Modified => transform_from_parts(
            &Matrix3::new(ct, -st, 0.0, st * ca, ct * ca, -sa, st * sa, ct * sa, ca),
            &Vector3::new(a, -sa * d, ca * d),
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn planar() -> Kinematics {
        Kinematics {
            convention: DhConvention::Standard,
            a: vec![0.5, 0.3],
            d: vec![0.0, 0.0],
            alpha: vec![0.0, 0.0],
            theta_offset: vec![0.0, 0.0],
            sign: None,
            tool: None,
        }
    }

    #[test]
    fn a_planar_arm_reaches_where_its_links_say() {
        let k = planar();
        let p = k.forward(&[std::f64::consts::FRAC_PI_2, -std::f64::consts::FRAC_PI_2]);
        assert_relative_eq!(
            p.translation.vector,
            Vector3::new(0.3, 0.5, 0.0),
            epsilon = 1e-12
        );
        let modified = Kinematics {
            convention: DhConvention::Modified,
            ..planar()
        };
        // Craig's table puts a_{i-1} before joint i: the same numbers reach only the first link.
        let p = modified.forward(&[0.0, 0.0]);
        assert_relative_eq!(
            p.translation.vector,
            Vector3::new(0.8, 0.0, 0.0),
            epsilon = 1e-12
        );
    }

    #[test]
    fn a_moved_parameter_is_the_table_with_it_edited() {
        let k = Kinematics {
            sign: Some(vec![1.0, -1.0]),
            ..planar()
        };
        let q = [0.4, -1.1];
        for (column, joint) in [(0, 1), (1, 0), (2, 1), (3, 0)] {
            let mut edited = k.clone();
            [
                &mut edited.a,
                &mut edited.d,
                &mut edited.alpha,
                &mut edited.theta_offset,
            ][column][joint] += 0.01;
            let moved = k.forward_moved(&q, Some((column * k.dof() + joint, 0.01)));
            let want = edited.forward(&q);
            assert_relative_eq!(
                moved.to_homogeneous(),
                want.to_homogeneous(),
                epsilon = 1e-15
            );
            assert!((moved.to_homogeneous() - k.forward(&q).to_homogeneous()).norm() > 1e-4);
        }
    }

    #[test]
    fn a_broken_table_is_named() {
        let mut k = planar();
        k.d.pop();
        assert!(
            k.validate()
                .unwrap_err()
                .message
                .contains("`d` has 1 values")
        );
        let mut k = planar();
        k.sign = Some(vec![1.0, 2.0]);
        assert_eq!(k.validate().unwrap_err().field, "sign[1]");
        let mut k = planar();
        k.alpha[0] = f64::NAN;
        assert_eq!(k.validate().unwrap_err().field, "alpha[0]");
    }
}
