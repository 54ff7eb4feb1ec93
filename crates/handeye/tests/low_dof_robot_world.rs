//! Robot-world calibration of a low-DOF robot (issue 30): SCARA recordings from
//! `sim::simulate_low_dof`, both setups. The poses leave one combination free, X's translation
//! along the axis and the target's along the same axis; a prior on X's component fixes both.
//!
//! `cargo test --release -p handeye --test low_dof_robot_world -- --nocapture` prints the
//! measurements.

use handeye::model::pose::rotation_angle_between;
use handeye::sim::{LowDofConfig, simulate_low_dof};
use handeye::{
    Component, Degeneracy, Error, Fix, LowDofMissing, Options, Pairing, PosePair, Prior, Problem,
    Setup, Transform, calibrate,
};

const SETUPS: [Setup; 2] = [Setup::EyeInHand, Setup::EyeToHand];
const SEEDS: u64 = 40;

fn prior(value: f64, sigma: f64) -> Prior {
    Prior {
        component: Component::Tz,
        value,
        sigma,
        unit: None,
    }
}

fn options(priors: Vec<Prior>) -> Options {
    Options {
        problem: Problem::ROBOT_WORLD,
        priors,
        ..Options::default()
    }
}

fn scara(setup: Setup) -> LowDofConfig {
    LowDofConfig {
        setup,
        ..LowDofConfig::default()
    }
}

/// Rotation error (degrees) and translation error (input units) of `x` against `truth`.
fn errors(x: &Transform, truth: &Transform) -> (f64, f64) {
    let r = rotation_angle_between(&x.rotation, &truth.rotation).to_degrees();
    (r, (x.translation.vector - truth.translation.vector).norm())
}

fn low_dof_missing(e: &Error) -> Option<LowDofMissing> {
    let e = match e {
        Error::Untrusted {
            refusal: Some(r), ..
        } => r.as_ref(),
        other => other,
    };
    match e {
        Error::Degenerate {
            reason: Degeneracy::LowDof { missing, .. },
            ..
        } => Some(*missing),
        _ => None,
    }
}

#[test]
fn noise_free_scara_gives_x_and_the_target_exactly() {
    for setup in SETUPS {
        for seed in 0..5 {
            let s = simulate_low_dof(&scara(setup).noise_free(), seed, 0);
            let tz = s.x.translation.vector.z;
            let r = calibrate(&s.poses, setup, &options(vec![prior(tz, 0.0)]))
                .map(|r| r.into_robot_world().expect("the robot-world report"))
                .unwrap_or_else(|e| panic!("{setup} {seed}: {e}"));
            let (xr, xt) = errors(&r.transform, &s.x);
            let (yr, yt) = errors(&r.target_transform, &s.fixed);
            assert!(
                xr.to_radians() < 1e-9 && xt < 1e-9 && yr.to_radians() < 1e-9 && yt < 1e-9,
                "{setup} seed {seed}: X {xr:e}° {xt:e}, target {yr:e}° {yt:e}"
            );
            assert_eq!(r.transform.translation.vector.z, tz);
            assert!(r.low_dof.is_some());
            assert_eq!(r.prior["tz"].value, tz);
        }
    }
}

/// The free combination, measured: a prior off by d moves X by d along the axis and the target by
/// d along the axis as its frame sees it (the base's vertical eye-in-hand; the gripper's axis
/// eye-to-hand), and every pose still agrees exactly.
#[test]
fn a_wrong_height_moves_x_and_the_target_together_along_the_axis() {
    let d = 0.01;
    for setup in SETUPS {
        for seed in 0..5 {
            let s = simulate_low_dof(&scara(setup).noise_free(), seed, 0);
            let tz = s.x.translation.vector.z;
            let r = calibrate(&s.poses, setup, &options(vec![prior(tz + d, 0.0)]))
                .map(|r| r.into_robot_world().expect("the robot-world report"))
                .unwrap_or_else(|e| panic!("{setup} {seed}: {e}"));
            assert!(
                r.residual.translation_max < 1e-9 && r.residual.rotation_deg_max < 1e-7,
                "{setup} {seed}: {:?}",
                r.residual
            );
            let dx = r.transform.translation.vector - s.x.translation.vector;
            let dy = r.target_transform.translation.vector - s.fixed.translation.vector;
            // The SCARA's axis is the gripper's z: X moves along it by d.
            assert!(
                (dx - nalgebra::Vector3::z() * d).norm() < 1e-9,
                "{setup}: {dx}"
            );
            // The target moves by d along R_Q z, the same for every pose.
            let q = setup.hand_pose(&s.poses[0].base_from_gripper);
            let along = q.rotation * nalgebra::Vector3::z() * d;
            assert!(
                (dy - along).norm() < 1e-9,
                "{setup} {seed}: {dy} vs {along}"
            );
            if setup == Setup::EyeInHand {
                // The base's vertical: the target's height.
                assert!((dy.z.abs() - d).abs() < 1e-9, "{dy}");
            }
            let (yr, _) = errors(&r.target_transform, &s.fixed);
            assert!(yr.to_radians() < 1e-9);
        }
    }
}

