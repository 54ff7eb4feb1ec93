//! The paper's simulated experiments (sec. 4.1), as SPEC sec. 6 fixes them: Monte-Carlo over
//! simulated series, in parallel, reproducible whatever the number of threads.
//!
//! - [`Experiment::Accuracy`]: 20 series × 200 poses; mean error per series of conventional, fixed
//!   and adaptive (error source: truth), and every batch solver on all poses (Fig. 2).
//! - [`Experiment::Adaptability`]: 100 series × 500 poses; calibrations per series, adaptive vs
//!   fixed (Fig. 3).
//! - [`Experiment::Realtime`]: 50 series × 100 poses; time per calibration and errors, adaptive vs
//!   optimal (Table I).

use std::fmt;
use std::str::FromStr;
use std::time::Instant;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::metrics::errors_against_truth;
use crate::motion::{Pairing, Setup, motion_pairs};
use crate::online::{ErrorSource, OnlineConfig, run_series};
use crate::select::{AdaptiveParams, Selection};
use crate::sim::{SimConfig, SimSeries, simulate};
use crate::solve::{Method, solve};

/// One of the paper's simulated experiments.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Experiment {
    /// Sec. 4.1.1: errors of conventional vs adaptive (Fig. 2).
    Accuracy,
    /// Sec. 4.1.2: calibrations per series, adaptive vs fixed (Fig. 3).
    Adaptability,
    /// Sec. 4.1.3: time and errors, adaptive vs optimal (Table I).
    Realtime,
}

impl Experiment {
    /// All three, in the paper's order.
    pub const ALL: [Experiment; 3] = [
        Experiment::Accuracy,
        Experiment::Adaptability,
        Experiment::Realtime,
    ];

    /// The name used on the command line and in file names.
    pub fn name(self) -> &'static str {
        match self {
            Self::Accuracy => "accuracy",
            Self::Adaptability => "adaptability",
            Self::Realtime => "realtime",
        }
    }

    /// The paper's number of series.
    pub fn default_series(self) -> usize {
        match self {
            Self::Accuracy => 20,
            Self::Adaptability => 100,
            Self::Realtime => 50,
        }
    }

    /// The paper's poses per series.
    pub fn default_poses(self) -> usize {
        match self {
            Self::Accuracy => 200,
            Self::Adaptability => 500,
            Self::Realtime => 100,
        }
    }

    /// The online methods the experiment compares (batch solvers come as reference rows).
    pub fn online_methods(self) -> &'static [OnlineMethod] {
        match self {
            Self::Accuracy => &[
                OnlineMethod::Conventional,
                OnlineMethod::Fixed,
                OnlineMethod::Adaptive,
            ],
            Self::Adaptability => &[
                OnlineMethod::Adaptive,
                OnlineMethod::Fixed,
                OnlineMethod::Conventional,
            ],
            Self::Realtime => &[OnlineMethod::Adaptive, OnlineMethod::Optimal],
        }
    }
}

impl fmt::Display for Experiment {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Experiment {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self> {
        Experiment::ALL
            .into_iter()
            .find(|e| e.name() == s)
            .ok_or_else(|| Error::InvalidParameter {
                name: "experiment",
                message: format!(
                    "unknown experiment `{s}`; one of accuracy, adaptability, realtime"
                ),
            })
    }
}

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

impl OnlineMethod {
    /// The name used in tables.
    pub fn name(self) -> &'static str {
        match self {
            Self::Conventional => "conventional",
            Self::Fixed => "fixed",
            Self::Adaptive => "adaptive",
            Self::Optimal => "optimal",
        }
    }
}

/// Settings of a run; `for_experiment` gives the paper's.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ExperimentConfig {
    /// Number of series.
    pub series: usize,
    /// Seed of the run; series s uses the generator of (seed, s).
    pub seed: u64,
    /// The simulation (its `poses` is the poses per series).
    pub sim: SimConfig,
    /// Parameters of the adaptive method. `d_max` is 100 because the simulation is in millimetres.
    pub params: AdaptiveParams,
    /// Also solve each series with every batch solver on all its poses (reference rows).
    pub batch: bool,
}

impl ExperimentConfig {
    /// The paper's settings for `experiment`, with seed 1.
    pub fn for_experiment(experiment: Experiment) -> Self {
        Self {
            series: experiment.default_series(),
            seed: 1,
            sim: SimConfig {
                poses: experiment.default_poses(),
                ..SimConfig::default()
            },
            params: AdaptiveParams {
                d_max: 100.0,
                ..AdaptiveParams::default()
            },
            batch: true,
        }
    }
}

