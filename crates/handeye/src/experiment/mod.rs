//! The simulated studies `handeye experiment` runs, through one entry: [`run_experiment`] with an
//! [`Experiment`] and an [`ExperimentConfig`] ([`ExperimentConfig::for_experiment`] gives each
//! one's defaults), returning an [`ExperimentReport`] with one variant per experiment whose rows
//! are read off its fields. Monte-Carlo over series of the paper's simulation ([`crate::sim`]),
//! in parallel, reproducible whatever the number of threads.
//!
//! The paper's (sec. 4.1), as SPEC sec. 6 fixes them:
//! - [`Experiment::Accuracy`]: 20 series × 200 poses; mean error per series of conventional,
//!   fixed and adaptive (error source: truth), and every batch solver on all poses (Fig. 2).
//! - [`Experiment::Adaptability`]: 100 series × 500 poses; calibrations per series, adaptive
//!   vs fixed (Fig. 3).
//! - [`Experiment::Realtime`]: 50 series × 100 poses; time per calibration and errors,
//!   adaptive vs optimal (Table I).
//!
//! Beyond the paper:
//! - [`Experiment::Tracking`]: 20 series × 200 poses; the accumulating estimator's errors as the
//!   poses come, against the paper's selection and a batch solve so far, and how fast a change of
//!   X is noticed (`series` series of `jump_poses` poses for each jump size, the jump halfway).
//! - [`Experiment::Advice`]: 20 series; how many poses the paper's walk, random turns and
//!   [`advise`](crate::advise)'s suggestions need to reach the same uncertainty (the advice's
//!   closed loop).

mod paper;
mod tracking;

use serde::{Deserialize, Serialize};

use crate::calibrate::advice::{ClosedLoop, closed_loop};
use crate::model::error::Result;
use crate::online::select::AdaptiveParams;
use crate::sim::SimConfig;

pub use paper::{MethodSummary, MethodsReport, MethodsSettings, SeriesResult};
pub use tracking::{DetectionResult, TrackingCurve, TrackingReport, TrackingSettings};

/// One of the studies: the paper's three experiments, then two beyond it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Experiment {
    /// Sec. 4.1.1: errors of conventional vs adaptive (Fig. 2).
    Accuracy,
    /// Sec. 4.1.2: calibrations per series, adaptive vs fixed (Fig. 3).
    Adaptability,
    /// Sec. 4.1.3: time and errors, adaptive vs optimal (Table I).
    Realtime,
    /// The accumulating estimator: its errors as the poses come, and how fast a change of X is
    /// noticed.
    Tracking,
    /// The closed loop of [`advise`](crate::advise): the poses each way of moving needs to reach
    /// the uncertainty the paper's walk reaches after 100 poses.
    Advice,
}

crate::named_enum!(Experiment, "experiment", "experiment" {
    Accuracy => "accuracy",
    Adaptability => "adaptability",
    Realtime => "realtime",
    Tracking => "tracking",
    Advice => "advice",
});

/// Settings of a run; [`for_experiment`](Self::for_experiment) gives each experiment's. Each
/// field says which experiments read it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ExperimentConfig {
    /// Number of series (all). The paper's: 20 accuracy, 100 adaptability, 50 realtime; 20
    /// tracking and advice.
    pub series: usize,
    /// Seed of the run; series s uses the generator of (seed, s) (all). Default 1.
    pub seed: u64,
    /// The simulation; its `poses` is the poses per series: 200 accuracy, 500 adaptability, 100
    /// realtime, 200 tracking. Tracking reads `poses` alone (the protocol's defaults otherwise);
    /// advice none of it (the protocol, up to 300 poses a series).
    pub sim: SimConfig,
    /// Parameters of the adaptive method (all but advice). `d_max` is 100 because the simulation
    /// is in millimetres.
    pub params: AdaptiveParams,
    /// Accuracy, adaptability, realtime: also solve each series with every batch solver on all
    /// its poses (reference rows). Default true.
    pub batch: bool,
    /// Tracking: errors are recorded every this many poses. Default 10.
    pub every: usize,
    /// Tracking: the jumps of X to detect, (rotation degrees, translation mm). Default (0.1, 0.5),
    /// (0.25, 1.25), (0.5, 2.5), (1, 5), (2, 10).
    pub jumps: Vec<(f64, f64)>,
    /// Tracking: poses of each jump series; the jump comes at the middle. Default 300.
    pub jump_poses: usize,
}

