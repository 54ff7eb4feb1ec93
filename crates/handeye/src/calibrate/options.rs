//! How to calibrate: one [`Options`] for every problem and input kind, the [`Problem`] a field
//! (hand–eye with its [`Method`], robot-world with its [`RobotWorldMethod`]), and [`Fix`], what to
//! do about a better reading of the input.

use serde::{Deserialize, Serialize};

use crate::model::error::{Error, Result};
use crate::model::findings::{Reading, Written};
use crate::model::motion::{Pairing, PosePair};
use crate::model::prior::Prior;
use crate::solve::{Method, RobotWorldMethod, TsaiOptions};

/// What to do about a reading of the input that fits far better than the as-given one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Fix {
    /// Refuse with the finding ([`Error::Misread`]).
    #[default]
    Refuse,
    /// Read the input this way (no check); [`Reading::AsGiven`] keeps it as given and turns the
    /// refusal into a warning.
    Read(Reading),
    /// Apply the better reading when one is found, and say so.
    Auto,
}

impl Fix {
    /// Every fix: `refuse`, `auto`, then each [`Reading`] (its name reads the input that way).
    pub const ALL: [Fix; 2 + Reading::ALL.len()] = {
        let mut all = [Fix::Refuse; 2 + Reading::ALL.len()];
        all[1] = Fix::Auto;
        let mut i = 0;
        while i < Reading::ALL.len() {
            all[2 + i] = Fix::Read(Reading::ALL[i]);
            i += 1;
        }
        all
    };

    /// The reading this fix reads the input as, before any check: the named one, else as given.
    pub fn reading(self) -> Reading {
        match self {
            Fix::Read(r) => r,
            Fix::Refuse | Fix::Auto => Reading::AsGiven,
        }
    }

    /// The name on the command line and in the Python bindings: `refuse`, `auto`, or the
    /// reading's name (`as-given`, `robot-inverted`, …).
    pub fn name(self) -> &'static str {
        match self {
            Fix::Refuse => "refuse",
            Fix::Auto => "auto",
            Fix::Read(r) => r.name(),
        }
    }
}

impl crate::model::names::Named for Fix {
    const WHAT: &'static str = "fix";
    const PARAM: &'static str = "fix";
    const ALL: &'static [Self] = &Fix::ALL;

    fn name(self) -> &'static str {
        Fix::name(self)
    }
}

impl std::fmt::Display for Fix {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Fix {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self> {
        <Fix as crate::model::names::Named>::parse_name(s)
    }
}

/// What is calibrated: X alone from the motions between poses (A X = X B), or X and the target's
/// pose together from every pose once (A X = Z B); each with its own methods. On the pixels
/// ([`Input::Pixels`](crate::Input::Pixels)) the method is the fit to the pixels whatever is named
/// here: the input's kind, not a method, chooses it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Problem {
    /// Hand–eye calibration, A X = X B, by a [`Method`] over the pairing's motions.
    HandEye(Method),
    /// Robot-world–hand-eye calibration, A X = Z B, by a [`RobotWorldMethod`]: X and the target's
    /// pose (`base_from_target` eye-in-hand, `gripper_from_target` eye-to-hand).
    RobotWorld(RobotWorldMethod),
}

impl Problem {
    /// The robot-world problem by its default method, [`RobotWorldMethod::Refine`].
    pub const ROBOT_WORLD: Problem = Problem::RobotWorld(RobotWorldMethod::Refine);
}

impl Default for Problem {
    /// Hand–eye by [`Method::Andreff`].
    fn default() -> Self {
        Problem::HandEye(Method::Andreff)
    }
}

impl std::fmt::Display for Problem {
    /// The method's name (`andreff`, `refine`, …), as the command line takes it.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Problem::HandEye(method) => method.fmt(f),
            Problem::RobotWorld(method) => method.fmt(f),
        }
    }
}

impl From<Method> for Problem {
    fn from(method: Method) -> Self {
        Problem::HandEye(method)
    }
}

impl From<RobotWorldMethod> for Problem {
    fn from(method: RobotWorldMethod) -> Self {
        Problem::RobotWorld(method)
    }
}

