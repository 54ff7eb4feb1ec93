//! The residuals against the robot's own kinematic model: where the user gives the DH table the
//! robot reports its poses through (`--robot-model`), the systematic-error test asks whether the
//! per-pose residuals lie along what an error of the table's parameters would do to them.
//!
//! An error δp of the parameters moves the reported hand pose A_i = F(p, q_i) by the first-order
//! change F(q_i)⁻¹ F(p + δp, q_i), and the residual D_i = Y⁻¹ Y_i with it: D ≈ D₀ + J δp, one
//! column of J per parameter, evaluated at each pose's joint angles (the identification Jacobian of
//! robot calibration). Part of J is X's and the target's own (an error at the flange or the base
//! is a change of X or of the target's pose, which no hand–eye data can tell apart); what is left,
//! J's part outside X's and the target's columns, spans the residuals an uncalibrated robot leaves
//! after the fit. The statistic is the share of the residuals in that span, judged against the
//! same share for the stations' residuals permuted (random errors do not care which
//! configuration they come with), a z-score as the other statistics of `check::systematic`.
//!
//! Measured against an oracle that knows the noise as well as the model
//! (`testdata/kinhec/oracle_power.py`): the table alone is what gives the power at 32 poses.

use nalgebra::{DMatrix, DVector, Vector3, Vector6};
use rand_xoshiro::Xoshiro256PlusPlus;
use serde::{Deserialize, Serialize};

use crate::model::kinematics::Kinematics;
use crate::model::motion::{PosePair, Setup};
use crate::model::pose::{Transform, exp_so3, log_so3, transform_from_parts};
use crate::solve::residual::PoseResidual;

/// At most this many stations enter the statistic (evenly spaced): its cost is the design's
/// singular value decomposition and one product per permutation, and a thousand poses decide.
pub const MAX_STATIONS: usize = 1024;

/// The relative step of the finite differences: angles in radians, lengths in the scene's size.
const STEP: f64 = 1e-6;

/// What the table's directions explain (the report's `systematic.kinematic`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct KinematicFit {
    /// The share of the residuals (rotation in radians, translation over the scene's size) in
    /// the directions of the table's parameters that X and the target's pose do not absorb.
    pub explained: f64,
    /// How many such directions: the parameters the poses can tell apart from X and the target.
    pub parameters: usize,
    /// The share's z-score against permuted residuals (negative: more than chance).
    pub z: f64,
}

/// One station of the test: its representative pose, its joint angles and its residual.
pub struct Station<'a> {
    /// The station's first pose.
    pub pose: &'a PosePair,
    /// Its joint angles.
    pub joints: &'a [f64],
    /// Its residual (the mean of its poses').
    pub residual: &'a PoseResidual,
}

