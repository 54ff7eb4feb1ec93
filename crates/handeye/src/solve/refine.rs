//! Nonlinear refinement of X: Levenberg–Marquardt on the A X − X B residuals.

use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};
use serde::{Deserialize, Serialize};

use crate::model::error::Result;
use crate::model::pose::{Transform, exp_so3, proj_so3, rotation_matrix, transform_from_parts};
use crate::solve::lm::{
    LeastSquares, Linearisation, RefineOptions, Termination, levenberg_marquardt,
};
use crate::solve::motions::MotionSource;
use crate::solve::residual::{PerMotion, Residuals, covariance};
use crate::solve::scale::{Scaled, length_scale};
use crate::solve::{Calibration, Method, MotionCheck, andreff, check_motions};

/// The outcome of [`refine`] or [`refine_from`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Refinement {
    /// The refined X, with the conditioning and warnings of the motions.
    pub calibration: Calibration,
    /// Weighted cost ½Σr² at the start.
    pub initial_cost: f64,
    /// Weighted cost at the end; never above `initial_cost`.
    pub final_cost: f64,
    /// Iterations run.
    pub iterations: usize,
    /// Why it stopped.
    pub termination: Termination,
    /// The block scales: RMS of the ΔR entries and of the ΔT entries at the start.
    pub scales: [f64; 2],
    /// Covariance of the 6 parameters at the end (rotation increment of `R_x exp([δ]×)` in radians,
    /// then t_x in input units), from the Jacobian with each residual block's noise estimated from
    /// its final residuals; `None` when JᵀJ is singular or there are too few residuals.
    pub covariance: Option<Matrix6<f64>>,
}

/// Refines X over all motions, started from [`andreff`] (SPEC sec. 3, `refine`).
///
/// Unknowns `R_x = R₀ exp([r]×)` and t_x; residuals the 9 entries of ΔR_k = R_a R_x − R_x R_b and the
/// 3 of ΔT_k = R_a t_x + t_a − R_x t_b − t_x, each block divided by its RMS at the start so that
/// neither dominates. The parameterisation is re-centred after every accepted step
/// (`R₀ ← R₀ exp([δ]×)`), which reaches the same minimum as a fixed R₀.
///
/// # References
/// K. Levenberg (1944), D. Marquardt (1963); the step control follows H. B. Nielsen,
/// "Damping parameter in Marquardt's method", IMM-REP-1999-05.
///
/// # Example
/// ```
/// use handeye::solve::refine;
/// use handeye::{MotionPair, Transform};
/// use nalgebra::{Rotation3, Translation3, Vector3};
/// let x = Transform::from_parts(Translation3::new(0.1, 0.0, 0.05), Rotation3::from_euler_angles(0.1, 0.2, 0.3));
/// let a1 = Transform::new(Vector3::new(0.1, 0.2, 0.3), Vector3::new(0.5, 0.0, 0.0));
/// let a2 = Transform::new(Vector3::new(-0.2, 0.1, 0.4), Vector3::new(0.0, 0.4, 0.1));
/// let motions: Vec<_> = [a1, a2].iter().map(|a| MotionPair { a: *a, b: x.inverse() * a * x }).collect();
/// let r = refine(&motions)?;
/// assert!(r.final_cost <= r.initial_cost);
/// assert!((r.calibration.x.to_homogeneous() - x.to_homogeneous()).norm() < 1e-9);
/// # Ok::<(), handeye::Error>(())
/// ```
pub fn refine(motions: &(impl MotionSource + ?Sized)) -> Result<Refinement> {
    let start = andreff(motions)?;
    let check = MotionCheck {
        conditioning: start.conditioning,
        andreff_rotation: rotation_matrix(&start.x),
        warnings: start.warnings.clone(),
    };
    Ok(run(motions, &start.x, check, &RefineOptions::default()))
}

/// Refines X over all motions from a given start.
pub fn refine_from(
    motions: &(impl MotionSource + ?Sized),
    start: &Transform,
    options: &RefineOptions,
) -> Result<Refinement> {
    let check = check_motions(motions)?;
    Ok(run(motions, start, check, options))
}

/// Refines X over all motions from a given start without [`check_motions`]'s refusals: for motions
/// that all rotate about one axis ([`crate::solve::low_dof`]), whose rotation system is singular
/// but whose A X − X B residuals still fix every direction of X but the translation along the
/// axis (the caller puts that back from its prior). `conditioning` is reported as given.
pub fn refine_unchecked(
    motions: &(impl MotionSource + ?Sized),
    start: &Transform,
    conditioning: f64,
    options: &RefineOptions,
) -> Refinement {
    let check = MotionCheck {
        conditioning,
        andreff_rotation: rotation_matrix(start),
        warnings: Vec::new(),
    };
    run(motions, start, check, options)
}

