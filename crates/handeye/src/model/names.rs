//! One source of names for the library's choices (methods, setups, pairings, …): each enum's
//! spellings are written once, in a [`named_enum!`](crate::named_enum) list, and its `ALL`,
//! `name()`, `FromStr` and `Display` come from that list. The command line's value parsers and the
//! Python bindings parse through the same [`Named`] trait, so a name is accepted, listed and
//! printed the same way in every face.

use crate::model::error::{Error, Result};

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

    /// The names of every variant, comma separated.
    fn list_names() -> String {
        Self::ALL
            .iter()
            .map(|v| v.name())
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// Parses a name; an unknown one is an [`Error::InvalidParameter`] listing the names
    /// (`a or b` for two, `one of a, b, c` for more).
    fn parse_name(s: &str) -> Result<Self> {
        Self::from_name(s).ok_or_else(|| {
            let choices = match Self::ALL {
                [a, b] => format!("{} or {}", a.name(), b.name()),
                _ => format!("one of {}", Self::list_names()),
            };
            Error::InvalidParameter {
                name: Self::PARAM,
                message: format!("unknown {} `{s}`; {choices}", Self::WHAT),
            }
        })
    }
}

/// Gives a fieldless enum its names from one list: `ALL` (every variant, in the listed order),
/// `name()`, [`Named`], `Display` (the name) and `FromStr` ([`Named::parse_name`]: the name or an alias).
///
/// ```ignore
/// named_enum!(Unit, "unit", "unit" {
///     Auto => "auto",
///     Metre => "m" | "metre" | "meter",   // the name first, then accepted aliases
/// });
/// ```
/// The first literal is what the value is in messages, the second the parameter's name in
/// [`Error::InvalidParameter`]. Variants after `; not listed:` have a name and parse, but are left
/// out of `ALL` (what contract suites iterate). A spelling given twice does not compile without a warning
/// (an unreachable pattern).
#[macro_export]
macro_rules! named_enum {
    ($ty:ident, $what:literal, $param:literal {
        $($variant:ident => $name:literal $(| $alias:literal)*),+ $(,)?
        $(; not listed: $($xvariant:ident => $xname:literal),+ $(,)?)?
    }) => {
        impl $ty {
            #[doc = concat!("Every ", $what, ", in the order they are listed to users.")]
            pub const ALL: [$ty; [$($name),+].len()] = [$($ty::$variant),+];

            /// The name used on the command line, in the Python bindings and in output.
            pub fn name(self) -> &'static str {
                match self {
                    $($ty::$variant => $name,)+
                    $($($ty::$xvariant => $xname,)+)?
                }
            }
        }

        impl $crate::Named for $ty {
            const WHAT: &'static str = $what;
            const PARAM: &'static str = $param;
            const ALL: &'static [Self] = &<$ty>::ALL;

            fn name(self) -> &'static str {
                <$ty>::name(self)
            }

            fn from_name(s: &str) -> Option<Self> {
                match s {
                    $($name $(| $alias)* => Some($ty::$variant),)+
                    $($($xname => Some($ty::$xvariant),)+)?
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
                <$ty as $crate::Named>::parse_name(s)
            }
        }
    };
}
