//! The contract of `contract.rs`, for the robot-world methods (Q_i X C_i = Y: [`shah`], [`li`] and
//! [`refine_robot_world`], each called through the one entry [`robot_world`]) and for the
//! accumulating estimators ([`PoseAccumulator`], X from all pairs; [`RobotWorldAccumulator`], X and
//! Y by Shah), over random X, random target poses Y and random robot poses:
//!
//! - exact recovery of X and Y from noise-free poses (≤ 1e-9);
//! - changes of frame: of the robot's base (H_i → G H_i), of the gripper (H_i → H_i G), of the
//!   target (C_i → C_i T) and of the camera (C_i → T C_i), each with the X and Y it implies;
//! - reordering the poses, and the eye-in-hand / eye-to-hand duality (the robot poses inverted),
//!   on noisy poses too;
//! - refusal below the minimum number of poses (3) and of rotations about one axis;
//! - `refine` stops for a reason of convergence on exact data, and lowers the cost on noisy data
//!   from Shah's start and from Li's;
//! - the accumulators equal their batch solvers (all-pairs Andreff, Shah) at every pose.

mod common;

use common::{any_transform, errors, recording, robot_pose, transform};
use handeye::solve::accumulate::PoseAccumulator;
use handeye::solve::robot_world_accumulate::RobotWorldAccumulator;
use handeye::solve::{
    RefineOptions, RobotWorld, RobotWorldMethod, Termination, check_motions, li,
    refine_robot_world, refine_robot_world_from, robot_world, shah,
};
use handeye::{Error, Method, Pairing, PosePair, Setup, Transform, motion_pairs, solve};
use proptest::prelude::*;

/// Bound on the errors of X and Y where they are determined to rounding (Frobenius error of the
/// rotation and translation error, the scenes spanning about 1 unit).
const EXACT: f64 = 1e-9;

/// `refine` stops when a step lowers the cost by less than 1e-15 of it, which fixes the parameters
/// to about √1e-15 ≈ 3e-8 (as in `contract.rs`): two equivalent noisy problems may stop that far
/// apart.
const REFINE_STOP: f64 = 1e-7;

/// One recording: the setup, the true X and Y, and the pose pairs.
#[derive(Debug, Clone)]
struct Case {
    setup: Setup,
    x: Transform,
    y: Transform,
    poses: Vec<PosePair>,
}

impl Case {
    /// The same recording with other poses.
    fn with(&self, poses: Vec<PosePair>) -> Self {
        Self {
            poses,
            ..self.clone()
        }
    }
}

prop_compose! {
    /// A noise-free recording of 4 to 9 generic poses, either setup.
    fn exact_case()(
        x in any_transform(),
        y in any_transform(),
        robot in prop::collection::vec(robot_pose(), 4..10),
        eye_to_hand in any::<bool>(),
    ) -> Case {
        let setup = if eye_to_hand { Setup::EyeToHand } else { Setup::EyeInHand };
        Case { setup, x, y, poses: recording(setup, &x, &y, &robot) }
    }
}

prop_compose! {
    /// The same with every robot and camera pose moved by up to about 1° and 5 mm (for 1 m).
    fn noisy_case()(case in exact_case())(
        noise in prop::collection::vec(
            (prop::array::uniform3(-1e-2f64..1e-2), prop::array::uniform3(-5e-3f64..5e-3)),
            2 * case.poses.len(),
        ),
        case in Just(case),
    ) -> Case {
        let poses = case.poses.iter().zip(noise.chunks(2)).map(|(p, n)| PosePair {
            base_from_gripper: p.base_from_gripper * transform(n[0].0, n[0].1),
            camera_from_target: p.camera_from_target * transform(n[1].0, n[1].1),
        }).collect();
        case.with(poses)
    }
}