/// The motions' residuals as the refinement sees them, lengths in units of `unit`: over all
/// pairs of a pose sequence the quadratic form of the per-pose sums
/// ([`crate::solve::quadratic::Quadratic`], O(1) per evaluation), else motion by motion.
fn with_residuals<T>(
    motions: &(impl MotionSource + ?Sized),
    unit: f64,
    f: impl FnOnce(&dyn Residuals) -> T,
) -> T {
    match motions.all_pairs() {
        Some(pairs) => f(&pairs.sums().quadratic().in_unit(unit)),
        None => f(&PerMotion(&Scaled::new(motions, unit))),
    }
}

/// Levenberg–Marquardt ([`levenberg_marquardt`]) in the data's length unit.
fn run(
    motions: &(impl MotionSource + ?Sized),
    start: &Transform,
    check: MotionCheck,
    options: &RefineOptions,
) -> Refinement {
    // Lengths are measured in the data's own unit (its RMS translation): the
    // tolerances below mix rotation (radians) with translation (the gradient's t entries carry
    // 1/length, the step size adds |t_x| to 1, the ΔT floor is a length), so in the input's unit
    // they would stop the solve early, or never, depending on whether the data is in kilometres
    // or micrometres.
    let unit = length_scale(motions);
    with_residuals(motions, unit, |residuals| {
        refine_in_unit(residuals, unit, start, check, options)
    })
}

/// The hand–eye refinement as a problem of the Levenberg–Marquardt loop: the iterate (R_x, t_x),
/// t_x in units of the data's length scale, and the residuals weighted block by block.
struct HandEye<'a> {
    residuals: &'a dyn Residuals,
    weights: [f64; 2],
}

impl LeastSquares<6> for HandEye<'_> {
    type State = (Matrix3<f64>, Vector3<f64>);

    fn linearise(&self, (r_x, t_x): &Self::State) -> Linearisation<6> {
        self.residuals.linearise(r_x, t_x, self.weights)
    }

    fn step(&self, (r_x, t_x): &Self::State, delta: &Vector6<f64>) -> Self::State {
        let rotation_step: Vector3<f64> = delta.fixed_rows::<3>(0).into_owned();
        (
            proj_so3(&(r_x * exp_so3(&rotation_step))),
            t_x + delta.fixed_rows::<3>(3),
        )
    }

    fn cost_drop(&self, from: &Self::State, to: &Self::State, cost: f64) -> f64 {
        -self
            .residuals
            .cost_change((&from.0, &from.1), (&to.0, &to.1), cost, self.weights)
    }

    fn size(&self, (_, t_x): &Self::State) -> f64 {
        t_x.norm() + 1.0
    }
}

/// [`run`] on the residuals of the motions in units of `unit`.
fn refine_in_unit(
    residuals: &dyn Residuals,
    unit: f64,
    start: &Transform,
    check: MotionCheck,
    options: &RefineOptions,
) -> Refinement {
    let r_x = rotation_matrix(start);
    let t_x = start.translation.vector / unit;
    let scales = residuals.block_rms(&r_x, &t_x).scales();
    let problem = HandEye {
        residuals,
        weights: [1.0 / scales[0], 1.0 / scales[1]],
    };
    let end = levenberg_marquardt(&problem, (r_x, t_x), options);
    let (r_x, t_x) = end.state;
    let covariance = in_input_unit(covariance(residuals, &r_x, &t_x), unit);
    Refinement {
        calibration: Calibration {
            x: transform_from_parts(&r_x, &(t_x * unit)),
            method: Method::Refine,
            motions: residuals.count(),
            conditioning: check.conditioning,
            warnings: check.warnings,
        },
        initial_cost: end.initial_cost,
        final_cost: end.final_cost,
        iterations: end.iterations,
        termination: end.termination,
        scales: [scales[0], scales[1] * unit],
        covariance,
    }
}

/// Covariance of X's parameters (rotation increment of `R_x exp([δ]×)` in radians, then t_x) at a
/// given X, as [`Refinement::covariance`]: the uncertainty of a solution from its residuals
/// (Gauss–Newton, each residual block's noise estimated from its own residuals).
pub fn covariance_at(
    motions: &(impl MotionSource + ?Sized),
    x: &Transform,
) -> Option<Matrix6<f64>> {
    let unit = length_scale(motions);
    let t_x = x.translation.vector / unit;
    let c = with_residuals(motions, unit, |r| covariance(r, &rotation_matrix(x), &t_x));
    in_input_unit(c, unit)
}

/// A covariance of (δ, t) with t in units of `unit`, in the input's unit.
fn in_input_unit(c: Option<Matrix6<f64>>, unit: f64) -> Option<Matrix6<f64>> {
    let units = Matrix6::from_diagonal(&Vector6::new(1.0, 1.0, 1.0, unit, unit, unit));
    c.map(|c| units * c * units)
}
