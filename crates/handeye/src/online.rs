//! The online calibrator: pose pairs in, one at a time; calibration events out as they happen.
//!
//! [`OnlineCalibrator::push`] offers each pose pair to the selection policy ([`crate::select`]);
//! when a pair of motions is selected it solves X with Andreff's method on those two motions,
//! measures rmsR and rmsT with the configured [`ErrorSource`], tells the adaptive policy, and
//! returns an [`Event`]. With `optimal` set it also refines X over the last five selected motions
//! (the paper's "optimal method", sec. 4.1.3). Its state is constant in size, and serialisable
//! (serde) so that a run can be saved and resumed.

use std::collections::VecDeque;
use std::str::FromStr;
use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::accumulate::{ChangeDetector, ChangeOptions, Estimate, PoseAccumulator};
use crate::error::{Error, Result};
use crate::metrics::{errors_against_truth, residual_rms};
use crate::motion::{MotionPair, PosePair, Setup};
use crate::pose::Transform;
use crate::select::{AdaptiveParams, Selected, Selection, Selector, Thresholds};
use crate::solve::{RefineOptions, andreff, refine_from};

/// Number of selected motions the optimal method refines over (sec. 4.1.3).
pub const OPTIMAL_WINDOW: usize = 5;

/// Where rmsR and rmsT come from (SPEC sec. 2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ErrorSource {
    /// Against the true X (simulation): rmsR = ‖R̂ − R‖_F / 3, rmsT = ‖t − t̂‖ / ‖t‖.
    Truth,
    /// The A X − X B residuals of the two motions used (real data; the paper's sec. 4.2).
    #[default]
    Residual,
}

/// Settings of an online run; `Default` is eye-in-hand, adaptive, residual errors, no optimal.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct OnlineConfig {
    /// Mounting of the camera. Default eye-in-hand.
    pub setup: Setup,
    /// Selection policy. Default adaptive.
    pub selection: Selection,
    /// Parameters of the adaptive (and, for `n_init`, the fixed) policy. Default: the paper's.
    pub params: AdaptiveParams,
    /// Source of rmsR and rmsT. Default residual.
    pub error_source: ErrorSource,
    /// The true X (`gripper_from_camera`, or `base_from_camera` for eye-to-hand); required by
    /// [`ErrorSource::Truth`]. Default none.
    pub truth: Option<Transform>,
    /// Also run the optimal method (sec. 4.5). Default false.
    pub optimal: bool,
    /// Which estimate events carry besides the paper's two-motion X. Default `Paper` (none).
    pub estimator: Estimator,
    /// The change detector of the accumulating estimator. Default: [`ChangeOptions::default`].
    pub change: ChangeOptions,
}

/// The estimator behind the selection.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Estimator {
    /// The paper: Andreff on the two selected motions of each calibration.
    #[default]
    Paper,
    /// Normal equations over every pair of poses since the last detected change of X, updated in
    /// O(1) per pose ([`crate::accumulate`]); the selection policy still decides when events are
    /// emitted, but every pose contributes.
    Accumulate,
}

impl ErrorSource {
    /// The name used on the command line and in the Python bindings.
    pub fn name(self) -> &'static str {
        match self {
            Self::Truth => "truth",
            Self::Residual => "residual",
        }
    }
}

impl FromStr for ErrorSource {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self> {
        [Self::Residual, Self::Truth]
            .into_iter()
            .find(|e| e.name() == s)
            .ok_or_else(|| Error::InvalidParameter {
                name: "error_source",
                message: format!("unknown error source `{s}`; residual or truth"),
            })
    }
}

impl Estimator {
    /// The name used on the command line and in the Python bindings.
    pub fn name(self) -> &'static str {
        match self {
            Self::Paper => "paper",
            Self::Accumulate => "accumulate",
        }
    }
}

impl FromStr for Estimator {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self> {
        [Self::Paper, Self::Accumulate]
            .into_iter()
            .find(|e| e.name() == s)
            .ok_or_else(|| Error::InvalidParameter {
                name: "estimator",
                message: format!("unknown estimator `{s}`; paper or accumulate"),
            })
    }
}

