//! Issue 12, "never a silent wrong answer": every solver on noise-free data with motions of 180°
//! and near it (the quaternion and logarithm signs are arbitrary there), and with every length
//! scaled by 1e-8..1e8 (solvers that mix lengths with pure numbers), X recovered to 1e-9: rotation
//! as ‖R̂ − R‖_F, translation as ‖t̂ − t‖ / ‖t‖.

use std::f64::consts::PI;

use handeye::model::pose::{exp_so3, transform_from_parts};
use handeye::solve::check_motions;
use handeye::{
    Degeneracy, Error, Method, MotionPair, Pairing, PosePair, Setup, Transform, motion_pairs, solve,
};
use nalgebra::{Matrix3, Vector3};
use proptest::prelude::*;

/// The bound of issue 12 on noise-free data.
const BOUND: f64 = 1e-9;

fn unit(v: [f64; 3]) -> Vector3<f64> {
    let v = Vector3::from(v);
    if v.norm() < 1e-3 {
        Vector3::x()
    } else {
        v.normalize()
    }
}

/// A rotation of exactly 180° about `k` built as 2kkᵀ − I (no trigonometry: the skew part is 0
/// and the quaternion's scalar part comes out as exactly 0 or ±rounding).
fn half_turn(k: &Vector3<f64>) -> Matrix3<f64> {
    let k = k.normalize();
    k * k.transpose() * 2.0 - Matrix3::identity()
}

/// How the large motion is made.
#[derive(Debug, Clone, Copy)]
enum Large {
    /// 2kkᵀ − I about the axis.
    Exact,
    /// 2kkᵀ − I about the axis plus `noise` (a tiny tilt, still exactly 180°).
    Tilted([f64; 3]),
    /// exp_so3 of (π − δ) k.
    Near(f64),
}

fn large_rotation(kind: Large, axis: &Vector3<f64>) -> Matrix3<f64> {
    match kind {
        Large::Exact => half_turn(axis),
        Large::Tilted(noise) => half_turn(&(axis + Vector3::from(noise) * 1e-9)),
        Large::Near(delta) => exp_so3(&(axis * (PI - delta))),
    }
}

fn any_large() -> impl Strategy<Value = Large> {
    prop_oneof![
        Just(Large::Exact),
        prop::array::uniform3(-1.0f64..1.0).prop_map(Large::Tilted),
        Just(Large::Near(0.0)),
        // 179.99°, 179.999999° and everything between 180° − 1e-15 rad and 180° − 0.06°.
        Just(Large::Near(0.01_f64.to_radians())),
        Just(Large::Near(1e-6_f64.to_radians())),
        (-15.0f64..-3.0).prop_map(|e| Large::Near(10f64.powf(e))),
    ]
}

/// Noise-free recording for the setup, every length multiplied by `scale`.
fn recording(
    setup: Setup,
    x: &Transform,
    fixed: &Transform,
    robot: &[Transform],
    scale: f64,
) -> Vec<PosePair> {
    let scaled =
        |t: &Transform| transform_from_parts(t.rotation.matrix(), &(t.translation.vector * scale));
    let (x, fixed) = (scaled(x), scaled(fixed));
    robot
        .iter()
        .map(|q| {
            let q = scaled(q);
            let camera_from_target = match setup {
                Setup::EyeInHand => (q * x).inverse() * fixed,
                Setup::EyeToHand => x.inverse() * q * fixed,
            };
            PosePair {
                base_from_gripper: q,
                camera_from_target,
            }
        })
        .collect()
}

/// Rotation error ‖R̂ − R‖_F and relative translation error of `got` against `truth` scaled by
/// `scale`.
fn errors(got: &Transform, truth: &Transform, scale: f64) -> (f64, f64) {
    let r = (got.rotation.matrix() - truth.rotation.matrix()).norm();
    let t = truth.translation.vector * scale;
    (r, (got.translation.vector - t).norm() / t.norm())
}