/// One method on one series.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SeriesResult {
    /// Calibrations made.
    pub calibrations: usize,
    /// Mean ‖R̂ − R‖_F over the calibrations (NaN without any).
    pub rot_fro: f64,
    /// Mean rotation error, degrees.
    pub rot_deg: f64,
    /// Mean ‖t − t̂‖ / ‖t‖.
    pub trans_rel: f64,
    /// Median time of one calibration in this series, seconds (NaN without any). A median, so that
    /// a context switch during one calibration does not dominate.
    pub seconds: f64,
}

/// One method over all series, as the experiment's JSON reports it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MethodSummary {
    /// Method name (an online method or a batch solver).
    pub method: String,
    /// Whether it is a batch solver on all poses (a reference row).
    pub batch: bool,
    /// Number of series.
    pub series: usize,
    /// Series with at least one calibration.
    pub series_with_calibration: usize,
    /// Mean calibrations per series.
    pub calibrations_mean: f64,
    /// Median calibrations per series.
    pub calibrations_median: f64,
    /// Mean over series (with calibrations) of the per-series mean ‖R̂ − R‖_F.
    pub rot_fro_mean: f64,
    /// The same for the rotation error in degrees.
    pub rot_deg_mean: f64,
    /// The same for ‖t − t̂‖ / ‖t‖.
    pub trans_rel_mean: f64,
    /// Median over the series of their median time per calibration, seconds.
    pub time_per_calibration_s: f64,
    /// Per-series results, in series order.
    pub per_series: Vec<SeriesResult>,
}

/// The outcome of an experiment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ExperimentReport {
    /// Which experiment.
    pub experiment: Experiment,
    /// Its settings.
    pub config: ExperimentConfig,
    /// One summary per method: the online methods first, then the batch solvers.
    pub methods: Vec<MethodSummary>,
}

impl ExperimentReport {
    /// The summary of a method by name.
    pub fn method(&self, name: &str) -> Option<&MethodSummary> {
        self.methods.iter().find(|m| m.method == name)
    }
}

/// Runs `experiment`, calling `progress` after each finished series (from any thread).
pub fn run_experiment(
    experiment: Experiment,
    config: &ExperimentConfig,
    progress: impl Fn() + Sync,
) -> Result<ExperimentReport> {
    config.params.validate()?;
    let online = experiment.online_methods();
    let batch: &[Method] = if config.batch { &Method::ALL } else { &[] };
    let rows: Vec<Vec<SeriesResult>> = (0..config.series)
        .into_par_iter()
        .map(|s| {
            let sim = simulate(&config.sim, config.seed, s as u64);
            let mut row: Vec<SeriesResult> = online
                .iter()
                .map(|m| run_online(*m, &sim, &config.params))
                .collect::<Result<_>>()?;
            row.extend(batch.iter().map(|m| run_batch(*m, &sim)));
            progress();
            Ok(row)
        })
        .collect::<Result<_>>()?;
    let names = online
        .iter()
        .map(|m| (m.name().to_string(), false))
        .chain(batch.iter().map(|m| (m.name().to_string(), true)));
    let methods = names
        .enumerate()
        .map(|(k, (method, is_batch))| {
            summarise(method, is_batch, rows.iter().map(|r| r[k]).collect())
        })
        .collect();
    Ok(ExperimentReport {
        experiment,
        config: *config,
        methods,
    })
}

/// One online method on one series, errors against the true X.
fn run_online(
    method: OnlineMethod,
    sim: &SimSeries,
    params: &AdaptiveParams,
) -> Result<SeriesResult> {
    let selection = match method {
        OnlineMethod::Conventional => Selection::None,
        OnlineMethod::Fixed => Selection::Fixed,
        OnlineMethod::Adaptive | OnlineMethod::Optimal => Selection::Adaptive,
    };
    let config = OnlineConfig {
        setup: Setup::EyeInHand,
        selection,
        params: *params,
        error_source: ErrorSource::Truth,
        truth: Some(sim.gripper_from_camera),
        optimal: method == OnlineMethod::Optimal,
        ..OnlineConfig::default()
    };
    let events = run_series(config, &sim.poses)?;
    let estimates: Vec<(crate::Transform, f64)> = if method == OnlineMethod::Optimal {
        events
            .iter()
            .filter_map(|e| e.optimal.map(|o| (o.x, o.seconds)))
            .collect()
    } else {
        events.iter().map(|e| (e.x, e.seconds)).collect()
    };
    Ok(mean_errors(&estimates, sim))
}

