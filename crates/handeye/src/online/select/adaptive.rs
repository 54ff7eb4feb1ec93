//! The paper's adaptive motion selection: the Main Algorithm of sec. 3.1 with the threshold
//! prediction of sec. 3.2 (Algorithms I–III), as SPEC sec. 4.3–4.4 fixes them.

use std::collections::VecDeque;

use serde::{Deserialize, Serialize};

use crate::model::motion::{MotionPair, PosePair, Setup};
use crate::online::select::{
    AdaptiveParams, FirstMotion, InitialStats, Numbered, Selected, Thresholds, axis_sine,
    gripper_motion, regression::Cubic,
};

/// Number of past calibrations the regression of sec. 3.2 looks at.
pub(crate) const RECORDS: usize = 4;

/// What one calibration leaves for the prediction: the thresholds it was selected with and its
/// errors (step 14 of the Main Algorithm).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Record {
    /// Thresholds in force when the pair was accepted.
    pub thresholds: Thresholds,
    /// rmsR of the calibration.
    pub rms_r: f64,
    /// rmsT of the calibration.
    pub rms_t: f64,
}

/// Where the Main Algorithm is.
// The phases live inline (no box): the calibrator's state stays one allocation-free value.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
enum Phase {
    /// Step 1: averaging the first N motions (Eq. (1)); holds the previous pose.
    Initial { previous: Option<PosePair> },
    /// Steps 3–7: searching A' = Q_a⁻¹ Q_i from the anchor a.
    First { anchor: Numbered },
    /// Steps 9–13: searching A'' = Q_i⁻¹ Q_j; `anchor` is a, `first` is A' ending at i.
    Second { anchor: usize, first: FirstMotion },
}

/// The adaptive selector's state: constant in size whatever the length of the stream.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(crate) struct AdaptiveSelector {
    setup: Setup,
    params: AdaptiveParams,
    stats: InitialStats,
    phase: Phase,
    /// (sin α₀, β₀, d₀) in force; meaningful once Eq. (1) has run.
    thresholds: Thresholds,
    /// First candidate of the current search round (`start` of the listing).
    start: usize,
    /// calibNo of the listing.
    calibrations: usize,
    /// The last [`RECORDS`] records, oldest first.
    records: VecDeque<Record>,
}

impl AdaptiveSelector {
    /// A fresh selector.
    pub fn new(setup: Setup, params: AdaptiveParams) -> Self {
        Self {
            setup,
            params,
            stats: InitialStats::default(),
            phase: Phase::Initial { previous: None },
            thresholds: Thresholds {
                sin_alpha: 0.0,
                beta: 0.0,
                d: 0.0,
            },
            start: 0,
            calibrations: 0,
            records: VecDeque::with_capacity(RECORDS),
        }
    }

    /// The thresholds in force, once Eq. (1) has run.
    pub fn thresholds(&self) -> Option<Thresholds> {
        (!matches!(self.phase, Phase::Initial { .. })).then_some(self.thresholds)
    }

    /// Offers the next pose; returns a selected pair when A'' is accepted (step 11).
    pub fn offer(&mut self, number: usize, pose: &PosePair) -> Option<Selected> {
        match self.phase {
            Phase::Initial { previous } => {
                self.initial(number, pose, previous);
                None
            }
            Phase::First { anchor } => {
                self.search_first(anchor, number, pose);
                None
            }
            Phase::Second { anchor, first } => self.search_second(anchor, first, number, pose),
        }
    }

    /// Step 1, Eq. (1): the means over motions A_1..A_N (poses 1..N+1); the anchor of A' is Q_N.
    /// Pose N+1 is also the first candidate i = N+1 of step 2.
    fn initial(&mut self, number: usize, pose: &PosePair, previous: Option<PosePair>) {
        if let Some(previous) = previous {
            self.stats.add(gripper_motion(self.setup, &previous, pose));
        }
        if self.stats.motions() < self.params.n_init {
            self.phase = Phase::Initial {
                previous: Some(*pose),
            };
            return;
        }
        let means = self.stats.means();
        self.thresholds = Thresholds {
            sin_alpha: means.sin_alpha,
            beta: means.beta,
            d: means.d,
        };
        let anchor = Numbered {
            number: number - 1,
            pose: previous.unwrap_or(*pose),
        };
        // Step 2: i ← N + 1, start ← N + 1.
        self.start = number;
        self.phase = Phase::First { anchor };
        self.search_first(anchor, number, pose);
    }

