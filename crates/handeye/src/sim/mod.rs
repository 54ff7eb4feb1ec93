//! The paper's simulation protocol (sec. 4.1), as SPEC sec. 5 fixes it: a random consecutive
//! gripper walk, a hand–eye X, a target in front of the camera, and uniform relative noise.
//!
//! Lengths are millimetres. Series `s` of a run with seed `S` draws from its own generator seeded
//! from `(S, s)`, so a run is reproducible and independent of how many threads share it.

pub mod pixels;

use nalgebra::{Matrix3, Translation3, Vector3};
use rand::{Rng, RngExt, SeedableRng};
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;
use serde::{Deserialize, Serialize};

use crate::model::motion::PosePair;
use crate::model::pose::{Transform, exp_so3, log_so3, proj_so3, transform_from_parts};

/// Parameters of a simulated series; `Default` is the paper's protocol (values on each field).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SimConfig {
    /// Number of poses. Default 200.
    pub poses: usize,
    /// RMS rotation of the first pose about the nominal orientation, degrees. Default 10.
    pub initial_rotation_deg: f64,
    /// RMS distance of the first pose from the workspace centre, mm. Default 30.
    pub initial_translation: f64,
    /// RMS rotation of one step of the walk, degrees. Default 5.
    pub step_rotation_deg: f64,
    /// RMS translation of one step of the walk, mm. Default 10.
    pub step_translation: f64,
    /// Pull back towards the nominal orientation and the centre per step. Default 0.05.
    pub pull: f64,
    /// Distance of the target from the nominal camera along its optical axis, mm. Default 300.
    pub standoff: f64,
    /// Range of ‖t_x‖, mm. Default (50, 150).
    pub x_translation: (f64, f64),
    /// Amplitude of the uniform rotation-matrix noise (R + a·U, then projected). Default 0.001.
    pub rotation_noise: f64,
    /// Relative amplitude of the uniform translation noise (t + a·‖t‖·u). Default 0.01.
    pub translation_noise: f64,
    /// A change of X during the series (a bumped camera). Default none.
    pub jump: Option<Jump>,
}

/// A change of X at a given pose: from pose `at` (from 1) on, X becomes X·Δ with Δ a rotation of
/// `rotation_deg` about a random axis and a translation of length `translation` in a random
/// direction.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Jump {
    /// First pose (from 1) taken with the new X.
    pub at: usize,
    /// Rotation of the change, degrees.
    pub rotation_deg: f64,
    /// Translation of the change, input units (mm).
    pub translation: f64,
}

impl Default for SimConfig {
    fn default() -> Self {
        Self {
            poses: 200,
            initial_rotation_deg: 10.0,
            initial_translation: 30.0,
            step_rotation_deg: 5.0,
            step_translation: 10.0,
            pull: 0.05,
            standoff: 300.0,
            x_translation: (50.0, 150.0),
            rotation_noise: 0.001,
            translation_noise: 0.01,
            jump: None,
        }
    }
}

impl SimConfig {
    /// Large motions: 60° RMS steps, 30 mm, no orientation pull, 50 mm standoff (SPEC sec. 5).
    pub fn large_motions() -> Self {
        Self {
            step_rotation_deg: 60.0,
            step_translation: 30.0,
            pull: 0.0,
            standoff: 50.0,
            ..Self::default()
        }
    }

    /// The same series without noise.
    pub fn noise_free(self) -> Self {
        Self {
            rotation_noise: 0.0,
            translation_noise: 0.0,
            ..self
        }
    }
}

/// One simulated series.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SimSeries {
    /// The measured pose pairs, noise included.
    pub poses: Vec<PosePair>,
    /// The true X = `gripper_from_camera`.
    pub gripper_from_camera: Transform,
    /// The true target pose W = `base_from_target`.
    pub base_from_target: Transform,
    /// The true X after the jump, when the configuration has one.
    pub gripper_from_camera_after: Option<Transform>,
}