/// Whether the poses determine X and Y well: the consecutive motions (which the robot-world
/// methods check) and all pairs (which the accumulator solves) are well conditioned, and the
/// gripper's positions spread (Li's simultaneous form fixes the scale of its rotations by the
/// translations: with every gripper position alike it trades that scale against t_Y, and its
/// translations follow the rounding).
fn well_posed(poses: &[PosePair], setup: Setup) -> bool {
    let rotations_determined = [Pairing::Consecutive, Pairing::All].iter().all(|&pairing| {
        check_motions(&motion_pairs(poses, pairing, setup)).is_ok_and(|c| c.conditioning > 0.05)
    });
    let at: Vec<_> = poses
        .iter()
        .map(|p| p.base_from_gripper.translation.vector)
        .collect();
    let mean = at.iter().sum::<nalgebra::Vector3<f64>>() / at.len() as f64;
    let spread = at
        .iter()
        .map(|t| (t - mean).norm())
        .fold(f64::INFINITY, f64::min);
    rotations_determined && spread > 0.05
}

/// The method's X and Y, or the test's failure naming the method.
fn solved(
    method: RobotWorldMethod,
    poses: &[PosePair],
    setup: Setup,
) -> Result<RobotWorld, TestCaseError> {
    robot_world(method, poses, setup).map_err(|e| TestCaseError::fail(format!("{method}: {e}")))
}

/// Fails unless `got` is `want` within `tol`.
fn close(got: &Transform, want: &Transform, tol: f64, what: &str) -> Result<(), TestCaseError> {
    let (er, et) = errors(got, want);
    prop_assert!(
        er <= tol && et <= tol,
        "{what}: rotation {er:e}, translation {et:e} (bound {tol:e})"
    );
    Ok(())
}

/// Fails unless both X and Y are the wanted ones within `tol`.
fn close_both(
    got: &RobotWorld,
    want: (&Transform, &Transform),
    tol: f64,
    what: &str,
) -> Result<(), TestCaseError> {
    close(&got.x, want.0, tol, &format!("{what}: X"))?;
    close(&got.target, want.1, tol, &format!("{what}: Y"))
}

/// The other setup.
fn other(setup: Setup) -> Setup {
    match setup {
        Setup::EyeInHand => Setup::EyeToHand,
        Setup::EyeToHand => Setup::EyeInHand,
    }
}

/// A change of frame whose effect on X and Y is known.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Change {
    /// H_i → G H_i: another base frame (G = `new_base_from_base`).
    Base(Transform),
    /// H_i → H_i G: another gripper frame (G = `gripper_from_new_gripper`).
    Gripper(Transform),
    /// C_i → C_i T: another target frame (T = `target_from_new_target`).
    Target(Transform),
    /// C_i → T C_i: another camera frame (T = `new_camera_from_camera`).
    Camera(Transform),
}

impl Change {
    fn poses(self, case: &Case) -> Vec<PosePair> {
        case.poses
            .iter()
            .map(|p| match self {
                Self::Base(g) => PosePair {
                    base_from_gripper: g * p.base_from_gripper,
                    ..*p
                },
                Self::Gripper(g) => PosePair {
                    base_from_gripper: p.base_from_gripper * g,
                    ..*p
                },
                Self::Target(t) => PosePair {
                    camera_from_target: p.camera_from_target * t,
                    ..*p
                },
                Self::Camera(t) => PosePair {
                    camera_from_target: t * p.camera_from_target,
                    ..*p
                },
            })
            .collect()
    }

    /// X and Y of the changed data, from Q_i X C_i = Y with Q_i = H_i eye-in-hand, H_i⁻¹
    /// eye-to-hand: the base frame is Y's reference eye-in-hand and X's eye-to-hand, the gripper
    /// frame the other way round; the target frame is Y's child, the camera frame X's.
    fn x_y(self, setup: Setup, x: &Transform, y: &Transform) -> (Transform, Transform) {
        match (self, setup) {
            (Self::Base(g), Setup::EyeInHand) => (*x, g * y),
            (Self::Base(g), Setup::EyeToHand) => (g * x, *y),
            (Self::Gripper(g), Setup::EyeInHand) => (g.inverse() * x, *y),
            (Self::Gripper(g), Setup::EyeToHand) => (*x, g.inverse() * y),
            (Self::Target(t), _) => (*x, y * t),
            (Self::Camera(t), _) => (x * t.inverse(), *y),
        }
    }

    fn name(self) -> &'static str {
        match self {
            Self::Base(_) => "base frame",
            Self::Gripper(_) => "gripper frame",
            Self::Target(_) => "target frame",
            Self::Camera(_) => "camera frame",
        }
    }
}

