//! Value parsers of the numeric flags: every number is checked when the command line is read, so
//! that an out-of-range value is refused with exit 2 and the flag named (clap's message), before
//! anything is computed or allocated from it.

use std::ffi::OsStr;

use clap::builder::{PossibleValue, PossibleValuesParser, RangedU64ValueParser, TypedValueParser};
use clap::error::ErrorKind;
use clap::{Arg, Command};
use handeye::Named;
use handeye::io::TimeOffset;

/// The most poses `simulate`, `demo` and `bench` make (each pose is about a hundred bytes, and
/// `bench --pairs all` grows with the square).
pub const MAX_POSES: u64 = 1_000_000;

/// The most series of `experiment`.
pub const MAX_SERIES: u64 = 100_000;

/// The longest `bench --min-time`, seconds.
pub const MAX_MIN_TIME: f64 = 3600.0;

/// A count in `min..=max`.
pub fn count(min: u64, max: u64) -> RangedU64ValueParser<usize> {
    RangedU64ValueParser::new().range(min..=max)
}

/// A finite number.
fn number(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("`{s}` is not a number"))?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("must be a finite number, got `{s}`"))
    }
}

/// One `--rotation` value: NAME, robot=NAME or camera=NAME (the library's parser; a side named
/// twice is refused when the flags are read together).
pub fn rotation(s: &str) -> Result<String, String> {
    handeye::Rotations::parse(&[s])
        .map(|_| s.to_string())
        .map_err(|e| match e {
            handeye::Error::InvalidParameter { message, .. } => message,
            e => e.to_string(),
        })
}

/// A finite number above 0.
pub fn positive(s: &str) -> Result<f64, String> {
    let v = number(s)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(format!("must be above 0, got {s}"))
    }
}

/// A number in (0, 1].
pub fn fraction(s: &str) -> Result<f64, String> {
    let v = number(s)?;
    if v > 0.0 && v <= 1.0 {
        Ok(v)
    } else {
        Err(format!("must be in (0, 1], got {s}"))
    }
}

/// A factor in `[low, high]` (the library's range of an online parameter).
fn factor(s: &str, (low, high): (f64, f64)) -> Result<f64, String> {
    let v = number(s)?;
    if (low..=high).contains(&v) {
        Ok(v)
    } else {
        Err(format!("must be in [{low}, {high}], got {}", shown(s)))
    }
}

/// `--relax-down`: [`handeye::AdaptiveParams::RELAX_DOWN`].
pub fn relax_down(s: &str) -> Result<f64, String> {
    factor(s, handeye::AdaptiveParams::RELAX_DOWN)
}

/// `--relax-up`: [`handeye::AdaptiveParams::RELAX_UP`].
pub fn relax_up(s: &str) -> Result<f64, String> {
    factor(s, handeye::AdaptiveParams::RELAX_UP)
}

/// `--explore`: [`handeye::AdaptiveParams::EXPLORE`].
pub fn explore(s: &str) -> Result<f64, String> {
    factor(s, handeye::AdaptiveParams::EXPLORE)
}

/// An angle in (0°, 180°].
pub fn angle_deg(s: &str) -> Result<f64, String> {
    let v = number(s)?;
    if v > 0.0 && v <= 180.0 {
        Ok(v)
    } else {
        Err(format!("must be in (0, 180] degrees, got {s}"))
    }
}

/// An angle between two axes that a threshold can ask for: (0°, 90°].
pub fn axis_angle_deg(s: &str) -> Result<f64, String> {
    let v = number(s)?;
    if v > 0.0 && v <= 90.0 {
        Ok(v)
    } else {
        Err(format!("must be in (0, 90] degrees, got {s}"))
    }
}

/// A time budget in (0, MAX_MIN_TIME] seconds.
pub fn budget_s(s: &str) -> Result<f64, String> {
    let v = number(s)?;
    if v > 0.0 && v <= MAX_MIN_TIME {
        Ok(v)
    } else {
        Err(format!("must be in (0, {MAX_MIN_TIME}] seconds, got {s}"))
    }
}

/// `auto` or a number of seconds of at most [`TimeOffset::MAX_SECONDS`] in size (127 years).
pub fn time_offset(s: &str) -> Result<TimeOffset, String> {
    if s.trim() == "auto" {
        return Ok(TimeOffset::Auto);
    }
    let v = number(s)?;
    if v.abs() <= TimeOffset::MAX_SECONDS {
        Ok(TimeOffset::Fixed(v))
    } else {
        Err(format!(
            "must be `auto` or seconds of at most {:e} in size (127 years), got {}",
            TimeOffset::MAX_SECONDS,
            shown(s)
        ))
    }
}

/// The longest `--max-gap`, seconds (11.6 days).
pub const MAX_GAP: f64 = 1e6;

/// A gap in (0, [`MAX_GAP`]] seconds.
pub fn max_gap(s: &str) -> Result<f64, String> {
    let v = number(s)?;
    if v > 0.0 && v <= MAX_GAP {
        Ok(v)
    } else {
        Err(format!(
            "must be in (0, {MAX_GAP:e}] seconds, got {}",
            shown(s)
        ))
    }
}

/// A value as a message shows it: at most 24 characters (`1e308` written out has 309 digits).
fn shown(s: &str) -> String {
    let s = s.trim();
    if s.chars().count() <= 24 {
        s.to_string()
    } else {
        format!("{}…", s.chars().take(24).collect::<String>())
    }
}

/// A value parser of the names of some of `T`'s values, from the library's one list of names
/// ([`Named`]): `--help` lists them, and clap refuses any other name with the list (exit 2).
#[derive(Debug, Clone, Copy)]
pub struct NamedParser<T: 'static>(&'static [T]);

