//! The contract every hand–eye method keeps (sophus / factrs style), each method called through the
//! one entry [`solve`] over random X and random poses:
//!
//! - exact recovery of X from noise-free motions (≤ 1e-9);
//! - changes of frame: of the robot's base (H_k → G H_k), of the target (C_k → C_k T), of the
//!   gripper (H_k → H_k G) and of the camera (C_k → T C_k), each with the X it implies;
//! - reversing every motion (A, B → A⁻¹, B⁻¹) and reordering the motions;
//! - the eye-in-hand / eye-to-hand duality: eye-to-hand poses are eye-in-hand poses of the robot
//!   poses' inverses (`Setup::hand_pose`), so either setup's data solved as the other with the robot
//!   poses inverted gives the same X;
//! - for `refine`, a converged [`Termination`] on exact data (its Jacobian is checked against
//!   central differences where it lives, in `solve/refine.rs`'s unit tests).
//!
//! On noise-free data every method must meet every property. On noisy data a property holds only
//! for the methods whose estimate is equivariant by design; [`equivariant`] lists them, with the
//! reason for each method left out.

mod common;

use common::{any_transform, errors, recording, robot_pose, transform};
use handeye::solve::{Termination, check_motions, refine};
use handeye::{Method, MotionPair, Pairing, PosePair, Setup, Transform, motion_pairs, solve};
use proptest::prelude::*;

/// Bound on X's errors where the result is determined to rounding (both the Frobenius error of
/// the rotation and the translation error, the scenes spanning about 1 unit).
const EXACT: f64 = 1e-9;

/// `refine` stops when a step lowers the cost by less than 1e-15 of it. Near the minimum the cost
/// is quadratic in the parameters, so that rule fixes them to about √1e-15 ≈ 3e-8 (in the
/// weighted problem's units, about 1): two equivalent noisy problems may stop that far apart.
const REFINE_STOP: f64 = 1e-7;

/// One recording: the setup, the pairing, the true X and the pose pairs.
#[derive(Debug, Clone)]
struct Case {
    setup: Setup,
    pairing: Pairing,
    x: Transform,
    poses: Vec<PosePair>,
}

impl Case {
    fn motions(&self) -> Vec<MotionPair> {
        motion_pairs(&self.poses, self.pairing, self.setup)
    }

    /// The same recording with other poses.
    fn with(&self, poses: Vec<PosePair>) -> Self {
        Self {
            poses,
            ..self.clone()
        }
    }
}

prop_compose! {
    /// A noise-free recording of 4 to 7 generic poses, either setup, either pairing.
    fn exact_case()(
        x in any_transform(),
        fixed in any_transform(),
        robot in prop::collection::vec(robot_pose(), 4..8),
        eye_to_hand in any::<bool>(),
        all_pairs in any::<bool>(),
    ) -> Case {
        let setup = if eye_to_hand { Setup::EyeToHand } else { Setup::EyeInHand };
        let pairing = if all_pairs { Pairing::All } else { Pairing::Consecutive };
        Case { setup, pairing, x, poses: recording(setup, &x, &fixed, &robot) }
    }
}

