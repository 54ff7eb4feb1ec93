//! Every solver on noise-free data over random poses (proptest): X recovered to 1e-9, both setups,
//! both pairings (and Tsai with OpenCV's motion filter too); and degenerate data refused with the
//! reason by every solver.

mod common;

use common::{any_transform, errors, recording, robot_pose, transform};
use handeye::model::pose::{exp_so3, transform_from_parts};
use handeye::solve::{Calibration, TsaiOptions, tsai_with};
use handeye::{Degeneracy, Error, Method, MotionPair, Pairing, Setup, motion_pairs, solve};
use nalgebra::Vector3;
use proptest::prelude::*;

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, failure_persistence: None, ..ProptestConfig::default() })]
    #[test]
    fn every_solver_recovers_x_from_noise_free_data(
        x in any_transform(),
        fixed in any_transform(),
        robot in prop::collection::vec(robot_pose(), 3..8),
        eye_to_hand in any::<bool>(),
        all_pairs in any::<bool>(),
    ) {
        let setup = if eye_to_hand { Setup::EyeToHand } else { Setup::EyeInHand };
        let pairing = if all_pairs { Pairing::All } else { Pairing::Consecutive };
        let motions = motion_pairs(&recording(setup, &x, &fixed, &robot), pairing, setup);
        // Random poses can make two consecutive motions nearly parallel; skip what the solvers
        // rightly refuse or flag.
        let check = handeye::solve::check_motions(&motions);
        prop_assume!(check.as_ref().is_ok_and(|c| c.conditioning > 0.05));
        for method in Method::ALL {
            let got = solve(method, &motions).map_err(|e| TestCaseError::fail(format!("{method}: {e}")))?;
            let (er, et) = errors(&got.x, &x);
            prop_assert!(er <= 1e-9 && et <= 1e-9, "{} {method}: rotation {er:e}, translation {et:e}", setup.name());
        }
        // OpenCV's filter may leave too few motions, or nearly parallel ones; what it keeps must
        // still give X.
        match tsai_with(&motions, &OPENCV_FILTER) {
            Ok(got) if got.conditioning > 0.05 => {
                let (er, et) = errors(&got.x, &x);
                prop_assert!(er <= 1e-9 && et <= 1e-9, "{} tsai (filtered): rotation {er:e}, translation {et:e}", setup.name());
            }
            Ok(_) | Err(Error::TooFewMotions { .. }) | Err(Error::Degenerate { .. }) => {}
            Err(e) => return Err(TestCaseError::fail(format!("tsai (filtered): {e}"))),
        }
    }
}

/// Tsai with OpenCV 4.14's motion filter.
const OPENCV_FILTER: TsaiOptions = TsaiOptions {
    opencv_filter: true,
};

/// Every method, and Tsai with OpenCV's filter, on the same motions.
fn every_solver(motions: &[MotionPair]) -> Vec<(String, handeye::Result<Calibration>)> {
    let mut out: Vec<_> = Method::ALL
        .into_iter()
        .map(|m| (m.name().to_owned(), solve(m, motions)))
        .collect();
    out.push((
        "tsai (filtered)".to_owned(),
        tsai_with(motions, &OPENCV_FILTER),
    ));
    out
}

fn about_axis(axis: Vector3<f64>, angles: &[f64]) -> Vec<MotionPair> {
    let x = transform([0.3, -0.2, 0.5], [0.1, 0.2, 0.3]);
    angles
        .iter()
        .enumerate()
        .map(|(k, a)| {
            let a = transform_from_parts(
                &exp_so3(&(axis.normalize() * *a)),
                &Vector3::new(k as f64, 0.5, 0.2),
            );
            MotionPair {
                a,
                b: x.inverse() * a * x,
            }
        })
        .collect()
}

#[test]
fn degenerate_data_is_refused_with_the_reason() {
    let one = about_axis(Vector3::x(), &[0.5]);
    for (name, got) in every_solver(&one) {
        assert!(
            matches!(got, Err(Error::TooFewMotions { got: 1, need: 2 })),
            "{name}: {got:?}"
        );
    }
    let parallel = about_axis(Vector3::new(1.0, 2.0, 3.0), &[0.3, 0.7, -0.4]);
    for (name, got) in every_solver(&parallel) {
        assert!(
            matches!(
                got,
                Err(Error::Degenerate {
                    reason: Degeneracy::ParallelAxes { .. },
                    ..
                })
            ),
            "{name}: {got:?}"
        );
    }
    let still = about_axis(Vector3::x(), &[0.0, 0.0, 0.0]);
    for (name, got) in every_solver(&still) {
        assert!(
            matches!(
                got,
                Err(Error::Degenerate {
                    reason: Degeneracy::SmallRotations { .. },
                    ..
                })
            ),
            "{name}: {got:?}"
        );
    }
    let e = solve(Method::Andreff, &about_axis(Vector3::z(), &[0.3, 0.7]))
        .unwrap_err()
        .to_string();
    assert!(e.contains("parallel") && e.contains("rotate about"), "{e}");
}

#[test]
fn weak_data_succeeds_with_warnings() {
    // Axes 0.2° apart: solvable, but flagged.
    let x = transform([0.3, -0.2, 0.5], [0.1, 0.2, 0.3]);
    let motions: Vec<MotionPair> = [Vector3::new(1.0, 0.0, 0.0), Vector3::new(1.0, 0.0035, 0.0)]
        .iter()
        .map(|axis| {
            let a = transform_from_parts(
                &exp_so3(&(axis.normalize() * 0.5)),
                &Vector3::new(0.3, 0.5, 0.2),
            );
            MotionPair {
                a,
                b: x.inverse() * a * x,
            }
        })
        .collect();
    let c = solve(Method::Andreff, &motions).unwrap();
    assert!(
        c.warnings
            .iter()
            .any(|w| matches!(w, handeye::Warning::WeakConditioning { .. })),
        "{:?}",
        c
    );
}

#[test]
fn opencv_filter_can_leave_too_few_motions() {
    // Rotations of 0.1 rad (2·sin(θ/2) ≈ 0.1 < 0.3) about three axes: enough for every method,
    // but OpenCV's Tsai filter drops them all (where OpenCV logs an error and returns the identity).
    let x = transform([0.3, -0.2, 0.5], [0.1, 0.2, 0.3]);
    let motions: Vec<MotionPair> = [Vector3::x(), Vector3::y(), Vector3::z()]
        .iter()
        .map(|axis| {
            let a = transform_from_parts(&exp_so3(&(axis * 0.1)), &Vector3::new(0.3, 0.5, 0.2));
            MotionPair {
                a,
                b: x.inverse() * a * x,
            }
        })
        .collect();
    for (name, got) in every_solver(&motions) {
        if name == "tsai (filtered)" {
            assert!(
                matches!(got, Err(Error::TooFewMotions { got: 0, need: 2 })),
                "{name}: {got:?}"
            );
        } else {
            let (er, et) = errors(&got.expect("solvable").x, &x);
            assert!(er <= 1e-9 && et <= 1e-9, "{name}: {er:e}, {et:e}");
        }
    }
}