/// On exact data every method and both accumulators give the changed X and Y.
fn check_change(case: &Case, change: Change) -> Result<(), TestCaseError> {
    let changed = change.poses(case);
    prop_assume!(well_posed(&case.poses, case.setup) && well_posed(&changed, case.setup));
    let (x, y) = change.x_y(case.setup, &case.x, &case.y);
    let what = |who: &str| format!("{who} {} ({})", change.name(), case.setup);
    for method in RobotWorldMethod::ALL {
        let got = solved(method, &changed, case.setup)?;
        close_both(&got, (&x, &y), EXACT, &what(method.name()))?;
    }
    let acc = PoseAccumulator::of(&changed, case.setup).estimate();
    let acc = acc.ok_or_else(|| TestCaseError::fail(what("accumulator: no estimate")))?;
    close(&acc.x, &x, EXACT, &what("accumulator"))?;
    let rw = robot_world_accumulated(&changed, case.setup)?;
    close_both(&rw, (&x, &y), EXACT, &what("robot-world accumulator"))
}

/// The robot-world accumulator's estimate over `poses`.
fn robot_world_accumulated(poses: &[PosePair], setup: Setup) -> Result<RobotWorld, TestCaseError> {
    let mut acc = RobotWorldAccumulator::new(setup);
    poses.iter().for_each(|p| acc.add(p));
    prop_assert_eq!(acc.poses(), poses.len());
    acc.estimate()
        .ok_or_else(|| TestCaseError::fail("robot-world accumulator: no estimate"))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn every_method_and_accumulator_recovers_x_and_y_from_exact_poses(case in exact_case()) {
        prop_assume!(well_posed(&case.poses, case.setup));
        for method in RobotWorldMethod::ALL {
            let got = solved(method, &case.poses, case.setup)?;
            close_both(&got, (&case.x, &case.y), EXACT, &format!("{method} ({})", case.setup))?;
            prop_assert_eq!(got.method, method);
            prop_assert_eq!(got.poses, case.poses.len());
        }
        let acc = PoseAccumulator::of(&case.poses, case.setup).estimate().unwrap();
        close(&acc.x, &case.x, EXACT, "accumulator")?;
        prop_assert_eq!(acc.poses, case.poses.len());
        let rw = robot_world_accumulated(&case.poses, case.setup)?;
        close_both(&rw, (&case.x, &case.y), EXACT, "robot-world accumulator")?;
    }

    #[test]
    fn a_change_of_base_frame(case in exact_case(), g in any_transform()) {
        check_change(&case, Change::Base(g))?;
    }

    #[test]
    fn a_change_of_gripper_frame(case in exact_case(), g in any_transform()) {
        check_change(&case, Change::Gripper(g))?;
    }

    #[test]
    fn a_change_of_target_frame(case in exact_case(), t in any_transform()) {
        check_change(&case, Change::Target(t))?;
    }

    #[test]
    fn a_change_of_camera_frame(case in exact_case(), t in any_transform()) {
        check_change(&case, Change::Camera(t))?;
    }

    /// The poses in reverse order: the same sums (Shah, Li, the robot-world accumulator) and the
    /// same cost (refine), so the same X and Y, noisy or not.
    #[test]
    fn reordered_poses(case in exact_case(), noisy in noisy_case()) {
        for (case, exact) in [(case, true), (noisy, false)] {
            let reversed: Vec<PosePair> = case.poses.iter().rev().copied().collect();
            prop_assume!(well_posed(&case.poses, case.setup) && well_posed(&reversed, case.setup));
            for method in RobotWorldMethod::ALL {
                let own = solved(method, &case.poses, case.setup)?;
                let want = if exact { (case.x, case.y) } else { (own.x, own.target) };
                let tol = if method == RobotWorldMethod::Refine && !exact { REFINE_STOP } else { EXACT };
                let got = solved(method, &reversed, case.setup)?;
                close_both(&got, (&want.0, &want.1), tol, &format!("{method} reordered ({})", case.setup))?;
            }
            // Reordering reverses some of the all-pairs motions, which keeps Andreff's rotation
            // system (2I − K − Kᵀ) but not its translation rows: on noisy poses only the
            // accumulator's rotation is the same.
            let forward = PoseAccumulator::of(&case.poses, case.setup).estimate().unwrap();
            let backward = PoseAccumulator::of(&reversed, case.setup).estimate().unwrap();
            let want = if exact { case.x } else { forward.x };
            let (er, et) = errors(&backward.x, &want);
            prop_assert!(er <= EXACT && (et <= EXACT || !exact), "accumulator reordered: {er:e} {et:e}");
        }
    }

    /// Either setup's poses, the robot poses inverted, solved as the other setup: the same
    /// Q_i, so the same X and Y from every method and accumulator, noisy or not.
    #[test]
    fn the_eye_in_hand_eye_to_hand_duality(case in exact_case(), noisy in noisy_case()) {
        for (case, exact) in [(case, true), (noisy, false)] {
            prop_assume!(well_posed(&case.poses, case.setup));
            let inverted: Vec<PosePair> = case.poses.iter().map(|p| PosePair {
                base_from_gripper: p.base_from_gripper.inverse(),
                ..*p
            }).collect();
            let dual = other(case.setup);
            for method in RobotWorldMethod::ALL {
                let own = solved(method, &case.poses, case.setup)?;
                let want = if exact { (case.x, case.y) } else { (own.x, own.target) };
                let tol = if method == RobotWorldMethod::Refine && !exact { REFINE_STOP } else { EXACT };
                let got = solved(method, &inverted, dual)?;
                close_both(&got, (&want.0, &want.1), tol, &format!("{method} {} as {dual}", case.setup))?;
            }
            let own = PoseAccumulator::of(&case.poses, case.setup).estimate().unwrap();
            let got = PoseAccumulator::of(&inverted, dual).estimate().unwrap();
            close(&got.x, &own.x, EXACT, "accumulator duality")?;
        }
    }

    /// On exact data refine starts at Shah's exact X and Y and stops for a reason of
    /// convergence, not at its iteration limit, with both still exact and the cost not raised.
    #[test]
    fn refine_converges_on_exact_poses(case in exact_case()) {
        prop_assume!(well_posed(&case.poses, case.setup));
        let r = refine_robot_world(&case.poses, case.setup).map_err(|e| TestCaseError::fail(e.to_string()))?;
        prop_assert!(
            matches!(
                r.termination,
                Termination::GradientSmall | Termination::StepSmall | Termination::CostConverged
            ),
            "{:?} after {} iterations",
            r.termination,
            r.iterations
        );
        prop_assert!(r.final_cost <= r.initial_cost);
        close_both(&r.solution, (&case.x, &case.y), EXACT, "refine")?;
    }

    /// On noisy poses refine lowers the cost, from Shah's start and from Li's, and fits the poses
    /// at least as well as its start (the weighted cost at the start is the start's own).
    #[test]
    fn refine_lowers_the_cost_from_shah_and_from_li(case in noisy_case()) {
        prop_assume!(well_posed(&case.poses, case.setup));
        for start in [shah(&case.poses, case.setup), li(&case.poses, case.setup)] {
            let start = start.map_err(|e| TestCaseError::fail(e.to_string()))?;
            let r = refine_robot_world_from(&case.poses, case.setup, start, &RefineOptions::default());
            prop_assert!(r.final_cost < r.initial_cost, "{:e} not below {:e}", r.final_cost, r.initial_cost);
            prop_assert!(r.iterations >= 1 && r.covariance.is_some());
        }
    }

    /// The accumulators are their batch solvers, pose by pose: all-pairs Andreff and Shah.
    #[test]
    fn the_accumulators_equal_their_batch_solvers(case in noisy_case()) {
        let mut acc = PoseAccumulator::new(case.setup);
        let mut rw = RobotWorldAccumulator::new(case.setup);
        for (k, p) in case.poses.iter().enumerate() {
            acc.add(p);
            rw.add(p);
            let so_far = &case.poses[..=k];
            if k < 2 {
                prop_assert!(acc.estimate().is_none() && rw.estimate().is_none(), "{} pose(s)", k + 1);
                continue;
            }
            if !well_posed(so_far, case.setup) {
                continue;
            }
            let batch = solve(Method::Andreff, &motion_pairs(so_far, Pairing::All, case.setup))
                .map_err(|e| TestCaseError::fail(e.to_string()))?;
            close(&acc.estimate().unwrap().x, &batch.x, EXACT, &format!("accumulator at {} poses", k + 1))?;
            let batch = shah(so_far, case.setup).map_err(|e| TestCaseError::fail(e.to_string()))?;
            let ours = rw.estimate().unwrap();
            close_both(&ours, (&batch.x, &batch.target), EXACT, &format!("robot-world accumulator at {} poses", k + 1))?;
        }
        acc.reset();
        rw.reset();
        prop_assert!(acc.estimate().is_none() && rw.estimate().is_none(), "after reset");
        prop_assert_eq!((acc.poses(), rw.poses()), (0, 0));
    }
}