prop_compose! {
    /// The same with every robot and camera pose moved by up to about 1° and 5 mm (for 1 m):
    /// data that no X fits exactly, so that what a method minimises shows.
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

/// Whether the motions determine X well (random poses can make the axes nearly parallel, which
/// the solvers rightly refuse or flag, and which amplifies rounding beyond [`EXACT`]).
fn well_posed(motions: &[MotionPair]) -> bool {
    check_motions(motions).is_ok_and(|c| c.conditioning > 0.05)
}

/// The method's X, or the test's failure naming the method.
fn solved(method: Method, motions: &[MotionPair]) -> Result<Transform, TestCaseError> {
    solve(method, motions)
        .map(|c| c.x)
        .map_err(|e| TestCaseError::fail(format!("{method}: {e}")))
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

/// A change of the data whose effect on X is known.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Change {
    /// H_k → G H_k: another base frame (G = `new_base_from_base`).
    Base(Transform),
    /// C_k → C_k T: another target frame (T = `target_from_new_target`).
    Target(Transform),
    /// H_k → H_k G: another gripper frame (G = `gripper_from_new_gripper`).
    Gripper(Transform),
    /// C_k → T C_k: another camera frame (T = `new_camera_from_camera`).
    Camera(Transform),
    /// Every motion (A, B) → (A⁻¹, B⁻¹).
    Reverse,
    /// The motions in reverse order.
    Reorder,
}

impl Change {
    /// The changed motions of a recording.
    fn motions(self, case: &Case) -> Vec<MotionPair> {
        let poses =
            |f: &dyn Fn(&PosePair) -> PosePair| case.with(case.poses.iter().map(f).collect());
        match self {
            Self::Base(g) => poses(&|p| PosePair {
                base_from_gripper: g * p.base_from_gripper,
                ..*p
            })
            .motions(),
            Self::Target(t) => poses(&|p| PosePair {
                camera_from_target: p.camera_from_target * t,
                ..*p
            })
            .motions(),
            Self::Gripper(g) => poses(&|p| PosePair {
                base_from_gripper: p.base_from_gripper * g,
                ..*p
            })
            .motions(),
            Self::Camera(t) => poses(&|p| PosePair {
                camera_from_target: t * p.camera_from_target,
                ..*p
            })
            .motions(),
            Self::Reverse => case.motions().iter().map(MotionPair::inverse).collect(),
            Self::Reorder => case.motions().into_iter().rev().collect(),
        }
    }

    /// X of the changed data, from X of the data.
    ///
    /// Eye-in-hand A = H_a⁻¹ H_b ignores the base and X = `gripper_from_camera` follows the
    /// gripper; eye-to-hand A = H_a H_b⁻¹ ignores the gripper and X = `base_from_camera` follows the
    /// base. B = C_a C_b⁻¹ ignores the target in both, and X follows the camera.
    fn x(self, setup: Setup, x: &Transform) -> Transform {
        match (self, setup) {
            (Self::Base(g), Setup::EyeToHand) => g * x,
            (Self::Gripper(g), Setup::EyeInHand) => g.inverse() * x,
            (Self::Camera(t), _) => x * t.inverse(),
            _ => *x,
        }
    }

    fn name(self) -> &'static str {
        match self {
            Self::Base(_) => "base frame",
            Self::Target(_) => "target frame",
            Self::Gripper(_) => "gripper frame",
            Self::Camera(_) => "camera frame",
            Self::Reverse => "reversed motions",
            Self::Reorder => "reordered motions",
        }
    }
}

/// Whether `method`'s estimate from noisy data follows `change` (the changed data's X is the
/// changed X): true where what the method minimises is the same function of the changed unknowns.
fn equivariant(method: Method, change: Change, setup: Setup) -> bool {
    // A change of frame that acts on A by conjugation, A → G A G⁻¹ (X → G X).
    let conjugates_a = matches!(
        (change, setup),
        (Change::Base(_), Setup::EyeToHand) | (Change::Gripper(_), Setup::EyeInHand)
    );
    match change {
        // The motions are unchanged (up to rounding): every method.
        Change::Base(_) | Change::Gripper(_) if !conjugates_a => true,
        Change::Target(_) | Change::Reorder => true,
        // AX − XB → G (AX − XB): every block of the residual is rotated, its norm kept, for the
        // methods that minimise it (Andreff's two forms, Park's and Horaud's rotation and
        // translation steps, refine). Not Tsai: its unknown is tan(θ/2)·axis of R_x, and its
        // rows skew(P_a + P_b), P_b − P_a are not rotated copies of the original ones when only
        // A rotates. Not Daniilidis: Eq. (31) keeps the vector parts of a q − q b only (the
        // scalar parts dropped, as OpenCV does), and left-multiplying by G's quaternion mixes
        // the two; its dual rows also carry G's translation, weighed against the real rows.
        Change::Base(_) | Change::Gripper(_) => {
            !matches!(method, Method::Tsai | Method::Daniilidis)
        }
        // AX − XB → (AX − XB) T⁻¹: the translation block gains ΔR·t, so every method that
        // weighs translation residuals minimises another function. None.
        Change::Camera(_) => false,
        // A⁻¹X − XB⁻¹ = −A⁻¹(AX − XB)B⁻¹: again ΔR enters the translation block. Daniilidis's
        // rows for (A⁻¹, B⁻¹) are the conjugate quaternions' and stay equivalent.
        Change::Reverse => method == Method::Daniilidis,
    }
}