#[test]
fn scara_with_the_true_height_is_within_three_sigma() {
    for setup in SETUPS {
        let mut within = 0;
        let mut ratios = Vec::new();
        for seed in 0..SEEDS {
            let s = simulate_low_dof(&scara(setup), seed, 0);
            let tz = s.x.translation.vector.z;
            let r = calibrate(&s.poses, setup, &options(vec![prior(tz, 0.0)]))
                .map(|r| r.into_robot_world().expect("the robot-world report"))
                .unwrap_or_else(|e| panic!("{setup} {seed}: {e}"));
            assert_eq!(r.transform.translation.vector.z, tz, "tz is the prior's");
            assert_eq!(r.prior["tz"].sigma, 0.0);
            let (xr, xt) = errors(&r.transform, &s.x);
            let (yr, yt) = errors(&r.target_transform, &s.fixed);
            let (u, v) = (&r.uncertainty, &r.target.uncertainty);
            let ratio = (xr / u.rotation_deg)
                .max(xt / u.translation)
                .max(yr / v.rotation_deg)
                .max(yt / v.translation);
            ratios.push(ratio);
            if ratio <= 3.0 {
                within += 1;
            }
        }
        ratios.sort_by(f64::total_cmp);
        println!(
            "{setup}: {within}/{SEEDS} with X and the target within 3 sigma; largest error/sigma median {:.2}, max {:.2}",
            ratios[ratios.len() / 2],
            ratios[ratios.len() - 1]
        );
        assert!(
            within as f64 >= 0.95 * SEEDS as f64,
            "{setup}: {within}/{SEEDS}"
        );
        // Not so wide as to say nothing.
        assert!(ratios[ratios.len() / 2] > 0.3, "{ratios:?}");
    }
}

#[test]
fn a_prior_with_a_sigma_widens_x_and_the_target_along_the_axis() {
    for setup in SETUPS {
        for seed in 0..5 {
            let s = simulate_low_dof(&scara(setup), seed, 0);
            let tz = s.x.translation.vector.z;
            let sigma = 0.002;
            let exact = calibrate(&s.poses, setup, &options(vec![prior(tz, 0.0)]))
                .map(|r| r.into_robot_world().expect("the robot-world report"))
                .unwrap();
            let r = calibrate(&s.poses, setup, &options(vec![prior(tz + 0.001, sigma)]))
                .map(|r| r.into_robot_world().expect("the robot-world report"))
                .unwrap();
            assert_eq!(r.transform.translation.vector.z, tz + 0.001);
            assert_eq!(r.prior["tz"].sigma, sigma);
            let reported = r.uncertainty.covariance[5][5].sqrt();
            assert!(reported >= sigma, "{setup} {seed}: {reported}");
            // The target's coupled direction: R_Q z, its variance the prior's more than without.
            let q = setup.hand_pose(&s.poses[0].base_from_gripper);
            let k = q.rotation * nalgebra::Vector3::z();
            let along = |c: &[[f64; 6]; 6]| {
                let m = nalgebra::Matrix3::from_fn(|i, j| c[3 + i][3 + j]);
                (k.transpose() * m * k)[0].sqrt()
            };
            let target = along(&r.target.uncertainty.covariance);
            let data = along(&exact.target.uncertainty.covariance);
            println!(
                "{setup} {seed}: X tz sigma {reported:.6}, target along the axis {target:.6} (data alone {data:.2e}; prior {sigma})"
            );
            assert!(target >= sigma && target > data, "{setup} {seed}: {target}");
        }
    }
}

#[test]
fn scara_without_a_prior_is_refused_in_the_hand_eye_words() {
    for setup in SETUPS {
        for seed in 0..SEEDS {
            let s = simulate_low_dof(&scara(setup), seed, 0);
            let e = calibrate(&s.poses, setup, &options(vec![]))
                .map(|r| r.into_robot_world().expect("the robot-world report"))
                .unwrap_err();
            assert_eq!(
                low_dof_missing(&e),
                Some(LowDofMissing::Prior(Component::Tz)),
                "{setup} {seed}: {e}"
            );
            let hand_eye = calibrate(
                &s.poses,
                setup,
                &Options {
                    pairing: Pairing::All,
                    ..Options::default()
                },
            )
            .map(|r| r.into_hand_eye().expect("the hand–eye report"))
            .unwrap_err();
            assert_eq!(e.to_string(), hand_eye.to_string());
            assert!(e.to_string().contains("--prior tz="), "{e}");
        }
    }
}

