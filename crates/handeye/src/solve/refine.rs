//! Nonlinear refinement of X: Levenberg–Marquardt on the A X − X B residuals.

use nalgebra::{Matrix3, Matrix6, SMatrix, Vector3, Vector6};
use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::motion::{MotionPair, MotionSource};
use crate::pose::{Transform, exp_so3, proj_so3, rotation_matrix, skew, transform_from_parts};
use crate::solve::scale::{Scaled, length_scale};
use crate::solve::{Calibration, Method, MotionCheck, andreff, check_motions};

/// A start RMS below this counts as this, so that exact data does not divide by zero (SPEC sec. 3).
/// For the ΔT block it is in units of the data's length scale (see `run`), not of the input: 1e-12
/// of a kilometre and 1e-12 of a micrometre are the same floor relative to the data.
const MIN_BLOCK_RMS: f64 = 1e-12;

/// Levenberg–Marquardt settings; `Default` gives the values documented on each field.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RefineOptions {
    /// Iteration limit. Default 100.
    pub max_iterations: usize,
    /// Stop when the largest entry of the scaled gradient Jᵀr falls below this. Default 1e-14.
    pub gradient_tolerance: f64,
    /// Stop when a step changes the parameters by less than this (relative). Default 1e-15.
    pub step_tolerance: f64,
    /// Stop when an accepted step lowers the cost by less than this fraction. Default 1e-15.
    pub cost_tolerance: f64,
    /// Initial damping, relative to the largest diagonal entry of JᵀJ. Default 1e-3.
    pub initial_damping: f64,
}

impl Default for RefineOptions {
    fn default() -> Self {
        Self {
            max_iterations: 100,
            gradient_tolerance: 1e-14,
            step_tolerance: 1e-15,
            cost_tolerance: 1e-15,
            initial_damping: 1e-3,
        }
    }
}

/// Why the refinement stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Termination {
    /// The gradient vanished (a stationary point).
    GradientSmall,
    /// Steps became negligible.
    StepSmall,
    /// The cost stopped decreasing.
    CostConverged,
    /// The iteration limit was reached; the last accepted iterate is returned.
    MaxIterations,
}

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
/// use handeye::{MotionPair, Transform, refine};
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

/// The problem's current state: X and the weights of the two residual blocks.
struct Problem<'a, M: MotionSource + ?Sized> {
    motions: &'a M,
    /// 1 / (start RMS of ΔR entries), 1 / (start RMS of ΔT entries).
    weights: [f64; 2],
}

/// Normal equations at one iterate.
struct Linearisation {
    jtj: Matrix6<f64>,
    jtr: Vector6<f64>,
    cost: f64,
}

impl<M: MotionSource + ?Sized> Problem<'_, M> {
    /// Weighted cost ½Σr² at (R, t).
    fn cost(&self, r_x: &Matrix3<f64>, t_x: &Vector3<f64>) -> f64 {
        let mut sum = 0.0;
        self.motions.for_each_motion(|m| {
            let (dr, dt) = residual(m, r_x, t_x);
            sum += (self.weights[0] * self.weights[0]) * dr.norm_squared()
                + (self.weights[1] * self.weights[1]) * dt.norm_squared();
        });
        0.5 * sum
    }

    /// JᵀJ, Jᵀr and the cost at (R, t), for the increment R exp([δ]×), t + Δt.
    fn linearise(&self, r_x: &Matrix3<f64>, t_x: &Vector3<f64>) -> Linearisation {
        let mut jtj = Matrix6::zeros();
        let mut jtr = Vector6::zeros();
        let mut cost = 0.0;
        self.motions.for_each_motion(|m| {
            let (dr, dt) = residual(m, r_x, t_x);
            let (j, r) = jacobian(m, r_x, &dr, &dt, self.weights);
            jtj += j.transpose() * j;
            jtr += j.transpose() * r;
            cost += 0.5 * r.norm_squared();
        });
        Linearisation { jtj, jtr, cost }
    }
}

/// ΔR and ΔT of one motion at (R_x, t_x).
fn residual(
    m: &MotionPair,
    r_x: &Matrix3<f64>,
    t_x: &Vector3<f64>,
) -> (Matrix3<f64>, Vector3<f64>) {
    let r_a = rotation_matrix(&m.a);
    let r_b = rotation_matrix(&m.b);
    let dr = r_a * r_x - r_x * r_b;
    let dt = r_a * t_x + m.a.translation.vector - r_x * m.b.translation.vector - t_x;
    (dr, dt)
}

