//! Generators shared by the solver tests: random transforms, generic robot poses, and the
//! noise-free recording of a setup.

#![allow(dead_code)] // Each test file uses its own part.

use handeye::model::pose::{exp_so3, transform_from_parts};
use handeye::{PosePair, Setup, Transform};
use nalgebra::Vector3;
use proptest::prelude::*;

/// The transform of rotation vector `r` and translation `t`.
pub fn transform(r: [f64; 3], t: [f64; 3]) -> Transform {
    transform_from_parts(&exp_so3(&Vector3::from(r)), &Vector3::from(t))
}

prop_compose! {
    /// A rigid transform with a rotation of up to about 170° and a translation of up to 1.
    pub fn any_transform()(r in prop::array::uniform3(-1.7f64..1.7), t in prop::array::uniform3(-1.0f64..1.0)) -> Transform {
        transform(r, t)
    }
}

prop_compose! {
    /// A robot pose whose motions from the previous one are generic (rotations of 10°–80°).
    pub fn robot_pose()(axis in prop::array::uniform3(-1.0f64..1.0), angle in 0.2f64..1.4, t in prop::array::uniform3(0.1f64..1.0)) -> Transform {
        let a = Vector3::from(axis);
        let a = if a.norm() < 1e-3 { Vector3::x() } else { a.normalize() };
        transform_from_parts(&exp_so3(&(a * angle)), &Vector3::from(t))
    }
}

/// Poses of a noise-free recording for the setup (X: gripper_from_camera or base_from_camera;
/// fixed: base_from_target or gripper_from_target).
pub fn recording(
    setup: Setup,
    x: &Transform,
    fixed: &Transform,
    robot: &[Transform],
) -> Vec<PosePair> {
    robot
        .iter()
        .map(|base_from_gripper| {
            let camera_from_target = match setup {
                Setup::EyeInHand => (base_from_gripper * x).inverse() * fixed,
                Setup::EyeToHand => x.inverse() * base_from_gripper * fixed,
            };
            PosePair {
                base_from_gripper: *base_from_gripper,
                camera_from_target,
            }
        })
        .collect()
}

/// ‖R̂ − R‖_F and ‖t̂ − t‖ (absolute: the scenes span about 1 unit).
pub fn errors(x: &Transform, truth: &Transform) -> (f64, f64) {
    let r = (x.rotation.matrix() - truth.rotation.matrix()).norm();
    let t = (x.translation.vector - truth.translation.vector).norm();
    (r, t)
}