/// One batch solver on all consecutive motions of a series.
fn run_batch(method: Method, sim: &SimSeries) -> SeriesResult {
    let started = Instant::now();
    let motions = motion_pairs(&sim.poses, Pairing::Consecutive, Setup::EyeInHand);
    match solve(method, &motions) {
        Ok(c) => mean_errors(&[(c.x, started.elapsed().as_secs_f64())], sim),
        Err(_) => mean_errors(&[], sim),
    }
}

/// Mean errors of a list of estimates (with their times).
fn mean_errors(estimates: &[(crate::Transform, f64)], sim: &SimSeries) -> SeriesResult {
    let n = estimates.len();
    let mut r = SeriesResult {
        calibrations: n,
        rot_fro: 0.0,
        rot_deg: 0.0,
        trans_rel: 0.0,
        seconds: 0.0,
    };
    for (x, _) in estimates {
        let e = errors_against_truth(x, &sim.gripper_from_camera);
        r.rot_fro += e.rot_fro;
        r.rot_deg += e.rot_deg;
        r.trans_rel += e.trans_rel;
    }
    let mut times: Vec<f64> = estimates.iter().map(|e| e.1).collect();
    times.sort_by(f64::total_cmp);
    r.seconds = times.get(times.len() / 2).copied().unwrap_or(f64::NAN);
    let d = if n == 0 { f64::NAN } else { n as f64 };
    r.rot_fro /= d;
    r.rot_deg /= d;
    r.trans_rel /= d;
    r
}

/// Aggregates one method's per-series results.
fn summarise(method: String, batch: bool, per_series: Vec<SeriesResult>) -> MethodSummary {
    let with: Vec<&SeriesResult> = per_series.iter().filter(|r| r.calibrations > 0).collect();
    let mean_of = |f: fn(&SeriesResult) -> f64| {
        if with.is_empty() {
            f64::NAN
        } else {
            with.iter().map(|r| f(r)).sum::<f64>() / with.len() as f64
        }
    };
    let mut counts: Vec<usize> = per_series.iter().map(|r| r.calibrations).collect();
    counts.sort_unstable();
    let total: usize = counts.iter().sum();
    let median = match counts.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => counts[n / 2] as f64,
        n => (counts[n / 2 - 1] + counts[n / 2]) as f64 / 2.0,
    };
    let mut times: Vec<f64> = per_series
        .iter()
        .map(|r| r.seconds)
        .filter(|t| t.is_finite())
        .collect();
    times.sort_by(f64::total_cmp);
    MethodSummary {
        method,
        batch,
        series: per_series.len(),
        series_with_calibration: with.len(),
        calibrations_mean: total as f64 / per_series.len().max(1) as f64,
        calibrations_median: median,
        rot_fro_mean: mean_of(|r| r.rot_fro),
        rot_deg_mean: mean_of(|r| r.rot_deg),
        trans_rel_mean: mean_of(|r| r.trans_rel),
        time_per_calibration_s: times.get(times.len() / 2).copied().unwrap_or(f64::NAN),
        per_series,
    }
}

/// The report as a Markdown table.
pub fn markdown_table(report: &ExperimentReport) -> String {
    let mut out = format!(
        "### {} ({} series × {} poses, seed {})\n\n| method | series with calibration | calibrations (mean / median) | ‖ΔR‖_F | rotation (°) | t_rel | time per calibration (µs) |\n|---|---|---|---|---|---|---|\n",
        report.experiment, report.config.series, report.config.sim.poses, report.config.seed
    );
    for m in &report.methods {
        let name = if m.batch {
            format!("batch `{}` (all poses)", m.method)
        } else {
            format!("**{}**", m.method)
        };
        out += &format!(
            "| {name} | {}/{} | {:.2} / {:.1} | {:.4} | {:.3} | {:.4} | {:.2} |\n",
            m.series_with_calibration,
            m.series,
            m.calibrations_mean,
            m.calibrations_median,
            m.rot_fro_mean,
            m.rot_deg_mean,
            m.trans_rel_mean,
            m.time_per_calibration_s * 1e6
        );
    }
    out
}
