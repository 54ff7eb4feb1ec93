//! Motion selection for online calibration: which consecutive motions to combine into the pair
//! (A', A'') that the next calibration uses.
//!
//! Three policies ([`Selection`]): `none`, the conventional method (SPEC sec. 4.1); `fixed`, Shi et
//! al.'s thresholds from the first motions (sec. 4.2); `adaptive`, the paper's Main Algorithm with
//! the threshold prediction of Algorithms I–III (sec. 4.3, 4.4). A selector sees one pose at a time
//! (a selector's `offer`) and answers with the selected motion pairs; the adaptive one then learns
//! the errors of the calibration made from them (a selector's `record`).

mod adaptive;
mod conventional;
mod fixed;
mod regression;

use serde::{Deserialize, Serialize};

pub(crate) use adaptive::AdaptiveSelector;
pub use adaptive::{Record, predict};
pub(crate) use conventional::ConventionalSelector;
pub(crate) use fixed::FixedSelector;
pub use regression::{fit, fit_condition};

use crate::model::error::{Error, Result};
use crate::model::motion::{MotionFeatures, MotionPair, PosePair, Setup};

/// Which selection policy runs in front of the solver.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Selection {
    /// No selection: Andreff on every two consecutive motions (the conventional method, sec. 4.1).
    None,
    /// Shi et al.'s fixed thresholds from the first `n_init` motions (sec. 4.2).
    Fixed,
    /// The paper's adaptive thresholds (sec. 4.3–4.4).
    #[default]
    Adaptive,
}

crate::named_enum!(Selection, "selection", "selection" {
    None => "none" | "conventional",
    Fixed => "fixed",
    Adaptive => "adaptive",
});

/// The adaptive method's thresholds (sin α₀, β₀, d₀).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Thresholds {
    /// sin α₀: the least sine of the angle between the axes of A' and A''.
    pub sin_alpha: f64,
    /// β₀: the least rotation angle of a selected motion, radians.
    pub beta: f64,
    /// d₀: the largest translation of a selected motion, input length units.
    pub d: f64,
}

/// The largest `n_init` accepted: far beyond any use (the paper's is 5), small enough that the
/// poses buffered before the first thresholds stay a few hundred megabytes at worst.
pub const MAX_N_INIT: usize = 1_000_000;

/// Parameters of the adaptive method (SPEC sec. 4.3); `Default` gives the paper's values, listed on
/// each field. Lengths are in the input's unit: the default `d_max` assumes metres.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct AdaptiveParams {
    /// N of Eq. (1): motions averaged for the initial thresholds. Default 5.
    pub n_init: usize,
    /// Candidates tried before the thresholds are relaxed. Default 5.
    pub interval: usize,
    /// Factor on sin α₀ and β₀ when relaxing, in [`AdaptiveParams::RELAX_DOWN`]. Default 0.9.
    pub relax_down: f64,
    /// Factor on d₀ when relaxing, in [`AdaptiveParams::RELAX_UP`]. Default 1.1.
    pub relax_up: f64,
    /// After calibrations 1..3: sin α₀ ← min(1, sin α₀·explore), β₀ ← β₀·explore,
    /// d₀ ← d₀/explore; in [`AdaptiveParams::EXPLORE`]. Default 1.1.
    pub explore: f64,
    /// rmsRMax, the required rotation accuracy. Default 0.001.
    pub rms_r_max: f64,
    /// rmsTMax, the required translation accuracy. Default 0.05.
    pub rms_t_max: f64,
    /// alphaMin: floor of a predicted sin α₀. Default sin 15°.
    pub alpha_min: f64,
    /// betaMin: floor of a predicted β₀, radians. Default 3°.
    pub beta_min: f64,
    /// dMax: ceiling of a predicted d₀, input length units. Default 0.1 (metres).
    pub d_max: f64,
    /// Opt-in remedy for the lock-in of sec. 4.4: when the four recorded values of a threshold are
    /// equal, the regression returns that constant and the threshold freezes for good; with
    /// `unfreeze` such a threshold takes an `explore` step instead. Default `false` (the paper).
    pub unfreeze: bool,
}