/// Any of `T`'s names.
pub fn named<T: Named>() -> NamedParser<T> {
    NamedParser(T::ALL)
}

/// The names of these values of `T` only.
pub fn named_of<T: Named>(values: &'static [T]) -> NamedParser<T> {
    NamedParser(values)
}

impl<T: Named + Send + Sync> TypedValueParser for NamedParser<T> {
    type Value = T;

    fn parse_ref(&self, cmd: &Command, arg: Option<&Arg>, value: &OsStr) -> Result<T, clap::Error> {
        let names = PossibleValuesParser::new(self.0.iter().map(|v| v.name()));
        let name = names.parse_ref(cmd, arg, value)?;
        self.0
            .iter()
            .copied()
            .find(|v| v.name() == name)
            .ok_or_else(|| clap::Error::new(ErrorKind::InvalidValue).with_cmd(cmd))
    }

    fn possible_values(&self) -> Option<Box<dyn Iterator<Item = PossibleValue> + '_>> {
        Some(Box::new(
            self.0.iter().map(|v| PossibleValue::new(v.name())),
        ))
    }
}

/// A point `X,Y,Z`: three finite numbers.
pub fn point(s: &str) -> Result<[f64; 3], String> {
    let parts: Vec<&str> = s.split(',').collect();
    if parts.len() != 3 {
        return Err(format!("expected X,Y,Z (three numbers), got `{s}`"));
    }
    Ok([number(parts[0])?, number(parts[1])?, number(parts[2])?])
}

/// `--goal DEGREES,LENGTH`: two positive sizes, a one-sigma rotation and translation.
pub fn goal(s: &str) -> Result<handeye::Sizes, String> {
    sizes(s, "a one-sigma rotation and translation")
}

/// `--tolerance DEGREES,LENGTH`: two positive sizes, the change of X that matters.
pub fn tolerance(s: &str) -> Result<handeye::Sizes, String> {
    sizes(
        s,
        "the change of X that matters: a rotation and a translation in the recording's unit",
    )
}

/// `DEGREES,LENGTH`: two positive sizes, `what` they are saying in the error.
fn sizes(s: &str, what: &str) -> Result<handeye::Sizes, String> {
    let parts: Vec<&str> = s.split(',').collect();
    if parts.len() != 2 {
        return Err(format!("expected DEGREES,LENGTH ({what}), got `{s}`"));
    }
    Ok(handeye::Sizes {
        rotation_deg: positive(parts[0])?,
        translation: positive(parts[1])?,
    })
}

/// `--prior NAME=VALUE[+-SIGMA]` (the library's parser and words).
pub fn prior(s: &str) -> Result<handeye::Prior, String> {
    s.parse::<handeye::Prior>().map_err(|e| match e {
        handeye::Error::InvalidParameter { message, .. } => message,
        other => other.to_string(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_what_is_not_finite_or_out_of_range() {
        for bad in ["nan", "NaN", "inf", "-inf", "1e309", "x", ""] {
            assert!(number(bad).is_err(), "{bad}");
            assert!(time_offset(bad).is_err(), "{bad}");
        }
        assert!(positive("0").is_err() && positive("-1").is_err());
        assert_eq!(positive("0.5"), Ok(0.5));
        assert!(fraction("1.01").is_err() && fraction("0").is_err());
        assert!(angle_deg("181").is_err() && angle_deg("180").is_ok());
        assert!(axis_angle_deg("91").is_err() && axis_angle_deg("15").is_ok());
        assert!(budget_s("1e308").is_err() && budget_s("0.3").is_ok());
        assert!(relax_up("0.99").is_err() && relax_up("1").is_ok() && relax_up("1e308").is_err());
        assert!(explore("1e-320").is_err() && explore("1.1").is_ok());
        assert!(relax_down("1e-320").is_err() && relax_down("0.9").is_ok());
        assert!(max_gap("0").is_err() && max_gap("1e7").is_err() && max_gap("0.2").is_ok());
        // A huge value is named short, not written out in its 309 digits.
        let e = time_offset(&format!("1{}", "0".repeat(308))).unwrap_err();
        assert!(e.len() < 200, "{e}");
        assert_eq!(time_offset(" 5"), Ok(TimeOffset::Fixed(5.0)));
        assert!(time_offset("4.1e9").is_err() && time_offset("-4e9").is_ok());
        assert_eq!(time_offset("auto"), Ok(TimeOffset::Auto));
        assert_eq!(time_offset("-0.25"), Ok(TimeOffset::Fixed(-0.25)));
    }

    #[test]
    fn named_values_parse_from_the_library_names_only() {
        use handeye::Setup;
        use handeye::Unit;
        let cmd = Command::new("t")
            .arg(
                Arg::new("setup")
                    .long("setup")
                    .value_parser(named::<Setup>()),
            )
            .arg(
                Arg::new("unit")
                    .long("unit")
                    .value_parser(named_of(&[Unit::Auto, Unit::Metre])),
            );
        let m = cmd
            .clone()
            .try_get_matches_from(["t", "--setup", "eye-to-hand", "--unit", "m"])
            .expect("listed names");
        assert_eq!(m.get_one::<Setup>("setup"), Some(&Setup::EyeToHand));
        assert_eq!(m.get_one::<Unit>("unit"), Some(&Unit::Metre));
        for bad in [
            ["--setup", "eye_to_hand"],
            ["--unit", "mm"],
            ["--unit", "metre"],
        ] {
            let e = cmd
                .clone()
                .try_get_matches_from(["t", bad[0], bad[1]])
                .unwrap_err();
            assert_eq!(e.kind(), ErrorKind::InvalidValue, "{bad:?}");
        }
    }
}
