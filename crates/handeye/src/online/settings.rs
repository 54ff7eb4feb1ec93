//! An online run's settings as a user gives them ([`OnlineSettings`]), and the one set of rules
//! that turns them into an [`OnlineConfig`] and a calibrator: what a setting left out defaults
//! to, the floor of α₀ as a sine or in degrees, β₀'s floor in degrees, an explicit `d_max` in the
//! input's unit whatever it is. Every face gathers its user's settings here and checks none of
//! them itself.

use serde::{Deserialize, Serialize};

use crate::model::camera::Intrinsics;
use crate::model::error::{Error, Result};
use crate::model::findings::Written;
use crate::model::kinematics::Kinematics;
use crate::model::motion::{PosePair, Setup};
use crate::model::pose::Transform;
use crate::model::prior::Prior;
use crate::online::OnlineCalibrator;
use crate::online::select::{AdaptiveParams, Selection};
use crate::track::TrackOptions;

/// The floor of a predicted α₀ (the angle between the axes of A′ and A″), as a user gives it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AlphaMin {
    /// In degrees, in (0, 90].
    Degrees(f64),
    /// As its sine, in (0, 1] (the older form).
    Sine(f64),
}

/// An online run's settings as a user gives them: each left out (`None`) takes the library's
/// default. [`OnlineSettings::config`] applies the rules; [`OnlineSettings::calibrator`] builds
/// the calibrator (on the pixels with `intrinsics`, with the priors and the robot's table).
///
/// # Example
/// ```
/// use handeye::sim::{SimConfig, simulate};
/// use handeye::{AlphaMin, Estimator, Name, OnlineSettings, Record};
/// let settings = OnlineSettings {
///     estimator: Estimator::Accumulate,
///     alpha_min: Some(AlphaMin::Degrees(15.0)),
///     ..OnlineSettings::default()
/// };
/// let mut calibrator = settings.calibrator()?;
/// let series = simulate(&SimConfig::default(), 1, 0); // 200 noisy poses, millimetres
/// let mut reports = 0;
/// for (k, pose) in series.poses.iter().enumerate() {
///     // Named as the input names it, so that a pose held out is told by its line.
///     let name = Name::Line { source: "poses.jsonl", line: k + 1 };
///     let outputs = calibrator.push(Record::pose(pose).named(name))?;
///     for h in &outputs.held_out {
///         println!("held out: {}: {}", h.name, h.why);
///     }
///     reports += usize::from(outputs.report.is_some());
/// }
/// reports += usize::from(calibrator.finish()?.report.is_some());
/// assert!(reports > 0);
/// # Ok::<(), handeye::Error>(())
/// ```
#[derive(Debug, Clone, Default)]
pub struct OnlineSettings {
    /// Mounting of the camera. Default eye-in-hand.
    pub setup: Setup,
    /// Selection policy. Default adaptive.
    pub selection: Selection,
    /// The estimator. Default: the library's ([`Estimator::Paper`]); the faces default to
    /// [`Estimator::Accumulate`].
    pub estimator: Estimator,
    /// Source of rmsR and rmsT. Default residual.
    pub error_source: ErrorSource,
    /// The true X, for [`ErrorSource::Truth`]. Default none.
    pub truth: Option<Transform>,
    /// Also run the optimal method. Default false.
    pub optimal: bool,
    /// N of Eq. (1). Default [`AdaptiveParams::default`]'s.
    pub n_init: Option<usize>,
    /// Candidates tried before the thresholds are relaxed. Default the paper's.
    pub interval: Option<usize>,
    /// Relaxation factor of sin α₀ and β₀. Default the paper's.
    pub relax_down: Option<f64>,
    /// Relaxation factor of d₀. Default the paper's.
    pub relax_up: Option<f64>,
    /// Exploration factor after calibrations 1–3. Default the paper's.
    pub explore: Option<f64>,
    /// Required rotation accuracy rmsRMax. Default the paper's.
    pub rms_r_max: Option<f64>,
    /// Required translation accuracy rmsTMax. Default the paper's.
    pub rms_t_max: Option<f64>,
    /// Floor of a predicted α₀. Default sin 15°.
    pub alpha_min: Option<AlphaMin>,
    /// Floor of a predicted β₀, degrees, in (0, 180]. Default 3°.
    pub beta_min_deg: Option<f64>,
    /// Ceiling of a predicted d₀ in the input's length unit, whatever it is (the unit is then
    /// [`Unit::AsGiven`]). Default: 0.1 m in the `unit`.
    pub d_max: Option<f64>,
    /// Opt-in remedy for thresholds that lock. Default false.
    pub unfreeze: bool,
    /// The input's length unit. Default `Auto`: inferred from the first pose.
    pub unit: Unit,
    /// The accumulating estimator reports at least every N poses. Default
    /// [`TrackOptions::default`]'s.
    pub every: Option<usize>,
    /// It also reports when both uncertainties have shrunk to this fraction. Default
    /// [`TrackOptions::default`]'s.
    pub shrink: Option<f64>,
    /// Least rotation-angle gap (degrees) that marks a pose as an outlier. Default
    /// [`TrackOptions::default`]'s.
    pub outlier_deg: Option<f64>,
    /// The point whose error through X each report gives. Default the mean target position.
    pub point: Option<[f64; 3]>,
    /// The directions in which the input writes its poses. Default: as handeye names them.
    pub written: Written,
    /// The camera's intrinsics: the calibrator is then on the pixels. Default none.
    pub intrinsics: Option<Intrinsics>,
    /// Priors on X's translation for a low-DOF robot. Default none.
    pub priors: Vec<Prior>,
    /// The robot's DH table, for the systematic-error test. Default none.
    pub robot_model: Option<Kinematics>,
}