impl Default for AdaptiveParams {
    fn default() -> Self {
        Self {
            n_init: 5,
            interval: 5,
            relax_down: 0.9,
            relax_up: 1.1,
            explore: 1.1,
            rms_r_max: 0.001,
            rms_t_max: 0.05,
            alpha_min: 15f64.to_radians().sin(),
            beta_min: 3f64.to_radians(),
            d_max: 0.1,
            unfreeze: false,
        }
    }
}

impl AdaptiveParams {
    /// The range of `relax_down`: a tenth at most per relaxation, so that the thresholds step
    /// down rather than vanish (`1e-320` made β₀ a subnormal number after one step).
    pub const RELAX_DOWN: (f64, f64) = (0.1, 1.0);
    /// The range of `relax_up`: ten times at most per relaxation (`1e308` made d₀ infinite, and
    /// every event's `"d"` null).
    pub const RELAX_UP: (f64, f64) = (1.0, 10.0);
    /// The range of `explore`: each of the first three calibrations changes the thresholds ten
    /// times at most (`1e-320` made d₀ infinite).
    pub const EXPLORE: (f64, f64) = (0.1, 10.0);
    /// The largest `n_init` accepted: far beyond any use (the paper's is 5), small enough that
    /// the poses buffered before the first thresholds stay a few hundred megabytes at worst.
    pub const MAX_N_INIT: usize = MAX_N_INIT;

    /// Checks every parameter's range.
    pub fn validate(&self) -> Result<()> {
        let bad = |name: &'static str, message: &str| {
            Err(Error::InvalidParameter {
                name,
                message: message.to_string(),
            })
        };
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if self.n_init < 2 {
            return bad(
                "n_init",
                "must be at least 2 (Eq. (1) averages the angle between consecutive axes)",
            );
        }
        if self.n_init > MAX_N_INIT {
            return bad(
                "n_init",
                &format!("must be at most {MAX_N_INIT} (got {})", self.n_init),
            );
        }
        if self.interval < 1 {
            return bad("interval", "must be at least 1");
        }
        for (name, v, (low, high)) in [
            ("relax_down", self.relax_down, Self::RELAX_DOWN),
            ("relax_up", self.relax_up, Self::RELAX_UP),
            ("explore", self.explore, Self::EXPLORE),
        ] {
            if !(low..=high).contains(&v) {
                return bad(
                    name,
                    &format!("must be in [{low}, {high}] (a factor per step), got {v:e}"),
                );
            }
        }
        for (name, v) in [
            ("rms_r_max", self.rms_r_max),
            ("rms_t_max", self.rms_t_max),
            ("beta_min", self.beta_min),
            ("d_max", self.d_max),
        ] {
            if !positive(v) {
                return bad(name, "must be positive");
            }
        }
        if !(positive(self.alpha_min) && self.alpha_min <= 1.0) {
            return bad("alpha_min", "must be in (0, 1] (it is a sine)");
        }
        Ok(())
    }
}

/// A pair of motions chosen for one calibration.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub(crate) struct Selected {
    /// Pose numbers (a, i, j), from 1: A' = Q_a⁻¹ Q_i and A'' = Q_i⁻¹ Q_j.
    pub poses: [usize; 3],
    /// (A', B').
    pub first: MotionPair,
    /// (A'', B'').
    pub second: MotionPair,
    /// Thresholds in force when the pair was accepted (adaptive only).
    pub thresholds: Option<Thresholds>,
}

/// A pose with its number in the stream (from 1).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub(crate) struct Numbered {
    pub number: usize,
    pub pose: PosePair,
}

/// The current A' of a selector: the pose i it ends at, the motion pair and its features.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub(crate) struct FirstMotion {
    pub end: Numbered,
    pub motion: MotionPair,
    pub features: MotionFeatures,
}

/// Running sums of Eq. (1) over the first motions: θ, ‖t‖, and the angle between consecutive axes
/// (both the angle, for the fixed method, and its sine, for the adaptive one).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub(crate) struct InitialStats {
    motions: usize,
    sum_angle: f64,
    sum_translation: f64,
    sum_axis_angle: f64,
    sum_axis_sine: f64,
    previous: Option<MotionFeatures>,
}

/// Eq. (1)'s means.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct InitialMeans {
    /// Mean θ_n.
    pub beta: f64,
    /// Mean ‖t_a,n‖.
    pub d: f64,
    /// Mean ∠(k_n, k_{n+1}).
    pub alpha: f64,
    /// Mean sin ∠(k_n, k_{n+1}).
    pub sin_alpha: f64,
}