/// The accumulating estimator's X at one calibration.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct AccumulatedEstimate {
    /// X from every pair of poses since the start or the last change.
    pub x: Transform,
    /// Poses it rests on.
    pub poses: usize,
    /// Conditioning of its rotation system.
    pub conditioning: f64,
    /// RMS residual of the tested motions under X so far: rotation in degrees, translation in
    /// input units.
    pub noise: [f64; 2],
    /// Uncertainty of X, as the expected size of its error: rotation in degrees, translation in
    /// input units. Split-half estimate: the poses are dealt alternately to two more accumulators,
    /// and half the difference of their estimates has the distribution of the full estimate's
    /// error. `None` until both halves have an estimate.
    pub uncertainty: Option<[f64; 2]>,
    /// Pose number of the last declared change of X (accumulation restarted there), if any.
    pub change_at: Option<usize>,
}

/// Poses between refreshes of the accumulated X used by the change detector.
const REFRESH: usize = 10;

/// rmsR and rmsT of a calibration, from the configured [`ErrorSource`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Rms {
    /// rmsR.
    pub rms_r: f64,
    /// rmsT.
    pub rms_t: f64,
}

/// The optimal method's estimate at one calibration (SPEC sec. 4.5).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct OptimalEstimate {
    /// Number of this optimal result (1 at the first calibration with five selected motions).
    pub number: usize,
    /// X refined over the last five selected motions.
    pub x: Transform,
    /// The five motions as pose-number pairs, oldest first.
    pub motions: [[usize; 2]; OPTIMAL_WINDOW],
    /// Wall time of the refinement, including its Andreff start, seconds.
    pub seconds: f64,
}

/// One calibration of an online run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Event {
    /// Number of this calibration (1, 2, …).
    pub calibration: usize,
    /// Pose numbers (a, i, j) of A' = Q_a⁻¹ Q_i and A'' = Q_i⁻¹ Q_j.
    pub poses: [usize; 3],
    /// Thresholds in force when the pair was accepted (adaptive only).
    pub thresholds: Option<Thresholds>,
    /// X from Andreff's method on (A', A'').
    pub x: Transform,
    /// rmsR and rmsT of X from the error source.
    pub rms: Rms,
    /// Conditioning of the two-motion rotation system.
    pub conditioning: f64,
    /// Wall time of the calibration (solve, errors, threshold update), seconds.
    pub seconds: f64,
    /// The optimal method's X, when enabled and five motions have been selected.
    pub optimal: Option<OptimalEstimate>,
    /// The accumulating estimator's X, with `Estimator::Accumulate`.
    pub accumulated: Option<AccumulatedEstimate>,
}

/// The online calibrator (see the module documentation).
///
/// # Example
/// ```
/// use handeye::online::{OnlineCalibrator, OnlineConfig};
/// use handeye::{PosePair, Transform};
/// let mut calibrator = OnlineCalibrator::new(OnlineConfig::default())?;
/// let still = PosePair { base_from_gripper: Transform::identity(), camera_from_target: Transform::identity() };
/// // A robot that never moves gives no calibration.
/// for _ in 0..20 {
///     assert!(calibrator.push(&still)?.is_empty());
/// }
/// assert_eq!(calibrator.poses(), 20);
/// # Ok::<(), handeye::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OnlineCalibrator {
    config: OnlineConfig,
    selector: Selector,
    poses: usize,
    calibrations: usize,
    /// Selections that Andreff refused as degenerate.
    refused: usize,
    /// The last selected motions with their pose numbers (optimal method only).
    window: VecDeque<([usize; 2], MotionPair)>,
    optimal_results: usize,
    last_x: Option<Transform>,
    accumulator: PoseAccumulator,
    /// Even- and odd-numbered poses apart, for the split-half uncertainty.
    halves: [PoseAccumulator; 2],
    detector: ChangeDetector,
    /// The last `lag` poses and the accumulated X last refreshed (accumulate estimator).
    recent: VecDeque<PosePair>,
    current: Option<Estimate>,
    last_change: Option<usize>,
}

