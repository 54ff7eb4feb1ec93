//! The paper's simulation protocol (sec. 4.1), as SPEC sec. 5 fixes it: a random consecutive
//! gripper walk, a hand–eye X, a target in front of the camera, and uniform relative noise.
//!
//! Lengths are millimetres. Series `s` of a run with seed `S` draws from its own generator seeded
//! from `(S, s)`, so a run is reproducible and independent of how many threads share it.

// The low-DOF and pixel simulators.
mod low_dof;
pub mod pixels;
pub use low_dof::{LowDofConfig, LowDofSeries, simulate_low_dof};

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

pub use series::SimSeries;

/// `poses` as they are when the camera slipped on its mount at pose `at` (from 0; 0 for a camera
/// moved before the recording): X becomes X·`slip`, so from then on each `camera_from_target` is
/// `slip⁻¹ · camera_from_target` (the target stays where it was), in either setup.
pub fn slipped(poses: &[PosePair], at: usize, slip: &Transform) -> Vec<PosePair> {
    let moved = slip.inverse();
    poses
        .iter()
        .enumerate()
        .map(|(i, p)| PosePair {
            camera_from_target: if i >= at {
                moved * p.camera_from_target
            } else {
                p.camera_from_target
            },
            ..*p
        })
        .collect()
}

mod series {
    use serde::{Deserialize, Serialize};

    use crate::model::motion::PosePair;
    use crate::model::pose::Transform;

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
}

/// The generator of series `series` of a run with seed `seed`.
pub(crate) fn series_rng(seed: u64, series: u64) -> Xoshiro256PlusPlus {
    // SplitMix64 of the pair, so neighbouring seeds and series give unrelated streams.
    let mut z = seed ^ series.wrapping_add(1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    Xoshiro256PlusPlus::seed_from_u64(z ^ (z >> 31))
}

/// Simulates series `series` of the run with seed `seed`: the measured pose pairs (`poses`,
/// noise included), the true X (`gripper_from_camera`; `gripper_from_camera_after`, after the
/// configuration's jump if it has one) and the true target pose (`base_from_target`).
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
pub(crate) fn gaussian(rng: &mut impl Rng, sigma: f64) -> Vector3<f64> {
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
