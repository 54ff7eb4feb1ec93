//! Priors on X's translation: what a user measured with a ruler, for the direction a low-DOF
//! robot's motions leave free (SPEC sec. 9: `--prior NAME=VALUE[+-SIGMA]`).
//!
//! A SCARA or 4-axis robot rotates only about one axis, so its motions never determine X's
//! translation along that axis (A X = X B's translation part, (R_A − I) t_X = R_X t_B − t_A, has
//! R_A − I singular along the axis for every motion). The user states that component instead.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::model::error::{Error, Result};
use crate::model::motion::Setup;

/// A prior on a coordinate component of X's translation can state the free direction of a
/// low-DOF robot only when that direction is within this many degrees of the coordinate axis.
pub const PRIOR_AXIS_DEG: f64 = 5.0;

/// A component of X's translation, in X's parent frame (the gripper's eye-in-hand, the robot
/// base's eye-to-hand).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Component {
    /// t_x.
    Tx,
    /// t_y.
    Ty,
    /// t_z.
    Tz,
}

crate::named_enum!(Component, "prior component", "prior" {
    Tx => "tx",
    Ty => "ty",
    Tz => "tz",
});

impl Component {
    /// The coordinate index (0, 1, 2).
    pub fn index(self) -> usize {
        match self {
            Self::Tx => 0,
            Self::Ty => 1,
            Self::Tz => 2,
        }
    }

    /// The component along coordinate axis `i` (0, 1, 2).
    pub fn of_index(i: usize) -> Option<Self> {
        [Self::Tx, Self::Ty, Self::Tz].get(i).copied()
    }
}

/// A length unit: the one a prior names (`tz=0.12m`, `tz=120mm`, converted to the poses' own), a saved X's, a recording's.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum LengthUnit {
    /// Metres (`m`).
    #[serde(rename = "m")]
    Metre,
    /// Millimetres (`mm`).
    #[serde(rename = "mm")]
    Millimetre,
}

impl LengthUnit {
    /// Its suffix: `m` or `mm`.
    pub fn suffix(self) -> &'static str {
        match self {
            Self::Metre => "m",
            Self::Millimetre => "mm",
        }
    }

    /// The unit of a suffix, `m` or `mm` ([`LengthUnit::suffix`]'s inverse).
    pub fn from_suffix(suffix: &str) -> Option<Self> {
        [Self::Metre, Self::Millimetre]
            .into_iter()
            .find(|u| u.suffix() == suffix)
    }

    /// Metres per this unit.
    pub fn metres(self) -> f64 {
        match self {
            Self::Metre => 1.0,
            Self::Millimetre => 1e-3,
        }
    }
}

/// One prior: X's translation component `component` is `value`, known to `sigma` (one sigma; 0
/// for exact), in the input's length unit or in the `unit` it names.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Prior {
    /// The component.
    pub component: Component,
    /// Its value, input unit (or `unit`).
    pub value: f64,
    /// Its one-sigma, input unit (or `unit`); 0: exact.
    pub sigma: f64,
    /// The unit the value was written in when it names one (`tz=0.12m`): converted to the
    /// poses' unit, told by their sizes, before use. `None`: the poses' unit.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unit: Option<LengthUnit>,
}

/// A prior as a report gives it (`"prior": {"tz": {"value", "sigma"}}`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PriorValue {
    /// The value taken, input unit.
    pub value: f64,
    /// Its one-sigma, input unit (0: exact).
    pub sigma: f64,
}

/// The components of X that came from a prior, by name.
pub type PriorsUsed = BTreeMap<String, PriorValue>;

/// Which way a component of X's translation points, in words: the positive direction of its axis
/// in X's parent frame (the gripper's eye-in-hand, the robot base's eye-to-hand), as a prior on it
/// is to be signed.
pub fn direction_words(setup: Setup, component: Component) -> String {
    let axis = ["x", "y", "z"][component.index()];
    match (setup, component) {
        (Setup::EyeInHand, Component::Tz) => {
            "the gripper frame's +z (for a flange frame, out of the flange towards the tool)".into()
        }
        (Setup::EyeToHand, Component::Tz) => {
            "the robot base's +z (up, for a robot standing on the floor)".into()
        }
        (Setup::EyeInHand, _) => format!("the gripper frame's +{axis}"),
        (Setup::EyeToHand, _) => format!("the robot base's +{axis}"),
    }
}

impl Prior {
    /// Checks the numbers: finite value, finite non-negative sigma, each at most
    /// [`MAX_TRANSLATION`](crate::model::pose::MAX_TRANSLATION) in size (no length of a recording
    /// is larger, and the sigma's square stays finite).
    pub fn validate(&self) -> Result<()> {
        let bound = crate::model::pose::MAX_TRANSLATION;
        if self.value.abs() > bound || self.sigma > bound {
            return Err(invalid(format!(
                "{}: {:e} +- {:e} is not a plausible length in any unit (more than {bound:e} in size)",
                self.component.name(),
                self.value,
                self.sigma
            )));
        }
        if !self.value.is_finite() || !self.sigma.is_finite() || self.sigma < 0.0 {
            return Err(invalid(format!(
                "{}: the value must be finite and the sigma finite and not negative (got {} +- {})",
                self.component.name(),
                self.value,
                self.sigma
            )));
        }
        Ok(())
    }