/// How to calibrate.
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    /// What is calibrated, and by which method. Default hand–eye by [`Method::Andreff`].
    pub problem: Problem,
    /// Which pose pairs become motions (hand–eye; the robot-world problem takes every pose once).
    pub pairing: Pairing,
    /// Tsai's options (with [`Method::Tsai`]).
    pub tsai: TsaiOptions,
    /// Leave out the outlier poses.
    pub reject_outliers: bool,
    /// A pose whose median rotation-angle gap is above this (degrees) is an outlier, whatever the
    /// data's noise level.
    pub outlier_deg: f64,
    /// What to do about a better reading of the input.
    pub fix: Fix,
    /// Bootstrap replicates for the uncertainty (within [`Options::REPLICATES_RANGE`]).
    pub replicates: usize,
    /// How each pose is named in messages (e.g. `file:line`), by input index; `pose i` when
    /// shorter than the input.
    pub pose_names: Vec<String>,
    /// The directions in which the input wrote its poses (`io::PoseSeries::written`, or
    /// [`Written::NAMED`] for poses given as handeye names them), where a quaternion-order reading
    /// undoes the mix-up.
    pub written: Written,
    /// The point (camera frame, input unit) whose error through X `uncertainty.at_point` gives;
    /// `None`: the median target position seen by the camera (per coordinate, over
    /// `camera_from_target`'s translations).
    pub point: Option<[f64; 3]>,
    /// The joint angles of each pose (radians, the robot's joint order), by input index, where the
    /// input gives them: the configuration the systematic-error test orders the poses by, and
    /// the joint it names. Empty: the hand poses order them.
    pub joints: Vec<Vec<f64>>,
    /// The robot's DH table (`--robot-model`), where given with the joint angles: the
    /// systematic-error test then also asks whether the residuals lie along what an error of its
    /// parameters does (`check::identification`). Default none.
    pub robot_model: Option<crate::model::kinematics::Kinematics>,
    /// Priors on components of X's translation (SPEC sec. 9, `--prior`): a low-DOF recording's
    /// free component comes from its prior; a prior on a component the motions determine is
    /// checked against the data (the data's value is kept). Default none.
    pub priors: Vec<Prior>,
    /// Refine the camera's intrinsics with X on the pixels (`--refine-intrinsics`; only with the
    /// calibration on the pixels, refused elsewhere). Default false.
    pub refine_intrinsics: bool,
    /// The uncertainty the user needs (`--goal`): a one-sigma rotation (degrees) and translation
    /// (input unit), as `advise` takes it. An X whose one-sigma uncertainty is above it in either
    /// is not `good` (`Warning::GoalMissed`); the report says whether it is met. Default none.
    pub goal: Option<crate::model::findings::Sizes>,
}

impl Options {
    /// The bootstrap replicates a calibration accepts (`replicates`, for every problem): fewer than 8 give no usable one-sigma, and
    /// more than 100,000 only cost memory and time (each keeps an X).
    pub const REPLICATES_RANGE: std::ops::RangeInclusive<usize> =
        crate::check::uncertainty::REPLICATES_RANGE;

    /// The hand–eye method: the problem's, or for the robot-world problem [`Method::Andreff`]
    /// (the linear solve that judges what the motions determine, whatever the problem).
    pub(crate) fn hand_eye_method(&self) -> Method {
        match self.problem {
            Problem::HandEye(method) => method,
            Problem::RobotWorld(_) => Method::Andreff,
        }
    }

    /// These options with the hand–eye problem by `method`.
    pub(crate) fn with_method(&self, method: Method) -> Options {
        Options {
            problem: Problem::HandEye(method),
            ..self.clone()
        }
    }
}

impl Default for Options {
    fn default() -> Self {
        Self {
            problem: Problem::default(),
            pairing: Pairing::Consecutive,
            tsai: TsaiOptions::default(),
            reject_outliers: false,
            outlier_deg: crate::check::quality::OUTLIER_DEG,
            fix: Fix::Refuse,
            replicates: crate::check::uncertainty::REPLICATES,
            pose_names: Vec::new(),
            written: Written::NAMED,
            point: None,
            joints: Vec::new(),
            robot_model: None,
            priors: Vec::new(),
            refine_intrinsics: false,
            goal: None,
        }
    }
}

/// Refuses `refine_intrinsics` on poses: the intrinsics are refined on the pixels only.
pub(crate) fn not_without_pixels(refine_intrinsics: bool) -> Result<()> {
    if refine_intrinsics {
        return Err(Error::InvalidParameter {
            name: "refine_intrinsics",
            message: "the intrinsics are refined on the pixels only: --method reprojection with a JSON Lines file with `detections` and --intrinsics FILE".into(),
        });
    }
    Ok(())
}

/// The farthest `point` (`--point`) from the camera, in working distances (the median of the
/// camera's translations to the target): a point the camera sees lies within a few of them, and
/// the error there is a first-order image of X's covariance, meaningless a thousand times out.
pub const POINT_WORKING_DISTANCES: f64 = 100.0;

/// A point given to place the uncertainty at is finite and within [`POINT_WORKING_DISTANCES`]
/// working distances of the camera, or refused naming it.
pub(crate) fn check_point(point: Option<[f64; 3]>, poses: &[PosePair]) -> Result<()> {
    let Some(p) = point else {
        return Ok(());
    };
    let refuse = |message: String| {
        Err(Error::InvalidParameter {
            name: "point",
            message,
        })
    };
    if p.iter().any(|c| !c.is_finite()) {
        return refuse(format!("{p:?}: every coordinate must be a finite number"));
    }
    let distance = p[0].hypot(p[1]).hypot(p[2]);
    let working = crate::check::outliers::working_distance(poses);
    if distance.is_nan() || distance > POINT_WORKING_DISTANCES * working {
        return refuse(format!(
            "({:e}, {:e}, {:e}) is {distance:e} from the camera, more than {POINT_WORKING_DISTANCES} times the recording's working distance ({working:.4}, the input's length unit): give a point the camera sees, in the camera frame and the input's unit",
            p[0], p[1], p[2]
        ));
    }
    Ok(())
}

/// Joint angles given are every pose's: one list a pose (or none at all).
pub(crate) fn check_joints(joints: &[Vec<f64>], poses: usize) -> Result<()> {
    if joints.is_empty() || joints.len() == poses {
        return Ok(());
    }
    Err(Error::InvalidParameter {
        name: "joints",
        message: format!(
            "{} lists of joint angles for {poses} poses: give every pose's, in order",
            joints.len()
        ),
    })
}