    /// Steps 3–7: test candidate i for A' = Q_a⁻¹ Q_i.
    fn search_first(&mut self, anchor: Numbered, i: usize, pose: &PosePair) {
        let f = gripper_motion(self.setup, &anchor.pose, pose);
        let t = &mut self.thresholds;
        let rotation_ok = f.angle >= t.beta;
        let translation_ok = f.translation_norm <= t.d;
        if rotation_ok && translation_ok {
            // Step 5 → 8: A' found; the search for A'' starts at j = i + 1.
            let first = FirstMotion {
                end: Numbered {
                    number: i,
                    pose: *pose,
                },
                motion: MotionPair::between(self.setup, &anchor.pose, pose),
                features: f,
            };
            self.phase = Phase::Second {
                anchor: anchor.number,
                first,
            };
            self.start = i + 1;
            return;
        }
        // Steps 6–7: after `interval` failed candidates, relax the thresholds that failed.
        if i + 1 - self.start >= self.params.interval {
            if !rotation_ok {
                t.beta *= self.params.relax_down;
            }
            if !translation_ok {
                t.d *= self.params.relax_up;
            }
            self.start = i + 1;
        }
    }

    /// Steps 9–13: test candidate j for A'' = Q_i⁻¹ Q_j.
    fn search_second(
        &mut self,
        anchor: usize,
        first: FirstMotion,
        j: usize,
        pose: &PosePair,
    ) -> Option<Selected> {
        let f = gripper_motion(self.setup, &first.end.pose, pose);
        let t = &mut self.thresholds;
        let axes_ok = axis_sine(&first.features, &f) >= t.sin_alpha;
        let rotation_ok = f.angle >= t.beta;
        let translation_ok = f.translation_norm <= t.d;
        if axes_ok && rotation_ok && translation_ok {
            // Step 14 is the caller's (calibrate, then `record`); steps 16–17: A' ← A'', a ← i,
            // i ← j, and the next search starts at j + 1.
            let second = MotionPair::between(self.setup, &first.end.pose, pose);
            let selected = Selected {
                poses: [anchor, first.end.number, j],
                first: first.motion,
                second,
                thresholds: Some(*t),
            };
            self.phase = Phase::Second {
                anchor: first.end.number,
                first: FirstMotion {
                    end: Numbered {
                        number: j,
                        pose: *pose,
                    },
                    motion: second,
                    features: f,
                },
            };
            self.start = j + 1;
            return Some(selected);
        }
        // Steps 12–13: after `interval` failed candidates, relax each threshold whose own test
        // failed on this candidate (the listing's θ' in step 13 is read as θ'').
        if j + 1 - self.start >= self.params.interval {
            if !axes_ok {
                t.sin_alpha *= self.params.relax_down;
            }
            if !rotation_ok {
                t.beta *= self.params.relax_down;
            }
            if !translation_ok {
                t.d *= self.params.relax_up;
            }
            self.start = j + 1;
        }
        None
    }

    /// Sets d_max (see [`super::Selector::set_d_max`]).
    pub fn set_d_max(&mut self, d_max: f64) {
        self.params.d_max = d_max;
    }

    /// Step 14–15: records the errors of the calibration made from the last selection, then
    /// predicts new thresholds (from the fourth calibration on) or explores (before it).
    pub fn record(&mut self, rms_r: f64, rms_t: f64) {
        self.calibrations += 1;
        if self.records.len() == RECORDS {
            self.records.pop_front();
        }
        self.records.push_back(Record {
            thresholds: self.thresholds,
            rms_r,
            rms_t,
        });
        if self.calibrations >= RECORDS {
            self.predict();
        } else {
            self.explore();
        }
    }