impl ExperimentConfig {
    /// Refuses counts no study can run with: no series, a tracking checkpoint every 0 poses, a
    /// jump series too short to jump halfway.
    pub fn validate(&self) -> Result<()> {
        let refuse = |name, message: &str| {
            Err(crate::model::error::Error::InvalidParameter {
                name,
                message: message.into(),
            })
        };
        if self.series == 0 {
            return refuse("series", "at least one series");
        }
        if self.every == 0 {
            return refuse("every", "a checkpoint every 1 pose or more");
        }
        if self.jump_poses < 2 {
            return refuse("jump_poses", "at least 2 poses, the jump halfway");
        }
        Ok(())
    }

    /// The settings of `experiment` (the paper's, for its three), with seed 1.
    pub fn for_experiment(experiment: Experiment) -> Self {
        let (series, poses) = match experiment {
            Experiment::Accuracy => (20, 200),
            Experiment::Adaptability => (100, 500),
            Experiment::Realtime => (50, 100),
            Experiment::Tracking | Experiment::Advice => (20, 200),
        };
        Self {
            series,
            seed: 1,
            sim: SimConfig {
                poses,
                ..SimConfig::default()
            },
            params: AdaptiveParams {
                d_max: 100.0,
                ..AdaptiveParams::default()
            },
            batch: true,
            every: 10,
            jumps: vec![
                (0.1, 0.5),
                (0.25, 1.25),
                (0.5, 2.5),
                (1.0, 5.0),
                (2.0, 10.0),
            ],
            jump_poses: 300,
        }
    }
}

/// The outcome of [`run_experiment`]: one variant per [`Experiment`], its rows read off the
/// variant's fields (with the settings the run read, `config`, but for advice). Serialised as the
/// variant's contents (the JSON `handeye experiment` writes).
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum ExperimentReport {
    /// One summary per method (`methods`, each with `per_series` results): conventional, fixed,
    /// adaptive, then the batch solvers; `method(name)` finds one.
    Accuracy(MethodsReport),
    /// As [`Accuracy`](Self::Accuracy): adaptive, fixed, conventional, then the batch solvers.
    Adaptability(MethodsReport),
    /// As [`Accuracy`](Self::Accuracy): adaptive and optimal, then the batch solvers.
    Realtime(MethodsReport),
    /// Mean error curves per estimator (`curves`), and one row per jump size (`detection`).
    Tracking(TrackingReport),
    /// The median poses each way of moving needed (`median_poses`: the paper's walk, random
    /// turns, the advice) to reach `target_rotation_deg`.
    Advice(ClosedLoop),
}

/// Runs `experiment` with `config`, calling `progress` after each finished series (from any
/// thread).
pub fn run_experiment(
    experiment: Experiment,
    config: &ExperimentConfig,
    progress: impl Fn() + Sync,
) -> Result<ExperimentReport> {
    config.validate()?;
    let methods = || paper::run(experiment, &MethodsSettings::from(config), &progress);
    Ok(match experiment {
        Experiment::Accuracy => ExperimentReport::Accuracy(methods()?),
        Experiment::Adaptability => ExperimentReport::Adaptability(methods()?),
        Experiment::Realtime => ExperimentReport::Realtime(methods()?),
        Experiment::Tracking => {
            ExperimentReport::Tracking(tracking::run(&TrackingSettings::from(config), &progress)?)
        }
        Experiment::Advice => {
            ExperimentReport::Advice(closed_loop(config.series, config.seed, &progress))
        }
    })
}

// The online methods a report names (as strings).
pub use methods::OnlineMethod;

mod methods {
    use serde::{Deserialize, Serialize};

    /// The paper's online methods.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
    #[serde(rename_all = "kebab-case")]
    pub enum OnlineMethod {
        /// Andreff on every two consecutive motions.
        Conventional,
        /// Shi et al.'s fixed thresholds.
        Fixed,
        /// The paper's adaptive selection.
        Adaptive,
        /// Adaptive selection, then refinement over the last five selected motions.
        Optimal,
    }

    crate::named_enum!(OnlineMethod, "online method", "method" {
        Conventional => "conventional",
        Fixed => "fixed",
        Adaptive => "adaptive",
        Optimal => "optimal",
    });
}
