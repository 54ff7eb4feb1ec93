//! The paper's three experiments (accuracy, adaptability, realtime): every online method and
//! batch solver on each series, errors against the true X.

use std::time::Instant;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::check::quality::errors_against_truth;
use crate::experiment::{Experiment, ExperimentConfig, OnlineMethod};
use crate::model::error::Result;
use crate::model::motion::{Pairing, Setup, motion_pairs};
use crate::online::select::{AdaptiveParams, Selection};
use crate::online::{ErrorSource, OnlineConfig, run_series};
use crate::sim::{SimConfig, SimSeries, simulate};
use crate::solve::{Method, solve};

/// The online methods `experiment` compares (batch solvers come as reference rows).
fn online_methods(experiment: Experiment) -> &'static [OnlineMethod] {
    match experiment {
        Experiment::Accuracy => &[
            OnlineMethod::Conventional,
            OnlineMethod::Fixed,
            OnlineMethod::Adaptive,
        ],
        Experiment::Adaptability => &[
            OnlineMethod::Adaptive,
            OnlineMethod::Fixed,
            OnlineMethod::Conventional,
        ],
        Experiment::Realtime => &[OnlineMethod::Adaptive, OnlineMethod::Optimal],
        Experiment::Tracking | Experiment::Advice => &[],
    }
}

/// The settings a run of the paper's experiments reads off its [`ExperimentConfig`], as its report
/// records them.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MethodsSettings {
    /// Number of series.
    pub series: usize,
    /// Seed of the run; series s uses the generator of (seed, s).
    pub seed: u64,
    /// The simulation (its `poses` is the poses per series).
    pub sim: SimConfig,
    /// Parameters of the adaptive method.
    pub params: AdaptiveParams,
    /// Whether each series was also solved with every batch solver on all its poses.
    pub batch: bool,
}

impl From<&ExperimentConfig> for MethodsSettings {
    fn from(config: &ExperimentConfig) -> Self {
        Self {
            series: config.series,
            seed: config.seed,
            sim: config.sim,
            params: config.params,
            batch: config.batch,
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

/// The outcome of one of the paper's experiments.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MethodsReport {
    /// Which experiment.
    pub experiment: Experiment,
    /// Its settings.
    pub config: MethodsSettings,
    /// One summary per method: the online methods first, then the batch solvers.
    pub methods: Vec<MethodSummary>,
}

impl MethodsReport {
    /// The summary of a method by name.
    pub fn method(&self, name: &str) -> Option<&MethodSummary> {
        self.methods.iter().find(|m| m.method == name)
    }
}

/// Runs `experiment`, calling `progress` after each finished series (from any thread).
pub(crate) fn run(
    experiment: Experiment,
    config: &MethodsSettings,
    progress: impl Fn() + Sync,
) -> Result<MethodsReport> {
    config.params.validate()?;
    let online = online_methods(experiment);
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
    Ok(MethodsReport {
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
    let estimates: Vec<(crate::model::pose::Transform, f64)> = if method == OnlineMethod::Optimal {
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
fn mean_errors(
    estimates: &[(crate::model::pose::Transform, f64)],
    sim: &SimSeries,
) -> SeriesResult {
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
    r.seconds = median(estimates.iter().map(|e| e.1).collect());
    let d = if n == 0 { f64::NAN } else { n as f64 };
    r.rot_fro /= d;
    r.rot_deg /= d;
    r.trans_rel /= d;
    r
}

/// The median of `values` (the mean of the middle two for an even count; NaN when empty).
fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    match values.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => values[n / 2],
        n => 0.5 * (values[n / 2 - 1] + values[n / 2]),
    }
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
    let total: usize = per_series.iter().map(|r| r.calibrations).sum();
    let times: Vec<f64> = per_series
        .iter()
        .map(|r| r.seconds)
        .filter(|t| t.is_finite())
        .collect();
    MethodSummary {
        method,
        batch,
        series: per_series.len(),
        series_with_calibration: with.len(),
        calibrations_mean: total as f64 / per_series.len().max(1) as f64,
        calibrations_median: median(per_series.iter().map(|r| r.calibrations as f64).collect()),
        rot_fro_mean: mean_of(|r| r.rot_fro),
        rot_deg_mean: mean_of(|r| r.rot_deg),
        trans_rel_mean: mean_of(|r| r.trans_rel),
        time_per_calibration_s: median(times),
        per_series,
    }
}
