//! The paper's simulated experiments (sec. 4.1), as SPEC sec. 6 fixes them: public as
//! [`crate::experiment`], with the advice's closed loop.

use std::time::Instant;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::check::quality::errors_against_truth;
use crate::model::error::Result;
use crate::model::motion::{Pairing, Setup, motion_pairs};
use crate::online::select::{AdaptiveParams, Selection};
use crate::online::{ErrorSource, OnlineConfig, run_series};
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
    pub(crate) fn online_methods(self) -> &'static [OnlineMethod] {
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

crate::named_enum!(Experiment, "experiment", "experiment" {
    Accuracy => "accuracy",
    Adaptability => "adaptability",
    Realtime => "realtime",
});

// The online methods an experiment compares are named in its report (`MethodSummary::method`);
// the enum is crate-internal, public with `internals` for this crate's tests.
#[cfg(feature = "internals")]
pub use methods::OnlineMethod;
#[cfg(not(feature = "internals"))]
use methods::OnlineMethod;

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

/// Settings of the tracking experiment (beyond the paper): how the running estimates improve with
/// the poses, and how fast a change of X is noticed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrackingConfig {
    /// Series per measurement. Default 20.
    pub series: usize,
    /// Seed of the run. Default 1.
    pub seed: u64,
    /// Poses of the accuracy series. Default 200.
    pub poses: usize,
    /// Errors are recorded every this many poses. Default 10.
    pub every: usize,
    /// Jumps to detect, (rotation degrees, translation mm). Default (0.1, 0.5), (0.25, 1.25),
    /// (0.5, 2.5), (1, 5), (2, 10).
    pub jumps: Vec<(f64, f64)>,
    /// Poses of the jump series; the jump comes at the middle. Default 300.
    pub jump_poses: usize,
    /// Parameters of the adaptive selection (`d_max` 100: millimetres).
    pub params: AdaptiveParams,
}

impl Default for TrackingConfig {
    fn default() -> Self {
        Self {
            series: 20,
            seed: 1,
            poses: 200,
            every: 10,
            jumps: vec![
                (0.1, 0.5),
                (0.25, 1.25),
                (0.5, 2.5),
                (1.0, 5.0),
                (2.0, 10.0),
            ],
            jump_poses: 300,
            params: AdaptiveParams {
                d_max: 100.0,
                ..AdaptiveParams::default()
            },
        }
    }
}

/// Mean errors of one estimator after each checkpoint.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrackingCurve {
    /// Estimator name.
    pub method: String,
    /// Pose counts of the checkpoints.
    pub poses: Vec<usize>,
    /// Mean ‖R̂ − R‖_F over the series that have an estimate at that point.
    pub rot_fro: Vec<f64>,
    /// Mean ‖t − t̂‖/‖t‖ likewise.
    pub trans_rel: Vec<f64>,
}

/// Detection of one jump size.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DetectionResult {
    /// Jump rotation, degrees.
    pub rotation_deg: f64,
    /// Jump translation, mm.
    pub translation: f64,
    /// Fraction of series where the jump was detected within 30 poses.
    pub detected_within_30: f64,
    /// Median delay (poses) over the detected series.
    pub median_delay: Option<usize>,
    /// False alarms (declared before the jump) over all series.
    pub false_alarms: usize,
    /// Stationary poses observed (before the jumps) over all series.
    pub stationary_poses: usize,
    /// Mean rotation error (degrees) of the final estimate against the new X.
    pub final_rot_deg: f64,
}

/// The outcome of the tracking experiment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrackingReport {
    /// Its settings.
    pub config: TrackingConfig,
    /// Error curves: accumulate, adaptive, conventional, batch Andreff on consecutive motions so far.
    pub curves: Vec<TrackingCurve>,
    /// One row per jump size.
    pub detection: Vec<DetectionResult>,
}