prop_compose! {
    /// X: a rotation of up to about 150° (Tsai's Eq. (14) parameter tan(θ/2) k is infinite at
    /// 180°, a limit of the method, not of the motions), a translation of length 0.2–1.
    fn any_x()(r in prop::array::uniform3(-1.5f64..1.5), d in prop::array::uniform3(-1.0f64..1.0), len in 0.2f64..1.0) -> Transform {
        transform_from_parts(&exp_so3(&Vector3::from(r)), &(unit(d) * len))
    }
}

prop_compose! {
    fn any_transform()(r in prop::array::uniform3(-1.7f64..1.7), t in prop::array::uniform3(-1.0f64..1.0)) -> Transform {
        transform_from_parts(&exp_so3(&Vector3::from(r)), &Vector3::from(t))
    }
}

prop_compose! {
    /// An ordinary motion step of the robot: 10°–80° about a random axis.
    fn ordinary_step()(axis in prop::array::uniform3(-1.0f64..1.0), angle in 0.2f64..1.4, t in prop::array::uniform3(-1.0f64..1.0)) -> Transform {
        transform_from_parts(&exp_so3(&(unit(axis) * angle)), &Vector3::from(t))
    }
}

prop_compose! {
    /// Robot poses: a start, ordinary steps, and one step of 180° or near it at a random place.
    fn robot_with_half_turn()(
        start in any_transform(),
        steps in prop::collection::vec(ordinary_step(), 2..6),
        at in 0usize..6,
        large in any_large(),
        axis in prop::array::uniform3(-1.0f64..1.0),
        t in prop::array::uniform3(-1.0f64..1.0),
    ) -> Vec<Transform> {
        let big = transform_from_parts(&large_rotation(large, &unit(axis)), &Vector3::from(t));
        let mut steps = steps;
        let at = at.min(steps.len());
        steps.insert(at, big);
        let mut poses = vec![start];
        for s in steps {
            let last = *poses.last().expect("start");
            poses.push(last * s);
        }
        poses
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, failure_persistence: None, ..ProptestConfig::default() })]

    /// Random motion sets with one motion of 180° or near it, lengths at any scale 1e-8..1e8,
    /// both setups and pairings: every method recovers X to 1e-9.
    #[test]
    fn every_solver_recovers_x_with_a_half_turn_at_any_scale(
        x in any_x(),
        fixed in any_transform(),
        robot in robot_with_half_turn(),
        exponent in -8.0f64..8.0,
        eye_to_hand in any::<bool>(),
        all_pairs in any::<bool>(),
    ) {
        let scale = 10f64.powf(exponent);
        let setup = if eye_to_hand { Setup::EyeToHand } else { Setup::EyeInHand };
        let pairing = if all_pairs { Pairing::All } else { Pairing::Consecutive };
        let motions = motion_pairs(&recording(setup, &x, &fixed, &robot, scale), pairing, setup);
        // As in `solver_exact`: random steps can make the motions nearly parallel.
        let check = check_motions(&motions);
        prop_assume!(check.as_ref().is_ok_and(|c| c.conditioning > 0.05));
        for method in Method::ALL {
            let got = solve(method, &motions)
                .map_err(|e| TestCaseError::fail(format!("{method}: {e}")))?;
            let (er, et) = errors(&got.x, &x, scale);
            prop_assert!(
                er <= BOUND && et <= BOUND,
                "{} {method} scale {scale:e}: rotation {er:e}, translation {et:e}",
                setup.name()
            );
        }
    }

    /// Scaling every length by 2^k changes nothing but X's translation, which scales by 2^k,
    /// bit for bit, for every method whose arithmetic is unit-free or done in units of the data's
    /// own scale. (`andreff-joint` and `daniilidis` solve in the input's unit near it, as OpenCV
    /// does, so their bits change with the unit; their accuracy at every scale is checked above.)
    #[test]
    fn power_of_two_scaling_is_exact(
        x in any_x(),
        fixed in any_transform(),
        robot in robot_with_half_turn(),
        k in -27i32..27,
        eye_to_hand in any::<bool>(),
    ) {
        let setup = if eye_to_hand { Setup::EyeToHand } else { Setup::EyeInHand };
        let scale = 2f64.powi(k);
        let base = motion_pairs(&recording(setup, &x, &fixed, &robot, 1.0), Pairing::Consecutive, setup);
        let scaled = motion_pairs(&recording(setup, &x, &fixed, &robot, scale), Pairing::Consecutive, setup);
        prop_assume!(check_motions(&base).is_ok_and(|c| c.conditioning > 0.05));
        let exact = [Method::Andreff, Method::Tsai, Method::Park, Method::Horaud, Method::Refine];
        for method in exact {
            let a = solve(method, &base).map_err(|e| TestCaseError::fail(format!("{method}: {e}")))?;
            let b = solve(method, &scaled).map_err(|e| TestCaseError::fail(format!("{method}: {e}")))?;
            prop_assert_eq!(a.x.rotation.matrix(), b.x.rotation.matrix(), "{}", method);
            prop_assert_eq!(a.x.translation.vector * scale, b.x.translation.vector, "{}", method);
        }
    }
}

