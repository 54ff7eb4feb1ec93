//! The simulator of SPEC sec. 5: reproducibility, noise model, walk statistics.

use handeye::check::quality::errors_against_truth;
use handeye::sim::{SimConfig, simulate};
use handeye::solve::andreff;
use handeye::{MotionFeatures, Pairing, Setup, motion_pairs};
use nalgebra::Matrix3;

#[test]
fn series_are_reproducible_and_distinct() {
    let c = SimConfig::default();
    assert_eq!(simulate(&c, 3, 1), simulate(&c, 3, 1));
    assert_ne!(simulate(&c, 3, 1), simulate(&c, 3, 2));
    assert_ne!(simulate(&c, 3, 1), simulate(&c, 4, 1));
}

#[test]
fn noise_has_the_specified_amplitude_and_keeps_rotations_orthonormal() {
    let noisy = simulate(&SimConfig::default(), 9, 0);
    let clean = simulate(&SimConfig::default().noise_free(), 9, 0);
    let (mut max_t, mut sum_sq, mut count) = (0.0_f64, 0.0, 0.0);
    let mut max_r = 0.0_f64;
    for (n, c) in noisy.poses.iter().zip(&clean.poses) {
        for (tn, tc) in [
            (n.base_from_gripper, c.base_from_gripper),
            (
                n.camera_from_target.inverse(),
                c.camera_from_target.inverse(),
            ),
        ] {
            let r = tn.rotation.matrix();
            assert!((r.transpose() * r - Matrix3::identity()).abs().max() < 1e-12);
            assert!((r.determinant() - 1.0).abs() < 1e-12);
            max_r = max_r.max((r - tc.rotation.matrix()).abs().max());
            let rel = (tn.translation.vector - tc.translation.vector)
                / (0.01 * tc.translation.vector.norm());
            max_t = max_t.max(rel.amax());
            sum_sq += rel.norm_squared();
            count += 3.0;
        }
    }
    // t ← t + 0.01‖t‖u, u_j ~ U(−1, 1): |u_j| ≤ 1 and RMS 1/√3.
    assert!(max_t <= 1.0 + 1e-9, "translation noise {max_t}");
    let rms = (sum_sq / count).sqrt();
    assert!(
        (rms - 3f64.sqrt().recip()).abs() < 0.03,
        "translation noise RMS {rms}"
    );
    // R ← proj(R + 0.001U): the projection keeps the change at the 1e-3 level.
    assert!(max_r > 1e-4 && max_r < 2e-3, "rotation noise {max_r}");
}

#[test]
fn the_walk_has_the_paper_step_sizes_and_a_consistent_x() {
    let s = simulate(&SimConfig::default().noise_free(), 1, 0);
    let motions = motion_pairs(&s.poses, Pairing::Consecutive, Setup::EyeInHand);
    let rms_angle = (motions
        .iter()
        .map(|m| MotionFeatures::of(&m.a).angle.powi(2))
        .sum::<f64>()
        / motions.len() as f64)
        .sqrt()
        .to_degrees();
    assert!(
        (3.5..7.0).contains(&rms_angle),
        "RMS step rotation {rms_angle}°"
    );
    let t = s.gripper_from_camera.translation.vector.norm();
    assert!((50.0..=150.0).contains(&t));
    // Noise-free data are consistent with the true X.
    let x = andreff(&motions).unwrap().x;
    let e = errors_against_truth(&x, &s.gripper_from_camera);
    assert!(e.rot_fro < 1e-9 && e.trans_rel < 1e-9, "{e:?}");
}

#[test]
fn large_motions_preset_moves_more() {
    let s = simulate(&SimConfig::large_motions().noise_free(), 1, 0);
    let motions = motion_pairs(&s.poses, Pairing::Consecutive, Setup::EyeInHand);
    let mean = motions
        .iter()
        .map(|m| MotionFeatures::of(&m.a).angle)
        .sum::<f64>()
        / motions.len() as f64;
    assert!(mean.to_degrees() > 30.0, "mean step {}°", mean.to_degrees());
}
