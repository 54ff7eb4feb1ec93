//! One source of names for the library's choices (methods, setups, pairings, …): each enum's
//! spellings are written once, in a [`named_enum!`](crate::named_enum) list, and its `ALL`,
//! `name()`, `FromStr` and `Display` come from that list. The command line's value parsers and the
//! Python bindings parse through the same [`Named`] trait, so a name is accepted, listed and
//! printed the same way in every face.

use crate::error::{Error, Result};

/// An enum whose variants each have one name (and perhaps other accepted spellings).
pub trait Named: Copy + Sized + 'static {
    /// What a value is, in messages (`method`, `setup`, …).
    const WHAT: &'static str;
    /// The parameter's name in an [`Error::InvalidParameter`].
    const PARAM: &'static str;
    /// Every variant, in the order they are listed to users.
    const ALL: &'static [Self];

    /// The name used on the command line, in the Python bindings and in output.
    fn name(self) -> &'static str;

    /// The variant a name or an accepted alias stands for.
    fn from_name(s: &str) -> Option<Self> {
        Self::ALL.iter().copied().find(|v| v.name() == s)
    }
}

/// The names of every variant of `T`, comma separated.
pub fn list<T: Named>() -> String {
    T::ALL
        .iter()
        .map(|v| v.name())
        .collect::<Vec<_>>()
        .join(", ")
}

/// Parses a name of `T`; an unknown one is an [`Error::InvalidParameter`] listing the names
/// (`a or b` for two, `one of a, b, c` for more).
pub fn parse<T: Named>(s: &str) -> Result<T> {
    T::from_name(s).ok_or_else(|| {
        let choices = match T::ALL {
            [a, b] => format!("{} or {}", a.name(), b.name()),
            _ => format!("one of {}", list::<T>()),
        };
        Error::InvalidParameter {
            name: T::PARAM,
            message: format!("unknown {} `{s}`; {choices}", T::WHAT),
        }
    })
}

/// Gives a fieldless enum its names from one list: `ALL` (every variant, in the listed order),
/// `name()`, [`Named`], `Display` (the name) and `FromStr` ([`parse`]: the name or an alias).
///
/// ```ignore
/// named_enum!(Unit, "unit", "unit" {
///     Auto => "auto",
///     Metre => "m" | "metre" | "meter",   // the name first, then accepted aliases
/// });
/// ```
/// The first literal is what the value is in messages, the second the parameter's name in
/// [`Error::InvalidParameter`]. A spelling given twice does not compile without a warning
/// (an unreachable pattern).
#[macro_export]
macro_rules! named_enum {
    ($ty:ident, $what:literal, $param:literal {
        $($variant:ident => $name:literal $(| $alias:literal)*),+ $(,)?
    }) => {
        impl $ty {
            #[doc = concat!("Every ", $what, ", in the order they are listed to users.")]
            pub const ALL: [$ty; [$($name),+].len()] = [$($ty::$variant),+];

            /// The name used on the command line, in the Python bindings and in output.
            pub fn name(self) -> &'static str {
                match self {
                    $($ty::$variant => $name),+
                }
            }
        }

        impl $crate::names::Named for $ty {
            const WHAT: &'static str = $what;
            const PARAM: &'static str = $param;
            const ALL: &'static [Self] = &<$ty>::ALL;

            fn name(self) -> &'static str {
                <$ty>::name(self)
            }

            fn from_name(s: &str) -> Option<Self> {
                match s {
                    $($name $(| $alias)* => Some($ty::$variant),)+
                    _ => None,
                }
            }
        }

        impl ::core::fmt::Display for $ty {
            fn fmt(&self, f: &mut ::core::fmt::Formatter<'_>) -> ::core::fmt::Result {
                f.write_str(self.name())
            }
        }

        impl ::core::str::FromStr for $ty {
            type Err = $crate::Error;

            fn from_str(s: &str) -> $crate::Result<Self> {
                $crate::names::parse(s)
            }
        }
    };
}

#[cfg(test)]
mod tests {
    use std::fmt::Debug;
    use std::str::FromStr;

    use serde::Serialize;
    use serde::de::DeserializeOwned;

    use super::*;
    use crate::calibration::Fix;
    use crate::conventions::Reading;
    use crate::experiment::{Experiment, OnlineMethod};
    use crate::io::Format;
    use crate::online::{ErrorSource, Estimator, Unit};
    use crate::select::Selection;
    use crate::solve::{Method, RobotWorldMethod};
    use crate::{Pairing, Setup};

