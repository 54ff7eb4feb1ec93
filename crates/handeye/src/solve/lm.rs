//! The one Levenberg–Marquardt loop, for the hand–eye refinement ([`crate::solve::refine`]) and the
//! robot-world one ([`crate::solve::refine_robot_world`]): a problem gives its normal equations at an
//! iterate, the iterate a step leads to, and the cost change of a step; the loop damps the steps
//! and decides when to stop.

use nalgebra::{SMatrix, SVector};
use serde::{Deserialize, Serialize};

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

/// Normal equations of the weighted residuals at one iterate, for `N` parameters.
pub(crate) struct Linearisation<const N: usize> {
    /// JᵀJ.
    pub(crate) jtj: SMatrix<f64, N, N>,
    /// Jᵀr.
    pub(crate) jtr: SVector<f64, N>,
    /// ½Σr².
    pub(crate) cost: f64,
}

/// A nonlinear least-squares problem in `N` parameters, as the loop sees it.
pub(crate) trait LeastSquares<const N: usize> {
    /// An iterate (rotations and translations).
    type State;
    /// JᵀJ, Jᵀr and ½Σr² at `s`.
    fn linearise(&self, s: &Self::State) -> Linearisation<N>;
    /// The iterate a step δ leads to from `s` (rotations `R exp([δ]×)`, translations `t + Δt`).
    fn step(&self, s: &Self::State, delta: &SVector<f64, N>) -> Self::State;
    /// How much the cost drops from `from`, where it is `cost`, to `to` (negative when it rises).
    fn cost_drop(&self, from: &Self::State, to: &Self::State, cost: f64) -> f64;
    /// The size a step is measured against: 1 plus the norms of the translations.
    fn size(&self, s: &Self::State) -> f64;
}

/// Where the loop stopped.
pub(crate) struct Minimum<S> {
    /// The last accepted iterate.
    pub(crate) state: S,
    /// Cost ½Σr² at the start.
    pub(crate) initial_cost: f64,
    /// Cost at `state`.
    pub(crate) final_cost: f64,
    /// Iterations run.
    pub(crate) iterations: usize,
    /// Why it stopped.
    pub(crate) termination: Termination,
}

/// Levenberg–Marquardt from `start`, with Nielsen's damping update: a step is accepted when it
/// lowers the cost, and the damping λ then shrinks by max(⅓, 1 − (2ρ − 1)³) for the gain ratio ρ
/// (actual over predicted drop); a rejected step multiplies λ by ν and doubles ν.
///
/// # References
/// K. Levenberg (1944), D. Marquardt (1963); the step control follows H. B. Nielsen,
/// "Damping parameter in Marquardt's method", IMM-REP-1999-05.
pub(crate) fn levenberg_marquardt<const N: usize, P: LeastSquares<N>>(
    problem: &P,
    start: P::State,
    options: &RefineOptions,
) -> Minimum<P::State> {
    minimise(
        start,
        options,
        |s: &P::State| problem.linearise(s),
        |s, delta| problem.step(s, delta),
        |from, to, cost| problem.cost_drop(from, to, cost),
        |s| problem.size(s),
    )
}

/// What the loop needs of the normal equations at an iterate, whatever their size: fixed
/// ([`Linearisation`]) or known at run time ([`DynLinearisation`]).
trait Normal {
    /// A step in the parameters.
    type Step;
    /// ½Σr².
    fn cost(&self) -> f64;
    /// The largest entry of Jᵀr in size.
    fn gradient_max(&self) -> f64;
    /// The largest diagonal entry of JᵀJ.
    fn diagonal_max(&self) -> f64;
    /// δ = −(JᵀJ + λI)⁻¹ Jᵀr, by Cholesky; `None` when the damped matrix is not positive definite.
    fn damped_step(&self, damping: f64) -> Option<Self::Step>;
    /// The linear model's drop for `step`: −δᵀJᵀr − ½δᵀJᵀJδ = ½δᵀ(λδ − Jᵀr).
    fn predicted(&self, step: &Self::Step, damping: f64) -> f64;
    /// |δ|.
    fn norm(step: &Self::Step) -> f64;
}

impl<const N: usize> Normal for Linearisation<N> {
    type Step = SVector<f64, N>;
    fn cost(&self) -> f64 {
        self.cost
    }
    fn gradient_max(&self) -> f64 {
        self.jtr.amax()
    }
    fn diagonal_max(&self) -> f64 {
        self.jtj.diagonal().max()
    }
    fn damped_step(&self, damping: f64) -> Option<Self::Step> {
        let mut lhs = self.jtj;
        for d in 0..N {
            lhs[(d, d)] += damping;
        }
        lhs.cholesky().map(|c| -c.solve(&self.jtr))
    }
    fn predicted(&self, step: &Self::Step, damping: f64) -> f64 {
        0.5 * step.dot(&(step * damping - self.jtr))
    }
    fn norm(step: &Self::Step) -> f64 {
        step.norm()
    }
}

