//! A low-DOF robot's recordings (SPEC sec. 9, priors), for this crate's tests: a gantry or SCARA
//! that translates freely and turns its flange about one or two axes.

use nalgebra::Vector3;
use rand::RngExt;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

use super::{gaussian, series_rng};
use crate::model::motion::PosePair;
use crate::model::pose::{Transform, exp_so3, transform_from_parts};

/// A low-DOF robot (SPEC sec. 9, priors): a gantry or SCARA that translates freely in x, y, z and
/// turns its flange about one fixed axis, and perhaps a wrist that tilts it about a second one.
///
/// Lengths are metres. The noise is a robot's (its reported pose off by `robot_noise`: a rotation
/// of that many radians per axis and as many metres per axis, one sigma) and PnP's (the target's
/// pose in the camera frame off by `camera_lateral` across the optical axis, `camera_depth` along
/// it and `camera_rotation` radians per axis).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LowDofConfig {
    /// Where the camera is mounted. Default eye-in-hand.
    pub setup: crate::model::motion::Setup,
    /// The flange's turning axis (a SCARA's yaw), in the gripper frame, unit. Default z.
    pub axis: [f64; 3],
    /// The range of the turn, radians (uniform in ±). Default π/2.
    pub turn: f64,
    /// A second joint tilting the flange about this axis (a 5-axis arm's wrist), uniform in
    /// ±`wrist_range`. Default none.
    pub wrist: Option<[f64; 3]>,
    /// See `wrist`. Default 0.5 rad.
    pub wrist_range: f64,
    /// Half the range of the hand's x and y, metres. Default 0.1.
    pub reach: f64,
    /// The range of the hand's z, metres. Default 0.1.
    pub lift: f64,
    /// Number of poses. Default 25.
    pub poses: usize,
    /// One-sigma robot noise: radians of rotation and metres of translation per axis. Default 1e-4.
    pub robot_noise: f64,
    /// One-sigma PnP noise across the optical axis, metres. Default 5e-4.
    pub camera_lateral: f64,
    /// One-sigma PnP noise along the optical axis, metres. Default 2e-3.
    pub camera_depth: f64,
    /// One-sigma PnP rotation noise per axis, radians. Default 1e-3.
    pub camera_rotation: f64,
}

impl Default for LowDofConfig {
    fn default() -> Self {
        Self {
            setup: crate::model::motion::Setup::EyeInHand,
            axis: [0.0, 0.0, 1.0],
            turn: std::f64::consts::FRAC_PI_2,
            wrist: None,
            wrist_range: 0.5,
            reach: 0.1,
            lift: 0.1,
            poses: 25,
            robot_noise: 1e-4,
            camera_lateral: 5e-4,
            camera_depth: 2e-3,
            camera_rotation: 1e-3,
        }
    }
}

impl LowDofConfig {
    /// The same robot without noise.
    pub fn noise_free(self) -> Self {
        Self {
            robot_noise: 0.0,
            camera_lateral: 0.0,
            camera_depth: 0.0,
            camera_rotation: 0.0,
            ..self
        }
    }
}

/// One simulated low-DOF recording and its truth.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LowDofSeries {
    /// The measured pose pairs, noise included.
    pub poses: Vec<PosePair>,
    /// The true X: `gripper_from_camera` eye-in-hand, `base_from_camera` eye-to-hand.
    pub x: Transform,
    /// The true fixed frame: `base_from_target` eye-in-hand, `gripper_from_target` eye-to-hand.
    pub fixed: Transform,
}

