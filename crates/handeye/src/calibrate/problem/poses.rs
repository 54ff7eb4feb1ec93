//! The robot-world problem on pose pairs, A X = Z B: X and the target's pose together from every
//! pose once. Returns the solution and the target's uncertainty; the pipeline
//! ([`calibrate`](crate::calibrate()) with [`Problem::RobotWorld`](crate::Problem::RobotWorld))
//! strings the steps and words the [`RobotWorldReport`](crate::RobotWorldReport):
//! 1. the readings a user may have meant are tried, and the poses that break the screw invariants
//!    of their motions found, as in the hand–eye problem ([`Error::Misread`] unless
//!    [`Fix`](crate::Fix) says otherwise; outliers named in a warning, or left out with `reject_outliers`; a
//!    refusal names them);
//! 2. the method ([`RobotWorldMethod`]) solves Q_i X C_i = Y from every pose once
//!    (`solve::shah`, `solve::li`, `solve::refine_robot_world`);
//! 3. the uncertainty of **X** is the hand–eye report's bootstrap (`check::uncertainty::bootstrap`:
//!    every pose rebuilt to agree with X̂ and the mean target pose, its own residual put back with a
//!    random sign, re-solved by the *same* robot-world method); the uncertainty of the **target
//!    pose** is the first-order covariance of the joint per-pose residual problem at the solution
//!    (`solve::joint_covariance`: `s² (JᵀJ)⁻¹`, each residual block's noise estimated from
//!    its own residuals; `replicates` 0 says so). A direction of X or of the target that either
//!    leaves undetermined refuses the result ([`Degeneracy::Undetermined`]), a weak one of X is a
//!    warning. The first-order covariance is close to the truth on well-posed data (kinhec: median
//!    error/σ 1.0) but underestimates nearly degenerate directions (3–4° where the bootstrap
//!    says 22–23° on single-joint recordings), which is why X's refusal rests on the bootstrap;
//! 4. the residuals per pose: the angle between R_Y and R_Q R_X R_C (degrees) and how far pose i

use nalgebra::{Matrix3, Matrix6};

use crate::calibrate::low_dof::{self, Plan};
use crate::check::uncertainty::{Uncertainty, summarise};
use crate::model::error::{Degeneracy, Error, Result};
use crate::model::findings::{Part, Verdict};
use crate::model::motion::{Pairing, PosePair, Setup};
use crate::model::pose::{Transform, rotation_matrix};
use crate::model::prior::PriorsUsed;
use crate::solve::{
    JointCovariance, RobotWorld, RobotWorldMethod, joint_covariance, joint_covariance_given,
    robot_world,
};

/// X and the target's pose from `used` by `method`, or in the low-DOF form of `plan` (X's free
/// component from the prior).
pub(crate) fn solve(
    plan: Option<&Plan>,
    used: &[PosePair],
    setup: Setup,
    method: RobotWorldMethod,
) -> Result<RobotWorld> {
    match plan {
        Some(plan) => {
            let (x, target, conditioning) = low_dof::solve_robot_world(plan, used, setup, method)?;
            Ok(RobotWorld {
                x,
                target,
                method,
                poses: used.len(),
                conditioning,
                warnings: Vec::new(),
            })
        }
        None => robot_world(method, used, setup),
    }
}

/// X of a bootstrap replicate: the same method (or the same low-DOF form) on the replicate's poses.
pub(crate) fn solve_replicate(
    plan: Option<&Plan>,
    poses: &[PosePair],
    setup: Setup,
    method: RobotWorldMethod,
) -> Result<Transform> {
    match plan {
        Some(plan) => low_dof::solve_replicate(plan, poses, setup, Pairing::All),
        None => robot_world(method, poses, setup).map(|r| r.x),
    }
}

/// The first-order covariance of X and the target at the solution (`None` where it is singular),
/// with the low-DOF form's component held at its prior.
pub(crate) fn covariance(
    plan: Option<&Plan>,
    used: &[PosePair],
    setup: Setup,
    solved: &RobotWorld,
) -> Option<JointCovariance> {
    match plan {
        Some(plan) => joint_covariance_given(
            used,
            setup,
            (&solved.x, &solved.target),
            plan.prior.component.index(),
        ),
        None => joint_covariance(used, setup, &solved.x, &solved.target),
    }
}

/// The target's one-sigma uncertainty from the joint covariance (its axes in the target pose's
/// reference frame).
pub(crate) fn target_uncertainty(
    cov: &JointCovariance,
    target: &Transform,
    scene: f64,
) -> Uncertainty {
    summarise(left_block(cov, 6, target), 0, 0, scene)
}

/// The refusal of a covariance that does not exist (the poses do not determine X and the target).
pub(crate) fn ill_conditioned(conditioning: f64) -> Error {
    Error::Degenerate {
        reason: Degeneracy::IllConditioned,
        conditioning,
    }
}

/// X's and the target's uncertainty with the prior's sigma: along the free direction for X (as
/// the hand–eye report's) and along the coupled direction for the target (its translation moves
/// by k_Y / k_i per unit of the prior's value, [`low_dof::target_axis`]); and the report's
/// `prior`.
pub(crate) fn with_prior(
    plan: &Plan,
    (x_unc, y_unc): (Uncertainty, Uncertainty),
    (poses, setup): (&[PosePair], Setup),
    scene: f64,
) -> (Uncertainty, Uncertainty, PriorsUsed) {
    let (x_unc, used) = low_dof::with_prior(plan, &x_unc, scene);
    let k = plan.axis.hand[plan.prior.component.index()];
    let gain = low_dof::target_axis(plan, poses, setup) / k;
    let y_unc = y_unc.with_prior(&gain, plan.prior.sigma, scene);
    (x_unc, y_unc, used)
}

/// The 6×6 covariance of one transform (at `offset` 0 for X, 6 for Y) with its rotation turned
/// from the right increment R exp([δ]×) into the left one exp([R δ]×) R, so that its axes lie in
/// the transform's reference frame as the hand–eye report's do.
fn left_block(cov: &JointCovariance, offset: usize, t: &Transform) -> Matrix6<f64> {
    let block: Matrix6<f64> = cov.fixed_view::<6, 6>(offset, offset).into_owned();
    let r: Matrix3<f64> = rotation_matrix(t);
    let mut m = Matrix6::identity();
    m.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
    m * block * m.transpose()
}

pub(crate) fn refuse_if_undetermined(
    u: &Uncertainty,
    setup: Setup,
    conditioning: f64,
) -> Result<()> {
    let (part, d) = if u.weakest_rotation.verdict == Verdict::Undetermined {
        (Part::Rotation, &u.weakest_rotation)
    } else if u.weakest_translation.verdict == Verdict::Undetermined {
        (Part::Translation, &u.weakest_translation)
    } else {
        return Ok(());
    };
    Err(Error::Degenerate {
        reason: Degeneracy::Undetermined {
            part,
            axis: d.axis,
            sigma: d.sigma,
            setup,
        },
        conditioning,
    })
}