/// Three generic poses, one of each setup's X and Y.
fn three_poses(setup: Setup) -> (Transform, Transform, Vec<PosePair>) {
    let x = transform([0.3, -0.5, 0.9], [0.05, -0.02, 0.11]);
    let y = transform([-1.2, 0.4, 0.2], [0.6, 0.3, -0.1]);
    let robot = [
        transform([0.0, 0.0, 0.0], [0.4, 0.0, 0.3]),
        transform([0.6, 0.1, -0.2], [0.3, 0.2, 0.4]),
        transform([-0.1, 0.7, 0.3], [0.5, -0.1, 0.35]),
    ];
    (x, y, recording(setup, &x, &y, &robot))
}

/// Three poses (two independent motions) are the minimum: every method solves them exactly, and
/// two are refused as too few, by every method and by both accumulators (no estimate).
#[test]
fn three_poses_are_the_minimum() {
    for setup in [Setup::EyeInHand, Setup::EyeToHand] {
        let (x, y, poses) = three_poses(setup);
        for method in RobotWorldMethod::ALL {
            let rw = robot_world(method, &poses, setup).unwrap();
            let (er, et) = errors(&rw.x, &x);
            assert!(er <= EXACT && et <= EXACT, "{method} X: {er:e} {et:e}");
            let (er, et) = errors(&rw.target, &y);
            assert!(er <= EXACT && et <= EXACT, "{method} Y: {er:e} {et:e}");
            for n in 0..3 {
                match robot_world(method, &poses[..n], setup) {
                    Err(Error::TooFewMotions { got, need }) => {
                        assert_eq!((got, need), (n.saturating_sub(1), 2), "{method}, {n} poses")
                    }
                    other => panic!("{method}, {n} poses: {other:?}"),
                }
            }
        }
        assert!(PoseAccumulator::of(&poses, setup).estimate().is_some());
        assert!(PoseAccumulator::of(&poses[..2], setup).estimate().is_none());
        let mut rw = RobotWorldAccumulator::new(setup);
        rw.add(&poses[0]);
        rw.add(&poses[1]);
        assert!(rw.estimate().is_none(), "two poses");
        rw.add(&poses[2]);
        let got = rw.estimate().expect("three generic poses");
        assert!(errors(&got.x, &x).0 <= EXACT && errors(&got.x, &x).1 <= EXACT);
    }
}