/// Simulates recording `series` of a low-DOF robot with seed `seed` (see [`LowDofConfig`]).
///
/// # Example
/// ```
/// use handeye::sim::{LowDofConfig, simulate_low_dof};
/// let s = simulate_low_dof(&LowDofConfig::default(), 3, 0);
/// assert_eq!(s.poses.len(), 25);
/// assert_eq!(s, simulate_low_dof(&LowDofConfig::default(), 3, 0));
/// ```
pub fn simulate_low_dof(config: &LowDofConfig, seed: u64, series: u64) -> LowDofSeries {
    use crate::model::motion::Setup;
    let mut rng = series_rng(seed ^ 0x5CA2_A000, series);
    let mut uniform = |lo: f64, hi: f64| {
        if hi > lo {
            rng.random_range(lo..hi)
        } else {
            lo
        }
    };
    // The camera looks down (its z against the gripper's z), tilted up to ~10°, turned at random.
    let look_down = exp_so3(&Vector3::new(std::f64::consts::PI, 0.0, 0.0));
    let tilt = Vector3::new(
        uniform(-0.12, 0.12),
        uniform(-0.12, 0.12),
        uniform(-3.1, 3.1),
    );
    let camera_rotation = exp_so3(&Vector3::new(0.0, 0.0, tilt.z))
        * exp_so3(&Vector3::new(tilt.x, tilt.y, 0.0))
        * look_down;
    let (x, fixed) = match config.setup {
        Setup::EyeInHand => {
            let t = Vector3::new(
                uniform(-0.06, 0.06),
                uniform(-0.06, 0.06),
                uniform(-0.15, -0.05),
            );
            let x = transform_from_parts(&camera_rotation, &t);
            // The target on the floor, face up, 0.45 m below the lowest flange.
            let target = Vector3::new(uniform(-0.03, 0.03), uniform(-0.03, 0.03), -0.45);
            (
                x,
                transform_from_parts(
                    &exp_so3(&Vector3::new(0.0, 0.0, uniform(-3.1, 3.1))),
                    &target,
                ),
            )
        }
        Setup::EyeToHand => {
            // The camera 0.6 m above the workspace, looking down; the target under the flange.
            let t = Vector3::new(uniform(-0.1, 0.1), uniform(-0.1, 0.1), uniform(0.55, 0.65));
            let x = transform_from_parts(&camera_rotation, &t);
            let target = Vector3::new(uniform(-0.03, 0.03), uniform(-0.03, 0.03), -0.05);
            (
                x,
                transform_from_parts(
                    &exp_so3(&Vector3::new(0.0, 0.0, uniform(-3.1, 3.1))),
                    &target,
                ),
            )
        }
    };
    let axis = Vector3::from(config.axis).normalize();
    let mut poses = Vec::with_capacity(config.poses);
    for _ in 0..config.poses {
        let p = Vector3::new(
            uniform(-config.reach, config.reach),
            uniform(-config.reach, config.reach),
            uniform(0.0, config.lift),
        );
        let mut r = exp_so3(&(axis * uniform(-config.turn, config.turn)));
        if let Some(w) = config.wrist {
            r *= exp_so3(
                &(Vector3::from(w).normalize() * uniform(-config.wrist_range, config.wrist_range)),
            );
        }
        let base_from_gripper = transform_from_parts(&r, &p);
        let camera_from_target = match config.setup {
            // C = X⁻¹ Q⁻¹ W (W = base_from_target).
            Setup::EyeInHand => x.inverse() * base_from_gripper.inverse() * fixed,
            // C = X⁻¹ Q W (X = base_from_camera, W = gripper_from_target).
            Setup::EyeToHand => x.inverse() * base_from_gripper * fixed,
        };
        poses.push((base_from_gripper, camera_from_target));
    }
    let mut rng = series_rng(seed ^ 0x5CA2_A001, series);
    let poses = poses
        .into_iter()
        .map(|(q, c)| {
            let dq = gaussian(&mut rng, config.robot_noise);
            let dt = gaussian(&mut rng, config.robot_noise);
            let dr = gaussian(&mut rng, config.camera_rotation);
            let lateral = gaussian(&mut rng, config.camera_lateral);
            let depth: f64 = StandardNormal.sample(&mut rng);
            let dc = Vector3::new(lateral.x, lateral.y, depth * config.camera_depth);
            PosePair {
                base_from_gripper: transform_from_parts(
                    &(q.rotation.matrix() * exp_so3(&dq)),
                    &(q.translation.vector + dt),
                ),
                camera_from_target: transform_from_parts(
                    &(exp_so3(&dr) * c.rotation.matrix()),
                    &(c.translation.vector + dc),
                ),
            }
        })
        .collect();
    LowDofSeries { poses, x, fixed }
}