/// The 12×6 weighted Jacobian of one motion's residuals and the weighted residual vector.
///
/// With R = `R_x exp([δ]×)`: ∂ΔR/∂δ_m = R_a R_x [e_m]× − R_x [e_m]× R_b and
/// ∂ΔT/∂δ_m = −R_x [e_m]× t_b; ∂ΔT/∂t = R_a − I.
fn jacobian(
    m: &MotionPair,
    r_x: &Matrix3<f64>,
    dr: &Matrix3<f64>,
    dt: &Vector3<f64>,
    weights: [f64; 2],
) -> (SMatrix<f64, 12, 6>, SMatrix<f64, 12, 1>) {
    let r_a = rotation_matrix(&m.a);
    let r_b = rotation_matrix(&m.b);
    let t_b = m.b.translation.vector;
    let ar = r_a * r_x;
    let mut j = SMatrix::<f64, 12, 6>::zeros();
    let mut r = SMatrix::<f64, 12, 1>::zeros();
    for c in 0..3 {
        let e = skew(&Vector3::ith(c, 1.0));
        let d_r = (ar * e - r_x * e * r_b) * weights[0];
        let d_t = -(r_x * e * t_b) * weights[1];
        for row in 0..3 {
            for col in 0..3 {
                // Row-major order of the 9 entries of ΔR.
                j[(3 * row + col, c)] = d_r[(row, col)];
            }
            j[(9 + row, c)] = d_t[row];
        }
    }
    let dta = (r_a - Matrix3::identity()) * weights[1];
    j.fixed_view_mut::<3, 3>(9, 3).copy_from(&dta);
    for row in 0..3 {
        for col in 0..3 {
            r[3 * row + col] = dr[(row, col)] * weights[0];
        }
        r[9 + row] = dt[row] * weights[1];
    }
    (j, r)
}

/// Block weights from the start: 1 / RMS of the ΔR entries and 1 / RMS of the ΔT entries.
fn block_scales(
    motions: &(impl MotionSource + ?Sized),
    r_x: &Matrix3<f64>,
    t_x: &Vector3<f64>,
) -> [f64; 2] {
    let mut rms = BlockRms::default();
    motions.for_each_motion(|m| {
        let (dr, dt) = residual(m, r_x, t_x);
        rms.add(&dr, &dt);
    });
    rms.scales()
}

/// The RMS of the rotation-matrix entries and of the translation entries of residuals, each
/// floored at [`MIN_BLOCK_RMS`]: the block scales that keep either block from dominating (SPEC
/// sec. 3), for hand–eye motions and robot-world poses alike.
#[derive(Debug, Default)]
pub(crate) struct BlockRms {
    rotation: f64,
    translation: f64,
    count: usize,
}

impl BlockRms {
    /// Adds one residual: ΔR (3×3) and ΔT.
    pub(crate) fn add(&mut self, dr: &Matrix3<f64>, dt: &Vector3<f64>) {
        self.rotation += dr.norm_squared();
        self.translation += dt.norm_squared();
        self.count += 1;
    }

    /// [rotation, translation] RMS per entry.
    pub(crate) fn scales(&self) -> [f64; 2] {
        let n = self.count.max(1) as f64;
        [
            (self.rotation / (9.0 * n)).sqrt().max(MIN_BLOCK_RMS),
            (self.translation / (3.0 * n)).sqrt().max(MIN_BLOCK_RMS),
        ]
    }
}

