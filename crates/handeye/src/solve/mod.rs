//! Batch solvers of A X = X B: one function per classical method, and [`solve`] to pick one by name.
//!
//! Every solver takes motion pairs (A_k, B_k) (see [`crate::MotionPair`]) and returns a
//! [`Calibration`], or an [`Error`] when the motions cannot determine X. Before any method runs,
//! [`check_motions`] refuses fewer than two motions, rotations that are all ≈ 0 and rotation axes
//! that are all parallel; every result carries the conditioning of Andreff's rotation system, the
//! same measure for every method.

pub mod accumulate;
mod andreff;
mod andreff_joint;
mod daniilidis;
mod horaud;
mod least_squares;
pub(crate) mod lm;
pub mod low_dof;
pub mod low_dof_accumulate;
pub mod motions;
mod park;
mod quadratic;
mod quaternion;
mod refine;
pub mod reprojection;
pub mod residual;
pub(crate) mod robot_world;
pub mod robot_world_accumulate;
mod rotation_system;
mod scale;
mod symmetric;
mod tsai;

use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

pub use andreff::andreff;
pub use andreff_joint::andreff_joint;
pub use daniilidis::daniilidis;
pub use horaud::horaud;
pub use lm::{RefineOptions, Termination};
pub use park::park;
pub use refine::{Refinement, covariance_at};
pub use refine::{refine, refine_from, refine_unchecked};
pub use residual::PoseResidual;
pub use robot_world::{
    JointCovariance, RobotWorld, RobotWorldMethod, joint_covariance, joint_covariance_given,
    pose_residuals, robot_world, target_frame, target_given,
};
pub use robot_world::{
    RobotWorldRefinement, li, refine_robot_world, refine_robot_world_from, shah,
};
pub(crate) use rotation_system::{RotationSolution, RotationSystem};
#[cfg(test)]
pub(crate) use scale::Scaled;
pub use tsai::tsai_with;
pub use tsai::{TsaiOptions, tsai};

use crate::model::error::{Degeneracy, Error, Result};
use crate::model::pose::{Transform, rotation_matrix};
use crate::model::warning::Warning;
use crate::solve::motions::MotionSource;

/// Below this conditioning (second-smallest over largest singular value of Andreff's rotation
/// system) a solve is refused as degenerate.
///
/// The system is solved through its 9×9 normal matrix, whose smallest eigenvalues are only known to
/// about 1e-16 of the largest: their square roots, the singular values, to about 1e-8. Exactly
/// parallel axes therefore show a conditioning near 1e-8, never 0, and the refusal sits above that
/// floor.
pub const REFUSE_CONDITIONING: f64 = 1e-6;

/// Below this conditioning a solve succeeds with a [`Warning::WeakConditioning`]: the rotation of X
/// about one direction rests on little information (axes a few tenths of a degree apart).
pub const WARN_CONDITIONING: f64 = 1e-2;

/// Motions whose rotations are all below this angle (radians) are refused: their axes, and so X,
/// are not determined.
pub const REFUSE_ANGLE: f64 = 1e-6;

/// When the largest rotation of the motions is below this angle (radians, 2°), a solve succeeds
/// with a [`Warning::SmallRotations`]: noise in the poses is amplified into X.
pub const WARN_ANGLE: f64 = 2.0 * std::f64::consts::PI / 180.0;

/// The classical solvers, by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Andreff et al., two-step Kronecker form (the paper's solver).
    Andreff,
    /// Andreff et al., simultaneous 12-unknown form (OpenCV's `CALIB_HAND_EYE_ANDREFF`).
    AndreffJoint,
    /// Tsai and Lenz (OpenCV's `CALIB_HAND_EYE_TSAI`).
    Tsai,
    /// Park and Martin (OpenCV's `CALIB_HAND_EYE_PARK`).
    Park,
    /// Horaud and Dornaika (OpenCV's `CALIB_HAND_EYE_HORAUD`).
    Horaud,
    /// Daniilidis, dual quaternions (OpenCV's `CALIB_HAND_EYE_DANIILIDIS`).
    Daniilidis,
    /// Levenberg–Marquardt on all motions, started from `andreff`.
    Refine,
    /// Levenberg–Marquardt on the pixels of the detections, X and the target's pose together
    /// ([`calibrate`](crate::calibrate()) on [`Input::Pixels`](crate::Input::Pixels)): not a
    /// solver of motions, so not in
    /// [`Method::ALL`], and [`solve`] refuses it.
    Reprojection,
}