impl OnlineSettings {
    /// The configuration these settings give: the defaults of what is left out, α₀'s floor as a
    /// sine, β₀'s in radians, an explicit `d_max` as given ([`Unit::AsGiven`]), every range
    /// checked ([`OnlineConfig::validate`]).
    ///
    /// Errors: [`Error::InvalidParameter`] naming the setting out of range.
    pub fn config(&self) -> Result<OnlineConfig> {
        let d = AdaptiveParams::default();
        let tracking = TrackOptions::default();
        let alpha_min = match self.alpha_min {
            None => d.alpha_min,
            Some(AlphaMin::Sine(sine)) => sine,
            Some(AlphaMin::Degrees(degrees)) => {
                if !(degrees > 0.0 && degrees <= 90.0) {
                    return Err(Error::InvalidParameter {
                        name: "alpha_min_deg",
                        message: format!("must be in (0, 90] degrees, got {degrees}"),
                    });
                }
                degrees.to_radians().sin()
            }
        };
        let config = OnlineConfig {
            setup: self.setup,
            selection: self.selection,
            params: AdaptiveParams {
                n_init: self.n_init.unwrap_or(d.n_init),
                interval: self.interval.unwrap_or(d.interval),
                relax_down: self.relax_down.unwrap_or(d.relax_down),
                relax_up: self.relax_up.unwrap_or(d.relax_up),
                explore: self.explore.unwrap_or(d.explore),
                rms_r_max: self.rms_r_max.unwrap_or(d.rms_r_max),
                rms_t_max: self.rms_t_max.unwrap_or(d.rms_t_max),
                alpha_min,
                beta_min: self.beta_min_deg.map_or(d.beta_min, f64::to_radians),
                d_max: self.d_max.unwrap_or(d.d_max),
                unfreeze: self.unfreeze,
            },
            error_source: self.error_source,
            truth: self.truth,
            optimal: self.optimal,
            estimator: self.estimator,
            tracking: TrackOptions {
                every: self.every.unwrap_or(tracking.every),
                shrink: self.shrink.unwrap_or(tracking.shrink),
                outlier_deg: self.outlier_deg.unwrap_or(tracking.outlier_deg),
                point: self.point,
                ..tracking
            },
            // An explicit d_max is in the input's unit whatever it is.
            unit: match self.d_max {
                Some(_) => Unit::AsGiven,
                None => self.unit,
            },
            written: self.written,
        };
        Ok(config)
    }

    /// The calibrator these settings give: on the pixels when `intrinsics` are given, with the
    /// priors and the robot's table.
    ///
    /// Errors: [`OnlineSettings::config`]'s; [`OnlineCalibrator::new`]'s and
    /// [`OnlineCalibrator::on_pixels`]'s (settings that do not apply); a prior or a table the
    /// estimator does not take ([`OnlineCalibrator::with_priors`],
    /// [`OnlineCalibrator::with_robot_model`]).
    pub fn calibrator(self) -> Result<OnlineCalibrator> {
        let config = self.config()?;
        let calibrator = match self.intrinsics {
            Some(camera) => OnlineCalibrator::on_pixels(camera, config)?,
            None => OnlineCalibrator::new(config)?,
        };
        calibrator
            .with_priors(&self.priors)?
            .with_robot_model(self.robot_model)
    }
}

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
    /// The paper's calibrations, or the accumulating estimator in their place. Default `Paper`.
    pub estimator: Estimator,
    /// The accumulating estimator's gates, change test and schedule. Default:
    /// [`TrackOptions::default`].
    pub tracking: TrackOptions,
    /// The input's length unit, which sets `params.d_max` (0.1 m in that unit). Default `Auto`:
    /// inferred from the first pose.
    pub unit: Unit,
    /// The directions in which the input writes its poses (`io::Recording::written`): a
    /// recording's, looked up between named frames, has a misread worded as frame names swapped.
    /// Default: both as handeye names them.
    #[serde(default)]
    pub written: Written,
}