impl OnlineCalibrator {
    /// A calibrator for `config`; errors on invalid parameters or `Truth` without a truth.
    pub fn new(config: OnlineConfig) -> Result<Self> {
        if config.error_source == ErrorSource::Truth && config.truth.is_none() {
            return Err(Error::InvalidParameter {
                name: "error_source",
                message: "`truth` needs the true X (give a truth file)".to_string(),
            });
        }
        Ok(Self {
            selector: Selector::new(config.selection, config.setup, config.params)?,
            config,
            poses: 0,
            calibrations: 0,
            refused: 0,
            window: VecDeque::with_capacity(OPTIMAL_WINDOW + 1),
            optimal_results: 0,
            last_x: None,
            accumulator: PoseAccumulator::new(config.setup),
            halves: [
                PoseAccumulator::new(config.setup),
                PoseAccumulator::new(config.setup),
            ],
            detector: ChangeDetector::new(config.change),
            recent: VecDeque::with_capacity(config.change.lag + 1),
            current: None,
            last_change: None,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &OnlineConfig {
        &self.config
    }

    /// Poses pushed so far.
    pub fn poses(&self) -> usize {
        self.poses
    }

    /// Calibrations made so far.
    pub fn calibrations(&self) -> usize {
        self.calibrations
    }

    /// Selected pairs that Andreff refused as degenerate (no event was emitted for them).
    pub fn refused(&self) -> usize {
        self.refused
    }

    /// The latest X, if any calibration happened.
    pub fn last_x(&self) -> Option<Transform> {
        self.last_x
    }

    /// The adaptive thresholds in force now.
    pub fn thresholds(&self) -> Option<Thresholds> {
        self.selector.thresholds()
    }

    /// Pushes the next pose pair; returns the calibrations it completes (usually none, at most one
    /// except at the end of the fixed method's initial window). A pose with a non-finite entry is
    /// refused with an error and leaves the state untouched.
    pub fn push(&mut self, pose: &PosePair) -> Result<Vec<Event>> {
        check_finite(pose)?;
        self.poses += 1;
        if self.config.estimator == Estimator::Accumulate {
            self.update_accumulator(pose);
        }
        let selections = self.selector.offer(self.poses, pose);
        Ok(selections
            .into_iter()
            .filter_map(|s| self.calibrate(&s))
            .collect())
    }

    /// Step 14 of the Main Algorithm: Andreff on (A', A''), the errors, the threshold update.
    fn calibrate(&mut self, selected: &Selected) -> Option<Event> {
        let started = Instant::now();
        let pair = [selected.first, selected.second];
        let Ok(calibration) = andreff(&pair) else {
            self.refused += 1;
            return None;
        };
        let x = calibration.x;
        let rms = self.errors(&pair, &x);
        self.selector.record(rms.rms_r, rms.rms_t);
        let seconds = started.elapsed().as_secs_f64();
        self.calibrations += 1;
        self.last_x = Some(x);
        let optimal = self
            .config
            .optimal
            .then(|| self.optimal(selected))
            .flatten();
        let accumulated = (self.config.estimator == Estimator::Accumulate)
            .then(|| self.accumulate())
            .flatten();
        Some(Event {
            calibration: self.calibrations,
            poses: selected.poses,
            thresholds: selected.thresholds,
            x,
            rms,
            conditioning: calibration.conditioning,
            seconds,
            optimal,
            accumulated,
        })
    }

    /// The accumulating estimator, per pose: test the motion from the pose `lag` poses earlier
    /// against the current X (CUSUM on its residual), restart after a change, add the pose.
    fn update_accumulator(&mut self, pose: &PosePair) {
        if self.recent.len() == self.config.change.lag.max(1)
            && let (Some(earlier), Some(current)) = (self.recent.front(), self.current)
        {
            let m = MotionPair::between(self.config.setup, earlier, pose);
            if self.detector.observe(&m, &current.x) {
                self.accumulator.reset();
                self.halves.iter_mut().for_each(PoseAccumulator::reset);
                self.recent.clear();
                self.current = None;
                self.last_change = Some(self.poses);
            }
        }
        self.accumulator.add(pose);
        self.halves[self.accumulator.poses() % 2].add(pose);
        if self.recent.len() == self.config.change.lag.max(1) {
            self.recent.pop_front();
        }
        self.recent.push_back(*pose);
        if self.current.is_none() || self.accumulator.poses() % REFRESH == 0 {
            self.current = self.accumulator.estimate();
        }
    }

    /// The accumulated estimate now, for an event.
    fn accumulate(&mut self) -> Option<AccumulatedEstimate> {
        let estimate = self.accumulator.estimate()?;
        self.current = Some(estimate);
        let (noise_r, noise_t) = self.detector.noise_level();
        let uncertainty = match (self.halves[0].estimate(), self.halves[1].estimate()) {
            (Some(a), Some(b)) => Some([
                0.5 * crate::pose::rotation_angle_between(&a.x.rotation, &b.x.rotation)
                    .to_degrees(),
                0.5 * (a.x.translation.vector - b.x.translation.vector).norm(),
            ]),
            _ => None,
        };
        Some(AccumulatedEstimate {
            x: estimate.x,
            poses: estimate.poses,
            conditioning: estimate.conditioning,
            noise: [noise_r.to_degrees(), noise_t],
            uncertainty,
            change_at: self.last_change,
        })
    }

    /// The accumulating estimator's current X (every pair of poses since the last change), at
    /// any time; `None` before three poses or with the paper's estimator.
    pub fn accumulated(&self) -> Option<Estimate> {
        (self.config.estimator == Estimator::Accumulate)
            .then(|| self.accumulator.estimate())
            .flatten()
    }

    /// The pose number of a change of X declared by the last `push`, if it declared one.
    pub fn change_detected(&self) -> Option<usize> {
        self.last_change.filter(|&pose| pose == self.poses)
    }

    /// rmsR and rmsT of `x` from the configured source.
    fn errors(&self, pair: &[MotionPair; 2], x: &Transform) -> Rms {
        match (self.config.error_source, self.config.truth) {
            (ErrorSource::Truth, Some(truth)) => {
                let e = errors_against_truth(x, &truth);
                Rms {
                    rms_r: e.rms_r(),
                    rms_t: e.rms_t(),
                }
            }
            _ => {
                let r = residual_rms(pair, x);
                Rms {
                    rms_r: r.rms_r,
                    rms_t: r.rms_t,
                }
            }
        }
    }

    /// Sec. 4.5: once five motions have been selected (the first A' and every accepted A''),
    /// refine over the last five, started from Andreff on them.
    fn optimal(&mut self, selected: &Selected) -> Option<OptimalEstimate> {
        let [a, i, j] = selected.poses;
        if self.window.is_empty() {
            self.window.push_back(([a, i], selected.first));
        }
        self.window.push_back(([i, j], selected.second));
        while self.window.len() > OPTIMAL_WINDOW {
            self.window.pop_front();
        }
        if self.window.len() < OPTIMAL_WINDOW {
            return None;
        }
        let started = Instant::now();
        let mut motions = [selected.first; OPTIMAL_WINDOW];
        let mut numbers = [[0; 2]; OPTIMAL_WINDOW];
        for (k, (n, m)) in self.window.iter().enumerate() {
            motions[k] = *m;
            numbers[k] = *n;
        }
        let start = andreff(&motions).ok()?;
        let refined = refine_from(&motions, &start.x, &RefineOptions::default()).ok()?;
        self.optimal_results += 1;
        Some(OptimalEstimate {
            number: self.optimal_results,
            x: refined.calibration.x,
            motions: numbers,
            seconds: started.elapsed().as_secs_f64(),
        })
    }
}

/// Refuses a pose pair with a NaN or infinite entry.
fn check_finite(pose: &PosePair) -> Result<()> {
    let finite = |t: &Transform| {
        t.translation
            .vector
            .iter()
            .chain(t.rotation.matrix().iter())
            .all(|v| v.is_finite())
    };
    for (what, t) in [
        ("base_from_gripper", &pose.base_from_gripper),
        ("camera_from_target", &pose.camera_from_target),
    ] {
        if !finite(t) {
            return Err(Error::InvalidTransform {
                what: what.to_string(),
                problem: crate::error::TransformProblem::NotFinite,
            });
        }
    }
    Ok(())
}

/// Convenience for whole series: pushes every pose and collects all events.
pub fn run_series(config: OnlineConfig, poses: &[PosePair]) -> Result<Vec<Event>> {
    let mut calibrator = OnlineCalibrator::new(config)?;
    let mut events = Vec::new();
    for p in poses {
        events.extend(calibrator.push(p)?);
    }
    Ok(events)
}
