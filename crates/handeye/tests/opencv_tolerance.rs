//! OpenCV's own accuracy test of `calibrateHandEye` (calib3d's test_calibration_hand_eye.cpp):
//! 100 trials × 10 poses with Gaussian noise on the rotation vector and translation of both
//! poses, every method, eye-in-hand and eye-to-hand, all pose pairs, OpenCV's tolerance table.

use handeye::pose::{exp_so3, log_so3, rotation_matrix, transform_from_parts};
use handeye::{Method, Pairing, PosePair, Setup, Transform, motion_pairs, solve};
use nalgebra::Vector3;
use rand::{Rng, RngExt, SeedableRng};
use rand_distr::{Distribution, Normal};
use rand_xoshiro::Xoshiro256PlusPlus;

/// A pose as OpenCV's `generatePose`: angle in [min, max] with a random sign about an axis of
/// U(−1, 1) components (not normalised), translation components in [lo, hi] with random signs.
fn generate_pose(rng: &mut impl Rng, theta: (f64, f64), t: (f64, f64)) -> Transform {
    let axis = Vector3::from_fn(|_, _| rng.random_range(-1.0..1.0));
    let mut angle = rng.random_range(theta.0..theta.1);
    if rng.random_range(-1.0..1.0) < 0.0 {
        angle = -angle;
    }
    let mut tv = Vector3::from_fn(|_, _| rng.random_range(t.0..t.1));
    for k in 0..3 {
        if rng.random_range(-1.0..1.0) < 0.0 {
            tv[k] = -tv[k];
        }
    }
    transform_from_parts(&exp_so3(&(axis * angle)), &tv)
}

/// Adds N(0, σ_r²) to each rotation-vector component and N(0, σ_t²) to each translation one.
fn perturb(rng: &mut impl Rng, t: &Transform, sigma_r: f64, sigma_t: f64) -> Transform {
    let nr = Normal::new(0.0, sigma_r).unwrap();
    let nt = Normal::new(0.0, sigma_t).unwrap();
    let r = log_so3(&rotation_matrix(t)) + Vector3::from_fn(|_, _| nr.sample(rng));
    let v = t.translation.vector + Vector3::from_fn(|_, _| nt.sample(rng));
    transform_from_parts(&exp_so3(&r), &v)
}

/// One trial: the poses as the user gives them (base_from_gripper, camera_from_target) and X.
fn trial(rng: &mut impl Rng, setup: Setup, n: usize) -> (Vec<PosePair>, Transform) {
    let deg = std::f64::consts::PI / 180.0;
    match setup {
        Setup::EyeInHand => {
            let gripper_from_camera = generate_pose(rng, (10.0 * deg, 50.0 * deg), (0.05, 0.5));
            let base_from_target = generate_pose(rng, (5.0 * deg, 85.0 * deg), (0.5, 3.5));
            let poses = (0..n)
                .map(|_| {
                    let base_from_gripper = generate_pose(rng, (5.0 * deg, 45.0 * deg), (0.5, 1.5));
                    let camera_from_target =
                        (base_from_gripper * gripper_from_camera).inverse() * base_from_target;
                    PosePair {
                        camera_from_target: perturb(rng, &camera_from_target, 0.002, 0.005),
                        base_from_gripper: perturb(rng, &base_from_gripper, 0.001, 0.001),
                    }
                })
                .collect();
            (poses, gripper_from_camera)
        }
        Setup::EyeToHand => {
            let base_from_camera = generate_pose(rng, (10.0 * deg, 50.0 * deg), (0.5, 3.5));
            let gripper_from_target = generate_pose(rng, (5.0 * deg, 85.0 * deg), (0.05, 0.5));
            let poses = (0..n)
                .map(|_| {
                    let base_from_gripper = generate_pose(rng, (5.0 * deg, 45.0 * deg), (0.5, 1.5));
                    let camera_from_target =
                        base_from_camera.inverse() * base_from_gripper * gripper_from_target;
                    // OpenCV perturbs base2gripper (our gripper_from_base) in the eye-to-hand test.
                    let gripper_from_base =
                        perturb(rng, &base_from_gripper.inverse(), 0.001, 0.001);
                    PosePair {
                        camera_from_target: perturb(rng, &camera_from_target, 0.002, 0.005),
                        base_from_gripper: gripper_from_base.inverse(),
                    }
                })
                .collect();
            (poses, base_from_camera)
        }
    }
}

/// OpenCV's tolerances on ‖rvec − rvec_true‖ and ‖t − t_true‖.
fn tolerance(method: Method) -> (f64, f64) {
    match method {
        Method::Tsai | Method::Park | Method::Horaud => (2e-2, 7e-2),
        _ => (1e-2, 5e-2),
    }
}

#[test]
fn every_method_passes_opencvs_tolerance_table() {
    for setup in [Setup::EyeInHand, Setup::EyeToHand] {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(0x0ce4);
        let mut worst = [(0.0_f64, 0.0_f64); 7];
        for _ in 0..100 {
            let (poses, truth) = trial(&mut rng, setup, 10);
            let motions = motion_pairs(&poses, Pairing::All, setup);
            for (k, method) in Method::ALL.into_iter().enumerate() {
                let x = solve(method, &motions)
                    .unwrap_or_else(|e| panic!("{method}: {e}"))
                    .x;
                let dr = (log_so3(&rotation_matrix(&x)) - log_so3(&rotation_matrix(&truth))).norm();
                let dt = (x.translation.vector - truth.translation.vector).norm();
                worst[k] = (worst[k].0.max(dr), worst[k].1.max(dt));
                let (tr, tt) = tolerance(method);
                assert!(
                    dr <= tr && dt <= tt,
                    "{} {method}: rvec error {dr:.2e}, tvec error {dt:.2e}",
                    setup.name()
                );
            }
        }
        for (k, method) in Method::ALL.into_iter().enumerate() {
            println!(
                "{} {method}: worst rvec error {:.2e}, worst tvec error {:.2e}",
                setup.name(),
                worst[k].0,
                worst[k].1
            );
        }
    }
}