/// Levenberg–Marquardt with Nielsen's damping update.
fn run(
    motions: &(impl MotionSource + ?Sized),
    start: &Transform,
    check: MotionCheck,
    options: &RefineOptions,
) -> Refinement {
    // Lengths are measured in the data's own unit (a power of two near its RMS translation): the
    // tolerances below mix rotation (radians) with translation (the gradient's t entries carry
    // 1/length, the step size adds |t_x| to 1, the ΔT floor is a length), so in the input's unit
    // they would stop the solve early, or never, depending on whether the data is in kilometres
    // or micrometres.
    let unit = length_scale(motions);
    let motions = &Scaled::new(motions, unit);
    let mut r_x = rotation_matrix(start);
    let mut t_x = start.translation.vector / unit;
    let scales = block_scales(motions, &r_x, &t_x);
    let problem = Problem {
        motions,
        weights: [1.0 / scales[0], 1.0 / scales[1]],
    };

    let mut lin = problem.linearise(&r_x, &t_x);
    let initial_cost = lin.cost;
    let mut damping = options.initial_damping * lin.jtj.diagonal().max();
    let mut growth = 2.0;
    let mut termination = Termination::MaxIterations;
    let mut iterations = 0;
    while iterations < options.max_iterations {
        if lin.jtr.amax() <= options.gradient_tolerance {
            termination = Termination::GradientSmall;
            break;
        }
        iterations += 1;
        let mut lhs = lin.jtj;
        for d in 0..6 {
            lhs[(d, d)] += damping;
        }
        let Some(step) = lhs.cholesky().map(|c| -c.solve(&lin.jtr)) else {
            damping *= growth;
            growth *= 2.0;
            continue;
        };
        let rotation_step: Vector3<f64> = step.fixed_rows::<3>(0).into_owned();
        let new_r = proj_so3(&(r_x * exp_so3(&rotation_step)));
        let new_t = t_x + step.fixed_rows::<3>(3);
        let new_cost = problem.cost(&new_r, &new_t);
        // Predicted reduction of the linear model: −δᵀJᵀr − ½δᵀJᵀJδ = ½δᵀ(λδ − Jᵀr).
        let predicted = 0.5 * step.dot(&(step * damping - lin.jtr));
        let gain = (lin.cost - new_cost) / predicted.max(f64::MIN_POSITIVE);
        if new_cost < lin.cost && gain > 0.0 {
            let relative_drop = (lin.cost - new_cost) / lin.cost.max(f64::MIN_POSITIVE);
            let step_size = step.norm() / (t_x.norm() + 1.0);
            r_x = new_r;
            t_x = new_t;
            lin = problem.linearise(&r_x, &t_x);
            damping *= (1.0_f64 / 3.0).max(1.0 - (2.0 * gain - 1.0).powi(3));
            growth = 2.0;
            if step_size <= options.step_tolerance {
                termination = Termination::StepSmall;
                break;
            }
            if relative_drop <= options.cost_tolerance {
                termination = Termination::CostConverged;
                break;
            }
        } else {
            damping *= growth;
            growth *= 2.0;
            if step.norm() / (t_x.norm() + 1.0) <= options.step_tolerance {
                termination = Termination::StepSmall;
                break;
            }
        }
    }
    let covariance = covariance_scaled(motions, &r_x, &t_x, unit);
    Refinement {
        calibration: Calibration {
            x: transform_from_parts(&r_x, &(t_x * unit)),
            method: Method::Refine,
            motions: motions.count(),
            conditioning: check.conditioning,
            warnings: check.warnings,
        },
        initial_cost,
        final_cost: lin.cost,
        iterations,
        termination,
        scales: [scales[0], scales[1] * unit],
        covariance,
    }
}

/// Covariance of X's parameters (rotation increment of `R_x exp([δ]×)` in radians, then t_x) at a
/// given X, as [`Refinement::covariance`]: the uncertainty of a solution from its residuals.
pub fn covariance_at(
    motions: &(impl MotionSource + ?Sized),
    x: &Transform,
) -> Option<Matrix6<f64>> {
    let unit = length_scale(motions);
    let t_x = x.translation.vector / unit;
    covariance_scaled(&Scaled::new(motions, unit), &rotation_matrix(x), &t_x, unit)
}

/// [`covariance`] of motions and a t_x given in units of `unit`, back in the input's unit.
fn covariance_scaled(
    motions: &(impl MotionSource + ?Sized),
    r_x: &Matrix3<f64>,
    t_x: &Vector3<f64>,
    unit: f64,
) -> Option<Matrix6<f64>> {
    let units = Vector6::new(1.0, 1.0, 1.0, unit, unit, unit);
    covariance(motions, r_x, t_x)
        .map(|c| Matrix6::from_diagonal(&units) * c * Matrix6::from_diagonal(&units))
}

/// Covariance of (δ, t): `s² (JᵀJ)⁻¹` of the problem weighted by the final block RMS values, with
/// `s² = Σr² / (N − 6)` for N residuals (Gauss–Newton with each block's noise estimated from its
/// own residuals).
fn covariance(
    motions: &(impl MotionSource + ?Sized),
    r_x: &Matrix3<f64>,
    t_x: &Vector3<f64>,
) -> Option<Matrix6<f64>> {
    let residuals = 12 * motions.count();
    if residuals <= 6 {
        return None;
    }
    let scales = block_scales(motions, r_x, t_x);
    let weighted = Problem {
        motions,
        weights: [1.0 / scales[0], 1.0 / scales[1]],
    };
    let lin = weighted.linearise(r_x, t_x);
    let s2 = 2.0 * lin.cost / (residuals - 6) as f64;
    lin.jtj.try_inverse().map(|inv| inv * s2)
}

#[cfg(test)]
#[path = "refine_tests.rs"]
mod tests;