impl InitialStats {
    /// Adds motion A_n's features.
    pub fn add(&mut self, f: MotionFeatures) {
        self.motions += 1;
        self.sum_angle += f.angle;
        self.sum_translation += f.translation_norm;
        if let Some(prev) = self.previous {
            self.sum_axis_angle += prev.axis_angle_to(&f);
            self.sum_axis_sine += axis_sine(&prev, &f);
        }
        self.previous = Some(f);
    }

    /// Number of motions added.
    pub fn motions(&self) -> usize {
        self.motions
    }

    /// The means of Eq. (1) (needs at least two motions).
    pub fn means(&self) -> InitialMeans {
        let n = self.motions as f64;
        let pairs = (self.motions.saturating_sub(1)).max(1) as f64;
        InitialMeans {
            beta: self.sum_angle / n,
            d: self.sum_translation / n,
            alpha: self.sum_axis_angle / pairs,
            sin_alpha: self.sum_axis_sine / pairs,
        }
    }
}

/// sin ∠(k₁, k₂) = ‖k₁ × k₂‖, 0 when either axis is undefined (SPEC sec. 1).
pub(crate) fn axis_sine(a: &MotionFeatures, b: &MotionFeatures) -> f64 {
    match (&a.axis, &b.axis) {
        (Some(k1), Some(k2)) => k1.cross(k2).norm().min(1.0),
        _ => 0.0,
    }
}

/// The gripper motion A = Q_from⁻¹ Q_to alone (the selection rules look at A only).
pub(crate) fn gripper_motion(setup: Setup, from: &PosePair, to: &PosePair) -> MotionFeatures {
    let q_from = setup.hand_pose(&from.base_from_gripper);
    let q_to = setup.hand_pose(&to.base_from_gripper);
    MotionFeatures::of(&(q_from.inverse() * q_to))
}

/// One of the three selection policies, with its state.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub(crate) enum Selector {
    /// The conventional method.
    None(ConventionalSelector),
    /// Fixed thresholds.
    Fixed(FixedSelector),
    /// Adaptive thresholds.
    Adaptive(AdaptiveSelector),
}

impl Selector {
    /// A fresh selector of the given policy.
    pub fn new(selection: Selection, setup: Setup, params: AdaptiveParams) -> Result<Self> {
        params.validate()?;
        Ok(match selection {
            Selection::None => Self::None(ConventionalSelector::new(setup)),
            Selection::Fixed => Self::Fixed(FixedSelector::new(setup, params.n_init)),
            Selection::Adaptive => Self::Adaptive(AdaptiveSelector::new(setup, params)),
        })
    }

    /// Offers pose number `number` (from 1, one more than the last offered). Returns the motion pairs
    /// selected with it: none, usually; one when a calibration is due; for `fixed`, possibly more at
    /// the end of its initial window, when the buffered poses are searched at once.
    pub fn offer(&mut self, number: usize, pose: &PosePair) -> Vec<Selected> {
        match self {
            Self::None(s) => s.offer(number, pose).into_iter().collect(),
            Self::Fixed(s) => s.offer(number, pose),
            Self::Adaptive(s) => s.offer(number, pose).into_iter().collect(),
        }
    }

    /// Sets d_max, the one length parameter (the ceiling of a predicted d₀), once the input's unit
    /// is known. Only the adaptive policy uses it, and only after its first regression.
    pub fn set_d_max(&mut self, d_max: f64) {
        if let Self::Adaptive(s) = self {
            s.set_d_max(d_max);
        }
    }

    /// Tells the selector the errors (rmsR, rmsT) of the calibration made from its last selection.
    /// Only the adaptive policy uses them.
    pub fn record(&mut self, rms_r: f64, rms_t: f64) {
        if let Self::Adaptive(s) = self {
            s.record(rms_r, rms_t);
        }
    }

    /// The adaptive thresholds in force now (None for the other policies, and before Eq. (1)).
    pub fn thresholds(&self) -> Option<Thresholds> {
        match self {
            Self::Adaptive(s) => s.thresholds(),
            _ => None,
        }
    }
}