#[test]
fn a_prior_in_another_unit_is_refused_as_for_hand_eye() {
    for setup in SETUPS {
        let s = simulate_low_dof(&scara(setup), 3, 0);
        let tz = s.x.translation.vector.z;
        let e = calibrate(&s.poses, setup, &options(vec![prior(tz * 1e3, 1.0)]))
            .map(|r| r.into_robot_world().expect("the robot-world report"))
            .unwrap_err();
        assert!(
            matches!(e, Error::InvalidParameter { name: "prior", .. }),
            "{setup}: {e}"
        );
        assert!(e.to_string().contains("another length unit"), "{e}");
        // Named in millimetres: converted.
        let named: Prior = format!("tz={}mm", tz * 1e3).parse().unwrap();
        let r = calibrate(&s.poses, setup, &options(vec![named]))
            .map(|r| r.into_robot_world().expect("the robot-world report"))
            .unwrap();
        assert!((r.transform.translation.vector.z - tz).abs() < 1e-12);
    }
}

#[test]
fn an_outlier_is_named_and_left_out_on_request() {
    for setup in SETUPS {
        let s = simulate_low_dof(&scara(setup), 3, 0);
        let tz = s.x.translation.vector.z;
        let mut poses = s.poses.clone();
        poses[7].camera_from_target = poses[19].camera_from_target;
        match calibrate(&poses, setup, &options(vec![prior(tz, 0.0)]))
            .map(|r| r.into_robot_world().expect("the robot-world report"))
        {
            Ok(r) => {
                assert!(!r.warnings.is_empty(), "{setup}: a silent answer");
                assert!(
                    r.outliers.poses.iter().any(|p| p.pose == 7),
                    "{setup}: {:?}",
                    r.outliers
                );
            }
            Err(e) => assert!(e.to_string().contains("pose 7"), "{setup}: {e}"),
        }
        let r = calibrate(
            &poses,
            setup,
            &Options {
                problem: Problem::ROBOT_WORLD,
                reject_outliers: true,
                ..options(vec![prior(tz, 0.0)])
            },
        )
        .map(|r| r.into_robot_world().expect("the robot-world report"))
        .unwrap_or_else(|e| panic!("{setup}: {e}"));
        let (xr, xt) = errors(&r.transform, &s.x);
        let (yr, yt) = errors(&r.target_transform, &s.fixed);
        println!("{setup}, outlier left out: X {xr:.3}° {xt:.4}, target {yr:.3}° {yt:.4}");
        assert!(xr <= 3.0 * r.uncertainty.rotation_deg && xt <= 3.0 * r.uncertainty.translation);
        assert!(
            yr <= 3.0 * r.target.uncertainty.rotation_deg
                && yt <= 3.0 * r.target.uncertainty.translation
        );
    }
}

#[test]
fn an_inverted_recording_is_refused_or_read_right() {
    for setup in SETUPS {
        let s = simulate_low_dof(&scara(setup), 5, 0);
        let tz = s.x.translation.vector.z;
        // The robot's poses written the other way round.
        let inverted: Vec<PosePair> = s
            .poses
            .iter()
            .map(|p| PosePair {
                base_from_gripper: p.base_from_gripper.inverse(),
                camera_from_target: p.camera_from_target,
            })
            .collect();
        for fix in [Fix::Refuse, Fix::Auto] {
            let o = Options {
                problem: Problem::ROBOT_WORLD,
                fix,
                ..options(vec![prior(tz, 0.0)])
            };
            match calibrate(&inverted, setup, &o)
                .map(|r| r.into_robot_world().expect("the robot-world report"))
            {
                // Refused: for the reading, or for motions that do not fix X with the reading
                // named as the thing to check.
                Err(e) => {
                    println!("{setup}, inverted, {fix:?}: {e}");
                    let words = e.to_string();
                    assert!(
                        matches!(e, Error::Misread { .. })
                            || words.contains("each pose in the direction its name says"),
                        "{setup}: {e}"
                    );
                }
                // Answered only when read right, and said so.
                Ok(r) => {
                    let (xr, xt) = errors(&r.transform, &s.x);
                    println!("{setup}, inverted, {fix:?}: read right, X {xr:.3}° {xt:.4}");
                    assert!(!r.warnings.is_empty(), "{setup}: a silent answer");
                    assert!(
                        xr <= 3.0 * r.uncertainty.rotation_deg
                            && xt <= 3.0 * r.uncertainty.translation,
                        "{setup}: {xr}° {xt}"
                    );
                }
            }
        }
    }
}
