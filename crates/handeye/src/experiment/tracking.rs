//! The tracking study (beyond the paper): how the running estimates improve with the poses, and
//! how fast a change of X is noticed.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::check::quality::errors_against_truth;
use crate::experiment::{ExperimentConfig, OnlineMethod};
use crate::model::error::Result;
use crate::model::motion::{Pairing, Setup, motion_pairs};
use crate::online::select::{AdaptiveParams, Selection};
use crate::online::{ErrorSource, OnlineConfig};
use crate::sim::{SimConfig, simulate};
use crate::solve::{Method, solve};

/// The settings the tracking study reads off its [`ExperimentConfig`], as its report records them.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrackingSettings {
    /// Series per measurement.
    pub series: usize,
    /// Seed of the run.
    pub seed: u64,
    /// Poses of the accuracy series.
    pub poses: usize,
    /// Errors are recorded every this many poses.
    pub every: usize,
    /// Jumps to detect, (rotation degrees, translation mm).
    pub jumps: Vec<(f64, f64)>,
    /// Poses of the jump series; the jump comes at the middle.
    pub jump_poses: usize,
    /// Parameters of the adaptive selection.
    pub params: AdaptiveParams,
}

impl From<&ExperimentConfig> for TrackingSettings {
    fn from(config: &ExperimentConfig) -> Self {
        Self {
            series: config.series,
            seed: config.seed,
            poses: config.sim.poses,
            every: config.every,
            jumps: config.jumps.clone(),
            jump_poses: config.jump_poses,
            params: config.params,
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

/// The outcome of the tracking study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrackingReport {
    /// Its settings.
    pub config: TrackingSettings,
    /// Error curves: accumulate, adaptive, conventional, batch Andreff on consecutive motions so far.
    pub curves: Vec<TrackingCurve>,
    /// One row per jump size.
    pub detection: Vec<DetectionResult>,
}

/// Runs the tracking study, calling `progress` after each finished series of the error curves.
pub(crate) fn run(config: &TrackingSettings, progress: impl Fn() + Sync) -> Result<TrackingReport> {
    use crate::online::{Estimator, OnlineCalibrator};
    config.params.validate()?;
    let every = config.every;
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
            // The paper's calibrators (their errors against the truth), and the accumulating
            // estimator, its own entry (the selection's settings do not apply to it).
            let paper = |selection| {
                OnlineCalibrator::new(OnlineConfig {
                    selection,
                    params: config.params,
                    estimator: Estimator::Paper,
                    error_source: ErrorSource::Truth,
                    truth: Some(truth),
                    ..OnlineConfig::default()
                })
            };
            let mut acc = OnlineCalibrator::new(OnlineConfig {
                estimator: Estimator::Accumulate,
                ..OnlineConfig::default()
            })?;
            let mut adaptive = paper(Selection::Adaptive)?;
            let mut conventional = paper(Selection::None)?;
            let mut row: Row = vec![Vec::new(); names.len()];
            let (mut last_adaptive, mut last_conventional) = (None, None);
            let err = |x: &crate::model::pose::Transform| {
                let e = errors_against_truth(x, &truth);
                (e.rot_fro, e.trans_rel)
            };
            for (k, p) in sim.poses.iter().enumerate() {
                acc.push(p)?;
                if let Some(e) = adaptive.push(p)?.events.last() {
                    last_adaptive = Some(e.x);
                }
                if let Some(e) = conventional.push(p)?.events.last() {
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
fn detect(
    config: &TrackingSettings,
    rotation_deg: f64,
    translation: f64,
) -> Result<DetectionResult> {
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