/// The generator of series `series` of a run with seed `seed`.
pub(crate) fn series_rng(seed: u64, series: u64) -> Xoshiro256PlusPlus {
    // SplitMix64 of the pair, so neighbouring seeds and series give unrelated streams.
    let mut z = seed ^ series.wrapping_add(1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    Xoshiro256PlusPlus::seed_from_u64(z ^ (z >> 31))
}

/// Simulates series `series` of the run with seed `seed`.
///
/// # Example
/// ```
/// use handeye::sim::{SimConfig, simulate};
/// let a = simulate(&SimConfig::default(), 7, 0);
/// assert_eq!(a.poses.len(), 200);
/// assert_eq!(a, simulate(&SimConfig::default(), 7, 0)); // reproducible
/// ```
pub fn simulate(config: &SimConfig, seed: u64, series: u64) -> SimSeries {
    let mut rng = series_rng(seed, series);
    let x = random_x(&mut rng, config.x_translation);
    let r_nom = random_rotation(&mut rng);
    let c = Vector3::zeros();
    let base_from_target = target_in_front(&transform_from_parts(&r_nom, &c), &x, config.standoff);
    let target_from_base = base_from_target.inverse();
    // The jump's random draws come after everything else, so a series with a jump shares its
    // walk and noise-free X with the same series without one.
    let mut jump_rng = series_rng(seed ^ 0x6A75_6D70, series);
    let x_after = config.jump.map(|j| {
        let axis = gaussian(&mut jump_rng, 1.0).normalize();
        let dir = gaussian(&mut jump_rng, 1.0).normalize();
        x * transform_from_parts(
            &exp_so3(&(axis * j.rotation_deg.to_radians())),
            &(dir * j.translation),
        )
    });

    let rot_sigma = config.step_rotation_deg.to_radians() / 3f64.sqrt();
    let trans_sigma = config.step_translation / 3f64.sqrt();
    let mut r = r_nom
        * exp_so3(&gaussian(
            &mut rng,
            config.initial_rotation_deg.to_radians() / 3f64.sqrt(),
        ));
    let mut p = c + gaussian(&mut rng, config.initial_translation / 3f64.sqrt());
    let mut clean = Vec::with_capacity(config.poses);
    for k in 0..config.poses {
        if k > 0 {
            let w = gaussian(&mut rng, rot_sigma);
            let v = gaussian(&mut rng, trans_sigma);
            let pull = log_so3(&(r_nom.transpose() * r)) * config.pull;
            r = proj_so3(&(r * exp_so3(&(w - pull))));
            p = p + v - (p - c) * config.pull;
        }
        let base_from_gripper = transform_from_parts(&r, &p);
        let x_now = match (config.jump, x_after) {
            (Some(j), Some(after)) if k + 1 >= j.at => after,
            _ => x,
        };
        let target_from_camera = target_from_base * base_from_gripper * x_now;
        clean.push((base_from_gripper, target_from_camera));
    }
    let noisy_q: Vec<Transform> = clean
        .iter()
        .map(|(q, _)| add_noise(&mut rng, q, config))
        .collect();
    let noisy_p: Vec<Transform> = clean
        .iter()
        .map(|(_, pc)| add_noise(&mut rng, pc, config))
        .collect();
    let poses = noisy_q
        .into_iter()
        .zip(noisy_p)
        .map(|(q, pc)| PosePair {
            base_from_gripper: q,
            camera_from_target: pc.inverse(),
        })
        .collect();
    SimSeries {
        poses,
        gripper_from_camera: x,
        base_from_target,
        gripper_from_camera_after: x_after,
    }
}

/// A rotation drawn uniformly from SO(3) (a normalised Gaussian quaternion).
pub(crate) fn random_rotation(rng: &mut impl Rng) -> Matrix3<f64> {
    let q = nalgebra::Quaternion::new(
        StandardNormal.sample(rng),
        StandardNormal.sample(rng),
        StandardNormal.sample(rng),
        StandardNormal.sample(rng),
    );
    *nalgebra::UnitQuaternion::from_quaternion(q)
        .to_rotation_matrix()
        .matrix()
}

/// X: uniform rotation; translation of uniform direction and length U(lo, hi).
fn random_x(rng: &mut impl Rng, (lo, hi): (f64, f64)) -> Transform {
    let r = random_rotation(rng);
    let dir = loop {
        let v: Vector3<f64> = gaussian(rng, 1.0);
        if v.norm() > 1e-9 {
            break v.normalize();
        }
    };
    let len = if hi > lo {
        rng.random_range(lo..hi)
    } else {
        lo
    };
    transform_from_parts(&r, &(dir * len))
}

/// The target W = `base_from_target` on the nominal camera's optical axis, `standoff` away, its z
/// axis facing the camera (a half turn about the camera's x axis).
fn target_in_front(base_from_gripper: &Transform, x: &Transform, standoff: f64) -> Transform {
    let base_from_camera = base_from_gripper * x;
    let centre = base_from_camera * nalgebra::Point3::new(0.0, 0.0, standoff);
    let flip = Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -1.0));
    let r = base_from_camera.rotation.matrix() * flip;
    Transform::from_parts(
        Translation3::from(centre.coords),
        nalgebra::Rotation3::from_matrix_unchecked(r),
    )
}

/// A vector of independent N(0, σ²) components.
fn gaussian(rng: &mut impl Rng, sigma: f64) -> Vector3<f64> {
    let mut n = || -> f64 { StandardNormal.sample(rng) };
    Vector3::new(n(), n(), n()) * sigma
}

/// SPEC sec. 5 noise: R ← proj_SO3(R + a·U), U_jk ~ U(−1, 1); t ← t + b·‖t‖·u, u_j ~ U(−1, 1).
fn add_noise(rng: &mut impl Rng, t: &Transform, config: &SimConfig) -> Transform {
    let mut u = || rng.random_range(-1.0..=1.0);
    let noise_r = Matrix3::from_fn(|_, _| u());
    let noise_t = Vector3::from_fn(|_, _| u());
    if config.rotation_noise == 0.0 && config.translation_noise == 0.0 {
        return *t;
    }
    let r = proj_so3(&(t.rotation.matrix() + noise_r * config.rotation_noise));
    let v = t.translation.vector;
    transform_from_parts(&r, &(v + noise_t * (config.translation_noise * v.norm())))
}

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
