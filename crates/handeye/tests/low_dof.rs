//! Low-DOF robots (issue 30): SCARA, 5-axis and gantry recordings from `sim::simulate_low_dof`.
//! Without a prior the free direction is refused, naming the prior; with one, X is within its
//! reported uncertainty and the prior's component is the prior's.
//!
//! `cargo test --release -p handeye --test low_dof -- --nocapture` prints the measurements.

use handeye::model::pose::rotation_angle_between;
use handeye::sim::{LowDofConfig, simulate_low_dof};
use handeye::{
    Component, Degeneracy, Error, LowDofMissing, Method, Options, Pairing, PosePair, Prior,
    Problem, Setup, Transform, Warning, calibrate,
};
use nalgebra::Vector3;

const SETUPS: [Setup; 2] = [Setup::EyeInHand, Setup::EyeToHand];
const SEEDS: u64 = 40;

fn prior(component: Component, value: f64, sigma: f64) -> Prior {
    Prior {
        component,
        value,
        sigma,
        unit: None,
    }
}

fn options(priors: Vec<Prior>) -> Options {
    Options {
        pairing: Pairing::All,
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

fn low_dof_reason(e: &Error) -> Option<(LowDofMissing, [f64; 3])> {
    let e = match e {
        Error::Untrusted {
            refusal: Some(r), ..
        } => r.as_ref(),
        other => other,
    };
    match e {
        Error::Degenerate {
            reason: Degeneracy::LowDof { missing, axis, .. },
            ..
        } => Some((*missing, *axis)),
        _ => None,
    }
}

#[test]
fn noise_free_scara_is_exact_with_the_true_height() {
    for setup in SETUPS {
        for seed in 0..5 {
            let s = simulate_low_dof(&scara(setup).noise_free(), seed, 0);
            let tz = s.x.translation.vector.z;
            for (method, pairing) in [
                (Method::Andreff, Pairing::All),
                (Method::Refine, Pairing::All),
                (Method::Andreff, Pairing::Consecutive),
                (Method::Refine, Pairing::Consecutive),
            ] {
                let o = Options {
                    problem: Problem::HandEye(method),
                    pairing,
                    ..options(vec![prior(Component::Tz, tz, 0.0)])
                };
                let r = calibrate(&s.poses, setup, &o)
                    .map(|r| r.into_hand_eye().expect("the hand–eye report"))
                    .unwrap();
                let (er, et) = errors(&r.transform, &s.x);
                assert!(
                    er.to_radians() < 1e-9 && et < 1e-9,
                    "{setup} seed {seed} {method:?} {pairing:?}: {er:e}° {et:e}"
                );
                assert!(r.low_dof.is_some());
            }
        }
    }
}

#[test]
fn scara_without_a_prior_is_refused_naming_it() {
    for setup in SETUPS {
        for seed in 0..SEEDS {
            let s = simulate_low_dof(&scara(setup), seed, 0);
            let e = calibrate(&s.poses, setup, &options(vec![]))
                .map(|r| r.into_hand_eye().expect("the hand–eye report"))
                .unwrap_err();
            let (missing, axis) =
                low_dof_reason(&e).unwrap_or_else(|| panic!("{setup} {seed}: {e}"));
            assert_eq!(missing, LowDofMissing::Prior(Component::Tz));
            assert!(axis[2] > 0.999, "{axis:?}");
            let words = e.to_string();
            assert!(words.contains("--prior tz="), "{words}");
            assert!(words.contains("SCARA"), "{words}");
            assert!(!words.contains("rotate about the gripper x"), "{words}");
            // A prior on a component the motions determine does not cover the free one.
            let e = calibrate(
                &s.poses,
                setup,
                &options(vec![prior(Component::Tx, 0.0, 0.0)]),
            )
            .map(|r| r.into_hand_eye().expect("the hand–eye report"))
            .unwrap_err();
            assert_eq!(
                low_dof_reason(&e).map(|r| r.0),
                Some(LowDofMissing::Prior(Component::Tz))
            );
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
            let method = if seed % 2 == 0 {
                Method::Andreff
            } else {
                Method::Refine
            };
            let o = Options {
                problem: Problem::HandEye(method),
                ..options(vec![prior(Component::Tz, tz, 0.0)])
            };
            let r = calibrate(&s.poses, setup, &o)
                .map(|r| r.into_hand_eye().expect("the hand–eye report"))
                .unwrap_or_else(|e| panic!("{setup} {seed}: {e}"));
            assert_eq!(r.transform.translation.vector.z, tz, "tz is the prior's");
            assert_eq!(r.prior["tz"].value, tz);
            assert_eq!(r.prior["tz"].sigma, 0.0);
            let (er, et) = errors(&r.transform, &s.x);
            let (sr, st) = (r.uncertainty.rotation_deg, r.uncertainty.translation);
            ratios.push((er / sr).max(et / st));
            if er <= 3.0 * sr && et <= 3.0 * st {
                within += 1;
            }
        }
        ratios.sort_by(f64::total_cmp);
        println!(
            "{setup}: {within}/{SEEDS} within 3 sigma; error/sigma median {:.2}, max {:.2}",
            ratios[ratios.len() / 2],
            ratios[ratios.len() - 1]
        );
        assert!(
            within as f64 >= 0.95 * SEEDS as f64,
            "{setup}: {within}/{SEEDS}"
        );
    }
}

#[test]
fn a_prior_with_a_sigma_is_the_reported_sigma_of_its_component() {
    for setup in SETUPS {
        for seed in 0..5 {
            let s = simulate_low_dof(&scara(setup), seed, 0);
            let tz = s.x.translation.vector.z;
            let exact = calibrate(
                &s.poses,
                setup,
                &options(vec![prior(Component::Tz, tz, 0.0)]),
            )
            .map(|r| r.into_hand_eye().expect("the hand–eye report"))
            .unwrap();
            let sigma = 0.002;
            let r = calibrate(
                &s.poses,
                setup,
                &options(vec![prior(Component::Tz, tz + 0.001, sigma)]),
            )
            .map(|r| r.into_hand_eye().expect("the hand–eye report"))
            .unwrap();
            let data = exact.uncertainty.covariance[5][5].sqrt();
            let reported = r.uncertainty.covariance[5][5].sqrt();
            println!(
                "{setup} {seed}: tz sigma {reported:.6} (prior {sigma}, data alone {data:.2e})"
            );
            assert!(reported >= sigma && reported <= (sigma * sigma + data * data).sqrt() + 1e-12);
            assert_eq!(r.prior["tz"].sigma, sigma);
            assert_eq!(r.transform.translation.vector.z, tz + 0.001);
            let at = |r: &handeye::HandEyeReport| r.uncertainty.at_point.as_ref().unwrap().sigma;
            assert!(at(&r) >= sigma && at(&r) > at(&exact));
        }
    }
}

#[test]
fn a_prior_on_a_determined_component_keeps_the_data_and_warns() {
    let setup = Setup::EyeInHand;
    let s = simulate_low_dof(&scara(setup), 1, 0);
    let t = s.x.translation.vector;
    let r = calibrate(
        &s.poses,
        setup,
        &options(vec![
            prior(Component::Tz, t.z, 0.0),
            prior(Component::Tx, t.x + 0.05, 0.001),
        ]),
    )
    .map(|r| r.into_hand_eye().expect("the hand–eye report"))
    .unwrap();
    assert!(!r.prior.contains_key("tx"));
    assert!((r.transform.translation.vector.x - t.x).abs() < 0.01);
    assert!(
        r.warnings
            .iter()
            .any(|w| matches!(w, Warning::PriorDisagrees { component, .. } if component == "tx")),
        "{:?}",
        r.warnings
    );
    // An agreeing one is no warning.
    let r = calibrate(
        &s.poses,
        setup,
        &options(vec![
            prior(Component::Tz, t.z, 0.0),
            prior(Component::Tx, t.x, 0.001),
        ]),
    )
    .map(|r| r.into_hand_eye().expect("the hand–eye report"))
    .unwrap();
    assert!(
        !r.warnings
            .iter()
            .any(|w| matches!(w, Warning::PriorDisagrees { .. }))
    );
}

/// A 5-axis arm: x, y, z, a turn about z and a wrist about the flange's x. Two rotation axes:
/// the motions determine all of X, no prior needed.
#[test]
fn five_axis_arm_is_determined_without_a_prior() {
    for setup in SETUPS {
        let mut within = 0;
        for seed in 0..SEEDS {
            let config = LowDofConfig {
                wrist: Some([1.0, 0.0, 0.0]),
                ..scara(setup)
            };
            let s = simulate_low_dof(&config, seed, 0);
            let r = calibrate(&s.poses, setup, &options(vec![]))
                .map(|r| r.into_hand_eye().expect("the hand–eye report"))
                .unwrap_or_else(|e| panic!("{setup} {seed}: {e}"));
            assert!(r.low_dof.is_none() && r.prior.is_empty());
            let (er, et) = errors(&r.transform, &s.x);
            if er <= 3.0 * r.uncertainty.rotation_deg && et <= 3.0 * r.uncertainty.translation {
                within += 1;
            }
        }
        println!("5-axis {setup}: {within}/{SEEDS} within 3 sigma");
        assert!(within as f64 >= 0.95 * SEEDS as f64);
    }
}

/// A gantry whose one wrist joint turns about the flange's x: the free component is tx.
#[test]
fn gantry_with_a_wrist_about_x_needs_tx() {
    for setup in SETUPS {
        for seed in 0..5 {
            let config = LowDofConfig {
                axis: [1.0, 0.0, 0.0],
                ..scara(setup)
            };
            let s = simulate_low_dof(&config, seed, 0);
            let e = calibrate(&s.poses, setup, &options(vec![]))
                .map(|r| r.into_hand_eye().expect("the hand–eye report"))
                .unwrap_err();
            assert_eq!(
                low_dof_reason(&e).map(|r| r.0),
                Some(LowDofMissing::Prior(Component::Tx)),
                "{e}"
            );
            assert!(e.to_string().contains("--prior tx="));
            let tx = s.x.translation.vector.x;
            let r = calibrate(
                &s.poses,
                setup,
                &options(vec![prior(Component::Tx, tx, 0.0)]),
            )
            .map(|r| r.into_hand_eye().expect("the hand–eye report"))
            .unwrap_or_else(|e| panic!("{setup} {seed}: {e}"));
            assert_eq!(r.transform.translation.vector.x, tx);
            let (er, et) = errors(&r.transform, &s.x);
            assert!(er < 5.0 * r.uncertainty.rotation_deg && et < 5.0 * r.uncertainty.translation);
        }
    }
}

/// A wrist whose axis is 30° off the flange's z: the free direction is along no coordinate
/// axis, so no prior can state it; refused, naming the direction.
#[test]
fn a_free_direction_off_the_axes_is_refused_naming_it() {
    let tilted = [0.0, -(30f64.to_radians().sin()), 30f64.to_radians().cos()];
    for setup in SETUPS {
        for seed in 0..5 {
            let config = LowDofConfig {
                axis: tilted,
                ..scara(setup)
            };
            let s = simulate_low_dof(&config, seed, 0);
            for priors in [
                vec![],
                vec![prior(Component::Tz, s.x.translation.vector.z, 0.0)],
            ] {
                let e = calibrate(&s.poses, setup, &options(priors))
                    .map(|r| r.into_hand_eye().expect("the hand–eye report"))
                    .unwrap_err();
                let (missing, axis) = low_dof_reason(&e).unwrap_or_else(|| panic!("{e}"));
                assert_eq!(missing, LowDofMissing::NotStatable);
                let off = Vector3::from(axis).dot(&Vector3::from(tilted)).abs();
                assert!(off > 0.9999, "{axis:?}");
                let words = e.to_string();
                assert!(words.contains("no prior on tx, ty or tz"), "{words}");
                assert!(
                    words.contains("(0.000, -0.500, 0.866)") && words.contains("one axis"),
                    "{words}"
                );
            }
        }
    }
}

#[test]
fn a_prior_in_another_unit_is_refused_naming_the_unit() {
    for setup in SETUPS {
        let s = simulate_low_dof(&scara(setup), 3, 0);
        let tz = s.x.translation.vector[2];
        // Millimetres on a recording in metres: refused for its size, not blamed on the motions.
        let e = calibrate(
            &s.poses,
            setup,
            &options(vec![prior(Component::Tz, tz * 1e3, 1.0)]),
        )
        .map(|r| r.into_hand_eye().expect("the hand–eye report"))
        .unwrap_err();
        assert!(
            matches!(e, Error::InvalidParameter { name: "prior", .. }),
            "{setup}: {e}"
        );
        assert!(e.to_string().contains("another length unit"), "{e}");
        // The true value in the poses' unit is answered.
        calibrate(
            &s.poses,
            setup,
            &options(vec![prior(Component::Tz, tz, 0.001)]),
        )
        .map(|r| r.into_hand_eye().expect("the hand–eye report"))
        .unwrap();
        // Metres on a recording in millimetres: refused too, with the value in millimetres
        // offered (nothing in the data tells: the motions leave tz free, and the answer was
        // "good" with X's height 1000 times too small).
        let mm: Vec<PosePair> = s
            .poses
            .iter()
            .map(|p| {
                let mut p = *p;
                p.base_from_gripper.translation.vector *= 1e3;
                p.camera_from_target.translation.vector *= 1e3;
                p
            })
            .collect();
        let e = calibrate(&mm, setup, &options(vec![prior(Component::Tz, tz, 0.001)]))
            .map(|r| r.into_hand_eye().expect("the hand–eye report"))
            .unwrap_err();
        let words = e.to_string();
        assert!(
            matches!(e, Error::InvalidParameter { name: "prior", .. }),
            "{setup}: {e}"
        );
        assert!(words.contains("another length unit"), "{words}");
        assert!(words.contains(&format!("tz={tz}m+-0.001m")), "{words}");
        // In the poses' unit, or with its own: the same X, tz the prior's.
        let r = calibrate(
            &mm,
            setup,
            &options(vec![prior(Component::Tz, tz * 1e3, 1.0)]),
        )
        .map(|r| r.into_hand_eye().expect("the hand–eye report"))
        .unwrap();
        assert_eq!(r.transform.translation.vector[2], tz * 1e3);
        let metres: Prior = format!("tz={tz}+-0.001m").parse().unwrap();
        let told = calibrate(&mm, setup, &options(vec![metres]))
            .map(|r| r.into_hand_eye().expect("the hand–eye report"))
            .unwrap();
        let d = told.transform.translation.vector - r.transform.translation.vector;
        assert!(d.norm() < 1e-9 * 1e3, "{d}");
        // Millimetres named on a recording in metres: converted.
        let named: Prior = format!("tz={}mm", tz * 1e3).parse().unwrap();
        let r = calibrate(&s.poses, setup, &options(vec![named]))
            .map(|r| r.into_hand_eye().expect("the hand–eye report"))
            .unwrap();
        assert!((r.transform.translation.vector[2] - tz).abs() < 1e-12);
        // A camera at the flange's height: 0 is a value in any unit.
        calibrate(&mm, setup, &options(vec![prior(Component::Tz, 0.0, 1.0)]))
            .map(|r| r.into_hand_eye().expect("the hand–eye report"))
            .unwrap();
    }
}

#[test]
fn a_weak_direction_of_a_low_dof_x_advises_what_the_robot_can_record() {
    // Four poses of a SCARA: X is weakly determined, and the advice must not ask for turns about
    // another axis, which such a robot cannot make.
    let mut weak = 0;
    for seed in 0..SEEDS {
        let s = simulate_low_dof(&scara(Setup::EyeInHand), seed, 0);
        let few = &s.poses[..4];
        let tz = s.x.translation.vector[2];
        let Ok(r) = calibrate(
            few,
            Setup::EyeInHand,
            &options(vec![prior(Component::Tz, tz, 0.001)]),
        )
        .map(|r| r.into_hand_eye().expect("the hand–eye report")) else {
            continue;
        };
        for w in &r.warnings {
            if let Warning::WeakDirection { one_axis, .. } = w {
                weak += 1;
                assert!(one_axis.is_some(), "{w:?}");
                let words = w.to_string();
                assert!(!words.contains("x or y"), "{words}");
                assert!(words.contains("further across the axis"), "{words}");
            }
        }
    }
    println!("weak directions on 4-pose SCARA recordings: {weak}");
    assert!(
        weak > 0,
        "no 4-pose recording gave a weak direction: the test tests nothing"
    );
}

/// The gripper-frame axis of the motion from the first pose to the first one turned by more
/// than 5° from it.
fn gripper_axis(poses: &[handeye::PosePair]) -> Vector3<f64> {
    poses
        .iter()
        .find_map(|p| {
            let m = poses[0].base_from_gripper.inverse() * p.base_from_gripper;
            let f = handeye::MotionFeatures::of(&m);
            (f.angle > 5f64.to_radians()).then_some(f.axis?)
        })
        .unwrap()
}

#[test]
fn advice_with_the_prior_turns_about_the_robots_axis_with_the_calibrations_sigma() {
    use handeye::{AdviseOptions, Written, advise};
    let (mut ratios, mut rotation_ratios) = (Vec::new(), Vec::new());
    for setup in SETUPS {
        for seed in 0..8 {
            let s = simulate_low_dof(&scara(setup), seed, 0);
            let tz = s.x.translation.vector.z;
            let given = prior(Component::Tz, tz, 0.002);
            let advice = advise(
                &s.poses,
                setup,
                Written::NAMED,
                &AdviseOptions {
                    priors: vec![given],
                    ..AdviseOptions::default()
                },
            )
            .unwrap_or_else(|e| panic!("{setup} {seed}: {e}"));
            let words = advice.low_dof.as_deref().unwrap();
            assert!(words.contains("X's tz is the prior's"), "{words}");
            let current = advice.current.unwrap();
            let r = calibrate(&s.poses, setup, &options(vec![given]))
                .map(|r| r.into_hand_eye().expect("the hand–eye report"))
                .unwrap();
            ratios.push(current.translation / r.uncertainty.translation);
            rotation_ratios.push(current.rotation_deg / r.uncertainty.rotation_deg);
            // Every turn suggested is about the robot's one axis, as the gripper sees it.
            let axis = gripper_axis(&s.poses);
            assert_eq!(advice.suggestions.len(), 3);
            let mut before = current;
            for t in &advice.suggestions {
                let k = Vector3::from(t.axis_gripper);
                assert!(
                    k.dot(&axis).abs() > 0.999,
                    "{setup} {seed}: {k:?} vs {axis:?}"
                );
                let p = t.predicted.unwrap();
                assert!(p.translation <= before.translation * (1.0 + 1e-9));
                before = p;
            }
        }
    }
    ratios.sort_by(f64::total_cmp);
    println!(
        "advise's translation sigma / calibrate's bootstrap, with the prior: {:.2} to {:.2} (median {:.2})",
        ratios[0],
        ratios[ratios.len() - 1],
        ratios[ratios.len() / 2]
    );
    assert!(
        ratios[0] > 1.0 / 3.0 && ratios[ratios.len() - 1] < 3.0,
        "{ratios:?}"
    );
    // The rotation: the advice's first-order sigma against the bootstrap's.
    rotation_ratios.sort_by(f64::total_cmp);
    println!(
        "advise's rotation sigma / calibrate's bootstrap, with the prior: {:.2} to {:.2} (median {:.2})",
        rotation_ratios[0],
        rotation_ratios[rotation_ratios.len() - 1],
        rotation_ratios[rotation_ratios.len() / 2]
    );
}

#[test]
fn advice_on_a_low_dof_recording_refuses_a_prior_in_another_unit_and_leaves_outliers_out() {
    use handeye::{AdviseOptions, Written, advise};
    let s = simulate_low_dof(&scara(Setup::EyeInHand), 3, 0);
    let tz = s.x.translation.vector.z;
    // Millimetres on a recording in metres.
    let e = advise(
        &s.poses,
        Setup::EyeInHand,
        Written::NAMED,
        &AdviseOptions {
            priors: vec![prior(Component::Tz, tz * 1000.0, 0.0)],
            ..AdviseOptions::default()
        },
    )
    .unwrap_err();
    assert!(
        matches!(e, Error::InvalidParameter { name: "prior", .. }),
        "{e}"
    );
    // A camera pose replaced by another one's: left out, and the advice is still the SCARA's.
    let mut poses = s.poses.clone();
    poses[7].camera_from_target = poses[19].camera_from_target;
    let advice = advise(
        &poses,
        Setup::EyeInHand,
        Written::NAMED,
        &AdviseOptions {
            count: 2,
            priors: vec![prior(Component::Tz, tz, 0.0)],
            ..AdviseOptions::default()
        },
    )
    .unwrap();
    assert!(advice.outliers >= 1, "{advice:?}");
    assert!(advice.low_dof.unwrap().contains("the prior's"));
    // Without the prior, the words name it.
    let advice = advise(
        &s.poses,
        Setup::EyeInHand,
        Written::NAMED,
        &AdviseOptions {
            count: 2,
            ..AdviseOptions::default()
        },
    )
    .unwrap();
    assert!(advice.low_dof.unwrap().contains("--prior tz="));
}