/// Runs the tracking experiment, calling `progress` after each finished series.
pub fn run_tracking(config: &TrackingConfig, progress: impl Fn() + Sync) -> Result<TrackingReport> {
    use crate::online::{Estimator, OnlineCalibrator};
    config.params.validate()?;
    let every = config.every.max(1);
    let checkpoints: Vec<usize> = (1..=config.poses / every).map(|k| k * every).collect();
    let names = [
        Estimator::Accumulate.name(),
        OnlineMethod::Adaptive.name(),
        OnlineMethod::Conventional.name(),
        "batch andreff (consecutive, so far)",
    ];
    // Per series: for each estimator and checkpoint, the errors (None before the first estimate).
    type Row = Vec<Vec<Option<(f64, f64)>>>;
    let rows: Vec<Row> = (0..config.series)
        .into_par_iter()
        .map(|s| {
            let sim = simulate(
                &SimConfig {
                    poses: config.poses,
                    ..SimConfig::default()
                },
                config.seed,
                s as u64,
            );
            let truth = sim.gripper_from_camera;
            let make = |selection, estimator| {
                OnlineCalibrator::new(OnlineConfig {
                    selection,
                    params: config.params,
                    estimator,
                    error_source: ErrorSource::Truth,
                    truth: Some(truth),
                    ..OnlineConfig::default()
                })
            };
            let mut acc = make(Selection::Adaptive, Estimator::Accumulate)?;
            let mut conventional = make(Selection::None, Estimator::Paper)?;
            let mut row: Row = vec![Vec::new(); names.len()];
            let (mut last_adaptive, mut last_conventional) = (None, None);
            let err = |x: &crate::model::pose::Transform| {
                let e = errors_against_truth(x, &truth);
                (e.rot_fro, e.trans_rel)
            };
            for (k, p) in sim.poses.iter().enumerate() {
                if let Some(e) = acc.push(p)?.last() {
                    last_adaptive = Some(e.x);
                }
                if let Some(e) = conventional.push(p)?.last() {
                    last_conventional = Some(e.x);
                }
                if (k + 1) % every == 0 {
                    let batch = solve(
                        Method::Andreff,
                        &motion_pairs(&sim.poses[..=k], Pairing::Consecutive, Setup::EyeInHand),
                    )
                    .ok()
                    .map(|c| c.x);
                    row[0].push(acc.accumulated().map(|e| err(&e.x)));
                    row[1].push(last_adaptive.as_ref().map(err));
                    row[2].push(last_conventional.as_ref().map(err));
                    row[3].push(batch.as_ref().map(err));
                }
            }
            progress();
            Ok(row)
        })
        .collect::<Result<_>>()?;
    let curves = names
        .iter()
        .enumerate()
        .map(|(m, name)| {
            let mean = |k: usize, f: fn(&(f64, f64)) -> f64| {
                let v: Vec<f64> = rows
                    .iter()
                    .filter_map(|r| r[m][k].as_ref().map(f))
                    .collect();
                if v.is_empty() {
                    f64::NAN
                } else {
                    v.iter().sum::<f64>() / v.len() as f64
                }
            };
            TrackingCurve {
                method: name.to_string(),
                poses: checkpoints.clone(),
                rot_fro: (0..checkpoints.len()).map(|k| mean(k, |e| e.0)).collect(),
                trans_rel: (0..checkpoints.len()).map(|k| mean(k, |e| e.1)).collect(),
            }
        })
        .collect();
    let detection = config
        .jumps
        .iter()
        .map(|&(rotation_deg, translation)| detect(config, rotation_deg, translation))
        .collect::<Result<_>>()?;
    Ok(TrackingReport {
        config: config.clone(),
        curves,
        detection,
    })
}

/// Detection statistics of one jump size.
fn detect(config: &TrackingConfig, rotation_deg: f64, translation: f64) -> Result<DetectionResult> {
    use crate::online::{Estimator, OnlineCalibrator};
    use crate::sim::Jump;
    let at = config.jump_poses / 2;
    let outcomes: Vec<(Option<usize>, usize, f64)> = (0..config.series)
        .into_par_iter()
        .map(|s| {
            let jump = Jump {
                at,
                rotation_deg,
                translation,
            };
            let sim = simulate(
                &SimConfig {
                    poses: config.jump_poses,
                    jump: Some(jump),
                    ..SimConfig::default()
                },
                config.seed ^ 0x7472,
                s as u64,
            );
            let mut c = OnlineCalibrator::new(OnlineConfig {
                params: config.params,
                estimator: Estimator::Accumulate,
                ..OnlineConfig::default()
            })?;
            let (mut delay, mut false_alarms) = (None, 0);
            for p in &sim.poses {
                c.push(p)?;
                // Delay to the confirmation; a change confirmed before the jump is a false alarm.
                if let Some(change) = c.step().and_then(|s| s.change) {
                    if change.confirmed < at {
                        false_alarms += 1;
                    } else if delay.is_none() {
                        delay = Some(change.confirmed - at);
                    }
                }
            }
            let after = sim
                .gripper_from_camera_after
                .unwrap_or(sim.gripper_from_camera);
            let final_deg = c
                .accumulated()
                .map_or(f64::NAN, |e| errors_against_truth(&e.x, &after).rot_deg);
            Ok((delay, false_alarms, final_deg))
        })
        .collect::<Result<_>>()?;
    let mut delays: Vec<usize> = outcomes
        .iter()
        .filter_map(|o| o.0)
        .filter(|d| *d < 30)
        .collect();
    delays.sort_unstable();
    let n = config.series.max(1) as f64;
    Ok(DetectionResult {
        rotation_deg,
        translation,
        detected_within_30: delays.len() as f64 / n,
        median_delay: delays.get(delays.len() / 2).copied(),
        false_alarms: outcomes.iter().map(|o| o.1).sum(),
        stationary_poses: config.series * (at - 1),
        final_rot_deg: outcomes.iter().map(|o| o.2).sum::<f64>() / n,
    })
}