/// A fixed X, a fixed target and a robot path with one large step `large` about `axis` between
/// ordinary ones.
fn path(large: Matrix3<f64>) -> (Transform, Transform, Vec<Transform>) {
    let x = transform_from_parts(
        &exp_so3(&Vector3::new(0.3, -0.2, 0.5)),
        &Vector3::new(0.1, 0.2, 0.3),
    );
    let fixed = transform_from_parts(
        &exp_so3(&Vector3::new(1.0, 0.2, -0.4)),
        &Vector3::new(0.4, -0.2, 0.9),
    );
    let steps = [
        transform_from_parts(
            &exp_so3(&Vector3::new(0.4, 0.3, -0.2)),
            &Vector3::new(0.3, -0.1, 0.2),
        ),
        transform_from_parts(&large, &Vector3::new(-0.2, 0.4, 0.1)),
        transform_from_parts(
            &exp_so3(&Vector3::new(-0.1, 0.5, 0.4)),
            &Vector3::new(0.1, 0.2, -0.3),
        ),
    ];
    let mut robot = vec![transform_from_parts(
        &exp_so3(&Vector3::new(0.2, 0.1, 0.3)),
        &Vector3::new(0.5, 0.5, 0.5),
    )];
    for s in steps {
        let last = *robot.last().expect("start");
        robot.push(last * s);
    }
    (x, fixed, robot)
}

/// The cases of issue 12 one by one, all methods, both setups, both pairings, three scales.
#[test]
fn half_turns_and_near_half_turns() {
    let axis = Vector3::new(0.3, -0.8, 0.5).normalize();
    let cases: [(&str, Matrix3<f64>); 6] = [
        ("180° (2kkᵀ − I)", half_turn(&axis)),
        ("180° about x", half_turn(&Vector3::x())),
        ("180° (exp)", exp_so3(&(axis * PI))),
        ("179.99°", exp_so3(&(axis * 179.99_f64.to_radians()))),
        (
            "179.999999°",
            exp_so3(&(axis * 179.999_999_f64.to_radians())),
        ),
        (
            "180°, axis tilted by 1e-9",
            half_turn(&(axis + Vector3::new(1e-9, -2e-9, 0.5e-9))),
        ),
    ];
    let mut worst = (0.0_f64, 0.0_f64);
    for (name, large) in cases {
        let (x, fixed, robot) = path(large);
        for setup in [Setup::EyeInHand, Setup::EyeToHand] {
            for pairing in [Pairing::Consecutive, Pairing::All] {
                for scale in [1.0, 1e-8, 1e8] {
                    let motions =
                        motion_pairs(&recording(setup, &x, &fixed, &robot, scale), pairing, setup);
                    for method in Method::ALL {
                        let got = solve(method, &motions)
                            .unwrap_or_else(|e| panic!("{name} {} {method}: {e}", setup.name()));
                        let (er, et) = errors(&got.x, &x, scale);
                        assert!(
                            er <= BOUND && et <= BOUND,
                            "{name} {} {pairing:?} scale {scale:e} {method}: rotation {er:e}, translation {et:e}",
                            setup.name()
                        );
                        worst = (worst.0.max(er), worst.1.max(et));
                    }
                }
            }
        }
    }
    // Measured: rotation 3.4e-11, translation 8.2e-11, both from `andreff-joint` and
    // `daniilidis` at scales ×1e±8, solved with their two row blocks 2^10 apart (see the solvers).
    println!(
        "worst: rotation {:.1e}, translation {:.1e}",
        worst.0, worst.1
    );
}

