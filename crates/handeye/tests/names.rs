//! Every named enum of the public surface: its names parse back, print as themselves, and are
//! its serde names; an unknown name is refused with the list of names.

use std::fmt::Debug;
use std::str::FromStr;

use serde::Serialize;
use serde::de::DeserializeOwned;

use handeye::Fix;
use handeye::experiment::{Experiment, OnlineMethod};
use handeye::io::Format;
use handeye::model::findings::Reading;
use handeye::model::names::Named;
use handeye::online::select::Selection;
use handeye::online::{ErrorSource, Estimator, Unit};
use handeye::solve::{Method, RobotWorldMethod};
use handeye::{Error, Pairing, Setup};

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
    round_trip::<handeye::RotationConvention>();
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