    /// After calibrations 1..3: ask for more (sin α₀, β₀ up, d₀ down) by the `explore` factor.
    fn explore(&mut self) {
        let e = self.params.explore;
        let t = &mut self.thresholds;
        t.sin_alpha = (t.sin_alpha * e).min(1.0);
        t.beta *= e;
        t.d /= e;
    }

    /// Sec. 3.2: new thresholds from the last four records.
    fn predict(&mut self) {
        let mut records = [Record {
            thresholds: self.thresholds,
            rms_r: 0.0,
            rms_t: 0.0,
        }; RECORDS];
        for (slot, r) in records.iter_mut().zip(&self.records) {
            *slot = *r;
        }
        self.thresholds = predict(&records, self.thresholds, &self.params);
    }
}

/// Algorithms I–III (sec. 3.2, SPEC sec. 4.4): the thresholds that follow `current` given the last
/// four records, oldest first.
///
/// x_R = min(mean rmsR, rms_r_max) and x_T = min(mean rmsT, rms_t_max), each metric against its own
/// maximum. I: sin α₀ ← max(alpha_min, min(1, fit(rmsR, sin α₀, x_R))). II: β₀ ←
/// max(beta_min, min(π, (3β₁ + β₂)/4)) with β₁ = fit(rmsR, β₀, x_R), β₂ = fit(rmsT, β₀, x_T).
/// III: d₀ ← min(d_max, fit(rmsT, d₀, x_T)) when positive. A threshold whose fit gives nothing (a
/// singular Eq. (3)) keeps its current value.
pub fn predict(
    records: &[Record; RECORDS],
    current: Thresholds,
    params: &AdaptiveParams,
) -> Thresholds {
    let column = |f: fn(&Record) -> f64| records.map(|r| f(&r));
    let rms_r = column(|r| r.rms_r);
    let rms_t = column(|r| r.rms_t);
    let sin_alpha = column(|r| r.thresholds.sin_alpha);
    let beta = column(|r| r.thresholds.beta);
    let d = column(|r| r.thresholds.d);
    let x_r = mean(&rms_r).min(params.rms_r_max);
    let x_t = mean(&rms_t).min(params.rms_t_max);
    let mut t = current;

    // Eq. (3) once for each x: rmsR serves Algorithms I and II, rmsT II and III.
    let (fit_r, fit_t) = (Cubic::of(&rms_r), Cubic::of(&rms_t));
    let at = |fit: &Option<Cubic>, y: &[f64; RECORDS], x: f64| fit.as_ref()?.at(y, x);
    // Algorithm I: sin α₀ from rmsR.
    if let Some(v) = at(&fit_r, &sin_alpha, x_r) {
        t.sin_alpha = params.alpha_min.max(v.min(1.0));
    }
    // Algorithm II: β₀ from rmsR and rmsT, weighted 3:1.
    if let (Some(b1), Some(b2)) = (at(&fit_r, &beta, x_r), at(&fit_t, &beta, x_t)) {
        t.beta = params
            .beta_min
            .max(((3.0 * b1 + b2) / 4.0).min(std::f64::consts::PI));
    }
    // Algorithm III: d₀ from rmsT.
    if let Some(v) = at(&fit_t, &d, x_t).filter(|v| *v > 0.0) {
        t.d = params.d_max.min(v);
    }
    // The opt-in remedy for lock-in: a threshold whose four records are equal explores instead.
    if params.unfreeze {
        let e = params.explore;
        if all_equal(&sin_alpha) {
            t.sin_alpha = (t.sin_alpha * e).min(1.0);
        }
        if all_equal(&beta) {
            t.beta *= e;
        }
        if all_equal(&d) {
            t.d /= e;
        }
    }
    t
}

/// Mean of the records' values.
fn mean(v: &[f64; RECORDS]) -> f64 {
    v.iter().sum::<f64>() / RECORDS as f64
}

/// True when the four values are equal (the lock-in of SPEC sec. 4.4).
fn all_equal(v: &[f64; RECORDS]) -> bool {
    v.iter().all(|x| *x == v[0])
}