/// Robot rotations all about one axis leave X's rotation about it undetermined: every method
/// refuses as degenerate, and both accumulators give no estimate.
#[test]
fn rotations_about_one_axis_are_refused() {
    for setup in [Setup::EyeInHand, Setup::EyeToHand] {
        let x = transform([0.3, -0.5, 0.9], [0.05, -0.02, 0.11]);
        let y = transform([-1.2, 0.4, 0.2], [0.6, 0.3, -0.1]);
        let robot: Vec<Transform> = (0..8)
            .map(|i| {
                let f = i as f64;
                transform([0.0, 0.0, 0.3 * f], [0.4 + 0.05 * f, 0.1 * f.sin(), 0.3])
            })
            .collect();
        let poses = recording(setup, &x, &y, &robot);
        for method in RobotWorldMethod::ALL {
            let got = robot_world(method, &poses, setup);
            assert!(
                matches!(got, Err(Error::Degenerate { .. })),
                "{method} ({setup}): {got:?}"
            );
        }
        assert!(PoseAccumulator::of(&poses, setup).estimate().is_none());
        let mut rw = RobotWorldAccumulator::new(setup);
        poses.iter().for_each(|p| rw.add(p));
        assert!(rw.estimate().is_none(), "robot-world accumulator ({setup})");
    }
}