impl Normal for DynLinearisation {
    type Step = nalgebra::DVector<f64>;
    fn cost(&self) -> f64 {
        self.cost
    }
    fn gradient_max(&self) -> f64 {
        self.jtr.amax()
    }
    fn diagonal_max(&self) -> f64 {
        self.jtj.diagonal().max()
    }
    fn damped_step(&self, damping: f64) -> Option<Self::Step> {
        let mut lhs = self.jtj.clone();
        for d in 0..lhs.nrows() {
            lhs[(d, d)] += damping;
        }
        lhs.cholesky().map(|c| -c.solve(&self.jtr))
    }
    fn predicted(&self, step: &Self::Step, damping: f64) -> f64 {
        0.5 * step.dot(&(step * damping - &self.jtr))
    }
    fn norm(step: &Self::Step) -> f64 {
        step.norm()
    }
}

/// The loop itself, for normal equations of any size: Nielsen's damping, the stopping rules, and
/// never a higher cost than the start.
fn minimise<S, L: Normal>(
    start: S,
    options: &RefineOptions,
    linearise: impl Fn(&S) -> L,
    step_from: impl Fn(&S, &L::Step) -> S,
    cost_drop: impl Fn(&S, &S, f64) -> f64,
    size: impl Fn(&S) -> f64,
) -> Minimum<S> {
    let mut s = start;
    let mut lin = linearise(&s);
    let initial_cost = lin.cost();
    let mut damping = options.initial_damping * lin.diagonal_max();
    let mut growth = 2.0;
    let mut termination = Termination::MaxIterations;
    let mut iterations = 0;
    while iterations < options.max_iterations {
        if lin.gradient_max() <= options.gradient_tolerance {
            termination = Termination::GradientSmall;
            break;
        }
        iterations += 1;
        let Some(step) = lin.damped_step(damping) else {
            damping *= growth;
            growth *= 2.0;
            continue;
        };
        let next = step_from(&s, &step);
        let drop = cost_drop(&s, &next, lin.cost());
        let gain = drop / lin.predicted(&step, damping).max(f64::MIN_POSITIVE);
        let step_size = L::norm(&step) / size(&s);
        if drop > 0.0 && gain > 0.0 {
            let relative_drop = drop / lin.cost().max(f64::MIN_POSITIVE);
            s = next;
            lin = linearise(&s);
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
            if step_size <= options.step_tolerance {
                termination = Termination::StepSmall;
                break;
            }
        }
    }
    Minimum {
        state: s,
        initial_cost,
        final_cost: lin.cost(),
        iterations,
        termination,
    }
}

/// Normal equations of the weighted residuals at one iterate, for a number of parameters known
/// only at run time (a rig's cameras and targets, six each).
pub(crate) struct DynLinearisation {
    /// JᵀJ.
    pub(crate) jtj: nalgebra::DMatrix<f64>,
    /// Jᵀr.
    pub(crate) jtr: nalgebra::DVector<f64>,
    /// ½Σr².
    pub(crate) cost: f64,
}

/// [`LeastSquares`] for a number of parameters known only at run time.
pub(crate) trait DynLeastSquares {
    /// An iterate.
    type State;
    /// JᵀJ, Jᵀr and ½Σr² at `s`.
    fn linearise(&self, s: &Self::State) -> DynLinearisation;
    /// The iterate a step δ leads to from `s`.
    fn step(&self, s: &Self::State, delta: &nalgebra::DVector<f64>) -> Self::State;
    /// ½Σr² at `s`.
    fn cost(&self, s: &Self::State) -> f64;
    /// The size a step is measured against: 1 plus the norms of the translations.
    fn size(&self, s: &Self::State) -> f64;
}

/// [`levenberg_marquardt`] on a problem whose size is known at run time: the same damping
/// (Nielsen's update), the same stopping rules, the same guarantee (never a higher cost than the
/// start).
pub(crate) fn levenberg_marquardt_dyn<P: DynLeastSquares>(
    problem: &P,
    start: P::State,
    options: &RefineOptions,
) -> Minimum<P::State> {
    minimise(
        start,
        options,
        |s: &P::State| problem.linearise(s),
        |s, delta| problem.step(s, delta),
        |_, to, cost| cost - problem.cost(to),
        |s| problem.size(s),
    )
}