crate::named_enum!(Method, "method", "method" {
    Andreff => "andreff",
    AndreffJoint => "andreff-joint",
    Tsai => "tsai",
    Park => "park",
    Horaud => "horaud",
    Daniilidis => "daniilidis",
    Refine => "refine";
    not listed: Reprojection => "reprojection",
});

impl Method {
    /// Every method, the motion solvers of [`Method::ALL`] and [`Method::Reprojection`].
    pub const WITH_PIXELS: [Method; 8] = {
        let mut all = [Method::Reprojection; 8];
        let mut i = 0;
        while i < Method::ALL.len() {
            all[i] = Method::ALL[i];
            i += 1;
        }
        all
    };

    /// What the method can do beyond solving motions: its row of the capability table, the one
    /// place a job asks (how its bootstrap replicates are made, whether it solves a low-DOF
    /// recording, whether it solves on the pixels). A new method is a variant, its solver file,
    /// and a row here.
    pub const fn capabilities(self) -> Capabilities {
        use Replicates::{AndreffSums, Own, SumsOrBriefRefine};
        let (replicates, low_dof, pixels) = match self {
            Method::Andreff => (AndreffSums, true, false),
            Method::AndreffJoint => (Own, false, false),
            Method::Tsai | Method::Park | Method::Horaud => (AndreffSums, false, false),
            Method::Daniilidis => (Own, false, false),
            Method::Refine => (SumsOrBriefRefine, true, false),
            Method::Reprojection => (Own, false, true),
        };
        Capabilities {
            replicates,
            low_dof,
            pixels,
        }
    }
}

/// A method's row of the capability table ([`Method::capabilities`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Capabilities {
    /// How its bootstrap replicates are solved.
    pub replicates: Replicates,
    /// Whether it solves a recording whose motions all rotate about one axis (a low-DOF robot,
    /// with a prior on the free component).
    pub low_dof: bool,
    /// Whether it solves on the pixels of the detections rather than on motions.
    pub pixels: bool,
}

/// How a method's bootstrap replicates are solved (the batch job's uncertainty).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Replicates {
    /// Over every pair, by Andreff's O(n) accumulated sums: the method's errors over all pairs
    /// are Andreff's size (measured, docs/DECISIONS.md), and re-solving n² motions per replicate
    /// was most of a `calibrate`; over consecutive pairs, by the method itself.
    AndreffSums,
    /// As [`Replicates::AndreffSums`] over every pair; over consecutive pairs, a few refinement
    /// steps from the replicate's own Andreff start.
    SumsOrBriefRefine,
    /// By the method itself: its errors are larger than Andreff's (andreff-joint, daniilidis),
    /// or it has its own uncertainty (the pixels).
    Own,
}

/// The result of a batch solve.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Calibration {
    /// X, the solution of A X = X B: `gripper_from_camera` for eye-in-hand motions,
    /// `base_from_camera` for eye-to-hand motions (see [`crate::Setup`]).
    pub x: Transform,
    /// The method that produced X.
    pub method: Method,
    /// Number of motion pairs used.
    pub motions: usize,
    /// Second-smallest over largest singular value of Andreff's rotation system (1 is ideal).
    pub conditioning: f64,
    /// Cautions about the data; empty when none.
    pub warnings: Vec<Warning>,
}