/// `andreff-joint` refuses a gripper that does not translate, and accepts one that does, at every
/// length scale: the decision compares the gripper's translations with the data's own lengths.
#[test]
fn andreff_joint_decides_the_same_at_every_scale() {
    let (x, fixed, robot) = path(exp_so3(&Vector3::new(0.2, 0.9, -0.3)));
    // The same orientations with the gripper always at one place: every A has t_a = 0.
    let still: Vec<Transform> = robot
        .iter()
        .map(|q| transform_from_parts(q.rotation.matrix(), &Vector3::new(0.5, 0.5, 0.5)))
        .collect();
    for scale in [1e-8, 1e-4, 1.0, 1e4, 1e8] {
        for setup in [Setup::EyeInHand, Setup::EyeToHand] {
            let moving = motion_pairs(
                &recording(setup, &x, &fixed, &robot, scale),
                Pairing::Consecutive,
                setup,
            );
            let got = solve(Method::AndreffJoint, &moving).expect("translating gripper");
            let (er, et) = errors(&got.x, &x, scale);
            assert!(er <= BOUND && et <= BOUND, "scale {scale:e}: {er:e} {et:e}");
            let motions = motion_pairs(
                &recording(setup, &x, &fixed, &still, scale),
                Pairing::Consecutive,
                setup,
            );
            let got = solve(Method::AndreffJoint, &motions);
            // Eye-in-hand, A = Q_a⁻¹ Q_b does not translate at all. Eye-to-hand A translates, but
            // every A is a rotation about the one point the gripper stays at, t_a = (I − R_a) c,
            // and (s R_x, s t_x + (1 − s) c) solves Eq. (10) for every s: degenerate too.
            assert!(
                matches!(
                    got,
                    Err(Error::Degenerate {
                        reason: Degeneracy::NoTranslation { .. },
                        ..
                    })
                ),
                "{} scale {scale:e}: {got:?}",
                setup.name()
            );
        }
    }
}

/// Refine's result does not depend on the unit either (its tolerances mix radians and lengths),
/// including the block scales it reports, which are in the input's unit.
#[test]
fn refine_reports_in_the_input_unit() {
    let (x, fixed, robot) = path(exp_so3(&Vector3::new(0.2, 0.9, -0.3)));
    let motions = |scale: f64| -> Vec<MotionPair> {
        motion_pairs(
            &recording(Setup::EyeInHand, &x, &fixed, &robot, scale),
            Pairing::Consecutive,
            Setup::EyeInHand,
        )
    };
    let one = handeye::solve::refine(&motions(1.0)).expect("solvable");
    let k = 2f64.powi(-30);
    let small = handeye::solve::refine(&motions(k)).expect("solvable");
    assert_eq!(one.iterations, small.iterations);
    assert_eq!(one.termination, small.termination);
    assert_eq!(one.scales[0], small.scales[0]);
    assert_eq!(one.scales[1] * k, small.scales[1]);
}