    /// Each name in `ALL` is distinct, parses back to its variant (through `FromStr` and
    /// `from_name`), and prints as itself; an unknown name's error lists every name.
    fn round_trip<T>()
    where
        T: Named + FromStr<Err = Error> + std::fmt::Display + PartialEq + Debug,
    {
        for (k, &v) in T::ALL.iter().enumerate() {
            assert_eq!(v.name().parse::<T>().ok(), Some(v), "{}", v.name());
            assert_eq!(v.to_string(), v.name());
            assert!(
                T::ALL[..k].iter().all(|u| u.name() != v.name()),
                "{} twice",
                v.name()
            );
        }
        let Err(Error::InvalidParameter { name, message }) = "no-such-name".parse::<T>() else {
            panic!("`no-such-name` parsed as a {}", T::WHAT);
        };
        assert_eq!(name, T::PARAM);
        assert!(message.contains("`no-such-name`"), "{message}");
        for v in T::ALL {
            assert!(message.contains(v.name()), "{message} lacks {}", v.name());
        }
    }

    /// The serde name of each variant is its `name()`, and deserialises back to it.
    fn serde_is_name<T>()
    where
        T: Named + Serialize + DeserializeOwned + PartialEq + Debug,
    {
        for &v in T::ALL {
            let json = serde_json::to_value(v).expect("a unit variant serialises");
            assert_eq!(json, serde_json::Value::from(v.name()), "{v:?}");
            assert_eq!(serde_json::from_value::<T>(json).ok(), Some(v));
        }
    }

    #[test]
    fn every_name_parses_back_and_serde_agrees() {
        round_trip::<Method>();
        serde_is_name::<Method>();
        round_trip::<RobotWorldMethod>();
        serde_is_name::<RobotWorldMethod>();
        round_trip::<Setup>();
        serde_is_name::<Setup>();
        round_trip::<Pairing>();
        serde_is_name::<Pairing>();
        round_trip::<Reading>();
        serde_is_name::<Reading>();
        round_trip::<Selection>();
        serde_is_name::<Selection>();
        round_trip::<ErrorSource>();
        serde_is_name::<ErrorSource>();
        round_trip::<Estimator>();
        serde_is_name::<Estimator>();
        round_trip::<Experiment>();
        serde_is_name::<Experiment>();
        round_trip::<OnlineMethod>();
        serde_is_name::<OnlineMethod>();
        // Not serialised.
        round_trip::<Format>();
        // Fix::Read carries a reading: serde writes {"read": name}, so only refuse and auto
        // are bare names.
        round_trip::<Fix>();
        for fix in [Fix::Refuse, Fix::Auto] {
            assert_eq!(serde_json::to_value(fix).ok(), Some(fix.name().into()));
        }
        // Unit's serde names (`metre`, `millimetre`) predate its short names and stay for saved
        // states: each parses as an alias and deserialises.
        round_trip::<Unit>();
        for unit in Unit::ALL {
            let json = serde_json::to_value(unit).expect("a unit variant serialises");
            let serde_name = json.as_str().expect("a string");
            assert_eq!(serde_name.parse::<Unit>().ok(), Some(unit), "{serde_name}");
        }
    }

    #[test]
    fn aliases_parse() {
        assert_eq!(
            "conventional".parse::<Selection>().ok(),
            Some(Selection::None)
        );
        assert_eq!("json".parse::<Format>().ok(), Some(Format::Jsonl));
        assert_eq!("yaml".parse::<Format>().ok(), Some(Format::OpencvYaml));
        for s in ["metre", "meter", "metres", "meters"] {
            assert_eq!(s.parse::<Unit>().ok(), Some(Unit::Metre), "{s}");
        }
        for s in ["millimetre", "millimeter", "millimetres", "millimeters"] {
            assert_eq!(s.parse::<Unit>().ok(), Some(Unit::Millimetre), "{s}");
        }
    }

    #[test]
    fn unknown_name_lists_the_names() {
        let e = "selected".parse::<Estimator>().unwrap_err().to_string();
        assert!(
            e.contains("unknown estimator `selected`; paper or accumulate"),
            "{e}"
        );
        let e = "opencv".parse::<Method>().unwrap_err().to_string();
        assert!(
            e.contains(
                "unknown method `opencv`; one of andreff, andreff-joint, tsai, park, horaud, daniilidis, refine"
            ),
            "{e}"
        );
    }
}