/// What [`check_motions`] learned about the motions: enough to solve, with cautions.
#[derive(Debug, Clone, PartialEq)]
pub struct MotionCheck {
    /// Conditioning of Andreff's rotation system.
    pub conditioning: f64,
    /// Andreff's rotation R_x from the same system (step 1 of [`andreff`]).
    pub andreff_rotation: Matrix3<f64>,
    /// Cautions about the data.
    pub warnings: Vec<Warning>,
}

/// Refuses motion sets that cannot determine X, and says how well they determine it.
///
/// Errors: [`Error::TooFewMotions`] below two motions, [`Error::Degenerate`] when every rotation is
/// below [`REFUSE_ANGLE`] or the conditioning is below [`REFUSE_CONDITIONING`] (parallel axes).
pub fn check_motions(motions: &(impl MotionSource + ?Sized)) -> Result<MotionCheck> {
    if motions.count() < 2 {
        return Err(Error::TooFewMotions {
            got: motions.count(),
            need: 2,
        });
    }
    let (
        RotationSolution {
            r_x: andreff_rotation,
            conditioning,
        },
        largest,
    ) = match motions.all_pairs() {
        Some(pairs) => (
            pairs.sums().poses.rotation_system().solve_refined(motions),
            largest_rotation_of_pairs(pairs, motions),
        ),
        None => {
            let mut system = RotationSystem::default();
            motions.for_each_motion(|m| {
                system.add(&rotation_matrix(&m.a), &rotation_matrix(&m.b));
            });
            (system.solve_refined(motions), largest_rotation(motions))
        }
    };
    if largest < REFUSE_ANGLE {
        return Err(Error::Degenerate {
            reason: Degeneracy::SmallRotations {
                largest_deg: largest.to_degrees(),
            },
            conditioning,
        });
    }
    if conditioning < REFUSE_CONDITIONING {
        let reason = Degeneracy::ParallelAxes {
            largest_axis_angle_deg: 2.0 * crate::solve::motions::axis_spread(motions).to_degrees(),
        };
        return Err(Error::Degenerate {
            reason,
            conditioning,
        });
    }
    let mut warnings = Vec::new();
    if conditioning < WARN_CONDITIONING {
        warnings.push(Warning::WeakConditioning { conditioning });
    }
    if largest < WARN_ANGLE {
        warnings.push(Warning::SmallRotations {
            largest_deg: largest.to_degrees(),
        });
    }
    Ok(MotionCheck {
        conditioning,
        andreff_rotation,
        warnings,
    })
}

/// The largest rotation angle of the motions, radians.
fn largest_rotation(motions: &(impl MotionSource + ?Sized)) -> f64 {
    // The largest rotation is the one with the smallest trace (θ = acos((tr − 1) / 2)): one
    // comparison per motion, and one angle computed at the end.
    let mut widest = Matrix3::identity();
    motions.for_each_motion(|m| {
        let r_a = rotation_matrix(&m.a);
        if r_a.trace() < widest.trace() {
            widest = r_a;
        }
    });
    crate::model::pose::axis_angle(&widest).0
}

/// [`largest_rotation`] over all pairs of poses, exactly where it decides anything, in O(n) when
/// the rotations are not small. The motions from pose 0 give α = max_k ∠(R_0, R_k), attained by a
/// pair; every pair's angle is at most 2α (the triangle inequality of the rotation angle). So
/// when α ≥ [`WARN_ANGLE`], α is returned: the largest rotation is at least that, and neither the
/// refusal nor the warning applies. Below, the motions are gone through.
fn largest_rotation_of_pairs(
    pairs: &crate::solve::motions::AllPairs,
    motions: &(impl MotionSource + ?Sized),
) -> f64 {
    if pairs.poses() < 2 {
        return 0.0;
    }
    let r_0 = rotation_matrix(pairs.pose(0).0);
    let mut widest = Matrix3::identity();
    for k in 1..pairs.poses() {
        let r_a = rotation_matrix(pairs.pose(k).0).transpose() * r_0;
        if r_a.trace() < widest.trace() {
            widest = r_a;
        }
    }
    let alpha = crate::model::pose::axis_angle(&widest).0;
    if alpha >= WARN_ANGLE {
        alpha
    } else {
        largest_rotation(motions)
    }
}