impl OnlineConfig {
    /// Checks every setting's range (the adaptive parameters', the accumulating estimator's), and
    /// that `truth` is given when it is the error source: what [`OnlineCalibrator::new`] checks,
    /// for a calibrator restored from its saved state too.
    pub fn validate(&self) -> Result<()> {
        if self.error_source == ErrorSource::Truth && self.truth.is_none() {
            return Err(Error::InvalidParameter {
                name: "error_source",
                message: "`truth` needs the true X (give a truth file)".to_string(),
            });
        }
        self.params.validate()?;
        self.tracking.validate()
    }
}

/// The length unit of the input, for the one threshold that has a unit (`d_max`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Unit {
    /// Inferred from the first pose whose translations fit a unit: metres when they are 0.05–10,
    /// millimetres when they are 50–10,000 ([`Unit::infer`]).
    #[default]
    Auto,
    /// Metres: `d_max` = 0.1.
    Metre,
    /// Millimetres: `d_max` = 100.
    Millimetre,
    /// `params.d_max` as given, in the input's unit.
    AsGiven,
}

impl Unit {
    /// Metres or millimetres from the size of a pose's translations (the robot's reach and the
    /// camera's distance to the target), or `None` when the size fits neither.
    pub fn infer(pose: &PosePair) -> Option<Self> {
        let size = pose
            .base_from_gripper
            .translation
            .vector
            .norm()
            .max(pose.camera_from_target.translation.vector.norm());
        if (0.05..=10.0).contains(&size) {
            Some(Self::Metre)
        } else if (50.0..=10_000.0).contains(&size) {
            Some(Self::Millimetre)
        } else {
            None
        }
    }

    /// `d_max` in this unit, or `None` for `Auto` and `AsGiven`.
    pub fn d_max(self) -> Option<f64> {
        match self {
            Self::Metre => Some(0.1),
            Self::Millimetre => Some(100.0),
            Self::Auto | Self::AsGiven => None,
        }
    }
}

// The serde names (`metre`, `millimetre`) are older than these and stay, for saved states; they
// parse as aliases.
crate::named_enum!(Unit, "unit", "unit" {
    Auto => "auto",
    Metre => "m" | "metre" | "meter" | "metres" | "meters",
    Millimetre => "mm" | "millimetre" | "millimeter" | "millimetres" | "millimeters",
    AsGiven => "as-given",
});

/// The estimator behind the selection.
///
/// The library's default stays the paper's (its reproduction, `experiment` and `demo` build on
/// it); the command line's `online` defaults to [`Estimator::Accumulate`], the one whose X carries
/// an uncertainty and has passed the readings checks (docs/DECISIONS.md measures both).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Estimator {
    /// The paper: Andreff on the two selected motions of each calibration.
    #[default]
    Paper,
    /// Normal equations over every pair of poses since the last detected change of X, updated in
    /// O(1) per pose and reported on their own schedule (`crate::track`); the paper's
    /// selection does not run beside it.
    Accumulate,
}

crate::named_enum!(ErrorSource, "error source", "error_source" {
    Residual => "residual",
    Truth => "truth",
});

crate::named_enum!(Estimator, "estimator", "estimator" {
    Paper => "paper",
    Accumulate => "accumulate",
});

impl Estimator {
    /// Whether this estimator's X may be published as a transform for others to use (a ROS
    /// file, a publisher line): only an X with an uncertainty, from poses whose readings were
    /// checked. The paper's calibrations have neither (each solves two motions, and their error
    /// measured on the realistic streams is 30–100 times the accumulating estimator's); the
    /// refusal says which estimator gives one.
    pub fn publishable(self) -> Result<()> {
        match self {
            Self::Accumulate => Ok(()),
            Self::Paper => Err(Error::InvalidParameter {
                name: "estimator",
                message: "the paper's estimator gives X without an uncertainty (two motions per calibration, no check of the readings), so it is not published: the accumulating estimator's X carries one (`--estimator accumulate`, the default; `estimator=\"accumulate\"` in Python)".to_string(),
            }),
        }
    }
}