/// The test of `stations` under X `x` and the target's pose `y` (`D_i = Y⁻¹ Y_i`), with the
/// table `model`; `scene` the translation scale. `None` where the table's joints are not the
/// recording's, or where too few stations are left to judge its directions.
pub fn kinematic_fit(
    stations: &[Station<'_>],
    (setup, x, y): (Setup, &Transform, &Transform),
    model: &Kinematics,
    scene: f64,
    rng: &mut Xoshiro256PlusPlus,
) -> Option<KinematicFit> {
    let stride = stations.len().div_ceil(MAX_STATIONS).max(1);
    let picked: Vec<&Station<'_>> = stations.iter().step_by(stride).collect();
    let m = picked.len();
    if m == 0
        || model.validate().is_err()
        || picked.iter().any(|s| s.joints.len() != model.dof())
        || scene.is_nan()
        || scene <= 0.0
    {
        return None;
    }
    let y_inv = y.inverse();
    let scale =
        |v: Vector6<f64>| Vector6::new(v[0], v[1], v[2], v[3] / scene, v[4] / scene, v[5] / scene);
    let absorbed = design(m, 12, |row, j| {
        let s = picked[row];
        let h = STEP;
        let at = |sign: f64| {
            let d = twist_step(j % 6, sign * h);
            let (xs, ys) = if j < 6 { (x * d, *y) } else { (*x, y * d) };
            residual6(&ys.inverse(), setup, s.pose, &s.pose.base_from_gripper, &xs)
        };
        scale((at(1.0) - at(-1.0)) / (2.0 * h))
    });
    // The reported pose with the table's error: A_i F(q_i)⁻¹ F(p + δp, q_i).
    let unflanged: Vec<Transform> = picked
        .iter()
        .map(|s| s.pose.base_from_gripper * model.forward(s.joints).inverse())
        .collect();
    let params = design(m, model.parameter_count(), |row, k| {
        let s = picked[row];
        let h = if k / model.dof() < 2 {
            STEP * scene
        } else {
            STEP
        };
        let at = |step: f64| {
            let reported = unflanged[row] * model.forward_moved(s.joints, Some((k, step)));
            residual6(&y_inv, setup, s.pose, &reported, x)
        };
        scale((at(h) - at(-h)) / (2.0 * h))
    });
    let basis = free_directions(&absorbed, &params)?;
    let k = basis.ncols();
    let residual_dof = 6 * m - 12;
    if k == 0 || residual_dof < 2 * k {
        return None;
    }
    let e: Vec<Vector6<f64>> = picked
        .iter()
        .map(|s| {
            scale(Vector6::new(
                s.residual.rotation.x,
                s.residual.rotation.y,
                s.residual.rotation.z,
                s.residual.translation.x,
                s.residual.translation.y,
                s.residual.translation.z,
            ))
        })
        .collect();
    let total: f64 = e.iter().map(|v| v.norm_squared()).sum();
    if total.is_nan() || total <= 0.0 {
        return None;
    }
    let share = |order: &[usize]| {
        let mut b = DVector::<f64>::zeros(k);
        for (row, &from) in order.iter().enumerate() {
            for c in 0..6 {
                let v = e[from][c];
                for j in 0..k {
                    b[j] += basis[(6 * row + c, j)] * v;
                }
            }
        }
        b.norm_squared() / total
    };
    // A large share is the finding: negative z, as the other statistics.
    let identity: Vec<usize> = (0..m).collect();
    let (explained, z) = crate::check::systematic::permutation_z(&identity, rng, share);
    Some(KinematicFit {
        explained,
        parameters: k,
        z: 0.0 - z, // 0 − z: a z of 0 stays +0
    })
}

/// A (6m × cols) matrix whose 6-row block `row`, column `col` is `f(row, col)`.
fn design(m: usize, cols: usize, f: impl Fn(usize, usize) -> Vector6<f64>) -> DMatrix<f64> {
    let mut out = DMatrix::zeros(6 * m, cols);
    for row in 0..m {
        for col in 0..cols {
            out.fixed_view_mut::<6, 1>(6 * row, col)
                .copy_from(&f(row, col));
        }
    }
    out
}

/// An orthonormal basis of the part of `params`' span outside `absorbed`'s.
fn free_directions(absorbed: &DMatrix<f64>, params: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    let q = orthonormal(absorbed, 1e-9)?;
    let free = params - &q * (q.transpose() * params);
    let largest = params.column_iter().map(|c| c.norm()).fold(0.0, f64::max);
    if largest.is_nan() || largest <= 0.0 {
        return None;
    }
    let svd = free.svd(true, false);
    let u = svd.u?;
    let keep: Vec<usize> = (0..svd.singular_values.len())
        .filter(|&i| svd.singular_values[i] > 1e-6 * largest)
        .collect();
    Some(u.select_columns(&keep))
}

/// An orthonormal basis of `a`'s column space (singular values above `tol` of the largest).
fn orthonormal(a: &DMatrix<f64>, tol: f64) -> Option<DMatrix<f64>> {
    let svd = a.clone().svd(true, false);
    let u = svd.u?;
    let top = svd.singular_values.max();
    let keep: Vec<usize> = (0..svd.singular_values.len())
        .filter(|&i| svd.singular_values[i] > tol * top)
        .collect();
    Some(u.select_columns(&keep))
}

/// exp of a step along one twist coordinate (0–2 rotation, 3–5 translation).
fn twist_step(j: usize, h: f64) -> Transform {
    let mut w = Vector3::zeros();
    let mut t = Vector3::zeros();
    if j < 3 {
        w[j] = h;
    } else {
        t[j - 3] = h;
    }
    transform_from_parts(&exp_so3(&w), &t)
}

/// log(Y⁻¹ Y_i) as (rotation vector, translation), with the hand pose `reported` in place of the
/// pose's own.
fn residual6(
    y_inv: &Transform,
    setup: Setup,
    pose: &PosePair,
    reported: &Transform,
    x: &Transform,
) -> Vector6<f64> {
    let d = y_inv * setup.hand_pose(reported) * x * pose.camera_from_target;
    let r = log_so3(d.rotation.matrix());
    let t = d.translation.vector;
    Vector6::new(r.x, r.y, r.z, t.x, t.y, t.z)
}

/// The median difference, degrees, between the turn of the hand from pose to pose and the turn
/// the table gives at the joint angles, beyond which the table is not the robot's.
pub const MODEL_MISMATCH_DEG: f64 = 1.0;

/// Checks that `model` is the table the poses were reported through: each pose's joint angles, as
/// many as the table's joints; the hand's turn between consecutive poses as the table gives it
/// (within [`MODEL_MISMATCH_DEG`] in the median: the turn is the same whatever the base and the
/// tool); the hand's positions spread as the table's do (within ten times: another unit).
/// The message says what is wrong, for the parameter `--robot-model`.
pub fn check_model(
    model: &Kinematics,
    poses: &[PosePair],
    joints: &[Vec<f64>],
) -> Result<(), String> {
    model
        .validate()
        .map_err(|problem| format!("the table is not whole: {problem}"))?;
    if joints.len() != poses.len() {
        return Err(format!(
            "the table needs the joint angles of every pose (`joints` in JSON Lines, /joint_states in a ROS 2 recording); {} of {} poses carry them",
            joints.len(),
            poses.len()
        ));
    }
    if let Some(i) = joints.iter().position(|q| q.len() != model.dof()) {
        return Err(format!(
            "the table has {} joints, pose {} carries {} joint angles",
            model.dof(),
            i + 1,
            joints[i].len()
        ));
    }
    let flanges: Vec<Transform> = joints.iter().map(|q| model.forward(q)).collect();
    let mut gaps: Vec<f64> = (1..poses.len())
        .map(|i| {
            let by_poses = crate::model::pose::rotation_angle_between(
                &poses[i - 1].base_from_gripper.rotation,
                &poses[i].base_from_gripper.rotation,
            );
            let by_table = crate::model::pose::rotation_angle_between(
                &flanges[i - 1].rotation,
                &flanges[i].rotation,
            );
            (by_poses - by_table).abs().to_degrees()
        })
        .collect();
    gaps.sort_by(f64::total_cmp);
    if let Some(&gap) = gaps.get(gaps.len() / 2)
        && gap > MODEL_MISMATCH_DEG
    {
        return Err(format!(
            "the table does not turn the hand as the poses do: the turns between consecutive poses differ by {gap:.2}° in the median (more than {MODEL_MISMATCH_DEG}°); another robot's table, the joints in another order or with other signs, or joint angles in degrees"
        ));
    }
    let spread = |t: &mut dyn Iterator<Item = Vector3<f64>>| {
        let v: Vec<Vector3<f64>> = t.collect();
        let mean = v.iter().sum::<Vector3<f64>>() / v.len().max(1) as f64;
        (v.iter().map(|p| (p - mean).norm_squared()).sum::<f64>() / v.len().max(1) as f64).sqrt()
    };
    let by_poses = spread(&mut poses.iter().map(|p| p.base_from_gripper.translation.vector));
    let by_table = spread(&mut flanges.iter().map(|f| f.translation.vector));
    if by_poses > 0.0 && by_table > 0.0 {
        let ratio = by_table / by_poses;
        if !(0.1..=10.0).contains(&ratio) {
            return Err(format!(
                "the table's lengths are {ratio:.3e} times the poses' (the hand's positions spread {by_poses:.4} in the poses, {by_table:.4} by the table): give them in the poses' unit"
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::kinematics::DhConvention;

    /// A table built in code, never read from a file, is checked before it is used: a short
    /// column is refused by name instead of indexing past its end.
    #[test]
    fn a_table_built_in_code_is_checked_before_use() {
        let table = Kinematics {
            convention: DhConvention::Standard,
            a: vec![0.5, 0.3],
            d: vec![0.0],
            alpha: vec![0.0, 0.0],
            theta_offset: vec![0.0, 0.0],
            sign: None,
            tool: None,
        };
        let pose = PosePair {
            base_from_gripper: Transform::identity(),
            camera_from_target: Transform::identity(),
        };
        let message =
            check_model(&table, &[pose, pose], &[vec![0.0, 0.1], vec![0.2, 0.3]]).unwrap_err();
        assert!(message.contains("`d` has 1 values"), "{message}");
        let residual = PoseResidual {
            rotation: Vector3::new(0.01, 0.0, 0.0),
            angle: 0.01,
            translation: Vector3::zeros(),
        };
        let station = Station {
            pose: &pose,
            joints: &[0.0, 0.1],
            residual: &residual,
        };
        let mut rng = <Xoshiro256PlusPlus as rand::SeedableRng>::seed_from_u64(1);
        let fit = kinematic_fit(
            &[station],
            (
                Setup::EyeInHand,
                &pose.base_from_gripper,
                &pose.base_from_gripper,
            ),
            &table,
            1.0,
            &mut rng,
        );
        assert!(fit.is_none());
    }
}