/// Solves A X = X B with the given method.
///
/// # Example
/// ```
/// use handeye::{Method, MotionPair, Transform, solve};
/// use nalgebra::{Rotation3, Translation3, Vector3};
/// let x = Transform::from_parts(Translation3::new(0.1, 0.0, 0.05), Rotation3::from_euler_angles(0.1, 0.2, 0.3));
/// let a1 = Transform::new(Vector3::new(0.1, 0.2, 0.3), Vector3::new(0.5, 0.0, 0.0));
/// let a2 = Transform::new(Vector3::new(-0.2, 0.1, 0.4), Vector3::new(0.0, 0.4, 0.1));
/// let motions: Vec<_> = [a1, a2].iter().map(|a| MotionPair { a: *a, b: x.inverse() * a * x }).collect();
/// let cal = solve(Method::Park, &motions)?;
/// assert!((cal.x.to_homogeneous() - x.to_homogeneous()).norm() < 1e-9);
/// # Ok::<(), handeye::Error>(())
/// ```
pub fn solve(method: Method, motions: &(impl MotionSource + ?Sized)) -> Result<Calibration> {
    match method {
        Method::Andreff => andreff(motions),
        Method::AndreffJoint => andreff_joint(motions),
        Method::Tsai => tsai(motions),
        Method::Park => park(motions),
        Method::Horaud => horaud(motions),
        Method::Daniilidis => daniilidis(motions),
        Method::Refine => refine(motions).map(|r| r.calibration),
        Method::Reprojection => Err(crate::model::error::Error::InvalidParameter {
            name: "method",
            message: "`reprojection` solves on the pixels: give detections and intrinsics (`--intrinsics FILE`), not motions".into(),
        }),
    }
}

/// Least-squares translation of X given its rotation: the stacked
/// (I − R_a) t_x = t_a − R_x t_b over all motions, solved through its 3×3 normal equations
/// (over all pairs of poses, accumulated in O(n): [`crate::solve::accumulate::PoseAccumulator`]).
///
/// Returns `None` when the 3×3 system is singular (all axes parallel).
pub(crate) fn translation_least_squares(
    motions: &(impl MotionSource + ?Sized),
    r_x: &Matrix3<f64>,
) -> Option<Vector3<f64>> {
    // Over all pairs the normal equations come from the per-pose sums.
    // One step of iterative refinement with the exact per-pose gradient, as `least_squares_3`
    // does with the motions' residuals.
    if let Some(pairs) = motions.all_pairs() {
        let sums = &pairs.sums().poses;
        let lu = sums.translation_normal().lu();
        let mut t = sums.translation(r_x)?;
        for _ in 0..2 {
            let gradient = crate::solve::residual::pairs_translation_gradient(pairs, r_x, &t);
            t -= lu.solve(&gradient)?;
        }
        return t.iter().all(|v| v.is_finite()).then_some(t);
    }
    // Rows C_k = I − R_a and right-hand sides d_k = t_a − R_x t_b.
    least_squares::least_squares_3(motions, |m| {
        (
            Matrix3::identity() - rotation_matrix(&m.a),
            m.a.translation.vector - r_x * m.b.translation.vector,
        )
    })
}

/// Wraps a solved rotation and translation into a [`Calibration`] carrying the motion check.
pub(crate) fn finish(
    method: Method,
    motions: usize,
    check: MotionCheck,
    r_x: &Matrix3<f64>,
    t_x: &Vector3<f64>,
) -> Calibration {
    Calibration {
        x: crate::model::pose::transform_from_parts(r_x, t_x),
        method,
        motions,
        conditioning: check.conditioning,
        warnings: check.warnings,
    }
}

/// The error returned when a method's own linear system turns out singular after the motion check
/// passed (possible only at the edge of the refusal thresholds).
pub(crate) fn singular(conditioning: f64) -> Error {
    Error::Degenerate {
        reason: Degeneracy::IllConditioned,
        conditioning,
    }
}