/// Checks one change on one recording: on exact data every method gives the changed X; on noisy
/// data the equivariant methods give their own estimate, changed.
fn check_change(case: &Case, change: Change, exact: bool) -> Result<(), TestCaseError> {
    let (motions, changed) = (case.motions(), change.motions(case));
    prop_assume!(well_posed(&motions) && well_posed(&changed));
    for method in Method::ALL {
        let got = solved(method, &changed)?;
        let what = format!("{method} {} ({})", change.name(), case.setup);
        if exact {
            close(&got, &change.x(case.setup, &case.x), EXACT, &what)?;
        } else if equivariant(method, change, case.setup) {
            let tol = if method == Method::Refine {
                REFINE_STOP
            } else {
                EXACT
            };
            let own = solved(method, &motions)?;
            close(&got, &change.x(case.setup, &own), tol, &what)?;
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn every_method_recovers_x_from_exact_motions(case in exact_case()) {
        let motions = case.motions();
        prop_assume!(well_posed(&motions));
        for method in Method::ALL {
            close(&solved(method, &motions)?, &case.x, EXACT, &format!("{method} ({})", case.setup))?;
        }
    }

    #[test]
    fn a_change_of_base_frame(case in exact_case(), noisy in noisy_case(), g in any_transform()) {
        check_change(&case, Change::Base(g), true)?;
        check_change(&noisy, Change::Base(g), false)?;
    }

    #[test]
    fn a_change_of_target_frame(case in exact_case(), noisy in noisy_case(), t in any_transform()) {
        check_change(&case, Change::Target(t), true)?;
        check_change(&noisy, Change::Target(t), false)?;
    }

    #[test]
    fn a_change_of_gripper_frame(case in exact_case(), noisy in noisy_case(), g in any_transform()) {
        check_change(&case, Change::Gripper(g), true)?;
        check_change(&noisy, Change::Gripper(g), false)?;
    }

    #[test]
    fn a_change_of_camera_frame(case in exact_case(), noisy in noisy_case(), t in any_transform()) {
        check_change(&case, Change::Camera(t), true)?;
        check_change(&noisy, Change::Camera(t), false)?;
    }

    #[test]
    fn reversed_motions(case in exact_case(), noisy in noisy_case()) {
        check_change(&case, Change::Reverse, true)?;
        check_change(&noisy, Change::Reverse, false)?;
    }

    #[test]
    fn reordered_motions(case in exact_case(), noisy in noisy_case()) {
        check_change(&case, Change::Reorder, true)?;
        check_change(&noisy, Change::Reorder, false)?;
    }

    /// Either setup's poses, the robot poses inverted, solved as the other setup: the same
    /// motions, so every method gives the same X, noisy or not (and the true one when exact).
    #[test]
    fn the_eye_in_hand_eye_to_hand_duality(case in exact_case(), noisy in noisy_case()) {
        for (case, exact) in [(case, true), (noisy, false)] {
            let other = match case.setup {
                Setup::EyeInHand => Setup::EyeToHand,
                Setup::EyeToHand => Setup::EyeInHand,
            };
            let inverted: Vec<PosePair> = case.poses.iter().map(|p| PosePair {
                base_from_gripper: p.base_from_gripper.inverse(),
                ..*p
            }).collect();
            let dual = motion_pairs(&inverted, case.pairing, other);
            let motions = case.motions();
            prop_assume!(well_posed(&motions));
            for method in Method::ALL {
                let want = if exact { case.x } else { solved(method, &motions)? };
                let tol = if method == Method::Refine && !exact { REFINE_STOP } else { EXACT };
                close(&solved(method, &dual)?, &want, tol, &format!("{method} {} as {other}", case.setup))?;
            }
        }
    }

    /// On exact data refine starts at Andreff's exact X and stops for a reason of convergence,
    /// not at its iteration limit, with X still exact and the cost not raised.
    #[test]
    fn refine_converges_on_exact_motions(case in exact_case()) {
        let motions = case.motions();
        prop_assume!(well_posed(&motions));
        let r = refine(&motions).map_err(|e| TestCaseError::fail(e.to_string()))?;
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
        close(&r.calibration.x, &case.x, EXACT, "refine")?;
    }
}