    /// As a report gives it.
    pub fn value(&self) -> PriorValue {
        PriorValue {
            value: self.value,
            sigma: self.sigma,
        }
    }
}

/// Refuses two priors on the same component, and bad numbers.
pub fn check_priors(priors: &[Prior]) -> Result<()> {
    for (i, p) in priors.iter().enumerate() {
        p.validate()?;
        if priors[..i].iter().any(|q| q.component == p.component) {
            return Err(invalid(format!(
                "{} is given twice: give each component once",
                p.component.name()
            )));
        }
    }
    Ok(())
}

fn invalid(message: String) -> Error {
    Error::InvalidParameter {
        name: "prior",
        message,
    }
}

impl std::str::FromStr for Prior {
    type Err = Error;

    /// `NAME=VALUE` (exact) or `NAME=VALUE+-SIGMA` (also `±`), NAME one of `tx`, `ty`, `tz`; the
    /// value and the sigma may end in a unit, `m` or `mm` (one for both).
    fn from_str(s: &str) -> Result<Self> {
        let syntax = || {
            invalid(format!(
                "`{s}`: write NAME=VALUE or NAME=VALUE+-SIGMA, NAME one of tx, ty, tz (a component of X's translation in X's parent frame, in the input's length unit, or with its unit: m or mm), e.g. tz=0.12, tz=0.12+-0.002 or tz=120mm+-2mm"
            ))
        };
        let (name, rest) = s.split_once('=').ok_or_else(syntax)?;
        let component = <Component as crate::model::names::Named>::parse_name(name.trim())?;
        let (value, sigma) = match rest.split_once("+-").or_else(|| rest.split_once('±')) {
            Some((v, sg)) => (v, Some(sg)),
            None => (rest, None),
        };
        let number = |t: &str| -> Result<(f64, Option<LengthUnit>)> {
            let t = t.trim();
            let (digits, unit) = if let Some(d) = t.strip_suffix("mm") {
                (d, Some(LengthUnit::Millimetre))
            } else if let Some(d) = t.strip_suffix('m') {
                (d, Some(LengthUnit::Metre))
            } else {
                (t, None)
            };
            let v = digits.trim().parse::<f64>().map_err(|_| syntax())?;
            Ok((v, unit))
        };
        let (value, value_unit) = number(value)?;
        let (sigma, sigma_unit) = sigma.map(number).transpose()?.unwrap_or((0.0, None));
        let unit = match (value_unit, sigma_unit) {
            (Some(a), Some(b)) if a != b => {
                return Err(invalid(format!(
                    "`{s}`: the value is in {} and the sigma in {}: give both in one unit",
                    a.suffix(),
                    b.suffix()
                )));
            }
            (a, b) => a.or(b),
        };
        let prior = Prior {
            component,
            value,
            sigma,
            unit,
        };
        prior.validate()?;
        Ok(prior)
    }
}

impl std::fmt::Display for Prior {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let unit = self.unit.map_or("", LengthUnit::suffix);
        if self.sigma > 0.0 {
            write!(
                f,
                "{}={}{unit}+-{}{unit}",
                self.component.name(),
                self.value,
                self.sigma
            )
        } else {
            write!(f, "{}={}{unit}", self.component.name(), self.value)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_exact_and_with_sigma() {
        let p: Prior = "tz=0.12".parse().unwrap();
        assert_eq!(
            p,
            Prior {
                component: Component::Tz,
                value: 0.12,
                sigma: 0.0,
                unit: None,
            }
        );
        let p: Prior = "tz=120mm+-2".parse().unwrap();
        assert_eq!(
            (p.value, p.sigma, p.unit),
            (120.0, 2.0, Some(LengthUnit::Millimetre))
        );
        assert_eq!(p.to_string(), "tz=120mm+-2mm");
        let p: Prior = "tz=0.12+-0.002m".parse().unwrap();
        assert_eq!(
            (p.value, p.sigma, p.unit),
            (0.12, 0.002, Some(LengthUnit::Metre))
        );
        assert!("tz=0.12m+-2mm".parse::<Prior>().is_err());
        assert!("tz=0.12km".parse::<Prior>().is_err());
        let p: Prior = "tx=-5+-0.5".parse().unwrap();
        assert_eq!((p.component, p.value, p.sigma), (Component::Tx, -5.0, 0.5));
        let p: Prior = "ty=1e-1±2e-3".parse().unwrap();
        assert_eq!((p.component, p.value, p.sigma), (Component::Ty, 0.1, 0.002));
    }

    #[test]
    fn refuses_bad_syntax_names_and_numbers() {
        for bad in [
            "tz",
            "tz=",
            "rz=0.1",
            "tz=abc",
            "tz=0.1+-",
            "tz=0.1+--1",
            "tz=nan",
            "tz=0.12+-1e160",
            "tz=1e308m",
            "=1",
        ] {
            let e = bad.parse::<Prior>().unwrap_err();
            assert!(
                matches!(e, Error::InvalidParameter { name: "prior", .. }),
                "{bad}: {e}"
            );
        }
        let twice = [
            "tz=1".parse::<Prior>().unwrap(),
            "tz=2".parse::<Prior>().unwrap(),
        ];
        assert!(check_priors(&twice).is_err());
    }
}
